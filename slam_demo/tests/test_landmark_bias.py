# SPDX-License-Identifier: BSD-3-Clause
"""The centroid's residual bias as one state per landmark (Params.lm_bias, obs.bias_var_px2): the
factor's residual and Jacobian against central differences, and a Monte Carlo in which every
landmark's observations share one centroid error, as the frontend's silhouette residual does:
modelled as white noise per frame it makes the landmarks over-confident; as a state, landmarks and
poses are consistent."""
import gtsam
import numpy as np
import pytest

from cylslam.backend import B, CALIB, L, X, Params, Slam, calib_factor, rb_jacobians
from cylslam.data import Dataset, Obs, Step, between, compose, wrap
from cylslam.metrics import evaluate

# d(range, bearing)/d(cx, cy) of a camera looking forward (range from the row, bearing from the column)
JPX = np.array([[0.0, -0.02], [-1.0 / 500, 0.0]])


def _jac():
    j = np.zeros((2, 8))
    j[:, 2:4] = JPX
    return j


def test_bias_factor_residual_and_jacobian():
    pose, lm, bias = np.array([0.2, -0.1, 0.4]), np.array([2.5, 1.0]), np.array([0.3, -0.2])
    b, r, _, _ = rb_jacobians(pose, lm)
    # the centroid moved by `bias` px moves (range, bearing) by -J_cxcy bias
    z = np.array([r, b]) - JPX @ bias
    o = Obs(cls="orange", range_m=z[0], bearing_rad=z[1], cov=np.eye(2), jac_calib=_jac(),
            cov_frame=np.diag([1e-4, 1e-6]))
    noise = gtsam.noiseModel.Gaussian.Covariance(np.diag([1e-6, 1e-4]))
    f = calib_factor(X(0), L(0), o, noise, [B(0)])

    def values(bv):
        v = gtsam.Values()
        v.insert(X(0), gtsam.Pose2(*pose))
        v.insert(L(0), gtsam.Point2(*lm))
        v.insert(CALIB, np.zeros(8))
        v.insert(B(0), np.asarray(bv, float))
        return v

    assert f.error(values(bias)) < 1e-20
    assert f.error(values(np.zeros(2))) > 0.1     # 0.26: (0.6^2 + 0.4^2) / 2
    # the whitened residual's Jacobian w.r.t. the bias, by central differences
    w = np.linalg.cholesky(np.linalg.inv(np.diag([1e-6, 1e-4]))).T
    eps = 1e-6
    num = np.array([(f.whitenedError(values(bias + d)) - f.whitenedError(values(bias - d))) / (2 * eps)
                    for d in (np.array([eps, 0]), np.array([0, eps]))]).T
    g = f.linearize(values(np.zeros(2)))
    a, _ = g.jacobian()
    keys = list(g.keys())
    off = sum({X(0): 3, L(0): 2, CALIB: 8}[k] for k in keys[:keys.index(B(0))])
    assert np.allclose(a[:, off:off + 2], num, rtol=1e-6, atol=1e-9)
    assert np.allclose(num, w @ -np.vstack([JPX[1], JPX[0]]), rtol=1e-6)


