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
         lib/cmake/cyl/cylConfig.cmake lib/cmake/cyl/cylConfigVersion.cmake; do
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

echo "[==========] $((passed + failed)) tests ran."
echo "[  PASSED  ] $passed tests."
[ $failed -eq 0 ] || { echo "[  FAILED  ] $failed tests."; exit 1; }
