#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# make multiband's reduced form (scripts/multiband.py --quick: the multiband scene, held-out seed
# 101, 150 frames: render, detect with the scene's landmark models, map with and without the
# identities). Asserts the figures the full form is judged on: one observation per landmark wholly
# in view (>= 0.95), identities right (>= 0.99 of those read, <= 0.005 wrong), grouped ranges
# unbiased within 1% over 1-4 m, cones confident (>= 0.9 at >= 0.8), no association error with
# identities and an ATE no worse than gating's (multiband.py --check, where the targets are written
# once), on enough views and identities to judge. GoogleTest-style lines.
#   test_multiband_quick.sh BUILD_DIR
set -u
B=$1
cd "$(dirname "$0")/../.."
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
echo "[ RUN      ] multiband.quick"
if ! .venv/bin/python scripts/multiband.py --quick --check --build "$B" --out "$T/m" >"$T/log" 2>"$T/err"; then
  echo "  multiband.py failed: $(tail -5 "$T/err")"; echo "[  FAILED  ] multiband.quick"; exit 1
fi
msg=$(.venv/bin/python - "$T/log" <<'PY'
import json, sys
r = json.loads(open(sys.argv[1]).read().strip().splitlines()[-1])
bad = []
if r["landmark_views_whole"] < 100: bad.append(f"only {r['landmark_views_whole']} whole views")
if r["ids_read"] < 50: bad.append(f"only {r['ids_read']} identities read")
print("; ".join(bad))
PY
)
if [ -z "$msg" ]; then echo "[       OK ] multiband.quick ($(tail -1 "$T/log" | cut -c1-200))"; echo "[  PASSED  ] 1 tests."
else echo "  $msg"; echo "[  FAILED  ] multiband.quick"; exit 1; fi
