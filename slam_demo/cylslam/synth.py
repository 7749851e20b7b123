# SPDX-License-Identifier: BSD-3-Clause
"""Synthetic observation logs in the docs/formats.md format, with ground truth.

Stand-in for the renderer + frontend until real logs exist. Everything is drawn from documented
models with a seeded generator, so a given (seed, options) always writes the same file.

Scene: `n_landmarks` cylinders in `len(classes)` colours on a jittered grid over a 10 m x 8 m
field, same-colour landmarks at least `min_sep` apart. The robot drives a figure-eight
(x = A sin(w t), y = B sin(2 w t)) at ~0.3 m/s, one frame every `dt` seconds.

Camera (the covariance varies with range, as a ground-plane camera's does): horizontal field of
view +-35 deg, ranges 0.4-5 m, detection probability 0.9. Per observation, with r the true range,
    sigma_r = 0.004 r^2 (pixel noise, dr/dv = r^2/(f h)) (+) 0.008 r^2 (tilt) (+) 0.003 m
    sigma_b = 0.0012 rad (pixel) (+) 0.002 rad (yaw)            [(+): root sum of squares]
    rho(r, b) = 0.3 sin(b)  (range/bearing correlation; off-axis blobs couple the two)
and the reported (range, bearing) = truth + a draw from N(0, that covariance). Every observation is
drawn independently (a real camera's calibration error is constant over a run: see README).
Confidence 0.75-0.97 for landmarks. Clutter: with probability `clutter` per frame, one false
detection of a random class at a random place in view, confidence 0.05-0.35. With probability
0.02 a landmark observation is cut by the image border (flags 0x20) and its range is biased by
+30 %: the back end must drop it by its flags.

Odometry per frame, with d the distance and a the rotation of the true increment:
    sigma_x = 0.05 d + 1e-4,  sigma_y = 0.02 d + 1e-4,  sigma_theta = 0.05 |a| + 0.15 d + 1e-4
(independent), the measured increment = truth + a draw, the covariance written to the log.
"""
from __future__ import annotations

import numpy as np

from .data import between, compose, rb_to_world, wrap
from .obslog import ObsLogWriter

FOV = np.deg2rad(35.0)
R_MIN, R_MAX = 0.4, 5.0


def place_landmarks(rng, n, classes, min_sep=1.6, field=(10.0, 8.0)):
    """Jittered-grid landmarks with same-class separation >= min_sep (deterministic per rng)."""
    out = []
    tries = 0
    while len(out) < n:
        tries += 1
        if tries > 100000:
            raise RuntimeError("cannot place landmarks")
        x = rng.uniform(-field[0] / 2, field[0] / 2)
        y = rng.uniform(-field[1] / 2, field[1] / 2)
        cls = len(out) % len(classes)
        # keep off the robot's path (|y - B sin(2 asin(x/A))| > 0.5 is approximated by a check
        # against a dense sampling of the path)
        if _near_path(x, y, 0.6):
            continue
        ok = all(np.hypot(x - p[0], y - p[1]) >= (min_sep if c == cls else 0.5)
                 for p in out for c in [p[2]])
        if ok:
            out.append((x, y, cls))
    return out


_A, _B = 3.6, 2.4


def _path(t, period):
    w = 2 * np.pi / period
    x = _A * np.sin(w * t)
    y = _B * np.sin(2 * w * t)
    dx = _A * w * np.cos(w * t)
    dy = 2 * _B * w * np.cos(2 * w * t)
    return np.array([x, y, np.arctan2(dy, dx)])


def _near_path(x, y, d):
    s = np.linspace(0, 1, 400)
    xs = _A * np.sin(2 * np.pi * s)
    ys = _B * np.sin(4 * np.pi * s)
    return np.min(np.hypot(xs - x, ys - y)) < d


def obs_cov(r, b):
    """Camera-like (range, bearing) covariance at range r, bearing b (see module doc)."""
    sr = np.sqrt((0.004 * r * r) ** 2 + (0.008 * r * r) ** 2 + 0.003 ** 2)
    sb = np.sqrt(0.0012 ** 2 + 0.002 ** 2)
    rho = 0.3 * np.sin(b)
    return np.array([[sr * sr, rho * sr * sb], [rho * sr * sb, sb * sb]])


