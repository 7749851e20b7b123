# SPDX-License-Identifier: BSD-3-Clause
import itertools
import math

import gtsam
import numpy as np
import pytest

from cylslam import backend, metrics
from cylslam.data import Dataset, Obs, Step


def test_covariance_permutation_to_gtsam_order():
    c = np.array([[0.04, 0.003], [0.003, 0.0001]])   # (range, bearing)
    g = backend.to_gtsam_cov(c)
    assert np.allclose(g, [[0.0001, 0.003], [0.003, 0.04]])  # (bearing, range)


def test_factor_whitening_uses_range_sigma_for_range_error():
    # range error 0.1 m with sigma_r 0.1 m and a loose bearing: error = 0.5 * 1^2
    v = gtsam.Values()
    v.insert(backend.X(0), gtsam.Pose2(0, 0, 0))
    v.insert(backend.L(0), gtsam.Point2(2.0, 0.0))
    cov_rb = np.diag([0.1 ** 2, 1.0 ** 2])
    f = gtsam.BearingRangeFactor2D(backend.X(0), backend.L(0), gtsam.Rot2(0.0), 2.1,
                                   gtsam.noiseModel.Gaussian.Covariance(backend.to_gtsam_cov(cov_rb)))
    assert f.error(v) == pytest.approx(0.5)
    # bearing error 0.01 rad with sigma_b 0.01 and a loose range: also 0.5
    cov_rb = np.diag([1.0, 0.01 ** 2])
    f = gtsam.BearingRangeFactor2D(backend.X(0), backend.L(0), gtsam.Rot2(0.01), 2.0,
                                   gtsam.noiseModel.Gaussian.Covariance(backend.to_gtsam_cov(cov_rb)))
    assert f.error(v) == pytest.approx(0.5, rel=1e-6)


def test_prediction_jacobian_matches_gtsam_retract():
    pose = np.array([0.3, -0.2, 0.7])
    lm = np.array([2.0, 1.5])
    h, H = backend.predict_rb(pose, lm)
    P = gtsam.Pose2(*pose)
    num = np.zeros((2, 5))
    eps = 1e-6
    for k in range(5):
        d = np.zeros(5)
        d[k] = eps
        Pk = P.retract(d[:3])
        lk = lm + d[3:]
        hk, _ = backend.predict_rb(np.array([Pk.x(), Pk.y(), Pk.theta()]), lk)
        num[:, k] = (hk - h) / eps
    assert np.allclose(H, num, atol=1e-5)
    assert h[0] == pytest.approx(P.range(gtsam.Point2(*lm)))
    assert h[1] == pytest.approx(P.bearing(gtsam.Point2(*lm)).theta())


def test_hungarian_matches_brute_force():
    rng = np.random.default_rng(5)
    for _ in range(30):
        n, m = int(rng.integers(1, 5)), int(rng.integers(4, 7))
        C = rng.uniform(0, 10, (n, m))
        sol = backend.hungarian(C)
        best = min(sum(C[i, p[i]] for i in range(n)) for p in itertools.permutations(range(m), n))
        assert len(set(sol)) == n
        assert sum(C[i, sol[i]] for i in range(n)) == pytest.approx(best)


def _obs(cls, pose, lm, cov, conf=0.9, flags=0):
    h, _ = backend.predict_rb(pose, lm)
    return Obs(cls=cls, range_m=float(h[0]), bearing_rad=float(h[1]), cov=cov, confidence=conf,
               flags=flags)


