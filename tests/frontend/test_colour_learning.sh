#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Colour learning from labelled real images, as a user runs it: cyl-train learn on the committed
# real-image subset (tests/fixtures/real: RoboCup ball, Apache-2.0; FRC cones and cubes,
# CC BY 4.0), cyl-score on its held-out images, the detector config it writes read back by
# cyl detect, the observation log's blob boxes, and the tools' bad input. The subset's figures are
# asserted against floors a little under what this code measures on it (the figures and the rule
# are in docs/colour-learning.md); the full benchmark is make realeval. GoogleTest-style lines.
#   test_colour_learning.sh BUILD_DIR
set -u
B=$(cd "$1" && pwd)
cd "$(dirname "$0")/../.."
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
R=tests/fixtures/real
passed=0; failed=0
ok() { passed=$((passed + 1)); echo "[       OK ] colour_learning.$1"; }
bad() { failed=$((failed + 1)); echo "  $2"; echo "[  FAILED  ] colour_learning.$1"; }
run() { echo "[ RUN      ] colour_learning.$1"; }
expect() {  # expect NAME EXIT STDERR_PATTERN -- command...
  local name=$1 code=$2 pat=$3; shift 4
  run "$name"
  timeout 120 "$@" >"$T/out" 2>"$T/err"; local rc=$? msg=""
  [ $rc -eq "$code" ] || msg="exit $rc, expected $code"
  [ -z "$pat" ] || grep -qE -- "$pat" "$T/err" || msg="$msg; stderr lacks /$pat/: $(head -c 300 "$T/err")"
  if [ -z "$msg" ]; then ok "$name"; else bad "$name" "$msg"; fi
}

# 1. the subset benchmark: learn, score, floors
run subset_benchmark
if python3 scripts/realeval.py --subset $R --build "$B" --out "$T/re" >"$T/re.log" 2>"$T/re.err"; then
  tail -1 "$T/re.log" > "$T/re.json"
  msg=$(python3 - "$T/re.json" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1]))
# measured on this subset: ball centroid 0.25 (8 balls), cone 0.86, cube 0.92 (0.67 with weak
# blobs alone off: the training images turn them on for the cube alone), hard scene 0.99 (0.44
# before the surround was taken out of the classes), false blobs at most 0.56 per image and 0 per
# rendered frame
floors = {"ball_recall_centroid": 0.2, "cone_recall_iou50": 0.7, "cube_recall_iou50": 0.8, "hard_synth_recall": 0.9}
out = [f"{k} {r[k]:.3f} < {v}" for k, v in floors.items() if r[k] < v]
if r["fp_per_image_max"] > 1.0:
    out.append(f"fp_per_image_max {r['fp_per_image_max']:.2f} > 1")
if r["hard_synth_fp_per_frame"] > 0.5:
    out.append(f"hard_synth_fp_per_frame {r['hard_synth_fp_per_frame']:.2f} > 0.5")
print("; ".join(out))
EOF
)
  if [ -z "$msg" ]; then ok subset_benchmark; else bad subset_benchmark "$msg ($(cat "$T/re.json"))"; fi
else
  bad subset_benchmark "realeval.py failed: $(tail -5 "$T/re.err")"
fi

# 2. the learned table is a version-2 file, and has the weak classes
run table_version_2
v=$(od -An -tu2 -j4 -N2 "$T/re/frc.cylt" 2>/dev/null | tr -d ' ')
sz=$(stat -c %s "$T/re/frc.cylt" 2>/dev/null)
if [ "$v" = 2 ] && [ "$sz" = 197036 ]; then ok table_version_2; else bad table_version_2 "version '$v', size '$sz'"; fi

# 3. the training report: every class, its weak class, recall and background claimed
run training_report
if python3 - "$T/re/frc-training.json" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1]))
names = [c["name"] for c in r["classes"]]
assert names == ["cone", "cube"], names
for c in r["classes"]:
    assert c["weak_index"] is not None
    assert 0 < c["recall"] <= 1 and 0 <= c["background_claimed"] <= 0.01, c
    assert c["box_aspect_range"][0] > 0, c
    # weak blobs alone, chosen on the training images: on exactly when they find more boxes there
    # and keep the false blobs within 1 per image (on this subset: the cube only, 7 -> 8 of 9)
    w = c["weak_alone"]
    gain = w["train_boxes_found_on"] > w["train_boxes_found_off"] and w["train_fp_per_image_on"] <= 1.0
    assert w["tried_area_px"] == 700 and w["min_area_px"] == (700 if gain else 0), c
assert [c["weak_alone"]["min_area_px"] for c in r["classes"]] == [0, 700], r
assert r["images"] == 10
EOF
then ok training_report; else bad training_report "report check failed"; fi

