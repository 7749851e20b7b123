# SPDX-License-Identifier: BSD-3-Clause
"""libcyl's camera model for the back end: the observation log's camera, evaluated through the
`cyl` Python binding (cyl.RangeBearing, which calls cyl_rb_eval in C). The model is written once,
in C; this module only finds the binding and builds the camera from the log's header.

The binding is the package `cyl` (python/; `python/build.sh` builds it in place into build/python,
as the test scripts do); when it is not importable as installed, the repository's build/python
beside this package is tried."""
from __future__ import annotations

import os
import sys

# the header's camera fields the model needs, which are cyl.Camera's keyword names too
# (docs/formats.md; older logs lack the distortion coefficients and cannot use the exact model)
HEADER_FIELDS = ("width", "height", "fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "tilt_rad",
                 "yaw_rad", "height_m", "offset_m")


def import_binding():
    """The `cyl` module, or None with the reason as a string."""
    try:
        import cyl  # noqa: F401
        return sys.modules["cyl"], None
    except ImportError as e:
        first = str(e)
    here = os.path.dirname(os.path.abspath(__file__))
    cand = os.path.normpath(os.path.join(here, "..", "..", "build", "python"))
    if os.path.isdir(os.path.join(cand, "cyl")) and cand not in sys.path:
        sys.path.append(cand)
        try:
            import cyl  # noqa: F401,F811
            return sys.modules["cyl"], None
        except ImportError as e:
            first = str(e)
    return None, f"the cyl Python binding is not importable ({first}; `python/build.sh` builds it)"


def range_bearing_model(header):
    """cyl.RangeBearing for the log's camera, or (None, why) when the header lacks a field the
    model needs or the binding is missing. Returns (model, None) on success."""
    cam = (header or {}).get("camera")
    if not isinstance(cam, dict):
        return None, "the log's header has no camera"
    missing = [k for k in HEADER_FIELDS if not isinstance(cam.get(k), (int, float)) or isinstance(cam.get(k), bool)]
    if missing:
        return None, "the log header's camera lacks " + ", ".join(missing)
    geom = (header or {}).get("model", "exact")
    if geom not in ("exact", "paper"):
        return None, f"the log header's model '{geom}' is not one libcyl evaluates"
    cyl, why = import_binding()
    if cyl is None:
        return None, why
    c = cyl.Camera(**{k: cam[k] for k in HEADER_FIELDS})
    return cyl.RangeBearing(c, geom), None
