#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The cyl tool as a user meets it: exit codes, errors that name what is wrong, no partial
# output in place of a good file, a clean stop on SIGINT that keeps every complete record.
# Prints GoogleTest-style lines for scripts/run-tests.sh.
#   test_cli.sh path/to/cyl
set -u
CYL=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
cd "$ROOT"
TABLE=calib_data/synthetic.cylt
CALIB=calib_data/synthetic_camera.yaml
passed=0; failed=0; current=""; ok=1

start() { current=$1; ok=1; echo "[ RUN      ] cli.$1"; }
fail() { echo "  $*"; ok=0; }
finish() {
  if [ $ok -eq 1 ]; then passed=$((passed + 1)); echo "[       OK ] cli.$current"
  else failed=$((failed + 1)); echo "[  FAILED  ] cli.$current"; fi
}
# expect_exit CODE PATTERN -- command...: exit code and a stderr line matching PATTERN
expect_exit() {
  local code=$1 pat=$2; shift 3
  "$@" >"$T/out" 2>"$T/err"; local rc=$?
  [ $rc -eq "$code" ] || fail "exit $rc, expected $code: $*"
  [ -z "$pat" ] || grep -qE -- "$pat" "$T/err" || fail "stderr lacks /$pat/: $(head -c 300 "$T/err")"
}
valid_jsonl() {  # every line is a JSON object; prints frame and obs counts
  python3 - "$1" <<'EOF'
import json, sys
frames = obs = 0
for n, line in enumerate(open(sys.argv[1]), 1):
    o = json.loads(line)
    assert isinstance(o, dict) and "type" in o, f"line {n}"
    frames += o["type"] == "frame"
    obs += o["type"] == "obs"
    if o["type"] == "obs" and not (o["flags"] & 0x320):
        assert o["range_m"] > 0 and o["cov_rr"] > 0 and o["cov_bb"] > 0, f"line {n}: {o}"
        assert o["cov_rb"] ** 2 <= o["cov_rr"] * o["cov_bb"] * (1 + 1e-9), f"line {n}: not PSD"
print(frames, obs)
EOF
}

start usage
expect_exit 0 "" -- "$CYL" --help
grep -q "usage: cyl" "$T/out" || fail "--help prints no usage"
expect_exit 2 "no command given" -- "$CYL"
expect_exit 2 "unknown option '--bogus'" -- "$CYL" detect x --bogus
expect_exit 2 "--max-frames: expected a whole number" -- "$CYL" detect x --max-frames -3
expect_exit 2 "--model: exact or paper" -- "$CYL" detect x --model wrong
expect_exit 2 "--edges: subpixel or table" -- "$CYL" detect x --edges soft
finish

start record_and_info
expect_exit 0 "" -- "$CYL" record synthetic:3 --frames 12 --out "$T/s.cylraw"
[ -f "$T/s.cylraw" ] && [ ! -f "$T/s.cylraw.part" ] || fail "no renamed output"
expect_exit 0 "" -- "$CYL" info "$T/s.cylraw"
grep -q "records: 12 frames, 12 odometry, 12 truth poses" "$T/out" || fail "info: $(cat "$T/out")"
grep -q "ground-truth" "$T/out" || fail "info: no ground-truth flag"
finish

