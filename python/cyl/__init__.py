# SPDX-License-Identifier: BSD-3-Clause
"""cyl: libcyl's C core from Python (cffi), on numpy frames.

    import numpy as np, cyl
    table = cyl.Table.load("calib_data/synthetic.cylt")
    frame = np.zeros((480, 1280), np.uint8)            # a 640x480 YUYV frame, 2 bytes per pixel
    blobs = cyl.segment(table, frame, "YUYV")          # list of cyl.Blob
    cam = cyl.Camera(640, 480, fx=570, fy=568, cx=322.4, cy=236.9, tilt_rad=0.209, height_m=0.326)
    cam = cyl.load_camera("calib_data/synthetic_camera.yaml")   # or from a calibration file
    obs = cyl.observe(table, frame, "YUYV", cam, sizes={"orange": (0.10, 0.30)})   # list of dicts

Frames are C-contiguous uint8 arrays in the camera's own layout: YUYV and UYVY as (H, 2W) or
(H, W, 2); NV12 and I420 (YU12) as (3H/2, W) with the chroma planes after the luma plane, as V4L2
delivers them. Every unit is in the field's name (docs/formats.md); the C headers in
libcyl/include/cyl/ document each one.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Dict, List, Optional, Tuple

import numpy as np

from ._cyl import ffi, lib

__all__ = ["CylError", "Table", "Blob", "Camera", "CameraFileError", "load_camera", "segment", "observe", "version",
           "RangeBearing", "FORMATS"]

FORMATS = {"YUYV": lib.CYL_FMT_YUYV, "UYVY": lib.CYL_FMT_UYVY, "NV12": lib.CYL_FMT_NV12,
           "I420": lib.CYL_FMT_I420, "YU12": lib.CYL_FMT_I420}
ESTIMATORS = {"uniform": lib.CYL_NOISE_UNIFORM, "column": lib.CYL_NOISE_COLUMN, "local": lib.CYL_NOISE_LOCAL,
              "image": lib.CYL_NOISE_IMAGE}


class CylError(Exception):
    """A libcyl status other than success; .status is the code."""

    def __init__(self, status, what):
        self.status = status
        super().__init__(f"{what}: {ffi.string(lib.cyl_status_str(status)).decode()}")


def _check(status, what):
    if status < 0:
        raise CylError(status, what)
    return status


def version() -> str:
    """libcyl's version (the one C macro CYL_VERSION_STRING)."""
    return ffi.string(lib.cyl_version()).decode()


class Table:
    """A colour table (cyl/colortable.h): load/save CYLT files (versions 1 and 2), add boxes."""

    def __init__(self):
        self._t = ffi.new("cyl_colortable *")
        lib.cyl_colortable_init(self._t)

    @classmethod
    def load(cls, path: str) -> "Table":
        with open(path, "rb") as f:
            return cls.from_bytes(f.read(), path)

    @classmethod
    def from_bytes(cls, data: bytes, what: str = "colour table") -> "Table":
        t = cls()
        _check(lib.cyl_colortable_load(t._t, data, len(data)), what)
        return t

    def to_bytes(self) -> bytes:
        buf = ffi.new("uint8_t[]", lib.CYL_TABLE_FILE_MAX_SIZE)
        n = ffi.new("size_t *")
        _check(lib.cyl_colortable_save(self._t, buf, lib.CYL_TABLE_FILE_MAX_SIZE, n), "saving the table")
        return bytes(ffi.buffer(buf, n[0]))

    def save(self, path: str) -> None:
        with open(path, "wb") as f:
            f.write(self.to_bytes())

    @property
    def classes(self) -> List[str]:
        """Class names by index ('' = unused)."""
        return [ffi.string(self._t.name[i]).decode() for i in range(lib.CYL_MAX_CLASSES)]

    def index(self, name: str) -> int:
        i = lib.cyl_colortable_find_class(self._t, name.encode())
        if i < 0:
            raise KeyError(f"no class '{name}' in the table (classes: {[c for c in self.classes if c]})")
        return i

    def add_box(self, cls: int, name: str, y: Tuple[int, int], u: Tuple[int, int], v: Tuple[int, int],
                rgb: Tuple[int, int, int] = (128, 128, 128)) -> None:
        """Class cls (0-7) named name gets the box y x u x v (inclusive 8-bit ranges)."""
        _check(lib.cyl_colortable_set_class(self._t, cls, name.encode(), *rgb), "class name")
        _check(lib.cyl_colortable_add_box(self._t, cls, y[0], y[1], u[0], u[1], v[0], v[1]), "box")

    def mask(self, Y: int, U: int, V: int) -> int:
        """Class bits of one colour (bit i = class i)."""
        return int(lib.cyl_colortable_mask(self._t, Y, U, V))


