#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# make bench: every benchmark in one run; each prints its table, and the last line is one JSON
# object merging all their figures. Timing figures are medians and ratios against baselines
# measured in the same run (memcpy, OpenCV); instruction counts come from callgrind.
#   1. segmentation: libcyl (vector and scalar paths, checked bit-identical) vs memcpy vs an
#      OpenCV pipeline, and instructions per pixel, on the
#      typical frames and the dense and speckle worst cases; large frames (2048x1536, 3840x2160)
#      and, when the shared data are there, real images (RoboCup ball, FRC cones and cubes) with
#      the tables learned on their training splits
#   2. uncertainty: cyl_observe (noise estimation + camera model) vs cyl_segment per frame
#   3. end-to-end replay of recorded 640x480 YUYV logs through `cyl detect` (frames/s, peak RSS
#      of a 1,000- and a 10,000-frame log; ~6 GB of temporary disk in build/bench)
set -euo pipefail
B=${BUILD:-build}
strip() { local j=$1; j=${j#\{}; echo "${j%\}}"; }
seg=$("$B/bench_segment" "$@")
echo "$seg" | sed '$d'
cg=$(mktemp -d)
K=32
valgrind --tool=callgrind --callgrind-out-file="$cg/cg.out" --toggle-collect=cyl_segment \
  "$B/bench_segment" --callgrind $K >/dev/null 2>"$cg/log"
ir=$(awk '/^totals:/{print $2}' "$cg/cg.out")
ipp=$(awk -v ir="$ir" -v k=$K 'BEGIN{printf "%.2f", ir / (k * 640 * 480)}')
echo "callgrind: cyl_segment $ir instructions over $K frames = $ipp instructions per pixel (vector path)"
valgrind --tool=callgrind --callgrind-out-file="$cg/scalar.out" --toggle-collect=cyl_segment \
  "$B/bench_segment" --callgrind $K --scalar >/dev/null 2>"$cg/log"
ipp_scalar=$(awk -v ir="$(awk '/^totals:/{print $2}' "$cg/scalar.out")" -v k=$K 'BEGIN{printf "%.2f", ir / (k * 640 * 480)}')
echo "callgrind: cyl_segment on the scalar reference path = $ipp_scalar instructions per pixel"
# the worst-case sets too
for set in dense speckle; do
  valgrind --tool=callgrind --callgrind-out-file="$cg/$set.out" --toggle-collect=cyl_segment \
    "$B/bench_segment" --callgrind $K --set $set >/dev/null 2>"$cg/log"
  v=$(awk -v ir="$(awk '/^totals:/{print $2}' "$cg/$set.out")" -v k=$K 'BEGIN{printf "%.2f", ir / (k * 640 * 480)}')
  echo "callgrind: cyl_segment on the $set set = $v instructions per pixel"
  eval "ipp_$set=$v"
done
rm -rf "$cg"
echo
unc=$("$B/bench_uncertainty")
echo "$unc" | sed '$d'
echo
rep=$("$B/bench_replay" "$B/cyl" calib_data/synthetic.cylt)
echo "$rep" | sed '$d'
echo
# Real images when the shared data are there (SHARED, default ../shared): the colour tables
# `make realeval` learns on each set's training split, timed on its test split.
SHARED=${SHARED:-../shared}
real=""
if [ -d "$SHARED/data/real" ] && [ -x "$B/cyl-train" ] && [ -x "$B/cyl-score" ]; then
  python3 scripts/realeval.py --shared "$SHARED" --build "$B" --out "$B/bench/real" >"$B/bench/realeval.log" 2>&1 ||
    { echo "real images: realeval failed (see $B/bench/realeval.log)"; exit 1; }
  for n in ball frc; do
    r=$("$B/bench_segment" --real "$B/bench/real/$n-test.list" "$B/bench/real/$n.cylt" --iterations 30)
    echo "$r" | sed '$d'
    j=$(echo "$r" | tail -1 | sed "s/\"real_/\"real_${n}_/g")
    real="$real, $(strip "$j")"
  done
else
  echo "real images: not measured ($SHARED/data/real absent, or cyl-train/cyl-score not built)"
fi
echo
echo "{$(strip "$(echo "$seg" | tail -1)")$real, \"instr_per_pixel\": $ipp, \"instr_per_pixel_scalar\": $ipp_scalar, \"instr_per_pixel_dense\": $ipp_dense, \"instr_per_pixel_speckle\": $ipp_speckle$(echo "$unc" | tail -1), $(strip "$(echo "$rep" | tail -1)")}"
