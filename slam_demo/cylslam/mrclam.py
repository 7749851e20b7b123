# SPDX-License-Identifier: BSD-3-Clause
"""Reader of one robot of the UTIAS MRCLAM data set (Leung, Halpern, Barfoot, Liu, IJRR 2011).

Files (4 '#' header lines, whitespace-separated columns): Barcodes.dat (subject, barcode),
Landmark_Groundtruth.dat (subject, x, y, sd_x, sd_y), RobotN_Odometry.dat (t, v, w),
RobotN_Measurement.dat (t, barcode, range, bearing), RobotN_Groundtruth.dat (t, x, y, theta).

- Odometry: the velocity commands (v, w) are held from their time stamp to the next one and
  integrated exactly (circular arcs) into a dead-reckoning pose at any time; the increment
  between two steps is DR(t_a)^-1 DR(t_b).
- Steps: one per measurement time stamp (measurements less than `merge_dt` = 50 ms after a step
  join it: the robot moves < 1.5 cm in that time, well under the range noise), and keyframes so
  that no two consecutive steps are more than `keyframe_dt` (0.5 s) apart. The run
  starts at the first odometry command; measurements before it are dropped (counted).
- Barcodes are mapped to subjects with Barcodes.dat; subjects 1-5 (robots) and barcodes not in
  the file are dropped (counted). Landmarks are subjects 6-20, class "barcode".
- Ground truth (Vicon) is interpolated linearly (angles unwrapped) at each step; steps farther
  than `max_gap` (0.25 s) from a Vicon sample on either side of a gap get no truth.

With a learned noise model (`model`, noise_model.py) the commands are first shifted by its command
delay and scaled by its speed and turn scales; its sigmas then replace the models below, each
measurement's and step's variance multiplied by its stream's correlation sum. With
`odom_corr="state"` (the default) each step also carries its error split into a white part and the
Gauss-Markov states of the odometry's correlation (Step.odom_gm), which the batch solution uses in
place of the inflated step covariance (backend.odom_factors).

Noise models (documented in README):
- odometry increment of distance d and rotation a (both of the commanded motion) over dt s:
  sigma_x = 0.05 d + 0.002 sqrt(dt), sigma_y = 0.02 d + 0.002 sqrt(dt),
  sigma_theta = 0.08 |a| + 0.1 d + 0.005 sqrt(dt)   (independent; m, rad; floors 1e-3 m / rad),
  all multiplied by `odom_scale` (default 1; 4 is used for unknown association, see README)
- measurements, `noise="range"` (default): sigma_r = 0.03 r + 0.02 m, sigma_b = 0.01 rad
  (range-dependent, the reference model of datasets.md); `noise="fixed"`: sigma_r = 0.1 m,
  sigma_b = 0.01 rad for every measurement.
"""
from __future__ import annotations

import math
import os

import numpy as np

from .data import Dataset, Obs, Step, between, wrap

ROBOT_SUBJECTS = range(1, 6)


class MrclamError(Exception):
    pass


def _load(path, ncols):
    try:
        a = np.loadtxt(path, comments="#", ndmin=2)
    except (OSError, ValueError) as e:
        raise MrclamError(f"{path}: {e}")
    if a.shape[1] < ncols:
        raise MrclamError(f"{path}: expected {ncols} columns, found {a.shape[1]}")
    return a[:, :ncols]


def integrate(odo):
    """Dead-reckoning poses at the command times of odo (t, v, w), starting at (0, 0, 0)."""
    t, v, w = odo[:, 0], odo[:, 1], odo[:, 2]
    dt = np.diff(t)
    n = len(t)
    P = np.zeros((n, 3))
    th = np.concatenate([[0.0], np.cumsum(w[:-1] * dt)])
    for k in range(n - 1):
        P[k + 1] = _arc(P[k], v[k], w[k], dt[k])
    P[:, 2] = th  # identical up to wrapping; keep unwrapped heading
    return P


def _arc(p, v, w, dt):
    th = p[2]
    if abs(w) < 1e-9:
        return np.array([p[0] + v * dt * math.cos(th), p[1] + v * dt * math.sin(th), th])
    th2 = th + w * dt
    return np.array([p[0] + v / w * (math.sin(th2) - math.sin(th)),
                     p[1] - v / w * (math.cos(th2) - math.cos(th)), th2])


def dr_at(odo, P, tq):
    """Dead-reckoning pose at query times tq (sorted)."""
    k = np.searchsorted(odo[:, 0], tq, side="right") - 1
    k = np.clip(k, 0, len(odo) - 1)
    out = np.empty((len(tq), 3))
    for q, (kk, t) in enumerate(zip(k, tq)):
        out[q] = _arc(P[kk], odo[kk, 1], odo[kk, 2], t - odo[kk, 0])
    return out


