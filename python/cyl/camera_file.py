# SPDX-License-Identifier: BSD-3-Clause
"""Camera calibration files (OpenCV YAML or ROS camera_info YAML, with libcyl's mount and sigma
fields; docs/formats.md) into a libcyl camera.

The same rules as the C++ tools' reader (frontend/src/calibration.cpp), which tests check field by
field against this one: unknown keys are errors naming the nearest known key (lenient=True makes
them warnings), a key given twice is an error, a misspelling never silently becomes a default.
"""
from __future__ import annotations

import math
from typing import List, Optional

import yaml

from ._cyl import ffi, lib

INTR_COUNT = 9
USED_KEYS = ["image_width", "image_height", "camera_matrix", "distortion_coefficients", "distortion_model",
             "intrinsic_covariance", "intrinsic_sigmas", "mount_tilt_deg", "mount_yaw_deg", "mount_height_m",
             "mount_offset_m", "mount_tilt_sigma_deg", "mount_yaw_sigma_deg", "mount_height_sigma_m",
             "mount_offset_sigma_m"]
IGNORED_KEYS = ["camera_name", "rectification_matrix", "projection_matrix",            # ROS camera_info
                "calibration_time", "nframes", "nr_of_frames", "board_width", "board_height", "square_size",
                "aspectRatio", "fix_aspect_ratio", "flags", "fisheye_model", "avg_reprojection_error",
                "per_view_reprojection_errors", "extrinsic_parameters", "image_points", "grid_points"]


class CameraFileError(ValueError):
    """A calibration file that cannot be used; the message names the file and the field or line."""


def _edit_distance(a: str, b: str) -> int:
    prev = list(range(len(b) + 1))
    for i, ca in enumerate(a, 1):
        cur = [i]
        for j, cb in enumerate(b, 1):
            cur.append(min(prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (ca != cb)))
        prev = cur
    return prev[-1]


def _did_you_mean(key: str, known: List[str]) -> str:
    best, bd = "", 4
    for k in known:
        d = _edit_distance(key, k)
        if d < bd:
            best, bd = k, d
    return f" (did you mean '{best}'?)" if best else ""


class _Loader(yaml.SafeLoader):
    """Safe YAML with OpenCV's !!opencv-matrix read as a mapping."""


_Loader.add_constructor("tag:yaml.org,2002:opencv-matrix", lambda ld, node: ld.construct_mapping(node, deep=True))


class _Reader:
    def __init__(self, path: str):
        self.path = path

    def fail(self, field: str, what: str):
        raise CameraFileError(f"{self.path}: field '{field}': {what}")

    def number(self, v, field: str) -> float:
        if isinstance(v, bool) or not isinstance(v, (int, float, str)):
            self.fail(field, "expected a number")
        try:
            return float(v)
        except ValueError:
            self.fail(field, f"expected a number, got '{v}'")

    def matrix(self, n, field: str, rows: int, cols: int) -> List[float]:
        if n is None:
            self.fail(field, "missing")
        d = n.get("data") if isinstance(n, dict) else n
        if isinstance(n, dict) and ("rows" in n or "cols" in n):
            dr, dc = self.number(n.get("rows"), field + ".rows"), self.number(n.get("cols"), field + ".cols")
            want = rows * cols if rows > 0 else 1024
            if not (dr >= 1 and dc >= 1 and dr * dc <= want) or dr != math.floor(dr) or dc != math.floor(dc):
                self.fail(field, f"declared size {n.get('rows')}x{n.get('cols')} out of range")
        if not isinstance(d, list):
            self.fail(field, "expected a matrix (opencv-matrix, {rows, cols, data} or a list)")
        if len(d) > 1024:
            self.fail(field, "too many values")
        v = [self.number(e, field) for e in d]
        if rows > 0 and len(v) != rows * cols:
            self.fail(field, f"expected {rows * cols} values, got {len(v)}")
        if not all(math.isfinite(x) for x in v):
            self.fail(field, "non-finite value")
        return v

    def opt_number(self, root: dict, field: str, required: bool = False) -> Optional[float]:
        if root.get(field) is None:
            if required:
                self.fail(field, "missing")
            return None
        x = self.number(root[field], field)
        if not math.isfinite(x):
            self.fail(field, "non-finite value")
        return x


