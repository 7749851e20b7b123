#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# libcyl installed into a scratch prefix (make install PREFIX=...), then an out-of-tree program
# built against it with nothing but `pkg-config --cflags --libs libcyl` (no -lm of its own: the
# .pc file must carry it), run, and checked. Prints GoogleTest-style lines.
#   test_install.sh
set -u
cd "$(dirname "$0")/../.."
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
passed=0; failed=0
result() { if [ -z "$2" ]; then passed=$((passed + 1)); echo "[       OK ] install.$1"; else failed=$((failed + 1)); echo "  $2"; echo "[  FAILED  ] install.$1"; fi; }

echo "[ RUN      ] install.prefix"
msg=""
# a plain build, whatever the calling make passed down or exported (make test SAN=1 puts SAN=1
# in the environment too; a sanitized library cannot link into a plain program)
env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL -u SAN make -s install SAN= PREFIX="$T/prefix" >"$T/log" 2>&1 ||
  msg="make install failed: $(tail -5 "$T/log")"
for f in include/cyl/version.h include/cyl/colorlearn.h lib/libcyl.a lib/libcyl.so lib/pkgconfig/libcyl.pc \
         lib/cmake/cyl/cylConfig.cmake lib/cmake/cyl/cylConfigVersion.cmake \
         bin/cyl bin/cyl-train bin/cyl-score bin/cyl-calibrate bin/cyl-render bin/cyl-synth-validate bin/cyl_paper \
         share/cyl/synthetic.cylt share/cyl/paper_camera.yaml lib/cyl/libcyl-media.so; do
  [ -f "$T/prefix/$f" ] || msg="$msg; $f not installed"
done
result prefix "$msg"

echo "[ RUN      ] install.pkg_config_consumer"
msg=""
export PKG_CONFIG_PATH="$T/prefix/lib/pkgconfig"
v=$(pkg-config --modversion libcyl 2>&1)
hv=$(sed -n 's/^#define CYL_VERSION_STRING "\(.*\)"/\1/p' libcyl/include/cyl/version.h)
[ "$v" = "$hv" ] || msg="pkg-config --modversion: '$v', header: '$hv'"
# shellcheck disable=SC2046
cc -std=c99 -Wall -Wextra -Werror tests/install/consumer.c -o "$T/consumer" $(pkg-config --cflags --libs libcyl) \
  >"$T/cc" 2>&1 || msg="$msg; the consumer does not build with pkg-config alone: $(head -c 400 "$T/cc")"
if [ -x "$T/consumer" ]; then
  # pkg-config's -lcyl picks the shared library: the loader finds it through LD_LIBRARY_PATH
  out=$(LD_LIBRARY_PATH="$T/prefix/lib" "$T/consumer") || msg="$msg; the consumer failed (exit $?)"
  echo "$out" | grep -q "^libcyl $hv: blob area 100 at (24.5, 14.5)" || msg="$msg; unexpected output: $out"
  ldd "$T/consumer" | grep -q "libcyl.so.${hv%%.*} => $T/prefix/lib/" 2>/dev/null ||
    LD_LIBRARY_PATH="$T/prefix/lib" ldd "$T/consumer" | grep -q "libcyl.so.${hv%%.*} => $T/prefix/lib/" ||
    msg="$msg; not linked against the installed libcyl.so: $(LD_LIBRARY_PATH="$T/prefix/lib" ldd "$T/consumer" | grep cyl)"
fi
result pkg_config_consumer "$msg"

echo "[ RUN      ] install.cmake_consumer"
msg=""
if ! cmake -S tests/install -B "$T/cm" -DCMAKE_PREFIX_PATH="$T/prefix" >"$T/cmake.log" 2>&1 ||
   ! cmake --build "$T/cm" >>"$T/cmake.log" 2>&1; then
  msg="find_package(cyl) build failed: $(tail -8 "$T/cmake.log")"
else
  for v in shared static; do
    out=$("$T/cm/consumer_$v") || msg="$msg; consumer_$v failed (exit $?)"
    echo "$out" | grep -q "^libcyl $hv: blob area 100 at (24.5, 14.5)" || msg="$msg; consumer_$v: $out"
  done
  # CMake puts the imported library's folder in the shared consumer's RUNPATH; the static one has no libcyl.so
  ldd "$T/cm/consumer_shared" | grep -q "libcyl.so" || msg="$msg; consumer_shared does not use libcyl.so"
  ldd "$T/cm/consumer_static" | grep -q "libcyl.so" && msg="$msg; consumer_static uses libcyl.so"
fi
result cmake_consumer "$msg"

echo "[ RUN      ] install.tools_from_any_directory"
msg=""
mkdir -p "$T/elsewhere" "$T/nodata"
# the installed cyl finds its default colour table in PREFIX/share/cyl, not in the repository
(cd "$T/elsewhere" && "$T/prefix/bin/cyl" detect synthetic:3 --max-frames 2 --out obs.jsonl) >"$T/tool.log" 2>&1 ||
  msg="installed cyl detect synthetic failed in another directory: $(tail -3 "$T/tool.log")"
n=$(grep -c "\"type\":\"frame\"" "$T/elsewhere/obs.jsonl" 2>/dev/null)
[ "${n:-0}" -ge 2 ] || msg="$msg; $n frame records in the installed tool's log"
(cd "$T/elsewhere" && "$T/prefix/bin/cyl_paper") >"$T/paper.log" 2>&1 ||
  msg="$msg; installed cyl_paper failed in another directory: $(tail -3 "$T/paper.log")"
tail -1 "$T/paper.log" | grep -q '^{' || msg="$msg; cyl_paper's last line is not JSON"
# CYL_DATA_DIR overrides the search, and a wrong one is an error naming the file and the place
(cd "$T/elsewhere" && CYL_DATA_DIR="$T/nodata" "$T/prefix/bin/cyl" detect synthetic --max-frames 1 --out o2.jsonl) \
  >"$T/nodata.log" 2>&1; rc=$?
[ $rc -eq 1 ] || msg="$msg; CYL_DATA_DIR without the table: exit $rc, expected 1"
grep -q "synthetic.cylt: data file not found (looked at $T/nodata/synthetic.cylt; CYL_DATA_DIR is set" "$T/nodata.log" ||
  msg="$msg; unexpected error: $(head -c 300 "$T/nodata.log")"
cp "$T/prefix/share/cyl/synthetic.cylt" "$T/nodata/"
(cd "$T/elsewhere" && CYL_DATA_DIR="$T/nodata" "$T/prefix/bin/cyl" detect synthetic --max-frames 1 --out o3.jsonl) \
  >"$T/data.log" 2>&1 || msg="$msg; CYL_DATA_DIR with the table failed: $(tail -2 "$T/data.log")"
# the installed media plugin: an overlay image written from the installed tool
(cd "$T/elsewhere" && "$T/prefix/bin/cyl" detect synthetic --max-frames 1 --out o4.jsonl --overlay ov/) \
  >"$T/ov.log" 2>&1 || msg="$msg; installed cyl --overlay failed: $(tail -2 "$T/ov.log")"
[ -s "$T/elsewhere/ov/frame_000000.png" ] || msg="$msg; no overlay image from the installed tool"
result tools_from_any_directory "$msg"

echo "[==========] $((passed + failed)) tests ran."
echo "[  PASSED  ] $passed tests."
[ $failed -eq 0 ] || { echo "[  FAILED  ] $failed tests."; exit 1; }
