# SPDX-License-Identifier: BSD-3-Clause
"""The observation log (JSON Lines, docs/formats.md) as an MCAP file that Foxglove and the `mcap`
library read: one channel per record type, JSON messages described by JSON Schema (units in the
field names and descriptions), every field of every record kept as written.

    /cyl/header          the log's header (once)          schema cyl.ObservationLogHeader
    /cyl/frame           one per frame                     schema cyl.Frame
    /cyl/obs             one per observation               schema cyl.Observation
    /cyl/odom            one per odometry increment        schema cyl.Odometry
    /cyl/truth_pose      ground-truth robot poses           schema cyl.TruthPose
    /cyl/truth_landmark  ground-truth landmarks             schema cyl.TruthLandmark

Log and publish times are the record's `t` (s) in ns; records without one (truth landmarks, the
header) take the first frame's time.
"""
from __future__ import annotations

import json
from typing import Dict

from .output import OutputFile

NUM = {"type": "number"}


def _obj(title, desc, props, required=()):
    return {"$schema": "https://json-schema.org/draft/2020-12/schema", "title": title, "description": desc,
            "type": "object", "properties": props, "required": list(required)}


def _n(desc):
    return {"type": "number", "description": desc}


SCHEMAS: Dict[str, dict] = {
    "header": _obj("cyl.ObservationLogHeader", "libcyl observation log header (format cyl-observations)", {
        "type": {"const": "header"}, "format": {"const": "cyl-observations"}, "version": {"type": "integer"},
        "source": {"type": "string"}, "model": {"type": "string"}, "estimator": {"type": "string"},
        "classes": {"type": "array", "items": {"type": "string"}},
        "camera": {"type": ["object", "null"], "description": "intrinsics (px), mount (rad, m), calib_cov (8x8)"},
    }, ["type", "format", "version"]),
    "frame": _obj("cyl.Frame", "one camera frame", {
        "seq": {"type": "integer"}, "t": _n("s, the source's clock"), "n_obs": {"type": "integer"}}, ["seq", "t"]),
    "obs": _obj("cyl.Observation", "one landmark observation: range, bearing, their covariance, confidence", {
        "seq": {"type": "integer"}, "t": _n("s"), "class": {"type": "string"}, "class_id": {"type": "integer"},
        "range_m": _n("m, from the robot centre"), "bearing_rad": _n("rad, counter-clockwise from ahead"),
        "cov_rr": _n("m^2"), "cov_rb": _n("m rad"), "cov_bb": _n("rad^2"),
        "x_m": _n("m, robot frame, ahead"), "y_m": _n("m, robot frame, left"),
        "cov_xx": _n("m^2"), "cov_xy": _n("m^2"), "cov_yy": _n("m^2"),
        "confidence": _n("0..1, that the blob is a landmark of its class"),
        "u_px": _n("px, measurement point column"), "v_px": _n("px, row"),
        "var_u_px2": _n("px^2"), "var_v_px2": _n("px^2"), "area_px": {"type": "integer"},
        "aspect_rel": _n("blob width/height over the whole landmark's, < 1 a side hidden"),
        "area_rel": _n("blob area over the whole landmark's silhouette's, < 1 parts not classified"),
        "offset_rel": _n("(u_px - box middle column) / box width, away from 0 a side not classified"),
        "side_colour_rel": _n("share of a strip left of the box in the blob's colour less that right of it, -1..1"),
        "flags": {"type": "integer"}, "bbox_px": {"type": "array", "items": {"type": "integer"},
                                                  "description": "x0 y0 x1 y1, px, inclusive"},
        "jac_calib": {"type": "array", "items": NUM}, "cov_frame": {"type": "array", "items": NUM},
        "bias_var_px2": {"type": "array", "items": NUM,
                         "description": "u, v variance of the centroid's residual bias (part of cov_frame), px^2"},
        "subpixel_shift_px": {"type": "array", "items": NUM,
                              "description": "u, v shift of the centroid by the sub-pixel edges (in u_px, v_px), px"},
    }, ["seq", "class", "range_m", "bearing_rad", "cov_rr", "cov_rb", "cov_bb"]),
    "odom": _obj("cyl.Odometry", "pose increment since the previous one, in its frame (a BetweenFactor<Pose2>)", {
        "seq": {"type": "integer"}, "t": _n("s"), "dx_m": _n("m"), "dy_m": _n("m"), "dtheta_rad": _n("rad"),
        "cov": {"type": "array", "items": NUM, "description": "xx xy xt yy yt tt (m^2, m rad, rad^2)"},
    }, ["seq", "dx_m", "dy_m", "dtheta_rad", "cov"]),
    "truth_pose": _obj("cyl.TruthPose", "true robot pose, world frame", {
        "seq": {"type": "integer"}, "t": _n("s"), "x_m": _n("m"), "y_m": _n("m"), "theta_rad": _n("rad")},
        ["x_m", "y_m", "theta_rad"]),
    "truth_landmark": _obj("cyl.TruthLandmark", "true landmark, world frame", {
        "id": {"type": "integer"}, "class": {"type": "string"}, "class_id": {"type": "integer"}, "x_m": _n("m"),
        "y_m": _n("m"), "diameter_m": _n("m"), "height_m": _n("m")}, ["id", "x_m", "y_m"]),
}


class ObsMcapError(ValueError):
    pass


def convert(log: str, out: str) -> Dict[str, int]:
    """Write the observation log `log` as MCAP `out`; returns the message count per channel."""
    from mcap.writer import Writer
    try:
        lines = open(log, encoding="utf-8").read().splitlines()
    except OSError as e:
        raise ObsMcapError(f"{log}: cannot open: {e.strerror}") from None
    recs = []
    for n, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            r = json.loads(line)
        except json.JSONDecodeError as e:
            raise ObsMcapError(f"{log}:{n}: not JSON: {e.msg}") from None
        if not isinstance(r, dict) or r.get("type") not in SCHEMAS:
            raise ObsMcapError(f"{log}:{n}: record type {r.get('type') if isinstance(r, dict) else r!r} is not one of "
                               f"{', '.join(SCHEMAS)}")
        if n == 1 and (r["type"] != "header" or r.get("format") != "cyl-observations" or r.get("version") not in (1, 2)):
            raise ObsMcapError(f"{log}:1: not a cyl-observations log of version 1 or 2")
        recs.append(r)
    if not recs:
        raise ObsMcapError(f"{log}: empty")
    t0 = next((r["t"] for r in recs if "t" in r), 0.0)
    counts = {k: 0 for k in SCHEMAS}
    with OutputFile(out) as f:   # .part renamed at the end, device nodes and FIFOs written in place
        w = Writer(f)
        w.start(profile="", library="libcyl cyl-robotlog")
        chan = {}
        for k, sch in SCHEMAS.items():
            sid = w.register_schema(name=sch["title"], encoding="jsonschema", data=json.dumps(sch).encode())
            chan[k] = w.register_channel(topic=f"/cyl/{k}", message_encoding="json", schema_id=sid)
        for r in recs:
            t_ns = int(round(float(r.get("t", t0)) * 1e9))
            w.add_message(chan[r["type"]], log_time=t_ns, publish_time=t_ns, sequence=counts[r["type"]],
                          data=json.dumps(r, separators=(",", ":")).encode())
            counts[r["type"]] += 1
        w.finish()
    return counts
