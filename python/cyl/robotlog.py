# SPDX-License-Identifier: BSD-3-Clause
"""Robot logs in: ROS 1 bags, ROS 2 bags (sqlite3 or MCAP) and CSV odometry to raw frame logs
(`*.cylraw`), so that `cyl detect` and the SLAM demo run on them unchanged; and the reverse, a raw
log written as a bag (the test fixtures: no outside data needed). Bags are read and written with
the `rosbags` library (pure Python, no ROS installation).

Odometry (docs/formats.md, "Robot logs"): the robot's pose is interpolated at each frame's time
between the two odometry messages around it (x, y linearly, the heading along the shorter arc),
and the frame's ODOMETRY record is the SE(2) increment from the previous frame's pose. Its
covariance is the twist covariance of the message nearest the frame times the frame interval
squared (vx, vy, wz block); where the messages carry none (all zero), the model given by
`odom_noise` is used and said so. Frames outside the odometry's time span are dropped and
counted; a gap between odometry messages longer than `max_gap_s` that a frame falls into is an
error naming it, unless `bridge_gaps` is set (then each bridged gap is reported).
"""
from __future__ import annotations

import csv
import io
import math
import sys
from bisect import bisect_left
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from . import rawlog
from .output import OutputError, OutputFile


class RobotLogError(ValueError):
    """A robot log that cannot be brought in as asked; the message names the file, topic or line."""


# ---- SE(2) ------------------------------------------------------------------------------------

def wrap(a: float) -> float:
    return math.atan2(math.sin(a), math.cos(a))


