# SPDX-License-Identifier: BSD-3-Clause
"""The common in-memory model every reader produces and the back end consumes.

A data set is a list of steps (one robot pose each). Step 0 is the start pose; every later step
carries the odometry increment from the previous step (a BetweenFactor<Pose2> measurement: the
motion expressed in the previous pose's frame) and its 3x3 covariance in (x, y, theta). Each step
carries the observations taken at that pose. Range/bearing covariances are always stored in
(range, bearing) order, as in docs/formats.md; the back end permutes them for GTSAM.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np

# obs.flags bits (docs/formats.md): a back end uses observations with flags & 0xB20 == 0
FLAG_MERGED = 0x10
FLAG_CUT = 0x20
FLAG_NO_RANGE = 0x100
FLAG_INVALID = 0x200
FLAG_NONLINEAR = 0x400
FLAG_PARTIAL = 0x800      # a side of the landmark hidden: its centroid (bearing too) is off
FLAGS_REJECT = 0xB20


@dataclass
class Obs:
    cls: str                      # class name (colour); all MRCLAM landmarks are "barcode"
    range_m: float
    bearing_rad: float
    cov: np.ndarray               # 2x2 covariance of (range, bearing): m^2, m rad, rad^2
    confidence: float = 1.0
    flags: int = 0
    lm_id: Optional[int] = None   # known identity (MRCLAM subject, Victoria Park id), else None
    where: str = ""               # "file:line" for messages
    jac_calib: Optional[np.ndarray] = None   # 2x8 d(range, bearing)/d(fx fy cx cy tilt yaw h s), or None
    cov_frame: Optional[np.ndarray] = None   # 2x2 frame-to-frame covariance (no calibration), or None
    bias_var_px2: Optional[np.ndarray] = None   # (u, v) variance of the centroid's residual bias, px^2,
                                  # a part of cov_frame that does not change from frame to frame
    u_px: Optional[float] = None  # the measured point range and bearing were computed from, px
    v_px: Optional[float] = None  # (the camera model's input; None when the source has no pixel)
    grouped: bool = False         # a landmark of several bands grouped by the frontend (the log's
                                  # landmark_model): its blob is merged by design, not by noise


@dataclass
class Step:
    t: float
    seq: int
    odom: Optional[np.ndarray] = None       # (dx, dy, dtheta) from previous step, None for step 0
    odom_cov: Optional[np.ndarray] = None   # 3x3
    # the step's time-correlated odometry error as a state (backend.odom_factors), or None:
    # (white, sd, phi): white the 3x3 covariance of the uncorrelated part; sd (3 m,) m, m, rad the
    # standard deviations in x, y, theta of the m correlated terms, one after the other; phi (3 m,)
    # each term's correlation with the previous step's (exp(-dt / tau), 0 at the first step).
    # odom_cov stays the whole error's covariance, inflated by its correlation sum: what an online
    # solver (iSAM2) uses
    odom_gm: Optional[tuple] = None
    obs: list = field(default_factory=list)
    truth: Optional[np.ndarray] = None      # true (x, y, theta) or None


@dataclass
class Dataset:
    name: str
    steps: list
    truth_landmarks: dict = field(default_factory=dict)   # id -> (x, y, cls)
    classes: list = field(default_factory=list)
    notes: list = field(default_factory=list)             # reader remarks (drops, skips, ...)
    known_ids: bool = False                               # observations carry identities

    def n_obs(self) -> int:
        return sum(len(s.obs) for s in self.steps)

    def has_truth(self) -> bool:
        return any(s.truth is not None for s in self.steps)


def wrap(a):
    """Wrap angle(s) to (-pi, pi]."""
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def compose(p, d):
    """SE(2) composition p (+) d for (x, y, theta) triples."""
    c, s = np.cos(p[2]), np.sin(p[2])
    return np.array([p[0] + c * d[0] - s * d[1], p[1] + s * d[0] + c * d[1], wrap(p[2] + d[2])])


def between(a, b):
    """SE(2) a^-1 (+) b: b expressed in a's frame."""
    c, s = np.cos(a[2]), np.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return np.array([c * dx + s * dy, -s * dx + c * dy, wrap(b[2] - a[2])])


def rb_to_world(pose, r, b):
    """World position of a (range, bearing) observation taken at pose."""
    return np.array([pose[0] + r * np.cos(pose[2] + b), pose[1] + r * np.sin(pose[2] + b)])
