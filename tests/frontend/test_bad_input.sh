#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Bad-input matrix at the tools' level: each bad input gives a clear error naming what
# is wrong, a non-zero exit, no crash (no exit >= 128), and never a partial file in place of a
# good one. (Covered elsewhere: strides and dimensions in tests/unit/test_image.c and
# test_segment.c, corrupt tables in test_colortable.c, corrupt logs in test_rawlog.cpp and the
# slam_demo tests, truncated logs, missing devices and malformed YAML in test_cli.sh, non-finite
# and negative sigmas in test_camera.c.) Prints GoogleTest-style lines.
#   test_bad_input.sh path/to/cyl
set -u
CYL=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
cd "$(dirname "$0")/../.."
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
TABLE=calib_data/synthetic.cylt; CALIB=calib_data/synthetic_camera.yaml
passed=0; failed=0
check() {  # check NAME EXPECTED_EXIT STDERR_PATTERN -- command...
  local name=$1 code=$2 pat=$3; shift 4
  echo "[ RUN      ] bad_input.$name"
  echo GOOD > "$T/good.jsonl"
  timeout 60 "$@" >"$T/out" 2>"$T/err"; local rc=$? msg=""
  [ $rc -eq "$code" ] || msg="exit $rc, expected $code"
  [ $rc -lt 124 ] || msg="$msg; crashed or hung (exit $rc)"
  [ -z "$pat" ] || grep -qE -- "$pat" "$T/err" || msg="$msg; stderr lacks /$pat/: $(head -c 200 "$T/err")"
  [ "$(cat "$T/good.jsonl")" = GOOD ] || msg="$msg; the good output file was replaced"
  if [ -z "$msg" ]; then passed=$((passed + 1)); echo "[       OK ] bad_input.$name"
  else failed=$((failed + 1)); echo "  $msg"; echo "[  FAILED  ] bad_input.$name"; fi
}
"$CYL" record synthetic:2 --frames 3 --out "$T/s.cylraw" --quiet
# detect SOURCE TABLE CALIB: a script (timeout runs programs, not shell functions)
printf '#!/usr/bin/env bash\nexec "%s" detect "$1" --table "$2" --calib "$3" --out "%s/good.jsonl" --quiet\n' "$CYL" "$T" > "$T/detect"
chmod +x "$T/detect"

: > "$T/empty"
check empty_table 1 "empty: table file truncated" -- "$T/detect" "$T/s.cylraw" "$T/empty" $CALIB
# calibration keys: a misspelled key is an error naming it and the nearest known key (it would
# otherwise silently become a default: no distortion); --lenient makes it a warning; a key given
# twice is an error either way
sed "s/^distortion_coefficients:/distortion_coeficients:/" $CALIB > "$T/typo.yaml"
check calib_misspelled_key 1 "typo.yaml:[0-9]+: unknown key 'distortion_coeficients' \(did you mean 'distortion_coefficients'\?\)" \
  -- "$T/detect" "$T/s.cylraw" $TABLE "$T/typo.yaml"
echo "[ RUN      ] bad_input.calib_misspelled_key_lenient"
if "$CYL" detect "$T/s.cylraw" --table $TABLE --calib "$T/typo.yaml" --lenient --out "$T/len.jsonl" --quiet 2>"$T/err" &&
   grep -q "warning: .*typo.yaml:[0-9]*: unknown key 'distortion_coeficients'.*ignored (--lenient)" "$T/err"; then
  passed=$((passed + 1)); echo "[       OK ] bad_input.calib_misspelled_key_lenient"
else failed=$((failed + 1)); echo "  $(head -c 300 "$T/err")"; echo "[  FAILED  ] bad_input.calib_misspelled_key_lenient"; fi
sed "s/^intrinsic_covariance:/intrinsic_covarience:/" $CALIB > "$T/typo2.yaml"
check calib_misspelled_covariance 1 "unknown key 'intrinsic_covarience' \(did you mean 'intrinsic_covariance'\?\)" \
  -- "$T/detect" "$T/s.cylraw" $TABLE "$T/typo2.yaml"
{ cat $CALIB; echo "mount_tilt_deg: 30"; } > "$T/dup.yaml"
check calib_duplicate_key 1 "dup.yaml: field 'mount_tilt_deg': given twice \(lines [0-9]+ and [0-9]+\)" \
  -- "$T/detect" "$T/s.cylraw" $TABLE "$T/dup.yaml"
# scene files: a misspelled key is an error naming where it is and the nearest known key
RENDER=$(dirname "$CYL")/cyl-render
"$RENDER" --write-scene "$T/scene.yaml" -q
sed "s/^imaging:/imagng:/" "$T/scene.yaml" > "$T/scene_top.yaml"
check scene_misspelled_section 1 "scene_top.yaml: \(top level\): unknown key 'imagng' \(did you mean 'imaging'\?\)" -- \
  "$RENDER" -S "$T/scene_top.yaml" -n 1 -q -o "$T/r.cylraw"
python3 - "$T/scene.yaml" "$T/scene_cyl.yaml" <<'PY'
import sys
lines = open(sys.argv[1]).read().split("\n")
k = [i for i, l in enumerate(lines) if l.strip().startswith("diameter_m:")][2]   # the third cylinder
lines[k] = lines[k].replace("diameter_m:", "diamter_m:")
open(sys.argv[2], "w").write("\n".join(lines))
PY
check scene_misspelled_cylinder_key 1 "scene_cyl.yaml: cylinders\[2\]: unknown key 'diamter_m' \(did you mean 'diameter_m'\?\)" -- \
  "$RENDER" -S "$T/scene_cyl.yaml" -n 1 -q -o "$T/r.cylraw"