def between(a, b):
    """The pose of b in the frame of a: (dx, dy, dtheta)."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    c, s = math.cos(a[2]), math.sin(a[2])
    return (c * dx + s * dy, -s * dx + c * dy, wrap(b[2] - a[2]))


def compose(a, d):
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * d[0] - s * d[1], a[1] + s * d[0] + c * d[1], wrap(a[2] + d[2]))


def yaw_of(q) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


@dataclass
class PoseTrack:
    """Timestamped planar poses (t in ns, strictly increasing) with an optional 3x3 twist
    covariance (vx, vy, wz) per sample."""
    what: str
    t_ns: List[int] = field(default_factory=list)
    pose: List[Tuple[float, float, float]] = field(default_factory=list)
    twist_cov: List[Optional[np.ndarray]] = field(default_factory=list)

    def add(self, t_ns: int, pose, twist_cov=None, where: str = ""):
        if self.t_ns and t_ns <= self.t_ns[-1]:
            kind = "repeated" if t_ns == self.t_ns[-1] else "out-of-order"
            raise RobotLogError(f"{self.what}{where}: {kind} timestamp {t_ns * 1e-9:.9f} s after "
                                f"{self.t_ns[-1] * 1e-9:.9f} s")
        self.t_ns.append(t_ns)
        self.pose.append(tuple(float(v) for v in pose))
        self.twist_cov.append(twist_cov)

    def span(self):
        return (self.t_ns[0], self.t_ns[-1]) if self.t_ns else (None, None)

    def at(self, t: int):
        """(pose at t, index of the sample nearest t, gap_s of the bracketing interval); None
        outside the span."""
        if not self.t_ns or t < self.t_ns[0] or t > self.t_ns[-1]:
            return None
        i = bisect_left(self.t_ns, t)
        if self.t_ns[i] == t:
            return self.pose[i], i, 0.0
        t0, t1 = self.t_ns[i - 1], self.t_ns[i]
        a, b = self.pose[i - 1], self.pose[i]
        f = (t - t0) / (t1 - t0)
        p = (a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), wrap(a[2] + f * wrap(b[2] - a[2])))
        return p, (i if f >= 0.5 else i - 1), (t1 - t0) * 1e-9


class TfTree:
    """Planar transforms from /tf (dynamic, timestamped) and /tf_static (constant), for odometry
    as the chain between two named frames (e.g. odom -> base_link through base_footprint)."""

    def __init__(self, what: str):
        self.what = what
        self.dynamic: Dict[Tuple[str, str], PoseTrack] = {}
        self.static: Dict[Tuple[str, str], Tuple[float, float, float]] = {}

    def add(self, tf, is_static: bool):
        parent, child = tf.header.frame_id.lstrip("/"), tf.child_frame_id.lstrip("/")
        tr, q = tf.transform.translation, tf.transform.rotation
        pose = (tr.x, tr.y, yaw_of(q))
        if is_static:
            self.static[(parent, child)] = pose
        else:
            track = self.dynamic.setdefault((parent, child), PoseTrack(f"{self.what}: {parent} -> {child}"))
            t = _stamp_ns(tf)
            if track.t_ns and t == track.t_ns[-1]:
                return                      # republished at the same stamp
            track.add(t, pose, where=f", message {len(track.t_ns)}")

    def chain(self, a: str, b: str):
        """The links from frame a to frame b: [(parent, child, forward)], or raise naming the frames."""
        edges = {}
        for (p, c) in list(self.dynamic) + list(self.static):
            edges.setdefault(p, []).append((c, (p, c, True)))
            edges.setdefault(c, []).append((p, (p, c, False)))
        prev = {a: None}
        todo = [a]
        while todo:
            f = todo.pop(0)
            for g, link in edges.get(f, []):
                if g not in prev:
                    prev[g] = (f, link)
                    todo.append(g)
        if b not in prev:
            frames = sorted(edges)
            raise RobotLogError(f"{self.what}: no transform chain from '{a}' to '{b}' (frames in /tf and /tf_static: "
                                f"{', '.join(frames) or 'none'})")
        links = []
        f = b
        while prev[f] is not None:
            f0, link = prev[f]
            links.append(link)
            f = f0
        return links[::-1]

    def track(self, a: str, b: str) -> PoseTrack:
        """The pose of frame b in frame a at the stamps of the chain's dynamic links, composed
        along the chain (each dynamic link interpolated at each stamp)."""
        links = self.chain(a, b)
        dyn = [self.dynamic[(p, c)] for (p, c, _f) in links if (p, c) in self.dynamic]
        if not dyn:
            raise RobotLogError(f"{self.what}: the chain from '{a}' to '{b}' has no moving transform (only /tf_static)")
        lo = max(d.t_ns[0] for d in dyn)
        hi = min(d.t_ns[-1] for d in dyn)
        stamps = sorted({t for d in dyn for t in d.t_ns if lo <= t <= hi})
        out = PoseTrack(f"{self.what}: {a} -> {b}")
        for t in stamps:
            pose = (0.0, 0.0, 0.0)
            for (p, c, fwd) in links:
                link = self.dynamic[(p, c)].at(t)[0] if (p, c) in self.dynamic else self.static[(p, c)]
                if not fwd:
                    link = between(link, (0.0, 0.0, 0.0))   # the inverse transform
                pose = compose(pose, link)
            out.add(t, pose)
        return out


@dataclass
class OdomNoise:
    """The odometry model used where the log carries no covariance: per frame-to-frame step,
    sigma_x = sigma_y = trans_rel * distance + trans_abs_m, sigma_theta = rot_rel * |dtheta| +
    rot_per_m * distance + rot_abs_rad."""
    trans_rel: float = 0.05
    trans_abs_m: float = 1e-4
    rot_rel: float = 0.05
    rot_per_m: float = 0.02
    rot_abs_rad: float = 1e-4

    def cov(self, d) -> Tuple[float, ...]:
        dist = math.hypot(d[0], d[1])
        st = self.trans_rel * dist + self.trans_abs_m
        sr = self.rot_rel * abs(d[2]) + self.rot_per_m * dist + self.rot_abs_rad
        return (st * st, 0.0, 0.0, st * st, 0.0, sr * sr)


@dataclass
class ImportReport:
    frames: int = 0
    dropped_before: int = 0
    dropped_after: int = 0
    bridged_gaps: List[str] = field(default_factory=list)
    model_covariance_steps: int = 0
    truth_poses: int = 0
    truth_landmarks: int = 0
    source: str = ""

    def lines(self) -> List[str]:
        out = [f"{self.frames} frames with odometry from {self.source}"]
        if self.dropped_before or self.dropped_after:
            out.append(f"dropped {self.dropped_before} frames before the first and {self.dropped_after} after the "
                       f"last odometry message (no pose to give them)")
        for g in self.bridged_gaps:
            out.append("bridged " + g)
        if self.model_covariance_steps:
            out.append(f"{self.model_covariance_steps} steps had no twist covariance in the log: the odometry "
                       f"noise model was used for them")
        if self.truth_poses or self.truth_landmarks:
            out.append(f"ground truth: {self.truth_poses} poses, {self.truth_landmarks} landmarks")
        return out


def odometry_records(frame_t: Sequence[int], track: PoseTrack, noise: OdomNoise, max_gap_s: float,
                     bridge_gaps: bool, report: ImportReport):
    """For each frame time: None (outside the odometry, dropped) or (increment, cov6) from the
    previous kept frame (the first kept frame gets a zero increment)."""
    out = []
    prev = None
    prev_t = None
    lo, hi = track.span()
    for k, t in enumerate(frame_t):
        got = track.at(t)
        if got is None:
            if lo is None or t < lo:
                report.dropped_before += 1
            else:
                report.dropped_after += 1
            out.append(None)
            continue
        pose, near, gap = got
        if gap > max_gap_s:
            msg = (f"{track.what}: an odometry gap of {gap:.3f} s (at {t * 1e-9:.3f} s, frame {k}) is longer than "
                   f"{max_gap_s} s")
            if not bridge_gaps:
                raise RobotLogError(msg + "; --bridge-gaps interpolates across it")
            report.bridged_gaps.append(msg)
        if prev is None:
            out.append(((0.0, 0.0, 0.0), (1e-8, 0.0, 0.0, 1e-8, 0.0, 1e-8)))
        else:
            d = between(prev, pose)
            tc = track.twist_cov[near]
            dt = (t - prev_t) * 1e-9
            if tc is not None and np.any(tc != 0.0):
                c = tc * dt * dt
                cov = (c[0, 0], c[0, 1], c[0, 2], c[1, 1], c[1, 2], c[2, 2])
            else:
                cov = noise.cov(d)
                report.model_covariance_steps += 1
            out.append((d, cov))
        prev, prev_t = pose, t
    return out


# ---- pixels -----------------------------------------------------------------------------------

ENCODINGS = {"yuv422_yuy2": "YUYV", "yuyv": "YUYV", "yuv422": "UYVY", "uyvy": "UYVY", "nv12": "NV12",
             "rgb8": "RGB", "bgr8": "BGR", "mono8": "MONO"}


def rgb_to_i420(rgb: np.ndarray) -> bytes:
    """RGB (H, W, 3) uint8 to I420 with BT.601 studio-range coefficients, chroma from the top-left
    pixel of each 2x2 block: the conversion OpenCV's COLOR_RGB2YUV_I420 makes, which `cyl detect`
    uses on image files. Odd sizes are cropped to even."""
    h, w = rgb.shape[0] & ~1, rgb.shape[1] & ~1
    f = rgb[:h, :w].astype(np.float64)
    r, g, b = f[..., 0], f[..., 1], f[..., 2]
    y = 16.0 + 0.257 * r + 0.504 * g + 0.098 * b
    rs, gs, bs = r[0::2, 0::2], g[0::2, 0::2], b[0::2, 0::2]
    u = 128.0 - 0.148 * rs - 0.291 * gs + 0.439 * bs
    v = 128.0 + 0.439 * rs - 0.368 * gs - 0.071 * bs
    q = lambda a: np.clip(np.floor(a + 0.5), 0, 255).astype(np.uint8)  # noqa: E731
    return q(y).tobytes() + q(u).tobytes() + q(v).tobytes()


def frame_from_image_msg(msg, where: str):
    """(fourcc, width, height, stride, payload) of a sensor_msgs/Image."""
    enc = msg.encoding.lower()
    if enc not in ENCODINGS:
        raise RobotLogError(f"{where}: image encoding '{msg.encoding}' is not supported "
                            f"({', '.join(sorted(ENCODINGS))}, or a CompressedImage in JPEG)")
    kind = ENCODINGS[enc]
    w, h, step = int(msg.width), int(msg.height), int(msg.step)
    data = np.asarray(msg.data, dtype=np.uint8)
    if kind in ("YUYV", "UYVY"):
        if step < 2 * w or len(data) < step * h:
            raise RobotLogError(f"{where}: {msg.encoding} {w}x{h} with step {step} needs {step * h} bytes, has {len(data)}")
        return kind, w, h, step, data[:step * h].tobytes()
    if kind == "NV12":
        need = step * h + step * ((h + 1) // 2)
        if step < w or len(data) < need:
            raise RobotLogError(f"{where}: nv12 {w}x{h} with step {step} needs {need} bytes, has {len(data)}")
        return "NV12", w, h, step, data[:need].tobytes()
    ch = 1 if kind == "MONO" else 3
    if step < ch * w or len(data) < step * h:
        raise RobotLogError(f"{where}: {msg.encoding} {w}x{h} with step {step} needs {step * h} bytes, has {len(data)}")
    img = data[:step * h].reshape(h, step)[:, :ch * w].reshape(h, w, ch)
    if kind == "MONO":
        img = np.repeat(img, 3, axis=2)
    elif kind == "BGR":
        img = img[..., ::-1]
    return "YU12", w & ~1, h & ~1, w & ~1, rgb_to_i420(img)


def frame_from_compressed_msg(msg, where: str):
    fmt = msg.format.lower()
    if "jpeg" not in fmt and "jpg" not in fmt:
        raise RobotLogError(f"{where}: compressed image format '{msg.format}' is not supported (JPEG only)")
    from PIL import Image
    try:
        img = np.asarray(Image.open(io.BytesIO(bytes(msg.data))).convert("RGB"))
    except Exception as e:  # noqa: BLE001 - any decoder failure names the message
        raise RobotLogError(f"{where}: cannot decode the JPEG: {e}") from None
    h, w = img.shape[:2]
    return "YU12", w & ~1, h & ~1, w & ~1, rgb_to_i420(img)


def frame_to_rgb(fourcc: str, w: int, h: int, stride: int, payload: bytes) -> np.ndarray:
    """A raw-log frame to RGB (BT.601 studio range; for JPEG fixtures)."""
    a = np.frombuffer(payload, np.uint8)
    if fourcc in ("YUYV", "UYVY"):
        p = a[:stride * h].reshape(h, stride)[:, :2 * w]
        yi, ui, vi = (0, 1, 3) if fourcc == "YUYV" else (1, 0, 2)
        Y = p[:, yi::2].astype(np.float64)
        U = np.repeat(p[:, ui::4], 2, axis=1).astype(np.float64)
        V = np.repeat(p[:, vi::4], 2, axis=1).astype(np.float64)
    else:
        raise RobotLogError(f"frame format {fourcc}: only YUYV and UYVY frames are written as JPEG")
    c, d, e = Y - 16.0, U - 128.0, V - 128.0
    r = 1.164 * c + 1.596 * e
    g = 1.164 * c - 0.392 * d - 0.813 * e
    b = 1.164 * c + 2.017 * d
    return np.clip(np.stack([r, g, b], axis=2) + 0.5, 0, 255).astype(np.uint8)


# ---- reading bags -----------------------------------------------------------------------------

def _stamp_ns(msg) -> int:
    s = msg.header.stamp
    return int(s.sec) * 1_000_000_000 + int(getattr(s, "nanosec", getattr(s, "nsec", 0)))


def _twist_cov(msg) -> np.ndarray:
    c = np.asarray(msg.twist.covariance, dtype=np.float64).reshape(6, 6)
    idx = [0, 1, 5]
    return c[np.ix_(idx, idx)]


def storage_of(path: Path) -> str:
    if path.is_file() and path.suffix == ".bag":
        return "ros1"
    if path.is_file() and path.suffix == ".mcap":
        return "mcap"
    if path.is_dir():
        if any(path.glob("*.mcap")):
            return "mcap"
        if any(path.glob("*.db3")):
            return "sqlite3"
    raise RobotLogError(f"{path}: not a ROS bag (a ROS 1 .bag file, or a ROS 2 bag folder with .db3 or .mcap)")


@dataclass
class ImportOptions:
    image_topic: str
    odom_topic: Optional[str] = None
    tf_frames: Optional[Tuple[str, str]] = None   # odometry from /tf: (odometry frame, robot frame)
    truth_topic: Optional[str] = None
    truth_landmarks_topic: Optional[str] = None
    classes: Sequence[str] = ()          # class names in colour-table order (truth landmarks' ns)
    max_gap_s: float = 0.5
    bridge_gaps: bool = False
    allow_no_odometry: bool = False
    noise: OdomNoise = field(default_factory=OdomNoise)
    max_frames: int = 0


def import_bag(bag: str, out: str, opt: ImportOptions, camera_info_out: Optional[str] = None,
               progress=None) -> ImportReport:
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    path = Path(bag)
    if not path.exists():
        raise RobotLogError(f"{bag}: no such file or folder")
    storage = storage_of(path)
    report = ImportReport(source=f"{bag} ({storage})")
    try:
        reader = AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE))
        reader.open()
    except Exception as e:  # noqa: BLE001 - rosbags' own errors, named
        raise RobotLogError(f"{bag}: cannot open the bag: {e}") from None
    try:
        topics = {c.topic: c.msgtype for c in reader.connections}

        def need(topic, types, what):
            if topic not in topics:
                raise RobotLogError(f"{bag}: no topic '{topic}' ({what}); the bag has: "
                                    + ", ".join(f"{t} [{m}]" for t, m in sorted(topics.items())))
            if topics[topic] not in types:
                raise RobotLogError(f"{bag}: topic '{topic}' is {topics[topic]}, not {' or '.join(types)} ({what})")

        need(opt.image_topic, ("sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage"), "the camera images")
        if opt.odom_topic:
            need(opt.odom_topic, ("nav_msgs/msg/Odometry",), "the odometry")
        elif opt.tf_frames:
            need("/tf", ("tf2_msgs/msg/TFMessage",), "the transforms for --tf")
        elif not opt.allow_no_odometry:
            raise RobotLogError(f"{bag}: no odometry given (--odom-topic or --tf ODOM_FRAME:ROBOT_FRAME); without "
                                f"odometry the SLAM demo cannot place the frames (--no-odometry imports the frames alone)")
        if opt.truth_topic:
            need(opt.truth_topic, ("nav_msgs/msg/Odometry", "geometry_msgs/msg/PoseStamped"), "the ground-truth poses")
        if opt.truth_landmarks_topic:
            need(opt.truth_landmarks_topic, ("visualization_msgs/msg/MarkerArray",), "the ground-truth landmarks")

        # pass 1: odometry, truth, camera_info, frame times
        odom = PoseTrack(f"{bag}: {opt.odom_topic}")
        tf = TfTree(f"{bag}: /tf")
        truth = PoseTrack(f"{bag}: {opt.truth_topic}")
        landmarks = []
        frame_t: List[int] = []
        cam_info = None
        want = [c for c in reader.connections if c.topic in
                {opt.odom_topic, opt.truth_topic, opt.truth_landmarks_topic, opt.image_topic}
                or (opt.tf_frames and c.topic in ("/tf", "/tf_static"))
                or c.msgtype == "sensor_msgs/msg/CameraInfo"]
        for conn, _t, raw in reader.messages(connections=want):
            msg = reader.deserialize(raw, conn.msgtype)
            if conn.topic == opt.image_topic:
                t = _stamp_ns(msg)
                if frame_t and t <= frame_t[-1]:
                    raise RobotLogError(f"{bag}: {opt.image_topic}: image {len(frame_t)} has an out-of-order or repeated "
                                        f"timestamp {t * 1e-9:.9f} s after {frame_t[-1] * 1e-9:.9f} s")
                if t == 0:
                    raise RobotLogError(f"{bag}: {opt.image_topic}: image {len(frame_t)} has no timestamp (header stamp 0)")
                frame_t.append(t)
            elif conn.topic == opt.odom_topic:
                t = _stamp_ns(msg)
                p = msg.pose.pose
                odom.add(t, (p.position.x, p.position.y, yaw_of(p.orientation)), _twist_cov(msg),
                         where=f", message {len(odom.t_ns)}")
            elif opt.tf_frames and conn.topic in ("/tf", "/tf_static"):
                for tr in msg.transforms:
                    tf.add(tr, conn.topic == "/tf_static")
            elif conn.topic == opt.truth_topic:
                p = msg.pose.pose if conn.msgtype == "nav_msgs/msg/Odometry" else msg.pose
                truth.add(_stamp_ns(msg), (p.position.x, p.position.y, yaw_of(p.orientation)),
                          where=f", message {len(truth.t_ns)}")
            elif conn.topic == opt.truth_landmarks_topic and not landmarks:
                for m in msg.markers:
                    ns = m.ns
                    if ns in opt.classes:
                        cls = list(opt.classes).index(ns)
                    elif ns.startswith("class") and ns[5:].isdigit():
                        cls = int(ns[5:])
                    else:
                        raise RobotLogError(f"{bag}: {opt.truth_landmarks_topic}: marker {m.id} has namespace '{ns}', "
                                            f"not a class of {list(opt.classes)} (--classes)")
                    landmarks.append((int(m.id), cls, m.pose.position.x, m.pose.position.y, m.scale.x, m.scale.z))
            elif conn.msgtype == "sensor_msgs/msg/CameraInfo" and cam_info is None:
                cam_info = msg
        if not frame_t:
            raise RobotLogError(f"{bag}: {opt.image_topic}: no images")
        if opt.max_frames:
            frame_t = frame_t[:opt.max_frames]
        if opt.tf_frames:
            odom = tf.track(*opt.tf_frames)
        if opt.odom_topic or opt.tf_frames:
            if not odom.t_ns:
                raise RobotLogError(f"{odom.what}: no odometry messages")
            steps = odometry_records(frame_t, odom, opt.noise, opt.max_gap_s, opt.bridge_gaps, report)
        else:
            steps = [((0.0, 0.0, 0.0), None)] * len(frame_t)
        if camera_info_out:
            if cam_info is None:
                raise RobotLogError(f"{bag}: no sensor_msgs/CameraInfo topic to write {camera_info_out} from")
            write_camera_info_yaml(camera_info_out, cam_info)

        # pass 2: frames
        writer = None
        k = 0
        img_conn = [c for c in reader.connections if c.topic == opt.image_topic]
        for conn, _t, raw in reader.messages(connections=img_conn):
            if k >= len(frame_t):
                break
            msg = reader.deserialize(raw, conn.msgtype)
            where = f"{bag}: {opt.image_topic}, image {k}"
            if conn.msgtype == "sensor_msgs/msg/Image":
                fcc, w, h, stride, payload = frame_from_image_msg(msg, where)
            else:
                fcc, w, h, stride, payload = frame_from_compressed_msg(msg, where)
            t = frame_t[k]
            st = steps[k]
            k += 1
            if st is None:
                continue
            if writer is None:
                flags = rawlog.FLAG_HAS_TRUTH if (opt.truth_topic or landmarks) else 0
                info = rawlog.StreamInfo(fcc, w, h, stride, rawlog.frame_bytes(fcc, w, h, stride), flags,
                                         "bag " + path.name)
                writer = rawlog.Writer(out, info)
                for lm in landmarks:
                    writer.write(rawlog.TRUTH_LANDMARK, 0, t, rawlog.truth_landmark_payload(*lm))
                report.truth_landmarks = len(landmarks)
            elif (fcc, w, h, stride) != (writer.info.fourcc, writer.info.width, writer.info.height, writer.info.stride):
                writer.abort()
                raise RobotLogError(f"{where}: {fcc} {w}x{h} differs from the first image's {writer.info.fourcc} "
                                    f"{writer.info.width}x{writer.info.height}")
            seq = report.frames
            writer.write(rawlog.FRAME, seq, t, payload)
            if opt.odom_topic or opt.tf_frames:
                writer.write(rawlog.ODOMETRY, seq, t, rawlog.odometry_payload(*st))
            if opt.truth_topic:
                got = truth.at(t)
                if got is not None:
                    writer.write(rawlog.TRUTH_POSE, seq, t, rawlog.truth_pose_payload(*got[0]))
                    report.truth_poses += 1
            report.frames += 1
            if progress:
                progress(k, len(frame_t))
        if writer is None:
            raise RobotLogError(f"{bag}: no image falls inside the odometry's time span: nothing to write")
        writer.close()
        return report
    finally:
        reader.close()


def write_camera_info_yaml(path: str, ci):
    """A ROS camera_info YAML (what camera_calibration writes), without the mount fields: add
    mount_tilt_deg, mount_yaw_deg, mount_height_m, mount_offset_m for ranges."""
    K = list(getattr(ci, "k", getattr(ci, "K", [])))
    D = list(getattr(ci, "d", getattr(ci, "D", [])))
    fmt = lambda v: "[" + ", ".join(repr(float(x)) for x in v) + "]"  # noqa: E731
    text = (f"image_width: {ci.width}\nimage_height: {ci.height}\ncamera_name: camera\n"
            f"camera_matrix:\n  rows: 3\n  cols: 3\n  data: {fmt(K)}\n"
            f"distortion_model: {ci.distortion_model or 'plumb_bob'}\n"
            f"distortion_coefficients:\n  rows: 1\n  cols: {len(D)}\n  data: {fmt(D)}\n")
    with OutputFile(path, "w") as f:
        f.write(text)


# ---- writing bags (fixtures) ------------------------------------------------------------------

def _default(ts, typename):
    """A message of typename with every field at its zero value (nested messages too)."""
    from rosbags.typesys.store import Nodetype  # type: ignore
    _consts, fields = ts.fielddefs[typename]
    cls = ts.types[typename]
    vals = {}
    base_zero = {"string": "", "bool": False}
    for name, (nt, desc) in fields:
        if nt == Nodetype.NAME:
            vals[name] = _default(ts, desc)
        elif nt == Nodetype.BASE:
            vals[name] = base_zero.get(desc[0], 0 if not desc[0].startswith("float") else 0.0)
        elif nt == Nodetype.ARRAY:
            (snt, sdesc), n = desc
            if snt == Nodetype.BASE and sdesc[0] not in ("string", "bool"):
                vals[name] = np.zeros(n, dtype=_np_type(sdesc[0]))
            else:
                vals[name] = [(_default(ts, sdesc) if snt == Nodetype.NAME else base_zero.get(sdesc[0], 0))
                              for _ in range(n)]
        else:  # SEQUENCE
            (snt, sdesc), _n = desc
            if snt == Nodetype.BASE and sdesc[0] not in ("string", "bool"):
                vals[name] = np.zeros(0, dtype=_np_type(sdesc[0]))
            else:
                vals[name] = []
    return cls(**vals)


def _np_type(t):
    return {"float64": np.float64, "float32": np.float32, "uint8": np.uint8, "int8": np.int8, "byte": np.uint8,
            "char": np.uint8, "uint16": np.uint16, "int16": np.int16, "uint32": np.uint32, "int32": np.int32,
            "uint64": np.uint64, "int64": np.int64}[t]


def _header(ts, t_ns, frame_id):
    h = _default(ts, "std_msgs/msg/Header")
    h.stamp.sec = t_ns // 1_000_000_000
    if hasattr(h.stamp, "nanosec"):
        h.stamp.nanosec = t_ns % 1_000_000_000
    else:
        h.stamp.nsec = t_ns % 1_000_000_000
    h.frame_id = frame_id
    return h


def _set_yaw(q, th):
    q.x, q.y, q.z, q.w = 0.0, 0.0, math.sin(th / 2), math.cos(th / 2)


ENCODING_OF = {"YUYV": "yuv422_yuy2", "UYVY": "yuv422", "NV12": "nv12"}
TF_STATIC_LINK = (0.05, -0.02, 0.1)    # base_footprint -> base_link in write_bag's /tf_static (m, m, rad)


def write_bag(raw: str, out: str, storage: str, camera=None, jpeg: bool = False, classes: Sequence[str] = (),
              jpeg_quality: int = 95, time_offset_ns: int = 1_000_000_000, topics=None,
              tf: bool = False) -> Dict[str, int]:
    """A raw log as a bag: images (sensor_msgs/Image in the log's YUV layout, or CompressedImage
    JPEG), camera_info (from `camera`, a cyl.Camera), the odometry as nav_msgs/Odometry (the pose
    integrated from the increments, each increment's covariance as twist covariance over the frame
    interval), the ground truth as nav_msgs/Odometry and the truth landmarks as a MarkerArray of
    cylinders (namespace = class name). storage: 'mcap', 'sqlite3' (ROS 2) or 'ros1'. Every stamp
    is the log's time plus time_offset_ns (ROS reads a stamp of 0 as "not set", and the synthetic
    scene's logs start at 0). tf=True: the odometry also as /tf (odom -> base_footprint, moving)
    and /tf_static (base_footprint -> base_link, TF_STATIC_LINK), composing to the same pose."""
    from rosbags.typesys import Stores, get_typestore
    topics = topics or {"image": "/camera/image_raw", "info": "/camera/camera_info", "odom": "/odom",
                        "truth": "/ground_truth", "landmarks": "/truth/landmarks"}
    if jpeg:
        topics = dict(topics, image=topics["image"] + "/compressed")
    if storage == "ros1":
        from rosbags.rosbag1 import Writer
        ts = get_typestore(Stores.ROS1_NOETIC)
        if "tf2_msgs/msg/TFMessage" not in ts.types:   # the ROS 1 store lacks tf2_msgs
            from rosbags.typesys import get_types_from_msg
            ts.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage"))
        w = Writer(Path(out))
        ser = ts.serialize_ros1
    elif storage in ("mcap", "sqlite3"):
        from rosbags.rosbag2 import StoragePlugin, Writer
        ts = get_typestore(Stores.ROS2_HUMBLE)
        w = Writer(Path(out), version=9, storage_plugin=StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3)
        ser = ts.serialize_cdr
    else:
        raise RobotLogError(f"storage '{storage}': mcap, sqlite3 or ros1")
    if Path(out).exists():
        raise RobotLogError(f"{out}: exists; a bag is not overwritten")
    counts = {k: 0 for k in topics}
    if tf:
        counts.update(tf=0, tf_static=0)
    with rawlog.Reader(raw) as r:
        info = r.info
        if not jpeg and info.fourcc not in ENCODING_OF:
            raise RobotLogError(f"{raw}: {info.fourcc} frames have no sensor_msgs/Image encoding here (YUYV, UYVY, NV12)")
        img_type = "sensor_msgs/msg/CompressedImage" if jpeg else "sensor_msgs/msg/Image"
        w.open()
        try:
            conn = {"image": w.add_connection(topics["image"], img_type, typestore=ts),
                    "info": w.add_connection(topics["info"], "sensor_msgs/msg/CameraInfo", typestore=ts),
                    "odom": w.add_connection(topics["odom"], "nav_msgs/msg/Odometry", typestore=ts),
                    "truth": w.add_connection(topics["truth"], "nav_msgs/msg/Odometry", typestore=ts),
                    "landmarks": w.add_connection(topics["landmarks"], "visualization_msgs/msg/MarkerArray",
                                                  typestore=ts)}
            if tf:
                conn["tf"] = w.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=ts)
                conn["tf_static"] = w.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=ts)

            def transform(t_ns, parent, child, pose):
                m = _default(ts, "geometry_msgs/msg/TransformStamped")
                m.header, m.child_frame_id = _header(ts, t_ns, parent), child
                m.transform.translation.x, m.transform.translation.y = pose[0], pose[1]
                _set_yaw(m.transform.rotation, pose[2])
                msg = _default(ts, "tf2_msgs/msg/TFMessage")
                msg.transforms.append(m)
                return msg

            def put(key, t_ns, msg, typename):
                w.write(conn[key], t_ns, ser(msg, typename))
                counts[key] += 1

            pose = (0.0, 0.0, 0.0)
            prev_frame_t = None
            frame_t = None
            landmarks = []
            for rec in r:
                rec.t_ns += time_offset_ns
                if rec.type == rawlog.TRUTH_LANDMARK:
                    landmarks.append(rec.truth_landmark())
                elif rec.type == rawlog.FRAME:
                    prev_frame_t, frame_t = frame_t, rec.t_ns
                    if landmarks and counts["landmarks"] == 0:
                        ma = _default(ts, "visualization_msgs/msg/MarkerArray")
                        for lid, cls, x, y, d, h in landmarks:
                            m = _default(ts, "visualization_msgs/msg/Marker")
                            m.header = _header(ts, rec.t_ns, "map")
                            m.ns = classes[cls] if cls < len(classes) and classes[cls] else f"class{cls}"
                            m.id, m.type = lid, 3          # CYLINDER
                            m.pose.position.x, m.pose.position.y = x, y
                            m.pose.orientation.w = 1.0
                            m.scale.x = m.scale.y = d
                            m.scale.z = h
                            ma.markers.append(m)
                        put("landmarks", rec.t_ns, ma, "visualization_msgs/msg/MarkerArray")
                    hdr = _header(ts, rec.t_ns, "camera")
                    if jpeg:
                        from PIL import Image
                        buf = io.BytesIO()
                        Image.fromarray(frame_to_rgb(info.fourcc, info.width, info.height, info.stride,
                                                     rec.payload)).save(buf, "JPEG", quality=jpeg_quality)
                        msg = _default(ts, img_type)
                        msg.header, msg.format = hdr, "jpeg"
                        msg.data = np.frombuffer(buf.getvalue(), np.uint8)
                    else:
                        msg = _default(ts, img_type)
                        msg.header = hdr
                        msg.height, msg.width, msg.step = info.height, info.width, info.stride
                        msg.encoding = ENCODING_OF[info.fourcc]
                        msg.data = np.frombuffer(rec.payload, np.uint8)
                    put("image", rec.t_ns, msg, img_type)
                    if camera is not None:
                        ci = _default(ts, "sensor_msgs/msg/CameraInfo")
                        f = camera.fields()
                        ci.header, ci.width, ci.height, ci.distortion_model = hdr, f["width"], f["height"], "plumb_bob"
                        K = np.array([f["fx_px"], 0, f["cx_px"], 0, f["fy_px"], f["cy_px"], 0, 0, 1], np.float64)
                        D = np.array([f["k1"], f["k2"], f["p1"], f["p2"], f["k3"]], np.float64)
                        P = np.array([f["fx_px"], 0, f["cx_px"], 0, 0, f["fy_px"], f["cy_px"], 0, 0, 0, 1, 0], np.float64)
                        R = np.eye(3).ravel()
                        for a, v in (("k", K), ("d", D), ("p", P), ("r", R)):
                            setattr(ci, a if hasattr(ci, a) else a.upper(), v)
                        put("info", rec.t_ns, ci, "sensor_msgs/msg/CameraInfo")
                elif rec.type == rawlog.ODOMETRY:
                    d, c6 = rec.odometry()
                    pose = compose(pose, d)
                    m = _default(ts, "nav_msgs/msg/Odometry")
                    m.header, m.child_frame_id = _header(ts, rec.t_ns, "odom"), "base_link"
                    m.pose.pose.position.x, m.pose.pose.position.y = pose[0], pose[1]
                    _set_yaw(m.pose.pose.orientation, pose[2])
                    dt = (frame_t - prev_frame_t) * 1e-9 if (prev_frame_t is not None and frame_t == rec.t_ns) else 0.0
                    if dt > 0:
                        tw = np.zeros((6, 6))
                        xx, xy, xt, yy, yt, tt = c6
                        idx = [0, 1, 5]
                        blk = np.array([[xx, xy, xt], [xy, yy, yt], [xt, yt, tt]]) / (dt * dt)
                        tw[np.ix_(idx, idx)] = blk
                        m.twist.twist.linear.x, m.twist.twist.linear.y = d[0] / dt, d[1] / dt
                        m.twist.twist.angular.z = d[2] / dt
                        m.twist.covariance = tw.ravel()
                    put("odom", rec.t_ns, m, "nav_msgs/msg/Odometry")
                    if tf:
                        if counts["tf_static"] == 0:
                            put("tf_static", rec.t_ns, transform(rec.t_ns, "base_footprint", "base_link", TF_STATIC_LINK),
                                "tf2_msgs/msg/TFMessage")
                        foot = compose(pose, between(TF_STATIC_LINK, (0.0, 0.0, 0.0)))
                        put("tf", rec.t_ns, transform(rec.t_ns, "odom", "base_footprint", foot), "tf2_msgs/msg/TFMessage")
                elif rec.type == rawlog.TRUTH_POSE:
                    x, y, th = rec.truth_pose()
                    m = _default(ts, "nav_msgs/msg/Odometry")
                    m.header, m.child_frame_id = _header(ts, rec.t_ns, "map"), "base_link"
                    m.pose.pose.position.x, m.pose.pose.position.y = x, y
                    _set_yaw(m.pose.pose.orientation, th)
                    put("truth", rec.t_ns, m, "nav_msgs/msg/Odometry")
        finally:
            w.close()
    return counts


# ---- CSV odometry -----------------------------------------------------------------------------

CSV_COLUMNS = ("t_s", "x_m", "y_m", "theta_rad")
CSV_COV_COLUMNS = ("cov_vx", "cov_vxvy", "cov_vxwz", "cov_vy", "cov_vywz", "cov_wz")


def read_odometry_csv(path: str) -> PoseTrack:
    """Odometry from a CSV file: a header line naming at least t_s, x_m, y_m, theta_rad (the robot's
    pose in its odometry frame at time t_s, seconds on the camera's clock), and optionally the
    twist covariance upper triangle cov_vx cov_vxvy cov_vxwz cov_vy cov_vywz cov_wz ((m/s)^2,
    m/s rad/s, (rad/s)^2). Lines starting with # are comments."""
    track = PoseTrack(path)
    try:
        f = open(path, newline="")
    except OSError as e:
        raise RobotLogError(f"{path}: cannot open: {e.strerror}") from None
    with f:
        rows = (line for line in f if line.strip() and not line.lstrip().startswith("#"))
        rd = csv.DictReader(rows)
        cols = rd.fieldnames or []
        missing = [c for c in CSV_COLUMNS if c not in cols]
        if missing:
            raise RobotLogError(f"{path}: header lacks {', '.join(missing)} (needs {', '.join(CSV_COLUMNS)}; has "
                                f"{', '.join(cols) or 'nothing'})")
        unknown = [c for c in cols if c not in CSV_COLUMNS + CSV_COV_COLUMNS]
        if unknown:
            raise RobotLogError(f"{path}: unknown column(s) {', '.join(unknown)} (known: "
                                f"{', '.join(CSV_COLUMNS + CSV_COV_COLUMNS)})")
        has_cov = all(c in cols for c in CSV_COV_COLUMNS)
        if any(c in cols for c in CSV_COV_COLUMNS) and not has_cov:
            raise RobotLogError(f"{path}: give all six covariance columns ({', '.join(CSV_COV_COLUMNS)}) or none")
        for n, row in enumerate(rd, 2):
            try:
                t = float(row["t_s"])
                pose = (float(row["x_m"]), float(row["y_m"]), float(row["theta_rad"]))
                cov = None
                if has_cov:
                    xx, xy, xt, yy, yt, tt = (float(row[c]) for c in CSV_COV_COLUMNS)
                    cov = np.array([[xx, xy, xt], [xy, yy, yt], [xt, yt, tt]])
            except (TypeError, ValueError):
                raise RobotLogError(f"{path}: data line {n}: not a number in {dict(row)}") from None
            if not all(math.isfinite(v) for v in (t,) + pose):
                raise RobotLogError(f"{path}: data line {n}: non-finite value")
            track.add(int(round(t * 1e9)), pose, cov, where=f": data line {n}")
    if not track.t_ns:
        raise RobotLogError(f"{path}: no odometry lines")
    return track


def merge_odometry(raw: str, track: PoseTrack, out: str, noise: OdomNoise, max_gap_s: float,
                   bridge_gaps: bool) -> ImportReport:
    """A raw log's frames with odometry records from `track` (any odometry already in the log is
    replaced); truth records are kept."""
    report = ImportReport(source=track.what)
    with rawlog.Reader(raw) as r:
        recs = list(r)
        info = r.info
    frames = [rec for rec in recs if rec.type == rawlog.FRAME]
    if not frames:
        raise RobotLogError(f"{raw}: no frames")
    steps = odometry_records([f.t_ns for f in frames], track, noise, max_gap_s, bridge_gaps, report)
    step_of = {f.seq: s for f, s in zip(frames, steps)}
    with rawlog.Writer(out, info) as w:
        for rec in recs:
            if rec.type == rawlog.ODOMETRY:
                continue
            st = step_of.get(rec.seq) if rec.type != rawlog.TRUTH_LANDMARK else True
            if st is None:
                continue
            w.write(rec.type, rec.seq, rec.t_ns, rec.payload, rec.flags)
            if rec.type == rawlog.FRAME:
                w.write(rawlog.ODOMETRY, rec.seq, rec.t_ns, rawlog.odometry_payload(*st))
                report.frames += 1
    return report


# ---- command line: cyl-robotlog -----------------------------------------------------------------

def _noise(s: Optional[str]) -> OdomNoise:
    if not s:
        return OdomNoise()
    try:
        v = [float(x) for x in s.split(",")]
    except ValueError:
        v = []
    if len(v) != 5 or any(x < 0 for x in v):
        raise SystemExit("cyl-robotlog: --odom-noise TRANS_REL,TRANS_ABS_M,ROT_REL,ROT_PER_M,ROT_ABS_RAD "
                         "(five non-negative numbers)")
    return OdomNoise(*v)


def _progress(quiet: bool):
    if quiet:
        return None
    state = {"last": -1}

    def show(k, n):
        if not n:
            return
        pct = int(100 * k / n)
        if pct == state["last"]:
            return
        state["last"] = pct
        if sys.stderr.isatty():
            bar = "#" * (pct * 30 // 100)
            sys.stderr.write(f"\rimport [{bar:<30}] {k}/{n} frames")
            if k == n:
                sys.stderr.write("\n")
        elif pct % 10 == 0:
            sys.stderr.write(f"import: {pct}% ({k}/{n} frames)\n")
        sys.stderr.flush()
    return show


def main(argv=None) -> int:
    import argparse
    from . import version
    p = argparse.ArgumentParser(
        prog="cyl-robotlog",
        description="Robot logs to and from libcyl raw frame logs (.cylraw): ROS 1 bags, ROS 2 bags "
                    "(sqlite3, MCAP), CSV odometry. Exit 0 on success, 1 when the input cannot be used "
                    "(the message names the file, topic or line), 2 on a bad command line.")
    p.add_argument("--version", action="version", version=f"cyl-robotlog {version()} (libcyl {version()})")
    sp = p.add_subparsers(dest="cmd", required=True)
    a = sp.add_parser("import-bag", help="a bag's images, odometry and ground truth to a raw log")
    a.add_argument("bag", help="ROS 1 .bag file, or ROS 2 bag folder (sqlite3 or MCAP)")
    a.add_argument("-o", "--out", required=True, help="raw log to write (.cylraw)")
    a.add_argument("--image-topic", required=True, help="sensor_msgs/Image (yuv422_yuy2/yuyv, yuv422/uyvy, nv12, "
                   "rgb8, bgr8, mono8) or sensor_msgs/CompressedImage (JPEG)")
    a.add_argument("--odom-topic", help="nav_msgs/Odometry")
    a.add_argument("--tf", metavar="ODOM_FRAME:ROBOT_FRAME", help="odometry from /tf (and /tf_static): the "
                   "chain of transforms from the odometry frame to the robot's, e.g. odom:base_link")
    a.add_argument("--no-odometry", action="store_true", help="import the frames without odometry")
    a.add_argument("--truth-topic", help="ground-truth poses (nav_msgs/Odometry or geometry_msgs/PoseStamped)")
    a.add_argument("--truth-landmarks-topic", help="ground-truth landmarks (visualization_msgs/MarkerArray, "
                   "namespace = class name, scale.x = diameter, scale.z = height)")
    a.add_argument("--classes", default="", help="class names in colour-table order, comma-separated "
                   "(for the truth landmarks' namespaces)")
    a.add_argument("--camera-info-out", help="also write the bag's camera_info as a ROS camera_info YAML")
    a.add_argument("--max-gap", type=float, default=0.5, help="longest odometry gap a frame may fall in, s "
                   "(default %(default)s)")
    a.add_argument("--bridge-gaps", action="store_true", help="interpolate across longer gaps (each reported)")
    a.add_argument("--odom-noise", help="model for steps without twist covariance: TRANS_REL,TRANS_ABS_M,"
                   "ROT_REL,ROT_PER_M,ROT_ABS_RAD (default 0.05,1e-4,0.05,0.02,1e-4)")
    a.add_argument("--max-frames", type=int, default=0)
    a.add_argument("-q", "--quiet", action="store_true")
    b = sp.add_parser("write-bag", help="a raw log as a bag (test fixtures)")
    b.add_argument("raw", help="raw log (.cylraw) with frames, odometry and optionally truth")
    b.add_argument("-o", "--out", required=True, help="bag to write (a .bag file for ros1, a folder for ROS 2)")
    b.add_argument("--storage", choices=["mcap", "sqlite3", "ros1"], default="mcap")
    b.add_argument("--calib", help="calibration file for the camera_info topic (OpenCV or ROS YAML)")
    b.add_argument("--classes", default="orange,green", help="class names for the landmark markers' namespaces "
                   "(default %(default)s)")
    b.add_argument("--jpeg", action="store_true", help="images as sensor_msgs/CompressedImage JPEG")
    b.add_argument("--tf", action="store_true", help="the odometry also as /tf and /tf_static "
                   "(odom -> base_footprint -> base_link)")
    b.add_argument("--jpeg-quality", type=int, default=95)
    b.add_argument("--time-offset", type=float, default=1.0, help="added to every stamp, s (default %(default)s: "
                   "ROS reads a stamp of 0 as unset)")
    o = sp.add_parser("obs-to-mcap", help="an observation log (JSON Lines) as MCAP for Foxglove and the mcap library")
    o.add_argument("log", help="observation log (cyl detect --out)")
    o.add_argument("-o", "--out", required=True, help="MCAP file to write")
    m = sp.add_parser("merge-odom-csv", help="odometry from a CSV file merged into a raw log")
    m.add_argument("raw", help="raw log (.cylraw)")
    m.add_argument("csv", help="CSV odometry: t_s,x_m,y_m,theta_rad[,cov_vx,cov_vxvy,cov_vxwz,cov_vy,cov_vywz,cov_wz]")
    m.add_argument("-o", "--out", required=True)
    m.add_argument("--max-gap", type=float, default=0.5)
    m.add_argument("--bridge-gaps", action="store_true")
    m.add_argument("--odom-noise")
    m.add_argument("-q", "--quiet", action="store_true")
    args = p.parse_args(argv)
    try:
        if args.cmd == "import-bag":
            if sum(map(bool, (args.odom_topic, args.tf, args.no_odometry))) > 1:
                p.error("--odom-topic, --tf and --no-odometry exclude each other")
            tf_frames = None
            if args.tf:
                if args.tf.count(":") != 1 or not all(args.tf.split(":")):
                    p.error("--tf ODOM_FRAME:ROBOT_FRAME (e.g. odom:base_link)")
                tf_frames = tuple(args.tf.split(":"))
            opt = ImportOptions(image_topic=args.image_topic, odom_topic=args.odom_topic, tf_frames=tf_frames,
                                truth_topic=args.truth_topic,
                                truth_landmarks_topic=args.truth_landmarks_topic,
                                classes=[c for c in args.classes.split(",") if c], max_gap_s=args.max_gap,
                                bridge_gaps=args.bridge_gaps, allow_no_odometry=args.no_odometry,
                                noise=_noise(args.odom_noise), max_frames=args.max_frames)
            rep = import_bag(args.bag, args.out, opt, args.camera_info_out, _progress(args.quiet))
            for line in rep.lines():
                print(f"cyl-robotlog: {line}", file=sys.stderr)
            print(f"cyl-robotlog: wrote {args.out}", file=sys.stderr)
        elif args.cmd == "write-bag":
            from . import load_camera
            cam = load_camera(args.calib) if args.calib else None
            counts = write_bag(args.raw, args.out, args.storage, cam, args.jpeg,
                               [c for c in args.classes.split(",")], args.jpeg_quality,
                               int(round(args.time_offset * 1e9)), tf=args.tf)
            print(f"cyl-robotlog: wrote {args.out} ({args.storage}): "
                  + ", ".join(f"{v} {k}" for k, v in counts.items()), file=sys.stderr)
        elif args.cmd == "obs-to-mcap":
            from .obs_mcap import convert
            counts = convert(args.log, args.out)
            print(f"cyl-robotlog: wrote {args.out}: " + ", ".join(f"{v} {k}" for k, v in counts.items() if v),
                  file=sys.stderr)
        else:
            track = read_odometry_csv(args.csv)
            rep = merge_odometry(args.raw, track, args.out, _noise(args.odom_noise), args.max_gap, args.bridge_gaps)
            for line in rep.lines():
                print(f"cyl-robotlog: {line}", file=sys.stderr)
            print(f"cyl-robotlog: wrote {args.out}", file=sys.stderr)
    except (RobotLogError, rawlog.RawLogError, OutputError, ValueError) as e:
        print(f"cyl-robotlog: error: {e}", file=sys.stderr)
        return 1
    except OSError as e:
        print(f"cyl-robotlog: error: {e.filename or args.out}: {e.strerror}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