start detect_raw_log
expect_exit 0 "" -- "$CYL" detect "$T/s.cylraw" --table $TABLE --calib $CALIB --out "$T/o.jsonl" --quiet
counts=$(valid_jsonl "$T/o.jsonl") || fail "invalid JSON lines"
set -- $counts
[ "${1:-0}" -eq 12 ] || fail "frames: ${1:-?}"
[ "${2:-0}" -gt 0 ] || fail "no observations"
grep -q '"type":"odom"' "$T/o.jsonl" || fail "no odometry passed through"
grep -q '"type":"truth_landmark"' "$T/o.jsonl" || fail "no truth passed through"
# sub-pixel edges (the default) log their shift; --edges table leaves the blob's centroid
grep -q '"subpixel_shift_px"' "$T/o.jsonl" || fail "no subpixel_shift_px with the default edges"
expect_exit 0 "" -- "$CYL" detect "$T/s.cylraw" --table $TABLE --calib $CALIB --edges table --out "$T/t.jsonl" --quiet
grep -q '"subpixel_shift_px"' "$T/t.jsonl" && fail "subpixel_shift_px with --edges table"
[ "$(grep -c '"type":"obs"' "$T/t.jsonl")" -eq "$(grep -c '"type":"obs"' "$T/o.jsonl")" ] || fail "--edges changed the observation count"
expect_exit 2 "--silhouette-sigma: expected U,V" -- "$CYL" detect "$T/s.cylraw" --table $TABLE --calib $CALIB --silhouette-sigma 0.1 --out "$T/x.jsonl"
expect_exit 2 "--silhouette-sigma: each must be 0..100 px" -- "$CYL" detect "$T/s.cylraw" --table $TABLE --calib $CALIB --silhouette-sigma 0.1,-1 --out "$T/x.jsonl"
# with the classes' sizes every observation with a range carries aspect_rel, and
# --partial-aspect-min F flags 0x800 exactly where it lies outside [F, 1/F] (default 0.8)
SIZES="--size orange=0.10,0.30 --size green=0.10,0.30"
expect_exit 0 "" -- "$CYL" detect "$T/s.cylraw" --table $TABLE --calib $CALIB $SIZES --out "$T/a.jsonl" --quiet
expect_exit 0 "" -- "$CYL" detect "$T/s.cylraw" --table $TABLE --calib $CALIB $SIZES --partial-aspect-min 0.999 --out "$T/p.jsonl" --quiet
python3 - "$T/a.jsonl" "$T/p.jsonl" <<'PY' || fail "0x800 not where aspect_rel says"
import json, sys
for path, m in ((sys.argv[1], 0.8), (sys.argv[2], 0.999)):
    n = 0
    for line in open(path):
        o = json.loads(line)
        if o["type"] != "obs":
            continue
        assert "aspect_rel" in o or o["flags"] & 0x100, (path, o["seq"], "no aspect_rel")
        a = o.get("aspect_rel", 1.0)
        assert bool(o["flags"] & 0x800) == (a < m or a * m > 1), (path, o["seq"], a, o["flags"])
        n += bool(o["flags"] & 0x800)
    assert m == 0.8 or n > 0, "0.999 flagged nothing"
PY
expect_exit 2 "--partial-aspect-min: must be 0..2" -- "$CYL" detect "$T/s.cylraw" --table $TABLE --calib $CALIB --partial-aspect-min -1 --out "$T/x.jsonl"
# side_colour_rel is logged (-1..1) and --partial-side-max F flags 0x800 where |side_colour_rel| > F
# (and nowhere else that the default run did not flag); off by default
expect_exit 0 "" -- "$CYL" detect "$T/s.cylraw" --table $TABLE --calib $CALIB $SIZES --partial-side-max 0.05 --out "$T/sd.jsonl" --quiet
python3 - "$T/a.jsonl" "$T/sd.jsonl" <<'PY' || fail "side_colour_rel or its flag"
import json, sys
def obs(path):
    return [o for o in map(json.loads, open(path)) if o["type"] == "obs"]
a, b = obs(sys.argv[1]), obs(sys.argv[2])
assert len(a) == len(b) and any("side_colour_rel" in o for o in a), "no side_colour_rel logged"
n = 0
for x, y in zip(a, b):
    s = x.get("side_colour_rel", 0.0)
    assert -1.0 <= s <= 1.0 and s == y.get("side_colour_rel", 0.0), (x["seq"], s)
    assert bool(y["flags"] & 0x800) == (bool(x["flags"] & 0x800) or abs(s) > 0.05), (x["seq"], s, x["flags"], y["flags"])
    n += abs(s) > 0.05 and not x["flags"] & 0x800
