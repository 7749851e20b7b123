# SPDX-License-Identifier: BSD-3-Clause
"""The centroid's time-correlated bias (Params.bias_gm_sigma_px, the G states): the chain's marginal
covariance is the Gauss-Markov process's, hand-derived; the fit's log-likelihood is the dense
multivariate normal's; the fit recovers simulated parameters; and a Monte Carlo in which each
landmark's centroid error drifts over its views: with the constant bias state alone the landmarks
are over-confident, with the G states too they are consistent."""
import math

import gtsam
import numpy as np
import pytest

from cylslam.backend import G, Params, Slam, gm_chain_factor
from cylslam.centroid_noise import Sequence, fit, loglik
from cylslam.metrics import evaluate
from test_landmark_bias import _drive


def test_chain_marginals_are_the_process_covariance():
    sigma, tau = np.array([0.1, 0.2]), np.array([0.5, 2.0])
    t = np.array([0.0, 0.1, 0.25, 0.3, 1.0, 3.0])
    graph = gtsam.NonlinearFactorGraph()
    v = gtsam.Values()
    graph.add(gtsam.PriorFactorVector(G(0), np.zeros(2), gtsam.noiseModel.Diagonal.Variances(sigma ** 2)))
    for k in range(len(t)):
        v.insert(G(k), np.zeros(2))
        if k:
            phi = np.exp(-(t[k] - t[k - 1]) / tau)
            graph.add(gm_chain_factor(G(k - 1), G(k), phi, sigma ** 2 * (1 - phi ** 2)))
    m = gtsam.Marginals(graph, v)
    for a in range(len(t)):
        for b in range(len(t)):
            c = m.jointMarginalCovariance(gtsam.KeyVector([G(a), G(b)])).fullMatrix()
            want = sigma ** 2 * np.exp(-abs(t[a] - t[b]) / tau)
            blk = c[0:2, 2:4] if a != b else c[0:2, 0:2]
            assert np.allclose(np.diag(blk), want, rtol=1e-9)
            assert abs(blk[0, 1]) < 1e-15


def _dense_loglik(q, sigma, tau, white_scale, bias_scale):
    t = q.t_s
    c = (bias_scale * q.bias_var_px2 + sigma ** 2 * np.exp(-np.abs(t[:, None] - t[None, :]) / tau)
         + np.diag(white_scale * q.white_var_px2))
    _, logdet = np.linalg.slogdet(c)
    return -0.5 * (len(t) * math.log(2 * math.pi) + logdet + q.e_px @ np.linalg.solve(c, q.e_px))


def test_loglik_is_the_dense_gaussian():
    rng = np.random.default_rng(3)
    seqs = [Sequence(np.cumsum(rng.uniform(0.05, 0.5, n)), rng.normal(size=n) * 0.2,
                     rng.uniform(0.002, 0.02, n), 0.01) for n in (1, 7, 30)]
    for sigma, tau, ws, bs in ((0.1, 1.0, 1.0, 1.0), (0.3, 0.2, 0.5, 4.0), (0.0, 1.0, 2.0, 0.25)):
        want = sum(_dense_loglik(q, sigma, tau, ws, bs) for q in seqs)
        assert loglik(seqs, sigma, tau, ws, bs) == pytest.approx(want, rel=1e-10)


def _simulate(rng, sigma, tau, white_scale, n_seq=60, n=120, dt=1 / 15):
    seqs = []
    for _ in range(n_seq):
        t = np.arange(n) * dt
        white = rng.uniform(0.002, 0.006, n)
        bvar = 0.01
        g = np.empty(n)
        g[0] = rng.normal() * sigma
        phi = math.exp(-dt / tau)
        for k in range(1, n):
            g[k] = phi * g[k - 1] + rng.normal() * sigma * math.sqrt(1 - phi * phi)
        e = rng.normal() * math.sqrt(bvar) + g + rng.normal(size=n) * np.sqrt(white_scale * white)
        seqs.append(Sequence(t, e, white, bvar))
    return seqs


