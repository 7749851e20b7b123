#!/usr/bin/env bash
# make bench: timing medians (one run, ratios against memcpy and OpenCV) and
# callgrind instruction counts per pixel. Prints a table and, last, one JSON line
# merging both.
set -euo pipefail
B=${BUILD:-build}
out=$("$B/bench_segment" "$@")
echo "$out" | sed '$d'
json=$(echo "$out" | tail -1)
cg=$(mktemp -d)
K=32
valgrind --tool=callgrind --callgrind-out-file="$cg/cg.out" --toggle-collect=cyl_segment \
  "$B/bench_segment" --callgrind $K >/dev/null 2>"$cg/log"
ir=$(awk '/^totals:/{print $2}' "$cg/cg.out")
ipp=$(awk -v ir="$ir" -v k=$K 'BEGIN{printf "%.2f", ir / (k * 640 * 480)}')
echo "callgrind: cyl_segment $ir instructions over $K frames = $ipp instructions per pixel"
rm -rf "$cg"
extra=${BENCH_EXTRA_JSON:-}
echo "${json%\}}, \"instr_per_pixel\": $ipp${extra}}"