assert n > 0, "0.05 flagged nothing more"
PY
expect_exit 2 "--partial-side-max: must be 0..2" -- "$CYL" detect "$T/s.cylraw" --table $TABLE --calib $CALIB --partial-side-max -0.1 --out "$T/x.jsonl"
# --side-sigma C --side-sigma-free D: (C (|side_colour_rel| - D) w)^2 added to var_u_px2 of every
# view with a range (w from its bbox_px), nothing else of the centroid changed, the range's variance grown
expect_exit 0 "" -- "$CYL" detect "$T/s.cylraw" --table $TABLE --calib $CALIB $SIZES --side-sigma 0 --out "$T/s0.jsonl" --quiet
expect_exit 0 "" -- "$CYL" detect "$T/s.cylraw" --table $TABLE --calib $CALIB $SIZES --side-sigma 0.5 --side-sigma-free 0.05 --out "$T/s1.jsonl" --quiet
python3 - "$T/s0.jsonl" "$T/s1.jsonl" <<'PY' || fail "--side-sigma"
import json, sys
def obs(path):
    return [o for o in map(json.loads, open(path)) if o["type"] == "obs"]
a, b = obs(sys.argv[1]), obs(sys.argv[2])
assert len(a) == len(b)
n = 0
for x, y in zip(a, b):
    s = abs(x.get("side_colour_rel", 0.0))
    w = x["bbox_px"][2] - x["bbox_px"][0] + 1
    add = (0.5 * max(s - 0.05, 0.0) * w) ** 2 if not x["flags"] & 0x300 else 0.0
    assert abs(y["var_u_px2"] - x["var_u_px2"] - add) <= 1e-6 * (x["var_u_px2"] + add), (x["seq"], s, x["var_u_px2"], y["var_u_px2"], add)
    assert y["var_v_px2"] == x["var_v_px2"] and y["u_px"] == x["u_px"] and y["flags"] == x["flags"], x["seq"]
    if add > 0:
        assert y["cov_rr"] > x["cov_rr"] and y["range_m"] == x["range_m"], x["seq"]
        n += 1
assert n > 0, "no view's variance grew"
PY
expect_exit 2 "--side-sigma-free: must be 0..1" -- "$CYL" detect "$T/s.cylraw" --table $TABLE --calib $CALIB --side-sigma-free 1.5 --out "$T/x.jsonl"
finish

start stdout_stream
"$CYL" detect "$T/s.cylraw" --table $TABLE --calib $CALIB --max-frames 3 > "$T/stdout.jsonl" 2>/dev/null || fail "exit $?"
[ "$(grep -c '"type":"frame"' "$T/stdout.jsonl")" -eq 3 ] || fail "--max-frames 3 on stdout"
finish

start bad_inputs_name_the_problem
expect_exit 1 "missing.cylt: cannot open colour table" -- "$CYL" detect "$T/s.cylraw" --table "$T/missing.cylt" --calib $CALIB --out "$T/x.jsonl"
head -c 1000 $TABLE > "$T/short.cylt"
expect_exit 1 "short.cylt: table file truncated" -- "$CYL" detect "$T/s.cylraw" --table "$T/short.cylt" --calib $CALIB --out "$T/x.jsonl"
sed 's/^image_width:.*/image_width: wide/' $CALIB > "$T/bad.yaml"
expect_exit 1 "bad.yaml.*image_width" -- "$CYL" detect "$T/s.cylraw" --table $TABLE --calib "$T/bad.yaml" --out "$T/x.jsonl"
grep -v '^mount_' $CALIB > "$T/nomount.yaml"
expect_exit 1 "nomount.yaml: no mount fields" -- "$CYL" detect "$T/s.cylraw" --table $TABLE --calib "$T/nomount.yaml" --out "$T/x.jsonl"
# a file on which OpenCV 4.6's YAML parser loops forever (found by fuzzing): a clear error, at once
expect_exit 1 "regress-opencv46-hang.yaml:5: unknown key 'ro'" -- timeout 10 "$CYL" detect "$T/s.cylraw" \
  --table $TABLE --calib tests/fuzz/corpus/fuzz_calib/regress-opencv46-hang.yaml --out "$T/x.jsonl"
