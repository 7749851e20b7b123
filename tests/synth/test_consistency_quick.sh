#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# make consistency's reduced form (scripts/consistency.py --quick: held-out seeds 101-102 at 300
# frames, the imaging sweep at reduced sizes, the pixel-noise-only NEES). Asserts what holds today
# and would catch a regression: no association error, the pixel-only NEES within 1.6-2.6 (2
# expected, no floor), the image estimator's ratio to the measured variance within 0.5-1.5 over
# the sweep, every seed's SLAM run producing both ANEES figures with their bounds and the fixed
# covariance's ATE at every scale of its grid (the best of them the one reported). The full
# figures (20 seeds) are make consistency's. Then one short drive in another scene (--scene with
# tests/fixtures/scenes/variant.yaml): the camera, table and landmark size come from that scene
# (its 8 deg tilt and 0.25 m camera height above the landmarks' middle in the camera file the
# detector used) and the SLAM run gives both ANEES. Then --detect-args reaching cyl detect: a
# value cyl detect refuses ends the run with its message. GoogleTest-style lines.
#   test_consistency_quick.sh BUILD_DIR
set -u
B=$1
cd "$(dirname "$0")/../.."
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
echo "[ RUN      ] consistency.quick"
if ! .venv/bin/python scripts/consistency.py --quick --build "$B" --out "$T/c" >"$T/log" 2>"$T/err"; then
  echo "  consistency.py failed: $(tail -5 "$T/err")"; echo "[  FAILED  ] consistency.quick"; exit 1
fi
msg=$(.venv/bin/python - "$T/log" "$T/c/consistency.json" <<'PY'
import json, sys
r = json.loads(open(sys.argv[1]).read().strip().splitlines()[-1])
rows = json.load(open(sys.argv[2]))["rows"]
bad = []
if r["association_errors_total"] != 0: bad.append(f"association errors {r['association_errors_total']}")
if not 1.6 <= r["pixel_only_nees"] <= 2.6: bad.append(f"pixel-only NEES {r['pixel_only_nees']}")
if not (0.5 <= r["estimator_ratio_min"] and r["estimator_ratio_max"] <= 1.5):
    bad.append(f"image estimator ratio {r['estimator_ratio_min']}..{r['estimator_ratio_max']}")
for row in rows:
    for k in ("anees_landmarks", "anees_poses"):
        if not (isinstance(row[k], float) and row[k] > 0 and row[k + "_bounds95"]):
            bad.append(f"seed {row['seed']}: no {k}")
    g = row.get("fixed_cov_grid_ate_m") or {}
    if sorted(g) != ["0.25", "0.5", "1", "2", "4"] or not all(v is None or 0 < v < 1 for v in g.values()):
        bad.append(f"seed {row['seed']}: fixed-covariance grid ATEs {g}")
    elif row["ate_fixed_cov_m"] != min(v for v in g.values() if v is not None):
        bad.append(f"seed {row['seed']}: best fixed ATE {row['ate_fixed_cov_m']} is not the grid's least")
for k in ("seeds_landmark_anees_in_bounds", "seeds_pose_anees_in_bounds", "ate_better_than_fixed_frac",
          "ate_better_than_tuned_fixed_frac"):
    if not 0 <= r[k] <= 1: bad.append(f"{k} {r[k]}")
print("; ".join(bad))
PY
)
if [ -z "$msg" ]; then echo "[       OK ] consistency.quick ($(tail -1 "$T/log" | cut -c1-200))"
else echo "  $msg"; echo "[  FAILED  ] consistency.quick"; exit 1; fi

echo "[ RUN      ] consistency.scene_file"
if ! .venv/bin/python scripts/consistency.py --scene tests/fixtures/scenes/variant.yaml --seeds 101 --frames 300 \
     --drives-only --build "$B" --out "$T/s" >"$T/slog" 2>"$T/serr"; then
  echo "  consistency.py --scene failed: $(tail -5 "$T/serr")"; echo "[  FAILED  ] consistency.scene_file"; exit 1
fi
msg=$(.venv/bin/python - "$T/slog" "$T/s" <<'PY'
import json, os, re, sys
r = json.loads(open(sys.argv[1]).read().strip().splitlines()[-1])
d = os.path.join(sys.argv[2], "scene_detector")
bad = []
if r["scene"] != "tests/fixtures/scenes/variant.yaml": bad.append(f"scene {r['scene']}")
cam = open(os.path.join(d, "camera.yaml")).read()
tilt = float(re.search(r"^mount_tilt_deg:\s*(\S+)", cam, re.M).group(1))
height = float(re.search(r"^mount_height_m:\s*(\S+)", cam, re.M).group(1))
if abs(tilt - 8.0) > 1e-9 or abs(height - 0.25) > 1e-9: bad.append(f"camera tilt {tilt} deg, height {height} m")
if not os.path.getsize(os.path.join(d, "table.cylt")) > 0: bad.append("no table")
if not (isinstance(r["anees_poses"][0], float) and isinstance(r["anees_landmarks"][0], float)):
    bad.append(f"ANEES {r['anees_landmarks']} {r['anees_poses']}")
print("; ".join(bad))
PY
)
if [ -z "$msg" ]; then echo "[       OK ] consistency.scene_file ($(tail -1 "$T/slog" | cut -c1-160))"
else echo "  $msg"; echo "[  FAILED  ] consistency.scene_file"; exit 1; fi

echo "[ RUN      ] consistency.detect_args"
if .venv/bin/python scripts/consistency.py --scene tests/fixtures/scenes/variant.yaml --seeds 101 --frames 2 \
     --drives-only --build "$B" --out "$T/d" --detect-args "--missing-part-share -1" >"$T/dlog" 2>"$T/derr"; then
  echo "  --detect-args '--missing-part-share -1' did not fail"; echo "[  FAILED  ] consistency.detect_args"; exit 1
fi
if grep -q -- "--missing-part-share: must be 0..10" "$T/derr"; then echo "[       OK ] consistency.detect_args"; echo "[  PASSED  ] 3 tests."
else echo "  no cyl detect message in: $(tail -3 "$T/derr")"; echo "[  FAILED  ] consistency.detect_args"; exit 1; fi