def _check_keys(r: _Reader, node, line_offset: int, lenient: bool, warnings: List[str]):
    known = USED_KEYS + IGNORED_KEYS
    seen = {}
    for key_node, _ in node.value:
        if not isinstance(key_node, yaml.ScalarNode):
            r.fail("(top level)", "a key that is not a plain name")
        k, line = key_node.value, key_node.start_mark.line + 1 + line_offset
        if k in seen:
            r.fail(k, f"given twice (lines {seen[k]} and {line})")
        seen[k] = line
        if k in known:
            continue
        msg = f"{r.path}:{line}: unknown key '{k}'{_did_you_mean(k, known)}"
        if not lenient:
            raise CameraFileError(msg + "; lenient=True reads the file anyway")
        warnings.append(msg + ": ignored (lenient)")


def load_camera(path: str, lenient: bool = False):
    """Read a calibration file into a cyl.Camera. Its attributes `format` ('opencv' or 'ros'),
    `mount_known`, `intrinsic_cov_known`, `mount_sigmas_known` and `warnings` say what the file gave."""
    from . import Camera  # the package's camera type (cyl/camera.h)

    r = _Reader(path)
    try:
        with open(path, "rb") as f:
            text = f.read().decode("utf-8", errors="replace")
    except OSError as e:
        raise CameraFileError(f"{path}: cannot open camera calibration file: {e.strerror}") from None
    fmt = "opencv" if text.startswith("%YAML") else "ros"
    if fmt == "opencv":  # OpenCV writes a non-standard "%YAML:1.0" directive: drop that line
        eol = text.find("\n")
        text = "" if eol < 0 else text[eol + 1:]
    if len(text) > (1 << 20):
        raise CameraFileError(f"{path}: not a calibration file: larger than 1 MiB")
    try:
        node = yaml.compose(text, Loader=_Loader)
    except yaml.YAMLError as e:
        raise CameraFileError(f"{path}: not a readable YAML calibration file: {e}") from None
    if not isinstance(node, yaml.MappingNode):
        raise CameraFileError(f"{path}: not a calibration file: the top level is not a mapping of fields")
    warnings: List[str] = []
    _check_keys(r, node, 1 if fmt == "opencv" else 0, lenient, warnings)
    root = _Loader(text).get_single_data()

    c = ffi.new("cyl_camera *")
    lib.cyl_camera_init(c)
    c.height_m = 0.0
    w, h = r.opt_number(root, "image_width", True), r.opt_number(root, "image_height", True)
    if w < 1 or h < 1 or w != math.floor(w) or h != math.floor(h):
        r.fail("image_width/image_height", "not positive integers")
    if w > lib.CYL_MAX_DIM or h > lib.CYL_MAX_DIM:
        r.fail("image_width/image_height", f"larger than libcyl's limit of {lib.CYL_MAX_DIM} px")
    c.width, c.height = int(w), int(h)
    K = r.matrix(root.get("camera_matrix"), "camera_matrix", 3, 3)
    if K[1] != 0.0:
        r.fail("camera_matrix", "skew is not supported (K[0][1] must be 0)")
    if K[3] != 0.0 or K[6] != 0.0 or K[7] != 0.0 or K[8] != 1.0:
        r.fail("camera_matrix", "last row must be 0 0 1 and K[1][0] 0")
    c.fx_px, c.cx_px, c.fy_px, c.cy_px = K[0], K[2], K[4], K[5]
    if not (c.fx_px > 0 and c.fy_px > 0):
        r.fail("camera_matrix", "focal lengths must be positive")
    if fmt == "ros":
        model = root.get("distortion_model")
        model = model if isinstance(model, str) else "plumb_bob"
        if model not in ("plumb_bob", "rational_polynomial"):
            r.fail("distortion_model", f"'{model}' is not supported (plumb_bob or rational_polynomial)")
    if root.get("distortion_coefficients") is not None:
        D = r.matrix(root["distortion_coefficients"], "distortion_coefficients", 0, 0)
        if len(D) < 4:
            r.fail("distortion_coefficients", "expected at least 4 values (k1 k2 p1 p2 [k3])")
        if any(x != 0.0 for x in D[5:]):
            r.fail("distortion_coefficients", "terms beyond k3 (rational/thin prism) are not supported")
        c.k1, c.k2, c.p1, c.p2 = D[:4]
        c.k3 = D[4] if len(D) > 4 else 0.0

    intr_known = mount_known = sig_known = False
    if root.get("intrinsic_covariance") is not None:
        C = r.matrix(root["intrinsic_covariance"], "intrinsic_covariance", INTR_COUNT, INTR_COUNT)
        for i in range(INTR_COUNT):
            for j in range(INTR_COUNT):
                c.intr_cov[i][j] = C[i * INTR_COUNT + j]
        c.flags &= ~lib.CYL_CAM_INTR_COV_UNKNOWN
        intr_known = True
    elif root.get("intrinsic_sigmas") is not None:
        S = r.matrix(root["intrinsic_sigmas"], "intrinsic_sigmas", 0, 0)
        if len(S) not in (4, INTR_COUNT):
            r.fail("intrinsic_sigmas", "expected 4 (fx fy cx cy) or 9 (+ k1 k2 p1 p2 k3) values")
        if any(x < 0 for x in S):
            r.fail("intrinsic_sigmas", "negative standard deviation")
        lib.cyl_camera_set_intrinsic_sigmas(c, ffi.new("double[9]", S + [0.0] * (INTR_COUNT - len(S))))
        intr_known = True

    deg = math.pi / 180.0
    mount = [r.opt_number(root, k) for k in ("mount_tilt_deg", "mount_yaw_deg", "mount_height_m", "mount_offset_m")]
    given = sum(x is not None for x in mount)
    if given not in (0, 4):
        r.fail("mount_*", "give all of mount_tilt_deg, mount_yaw_deg, mount_height_m, mount_offset_m or none")
    if given == 4:
        if not mount[2] > 0:
            r.fail("mount_height_m", "must be positive")
        c.tilt_rad, c.yaw_rad, c.height_m, c.offset_m = mount[0] * deg, mount[1] * deg, mount[2], mount[3]
        mount_known = True
    sig = [r.opt_number(root, k) for k in ("mount_tilt_sigma_deg", "mount_yaw_sigma_deg", "mount_height_sigma_m",
                                           "mount_offset_sigma_m")]
    given = sum(x is not None for x in sig)
    if given not in (0, 4):
        r.fail("mount_*_sigma_*", "give all four mount sigmas or none")
    if given == 4:
        if any(x < 0 for x in sig):
            r.fail("mount_*_sigma_*", "negative standard deviation")
        c.tilt_sigma_rad, c.yaw_sigma_rad, c.height_sigma_m, c.offset_sigma_m = sig[0] * deg, sig[1] * deg, sig[2], sig[3]
        c.flags &= ~lib.CYL_CAM_EXTR_SIG_UNKNOWN
        sig_known = True
    chk = ffi.new("cyl_camera *", c[0])
    if not mount_known:
        chk.height_m = 1.0
    st = lib.cyl_camera_check(chk)
    if st != 0:  # CYL_OK
        raise CameraFileError(f"{path}: invalid camera: {ffi.string(lib.cyl_status_str(st)).decode()}")
    cam = Camera.__new__(Camera)
    cam._c = c
    cam.path, cam.format, cam.warnings = path, fmt, warnings
    cam.mount_known, cam.intrinsic_cov_known, cam.mount_sigmas_known = mount_known, intr_known, sig_known
    return cam