@dataclass
class Blob:
    cls: int                # class index
    flags: int              # CYL_BLOB_* bits (cyl/segment.h)
    x0: int                 # bounding box, first and last column and row, px (inclusive)
    y0: int
    x1: int
    y1: int
    area: int               # px
    cx_px: float            # centroid, px
    cy_px: float
    mxx_px2: float          # central second moments, px^2
    myy_px2: float
    mxy_px2: float
    n_components: int       # 4-connected components merged into it


def _image(frame: np.ndarray, fmt: str, width: Optional[int], height: Optional[int]):
    if fmt not in FORMATS:
        raise ValueError(f"format '{fmt}': one of {sorted(FORMATS)}")
    a = np.ascontiguousarray(frame, dtype=np.uint8)
    if frame.dtype != np.uint8:
        raise TypeError("frame: expected a uint8 array")
    packed = fmt in ("YUYV", "UYVY")
    if height is None:
        height = a.shape[0] if packed else (a.shape[0] * 2) // 3
    if width is None:
        if a.ndim == 3:
            width = a.shape[1]
        elif a.ndim == 2:
            width = a.shape[1] // 2 if packed else a.shape[1]
        else:
            raise ValueError("frame: a 1-D array needs width and height")
    f = FORMATS[fmt]
    need = lib.cyl_image_buffer_size(f, width, height, 0)
    if need == 0 or a.nbytes < need:
        raise ValueError(f"frame: {a.nbytes} bytes, a {width}x{height} {fmt} frame needs {need}")
    img = ffi.new("cyl_image *")
    ptr = ffi.from_buffer("uint8_t[]", a)
    _check(lib.cyl_image_wrap(img, f, width, height, ptr, 0), "frame")
    return img, (a, ptr)   # keep the array and its cffi view alive with the image


class _Segmentation:
    def __init__(self, table: Table, img, params=None):
        self.params = params if params is not None else lib.cyl_segment_params_default()
        self.p = ffi.new("cyl_segment_params *", self.params)
        mr = lib.cyl_segment_max_runs(img.width, img.height, self.p)
        mb = min(mr, 65536)
        size = lib.cyl_segment_mem_size(mr, mb)
        self.mem = ffi.new("uint8_t[]", size)
        self.seg = ffi.new("cyl_segmentation *")
        _check(lib.cyl_segmentation_init(self.seg, self.mem, size, mr, mb), "segmentation memory")
        _check(lib.cyl_segment(table._t, img, self.p, self.seg), "segmentation")


def segment(table: Table, frame: np.ndarray, fmt: str = "YUYV", width: Optional[int] = None,
            height: Optional[int] = None, min_area: Optional[int] = None, merge_gap_px: Optional[int] = None,
            min_run_px: Optional[int] = None) -> List[Blob]:
    """cyl_segment on one frame: blobs sorted by class, then area (largest first)."""
    img, keep = _image(frame, fmt, width, height)
    p = lib.cyl_segment_params_default()
    if min_run_px is not None:
        p.min_run_px = min_run_px
    for k in range(lib.CYL_MAX_CLASSES):
        if min_area is not None:
            p.cls[k].min_area = min_area
        if merge_gap_px is not None:
            p.cls[k].merge_gap_px = merge_gap_px
    s = _Segmentation(table, img, p)
    out = []
    for i in range(s.seg.n_blobs):
        b = s.seg.blobs[i]
        out.append(Blob(b.cls, b.flags, b.x0, b.y0, b.x1, b.y1, b.area, b.cx_px, b.cy_px, b.mxx_px2, b.myy_px2,
                        b.mxy_px2, b.n_components))
    del keep
    return out