def test_association_on_an_ambiguous_case():
    """Two orange landmarks 0.6 m apart and a green one between them. A is first seen 0.1 m
    off (its estimate is at y = 0.2). In frame 2 both orange observations lie nearer to A's
    estimate than to B's: nearest-neighbour would give A twice; the assignment gives A and B,
    one each (and the second is truly B: nearest true landmark). The green one must never take
    an orange observation."""
    A, B, G = np.array([3.0, 0.3]), np.array([3.0, -0.3]), np.array([3.0, 0.0])
    cov = np.diag([0.05 ** 2, 0.05 ** 2])
    p0 = np.zeros(3)
    p1 = np.array([0.1, 0.0, 0.0])
    s0 = Step(t=0, seq=0, truth=p0, obs=[_obs("orange", p0, np.array([3.0, 0.2]), cov),
                                         _obs("orange", p0, B, cov),
                                         _obs("green", p0, G, cov)])
    odc = np.diag([1e-4, 1e-4, 1e-4])
    obs1 = [_obs("orange", p1, np.array([3.0, 0.32]), cov),   # clearly A
            _obs("orange", p1, np.array([3.0, -0.02]), cov),  # nearer A's estimate, truly B
            _obs("orange", p1, np.array([3.0, -0.3]), cov, conf=0.2),  # low confidence: dropped
            _obs("orange", p1, np.array([3.0, -0.3]), cov, flags=0x20),  # cut: dropped
            _obs("green", p1, np.array([6.0, 3.0]), cov)]     # gates nothing: new landmark
    s1 = Step(t=1, seq=1, odom=p1.copy(), odom_cov=odc, truth=p1, obs=obs1)
    ds = Dataset(name="ambiguous", steps=[s0, s1], classes=["orange", "green"],
                 truth_landmarks={0: (*A, "orange"), 1: (*B, "orange"), 2: (*G, "green"),
                                  3: (6.0, 3.0, "green")})
    res = backend.Slam(backend.Params(assoc="unknown")).run(ds)
    targets = [(i, j) for (i, o, j) in res.assoc]
    assert targets[:3] == [(0, 0), (0, 1), (0, 2)]
    assert targets[3:] == [(1, 0), (1, 1), (1, 3)]
    assert res.stats["dropped_confidence"] == 1 and res.stats["dropped_flags"] == 1
    assert res.stats["new_landmarks"] == 4
    m = metrics.evaluate(ds, res)
    assert m["association_errors"] == 0
    # nearest-neighbour on the estimates would have put observation 2 of frame 1 on A
    d = [np.linalg.norm(np.array([3.0, -0.02]) - res_l) for res_l in
         (np.array([3.0, 0.2]), B)]
    assert d[0] < d[1]


def test_association_errors_are_counted():
    """Same scene; force a wrong association by a too generous gate with no alternative:
    B is never initialised (its first observation is dropped), so its later observation
    is put on A -> one association error."""
    A, B = np.array([3.0, 0.3]), np.array([3.0, -0.3])
    cov = np.diag([0.05 ** 2, 0.05 ** 2])
    p0 = np.zeros(3)
    p1 = np.array([0.1, 0.0, 0.0])
    s0 = Step(t=0, seq=0, truth=p0, obs=[_obs("orange", p0, A, cov)])
    s1 = Step(t=1, seq=1, odom=p1.copy(), odom_cov=np.diag([1e-4] * 3), truth=p1,
              obs=[_obs("orange", p1, B, cov)])
    ds = Dataset(name="wrong", steps=[s0, s1], truth_landmarks={0: (*A, "orange"), 1: (*B, "orange")})
    res = backend.Slam(backend.Params(assoc="unknown", gate_p=0.999999, new_p=0.9999999)).run(ds)
    assert [j for (_, _, j) in res.assoc] == [0, 0]
    assert metrics.evaluate(ds, res)["association_errors"] == 1


