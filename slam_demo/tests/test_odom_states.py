# SPDX-License-Identifier: BSD-3-Clause
"""The odometry's time-correlated error as a state (backend.odom_factors): its residual is GTSAM's
BetweenFactor's less the state's part, its Jacobians are central differences, a chain of them has
the hand-derived covariance of correlated steps, the Python Levenberg-Marquardt loop finds what
GTSAM's does, and the MRCLAM reader splits the learned model's variance into the two parts."""
import math
import os

import gtsam
import numpy as np
import pytest

from conftest import FIXTURES
from cylslam import backend
from cylslam import noise_model as nm
from cylslam.data import Step
from cylslam.mrclam import read_mrclam


def _values(p1, p2, z):
    v = gtsam.Values()
    v.insert(backend.X(0), gtsam.Pose2(*p1))
    v.insert(backend.X(1), gtsam.Pose2(*p2))
    v.insert(backend.Z(1), np.asarray(z, float))
    return v


def test_residual_is_the_between_factor_s_less_the_state_and_jacobians_are_central_differences():
    inc = np.array([0.31, -0.04, 0.12])
    sd = np.array([0.02, 0.005, 0.01])
    s = Step(t=1.0, seq=1, odom=inc, odom_cov=np.eye(3),
             odom_gm=(np.eye(3), sd, np.zeros(3)))     # unit white noise: whitened = raw
    fs, vs = backend.odom_factors(s, backend.X(0), backend.X(1), backend.Z(0), backend.Z(1), False)
    assert len(fs) == 2 and [k for k, _ in vs] == [backend.Z(1)]
    f = fs[0]
    p1, p2, z = (1.0, 2.0, 0.4), (1.3, 2.1, 0.55), np.array([0.7, -1.2, 0.3])
    bf = gtsam.BetweenFactorPose2(backend.X(0), backend.X(1), gtsam.Pose2(*inc), gtsam.noiseModel.Unit.Create(3))
    v = _values(p1, p2, z)
    assert np.allclose(f.unwhitenedError(v), bf.unwhitenedError(v) - sd * z, atol=1e-12)
    # Jacobians: the linearised factor's blocks against central differences in each variable's
    # tangent space (Pose2: body-frame (vx, vy, omega))
    a, b = f.linearize(v).jacobian()
    h = 1e-6
    num = np.zeros((3, 9))
    for c in range(9):
        d = np.zeros(9)
        d[c] = h
        out = []
        for sign in (1.0, -1.0):
            q1 = gtsam.Pose2(*p1).retract(sign * d[0:3])
            q2 = gtsam.Pose2(*p2).retract(sign * d[3:6])
            w = gtsam.Values()
            w.insert(backend.X(0), q1)
            w.insert(backend.X(1), q2)
            w.insert(backend.Z(1), z + sign * d[6:9])
            out.append(f.unwhitenedError(w))
        num[:, c] = (out[0] - out[1]) / (2 * h)
    assert np.allclose(a, num, atol=1e-6)
    assert np.allclose(b, -f.unwhitenedError(v), atol=1e-12)


def test_a_chain_of_states_has_the_covariance_of_correlated_steps():
    # a straight drive along x: to first order the x coordinate of the last pose is the sum of the
    # steps' x errors, so its variance is sum_ij C_ij with C = W + diag(sd) R diag(sd),
    # R_ij = prod of phi between i and j (the Gauss-Markov correlation), hand-derived
    rng = np.random.default_rng(3)
    n = 40
    white = rng.uniform(0.5, 2.0, (n, 3)) * 1e-4
    sd = rng.uniform(0.005, 0.03, (n, 3))
    phi = rng.uniform(0.6, 0.99, (n, 3))
    phi[0] = 0.0
    graph = gtsam.NonlinearFactorGraph()
    v = gtsam.Values()
    graph.add(gtsam.PriorFactorPose2(backend.X(0), gtsam.Pose2(0, 0, 0),
                                     gtsam.noiseModel.Diagonal.Sigmas(np.array([1e-6, 1e-6, 1e-6]))))
    v.insert(backend.X(0), gtsam.Pose2(0, 0, 0))
    steps = [Step(t=0.0, seq=0)]
    for k in range(1, n + 1):
        s = Step(t=float(k), seq=k, odom=np.array([0.2, 0.0, 0.0]), odom_cov=np.eye(3),
                 odom_gm=(np.diag(white[k - 1]), sd[k - 1], phi[k - 1]))
        fs, vs = backend.odom_factors(s, backend.X(k - 1), backend.X(k), backend.Z(k - 1), backend.Z(k),
                                      steps[-1].odom_gm is not None)
        steps.append(s)
        for f in fs:
            graph.add(f)
        for key, val in vs:
            v.insert(key, val)
        v.insert(backend.X(k), gtsam.Pose2(0.2 * k, 0, 0))
    got = gtsam.Marginals(graph, v).marginalCovariance(backend.X(n))[0, 0]
    R = np.eye(n)
    for i in range(n):
        for j in range(i + 1, n):
            R[i, j] = R[j, i] = np.prod(phi[i + 1:j + 1, 0])
    C = np.diag(white[:, 0]) + np.outer(sd[:, 0], sd[:, 0]) * R
    want = C.sum() + 1e-12
    assert got == pytest.approx(want, rel=1e-6)
    # and the steps are not independent: the same variances without the correlation give less
    assert np.sum(np.diag(C)) < 0.5 * want


