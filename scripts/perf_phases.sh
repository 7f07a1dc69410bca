#!/usr/bin/env bash
# Where a fuzzy step's time goes (docs/speed.md, "Where the time goes"): `perf record` on
# `qsweep bench --filter CELL`, then the CPU samples' functions sorted into five phases —
# activation (the memberships, their normaliser, the outer product), Q(s, ·), update and traces,
# dynamics, and the rest (the ε-greedy choice, the episode loop). Uses the profiling build, which
# keeps the symbols perf needs:
#
#   cargo build --profile profiling
#   scripts/perf_phases.sh 'cart-pole/fuzzy/q-lambda/4^4/2a' 'mountain-car/fuzzy/q0/4^2/3a'
#   STEPS=2000000 QSWEEP=path/to/qsweep scripts/perf_phases.sh CELL...
set -euo pipefail
cd "$(dirname "$0")/.."
qsweep=${QSWEEP:-target/profiling/qsweep}
[ $# -gt 0 ] || { sed -n '2,10p' "$0" | sed 's/^# \{0,1\}//'; exit 2; }
command -v perf >/dev/null || { echo "perf_phases.sh: needs perf (linux-perf)" >&2; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for cell in "$@"; do
    perf record -q -F 4000 -o "$tmp/perf.data" -- "$qsweep" bench --filter "$cell" \
        --steps "${STEPS:-1000000}" --repeat 1 --json >/dev/null 2>&1
    perf report -i "$tmp/perf.data" --no-children --sort symbol -F overhead,sym --stdio 2>/dev/null |
        python3 -c '
import re, sys
phases = {"activation": 0.0, "Q(s,·)": 0.0, "update+traces": 0.0, "dynamics": 0.0, "rest": 0.0}
for line in sys.stdin:
    m = re.match(r"\s+([0-9.]+)%\s+\[.\]\s+(.*)", line)
    if not m:
        continue
    share, sym = float(m.group(1)), m.group(2)
    if re.search(r"activate|fuzzy::|math::exp", sym):
        k = "activation"
    elif re.search(r"q_values|overlap", sym):
        k = "Q(s,·)"
    elif re.search(r"traces|q0_update|update", sym):
        k = "update+traces"
    elif re.search(r"env::|cart_pole|mountain_car|ball_beam|math::(sin|cos)", sym):
        k = "dynamics"
    else:
        k = "rest"
    phases[k] += share
print(sys.argv[1], " | ".join(f"{k} {v:.0f} %" for k, v in phases.items()))
' "$cell"
done
