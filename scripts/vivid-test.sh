#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# V4L2 against a real driver: boot Debian's own kernel under qemu (software emulation), load
# the kernel's vivid driver from a small initramfs and run the test program build/vivid_test
# inside (static; or dynamic with its libraries copied in, as `make test SAN=1` builds it). The kernel package is fetched with apt-get download (Debian's
# registry) into build/vivid/kcache once; its modules are never installed on the host.
# Fails loudly (non-zero exit, the reason printed) whenever the test cannot run.
set -euo pipefail
TEST=${1:?usage: vivid-test.sh path/to/static/vivid_test}
W=${VIVID_DIR:-build/vivid}
TIMEOUT=${VIVID_TIMEOUT:-240}
mkdir -p "$W"
W=$(cd "$W" && pwd)
TEST=$(cd "$(dirname "$TEST")" && pwd)/$(basename "$TEST")
die() { echo "vivid-test: FAILED TO RUN: $*" >&2; echo "[  FAILED  ] 1 tests."; exit 1; }

KPKG=${KPKG:-$(apt-cache depends linux-image-amd64 2>/dev/null | awk '/Depends: linux-image-[0-9]/{print $2; exit}')}
if [ -z "$KPKG" ]; then
  apt-get update -qq >&2 || true
  KPKG=$(apt-cache depends linux-image-amd64 2>/dev/null | awk '/Depends: linux-image-[0-9]/{print $2; exit}')
fi
[ -n "$KPKG" ] || die "cannot find the kernel package linux-image-amd64 depends on"
KVER=${KPKG#linux-image-}
C=$W/kcache/$KVER

if [ ! -s "$C/vmlinux" ] || [ ! -s "$C/modules.order" ]; then
  echo "vivid-test: preparing kernel $KVER (once)" >&2
  rm -rf "$W/kroot" "$W/deb" "$C"; mkdir -p "$W/deb" "$C/mod"
  (cd "$W/deb" && apt-get download "$KPKG" >&2) || die "apt-get download $KPKG failed"
  dpkg -x "$W"/deb/"${KPKG}"_*.deb "$W/kroot"
  depmod -b "$W/kroot" "$KVER"
  : > "$C/modules.order.tmp"
  for k in $(modprobe -d "$W/kroot" -S "$KVER" --show-depends vivid | awk '$1=="insmod"{print $2}'); do
    b=$(basename "$k")
    case $b in
      *.xz) xz -dc "$k" > "$C/mod/${b%.xz}"; b=${b%.xz};;
      *.zst) zstd -qdc "$k" > "$C/mod/${b%.zst}"; b=${b%.zst};;
      *) cp "$k" "$C/mod/";;
    esac
    echo "$b" >> "$C/modules.order.tmp"
  done
  grep -q '^vivid.ko$' "$C/modules.order.tmp" || die "vivid module not found in $KPKG"
  # Boot the uncompressed ELF: skips ~8 s of XZ decompression under emulation.
  off=$(grep -abo $'\xfd7zXZ\x00' "$W/kroot/boot/vmlinuz-$KVER" | head -1 | cut -d: -f1)
  [ -n "$off" ] || die "no XZ payload in vmlinuz-$KVER"
  tail -c +$((off + 1)) "$W/kroot/boot/vmlinuz-$KVER" | xz -dc > "$C/vmlinux.tmp" 2>/dev/null || true
  readelf -h "$C/vmlinux.tmp" >/dev/null 2>&1 || die "could not extract vmlinux"
  mv "$C/vmlinux.tmp" "$C/vmlinux"
  mv "$C/modules.order.tmp" "$C/modules.order"
  rm -rf "$W/kroot" "$W/deb"
fi

# initramfs: busybox, the modules, the test, and an init that runs it and powers off.
R=$W/initrd; rm -rf "$R"; mkdir -p "$R"/{bin,dev,proc,sys,tmp,lib/modules}
cp /bin/busybox "$R/bin/"
for a in sh mount insmod cat cut sleep poweroff; do ln -s busybox "$R/bin/$a"; done
cp "$TEST" "$R/bin/vivid_test"
# A dynamically linked test (make test SAN=1: the sanitizer runtimes are shared libraries) gets
# its libraries and loader copied in at their host paths, and the sanitizer options passed on.
dyn=$(readelf -d "$TEST" 2>/dev/null || true)
if grep -q '(NEEDED)' <<<"$dyn"; then
  for lib in $(ldd "$TEST" | awk '$2 == "=>" && $3 ~ /^\// {print $3} $1 ~ /^\// {print $1}'); do
    mkdir -p "$R$(dirname "$lib")"
    cp -L "$lib" "$R$lib"
  done
fi
: > "$R/env"
for v in ASAN_OPTIONS UBSAN_OPTIONS; do
  if [ -n "${!v:-}" ]; then printf 'export %s=%q\n' "$v" "${!v}" >> "$R/env"; fi
done
cp "$C"/mod/*.ko "$R/lib/modules/"
cp "$C/modules.order" "$R/"
cat > "$R/init" <<'INIT'
#!/bin/sh
export PATH=/bin
. /env
mount -t proc proc /proc; mount -t sysfs sys /sys; mount -t devtmpfs dev /dev; mount -t tmpfs tmp /tmp
for m in $(cat /modules.order); do
  opts=""; [ "$m" = vivid.ko ] && opts="n_devs=1"
  insmod /lib/modules/$m $opts || echo "VIVID: insmod $m failed"
done
i=0; while [ ! -e /dev/video0 ] && [ $i -lt 100 ]; do sleep 0.1; i=$((i+1)); done
echo "VIVID: nodes" /dev/video*
/bin/vivid_test /dev/video0; rc=$?
echo "VIVID-RESULT: rc=$rc"
poweroff -f
INIT
chmod +x "$R/init"
(cd "$R" && find . | cpio -o -H newc -R 0:0 --quiet | gzip -1) > "$W/initramfs.gz"
rm -rf "$R"

log=$W/console.log
set +e
timeout -k 5 "$TIMEOUT" qemu-system-x86_64 -accel tcg -m 512 -smp 1 -kernel "$C/vmlinux" \
  -initrd "$W/initramfs.gz" -append 'console=ttyS0 quiet panic=-1' -nographic -no-reboot -net none \
  </dev/null 2>&1 | tr -d '\r' > "$log"
qrc=${PIPESTATUS[0]}
set -e
grep -E '^(\[|  |VIVID)' "$log" || true
grep -q '^VIVID-RESULT: rc=' "$log" || die "the test did not run in the VM (qemu exit $qrc; see $log)"
if ! grep -q '^VIVID-RESULT: rc=0$' "$log"; then
  # the console filter above hides sanitizer reports: show them
  grep -aE '==[0-9]+==|SUMMARY|runtime error' "$log" | head -20 || true
  echo "vivid-test: FAILED: $(grep '^VIVID-RESULT' "$log") (console log: $log)" >&2
  exit 1
fi
