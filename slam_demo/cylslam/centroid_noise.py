# SPDX-License-Identifier: BSD-3-Clause
"""The centroid's error over one landmark's views, as the back end's bias states model it, and its
fit to residuals measured against the truth.

One axis (u or v) of one landmark's views at times t_k (s): the measured point less the image of
the landmark's centre is

    e_k = b + g_k + w_k

b the landmark's constant bias (prior N(0, bias_scale * bias_var), the frontend's `bias_var_px2`:
the back end's bias state B), g a first-order Gauss-Markov process of variance sigma^2 and
correlation exp(-|dt| / tau) (the back end's G states, `--bias-gm`), w white with variance
white_scale * (the frontend's centroid variance less bias_var) (`--white-scale`). `loglik` is the
exact Gaussian log-likelihood of the sequences under that model (a Kalman filter over (b, g));
`fit` maximises it over (sigma, tau, white_scale). What the frontend's per-frame variance cannot
see -- a residual that drifts with the viewing direction and range over seconds -- is what sigma
and tau measure; `scripts/fit_centroid_gm.py` takes the residuals from rendered drives with truth.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass
class Sequence:
    """One landmark's views on one axis, in time order."""
    t_s: np.ndarray          # view times, s (increasing)
    e_px: np.ndarray         # residual: measured point less the image of the centre, px
    white_var_px2: np.ndarray  # the frontend's centroid variance less bias_var, px^2
    bias_var_px2: float      # the prior variance of the landmark's constant bias, px^2


def loglik(seqs, sigma_px, tau_s, white_scale=1.0, bias_scale=1.0):
    """Log-likelihood of `seqs` (Sequence) under the model of the module's docstring."""
    s2 = float(sigma_px) ** 2
    total = 0.0
    ones = np.array([1.0, 1.0])
    for q in seqs:
        x = np.zeros(2)
        p = np.diag([bias_scale * q.bias_var_px2, s2])
        prev = None
        for t, e, w in zip(q.t_s, q.e_px, q.white_var_px2):
            if prev is not None:
                phi = math.exp(-abs(t - prev) / tau_s)
                x[1] *= phi
                p[0, 1] *= phi
                p[1, 0] *= phi
                p[1, 1] = phi * phi * p[1, 1] + s2 * (1.0 - phi * phi)
            prev = t
            ph = p @ ones
            s = ph @ ones + white_scale * w
            nu = e - x[0] - x[1]
            total -= 0.5 * (math.log(2.0 * math.pi * s) + nu * nu / s)
            k = ph / s
            x = x + k * nu
            p = p - np.outer(k, ph)
    return total


def fit(seqs, start=(0.1, 3.0, 1.0), bias_scale=1.0):
    """Maximum-likelihood (sigma_px, tau_s, white_scale) for `seqs` (Nelder-Mead on their logs from
    `start`). Returns a dict with those, the log-likelihood, that of the white model alone (sigma 0,
    white_scale fitted: what the frontend's per-frame variance says) and the count of views."""
    from scipy.optimize import minimize, minimize_scalar

    def neg(z):
        return -loglik(seqs, math.exp(z[0]), math.exp(z[1]), math.exp(z[2]), bias_scale)

    r = minimize(neg, np.log(np.asarray(start, float)), method="Nelder-Mead",
                 options=dict(xatol=0.01, fatol=0.5, maxiter=400))
    sigma, tau, white = (float(math.exp(v)) for v in r.x)
    w0 = minimize_scalar(lambda z: -loglik(seqs, 0.0, 1.0, math.exp(z), bias_scale),
                         bounds=(-3.0, 3.0), method="bounded")
    return dict(sigma_px=sigma, tau_s=tau, white_scale=white, loglik=-float(r.fun),
                loglik_white_only=-float(w0.fun), white_only_scale=float(math.exp(w0.x)),
                views=int(sum(len(q.e_px) for q in seqs)), sequences=len(seqs))
