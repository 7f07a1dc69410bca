#!/usr/bin/env bash
# Build qsweep in release, then time `qsweep bench` and scripts/python_baseline.py on the same
# Cart-Pole configurations, in one go on the same machine, and print the ratio per configuration.
#
# Environment: STEPS (qsweep step budget, default 1000000), SCALE (multiplies the Python budgets,
# default 1), FILTER (only configurations containing this), PYTHON (default python3; needs
# gymnasium and numpy).
set -euo pipefail
cd "$(dirname "$0")/.."
STEPS=${STEPS:-1000000}
SCALE=${SCALE:-1}
FILTER=${FILTER:-}
PYTHON=${PYTHON:-python3}

cargo build --release --quiet
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo 2>/dev/null | cut -d: -f2- | xargs || uname -m)" >&2
echo "running the Python baseline ..." >&2
"$PYTHON" scripts/python_baseline.py --json --filter "$FILTER" --scale "$SCALE" > "${TMPDIR:-/tmp}/qsweep-python-baseline.json"
echo "running qsweep bench ..." >&2
"$PYTHON" - "$STEPS" "${TMPDIR:-/tmp}/qsweep-python-baseline.json" <<'PY'
import json, subprocess, sys
steps, baseline = sys.argv[1], json.load(open(sys.argv[2]))
print(f"{'config':<40} {'python steps/s':>15} {'qsweep steps/s':>15} {'ratio':>8}")
for py in baseline:
    out = subprocess.run(
        ["target/release/qsweep", "bench", "--json", "--steps", steps, "--filter", py["config"]],
        check=True, capture_output=True, text=True,
    ).stdout
    rs = [r for r in json.loads(out)["results"] if r["config"] == py["config"]][0]
    ratio = rs["steps_per_s"] / py["steps_per_s"]
    print(f"{py['config']:<40} {py['steps_per_s']:>15,.0f} {rs['steps_per_s']:>15,.0f} {ratio:>7.0f}×", flush=True)
PY
