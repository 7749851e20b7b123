# SPDX-License-Identifier: BSD-3-Clause
"""Several robots, one map: every robot's odometry chain and observations in one factor graph
whose landmarks (known identities) are shared.

The gauge is the first robot's start pose (its true pose when known, as in the single-robot run);
the other robots' start poses are unknown and carry no prior: the shared landmarks place them.
Initial values: each robot is first mapped alone (`Slam`, its own frame); its map is then
aligned to the map built so far by the 2-D rigid transform that best fits their common landmarks
(least squares, Umeyama without scale), and its trajectory moved with it. A robot that shares fewer
than two landmarks with the map built so far is left out, with a note. One batch
Levenberg-Marquardt pass over the joint graph follows; marginals give the landmark covariances,
and the sparse information matrix the joint NEES.

Metrics: one SE(2) alignment of all robots' poses to truth (the joint frame), then per robot the
RMSE of its positions under that alignment; landmark RMSE under the same alignment; landmark
ANEES (marginal and joint); each robot's joint pose ANEES.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import gtsam
import numpy as np

from .backend import Information, L, Slam, X, Z, _poses, batch_optimize, drop_reason, odom_factors
from .data import between

from . import metrics

ROBOT_STRIDE = 10_000_000   # pose keys of robot k (0-based): X(k * ROBOT_STRIDE + step)


def rigid_fit(src, dst):
    """(R, t) minimising sum |R src + t - dst|^2 over rotations (2-D points, at least 2)."""
    src, dst = np.asarray(src, float), np.asarray(dst, float)
    ms, md = src.mean(0), dst.mean(0)
    U, _, Vt = np.linalg.svd((src - ms).T @ (dst - md))
    D = np.diag([1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
    R = Vt.T @ D @ U.T
    return R, md - R @ ms


def _move(pose, R, t):
    p = R @ pose[:2] + t
    return np.array([p[0], p[1], pose[2] + math.atan2(R[1, 0], R[0, 0])])


@dataclass
class MultiResult:
    robots: list                     # robot labels, in the order of `datasets`
    poses: dict                      # label -> (N, 3)
    lms: dict                        # landmark id -> (x, y)
    lm_cov: dict                     # landmark id -> 2x2
    info: object
    stats: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)


def run_multi(datasets, labels, params, progress=None) -> MultiResult:
    """One map from several robots' data sets: the observations that carry an identity, shared by
    identity (each robot alone is first mapped with known association, or mixed where only some
    observations carry one)."""
    t0 = time.perf_counter()
    notes = []
    singles = []
    for k, ds in enumerate(datasets):
        # identities everywhere (MRCLAM), or where they were read (coded landmarks): gated elsewhere
        p = params.__class__(**{**params.__dict__, "assoc": "known" if ds.known_ids else "mixed",
                                "covariances": False, "anchor": params.anchor if k == 0 else "origin"})
        res = Slam(p, progress=None).run(ds)
        singles.append(res)
        if progress:
            progress(k + 1, len(datasets))
    # initial values: align each robot's own map to the map so far
    ref = {i: res_lm for i, res_lm in zip(singles[0].lm_ids, singles[0].lms) if i is not None}
    init_poses = {0: singles[0].poses}
    for k in range(1, len(datasets)):
        res = singles[k]
        own = {i: p for i, p in zip(res.lm_ids, res.lms) if i is not None}
        common = sorted(set(own) & set(ref))
        if len(common) < 2:
            notes.append(f"{labels[k]}: shares {len(common)} landmark(s) with the map; left out")
            continue
        R, t = rigid_fit([own[i] for i in common], [ref[i] for i in common])
        init_poses[k] = np.array([_move(q, R, t) for q in res.poses])
        for i, p in own.items():
            if i not in ref:
                ref[i] = R @ p + t
    used = sorted(init_poses)
    graph = gtsam.NonlinearFactorGraph()
    values = gtsam.Values()
    slam = Slam(params)
    n_obs = 0
    n_states = 0                # odometry error states (odom_factors)
    for k in used:
        ds = datasets[k]
        base = k * ROBOT_STRIDE
        for i, s in enumerate(ds.steps):
            values.insert(X(base + i), gtsam.Pose2(*init_poses[k][i]))
            if i == 0 and k == used[0]:
                start = (np.array(s.truth, float) if params.anchor == "truth" and s.truth is not None
                         else np.zeros(3))
                graph.add(gtsam.PriorFactorPose2(X(base), gtsam.Pose2(*start),
                                                 gtsam.noiseModel.Diagonal.Sigmas(np.array(params.prior_sigmas))))
            if i > 0:
                fs, vs = odom_factors(s, X(base + i - 1), X(base + i), Z(base + i - 1), Z(base + i),
                                      ds.steps[i - 1].odom_gm is not None)
                for f in fs:
                    graph.add(f)
                for key, v in vs:
                    values.insert(key, v)
                    n_states += 1
            for o in s.obs:
                # the single-robot runs' rule; a landmark only those runs' dropped observations saw
                # has no estimate, and its observations stay out too
                if drop_reason(o, params) or o.lm_id is None or o.lm_id not in ref:
                    continue
                graph.add(slam._plain_factor(base + i, o.lm_id, o, o.cov))
                n_obs += 1
    for i, p in ref.items():
        values.insert(L(i), gtsam.Point2(*p))
    t_init = time.perf_counter() - t0
    est, iterations = batch_optimize(graph, values, python_loop=n_states > 0)
    marg = gtsam.Marginals(graph, est)
    poses = {labels[k]: _poses(est, len(datasets[k].steps), k * ROBOT_STRIDE) for k in used}
    lms = {i: np.array(est.atPoint2(L(i))) for i in ref}
    lm_cov = {i: marg.marginalCovariance(L(i)) for i in ref}
    stats = {"robots_used": [labels[k] for k in used], "observations_used": n_obs,
             "poses": sum(len(datasets[k].steps) for k in used), "landmarks": len(ref),
             "batch_iterations": iterations, "final_error": graph.error(est),
             "t_init_s": round(t_init, 3), "t_total_s": round(time.perf_counter() - t0, 3)}
    return MultiResult(robots=[labels[k] for k in used], poses=poses, lms=lms, lm_cov=lm_cov,
                       info=Information(graph, est), stats=stats, notes=notes)


def evaluate_multi(datasets, labels, res: MultiResult):
    """Joint-frame metrics (see the module text)."""
    idx = {lab: [i for i, s in enumerate(ds.steps) if s.truth is not None] for ds, lab in zip(datasets, labels)}
    by = dict(zip(labels, datasets))
    est = np.vstack([res.poses[lab][idx[lab]] for lab in res.robots])
    tru = np.vstack([np.array([by[lab].steps[i].truth for i in idx[lab]]) for lab in res.robots])
    _, joint_rmse, (R, t, ang) = metrics.ate(est, tru)
    out = {"joint_aligned_rmse_m": joint_rmse, "align_rotation_rad": ang, "robots": {}}
    for lab in res.robots:
        e = res.poses[lab][idx[lab]]
        tr = np.array([by[lab].steps[i].truth for i in idx[lab]])
        al = e[:, :2] @ R.T + t
        kk = labels.index(lab)
        errs = np.concatenate([between(e[j], tr[j]) for j in range(len(e))])
        keys = [X(kk * ROBOT_STRIDE + i) for i in idx[lab]]
        out["robots"][str(lab)] = {
            "aligned_rmse_joint_frame_m": metrics.rmse(al, tr),
            "unaligned_rmse_m": metrics.rmse(e, tr),
            "own_aligned_rmse_m": metrics.ate(e, tr)[1],
            "anees_poses_joint": res.info.nees(keys, errs) / len(errs)}
    tl = datasets[0].truth_landmarks
    ids = sorted(i for i in res.lms if i in tl)
    if ids:
        E = np.array([res.lms[i] for i in ids])
        T = np.array([tl[i][:2] for i in ids], float)
        out["landmark_rmse_m"] = metrics.rmse(E, T)
        out["landmark_rmse_aligned_m"] = metrics.rmse(E @ R.T + t, T)
        a, bnd = metrics.anees(list(E - T), [res.lm_cov[i] for i in ids])
        out["anees_landmarks"] = a
        out["anees_landmarks_bounds95"] = list(bnd)
        ej = (E - T).reshape(-1)
        out["anees_landmarks_joint"] = res.info.nees([L(i) for i in ids], ej) / len(ej)
        out["anees_landmarks_joint_bounds95"] = list(metrics.anees_bounds(len(ej), 1))
        out["landmarks_estimated"] = len(res.lms)
    return out
