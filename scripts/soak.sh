#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# make soak: 10,000 synthetic frames through the frontend (render + detect + log, one
# `cyl detect` process). The process's peak resident memory (VmHWM) is read when its log reaches
# frame 1,000 and again at the end: the peak of the 10,000-frame run
# must equal the peak of its first 1,000 frames, i.e. nothing grows per frame. Measured in one
# process, because two separate runs of the same command differ by ~1.2 MB from start-up alone.
# Checkpoints at 2,000 and 5,000 frames are printed too.
set -euo pipefail
B=${BUILD:-build}
N1=${SOAK_SMALL:-1000}; N2=${SOAK_LARGE:-10000}
TOL=${SOAK_TOLERANCE:-1.005}   # allowed peak ratio (end / frame N1): page-granular noise only
[ "$N1" -ge 1 ] && [ "$N2" -gt "$N1" ] || { echo "soak: need 1 <= SOAK_SMALL < SOAK_LARGE (got $N1, $N2)" >&2; exit 2; }
mkdir -p "$B/soak"
python3 - "$B/cyl" "$N1" "$N2" "$TOL" "$B/soak/soak.jsonl" <<'PY'
import json, os, subprocess, sys, time
cyl, n1, n2, tol, log = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4]), sys.argv[5]
checkpoints = sorted({n1, 2000, 5000} & set(range(1, n2)))

def hwm_kib(pid):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1])
    raise RuntimeError("no VmHWM")

t0 = time.time()
p = subprocess.Popen([cyl, "detect", f"synthetic:11", "--frames", str(n2), "--out", log, "--quiet"])
seen = {}
last_h = 0
frames = 0
pos = 0
partial = log + ".part"   # cyl writes LOG.part and renames it at the end
while True:
    done, status, ru = os.wait4(p.pid, os.WNOHANG)   # reaped here, for its rusage
    if done:
        p.returncode = os.waitstatus_to_exitcode(status)
        break
    time.sleep(0.2)
    try:
        with open(partial, "rb") as f:
            f.seek(pos)
            chunk = f.read()
    except FileNotFoundError:
        continue
    # count complete frame lines only
    end = chunk.rfind(b"\n") + 1
    frames += chunk[:end].count(b'"type":"frame"')
    pos += end
    try:
        h = hwm_kib(p.pid)
    except (OSError, RuntimeError):
        continue   # exiting: wait4 above reaps it
    last_h = max(last_h, h)
    for c in checkpoints:
        if c not in seen and frames >= c:
            seen[c] = (frames, h, time.time() - t0)
    bar = int(30 * frames / n2)
    print(f"\rsoak [{'#' * bar}{'.' * (30 - bar)}] {frames}/{n2} frames, peak RSS {h / 1024:.1f} MiB",
          end="", file=sys.stderr, flush=True)
print(file=sys.stderr)
rc = p.returncode
if rc:
    sys.exit(f"soak: cyl detect failed with exit {rc}")
# the kernel's hiwater mark is updated lazily: take the larger of the last VmHWM read (frames
# before the end) and maxrss at exit
end_kib = max(last_h, ru.ru_maxrss)
n_out = sum(1 for line in open(log, "rb") if b'"type":"frame"' in line)
if n_out != n2:
    sys.exit(f"soak: the log has {n_out} frames, expected {n2}")
os.remove(log)   # checked; 10,000 frames of log are not worth keeping
if n1 not in seen:
    sys.exit(f"soak: never saw frame {n1} in the log while the process ran")
print(f"{'frames':>8} {'seconds':>8} {'peak RSS KiB':>13}")
for c in checkpoints:
    if c in seen:
        f, h, t = seen[c]
        print(f"{c:>8} {t:>8.1f} {h:>13}")
print(f"{n2:>8} {time.time() - t0:>8.1f} {end_kib:>13}")
ratio = end_kib / seen[n1][1]
print(json.dumps({"soak_frames": n2, "soak_rss_at_small_kib": seen[n1][1], "soak_small_frames": n1,
                  "soak_rss_end_kib": end_kib, "soak_rss_growth": round(ratio, 4)}))
if ratio > tol:
    sys.exit(f"soak: peak memory grew by a factor {ratio:.4f} from frame {n1} to {n2} (limit {tol})")
PY
