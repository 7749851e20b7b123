# SPDX-License-Identifier: BSD-3-Clause
"""Metrics against ground truth.

- Position RMSE (ATE): sqrt(mean |p_est - p_true|^2) over the poses that have truth, in the
  world frame ("unaligned") and after the least-squares SE(2) alignment of the estimated
  positions onto the true ones ("aligned": R, t minimising sum |R p_est + t - p_true|^2, closed
  form: t from the centroids, the angle atan2(sum cross, sum dot) of the centred point pairs).
  `ate_m` is the aligned one.
- Landmark RMSE: over estimated landmarks matched to a true landmark, in the world frame.
- NEES of a landmark: e^T P^-1 e with e = estimate - truth (world frame) and P its marginal
  covariance; of a pose: xi^T P^-1 xi with xi = (est^-1 truth) in the pose's body frame
  (GTSAM's tangent convention of the marginals). ANEES = mean NEES / dimension, so a consistent
  estimator gives 1; its two-sided 95 % bounds are chi2_{N d}(0.025)/(N d) and
  chi2_{N d}(0.975)/(N d) for N estimates of dimension d (Wilson-Hilferty approximation).
- Joint NEES: the poses of one trajectory are strongly correlated (each carries every earlier
  odometry error), and the landmarks share the poses and the calibration; the mean of their
  marginal NEES then spreads far wider than the chi-square bounds above, which assume independent
  estimates (a consistent run can sit at 0.4). The joint NEES whitens the stacked errors with the
  joint covariance, e^T Sigma^-1 e, which for a consistent Gaussian estimator is chi-square with
  N d degrees of freedom however correlated the estimates are; `anees_*_joint` is it divided by
  N d, with the same bounds. Both are reported.
- Association: each used observation gets a true label: the true landmark of its class whose
  (range, bearing) from the true pose is nearest the measured one in the observation's own
  covariance (Mahalanobis), or "clutter" if that distance is beyond the 99.99% gate of 2 dof and
  the landmark is more than 0.5 m from the observation's true world position. A one-to-one matching of estimated to true landmarks
  maximising the number of agreeing observations (Hungarian on the contingency table) defines
  which estimated landmark *is* which true landmark; association errors = used observations not
  on a matched (estimated, true) pair: wrong landmark, a landmark split in two, clutter used.
  With known identities the label is the identity and the matching is by identity.
"""
from __future__ import annotations

import math

import numpy as np

from .backend import hungarian
from .data import between, rb_to_world, wrap

Z975 = 1.959963984540054


def chi2_ppf_wh(p_z, k):
    """Wilson-Hilferty chi-square quantile for standard normal quantile p_z, k dof."""
    a = 2.0 / (9.0 * k)
    return k * (1.0 - a + p_z * math.sqrt(a)) ** 3


def anees_bounds(n, d):
    k = n * d
    if k <= 0:
        return (float("nan"), float("nan"))
    return (chi2_ppf_wh(-Z975, k) / k, chi2_ppf_wh(Z975, k) / k)


