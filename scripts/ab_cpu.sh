#!/usr/bin/env bash
# Compare the CPU time of two qsweep binaries on real trials of `paper.yaml`, alternating the two
# builds run by run, one trial at a time, so that both see the same machine (on a shared VM the
# speed drifts by tens of percent within minutes; compare the ratio, never one build's figure
# with another run's).
#
#   scripts/ab_cpu.sh OLD_BINARY NEW_BINARY [RUNS]       # RUNS per build and cell, default 5
#
# e.g. build the old commit in a worktree with its own target directory (sharing this one's lets
# cargo overwrite target/release/qsweep with the old build), then
#   git worktree add /tmp/old REV && (cd /tmp/old && cargo build --release)
#   scripts/ab_cpu.sh /tmp/old/target/release/qsweep target/release/qsweep 9
#
# Cells: per group, the trial of median cost among that group's 0.8–2.5 s trials of a full run
# of paper.yaml (2026-12-02), with its real seed and limits; Cart-Pole crisp Q(λ), whose trials all
# run under 0.35 s, by its costliest (0.34 s, 1.8 M steps; the 10^4/2a cell it replaced ran 0.04 s,
# too short to time). Prints, per cell, the minimum and median user+system seconds of each build
# and the ratio of minima (new / old). Needs GNU time.
set -euo pipefail
if [ $# -lt 2 ]; then
    sed -n '2,18p' "$0" | sed 's/^# \{0,1\}//' >&2
    exit 2
fi
OLD=$1 NEW=$2 RUNS=${3:-5}
for b in "$OLD" "$NEW"; do
    [ -x "$b" ] || { echo "ab_cpu.sh: '$b' is not an executable qsweep binary" >&2; exit 2; }
done
[ -x /usr/bin/time ] || { echo "ab_cpu.sh: needs /usr/bin/time (apt-get install time)" >&2; exit 2; }

cpu() { # user+system seconds of one `qsweep trial` run
    { /usr/bin/time -f "%U %S" "$1" trial "${@:2}" < /dev/null > /dev/null; } 2>&1 | tail -1 | awk '{print $1 + $2}'
}
stats() { # min and median of the arguments
    printf '%s\n' "$@" | sort -g | awk '{v[NR] = $1} END {printf "%.2f %.2f", v[1], v[int((NR + 1) / 2)]}'
}

echo "| cell | old min / median (s) | new min / median (s) | new/old (minima) |"
echo "|---|---:|---:|---:|"
while IFS='|' read -r name args; do
    old=() new=()
    for _ in $(seq "$RUNS"); do
        # shellcheck disable=SC2086 # the argument list is split on purpose
        old+=("$(cpu "$OLD" $args)")
        # shellcheck disable=SC2086
        new+=("$(cpu "$NEW" $args)")
    done
    read -r omin omed <<< "$(stats "${old[@]}")"
    read -r nmin nmed <<< "$(stats "${new[@]}")"
    ratio=$(awk -v n="$nmin" -v o="$omin" 'BEGIN {printf (o > 0 ? "%.2f" : "n/a"), (o > 0 ? n / o : 0)}')
    echo "| $name | $omin / $omed | $nmin / $nmed | $ratio |"
done <<'CELLS'
Mountain Car crisp Q(0) 2^2/8a digitize, seed 9|--env mountain-car --repr crisp --resolution 2 --actions 8 --algorithm q0 --seed 9 --set binning=digitize --set success.max_episode_steps=10000
Mountain Car crisp Q(λ) 2^2/6a digitize, seed 1|--env mountain-car --repr crisp --resolution 2 --actions 6 --algorithm q-lambda --seed 1 --set binning=digitize --set success.max_episode_steps=10000
Mountain Car fuzzy Q(λ) 2x5/3a, seed 2|--env mountain-car --repr fuzzy --resolution 2,5 --actions 3 --algorithm q-lambda --seed 2 --set success.max_episode_steps=10000
Mountain Car fuzzy Q(0) 2^2/9a, seed 8|--env mountain-car --repr fuzzy --resolution 2 --actions 9 --algorithm q0 --seed 8 --set success.max_episode_steps=10000
Cart-Pole fuzzy Q(λ) 10x4x10x4/2a, seed 8|--env cart-pole --repr fuzzy --resolution 10,4,10,4 --actions 2 --algorithm q-lambda --seed 8
Cart-Pole fuzzy Q(λ) 6^4/10a, seed 2|--env cart-pole --repr fuzzy --resolution 6 --actions 10 --algorithm q-lambda --seed 2
Cart-Pole fuzzy Q(0) 4^4/2a, seed 9|--env cart-pole --repr fuzzy --resolution 4 --actions 2 --algorithm q0 --seed 9
Cart-Pole crisp Q(λ) 8x9x8x9/2a, seed 3|--env cart-pole --repr crisp --resolution 8,9,8,9 --actions 2 --algorithm q-lambda --seed 3
CELLS
