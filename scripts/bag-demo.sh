#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# make bag-demo: make demo's drive through a ROS bag, as a robot's log would come in.
#   1. render the synthetic drive (as make demo: seed 7, 1000 frames, calibration error drawn once);
#   2. write it as a ROS bag (cyl-robotlog write-bag: images, camera_info, odometry, ground truth;
#      BAG_STORAGE=mcap (default), sqlite3 or ros1; BAG_JPEG=1 for CompressedImage JPEG);
#   3. import the bag back (cyl-robotlog import-bag) into a raw log;
#   4. detect on it, and on the rendered log directly, and compare the two observation logs;
#   5. run the SLAM demo on the imported log and evo's ATE on its TUM output.
# The last line is make demo's JSON object plus "source" (the bag and its storage),
# "same_observations_as_direct", "evo_ate_m" and "rerun_entities" (the run's rerun recording, read back).
set -euo pipefail
B=${BUILD:-build}
OUT=${BAG_DEMO_OUT:-$B/bag-demo}
FRAMES=${DEMO_FRAMES:-1000}
SEED=${DEMO_SEED:-7}
STORAGE=${BAG_STORAGE:-mcap}
PY=".venv/bin/python"
export PYTHONPATH="build/python:slam_demo"   # python/build.sh puts the binding there
rm -rf "$OUT" && mkdir -p "$OUT"
BAG="$OUT/drive_bag"; [ "$STORAGE" = ros1 ] && BAG="$OUT/drive.bag"
IMG=/camera/image_raw; JPEG=(); [ "${BAG_JPEG:-0}" = 1 ] && { JPEG=(--jpeg); IMG=/camera/image_raw/compressed; }
echo "== 1/5 rendering $FRAMES frames (seed $SEED, calibration error drawn once)"
"$B/cyl-render" -o "$OUT/drive.cylraw" -n "$FRAMES" -s "$SEED" --calib-error -q
echo "== 2/5 writing the drive as a ROS bag ($STORAGE${JPEG:+, JPEG}): $BAG"
$PY -m cyl.robotlog write-bag "$OUT/drive.cylraw" -o "$BAG" --storage "$STORAGE" "${JPEG[@]}" \
  --calib calib_data/synthetic_camera.yaml
echo "== 3/5 importing the bag: cyl-robotlog import-bag -> $OUT/imported.cylraw"
$PY -m cyl.robotlog import-bag "$BAG" -o "$OUT/imported.cylraw" --image-topic "$IMG" --odom-topic /odom \
  --truth-topic /ground_truth --truth-landmarks-topic /truth/landmarks --classes orange,green
echo "== 4/5 detection on the imported log and on the rendered one"
for k in imported drive; do
  "$B/cyl" detect "$OUT/$k.cylraw" --table calib_data/synthetic.cylt --calib calib_data/synthetic_camera.yaml \
    --size orange=0.10,0.30 --size green=0.10,0.30 --out "$OUT/$k.jsonl" --quiet
done
same=$($PY - "$OUT/drive.jsonl" "$OUT/imported.jsonl" <<'PY'
import json, sys
def obs(p):
    keys = ("seq", "class", "range_m", "bearing_rad", "cov_rr", "cov_rb", "cov_bb", "u_px", "v_px", "confidence")
    return [tuple(json.dumps(r[k]) for k in keys) for r in map(json.loads, open(p)) if r["type"] == "obs"]
a, b = obs(sys.argv[1]), obs(sys.argv[2])
print("true" if a == b else "false")
print(f"   direct {len(a)} observations, through the bag {len(b)}; identical: {a == b}", file=sys.stderr)
PY
)
rm -f "$OUT/drive.cylraw" "$OUT/imported.cylraw"   # 614 MB each
echo "== 5/5 SLAM on the imported log, and evo's ATE on its TUM output"
$PY -m cylslam run "$OUT/imported.jsonl" --out "$OUT/slam" --calib-states --rerun "$OUT/slam/run.rrd" | tee "$OUT/slam.log"
evo=$($PY - "$OUT/slam" <<'PY'
import sys
from evo.core import metrics, sync
from evo.tools import file_interface
d = sys.argv[1]
ref = file_interface.read_tum_trajectory_file(d + "/truth.tum")
est = file_interface.read_tum_trajectory_file(d + "/trajectory.tum")
ref, est = sync.associate_trajectories(ref, est)
est.align(ref, correct_scale=False)
ape = metrics.APE(metrics.PoseRelation.translation_part)
ape.process_data((ref, est))
print(f"{ape.get_statistic(metrics.StatisticsType.rmse):.6f}")
PY
)
# the rerun recording, read back: its entities
ents=$($PY - "$OUT/slam/run.rrd" <<'PY'
import json, sys
from rerun.chunk import RrdReader
print(json.dumps(sorted({str(c.entity_path).lstrip("/") for c in RrdReader(sys.argv[1]).stream().to_chunks()} - {"__properties"})))
PY
)
tail -1 "$OUT/slam.log" | $PY -c "
import json, sys
r = json.loads(sys.stdin.read())
r.update(source={'bag': '$BAG', 'storage': '$STORAGE', 'jpeg': ${BAG_JPEG:-0} == 1},
         same_observations_as_direct='$same' == 'true', evo_ate_m=float('$evo'), rerun_entities=json.loads('$ents'))
print(json.dumps(r))"