def align_se2(est, truth):
    """SE(2) (R, t, angle) minimising sum |R est_i + t - truth_i|^2 over (N, 2) arrays."""
    est = np.asarray(est, float)[:, :2]
    truth = np.asarray(truth, float)[:, :2]
    me, mt = est.mean(0), truth.mean(0)
    a, b = est - me, truth - mt
    dot = np.sum(a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1])
    cross = np.sum(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
    ang = math.atan2(cross, dot)
    R = np.array([[math.cos(ang), -math.sin(ang)], [math.sin(ang), math.cos(ang)]])
    t = mt - R @ me
    return R, t, ang


def rmse(est, truth):
    e = np.asarray(est, float)[:, :2] - np.asarray(truth, float)[:, :2]
    return float(math.sqrt(np.mean(np.sum(e * e, axis=1)))) if len(e) else float("nan")


def ate(est, truth):
    """(unaligned RMSE, aligned RMSE, (R, t, angle))."""
    R, t, ang = align_se2(est, truth)
    al = (np.asarray(est, float)[:, :2] @ R.T) + t
    return rmse(est, truth), rmse(al, truth), (R, t, ang)


def nees(err, cov):
    err = np.asarray(err, float)
    return float(err @ np.linalg.solve(np.asarray(cov, float), err))


def anees(errs, covs):
    """ANEES (normalised by dimension) and its two-sided 95 % bounds."""
    if len(errs) == 0:
        return float("nan"), (float("nan"), float("nan"))
    d = len(errs[0])
    vals = [nees(e, c) for e, c in zip(errs, covs)]
    return float(np.mean(vals)) / d, anees_bounds(len(vals), d)


def anees_joint(err, cov):
    """Joint ANEES e^T cov^-1 e / k of a stacked error (k = its length) and its 95 % bounds."""
    err = np.asarray(err, float)
    k = len(err)
    if k == 0:
        return float("nan"), (float("nan"), float("nan"))
    cov = np.asarray(cov, float)
    try:
        Lc = np.linalg.cholesky(cov)
        z = np.linalg.solve(Lc, err)
        v = float(z @ z)
    except np.linalg.LinAlgError:
        v = float(err @ np.linalg.lstsq(cov, err, rcond=None)[0])
    return v / k, anees_bounds(k, 1)


def truth_labels(ds, res):
    """True label (landmark id or None = clutter) per used observation (res.assoc order)."""
    tl = ds.truth_landmarks
    by_cls = {}
    for k, (x, y, c) in tl.items():
        by_cls.setdefault(c, []).append((k, x, y))
    out = []
    for (i, o, j) in res.assoc:
        if o.lm_id is not None and o.lm_id in tl:
            out.append(o.lm_id)
            continue
        tp = ds.steps[i].truth
        if tp is None or o.cls not in by_cls:
            out.append(None)
            continue
        # The landmark the observation is most likely of: smallest Mahalanobis distance between the
        # measured (range, bearing) and the one predicted from the true pose, with the
        # observation's covariance. (Nearest in the plane was wrong far away, where a range sigma
        # of 0.6 m puts the point between two landmarks while the bearing, 8 mrad, is unambiguous.)
        best, bd2 = None, float("inf")
        try:
            inv = np.linalg.inv(np.asarray(o.cov, float))
        except np.linalg.LinAlgError:
            inv = None
        for k, x, y in by_cls[o.cls]:
            dx, dy = x - tp[0], y - tp[1]
            nu = np.array([o.range_m - math.hypot(dx, dy), wrap(o.bearing_rad - (math.atan2(dy, dx) - tp[2]))])
            d2 = float(nu @ inv @ nu) if inv is not None else float("inf")
            if d2 < bd2:
                best, bd2 = k, d2
        # accepted within the 99.99% chi-square gate of 2 dof, or within 0.5 m in the plane
        w = rb_to_world(tp, o.range_m, o.bearing_rad)
        near = best is not None and math.hypot(tl[best][0] - w[0], tl[best][1] - w[1]) <= 0.5
        out.append(best if (bd2 <= 18.42 or near) else None)
    return out


def match_landmarks(ds, res, labels):
    """(mapping est landmark -> true id, association error count)."""
    m = len(res.lms)
    if res.stats.get("association") == "known":
        mp = {j: res.lm_ids[j] for j in range(m) if res.lm_ids[j] in ds.truth_landmarks}
        err = sum(1 for (i, o, j), lab in zip(res.assoc, labels) if mp.get(j) != lab)
        return mp, err
    tids = sorted(ds.truth_landmarks)
    if not tids or m == 0:
        return {}, None
    col = {t: k for k, t in enumerate(tids)}
    C = np.zeros((m, len(tids)))
    for (i, o, j), lab in zip(res.assoc, labels):
        if lab is not None:
            C[j, col[lab]] += 1
    # maximise matched counts: minimise -C; pad so rows <= cols
    if m <= len(tids):
        sol = hungarian(-C)
        pairs = [(j, sol[j]) for j in range(m)]
    else:
        sol = hungarian(-C.T)
        pairs = [(sol[k], k) for k in range(len(tids))]
    mp = {j: tids[k] for j, k in pairs if C[j, k] > 0}
    err = sum(1 for (i, o, j), lab in zip(res.assoc, labels) if lab is None or mp.get(j) != lab)
    return mp, err


def evaluate(ds, res):
    """All metrics available for this data set (dict, JSON-friendly)."""
    out = {}
    idx = [i for i, s in enumerate(ds.steps) if s.truth is not None]
    if idx:
        truth = np.array([ds.steps[i].truth for i in idx])
        est = res.poses[idx]
        un, al, (R, t, ang) = ate(est, truth)
        out["ate_unaligned_m"] = un
        out["ate_m"] = al
        out["align_rotation_rad"] = ang
        out["align_translation_m"] = t.tolist()
        out["ate_isam_m"] = ate(res.isam_poses[idx], truth)[1]
        if res.pose_cov is not None:
            errs = [between(res.poses[i], ds.steps[i].truth) for i in idx]
            a, bnd = anees(errs, [res.pose_cov[i] for i in idx])
            out["anees_poses"] = a
            out["anees_poses_bounds95"] = list(bnd)
            if res.info is not None:
                from .backend import X
                e = np.concatenate(errs)
                out["anees_poses_joint"] = res.info.nees([X(i) for i in idx], e) / len(e)
                out["anees_poses_joint_bounds95"] = list(anees_bounds(len(e), 1))
        out["_align"] = (R, t)
    if ds.truth_landmarks:
        labels = truth_labels(ds, res)
        mp, err = match_landmarks(ds, res, labels)
        out["association_errors"] = err
        out["clutter_used"] = sum(1 for lab in labels if lab is None)
        out["landmarks_matched"] = len(mp)
        out["landmarks_estimated"] = len(res.lms)
        out["landmarks_true"] = len(ds.truth_landmarks)
        if mp:
            js = sorted(mp)
            est = res.lms[js]
            tr = np.array([ds.truth_landmarks[mp[j]][:2] for j in js], float)
            out["landmark_rmse_m"] = rmse(est, tr)
            if "_align" in out:
                R, t = out["_align"]
                out["landmark_rmse_aligned_m"] = rmse(est @ R.T + t, tr)
            if res.lm_cov is not None:
                a, bnd = anees(list(est - tr), [res.lm_cov[j] for j in js])
                out["anees_landmarks"] = a
                out["anees_landmarks_bounds95"] = list(bnd)
                if res.info is not None:
                    from .backend import L
                    e = (est - tr).reshape(-1)
                    keys = res.lm_keys or [L(j) for j in range(len(res.lms))]
                    out["anees_landmarks_joint"] = res.info.nees([keys[j] for j in js], e) / len(e)
                    out["anees_landmarks_joint_bounds95"] = list(anees_bounds(len(e), 1))
        out["_match"] = mp
    return out