# 3b. the per-box CSV (cyl-score --boxes) of the subset run: a found box names its blob, whose box
# overlaps the label box at IoU >= 0.5 (recomputed here); a box not found has empty blob columns; a
# false blob's row repeats its box in the blob columns, with its area >= 20 px
run boxes_csv
if msg=$(python3 - "$T/re/frc-boxes.csv" "$T/re/ball-boxes.csv" 2>&1 <<'EOF'
import csv, sys
n_found = n_false = 0
for path in sys.argv[1:]:
    rows = list(csv.DictReader(open(path)))
    assert rows and list(rows[0])[-6:] == ["blob_x0_px", "blob_y0_px", "blob_x1_px", "blob_y1_px",
                                           "blob_area_px", "blob_flags"], list(rows[0])
    for r in rows:
        box = [float(r[k]) for k in ("x0_px", "y0_px", "x1_px", "y1_px")]
        if r["matched_iou"] == "false_blob":
            blob = [float(r[k]) for k in ("blob_x0_px", "blob_y0_px", "blob_x1_px", "blob_y1_px")]
            assert blob == box and int(r["blob_area_px"]) >= 20, r
            n_false += 1
        elif r["matched_iou"] == "1":
            b = [float(r[k]) for k in ("blob_x0_px", "blob_y0_px", "blob_x1_px", "blob_y1_px")]
            ix = min(box[2], b[2]) - max(box[0], b[0])
            iy = min(box[3], b[3]) - max(box[1], b[1])
            inter = max(ix, 0) * max(iy, 0)
            iou = inter / ((box[2] - box[0]) * (box[3] - box[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter)
            assert 0.5 <= iou <= float(r["best_iou"]) + 5e-3, (r, iou)   # boxes and IoU printed rounded
            assert 0 < int(r["blob_area_px"]) <= (b[2] - b[0]) * (b[3] - b[1]), r
            n_found += 1
        else:
            assert r["matched_iou"] == "0" and r["blob_area_px"] == "", r
assert n_found >= 5 and n_false >= 1, (n_found, n_false)
EOF
); then ok boxes_csv; else bad boxes_csv "$msg"; fi

# 4. the detector config written by --config-out loads in cyl detect (strict keys) and in cyl-score
run config_round_trip
if grep -q "aspect_range" "$T/re/frc-detector.yaml" &&
   "$B/cyl-score" -q --table "$T/re/frc.cylt" --config "$T/re/frc-detector.yaml" --class cone=0 \
     $R/frc/images/$(sed -n 2p $R/frc/test.list | sed 's|images/||') >/dev/null 2>"$T/err"; then
  ok config_round_trip
else
  bad config_round_trip "$(cat "$T/err")"
fi

# 5. bad input: a label line with 4 fields names file and line; a missing label file; an unknown
# option; an unknown class in a config file
mkdir -p "$T/bad/images" "$T/bad/labels"
cp $R/frc/images/$(sed -n 2p $R/frc/train.list | sed 's|images/||') "$T/bad/images/a.jpg"
printf '0 0.5 0.5 0.1 0.1\n1 0.5 0.5 0.1\n' > "$T/bad/labels/a.txt"
expect label_bad_line 1 "labels/a.txt:2: expected 5 fields" -- "$B/cyl-train" learn -q -o "$T/x.cylt" --class cone=0 "$T/bad/images/a.jpg"
printf '0 0.5 0.5 1.5 0.1\n' > "$T/bad/labels/a.txt"
expect label_outside 1 "labels/a.txt:1: box reaches outside the image" -- "$B/cyl-train" learn -q -o "$T/x.cylt" --class cone=0 "$T/bad/images/a.jpg"
rm "$T/bad/labels/a.txt"
expect label_missing 1 "a.jpg: no label file" -- "$B/cyl-train" learn -q -o "$T/x.cylt" --class cone=0 "$T/bad/images/a.jpg"
expect learn_unknown_option 2 "unknown argument '--fpp'" -- "$B/cyl-train" learn -o "$T/x.cylt" --fpp 0.1 --class a=0 x.jpg
expect learn_bad_split_axes 2 "--split-axes: 'diagonal' is not rows, columns or both" -- "$B/cyl-train" learn -o "$T/x.cylt" --split-axes diagonal --class a=0 x.jpg
expect learn_bad_class 2 "--class: expected NAME=LABEL" -- "$B/cyl-train" learn -o "$T/x.cylt" --class cone x.jpg
expect score_no_table 2 "--table is required" -- "$B/cyl-score" --class cone=0 x.jpg
printf 'classes:\n  cone:\n    min_fil: 0.3\n' > "$T/c.yaml"
expect config_unknown_key 1 "c.yaml:3: classes.cone: unknown key 'min_fil' \(did you mean 'min_fill'\?\)" -- \
  "$B/cyl-score" -q --table "$T/re/frc.cylt" --config "$T/c.yaml" --class cone=0 "$T/bad/images/a.jpg"
printf 'classes:\n  cones:\n    min_fill: 0.3\n' > "$T/c.yaml"
expect config_unknown_class 1 "c.yaml:2: classes: unknown key 'cones' \(did you mean 'cone'\?\)" -- \
  "$B/cyl-score" -q --table "$T/re/frc.cylt" --config "$T/c.yaml" --class cone=0 "$T/bad/images/a.jpg"
expect learn_version 0 "" -- "$B/cyl-score" --version
expect learn_help 0 "" -- "$B/cyl-train" learn --help

# 6. no output is written when learning fails (the table file keeps its old bytes)
run no_partial_table
echo OLD > "$T/keep.cylt"
"$B/cyl-train" learn -q -o "$T/keep.cylt" --class cone=0 "$T/bad/images/a.jpg" 2>/dev/null
if [ "$(cat "$T/keep.cylt")" = OLD ]; then ok no_partial_table; else bad no_partial_table "the table was replaced"; fi

# 7. cyl detect: the observation log is version 2 and each observation has its blob's box
run obslog_bbox
"$B/cyl" detect synthetic:3 --frames 5 --quiet --out "$T/o.jsonl" --min-area 20 --size-gate 3
if head -1 "$T/o.jsonl" | grep -q '"version":2' && grep '"type":"obs"' "$T/o.jsonl" | head -1 | grep -qE '"bbox_px":\[[0-9]+,[0-9]+,[0-9]+,[0-9]+\]'; then
  ok obslog_bbox
else
  bad obslog_bbox "$(head -c 300 "$T/o.jsonl")"
fi

# 8. a learned table's weak classes (NAME~) need no landmark size; its classes do
run weak_class_no_size_warning
"$B/cyl" detect "$T/re/hard/drive.cylraw" --frames 3 --quiet --table "$T/re/hard.cylt" --calib "$T/re/hard/camera.yaml" \
  --size orange=0.10,0.30 --out "$T/w.jsonl" 2>"$T/w.err"
if ! grep -q "~" "$T/w.err" && grep -q "class 'green' has no landmark size" "$T/w.err"; then
  ok weak_class_no_size_warning
else
  bad weak_class_no_size_warning "$(cat "$T/w.err")"
fi

# 9. cyl-score --calib scores the detector's observations: the expected-size gate applies (a landmark
#    size 100 times too large drops every blob away from the frame's edges), and only with the camera
run score_with_camera
H="$T/re/hard"
ls "$H"/images/*.png | tail -n +2 > "$T/h.list"
printf 'classes:\n  orange:\n    size_m: [%s, %s]\n    size_gate: 2\n' 0.10 0.30 > "$T/h1.yaml"
printf 'classes:\n  orange:\n    size_m: [%s, %s]\n    size_gate: 2\n' 10 30 > "$T/h2.yaml"
rec() { "$B/cyl-score" -q --table "$T/re/hard.cylt" --class orange=0 "$@" "$T/h.list" | tail -1 |
        python3 -c 'import json,sys; print(json.load(sys.stdin)["classes"]["orange"]["recall_iou50"])'; }
r1=$(rec --config "$T/h1.yaml" --calib "$H/camera.yaml"); r2=$(rec --config "$T/h2.yaml" --calib "$H/camera.yaml")
r3=$(rec --config "$T/h2.yaml")
if python3 -c "import sys; a, b, c = map(float, sys.argv[1:]); sys.exit(0 if a >= 0.9 and b == 0 and c >= 0.9 else 1)" "$r1" "$r2" "$r3"; then
  ok score_with_camera
else
  bad score_with_camera "recall with the true size $r1, a size 100x too large $r2, no camera $r3"
fi
expect score_camera_size 1 "is 640x480 px but the camera's frames are 768x576" -- \
  "$B/cyl-score" -q --table "$T/re/hard.cylt" --class orange=0 --calib calib_data/paper_camera.yaml "$T/h.list"
expect score_camera_no_mount 1 "opencv_sample.yaml: no mount fields" -- \
  "$B/cyl-score" -q --table "$T/re/hard.cylt" --class orange=0 --calib calib_data/opencv_sample.yaml "$T/h.list"

echo "[==========] $((passed + failed)) tests ran."
echo "[  PASSED  ] $passed tests."
[ $failed -eq 0 ] || { echo "[  FAILED  ] $failed tests."; exit 1; }