def odom_cov(d):
    dist = np.hypot(d[0], d[1])
    sx = 0.05 * dist + 1e-4
    sy = 0.02 * dist + 1e-4
    st = 0.05 * abs(d[2]) + 0.15 * dist + 1e-4
    return np.diag([sx * sx, sy * sy, st * st])


def _xy_cov(r, b, cov):
    J = np.array([[np.cos(b), -r * np.sin(b)], [np.sin(b), r * np.cos(b)]])
    return J @ cov @ J.T


def generate(path, frames=1200, seed=7, n_landmarks=16, classes=("orange", "green"), dt=0.1,
             clutter=0.15, speed=0.3):
    """Write a synthetic log to `path`; returns a small dict describing it."""
    rng = np.random.default_rng(seed)
    lms = place_landmarks(rng, n_landmarks, classes)
    s = np.linspace(0, 1, 2000)
    per_len = np.sum(np.hypot(np.diff(_A * np.sin(2 * np.pi * s)), np.diff(_B * np.sin(4 * np.pi * s))))
    period = per_len / speed
    n_obs = n_clutter = n_cut = 0
    with ObsLogWriter(path, source=f"cylslam synth seed {seed}", classes=classes) as w:
        for i, (x, y, c) in enumerate(lms):
            w.truth_landmark(i, classes[c], c, float(x), float(y))
        prev_true = None
        for k in range(frames):
            t = k * dt
            pose = _path(t, period)
            obs = []
            for (lx, ly, c) in lms:
                d = between(pose, np.array([lx, ly, 0.0]))
                r = float(np.hypot(d[0], d[1]))
                b = float(np.arctan2(d[1], d[0]))
                if not (R_MIN <= r <= R_MAX and abs(b) <= FOV) or rng.random() > 0.9:
                    continue
                cov = obs_cov(r, b)
                z = np.array([r, b]) + np.linalg.cholesky(cov) @ rng.standard_normal(2)
                flags = 0
                if rng.random() < 0.02:
                    flags = 0x20
                    z[0] *= 1.3
                    n_cut += 1
                obs.append(_obs_rec(classes[c], c, z[0], z[1], cov,
                                    float(rng.uniform(0.75, 0.97)), flags))
                n_obs += 1
            if rng.random() < clutter:
                c = int(rng.integers(len(classes)))
                r = float(rng.uniform(R_MIN, R_MAX))
                b = float(rng.uniform(-FOV, FOV))
                obs.append(_obs_rec(classes[c], c, r, b, obs_cov(r, b),
                                    float(rng.uniform(0.05, 0.35)), 0))
                n_clutter += 1
            rng.shuffle(obs)
            odom = None
            if prev_true is not None:
                d_true = between(prev_true, pose)
                C = odom_cov(d_true)
                d_meas = d_true + np.sqrt(np.diag(C)) * rng.standard_normal(3)
                d_meas[2] = wrap(d_meas[2])
                odom = ([float(v) for v in d_meas], C.tolist())
            w.frame(k, round(t, 6), obs, odom=odom, truth=[float(v) for v in pose])
            prev_true = pose
    return dict(frames=frames, landmarks=len(lms), observations=n_obs, clutter=n_clutter,
                cut=n_cut, seed=seed)


def _obs_rec(cls, cid, r, b, cov, conf, flags):
    cxy = _xy_cov(r, b, cov)
    return {"class": cls, "class_id": cid, "range_m": float(r), "bearing_rad": float(b),
            "cov_rr": float(cov[0, 0]), "cov_rb": float(cov[0, 1]), "cov_bb": float(cov[1, 1]),
            "x_m": float(r * np.cos(b)), "y_m": float(r * np.sin(b)),
            "cov_xx": float(cxy[0, 0]), "cov_xy": float(cxy[0, 1]), "cov_yy": float(cxy[1, 1]),
            "confidence": round(conf, 3), "flags": flags}


__all__ = ["generate", "obs_cov", "odom_cov", "rb_to_world", "compose"]
