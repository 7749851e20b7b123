# SPDX-License-Identifier: BSD-3-Clause
"""The Python binding against the C core and the C tool: version, table files, segmentation on
every pixel layout, and observations equal to `cyl detect`'s on the same rendered frames."""
import json
import os
import re
import struct
import subprocess

import numpy as np
import pytest

import cyl

ROOT = os.path.normpath(os.path.join(os.path.dirname(__file__), "..", ".."))
BUILD = os.environ.get("CYL_BUILD", os.path.join(ROOT, "build"))
TABLE = os.path.join(ROOT, "calib_data", "synthetic.cylt")


def test_version_is_the_headers():
    with open(os.path.join(ROOT, "libcyl", "include", "cyl", "version.h")) as f:
        assert cyl.version() == re.search(r'CYL_VERSION_STRING "([^"]+)"', f.read()).group(1)


def test_table_round_trip_and_errors(tmp_path):
    raw = open(TABLE, "rb").read()
    t = cyl.Table.load(TABLE)
    assert t.to_bytes() == raw
    assert t.classes[:2] == ["orange", "green"]
    assert t.index("green") == 1
    with pytest.raises(KeyError):
        t.index("blue")
    bad = bytearray(raw)
    bad[500] ^= 1
    with pytest.raises(cyl.CylError, match="checksum"):
        cyl.Table.from_bytes(bytes(bad))
    u = cyl.Table()
    u.add_box(3, "pink", (50, 200), (150, 170), (150, 170))
    assert u.mask(100, 160, 160) == 1 << 3 and u.mask(40, 160, 160) == 0
    u.save(str(tmp_path / "p.cylt"))
    assert cyl.Table.load(str(tmp_path / "p.cylt")).classes[3] == "pink"