echo "not a log" > "$T/junk.cylraw"
expect_exit 1 "junk.cylraw: not a libcyl raw frame log" -- "$CYL" info "$T/junk.cylraw"
expect_exit 1 "no such device" -- "$CYL" detect /dev/video77 --table $TABLE --calib $CALIB
[ ! -e "$T/x.jsonl" ] && [ ! -e "$T/x.jsonl.part" ] || fail "a failed run left an output file"
finish

start good_output_never_replaced_by_a_failed_run
cp "$T/o.jsonl" "$T/keep.jsonl"; sum=$(md5sum < "$T/keep.jsonl")
expect_exit 1 "" -- "$CYL" detect "$T/junk.cylraw" --table $TABLE --calib $CALIB --out "$T/keep.jsonl"
[ "$(md5sum < "$T/keep.jsonl")" = "$sum" ] || fail "the good file was changed"
finish

start truncated_raw_log_keeps_complete_frames
size=$(stat -c %s "$T/s.cylraw"); head -c $((size - 1000)) "$T/s.cylraw" > "$T/cut.cylraw"
expect_exit 0 "ends with a truncated record" -- "$CYL" detect "$T/cut.cylraw" --table $TABLE --calib $CALIB --out "$T/cut.jsonl"
set -- $(valid_jsonl "$T/cut.jsonl")
[ "${1:-0}" -ge 11 ] || fail "frames from a cut log: ${1:-?}"
finish

start sigint_stops_cleanly_and_keeps_records
"$CYL" detect synthetic:5 --frames 100000 --out "$T/int.jsonl" --quiet 2>"$T/int.err" &
pid=$!
for i in $(seq 1 100); do
  [ -f "$T/int.jsonl.part" ] && [ "$(grep -c '"type":"frame"' "$T/int.jsonl.part" 2>/dev/null)" -ge 3 ] && break
  sleep 0.2
done
kill -INT $pid; wait $pid; rc=$?
[ $rc -eq 130 ] || fail "exit $rc after SIGINT, expected 130"
[ -f "$T/int.jsonl" ] && [ ! -f "$T/int.jsonl.part" ] || fail "output not closed and renamed"
set -- $(valid_jsonl "$T/int.jsonl") || fail "invalid lines after SIGINT"
[ "${1:-0}" -ge 3 ] || fail "frames kept: ${1:-?}"
finish

start killed_run_keeps_complete_lines_in_part_file
"$CYL" detect synthetic:6 --frames 100000 --out "$T/kill.jsonl" --quiet 2>/dev/null &
pid=$!
for i in $(seq 1 100); do
  [ -f "$T/kill.jsonl.part" ] && [ "$(grep -c '"type":"frame"' "$T/kill.jsonl.part" 2>/dev/null)" -ge 2 ] && break
  sleep 0.2
done
kill -KILL $pid; wait $pid 2>/dev/null
[ ! -f "$T/kill.jsonl" ] || fail "a killed run produced the final file"
valid_jsonl "$T/kill.jsonl.part" >/dev/null || fail "the .part file has a broken line"
finish

# progress on a non-terminal: plain lines, no carriage returns (a log file stays readable)
start progress_without_terminal
B=$(dirname "$CYL")
"$B/cyl-render" -n 12 -o "$T/p.cylraw" 2>"$T/p.err" || fail "cyl-render failed: $(head -c 300 "$T/p.err")"
"$CYL" detect "$T/p.cylraw" --table $TABLE --calib $CALIB --out "$T/p.jsonl" 2>>"$T/p.err" || fail "detect failed"
! grep -q $'\r' "$T/p.err" || fail "carriage returns written to a non-terminal"
grep -q "^rendering: 100%" "$T/p.err" || fail "no progress line from cyl-render: $(head -c 300 "$T/p.err")"
grep -q "^detecting: 100%" "$T/p.err" || fail "no progress line from cyl detect: $(head -c 300 "$T/p.err")"
finish

