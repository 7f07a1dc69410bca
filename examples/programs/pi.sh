#!/bin/sh
# A qsweep program in POSIX sh: estimates pi from `points` pseudo-random points in the unit square.
# stdin holds the trial's config as one JSON object, e.g. {"points":500,"seed":3}; a tiny sed
# reads the one param it needs, and the seed comes from QSWEEP_SEED (qsweep sets it).
points=$(sed -n 's/.*"points": *\([0-9]*\).*/\1/p')
if [ "${points:-0}" -lt 1 ]; then
  echo "points must be at least 1" >&2 # stderr: its tail is stored with the failed trial
  exit 3
fi
x=$((QSWEEP_SEED + 1)) inside=0 i=0
while [ "$i" -lt "$points" ]; do # an LCG: the same seed gives the same points everywhere
  x=$(((x * 1103515245 + 12345) % 2147483648)) a=$((x % 10000))
  x=$(((x * 1103515245 + 12345) % 2147483648)) b=$((x % 10000))
  [ $((a * a + b * b)) -lt 100000000 ] && inside=$((inside + 1))
  i=$((i + 1))
done
echo "$inside of $points points fell inside the quarter circle" # a log line
awk -v n="$points" -v k="$inside" 'BEGIN { printf "{\"pi\": %.6f, \"inside\": %d}\n", 4 * k / n, k }'
