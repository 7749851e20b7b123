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
for f in include/cyl/version.h include/cyl/silhouette.h lib/libcyl.a lib/pkgconfig/libcyl.pc; do
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
  out=$("$T/consumer") || msg="$msg; the consumer failed (exit $?)"
  echo "$out" | grep -q "^libcyl $hv: blob area 100 at (24.5, 14.5)" || msg="$msg; unexpected output: $out"
fi
result pkg_config_consumer "$msg"

echo "[==========] $((passed + failed)) tests ran."
echo "[  PASSED  ] $passed tests."
[ $failed -eq 0 ] || { echo "[  FAILED  ] $failed tests."; exit 1; }