# --max-frames N keeps the N-th frame's odometry and truth (they follow the frame in the source)
start max_frames_keeps_last_odometry
"$CYL" detect synthetic:3 --max-frames 5 --out "$T/mf.jsonl" --quiet 2>"$T/err" || fail "detect failed: $(head -c 300 "$T/err")"
counts=$(python3 -c "
import json, sys
t = [json.loads(l)['type'] for l in open(sys.argv[1])]
print(t.count('frame'), t.count('odom'), t.count('truth_pose'))" "$T/mf.jsonl")
[ "$counts" = "5 5 5" ] || fail "frames, odom, truth_pose: $counts (expected 5 5 5)"
"$CYL" record synthetic:3 --max-frames 4 --out "$T/mf.cylraw" --quiet 2>"$T/err" || fail "record failed"
"$CYL" detect "$T/mf.cylraw" --table $TABLE --calib $CALIB --out "$T/mf2.jsonl" --quiet 2>"$T/err" || fail "detect on the recording failed"
counts=$(python3 -c "
import json, sys
t = [json.loads(l)['type'] for l in open(sys.argv[1])]
print(t.count('frame'), t.count('odom'), t.count('truth_pose'))" "$T/mf2.jsonl")
[ "$counts" = "4 4 4" ] || fail "recorded with --max-frames 4: frames, odom, truth_pose $counts (expected 4 4 4)"
finish

# --version on every tool: "<tool> <version> (libcyl <version>)", the version from cyl/version.h
start version_on_every_tool
hv=$(sed -n 's/^#define CYL_VERSION_STRING "\(.*\)"/\1/p' libcyl/include/cyl/version.h)
B=$(dirname "$CYL")
for t in cyl cyl-render cyl-train cyl-calibrate cyl-synth-validate cyl_paper; do
  [ -x "$B/$t" ] || { fail "$B/$t not built"; continue; }
  out=$("$B/$t" --version 2>&1); rc=$?
  [ $rc -eq 0 ] || fail "$t --version: exit $rc"
  [ "$out" = "$t $hv (libcyl $hv)" ] || fail "$t --version printed '$out'"
done
finish

# `cyl` links OpenCV's core and imgproc only: image and video files and windows come from the
# media plugin, loaded at first use (a camera or raw log in, observations out loads none of it)
start lean_linking
n=$(ldd "$CYL" | wc -l)
[ "$n" -le 80 ] || fail "ldd $CYL lists $n libraries (at most 80)"
ldd "$CYL" | grep -E "opencv_(highgui|videoio|imgcodecs)|libQt|libgdal|libavcodec" && fail "cyl links a codec, video or GUI library"
expect_exit 0 "" -- "$CYL" detect synthetic:2 --max-frames 2 --out "$T/lean.jsonl" --quiet
# an image file needs the plugin: it works with it, and without it the error names the plugin and where it looked
python3 -c "
import struct, zlib
w, h = 640, 480
raw = b''.join(b'\\x00' + bytes([120, 120, 120] * w) for _ in range(h))
chunk = lambda t, d: struct.pack('>I', len(d)) + t + d + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)
open('$T/grey.png', 'wb').write(b'\\x89PNG\\r\\n\\x1a\\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 2, 0, 0, 0))
                                + chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b''))"
expect_exit 0 "" -- "$CYL" detect "$T/grey.png" --table $TABLE --calib $CALIB --out "$T/png.jsonl" --quiet
grep -q '"type":"frame"' "$T/png.jsonl" 2>/dev/null || fail "no frame record from the PNG"
expect_exit 1 "need the plugin libcyl-media.so .*$T/none.so: not there; CYL_MEDIA_PLUGIN names it" -- \
  env CYL_MEDIA_PLUGIN="$T/none.so" "$CYL" detect "$T/grey.png" --table $TABLE --calib $CALIB --out "$T/png2.jsonl" --quiet
[ ! -e "$T/png2.jsonl" ] || fail "a log was left behind after the plugin error"
finish

echo "[==========] $((passed + failed)) tests ran."
echo "[  PASSED  ] $passed tests."
[ $failed -eq 0 ] || echo "[  FAILED  ] $failed tests."
[ $failed -eq 0 ]
