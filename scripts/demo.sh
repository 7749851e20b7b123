#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# make demo: the whole system on built-in data.
#   1. render a synthetic drive (1000 frames, 16 landmarks in 2 colours, clutter) with a camera
#      whose true mount differs from its calibration by one error drawn from the calibration's
#      sigmas (as on a real robot: constant during the run);
#   2. run the frontend on its frames (libcyl detection + uncertainty) -> observation log and an
#      overlay video;
#   3. run the GTSAM SLAM demo on the log: per-observation covariance for what changes frame to
#      frame, and the calibration error (constant over the run) as one estimated state; beside
#      it the same data with one tuned fixed covariance; write plots and a summary.
# No centroid-variance floor: the silhouette's geometric bias is modelled in libcyl
# (docs/uncertainty.md, "The silhouette's geometric bias").
# The last line is a JSON object with the headline metrics.
set -euo pipefail
B=${BUILD:-build}
OUT=${DEMO_OUT:-$B/demo}
FRAMES=${DEMO_FRAMES:-1000}
SEED=${DEMO_SEED:-7}
mkdir -p "$OUT"
t0=$(date +%s)
echo "== 1/3 rendering $FRAMES frames of the synthetic scene (seed $SEED, calibration error drawn once)"
"$B/cyl-render" -o "$OUT/drive.cylraw" -n "$FRAMES" -s "$SEED" --calib-error 2>&1 | grep -v -e '^$' -e '^rendering: ' | tail -3
echo "== 2/3 detection: cyl detect -> $OUT/observations.jsonl"
"$B/cyl" detect "$OUT/drive.cylraw" --table calib_data/synthetic.cylt --calib calib_data/synthetic_camera.yaml \
  --size orange=0.10,0.30 --size green=0.10,0.30 \
  --out "$OUT/observations.jsonl" --overlay "$OUT/overlay.avi"
echo "== 3/3 SLAM: per-observation covariance + calibration state, vs one tuned fixed covariance"
PYTHONPATH=slam_demo .venv/bin/python -m cylslam run "$OUT/observations.jsonl" --out "$OUT/slam" --calib-states \
  --rerun "$OUT/slam/run.rrd" | tee "$OUT/slam.log"
rm -f "$OUT/drive.cylraw"   # 614 MB: re-rendered on demand
t1=$(date +%s)
echo
echo "demo outputs in $OUT/:"
echo "  observations.jsonl   the frontend's observation log (docs/formats.md)"
echo "  overlay.avi          classified pixels, boxes, range/bearing, 95% ellipses"
echo "  slam/plot.png        estimate vs truth with 95% ellipses; slam/summary.json, trajectory.csv, landmarks.csv"
echo "  slam/trajectory.tum  TUM trajectories for evo (and truth.tum, KITTI files)"
echo "  slam/run.rrd         the run as a rerun recording (rerun $OUT/slam/run.rrd)"
echo "  demo time: $((t1 - t0)) s"
tail -1 "$OUT/slam.log"