class Camera:
    """A libcyl camera (cyl/camera.h): intrinsics, Brown-Conrady distortion, the mount, sigmas."""

    def __init__(self, width: int, height: int, fx: float, fy: float, cx: float, cy: float,
                 k1: float = 0.0, k2: float = 0.0, p1: float = 0.0, p2: float = 0.0, k3: float = 0.0,
                 tilt_rad: float = 0.0, yaw_rad: float = 0.0, height_m: float = 1.0, offset_m: float = 0.0,
                 intrinsic_sigmas: Optional[List[float]] = None, tilt_sigma_rad: float = 0.0,
                 yaw_sigma_rad: float = 0.0, height_sigma_m: float = 0.0, offset_sigma_m: float = 0.0):
        c = ffi.new("cyl_camera *")
        lib.cyl_camera_init(c)
        c.width, c.height = width, height
        c.fx_px, c.fy_px, c.cx_px, c.cy_px = fx, fy, cx, cy
        c.k1, c.k2, c.p1, c.p2, c.k3 = k1, k2, p1, p2, k3
        c.tilt_rad, c.yaw_rad, c.height_m, c.offset_m = tilt_rad, yaw_rad, height_m, offset_m
        c.tilt_sigma_rad, c.yaw_sigma_rad = tilt_sigma_rad, yaw_sigma_rad
        c.height_sigma_m, c.offset_sigma_m = height_sigma_m, offset_sigma_m
        if intrinsic_sigmas is not None:
            if len(intrinsic_sigmas) != 9:
                raise ValueError("intrinsic_sigmas: 9 values (fx fy cx cy k1 k2 p1 p2 k3)")
            lib.cyl_camera_set_intrinsic_sigmas(c, ffi.new("double[9]", list(intrinsic_sigmas)))
        _check(lib.cyl_camera_check(c), "camera")
        self._c = c

    @classmethod
    def load(cls, path: str, lenient: bool = False) -> "Camera":
        """A calibration file (OpenCV or ROS YAML with libcyl's mount fields): see load_camera."""
        return load_camera(path, lenient)

    _FIELDS = ("width", "height", "fx_px", "fy_px", "cx_px", "cy_px", "k1", "k2", "p1", "p2", "k3", "tilt_rad",
               "yaw_rad", "height_m", "offset_m", "tilt_sigma_rad", "yaw_sigma_rad", "height_sigma_m",
               "offset_sigma_m", "flags")

    def fields(self) -> dict:
        """Every field of the C camera (cyl/camera.h names and units), intr_cov as a 9x9 list."""
        d = {k: getattr(self._c, k) for k in self._FIELDS}
        d["intr_cov"] = [[self._c.intr_cov[i][j] for j in range(9)] for i in range(9)]
        return d


def observe(table: Table, frame: np.ndarray, fmt: str, camera: Camera,
            sizes: Optional[Dict[str, Tuple[float, float]]] = None, estimator: str = "image",
            width: Optional[int] = None, height: Optional[int] = None, max_observations: int = 1024,
            edges: str = "subpixel") -> List[dict]:
    """Segmentation and cyl_observe on one frame, as `cyl detect` does: one dict per observation
    with the observation log's fields (range_m, bearing_rad, cov_rb [[rr, rb], [rb, bb]], ...).
    edges: "subpixel" (libcyl's defaults with the frame, cyl_observe_params_default_frame) or
    "table" (cyl_observe_params_default: the blob's edges where the colour table cut them)."""
    img, keep = _image(frame, fmt, width, height)
    if estimator not in ESTIMATORS:
        raise ValueError(f"estimator '{estimator}': one of {sorted(ESTIMATORS)}")
    if edges not in ("subpixel", "table"):
        raise ValueError(f"edges '{edges}': subpixel or table")
    s = _Segmentation(table, img)
    p = ffi.new("cyl_observe_params *", lib.cyl_observe_params_default_frame() if edges == "subpixel"
                else lib.cyl_observe_params_default())
    p.estimator = ESTIMATORS[estimator]
    for name, (d, h) in (sizes or {}).items():
        k = table.index(name)
        p.size[k].diameter_m = d
        p.size[k].height_m = h
    p.image = img
    p.table = table._t
    ws = lib.cyl_observe_work_size(s.seg, p)
    work = ffi.new("uint8_t[]", max(ws, 1))
    obs = ffi.new("cyl_observation[]", max_observations)
    n = ffi.new("uint32_t *")
    _check(lib.cyl_observe(s.seg, camera._c, p, work, ws, obs, max_observations, n), "observation")
    names = table.classes
    out = []
    for i in range(n[0]):
        o = obs[i]
        b = s.seg.blobs[o.blob]
        out.append({
            "class": names[o.cls], "class_id": o.cls, "range_m": o.range_m, "bearing_rad": o.bearing_rad,
            "cov_rb": [[o.cov_rb[0][0], o.cov_rb[0][1]], [o.cov_rb[1][0], o.cov_rb[1][1]]],
            "x_m": o.x_m, "y_m": o.y_m, "cov_xy": [[o.cov_xy[0][0], o.cov_xy[0][1]], [o.cov_xy[1][0], o.cov_xy[1][1]]],
            "confidence": o.confidence, "u_px": o.u_px, "v_px": o.v_px, "var_u_px2": o.var_u_px2,
            "var_v_px2": o.var_v_px2, "area_px": o.area, "flags": o.flags, "bbox_px": [b.x0, b.y0, b.x1, b.y1],
            "cov_frame": [o.cov_rb_frame[0][0], o.cov_rb_frame[0][1], o.cov_rb_frame[1][1]],
            "bias_var_px2": [o.bias_var_u_px2, o.bias_var_v_px2],
        })
        if o.aspect_rel > 0.0:
            out[-1]["aspect_rel"] = o.aspect_rel
        if o.area_rel > 0.0:
            out[-1]["area_rel"] = o.area_rel
            out[-1]["offset_rel"] = o.offset_rel
        if o.side_colour_rel != 0.0:
            out[-1]["side_colour_rel"] = o.side_colour_rel
        if o.subpixel_du_px != 0.0 or o.subpixel_dv_px != 0.0:
            out[-1]["subpixel_shift_px"] = [o.subpixel_du_px, o.subpixel_dv_px]
    del keep
    return out