def _drive(rng, var_white, var_bias, steps=80, drift=None, dt=0.1):
    """A robot on a circle among four landmarks, each seen every step (dt s apart). Each landmark's
    observations share one centroid error drawn from N(0, var_bias); each frame adds N(0, var_white).
    drift = (sigma px, tau s) per axis adds a Gauss-Markov drift per landmark, which the frontend's
    variance (cov_frame) does not cover."""
    lms = np.array([[3.0, 0.5], [-2.5, 2.0], [0.5, -3.0], [-1.0, -2.8]])
    bias = rng.normal(size=(len(lms), 2)) * np.sqrt(var_bias)
    g = np.zeros((len(lms), 2))
    if drift is not None:
        sigma_g, tau_s = (np.asarray(x, float) for x in drift)
        phi = np.exp(-dt / tau_s)
        g = rng.normal(size=g.shape) * sigma_g
    q = np.diag([0.01 ** 2, 0.005 ** 2, 0.004 ** 2])
    truth = [np.array([1.5, 0.0, np.pi / 2])]
    odo = [None]
    d = np.array([2 * np.pi * 1.5 / steps, 0.0, 2 * np.pi / steps])
    for _ in range(steps - 1):
        truth.append(compose(truth[-1], d))
        odo.append(d + np.linalg.cholesky(q) @ rng.standard_normal(3))
    cov_frame = JPX @ np.diag(var_white + var_bias) @ JPX.T
    out = []
    for k, p in enumerate(truth):
        if k and drift is not None:
            g = phi * g + rng.normal(size=g.shape) * sigma_g * np.sqrt(1 - phi ** 2)
        obs = []
        for j, lm in enumerate(lms):
            b, r, _, _ = rb_jacobians(p, lm)
            z = np.array([r, b]) - JPX @ (bias[j] + g[j] + rng.normal(size=2) * np.sqrt(var_white))
            obs.append(Obs(cls="orange", range_m=z[0], bearing_rad=float(wrap(z[1])), cov=cov_frame,
                           lm_id=j, jac_calib=_jac(), cov_frame=cov_frame, bias_var_px2=var_bias.copy()))
        out.append(Step(t=dt * k, seq=k, odom=odo[k], odom_cov=None if k == 0 else q, truth=p, obs=obs))
    ds = Dataset(name="bias", steps=out, truth_landmarks={j: (*lm, "orange") for j, lm in enumerate(lms)},
                 classes=["orange"], known_ids=True)
    ds.calib_cov = np.zeros((8, 8))   # the calibration known exactly: only the bias is unmodelled
    return ds


@pytest.mark.parametrize("mode", ["none", "state"])
def test_shared_bias_monte_carlo(mode):
    rng = np.random.default_rng(11)
    var_white, var_bias = np.array([0.02, 0.02]), np.array([0.04, 0.06])
    lm, pose = [], []
    for _ in range(12):
        ds = _drive(rng, var_white, var_bias)
        res = Slam(Params(calib_states=True, lm_bias=mode, batch=True)).run(ds)
        assert res.stats["bias_states"] == (4 if mode == "state" else 0)
        m = evaluate(ds, res)
        lm.append(m["anees_landmarks_joint"])
        pose.append(m["anees_poses_joint"])
    lm_mean, pose_mean = np.mean(lm), np.mean(pose)
    if mode == "state":
        # 12 runs of 8 landmark dof: the mean is chi-square 96 / 96 (sd 0.14); poses 12 x 240 dof
        assert 0.7 < lm_mean < 1.35
        assert 0.95 < pose_mean < 1.05
    else:
        # 80 frames average the white part away but not the shared one: over-confident landmarks
        assert lm_mean > 3.0


def test_logs_without_the_field():
    # a log written before the field existed: auto runs as before, state says what is missing
    import os
    from cylslam.obslog import read_obslog
    ds = read_obslog(os.path.join(os.path.dirname(__file__), "fixtures", "frontend_calib_error.jsonl"))
    res = Slam(Params(calib_states=True, covariances=False)).run(ds)
    assert res.stats["bias_states"] == 0 and res.stats["used"] > 100
    with pytest.raises(ValueError, match=r"frontend_calib_error.jsonl:\d+: --lm-bias state needs"):
        Slam(Params(calib_states=True, lm_bias="state", covariances=False)).run(ds)


def test_bias_var_is_read_and_checked(tmp_path):
    from cylslam.obslog import ObsLogError, read_obslog
    head = '{"type":"header","format":"cyl-observations","version":2}\n{"type":"frame","seq":0,"t":0}\n'
    obs = ('{"type":"obs","seq":0,"t":0,"class":"orange","range_m":2,"bearing_rad":0.1,"cov_rr":0.01,'
           '"cov_rb":0,"cov_bb":1e-4,"jac_calib":[0,0,0,0.01,0,0,0,0,0,0,-0.002,0,0,0,0,0],'
           '"cov_frame":[1e-5,0,1e-7],"bias_var_px2":%s}\n')
    ok = tmp_path / "ok.jsonl"
    ok.write_text(head + obs % "[0.0025,0.015625]")
    o = read_obslog(str(ok)).steps[0].obs[0]
    assert np.allclose(o.bias_var_px2, [0.0025, 0.015625])
    bad = tmp_path / "bad.jsonl"
    bad.write_text(head + obs % "[-1,0]")
    with pytest.raises(ObsLogError, match=r"bad.jsonl:3: bias_var_px2 must be >= 0"):
        read_obslog(str(bad))
