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


# --- the camera model evaluated at the estimated calibration (--calib-model exact) ------------

SYNTH_LENS = dict(k1=-0.12, k2=0.05, p1=0.0008, p2=-0.0006, k3=0.0)   # calib_data/synthetic_camera.yaml


def _exact_setup(u=180.0, v=150.0, d_true=None):
    """An observation of the synthetic camera at pixel (u, v) -- far, 3.2 m -- made with the nominal
    calibration, a pose, and the landmark where the true calibration (nominal + d_true) puts it."""
    from cylslam.camera_model import range_bearing_model
    header = {"model": "exact", "camera": dict(width=640, height=480, fx=570.0, fy=568.0, cx=322.4, cy=236.9,
                                               tilt_rad=0.20944, yaw_rad=0.0, height_m=0.326, offset_m=0.1,
                                               **SYNTH_LENS)}
    rbm, why = range_bearing_model(header)
    assert rbm is not None, why
    r0, b0, j0 = rbm.eval(u, v)
    jac = j0[:, list(rbm.CALIB_INPUTS)]
    jpx = j0[:, 0:2]
    cov_px = np.diag([0.01, 0.04])
    o = Obs(cls="orange", range_m=r0, bearing_rad=b0, cov=np.eye(2), jac_calib=jac,
            cov_frame=jpx @ cov_px @ jpx.T, u_px=u, v_px=v)
    pose = np.array([0.4, -0.3, 0.5])
    d_true = np.zeros(8) if d_true is None else d_true
    rt, bt, _ = rbm.eval(u, v, d_true)
    lm = pose[:2] + rt * np.array([np.cos(pose[2] + bt), np.sin(pose[2] + bt)])
    return rbm, o, pose, lm, cov_px


def _values(pose, lm, d, bias=None):
    from cylslam.backend import B
    v = gtsam.Values()
    v.insert(X(0), gtsam.Pose2(*pose))
    v.insert(L(0), gtsam.Point2(*lm))
    v.insert(CALIB, np.asarray(d, float))
    if bias is not None:
        v.insert(B(0), np.asarray(bias, float))
    return v


def test_exact_factor_is_the_model_at_the_estimate():
    """Zero residual where the true calibration error is (far beyond the linearisation: the range
    moves 9 % for a 1 deg tilt error at 3.2 m), a residual for the linear factor there; the noise is
    the centroid's in px; at the nominal calibration both factors give the same error."""
    from cylslam.backend import calib_factor_exact
    d_true = np.array([0.8, -0.6, 0.5, -0.4, np.radians(1.0), np.radians(-0.4), 0.002, -0.003])
    rbm, o, pose, lm, cov_px = _exact_setup(d_true=d_true)
    f = calib_factor_exact(X(0), L(0), o, o.cov_frame, rbm)
    lin = calib_factor(X(0), L(0), o, gtsam.noiseModel.Gaussian.Covariance(o.cov_frame[::-1, ::-1]))
    assert f.error(_values(pose, lm, d_true)) < 1e-16
    assert lin.error(_values(pose, lm, d_true)) > 1.0          # the linearisation misses by > 1 sigma
    # the factor's residual is in px: its noise model is the centroid's covariance
    assert np.allclose(f.noiseModel().covariance(), cov_px, rtol=1e-9)
    # at the nominal calibration the two are the same error, wherever pose and landmark are
    for lm2 in (lm, lm + [0.05, -0.03], lm + [-0.2, 0.1]):
        a, b = f.error(_values(pose, lm2, np.zeros(8))), lin.error(_values(pose, lm2, np.zeros(8)))
        assert a == pytest.approx(b, rel=1e-6)


def test_exact_factor_jacobians_match_central_differences():
    """The pose and landmark columns are exact everywhere (the residual's scaling A^-1 does not
    depend on them); the calibration and bias columns ignore how A^-1 itself changes (A is taken at
    the pixel less the bias, under the calibration delta) -- a Gauss-Newton approximation, exact
    where the residual is zero, which is checked there, each column to its own size."""
    from cylslam.backend import B, calib_factor_exact
    d0 = np.array([0.3, -0.2, 0.4, 0.1, np.radians(0.5), np.radians(0.2), 0.001, 0.002])
    rbm, o, pose, lm, _ = _exact_setup(u=420.0, v=190.0, d_true=d0)
    f = calib_factor_exact(X(0), L(0), o, o.cov_frame, rbm, bias_keys=[B(0)])
    moved = dict(pose=pose + [0.01, -0.02, 0.003], lm=lm + [0.03, -0.01], d=d0 * 0.7, b=np.array([0.2, -0.3]))
    at_zero = dict(pose=pose, lm=lm, d=d0, b=np.zeros(2))

    def jacobians(at):
        def werr(pose_xi=np.zeros(3), lm_=None, d=None, b=None):
            p = gtsam.Pose2(*at["pose"]).retract(pose_xi)
            return f.whitenedError(_values([p.x(), p.y(), p.theta()], at["lm"] if lm_ is None else lm_,
                                           at["d"] if d is None else d, at["b"] if b is None else b))
        a, _ = f.linearize(_values(at["pose"], at["lm"], at["d"], at["b"])).jacobian()
        num = np.hstack([numeric(lambda x: werr(pose_xi=x), np.zeros(3)),
                         numeric(lambda x: werr(lm_=x), at["lm"]),
                         numeric(lambda x: werr(d=x), at["d"], eps=1e-7),
                         numeric(lambda x: werr(b=x), at["b"])])
        return a, num, np.linalg.norm(werr())

    def close(a, b):
        return all(np.allclose(a[:, c], b[:, c], rtol=1e-4, atol=1e-4 * max(np.abs(b[:, c]).max(), 1e-9))
                   for c in range(a.shape[1]))
    a, num, r = jacobians(at_zero)
    assert r < 1e-7
    assert close(a, num)
    a, num, r = jacobians(moved)
    assert r > 1.0                                   # a real residual: the approximation matters
    assert close(a[:, 0:5], num[:, 0:5])             # pose and landmark: exact
    assert not close(a[:, 5:13], num[:, 5:13])       # calibration: the approximation shows
    assert not close(a[:, 13:15], num[:, 13:15])     # bias: likewise


def test_exact_model_needs_the_lens(tmp_path):
    """A log without the header's distortion coefficients cannot use the exact model: a clear error;
    with them (the fixture's camera is calib_data/synthetic_camera.yaml) the run maps as the linear
    one does on this drive's near observations, and evaluates every used observation exactly."""
    import json
    ds = read_obslog(FIX)
    with pytest.raises(ValueError, match="lacks k1, k2, p1, p2, k3"):
        Slam(Params(calib_states=True, calib_model="exact", covariances=False)).run(ds)
    lines = open(FIX).read().splitlines()
    h = json.loads(lines[0])
    h["camera"].update(SYNTH_LENS)
    p = tmp_path / "lens.jsonl"
    p.write_text("\n".join([json.dumps(h)] + lines[1:]) + "\n")
    ds = read_obslog(str(p))
    lin = Slam(Params(calib_states=True, covariances=False)).run(ds)
    ex = Slam(Params(calib_states=True, calib_model="exact", covariances=False)).run(ds)
    assert ex.stats["exact_factors"] == ex.stats["used"] > 100
    assert lin.stats["exact_factors"] == 0
    assert len(ex.lms) == len(lin.lms)
    assert abs(np.degrees(ex.stats["calib_error_estimate"][4] - lin.stats["calib_error_estimate"][4])) < 0.05
    assert np.max(np.abs(np.array(ex.lms) - np.array(lin.lms))) < 0.01
