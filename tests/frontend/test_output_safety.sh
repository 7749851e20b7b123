#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Output safety: every tool that writes a file replaces only a regular file. A character device
# node (made with mknod, as /dev/null is) stays a character device, a FIFO stays a FIFO and gets
# the output, a symbolic link to a regular file stays a link and its target gets the output, and
# a dangling link is refused with exit 1. Each writer of cyl, cyl-render, cyl-train and
# cyl-calibrate is run against each kind of path in a scratch folder. Prints GoogleTest-style lines.
#   test_output_safety.sh BUILD_DIR
set -u
B=$(cd "$1" && pwd)
cd "$(dirname "$0")/../.."
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
TABLE=calib_data/synthetic.cylt; CALIB=calib_data/synthetic_camera.yaml
passed=0; failed=0
result() {  # result NAME MESSAGE (empty message: pass)
  if [ -z "$2" ]; then passed=$((passed + 1)); echo "[       OK ] output_safety.$1"
  else failed=$((failed + 1)); echo "  $2"; echo "[  FAILED  ] output_safety.$1"; fi
}
"$B/cyl" record synthetic:2 --frames 3 --out "$T/s.cylraw" --quiet || { echo "cannot record a fixture"; exit 1; }

# One writer per line: NAME, then the command with @OUT@ where the output path goes.
writers=(
  "detect|$B/cyl detect $T/s.cylraw --table $TABLE --calib $CALIB --out @OUT@ --quiet"
  "record|$B/cyl record synthetic:2 --frames 2 --out @OUT@ --quiet"
  "render|$B/cyl-render -n 2 -q -o @OUT@"
  "render_table|$B/cyl-render -q --write-table @OUT@"
  "render_camera|$B/cyl-render -q --write-camera @OUT@"
  "train|$B/cyl-train -o @OUT@ --class marker --image $T/s.cylraw --frame 0 --rect 300,200,40,40"
  "calibrate|$B/cyl-calibrate intrinsics -q -o @OUT@ tests/fixtures/opencv_left/left01.jpg tests/fixtures/opencv_left/left02.jpg tests/fixtures/opencv_left/left03.jpg tests/fixtures/opencv_left/left04.jpg"
)
run_writer() {  # run_writer COMMAND_TEMPLATE OUT: runs it, stdout/stderr to $T/out, $T/err
  local cmd=${1//@OUT@/$2}
  # shellcheck disable=SC2086  # the template is split into words on purpose (no spaces in paths)
  timeout 300 $cmd >"$T/out" 2>"$T/err"
}

have_mknod=1
mknod "$T/probe" c 1 3 2>/dev/null || have_mknod=0
rm -f "$T/probe"
[ $have_mknod -eq 1 ] || echo "note: mknod is not permitted here (not root?); the device-node cases run on /dev/null only if it is writable"

for w in "${writers[@]}"; do
  name=${w%%|*}; cmd=${w#*|}
  D="$T/$name"; mkdir -p "$D"

  # 1. a character device node (1,3 = the null device): written, never replaced
  echo "[ RUN      ] output_safety.${name}_char_device"
  msg=""
  if [ $have_mknod -eq 1 ]; then
    mknod "$D/null" c 1 3
    run_writer "$cmd" "$D/null"; rc=$?
    [ $rc -eq 0 ] || msg="exit $rc: $(head -c 300 "$T/err")"
    [ -c "$D/null" ] || msg="$msg; $D/null is no longer a character device"
    [ -z "$(ls "$D" | grep -v '^null$')" ] || msg="$msg; left behind: $(ls "$D" | tr '\n' ' ')"
    rm -f "$D/null"
  else
    run_writer "$cmd" /dev/null; rc=$?
    [ $rc -eq 0 ] || msg="exit $rc: $(head -c 300 "$T/err")"
    [ -c /dev/null ] || msg="$msg; /dev/null is no longer a character device"
  fi
  result "${name}_char_device" "$msg"

  # 2. a FIFO with a reader: the reader gets the whole output, the FIFO stays a FIFO
  echo "[ RUN      ] output_safety.${name}_fifo"
  msg=""
  mkfifo "$D/fifo"
  timeout 300 cat "$D/fifo" > "$D.fifo-read" & reader=$!
  run_writer "$cmd" "$D/fifo"; rc=$?
  [ $rc -eq 0 ] || { msg="exit $rc: $(head -c 300 "$T/err")"; exec 8>"$D/fifo"; exec 8>&-; }  # release the reader
  wait $reader
  [ -p "$D/fifo" ] || msg="$msg; $D/fifo is no longer a FIFO"
  [ -s "$D.fifo-read" ] || msg="$msg; the reader got nothing"
  [ -z "$(ls "$D" | grep -v '^fifo$')" ] || msg="$msg; left behind: $(ls "$D" | tr '\n' ' ')"
  rm -f "$D/fifo"
  result "${name}_fifo" "$msg"

  # 3. a symbolic link to a regular file: the link stays, its target is replaced with the output
  #    (the same bytes as a write to a plain path)
  echo "[ RUN      ] output_safety.${name}_symlink"
  msg=""
  echo OLD > "$D/target"; ln -s target "$D/link"
  run_writer "$cmd" "$D/link"; rc=$?
  [ $rc -eq 0 ] || msg="exit $rc: $(head -c 300 "$T/err")"
  [ -L "$D/link" ] || msg="$msg; the link was replaced"
  [ "$(readlink "$D/link")" = target ] || msg="$msg; the link points elsewhere now"
  [ -f "$D/target" ] && [ "$(head -c 4 "$D/target")" != "OLD" ] && [ -s "$D/target" ] ||
    msg="$msg; the target was not written"
  [ -z "$(ls "$D" | grep -vE '^(link|target)$')" ] || msg="$msg; left behind: $(ls "$D" | tr '\n' ' ')"
  rm -f "$D/link" "$D/target"
  result "${name}_symlink" "$msg"

  # 4. a dangling symbolic link: refused (exit 1, the link named), nothing created
  echo "[ RUN      ] output_safety.${name}_dangling_symlink"
  msg=""
  ln -s missing/nowhere "$D/dangling"
  run_writer "$cmd" "$D/dangling"; rc=$?
  [ $rc -eq 1 ] || msg="exit $rc, expected 1"
  grep -q "dangling.*symbolic link" "$T/err" || msg="$msg; stderr lacks the reason: $(head -c 300 "$T/err")"
  [ -L "$D/dangling" ] || msg="$msg; the link was replaced"
  [ -z "$(ls "$D" | grep -v '^dangling$')" ] || msg="$msg; left behind: $(ls "$D" | tr '\n' ' ')"
  rm -f "$D/dangling"
  result "${name}_dangling_symlink" "$msg"
done

echo "[==========] $((passed + failed)) tests ran."
echo "[  PASSED  ] $passed tests."
[ $failed -eq 0 ] || { echo "[  FAILED  ] $failed tests."; exit 1; }