SIGMA_FLOOR = (1e-3, 1e-3)   # m, rad: no increment is trusted more than this
ODOM_K = dict(x_d=0.05, x_t=0.002, y_d=0.02, y_t=0.002, th_a=0.08, th_d=0.1, th_t=0.005)


def odom_sigmas(d, dt, k=None):
    k = k or ODOM_K
    dist = math.hypot(d[0], d[1])
    a = abs(d[2])
    sq = math.sqrt(max(dt, 0.0))
    return (max(k["x_d"] * dist + k["x_t"] * sq, SIGMA_FLOOR[0]),
            max(k["y_d"] * dist + k["y_t"] * sq, SIGMA_FLOOR[0]),
            max(k["th_a"] * a + k["th_d"] * dist + k["th_t"] * sq, SIGMA_FLOOR[1]))


def meas_cov(r, noise):
    if noise == "range":
        sr = 0.03 * r + 0.02
    elif noise == "fixed":
        sr = 0.1
    else:
        raise ValueError(f"unknown noise model {noise!r}")
    sb = 0.01
    return np.diag([sr * sr, sb * sb])


def interp_truth(gt, tq, max_gap=0.25):
    """Linear interpolation of (t, x, y, theta) at tq; NaN rows where the data has a gap."""
    t = gt[:, 0]
    th = np.unwrap(gt[:, 3])
    x = np.interp(tq, t, gt[:, 1])
    y = np.interp(tq, t, gt[:, 2])
    a = np.interp(tq, t, th)
    k = np.searchsorted(t, tq)
    ok = (k > 0) & (k < len(t))
    kk = np.clip(k, 1, len(t) - 1)
    near = np.minimum(np.abs(tq - t[kk - 1]), np.abs(t[kk] - tq))
    ok &= near <= max_gap
    out = np.stack([x, y, wrap(a)], 1)
    out[~ok] = np.nan
    return out