def test_fit_recovers_simulated_parameters():
    rng = np.random.default_rng(5)
    seqs = _simulate(rng, 0.12, 2.0, 0.7)
    r = fit(seqs, start=(0.05, 0.5, 1.0))
    # 60 sequences of 8 s: sigma and tau trade against each other (0.142 px and 3.0 s here)
    assert r["sigma_px"] == pytest.approx(0.12, rel=0.25)
    assert 2.0 / 1.6 < r["tau_s"] < 2.0 * 1.6
    assert r["white_scale"] == pytest.approx(0.7, rel=0.1)
    assert r["loglik"] > r["loglik_white_only"] + 100
    assert r["views"] == 60 * 120


@pytest.mark.parametrize("with_g", [False, True])
def test_drifting_bias_monte_carlo(with_g):
    rng = np.random.default_rng(17)
    var_white, var_bias = np.array([0.02, 0.02]), np.array([0.01, 0.01])
    sigma_g, tau_s = np.array([0.25, 0.3]), np.array([2.0, 3.0])
    lm, pose = [], []
    for _ in range(24 if with_g else 6):
        ds = _drive(rng, var_white, var_bias, drift=(sigma_g, tau_s))
        p = Params(calib_states=True, lm_bias="state", batch=True,
                   bias_gm_sigma_px=tuple(sigma_g) if with_g else (0.0, 0.0), bias_gm_tau_s=tuple(tau_s))
        res = Slam(p).run(ds)
        assert res.stats["gm_states"] == (4 * 80 if with_g else 0)
        m = evaluate(ds, res)
        lm.append(m["anees_landmarks_joint"])
        pose.append(m["anees_poses_joint"])
    if with_g:
        # 24 runs of 8 landmark dof: chi-square 192 / 192 (sd 0.10); poses 24 x 240 dof (sd 0.02)
        assert 0.7 < np.mean(lm) < 1.3
        assert 0.95 < np.mean(pose) < 1.05
    else:
        assert np.mean(lm) > 2.0


def test_options_are_checked():
    ds = _drive(np.random.default_rng(1), np.array([0.02, 0.02]), np.array([0.01, 0.01]), steps=3)
    with pytest.raises(ValueError, match="--bias-gm: the time-correlated bias goes with"):
        Slam(Params(calib_states=False, bias_gm_sigma_px=(0.1, 0.1))).run(ds)
    with pytest.raises(ValueError, match="two sigmas >= 0 px and two correlation times > 0 s"):
        Slam(Params(calib_states=True, bias_gm_sigma_px=(0.1, -0.1))).run(ds)
    with pytest.raises(ValueError, match="two sigmas >= 0 px and two correlation times > 0 s"):
        Slam(Params(calib_states=True, bias_gm_sigma_px=(0.1, 0.1), bias_gm_tau_s=(0.0, 1.0))).run(ds)


def test_a_log_without_the_bias_field_is_an_error():
    import os
    from cylslam.obslog import read_obslog
    ds = read_obslog(os.path.join(os.path.dirname(__file__), "fixtures", "frontend_calib_error.jsonl"))
    with pytest.raises(ValueError, match=r"frontend_calib_error.jsonl:\d+: --bias-gm needs the observation's bias_var_px2"):
        Slam(Params(calib_states=True, covariances=False, bias_gm_sigma_px=(0.1, 0.1))).run(ds)


def test_cauchy_chain_step_costs_the_kernel_s_loss():
    # a step of the drift r sigma off: Gaussian cost r^2 / 2, with the Cauchy kernel of scale k
    # k^2 / 2 log(1 + (r / k)^2) (GTSAM's Cauchy loss), so a jump of many sigmas costs little more
    # than a large step
    sig, phi = np.array([0.1, 0.2]), np.array([0.9, 0.5])
    q = sig ** 2 * (1 - phi ** 2)
    v = gtsam.Values()
    v.insert(G(0), np.array([0.3, -0.1]))
    step = np.array([6.0, 0.5]) * np.sqrt(q)            # 6 sigma in u, 0.5 in v
    v.insert(G(1), phi * np.array([0.3, -0.1]) + step)
    r2 = np.array([36.0, 0.25])
    assert gm_chain_factor(G(0), G(1), phi, q).error(v) == pytest.approx(0.5 * r2.sum(), rel=1e-9)
    k = 0.5
    want = 0.5 * k * k * math.log(1 + r2.sum() / k ** 2)
    assert gm_chain_factor(G(0), G(1), phi, q, cauchy_k=k).error(v) == pytest.approx(want, rel=1e-9)
