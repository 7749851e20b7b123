# SPDX-License-Identifier: BSD-3-Clause
import math

import numpy as np
import pytest

from cylslam import metrics


def test_rmse_hand_computed():
    est = np.array([[0.0, 0.0], [3.0, 4.0]])
    assert metrics.rmse(est, np.zeros((2, 2))) == pytest.approx(math.sqrt(25.0 / 2))


def test_se2_alignment_recovers_a_rigid_motion():
    truth = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 2.0], [-1.0, 1.0]])
    # est = truth rotated by +90 deg and shifted by (5, -1): est_i = R truth_i + (5, -1)
    R = np.array([[0.0, -1.0], [1.0, 0.0]])
    est = truth @ R.T + np.array([5.0, -1.0])
    un, al, (Ra, t, ang) = metrics.ate(est, truth)
    assert al == pytest.approx(0.0, abs=1e-12)
    assert ang == pytest.approx(-math.pi / 2)
    # unaligned by hand: |R p + (5,-1) - p| for each point
    d = [math.hypot(*(R @ p + np.array([5.0, -1.0]) - p)) for p in truth]
    assert un == pytest.approx(math.sqrt(np.mean(np.square(d))))


def test_se2_alignment_hand_case_with_residual():
    # two points, symmetric noise: truth (+-1, 0), est (+-1, +-0.1) -> best angle atan(0.1)
    # rotates est onto truth direction; residual |est| - 1 along the line
    truth = np.array([[1.0, 0.0], [-1.0, 0.0]])
    est = np.array([[1.0, 0.1], [-1.0, -0.1]])
    un, al, (_, t, ang) = metrics.ate(est, truth)
    assert ang == pytest.approx(-math.atan(0.1))
    assert np.allclose(t, 0.0)
    assert al == pytest.approx(math.hypot(1.0, 0.1) - 1.0)
    assert un == pytest.approx(0.1)


def test_anees_known_answer():
    errs = [np.array([1.0, 0.0]), np.array([0.0, 2.0]), np.array([0.5, 0.5])]
    covs = [np.eye(2), np.diag([1.0, 4.0]), np.array([[0.5, 0.0], [0.0, 0.25]])]
    # NEES: 1, 1, 0.25/0.5 + 0.25/0.25 = 1.5 -> mean 3.5/3, per dimension / 2
    a, (lo, hi) = metrics.anees(errs, covs)
    assert a == pytest.approx(3.5 / 3 / 2)
    # correlated covariance: e = (1, 1), C = [[2, 1], [1, 2]] -> e^T C^-1 e = 2/3
    assert metrics.nees([1.0, 1.0], [[2.0, 1.0], [1.0, 2.0]]) == pytest.approx(2.0 / 3.0)


def test_anees_bounds_match_chi_square_table():
    # chi2(20): 2.5 % = 9.591, 97.5 % = 34.170 (standard tables); N=10 estimates of dimension 2
    lo, hi = metrics.anees_bounds(10, 2)
    assert lo == pytest.approx(9.591 / 20, rel=0.01)
    assert hi == pytest.approx(34.170 / 20, rel=0.01)


def test_anees_is_one_for_a_consistent_monte_carlo():
    rng = np.random.default_rng(1)
    C = np.array([[0.04, 0.01], [0.01, 0.02]])
    Lc = np.linalg.cholesky(C)
    errs = [Lc @ rng.standard_normal(2) for _ in range(4000)]
    a, (lo, hi) = metrics.anees(errs, [C] * len(errs))
    assert lo < a < hi
    a2, _ = metrics.anees(errs, [C / 4] * len(errs))
    assert a2 == pytest.approx(4 * a)


def test_joint_anees_known_answer():
    # e = (1, 1), C = [[2, 1], [1, 2]]: e^T C^-1 e = 2/3, over k = 2
    a, (lo, hi) = metrics.anees_joint([1.0, 1.0], [[2.0, 1.0], [1.0, 2.0]])
    assert a == pytest.approx(1.0 / 3.0)
    assert (lo, hi) == metrics.anees_bounds(2, 1)


def test_joint_anees_holds_for_a_random_walk_where_the_marginal_mean_does_not():
    # A consistent trajectory: x_k = x_{k-1} + w_k, w ~ N(0, q), so Cov(x_i, x_j) = q min(i, j).
    # Over many independent trajectories both statistics average 1; per trajectory the joint one
    # stays inside its chi-square bounds 95% of the time, the marginal mean (which assumes
    # independent estimates) falls outside them most of the time.
    rng = np.random.default_rng(7)
    n, q = 300, 0.01
    i = np.arange(1, n + 1)
    C = q * np.minimum.outer(i, i)
    Lc = np.linalg.cholesky(C)
    joint_in = marg_in = 0
    joint_vals, marg_vals = [], []
    trials = 200
    for _ in range(trials):
        e = Lc @ rng.standard_normal(n)
        a, (lo, hi) = metrics.anees_joint(e, C)
        joint_vals.append(a)
        joint_in += lo <= a <= hi
        m, (mlo, mhi) = metrics.anees([np.array([x]) for x in e], [np.array([[v]]) for v in np.diag(C)])
        marg_vals.append(m)
        marg_in += mlo <= m <= mhi
    assert np.mean(joint_vals) == pytest.approx(1.0, abs=0.02)
    # the marginal mean is unbiased too, but spreads so widely (std 1.2 per trajectory here, with
    # a heavy right tail; the joint 0.08) that 200 trajectories pin its mean only to about +-0.1
    # (1 sigma)
    assert np.mean(marg_vals) == pytest.approx(1.0, abs=0.35)
    assert np.std(marg_vals) > 5 * np.std(joint_vals)
    assert joint_in / trials > 0.9
    assert marg_in / trials < 0.4


def test_truth_label_follows_the_bearing_far_away():
    # Seen from the origin: landmark 2 at 6.18 m, landmark 4 at 3.07 m, 0.16 rad apart. A far
    # observation of landmark 2 whose range came out 1.63 m short (2.7 sigma, sigma_r 0.61 m)
    # lies in the plane nearer landmark 4; its bearing (sigma 7.6 mrad) says landmark 2.
    # (A case from the synthetic drive, seed 2, step 701.)
    from types import SimpleNamespace
    from cylslam.data import Dataset, Obs, Step
    from cylslam.metrics import truth_labels
    lm2 = (6.177 * np.cos(0.0619), 6.177 * np.sin(0.0619), "orange")
    lm4 = (3.070 * np.cos(-0.0969), 3.070 * np.sin(-0.0969), "orange")
    o = Obs(cls="orange", range_m=4.550, bearing_rad=0.0685,
            cov=np.array([[0.613 ** 2, 0.0], [0.0, 0.0076 ** 2]]))
    clutter = Obs(cls="orange", range_m=4.550, bearing_rad=0.30,
                  cov=np.array([[0.613 ** 2, 0.0], [0.0, 0.0076 ** 2]]))
    ds = Dataset(name="t", steps=[Step(t=0.0, seq=0, obs=[o, clutter], truth=np.zeros(3))],
                 truth_landmarks={2: lm2, 4: lm4})
    res = SimpleNamespace(assoc=[(0, o, 0), (0, clutter, 1)])
    assert truth_labels(ds, res) == [2, None]