def test_imprecise_observation_does_not_seed_a_landmark():
    """A far observation with a range sigma of metres (a near-horizon blob) gates with nothing:
    it must be dropped, not start a landmark; a precise one starts a landmark."""
    p0 = np.zeros(3)
    far = _obs("orange", p0, np.array([25.0, 5.0]), np.diag([8.0 ** 2, 0.01 ** 2]))
    near = _obs("orange", p0, np.array([3.0, 0.0]), np.diag([0.05 ** 2, 0.01 ** 2]))
    ds = Dataset(name="imprecise", steps=[Step(t=0, seq=0, truth=p0, obs=[far, near])])
    res = backend.Slam(backend.Params(assoc="unknown")).run(ds)
    assert res.stats["dropped_imprecise"] == 1 and res.stats["new_landmarks"] == 1
    assert np.allclose(res.lms[0], [3.0, 0.0], atol=1e-3)


def test_gate_separates_a_new_landmark_from_a_known_one():
    """A is seen first; then B, same class, 0.6 m from A (d2 ~ 20 with these covariances, beyond
    chi2_2(0.9999) = 18.4): B must become a new landmark, not an update of A."""
    A, B = np.array([3.0, 0.3]), np.array([3.0, -0.3])
    cov = np.diag([0.03 ** 2, 0.03 ** 2])
    p0 = np.zeros(3)
    p1 = np.array([0.1, 0.0, 0.0])
    s0 = Step(t=0, seq=0, truth=p0, obs=[_obs("orange", p0, A, cov)])
    s1 = Step(t=1, seq=1, odom=p1.copy(), odom_cov=np.diag([1e-4] * 3), truth=p1,
              obs=[_obs("orange", p1, B, cov)])
    ds = Dataset(name="gate", steps=[s0, s1], truth_landmarks={0: (*A, "orange"), 1: (*B, "orange")})
    res = backend.Slam(backend.Params(assoc="unknown")).run(ds)
    assert [j for (_, _, j) in res.assoc] == [0, 1]
    assert metrics.evaluate(ds, res)["association_errors"] == 0
    assert backend.chi2_2dof(0.99) == pytest.approx(9.2103, abs=1e-4)


def test_mixed_association_uses_identities_where_given():
    """The scene of test_association_errors_are_counted, whose generous gate puts B's observation
    on A: with identities on A's and B's observations (a code read), B becomes its own landmark;
    an observation without an identity, near A, is gated onto the landmark A's identity made."""
    A, B = np.array([3.0, 0.3]), np.array([3.0, -0.3])
    cov = np.diag([0.05 ** 2, 0.05 ** 2])
    p0 = np.zeros(3)
    p1 = np.array([0.1, 0.0, 0.0])
    a0 = _obs("orange", p0, A, cov)
    a0.lm_id = 10
    b1 = _obs("orange", p1, B, cov)
    b1.lm_id = 11
    a1 = _obs("orange", p1, A + np.array([0.01, 0.0]), cov)   # no identity
    s0 = Step(t=0, seq=0, truth=p0, obs=[a0])
    s1 = Step(t=1, seq=1, odom=p1.copy(), odom_cov=np.diag([1e-4] * 3), truth=p1, obs=[b1, a1])
    ds = Dataset(name="mixed", steps=[s0, s1], truth_landmarks={0: (*A, "orange"), 1: (*B, "orange")})
    res = backend.Slam(backend.Params(assoc="auto", gate_p=0.999999, new_p=0.9999999)).run(ds)
    assert res.stats["association"] == "mixed"
    assert res.stats["by_identity"] == 2
    assert [j for (_, _, j) in res.assoc] == [0, 1, 0]
    assert metrics.evaluate(ds, res)["association_errors"] == 0
    # the same log without the identities: the gate takes B's observation for A
    b1.lm_id = a0.lm_id = None
    res = backend.Slam(backend.Params(assoc="auto", gate_p=0.999999, new_p=0.9999999)).run(ds)
    assert res.stats["association"] == "unknown"
    assert [j for (_, _, j) in res.assoc][:2] == [0, 0]


