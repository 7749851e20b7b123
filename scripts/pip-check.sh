#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# make pip-check: what a newcomer does. A fresh venv outside the repository, `pip install` of the
# repository, then `import cyl` segments a numpy YUYV frame and `cylslam --help` runs, from a
# folder outside the repository. Needs network access to PyPI (numpy, cffi, gtsam, scipy, ...).
set -euo pipefail
REPO=$(cd "$(dirname "$0")/.." && pwd)
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
python3 -m venv "$T/venv"
cd "$T"
"$T/venv/bin/pip" install -q "$REPO"
"$T/venv/bin/python" - "$REPO/calib_data/synthetic.cylt" "$REPO/calib_data/synthetic_camera.yaml" <<'PY'
import sys, numpy as np, cyl
t = cyl.Table.load(sys.argv[1])
f = np.zeros((480, 1280), np.uint8); f[:, 0::2] = 118; f[:, 1::4] = 126; f[:, 3::4] = 131
f[100:140, 400:480:2] = 137; f[100:140, 401:480:4] = 68; f[100:140, 403:480:4] = 194
b = cyl.segment(t, f, "YUYV")
assert len(b) == 1 and b[0].cls == 0 and (b[0].x0, b[0].x1, b[0].area) == (200, 239, 1600), b
print(f"cyl {cyl.version()}: segmented a numpy YUYV frame: {b[0]}")
cam = cyl.load_camera(sys.argv[2])
assert cam.fields()["fx_px"] == 570.0 and cam.mount_known, cam.fields()
print(f"cyl: read {sys.argv[2]}: {cam.format} file, fx {cam.fields()['fx_px']} px")
PY
"$T/venv/bin/cylslam" --help >/dev/null
echo "pip-check: ok (installed in a fresh venv; import cyl and cylslam --help work outside the repository)"