def yuv444_to(fmt, Y, U, V):
    """Pack full-resolution planes into a V4L2 layout (chroma of even columns/rows, as the core reads)."""
    H, W = Y.shape
    if fmt in ("YUYV", "UYVY"):
        out = np.zeros((H, 2 * W), np.uint8)
        if fmt == "YUYV":
            out[:, 0::2] = Y
            out[:, 1::4] = U[:, 0::2]
            out[:, 3::4] = V[:, 0::2]
        else:
            out[:, 1::2] = Y
            out[:, 0::4] = U[:, 0::2]
            out[:, 2::4] = V[:, 0::2]
        return out
    u, v = U[0::2, 0::2], V[0::2, 0::2]
    if fmt == "NV12":
        uv = np.zeros((H // 2, W), np.uint8)
        uv[:, 0::2], uv[:, 1::2] = u, v
        return np.vstack([Y, uv])
    return np.vstack([Y, u.reshape(H // 4, W), v.reshape(H // 4, W)])   # I420


def test_segmentation_is_the_same_on_every_layout():
    t = cyl.Table.load(TABLE)
    H, W = 120, 160
    Y = np.full((H, W), 118, np.uint8)
    U = np.full((H, W), 126, np.uint8)
    V = np.full((H, W), 131, np.uint8)
    Y[20:60, 30:50], U[20:60, 30:50], V[20:60, 30:50] = 137, 68, 194     # orange, 20x40
    Y[70:100, 100:140], U[70:100, 100:140], V[70:100, 100:140] = 114, 103, 75   # green, 40x30
    ref = None
    for fmt in ("YUYV", "UYVY", "NV12", "I420"):
        blobs = cyl.segment(t, yuv444_to(fmt, Y, U, V), fmt, width=W, height=H)
        got = [(b.cls, b.x0, b.y0, b.x1, b.y1, b.area, b.cx_px, b.cy_px) for b in blobs]
        assert got == [(0, 30, 20, 49, 59, 800, 39.5, 39.5), (1, 100, 70, 139, 99, 1200, 119.5, 84.5)], fmt
        ref = ref or got
        assert got == ref
    with pytest.raises(ValueError, match="needs"):
        cyl.segment(t, np.zeros((10, 10), np.uint8), "YUYV", width=160, height=120)


def read_cylraw(path):
    """Frames of a raw log (docs/formats.md), re-read here as an independent check."""
    with open(path, "rb") as f:
        data = f.read()
    assert data[:8] == b"CYLRAW\0\0"
    width, height, stride, payload = struct.unpack_from("<IIII", data, 20)
    pos, frames = 64, []
    while pos + 32 <= len(data):
        magic, typ, seq, t_ns, size, flags = struct.unpack_from("<4sIQqII", data, pos)
        assert magic == b"REC1"
        if typ == 1:
            frames.append((seq, np.frombuffer(data, np.uint8, payload, pos + 32).reshape(height, stride)))
        pos += 32 + size
    return width, height, frames


def camera_from_yaml(path):
    """The OpenCV YAML fields cyl_camera needs, read with a regex (a test-only re-derivation)."""
    txt = open(path).read()

    def num(key):
        return float(re.search(rf"^{key}:\s*([-+0-9.eE]+)", txt, re.M).group(1))

    def mat(key):
        block = re.search(rf"^{key}:.*?data:\s*\[([^\]]*)\]", txt, re.M | re.S).group(1)
        return [float(x) for x in block.replace("\n", " ").split(",")]
    K = mat("camera_matrix")
    d = mat("distortion_coefficients")
    sig = None
    if "intrinsic_covariance" in txt:   # diagonal in this file: the sigmas are its square roots
        C = np.array(mat("intrinsic_covariance")).reshape(9, 9)
        assert np.count_nonzero(C - np.diag(np.diag(C))) == 0
        sig = list(np.sqrt(np.diag(C)))
    deg = np.pi / 180
    return cyl.Camera(int(num("image_width")), int(num("image_height")), K[0], K[4], K[2], K[5],
                      k1=d[0], k2=d[1], p1=d[2], p2=d[3], k3=d[4], tilt_rad=num("mount_tilt_deg") * deg,
                      yaw_rad=num("mount_yaw_deg") * deg, height_m=num("mount_height_m"), offset_m=num("mount_offset_m"),
                      intrinsic_sigmas=sig, tilt_sigma_rad=num("mount_tilt_sigma_deg") * deg,
                      yaw_sigma_rad=num("mount_yaw_sigma_deg") * deg, height_sigma_m=num("mount_height_sigma_m"),
                      offset_sigma_m=num("mount_offset_sigma_m"))


def _render_and_detect(tmp_path, frames, seed):
    """Render `frames` frames of the default scene with cyl-render and detect them with cyl detect
    (the synthetic camera's calibration): returns (calibration file, observation log, raw log)."""
    raw, log = str(tmp_path / "d.cylraw"), str(tmp_path / "o.jsonl")
    calib = os.path.join(ROOT, "calib_data", "synthetic_camera.yaml")
    subprocess.run([os.path.join(BUILD, "cyl-render"), "-o", raw, "-n", str(frames), "-s", str(seed), "-q"],
                   check=True)
    subprocess.run([os.path.join(BUILD, "cyl"), "detect", raw, "--table", TABLE, "--calib", calib, "--size",
                    "orange=0.10,0.30", "--size", "green=0.10,0.30", "--out", log, "--quiet"], check=True)
    return calib, log, raw


@pytest.mark.skipif(not os.path.exists(os.path.join(BUILD, "cyl")), reason="needs build/cyl and build/cyl-render")
def test_observations_equal_the_c_tools(tmp_path):
    calib, log, raw = _render_and_detect(tmp_path, frames=6, seed=3)
    by_seq = {}
    for line in open(log):
        r = json.loads(line)
        if r["type"] == "obs":
            by_seq.setdefault(r["seq"], []).append(r)
    t = cyl.Table.load(TABLE)
    cam = camera_from_yaml(calib)
    w, h, frames = read_cylraw(raw)
    n = 0
    for seq, fr in frames:
        got = cyl.observe(t, fr, "YUYV", cam, sizes={"orange": (0.10, 0.30), "green": (0.10, 0.30)}, width=w, height=h)
        want = by_seq.get(seq, [])
        assert len(got) == len(want), seq
        for g, c in zip(got, want):
            assert g["class"] == c["class"] and g["bbox_px"] == c["bbox_px"] and g["flags"] == c["flags"]
            for k in ("range_m", "bearing_rad", "u_px", "v_px", "var_u_px2", "var_v_px2", "confidence", "aspect_rel"):
                assert g[k] == pytest.approx(c[k], rel=1e-8, abs=1e-12), (seq, k)
            assert ("area_rel" in g) == ("area_rel" in c) and ("offset_rel" in g) == ("offset_rel" in c), seq
            for k in ("area_rel", "offset_rel"):
                if k in c:
                    assert g[k] == pytest.approx(c[k], rel=1e-8, abs=1e-12), (seq, k)
            assert g["cov_rb"][0][0] == pytest.approx(c["cov_rr"], rel=1e-8)
            assert g["cov_rb"][1][1] == pytest.approx(c["cov_bb"], rel=1e-8)
            assert g["bias_var_px2"] == pytest.approx(c["bias_var_px2"], rel=1e-8)
            assert g["subpixel_shift_px"] == pytest.approx(c["subpixel_shift_px"], rel=1e-8, abs=1e-12)
            n += 1
    assert n >= 6


def _rb_by_hand(cam, u, v):
    """Range and bearing of a pixel of a camera without distortion, from the ray-plane formulas of
    cyl/rangebearing.h written out again here (an independent derivation for the test)."""
    f = cam.fields()
    xn, yn = (u - f["cx_px"]) / f["fx_px"], (v - f["cy_px"]) / f["fy_px"]
    t = f["tilt_rad"]
    X, Y, Z = np.cos(t) - yn * np.sin(t), xn, np.sin(t) + yn * np.cos(t)
    dc = f["height_m"] * np.hypot(X, Y) / Z
    th = f["yaw_rad"] - np.arctan2(Y, X)
    x, y = f["offset_m"] + dc * np.cos(th), dc * np.sin(th)
    return np.hypot(x, y), np.arctan2(y, x)


def test_range_bearing_model():
    """cyl.RangeBearing: the C model by hand on a lens without distortion, a calibration error equal
    to a camera moved by it, its Jacobians by central differences, None above the horizon, an
    unknown model name refused."""
    cam = cyl.Camera(640, 480, fx=570, fy=568, cx=322.4, cy=236.9, tilt_rad=0.2094, yaw_rad=0.01,
                     height_m=0.326, offset_m=0.1)
    rb = cyl.RangeBearing(cam)
    for u, v in ((320.0, 300.0), (40.5, 200.25), (600.0, 470.0)):
        r, b, _ = rb.eval(u, v)
        rr, bb = _rb_by_hand(cam, u, v)
        assert r == pytest.approx(rr, rel=1e-12) and b == pytest.approx(bb, abs=1e-12)
    delta = np.array([0.5, -0.4, 0.3, -0.2, 0.01, -0.004, 0.002, -0.003])
    moved = cyl.Camera(640, 480, fx=570.5, fy=567.6, cx=322.7, cy=236.7, tilt_rad=0.2194, yaw_rad=0.006,
                       height_m=0.328, offset_m=0.097)
    got, want = rb.eval(100.0, 260.0, delta), cyl.RangeBearing(moved).eval(100.0, 260.0)
    assert got[0] == pytest.approx(want[0], rel=1e-12) and got[1] == pytest.approx(want[1], abs=1e-12)
    # Jacobians: u, v and the eight calibration entries, by central differences
    u, v = 150.0, 300.0
    _, _, jac = rb.eval(u, v, delta)
    steps = [1e-4, 1e-4] + [1e-4, 1e-4, 1e-4, 1e-4, 1e-7, 1e-7, 1e-7, 1e-7]
    cols = [0, 1] + list(cyl.RangeBearing.CALIB_INPUTS)
    for k, (c, h) in enumerate(zip(cols, steps)):
        def at(s):
            if k < 2:
                return np.array(rb.eval(u + s * (k == 0), v + s * (k == 1), delta)[:2])
            d = delta.copy()
            d[k - 2] += s
            return np.array(rb.eval(u, v, d)[:2])
        num = (at(h) - at(-h)) / (2 * h)
        assert jac[:, c] == pytest.approx(num, rel=1e-5, abs=1e-9), c
    assert rb.eval(320.0, 20.0) is None              # above the horizon: no range
    with pytest.raises(ValueError):
        cyl.RangeBearing(cam, "pinhole")


@pytest.mark.skipif(not os.path.exists(os.path.join(BUILD, "cyl")), reason="needs build/cyl and build/cyl-render")
def test_range_bearing_reproduces_the_log(tmp_path):
    calib, log, _ = _render_and_detect(tmp_path, frames=4, seed=5)
    lines = [json.loads(x) for x in open(log)]
    c = lines[0]["camera"]
    cam = cyl.Camera(c["width"], c["height"], c["fx"], c["fy"], c["cx"], c["cy"], k1=c["k1"], k2=c["k2"],
                     p1=c["p1"], p2=c["p2"], k3=c["k3"], tilt_rad=c["tilt_rad"], yaw_rad=c["yaw_rad"],
                     height_m=c["height_m"], offset_m=c["offset_m"])
    assert c["k1"] == camera_from_yaml(calib).fields()["k1"]
    rb = cyl.RangeBearing(cam, lines[0]["model"])
    n = 0
    for o in lines:
        if o["type"] != "obs" or o["flags"] & 0x300:
            continue
        r, b, jac = rb.eval(o["u_px"], o["v_px"])
        assert r == pytest.approx(o["range_m"], rel=1e-8) and b == pytest.approx(o["bearing_rad"], abs=1e-9)
        got = jac[:, list(cyl.RangeBearing.CALIB_INPUTS)].ravel()
        assert got == pytest.approx(o["jac_calib"], rel=1e-7, abs=1e-12)
        n += 1
    assert n >= 4