def test_joint_nees_from_information_matches_dense_joint_covariance():
    # A small graph with every kind of variable the back end makes (poses, landmarks, odometry
    # states, a vector state) and a robust kernel: e^T Sigma_S^-1 e from the sparse information matrix's Schur
    # complement equals the same with gtsam.Marginals' dense joint covariance, for pose subsets,
    # landmark sets and mixed sets.
    rng = np.random.default_rng(3)
    g = gtsam.NonlinearFactorGraph()
    v = gtsam.Values()
    g.add(gtsam.PriorFactorPose2(backend.X(0), gtsam.Pose2(0, 0, 0), gtsam.noiseModel.Diagonal.Sigmas([1e-2, 1e-2, 1e-3])))
    v.insert(backend.X(0), gtsam.Pose2(0, 0, 0))
    g.add(gtsam.PriorFactorVector(backend.CALIB, np.zeros(8), gtsam.noiseModel.Isotropic.Sigma(8, 0.1)))
    v.insert(backend.CALIB, np.zeros(8))
    lms = rng.uniform(-3, 3, (4, 2)) + [4, 0]
    for j, p in enumerate(lms):
        v.insert(backend.L(j), gtsam.Point2(*(p + rng.normal(0, 0.05, 2))))
    huber = gtsam.noiseModel.Robust.Create(gtsam.noiseModel.mEstimator.Huber.Create(1.0),
                                           gtsam.noiseModel.Diagonal.Sigmas([0.01, 0.05]))
    for i in range(6):
        if i:
            # odometry with two Gauss-Markov states per component (backend.odom_factors)
            s = Step(t=float(i), seq=i, odom=np.array([0.3, 0, 0.05]), odom_cov=np.eye(3),
                     odom_gm=(np.diag([0.02, 0.01, 0.01]) ** 2, np.full(6, 0.01),
                              np.full(6, 0.7) if i > 1 else np.zeros(6)))
            fs, vs = backend.odom_factors(s, backend.X(i - 1), backend.X(i), backend.Z(i - 1), backend.Z(i), i > 1)
            for f in fs:
                g.add(f)
            for key, val in vs:
                v.insert(key, val)
            v.insert(backend.X(i), gtsam.Pose2(0.3 * i, 0.01 * i, 0.05 * i))
        for j, p in enumerate(lms):
            pose = gtsam.Pose2(0.3 * i, 0, 0.05 * i)
            b = pose.bearing(gtsam.Point2(*p)).theta() + rng.normal(0, 0.01)
            r = pose.range(gtsam.Point2(*p)) + rng.normal(0, 0.05)
            g.add(gtsam.BearingRangeFactor2D(backend.X(i), backend.L(j), gtsam.Rot2(b), r, huber))
    # the calibration state enters through its prior only here; tie it to a landmark so that the
    # Schur complement has off-diagonal blocks to remove
    g.add(gtsam.CustomFactor(gtsam.noiseModel.Isotropic.Sigma(2, 0.1), [backend.L(0), backend.CALIB],
                             lambda f, vals, H: _tie(vals, H)))
    est = gtsam.LevenbergMarquardtOptimizer(g, v).optimize()
    info = backend.Information(g, est)
    marg = gtsam.Marginals(g, est)
    for keys in ([backend.X(i) for i in range(6)], [backend.X(1), backend.X(4)],
                 [backend.L(j) for j in range(4)], [backend.L(2)], [backend.X(3), backend.L(1)],
                 [backend.Z(2), backend.X(5)]):
        dense = marg.jointMarginalCovariance(gtsam.KeyVector(keys)).fullMatrix()
        e = rng.normal(0, 0.1, dense.shape[0])
        want = float(e @ np.linalg.solve(dense, e))
        assert info.nees(keys, e) == pytest.approx(want, rel=1e-6)


def _tie(vals, H):
    lm = vals.atPoint2(backend.L(0))
    c = vals.atVector(backend.CALIB)
    if H is not None:
        H[0] = np.eye(2)
        H[1] = np.hstack([-np.eye(2), np.zeros((2, 6))])
    return np.array([lm[0] - c[0] - 4.0, lm[1] - c[1]])