class RangeBearing:
    """libcyl's camera model (cyl/rangebearing.h, cyl_rb_eval): a measured point (u, v) px to the
    landmark's range_m and bearing_rad from the robot centre, at the camera's calibration moved by
    an error delta = (fx, fy, cx, cy px, tilt, yaw rad, h, s m) -- the order of the observation's
    jac_calib -- with analytic Jacobians. What a SLAM back end that estimates the calibration
    needs: the model evaluated where the estimate is, not its linearisation at the nominal values."""

    CALIB_INPUTS = (2, 3, 4, 5, 11, 12, 13, 14)   # CYL_IN_FX .. CYL_IN_S of the delta's entries
    GEOM = {"exact": lib.CYL_GEOM_EXACT, "paper": lib.CYL_GEOM_PAPER}

    def __init__(self, camera: Camera, model: str = "exact"):
        if model not in self.GEOM:
            raise ValueError(f"model '{model}': one of {sorted(self.GEOM)}")
        self.model = self.GEOM[model]
        self.calib_columns = np.array(self.CALIB_INPUTS)   # jac's columns of the delta's entries
        n = lib.CYL_IN_COUNT
        nominal = ffi.new("double[]", n)
        lib.cyl_rb_inputs(camera._c, 0.0, 0.0, nominal)
        self.nominal = np.array([nominal[k] for k in range(n)])
        self._in = ffi.new("double[]", n)
        self._out = ffi.new("double[2]")
        self._jac = ffi.new("double[2][15]")
        self._inbuf = np.frombuffer(ffi.buffer(self._in), dtype=np.float64)
        self._jacbuf = np.frombuffer(ffi.buffer(self._jac), dtype=np.float64).reshape(2, 15)

    def eval(self, u_px: float, v_px: float, delta=None):
        """(range_m, bearing_rad, jac) with jac the 2x15 d(range, bearing)/d(inputs) (input order
        of cyl/rangebearing.h: u, v, fx, fy, cx, cy, k1, k2, p1, p2, k3, tilt, yaw, h, s), or None
        when the ray does not meet the floor (no range) or the model fails there."""
        self._inbuf[:] = self.nominal
        self._inbuf[0], self._inbuf[1] = u_px, v_px
        if delta is not None:
            self._inbuf[self.calib_columns] += np.asarray(delta, float)
        st = lib.cyl_rb_eval(self._in, self.model, self._out, ffi.NULL, self._jac, ffi.NULL)
        if st != 0:
            return None
        return self._out[0], self._out[1], self._jacbuf.copy()


from .camera_file import CameraFileError, load_camera  # noqa: E402  (needs Camera above)