def read_mrclam(directory, robot, duration=None, keyframe_dt=0.5, noise="range",
                max_gap=0.25, merge_dt=0.05, odom_scale=1.0, model=None, odom_corr="state") -> Dataset:
    """`model`: a noise_model.NoiseModel for the measurement and odometry covariances (then
    `noise` is not used), or None for the fixed models of the module text. `odom_corr`: how a
    model's odometry correlation in time is used: "state" (each step's error split into a white
    part and a Gauss-Markov state shared by neighbouring steps, Step.odom_gm) or "inflate" (each
    step's variance multiplied by its correlation sum, NoiseModel.odom_inflation)."""
    if odom_corr not in ("state", "inflate"):
        raise ValueError(f"unknown odometry correlation use {odom_corr!r}")
    d = directory
    for f in ("Barcodes.dat", "Landmark_Groundtruth.dat", f"Robot{robot}_Odometry.dat",
              f"Robot{robot}_Measurement.dat", f"Robot{robot}_Groundtruth.dat"):
        if not os.path.isfile(os.path.join(d, f)):
            raise MrclamError(f"{os.path.join(d, f)}: no such file")
    bc = _load(os.path.join(d, "Barcodes.dat"), 2).astype(int)
    barcode_to_subject = {int(b): int(s) for s, b in bc}
    lmgt = _load(os.path.join(d, "Landmark_Groundtruth.dat"), 3)
    odo = _load(os.path.join(d, f"Robot{robot}_Odometry.dat"), 3)
    meas = _load(os.path.join(d, f"Robot{robot}_Measurement.dat"), 4)
    gt = _load(os.path.join(d, f"Robot{robot}_Groundtruth.dat"), 4)
    odo = odo[np.argsort(odo[:, 0], kind="stable")]
    if model is not None and (model.cmd_scale != (1.0, 1.0) or model.cmd_delay_s != 0.0):
        # the robots act on a command some time after its stamp and move and turn less than
        # commanded (noise_model.py)
        odo = odo.copy()
        odo[:, 0] += model.cmd_delay_s
        odo[:, 1] *= model.cmd_scale[0]
        odo[:, 2] *= model.cmd_scale[1]
    t0 = odo[0, 0]
    t_end = odo[-1, 0] if duration is None else min(odo[-1, 0], t0 + duration)
    notes = []
    n_robot = n_unknown = n_before = n_after = 0
    keep = []
    for t, b, r, br in meas:
        s = barcode_to_subject.get(int(b))
        if s is None:
            n_unknown += 1
        elif s in ROBOT_SUBJECTS:
            n_robot += 1
        elif t < t0:
            n_before += 1
        elif t > t_end:
            n_after += 1
        else:
            keep.append((t, s, r, br))
    notes.append(f"robot {robot}: {len(meas)} measurements; dropped {n_robot} of other robots, "
                 f"{n_unknown} of unknown barcodes, {n_before} before the first odometry"
                 + (f", {n_after} after the end of the excerpt" if n_after else ""))
    mt = sorted({m[0] for m in keep})
    # step times: t0, measurement times (those within merge_dt of the previous step join it),
    # and fillers so that no gap exceeds keyframe_dt
    times = [t0]
    step_of = {}
    for t in mt + [t_end]:
        while t - times[-1] > keyframe_dt + 1e-9:
            times.append(times[-1] + keyframe_dt)
        if t - times[-1] >= merge_dt:
            times.append(t)
        step_of[t] = len(times) - 1
    times = np.array(times)
    P = integrate(odo)
    dr = dr_at(odo, P, times)
    truth = interp_truth(gt, times, max_gap)
    n_no_truth = int(np.isnan(truth[:, 0]).sum())
    if n_no_truth:
        notes.append(f"{n_no_truth} of {len(times)} steps have no ground truth (Vicon gaps)")
    gm = model is not None and model.odom_corr is not None and odom_corr == "state"
    if gm:
        # one state per exponential of the fitted correlation (a second only where a2 > 0)
        comps = ("x", "y", "theta")
        terms = [("a1", "tau1_s")] + ([("a2", "tau2_s")] if any(model.odom_corr[c]["a2"] > 0 for c in comps) else [])
        a = np.concatenate([[model.odom_corr[c][ka] for c in comps] for ka, _ in terms])
        tau = np.concatenate([[model.odom_corr[c][kt] for c in comps] for _, kt in terms])
        a_sum = a.reshape(-1, 3).sum(0)
    oinfl = (model.odom_inflation(times) if model is not None and model.odom_corr is not None
             else np.ones((len(times), 3)))
    steps = []
    for k, t in enumerate(times):
        s = Step(t=float(t), seq=k, truth=None if np.isnan(truth[k, 0]) else truth[k])
        if k > 0:
            inc = between(dr[k - 1], dr[k])
            if model is not None:
                cov = odom_scale ** 2 * model.odom_cov(inc, t - times[k - 1])
                s.odom_cov = cov * oinfl[k]
                if gm:
                    # the batch's model (backend.odom_factors); the inflated odom_cov is iSAM2's online
                    var = np.diag(cov)
                    s.odom_gm = (np.diag((1.0 - a_sum) * var), np.sqrt(a * np.tile(var, len(terms))),
                                 np.exp(-(t - times[k - 1]) / tau) if k > 1 else np.zeros(len(a)))
            else:
                sx, sy, st = (odom_scale * v for v in odom_sigmas(inc, t - times[k - 1]))
                s.odom_cov = np.diag([sx * sx, sy * sy, st * st])
            s.odom = inc
        steps.append(s)
    # a learned model's errors are correlated in time along one landmark's measurements: each
    # measurement's variance is multiplied by the sum of its correlations (noise_model.py)
    infl = np.ones((len(keep), 2))
    if model is not None and model.corr is not None:
        by_lm = {}
        for n_line, (t, s, r, br) in enumerate(keep):
            by_lm.setdefault(s, []).append(n_line)
        for idx in by_lm.values():
            infl[idx] = model.inflation([keep[i][0] for i in idx])
    for n_line, (t, s, r, br) in enumerate(keep):
        steps[step_of[t]].obs.append(Obs(cls="barcode", range_m=float(r), bearing_rad=float(br),
                                     cov=model.meas_cov(r, infl[n_line]) if model is not None else meas_cov(r, noise),
                                     lm_id=int(s),
                                     where=f"Robot{robot}_Measurement.dat t={t:.3f}"))
    tl = {int(s): (float(x), float(y), "barcode") for s, x, y in lmgt}
    ds = Dataset(name=f"MRCLAM Dataset robot {robot}", steps=steps, truth_landmarks=tl,
                 classes=["barcode"], notes=notes, known_ids=True)
    ds.duration_s = float(t_end - t0)
    return ds


def write_excerpt(src, dst, robot, seconds):
    """Copy the first `seconds` of one robot (from its first odometry command, ground truth
    from `seconds`+... with 15 s of margin before) plus Barcodes and Landmark_Groundtruth."""
    os.makedirs(dst, exist_ok=True)
    odo = _load(os.path.join(src, f"Robot{robot}_Odometry.dat"), 3)
    t0 = odo[:, 0].min()
    t1 = t0 + seconds
    for name in ("Barcodes.dat", "Landmark_Groundtruth.dat"):
        with open(os.path.join(src, name)) as fi, open(os.path.join(dst, name), "w") as fo:
            fo.write(fi.read())
    for kind, lo in (("Odometry", t0), ("Measurement", t0 - 15), ("Groundtruth", t0 - 15)):
        name = f"Robot{robot}_{kind}.dat"
        with open(os.path.join(src, name)) as fi, open(os.path.join(dst, name), "w") as fo:
            for line in fi:
                if line.startswith("#"):
                    fo.write(line)
                    continue
                parts = line.split()
                if parts and lo <= float(parts[0]) <= t1 + 1.0:
                    fo.write(line)
