#!/usr/bin/env bash
# make soak: 10,000 synthetic frames through the frontend (render + detect + log, one process)
# against 1,000; the peak resident memory must be the same (no growth per frame).
set -euo pipefail
B=${BUILD:-build}
N1=${SOAK_SMALL:-1000}; N2=${SOAK_LARGE:-10000}
run() {  # frames -> "seconds maxrss_kib"
  python3 - "$B/cyl" "$1" <<'PY'
import os, resource, subprocess, sys, time
t = time.time()
p = subprocess.run([sys.argv[1], "detect", "synthetic:11", "--frames", sys.argv[2], "--out", "/dev/null", "--quiet"])
ru = resource.getrusage(resource.RUSAGE_CHILDREN)
if p.returncode:
    sys.exit(f"cyl detect failed with exit {p.returncode}")
print(f"{time.time() - t:.1f} {ru.ru_maxrss}")
PY
}
read -r t1 m1 <<<"$(run "$N1")"
read -r t2 m2 <<<"$(run "$N2")"
growth=$(awk -v a="$m1" -v b="$m2" 'BEGIN{printf "%.3f", b / a}')
printf '%-8s %10s %14s\n' frames seconds "peak RSS KiB" "$N1" "$t1" "$m1" "$N2" "$t2" "$m2"
echo "{\"soak_frames\": $N2, \"soak_rss_small_kib\": $m1, \"soak_rss_large_kib\": $m2, \"soak_rss_growth\": $growth}"
awk -v g="$growth" 'BEGIN{exit !(g <= 1.02)}' || { echo "soak: peak memory grew by a factor $growth" >&2; exit 1; }