# frames of another size than the calibration's: an error naming both sizes, before any output
check frame_size_mismatch 1 "paper_camera.yaml: calibrated for 768x576 px, but synthetic:2 gives 640x480 px" -- \
  "$CYL" detect synthetic:2 --calib calib_data/paper_camera.yaml --max-frames 2 --out "$T/good.jsonl" --quiet
# no --size for a class: runs, and warns that its observations get confidence 0
echo "[ RUN      ] bad_input.missing_size_warns"
if "$CYL" detect "$T/s.cylraw" --table $TABLE --calib $CALIB --out "$T/w.jsonl" --quiet 2>"$T/err" &&
   grep -q "warning: class 'orange' has no landmark size (--size orange=D,H): its observations get confidence 0" "$T/err"; then
  passed=$((passed + 1)); echo "[       OK ] bad_input.missing_size_warns"
else failed=$((failed + 1)); echo "  $(head -c 300 "$T/err")"; echo "[  FAILED  ] bad_input.missing_size_warns"; fi
# --show without a display: a clear usage error, not Qt's abort (exit 134), and no .part left
check show_without_display 2 "--show needs a display" -- env -u DISPLAY -u WAYLAND_DISPLAY "$CYL" detect "$T/s.cylraw" \
  --table $TABLE --calib $CALIB --out "$T/good.jsonl" --show --quiet
[ ! -e "$T/good.jsonl.part" ] || { failed=$((failed + 1)); echo "  a .part file was left"; echo "[  FAILED  ] bad_input.show_without_display_part"; }
# --overlay with a container other than .avi: a usage error, and no folder named x.mp4 made
check overlay_mp4 2 "x.mp4: the video is written as MJPG in an .avi" -- "$CYL" detect "$T/s.cylraw" --table $TABLE \
  --calib $CALIB --out "$T/good.jsonl" --overlay "$T/x.mp4" --quiet
[ ! -e "$T/x.mp4" ] || { failed=$((failed + 1)); echo "  a folder x.mp4 was made"; echo "[  FAILED  ] bad_input.overlay_mp4_no_folder"; }
: > "$T/afile"
check overlay_onto_file 1 "afile: --overlay names an existing file that is not a folder" -- "$CYL" detect "$T/s.cylraw" \
  --table $TABLE --calib $CALIB --out "$T/good.jsonl" --overlay "$T/afile" --quiet
check empty_calib 1 "empty: not a calibration file" -- "$T/detect" "$T/s.cylraw" $TABLE "$T/empty"
: > "$T/empty.cylraw"
check empty_raw_log 1 "empty.cylraw: not a libcyl raw frame log" -- "$T/detect" "$T/empty.cylraw" $TABLE $CALIB
for v in .nan .inf -0.5; do
  sed "s/^mount_tilt_sigma_deg:.*/mount_tilt_sigma_deg: $v/" $CALIB > "$T/sig.yaml"
  check "calib_tilt_sigma_$v" 1 "sig.yaml.*mount_tilt_sigma_deg|sig.yaml.*(non-finite|negative)" -- "$T/detect" "$T/s.cylraw" $TABLE "$T/sig.yaml"
done
sed "s/^image_width:.*/image_width: 99999999999/" $CALIB > "$T/huge.yaml"
check calib_huge_width 1 "huge.yaml.*image_width" -- "$T/detect" "$T/s.cylraw" $TABLE "$T/huge.yaml"
# raw log headers: huge dimensions, stride smaller than a row, frame size that does not match
python3 - "$T/s.cylraw" "$T" <<'PY'
import struct, sys
d = bytearray(open(sys.argv[1], 'rb').read())
def w(name, off, val):
    b = bytearray(d); struct.pack_into('<I', b, off, val); open(f"{sys.argv[2]}/{name}.cylraw", 'wb').write(b)
w('huge', 20, 4000000000)     # width
w('stride', 28, 100)          # stride < 2 * 640
w('framesize', 32, 12345)     # payload size field
PY
check raw_huge_width 1 "huge.cylraw: header field: invalid frame size" -- "$T/detect" "$T/huge.cylraw" $TABLE $CALIB
check raw_stride_small 1 "stride.cylraw: header field: invalid frame size" -- "$T/detect" "$T/stride.cylraw" $TABLE $CALIB
check raw_frame_size 1 "framesize.cylraw: header field: frame size field 12345" -- "$T/detect" "$T/framesize.cylraw" $TABLE $CALIB
# a tilt that puts the horizon in view: no crash, the rays above it flagged no-range (0x100)
sed "s/^mount_tilt_deg:.*/mount_tilt_deg: -25/" $CALIB > "$T/up.yaml"
echo "[ RUN      ] bad_input.horizon_in_view"
if "$CYL" detect "$T/s.cylraw" --table $TABLE --calib "$T/up.yaml" --out "$T/up.jsonl" --quiet &&
   python3 - "$T/up.jsonl" <<'PY'
import json, sys
obs = [json.loads(l) for l in open(sys.argv[1]) if '"type":"obs"' in l]
nr = [o for o in obs if o["flags"] & 0x100]
assert obs and len(nr) == len(obs), (len(obs), len(nr))   # camera looking up: every ray above the horizon
assert all(o["range_m"] == 0 and o["cov_bb"] is not None and o["cov_bb"] > 0 for o in nr)
PY
then passed=$((passed + 1)); echo "[       OK ] bad_input.horizon_in_view"
else failed=$((failed + 1)); echo "[  FAILED  ] bad_input.horizon_in_view"; fi
echo "[==========] $((passed + failed)) tests ran."
echo "[  PASSED  ] $passed tests."
[ $failed -eq 0 ] || echo "[  FAILED  ] $failed tests."
[ $failed -eq 0 ]
