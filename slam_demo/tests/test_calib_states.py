# SPDX-License-Identifier: BSD-3-Clause
"""The calibration error as a state (backend.calib_factor): Jacobians against central
differences, the factor's residual and Jacobians through GTSAM's linearisation, the log fields,
and the effect on a real frontend log whose camera has a calibration error."""
import os

import gtsam
import numpy as np
import pytest

from cylslam.backend import CALIB, L, X, calib_factor, calib_prior, rb_jacobians, Params, Slam
from cylslam.data import Obs
from cylslam.obslog import read_obslog

FIX = os.path.join(os.path.dirname(__file__), "fixtures", "frontend_calib_error.jsonl")


def numeric(f, x, eps=1e-6):
    x = np.asarray(x, float)
    cols = []
    for k in range(len(x)):
        d = np.zeros_like(x)
        d[k] = eps
        cols.append((np.asarray(f(x + d)) - np.asarray(f(x - d))) / (2 * eps))
    return np.array(cols).T


def test_rb_jacobians_match_central_differences():
    pose, lm = np.array([0.3, -0.2, 0.7]), np.array([2.1, 1.4])

    def at_pose(xi):   # GTSAM's Pose2 retraction: body-frame (vx, vy, w)
        p = gtsam.Pose2(*pose).retract(xi)
        b, r, _, _ = rb_jacobians((p.x(), p.y(), p.theta()), lm)
        return [b, r]

    def at_lm(l):
        b, r, _, _ = rb_jacobians(pose, l)
        return [b, r]

    _, _, hp, hl = rb_jacobians(pose, lm)
    assert np.allclose(hp, numeric(at_pose, np.zeros(3)), atol=1e-7)
    assert np.allclose(hl, numeric(at_lm, lm), atol=1e-7)
    # and the prediction agrees with GTSAM's own bearing/range
    p = gtsam.Pose2(*pose)
    b, r, _, _ = rb_jacobians(pose, lm)
    assert abs(b - p.bearing(gtsam.Point2(*lm)).theta()) < 1e-12
    assert abs(r - p.range(gtsam.Point2(*lm))) < 1e-12


def test_calib_factor_residual_and_linearisation():
    rng = np.random.default_rng(4)
    jac = rng.normal(size=(2, 8)) * np.array([1e-3, 1e-3, 1e-3, 1e-3, 5.0, 0.5, 3.0, 1.0])
    pose, lm, delta = np.array([0.1, 0.2, 0.3]), np.array([2.0, -0.5]), rng.normal(size=8) * 1e-3
    b, r, _, _ = rb_jacobians(pose, lm)
    # a measurement made with the nominal calibration when the true one is off by delta
    z = np.array([r, b]) - jac @ delta
    o = Obs(cls="orange", range_m=z[0], bearing_rad=z[1], cov=np.eye(2), jac_calib=jac,
            cov_frame=np.diag([1e-4, 1e-6]))
    f = calib_factor(X(0), L(0), o, gtsam.noiseModel.Gaussian.Covariance(np.diag([1e-6, 1e-4])))
    v = gtsam.Values()
    v.insert(X(0), gtsam.Pose2(*pose))
    v.insert(L(0), gtsam.Point2(*lm))
    v.insert(CALIB, delta)
    assert f.error(v) < 1e-20                        # consistent values: zero residual
    v2 = gtsam.Values()
    v2.insert(X(0), gtsam.Pose2(*pose))
    v2.insert(L(0), gtsam.Point2(*lm))
    v2.insert(CALIB, np.zeros(8))
    assert f.error(v2) > 1e-3                        # ignoring the calibration error: a residual
    # the whitened Jacobian w.r.t. the calibration is -J (bearing row first), whitened
    g = f.linearize(v2)
    a, _ = g.jacobian()
    w = np.linalg.cholesky(np.linalg.inv(np.diag([1e-6, 1e-4]))).T
    keys = list(g.keys())
    blocks = {}
    off = 0
    for k, d in zip(keys, [3 if k == X(0) else 2 if k == L(0) else 8 for k in keys]):
        blocks[k] = a[:, off:off + d]
        off += d
    assert np.allclose(blocks[CALIB], w @ -np.vstack([jac[1], jac[0]]), rtol=1e-9, atol=1e-12)


def test_calib_prior_is_invertible_with_exact_parameters():
    c = np.diag([0.2, 0.2, 0.1, 0.1, 1e-4, 1e-4, 0.0, 1e-6])   # h known exactly
    f = calib_prior(c)
    v = gtsam.Values()
    v.insert(CALIB, np.zeros(8))
    assert f.error(v) == 0.0


def test_log_carries_calibration_fields():
    ds = read_obslog(FIX)
    assert ds.calib_cov is not None and ds.calib_cov.shape == (8, 8)
    assert np.all(np.diag(ds.calib_cov) > 0)
    used = [o for s in ds.steps for o in s.obs if o.jac_calib is not None]
    assert len(used) > 100
    for o in used[:50]:
        assert o.jac_calib.shape == (2, 8) and o.cov_frame.shape == (2, 2)
        # what changes frame to frame is a small part of the full covariance
        assert o.cov_frame[0, 0] < o.cov[0, 0]


def _landmark_rmse(ds, res):
    truth = np.array([v[:2] for v in ds.truth_landmarks.values()])
    err = [np.min(np.linalg.norm(truth - l, axis=1)) for l in res.lms]
    return float(np.sqrt(np.mean(np.square(err))))


def test_frontend_log_with_calibration_error():
    ds = read_obslog(FIX)
    plain = Slam(Params(covariances=False)).run(ds)
    states = Slam(Params(calib_states=True, covariances=False)).run(ds)
    # the tilt error the drive was rendered with (+0.317 deg) is recovered in sign and size
    est = states.stats["calib_error_estimate"]
    assert 0.1 < np.degrees(est[4]) < 0.5
    # and the map is several times better than with the full per-observation covariance
    assert _landmark_rmse(ds, states) < 0.5 * _landmark_rmse(ds, plain)


def test_fixed_frame_covariance_keeps_the_states_and_replaces_only_the_frame_part():
    """--fixed-cov frame-grid: with every observation's frame covariance equal to the fixed one the
    run is the main run (same graph); with a 100x larger one the calibration states are still
    there (the tilt error is still found) but the observations weigh less (the landmarks move)."""
    ds = read_obslog(FIX)
    obs = [o for s in ds.steps for o in s.obs if o.cov_frame is not None]
    common = sorted(obs, key=lambda o: o.cov_frame[0, 0])[len(obs) // 2].cov_frame.copy()   # a typical one
    for o in obs:   # the same frame covariance everywhere, the full one shifted by the difference
        o.cov = o.cov - o.cov_frame + common
        o.cov_frame = common.copy()
    main = Slam(Params(calib_states=True, lm_bias="none", covariances=False)).run(ds)
    same = Slam(Params(calib_states=True, lm_bias="none", covariances=False, fixed_frame_cov=common)).run(ds)
    assert len(main.lms) == len(same.lms) > 0
    assert np.allclose(np.array(main.lms), np.array(same.lms), atol=1e-9)
    assert np.allclose(main.stats["calib_error_estimate"], same.stats["calib_error_estimate"], atol=1e-9)
    wide = Slam(Params(calib_states=True, lm_bias="none", covariances=False, fixed_frame_cov=100 * common)).run(ds)
    assert 0.05 < np.degrees(wide.stats["calib_error_estimate"][4]) < 0.6
    moved = [np.min(np.linalg.norm(np.array(main.lms) - l, axis=1)) for l in wide.lms]
    assert len(moved) > 0 and max(moved) > 1e-4