def _ring_graph(with_states):
    """A noisy loop of 30 poses with a landmark seen from all: a non-trivial nonlinear problem."""
    rng = np.random.default_rng(5)
    graph = gtsam.NonlinearFactorGraph()
    v = gtsam.Values()
    graph.add(gtsam.PriorFactorPose2(backend.X(0), gtsam.Pose2(0, 0, 0),
                                     gtsam.noiseModel.Diagonal.Sigmas(np.array([1e-3, 1e-3, 1e-4]))))
    pose = np.zeros(3)
    v.insert(backend.X(0), gtsam.Pose2(*pose))
    prev = Step(t=0.0, seq=0)
    for k in range(1, 31):
        inc = np.array([0.3, 0.0, 2 * math.pi / 30])
        meas = inc + rng.normal(0, [0.02, 0.01, 0.02])
        s = Step(t=float(k), seq=k, odom=meas, odom_cov=np.diag([0.02, 0.01, 0.02]) ** 2,
                 odom_gm=(np.diag([0.014, 0.007, 0.014]) ** 2, np.array([0.014, 0.007, 0.014]),
                          np.full(3, 0.8) if k > 1 else np.zeros(3)) if with_states else None)
        fs, vs = backend.odom_factors(s, backend.X(k - 1), backend.X(k), backend.Z(k - 1), backend.Z(k),
                                      prev.odom_gm is not None)
        prev = s
        for f in fs:
            graph.add(f)
        for key, val in vs:
            v.insert(key, val)
        pose = pose + np.array([math.cos(pose[2]) * meas[0], math.sin(pose[2]) * meas[0], meas[2]])
        v.insert(backend.X(k), gtsam.Pose2(*pose))
        graph.add(gtsam.BearingRangeFactor2D(backend.X(k), backend.L(0), gtsam.Rot2(rng.normal(0, 0.01)),
                                             1.0 + rng.normal(0, 0.02),
                                             gtsam.noiseModel.Diagonal.Sigmas(np.array([0.01, 0.02]))))
    v.insert(backend.L(0), gtsam.Point2(0.5, 1.0))
    return graph, v


@pytest.mark.parametrize("with_states", [False, True])
def test_the_python_levenberg_marquardt_loop_finds_gtsam_s_solution(with_states):
    graph, v = _ring_graph(with_states)
    mine, it = backend.batch_optimize(graph, v, python_loop=True)
    lp = gtsam.LevenbergMarquardtParams()
    lp.setMaxIterations(100)
    ref = gtsam.LevenbergMarquardtOptimizer(graph, v, lp).optimize()
    assert 1 < it < 100
    assert graph.error(mine) == pytest.approx(graph.error(ref), rel=1e-6, abs=1e-9)
    for k in range(31):
        a, b = mine.atPose2(backend.X(k)), ref.atPose2(backend.X(k))
        assert np.allclose([a.x(), a.y(), a.theta()], [b.x(), b.y(), b.theta()], atol=1e-6)
    # the states change the answer: not the same problem
    if with_states:
        g0, v0 = _ring_graph(False)
        plain = backend.batch_optimize(g0, v0)[0]
        assert abs(plain.atPose2(backend.X(15)).x() - mine.atPose2(backend.X(15)).x()) > 1e-4


def test_the_reader_splits_the_learned_variance_into_white_and_correlated_parts():
    m = nm.NoiseModel.load(nm.DEFAULT_PATH)
    mr = os.path.join(FIXTURES, "mrclam")
    ds = read_mrclam(mr, 2, model=m)
    ds_inf = read_mrclam(mr, 2, model=m, odom_corr="inflate")
    comps = ("x", "y", "theta")
    # the shipped model has two exponentials: two states per component, (a1, tau1) then (a2, tau2)
    a = np.array([[m.odom_corr[c][k] for c in comps] for k in ("a1", "a2")])
    tau = np.array([[m.odom_corr[c][k] for c in comps] for k in ("tau1_s", "tau2_s")])
    assert np.all(a[1] > 0)
    assert ds.steps[1].odom_gm is not None and np.all(ds.steps[1].odom_gm[2] == 0.0)
    for k in (5, 17, 40):
        s, prev = ds.steps[k], ds.steps[k - 1]
        white, sd, phi = s.odom_gm
        assert sd.shape == phi.shape == (6,)
        var = np.diag(m.odom_cov(s.odom, s.t - prev.t))
        assert np.allclose(np.diag(white) + sd[:3] ** 2 + sd[3:] ** 2, var, rtol=1e-12)
        assert np.allclose(sd ** 2, a.reshape(-1) * np.tile(var, 2), rtol=1e-12)
        assert np.allclose(phi, np.exp(-(s.t - prev.t) / tau.reshape(-1)), rtol=1e-12)
        # iSAM2's online covariance is the inflated one either way
        assert np.allclose(s.odom_cov, ds_inf.steps[k].odom_cov)
        assert ds_inf.steps[k].odom_gm is None
    with pytest.raises(ValueError, match="odometry correlation"):
        read_mrclam(mr, 2, model=m, odom_corr="both")
