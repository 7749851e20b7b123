# SPDX-License-Identifier: BSD-3-Clause
"""The GTSAM back end: Pose2 chain, one BearingRangeFactor2D per observation with its own
covariance, iSAM2 incrementally, a final batch Levenberg-Marquardt pass, data association.

Conventions
- Our observations are (range, bearing) with a 2x2 covariance in that order. GTSAM's
  BearingRange measurement is (bearing, range), so the covariance handed to GTSAM is
  P C P with P = [[0, 1], [1, 0]] (`to_gtsam_cov`).
- Pose2 tangent coordinates are (vx, vy, omega) in the body frame (GTSAM's local coordinates);
  the Jacobians below use them.
- Gauge: the first pose gets a tight prior (sigmas 1e-3 m, 1e-3 m, 1e-4 rad) at the true start pose
  when the data has one (`anchor="truth"`, the only use of truth in estimation: it fixes the
  world frame so that estimates and their covariances can be compared with truth), else at the
  origin.

Data association (`assoc="unknown"`): per frame, for the usable observations (flags & 0xB20 == 0,
a range, confidence >= conf_min): candidates are landmarks of the same class whose estimate lies
within `cand_radius` m of the observation's predicted world position. For the frame's current pose
and all candidates one iSAM2 joint marginal covariance Sigma is computed; each (observation,
candidate) pair gets the innovation nu = z - h(x, l) and S = H Sigma H^T + R, and
d2 = nu^T S^-1 nu. Pairs with d2 <= chi2_2(gate_p) may associate; an optimal assignment
(Hungarian, minimum total d2, at most one observation per landmark) decides, with a "no landmark"
option of cost chi2_2(gate_p) per observation. An unassigned observation starts a new landmark if
its smallest d2 over its candidates exceeds chi2_2(new_p) (or it has no candidate)
and its largest planar standard deviation is <= init_max_sigma (0.5 m: a near-horizon blob with a
range sigma of metres must not seed a landmark; it may still update one); otherwise it is dropped
(ambiguous / imprecise, counted). The candidate radius is cand_radius + 3 sigma of the
observation, keeping the `max_cands` (4) nearest. Known association (`assoc="known"`) uses the identities in
the data instead. Options (off by default; slam_demo/README.md has their measured effect): `joint`
replaces the Hungarian assignment by joint compatibility branch and bound (`_jcbb`), `exclusion`
lets an observation whose compatible landmarks are all taken in its frame start a landmark, and
`merge_every` merges duplicates (`_merge`).

Far observations (`far_bearing`): one dropped only as far is a bearing-only factor; with
`far_init` one that starts no landmark waits in a bearing track (`FarTracks`) until its rays
triangulate, and the landmark then starts from bearings alone (no range factor); `far_robust`
puts a robust kernel on the bearing-only factors.
"""
from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, field
from typing import Optional

import gtsam
import numpy as np

from .camera_model import range_bearing_model
from .data import FLAG_MERGED, FLAG_NO_RANGE, FLAG_NONLINEAR, FLAGS_REJECT, compose, rb_to_world, wrap

PERM = np.array([[0.0, 1.0], [1.0, 0.0]])
ROBUST_KERNELS = {"huber": gtsam.noiseModel.mEstimator.Huber, "cauchy": gtsam.noiseModel.mEstimator.Cauchy}


def X(i):
    return gtsam.symbol("x", i)


def L(j):
    return gtsam.symbol("l", j)


def to_gtsam_cov(cov_rb):
    """(range, bearing) covariance -> GTSAM's (bearing, range) order."""
    return PERM @ np.asarray(cov_rb, float) @ PERM


@functools.lru_cache(maxsize=256)
def chi2_2k(p, k):
    """Chi-square quantile for 2k degrees of freedom at probability p (the joint gate of k
    pairings), by scipy."""
    from scipy.stats import chi2
    return float(chi2.ppf(p, 2 * k))


def chi2_2dof(p):
    """Inverse CDF of chi-square with 2 degrees of freedom (exact)."""
    return -2.0 * math.log(1.0 - p)


def predict_rb(pose, lm):
    """Predicted (range, bearing) of landmark lm from pose and the 2x5 Jacobian with respect to
    [pose tangent (vx, vy, omega), landmark (x, y)], rows in (range, bearing) order."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    ex, ey = lm[0] - pose[0], lm[1] - pose[1]
    dx, dy = c * ex + s * ey, -s * ex + c * ey
    r2 = dx * dx + dy * dy
    r = math.sqrt(r2)
    b = math.atan2(dy, dx)
    drb_dd = np.array([[dx / r, dy / r], [-dy / r2, dx / r2]])
    dd = np.array([[-1.0, 0.0, dy, c, s], [0.0, -1.0, -dx, -s, c]])
    return np.array([r, b]), drb_dd @ dd


CALIB = gtsam.symbol("c", 0)   # calibration error (fx fy cx cy tilt yaw h s): one Vector8 for the run


def B(j):
    """Landmark j's centroid bias (du, dv) px: a Vector2 (Params.lm_bias)."""
    return gtsam.symbol("b", j)


def rb_jacobians(pose, lm):
    """Predicted (bearing, range) of landmark lm from pose (x, y, theta) and their Jacobians with
    respect to the pose (GTSAM's Pose2 retraction: body-frame (vx, vy, w)) and the landmark."""
    dx, dy = lm[0] - pose[0], lm[1] - pose[1]
    r2 = dx * dx + dy * dy
    r = np.sqrt(r2)
    c, s = np.cos(pose[2]), np.sin(pose[2])
    b = np.arctan2(dy, dx) - pose[2]
    hp = np.array([[(dy * c - dx * s) / r2, (-dy * s - dx * c) / r2, -1.0],
                   [-(dx * c + dy * s) / r, -(-dx * s + dy * c) / r, 0.0]])
    hl = np.array([[-dy / r2, dx / r2], [dx / r, dy / r]])
    return b, r, hp, hl


def calib_factor(pose_key, lm_key, o, noise, bias_keys=(), bearing_only=False):
    """An observation with the calibration error as a state (docs/uncertainty.md, "Constant
    calibration errors"): the frontend computed z with the nominal calibration, so
    z = h(pose, lm) - J delta + n, with delta = true - nominal calibration, J = o.jac_calib and
    n ~ N(0, o.cov_frame). Residual in GTSAM's (bearing, range) order.

    With bias keys, the landmark's centroid bias b = (du, dv) px (one per landmark, see
    Params.lm_bias) is a state too: range and bearing depend on the centroid through
    (u - cx, v - cy), so a centroid moved by b reads as a principal-point error of b:
    z = h - J delta - J_cxcy b + n. bias_keys: the bias states (Vector2, px) whose sum is b (the
    landmark's constant one and the observation's time-correlated one, G).
    bearing_only: the bearing row alone (noise then 1-D: the bearing's variance)."""
    jbr = np.vstack([o.jac_calib[1], o.jac_calib[0]])   # (bearing, range) rows
    jpx = jbr[:, 2:4]                                   # d(bearing, range)/d(cx, cy)
    rows = slice(0, 1) if bearing_only else slice(0, 2)

    def error(this, values, H):
        p = values.atPose2(pose_key)
        l = values.atPoint2(lm_key)
        d = values.atVector(CALIB)
        b, r, hp, hl = rb_jacobians((p.x(), p.y(), p.theta()), (l[0], l[1]))
        e = np.array([b, r]) - jbr @ d - np.array([o.bearing_rad, o.range_m])
        for bk in bias_keys:
            e = e - jpx @ values.atVector(bk)
        e[0] = (e[0] + np.pi) % (2 * np.pi) - np.pi
        if H is not None:
            H[0] = hp[rows]
            H[1] = hl[rows]
            H[2] = -jbr[rows]
            for n in range(len(bias_keys)):
                H[3 + n] = -jpx[rows]
        return e[rows]

    keys = [pose_key, lm_key, CALIB] + list(bias_keys)
    return gtsam.CustomFactor(noise, keys, error)


def calib_factor_exact(pose_key, lm_key, o, cov_frame, rbm, robust=None, bias_keys=(), bearing_only=False):
    """As calib_factor, with libcyl's camera model evaluated at the estimated calibration instead of
    its linearisation at the nominal one (rbm: camera_model.range_bearing_model). The predicted
    measurement is m(delta, b) = cyl_rb_eval(u - du, v - dv, nominal + delta), so z = h(pose, lm) + n
    holds however far the range is from linear in the calibration (far observations: the range goes
    as h / tan(depression), and the tilt is in the depression).

    The noise is the centroid's, which lives in the image: the residual is taken there,
    e = A(delta)^-1 (h(pose, lm) - m(delta, b)) px with A = d(bearing, range)/d(u, v) at the estimate
    (to first order the predicted minus the measured centroid), and its covariance is the frame
    covariance moved into the image at the nominal calibration, A0^-1 cov_frame A0^-T (the centroid's
    covariance, with the frontend's distortion terms). So the range's noise grows with the range the
    estimated calibration gives the pixel, not the nominal one's. The bias state enters with the
    identity (it is a pixel offset). Where the model has no range for a delta the optimiser tries (the
    ray at or above the horizon), the linearisation at the nominal calibration stands in.
    bearing_only: the residual's column (u) alone, with the centroid's u variance: a far
    observation's row (v) carries its range, which is far from linear there and drifts."""
    jbr = np.vstack([o.jac_calib[1], o.jac_calib[0]])   # (bearing, range) rows, at the nominal
    a0 = -jbr[:, 2:4]                                   # d(bearing, range)/d(u, v) = -d/d(cx, cy)
    a0i = np.linalg.inv(a0)
    cov_px = a0i @ to_gtsam_cov(cov_frame) @ a0i.T
    cov_px = 0.5 * (cov_px + cov_px.T)
    rows = slice(0, 1) if bearing_only else slice(0, 2)
    noise = gtsam.noiseModel.Gaussian.Covariance(cov_px[rows, rows])
    if robust is not None:
        noise = gtsam.noiseModel.Robust.Create(robust, noise)
    z = np.array([o.bearing_rad, o.range_m])
    cal = rbm.calib_columns

    def error(this, values, H):
        p = values.atPose2(pose_key)
        l = values.atPoint2(lm_key)
        d = values.atVector(CALIB)
        bb = np.zeros(2)
        for bk in bias_keys:
            bb = bb + values.atVector(bk)
        b, r, hp, hl = rb_jacobians((p.x(), p.y(), p.theta()), (l[0], l[1]))
        m = rbm.eval(o.u_px - bb[0], o.v_px - bb[1], d)
        if m is not None:
            zhat = np.array([m[1], m[0]])
            j = m[2][::-1]                               # (bearing, range) rows
            jd, a = j[:, cal], j[:, 0:2]
        else:
            jd, a = jbr, a0
            zhat = z + jd @ d - a @ bb
        e = np.array([b, r]) - zhat
        e[0] = wrap(e[0])
        ai = np.linalg.inv(a)[rows]
        if H is not None:
            H[0] = ai @ hp
            H[1] = ai @ hl
            H[2] = -ai @ jd
            for n in range(len(bias_keys)):
                H[3 + n] = np.eye(2)[rows]               # zhat(u - b): d e / d b = A^-1 A (A^-1 held, Gauss-Newton)
        return ai @ e

    keys = [pose_key, lm_key, CALIB] + list(bias_keys)
    return gtsam.CustomFactor(noise, keys, error)


def calib_prior(cov):
    """Prior N(0, cov) on the calibration error; parameters with zero variance (known exactly)
    get a tiny one (1e-12 of the unit) so that the prior stays invertible."""
    c = np.array(cov, float) + np.diag(np.where(np.diag(cov) > 0, 0.0, 1e-24))
    return gtsam.PriorFactorVector(CALIB, np.zeros(8), gtsam.noiseModel.Gaussian.Covariance(c))


def G(n):
    """The n-th used observation's time-correlated centroid bias (du, dv) px: a Vector2
    (Params.bias_gm_sigma_px; gm_chain_factor)."""
    return gtsam.symbol("g", n)


def gm_chain_factor(g_prev, g, phi, q_var, cauchy_k=0.0):
    """Two consecutive time-correlated biases of one landmark's observations, a first-order
    Gauss-Markov process per axis: g - phi g_prev ~ N(0, diag(q_var)), phi = exp(-dt / tau) and
    q_var = sigma^2 (1 - phi^2), so the process keeps its variance sigma^2 and its correlation
    exp(-|dt| / tau). cauchy_k > 0: a Cauchy kernel of that scale on the whitened increment (a
    drift whose steps have heavy tails: a jump -- the centroid of a landmark sliding behind
    something -- costs little more than a large step, and the drift takes it, not the poses)."""
    phi = np.asarray(phi, float)
    noise = gtsam.noiseModel.Diagonal.Variances(np.maximum(np.asarray(q_var, float), 1e-12))
    if cauchy_k > 0:
        noise = gtsam.noiseModel.Robust.Create(gtsam.noiseModel.mEstimator.Cauchy.Create(cauchy_k), noise)

    def error(this, values, H):
        if H is not None:
            H[0] = -np.diag(phi)
            H[1] = np.eye(2)
        return values.atVector(g) - phi * values.atVector(g_prev)

    return gtsam.CustomFactor(noise, [g_prev, g], error)


def Z(i):
    """Step i's time-correlated odometry error, unit variance per component (x, y, theta) and
    per exponential of the fitted correlation: a Vector of 3 values a term (Step.odom_gm)."""
    return gtsam.symbol("z", i)


def odom_factors(s, k_prev, k, z_prev, z, prev_has_state, scale=1.0, state=True):
    """The factors of step s's odometry from pose key k_prev to pose key k, and the new variables
    they need as (key, initial value) pairs.

    Without s.odom_gm (or with state False): one BetweenFactorPose2 with s.odom_cov (times scale^2).
    With it, the step's error is e = w + sum_j sd_j * z_j (per component x, y, theta): w white with
    covariance s.odom_gm[0], each z_j a unit-variance Gauss-Markov state shared in time (one per
    exponential of the fitted correlation), z_k = phi z_{k-1} + sqrt(1 - phi^2) n (its first value a
    N(0, 1) prior); sd and phi list the terms one after the other (3 values each). The factor on
    (x_{k-1}, x_k, z_k) has GTSAM's BetweenFactor residual Logmap(odom^-1 x_{k-1}^-1 x_k) minus
    sum_j sd_j * z_j: neighbouring steps' errors then point the same way, as they do on a real robot, where
    s.odom_cov only inflates each step's variance by its correlation sum. `scale` multiplies both
    parts (the gating pass's sigma scale).

    The state factors are Python (gtsam.CustomFactor): optimise graphs holding them with
    `batch_optimize(..., python_loop=True)`, never with iSAM2 or GTSAM's own optimisers, which hand
    every factor call a copy of all the values (pybind), O(n) a call."""
    inc = gtsam.Pose2(*s.odom)
    if s.odom_gm is None or not state:
        cov = np.asarray(s.odom_cov, float) * scale * scale
        return [gtsam.BetweenFactorPose2(k_prev, k, inc, gtsam.noiseModel.Gaussian.Covariance(cov))], []
    cov = np.asarray(s.odom_gm[0], float) * scale * scale
    sd = np.asarray(s.odom_gm[1], float) * scale
    phi = np.asarray(s.odom_gm[2], float)
    m = len(sd) // 3                            # Gauss-Markov terms: z = (z_1 (x, y, theta), z_2, ...)
    hz = -np.hstack([np.diag(sd[3 * j:3 * j + 3]) for j in range(m)])

    def error(this, values, H):
        h1 = np.zeros((3, 3), order="F")
        h2 = np.zeros((3, 3), order="F")
        hl = np.zeros((3, 3), order="F")
        t = values.atPose2(k_prev).between(values.atPose2(k), h1, h2)
        e = gtsam.Pose2.Logmap(inc.between(t), hl) + hz @ values.atVector(z)
        if H is not None:
            H[0] = hl @ h1
            H[1] = hl @ h2
            H[2] = hz
        return e

    out = [gtsam.CustomFactor(gtsam.noiseModel.Gaussian.Covariance(cov), [k_prev, k, z], error)]
    if prev_has_state:
        hp = -np.diag(phi)

        def chain(this, values, H):
            if H is not None:
                H[0] = hp
                H[1] = np.eye(3 * m)
            return values.atVector(z) - phi * values.atVector(z_prev)
        out.append(gtsam.CustomFactor(
            gtsam.noiseModel.Diagonal.Variances(np.maximum(1.0 - phi * phi, 1e-12)), [z_prev, z], chain))
    else:
        out.append(gtsam.PriorFactorVector(z, np.zeros(3 * m), gtsam.noiseModel.Unit.Create(3 * m)))
    return out, [(z, np.zeros(3 * m))]


def batch_optimize(graph, values, max_iter=100, python_loop=False):
    """Levenberg-Marquardt: (estimate, iterations). GTSAM's optimiser, or with python_loop (graphs
    with odometry states, `odom_factors`) the same iteration written here -- linearise, damp every
    variable by lambda I, solve, retract; lambda / 10 on a step that lowers the error, x 10
    otherwise; stop when the error falls by less than 1e-5 (relative or absolute) -- so that the
    values stay Python's own and the Python factors read them without a copy."""
    if not python_loop:
        lp = gtsam.LevenbergMarquardtParams()
        lp.setMaxIterations(max_iter)
        opt = gtsam.LevenbergMarquardtOptimizer(graph, values, lp)
        return opt.optimize(), opt.iterations()
    v = gtsam.Values(values)
    keys = list(v.keys())
    dims = [_dim(v, key) for key in keys]
    err = graph.error(v)
    lam = 1e-5
    it = 0
    while it < max_iter:
        it += 1
        gfg = graph.linearize(v)
        while True:
            damped = gfg.clone()
            for key, d in zip(keys, dims):
                damped.add(gtsam.JacobianFactor(key, math.sqrt(lam) * np.eye(d), np.zeros(d),
                                                gtsam.noiseModel.Unit.Create(d)))
            nv = v.retract(damped.optimize())
            nerr = graph.error(nv)
            if nerr <= err:
                break
            lam *= 10.0
            if lam > 1e10:
                return v, it
        done = err - nerr < 1e-5 or (err - nerr) < 1e-5 * err
        v, err = nv, nerr
        lam = max(lam / 10.0, 1e-10)
        if done:
            break
    return v, it


def _covs_by_observation(frames):
    """{id(observation): its covariance} over the frames' usable observations (Slam._run's
    `frames`: (step, observations, covariances))."""
    return {id(o): c for (_, u, cs) in frames for o, c in zip(u, cs)}


BIG = 1e9      # an assignment cost that stands for "not allowed" (Hungarian cost matrices)


def hungarian(cost):
    """Minimum-cost assignment of rows to distinct columns (rows <= cols). Returns col per row.
    SciPy's linear_sum_assignment (the Jonker-Volgenant algorithm)."""
    from scipy.optimize import linear_sum_assignment
    cost = np.asarray(cost, float)
    n, m = cost.shape
    assert n <= m
    rows, cols = linear_sum_assignment(cost)
    ans = [-1] * n
    for r, c in zip(rows, cols):
        ans[int(r)] = int(c)
    return ans


@dataclass
class Params:
    assoc: str = "auto"            # auto (known if the data has identities) | known | unknown
    conf_min: float = 0.5          # drop observations with confidence below this
    gate_p: float = 0.99           # association gate, chi-square 2 dof
    new_p: float = 0.9999          # a new landmark only when every landmark is beyond this
    cand_radius: float = 2.0       # m, Euclidean pre-selection of candidates (+ 3 sigma of the obs)
    init_max_sigma: float = 0.5    # m, no new landmark from an observation less precise than this
    max_cands: int = 4             # at most this many nearest candidates per observation
    exclusion: bool = False        # an unassigned observation whose every compatible landmark is
                                   # taken by another observation of its frame starts a landmark
    joint: bool = False            # unknown association: joint compatibility (JCBB) instead of
                                   # the Hungarian assignment of individual distances
    init_views: int = 1            # unknown association: a landmark starts once this many views
                                   # (from distinct steps) agree; until then they wait in a
                                   # candidate buffer (1: at once)
    init_window: int = 50          # steps a candidate waits for its next view before it is dropped
    reassoc: int = 0               # unknown association: at most this many batch re-association
                                   # passes after the batch solve (pairings made again at the whole
                                   # run's estimate, duplicates merged; _reassociate); 0: none
    starts: tuple = (1.0,)         # unknown association with reassoc: one online pass per entry,
                                   # its odometry sigmas (for the gating of that pass only) times
                                   # the entry; after re-association under the nominal sigmas the
                                   # run of least penalised cost is kept (Slam.run)
    merge_every: int = 0           # unknown association: every N steps, two landmarks of a class
                                   # never seen in one frame whose difference is inside the gate
                                   # (joint marginal) become one; 0: never
    reject_flags: int = FLAGS_REJECT  # obs.flags bits that drop an observation (format: 0xB20)
    max_range_rel_sigma: Optional[float] = None  # drop an observation whose range sigma exceeds this
                                   # times its range (its range is then far from Gaussian); None: keep
    robust: str = "none"           # none | huber | cauchy
    huber_k: float = 1.345         # the kernel's threshold k on the whitened residual (Huber or Cauchy)
    merged_var_scale: float = 1.0  # a merged blob's (flag 0x010: more than one 4-connected
                                   # component; not a grouped landmark of several bands) frame
                                   # covariance times this (cov_frame, and its share of cov); the
                                   # calibration's share is the same as any view's
    fixed_cov: Optional[np.ndarray] = None   # replaces every observation covariance (r, b order)
    fixed_frame_cov: Optional[np.ndarray] = None  # with calib_states: replaces every observation's
                                   # frame covariance (the centroid noise, less the bias its state
                                   # carries), the calibration's part and the states kept (r, b order)
    anchor: str = "truth"          # truth | origin
    prior_sigmas: tuple = (1e-3, 1e-3, 1e-4)
    update_every: int = 10         # iSAM2 update at least every N steps (and every observed one)
    batch: bool = True             # final batch Levenberg-Marquardt
    covariances: bool = True       # compute marginals after the batch pass
    calib_states: bool = False     # estimate the calibration error (constant over the run) as a state
    calib_model: str = "linear"    # with calib_states, how an observation depends on that error:
                                   # linear (the log's jac_calib at the nominal calibration) | exact
                                   # (libcyl's camera model evaluated at the estimate through the cyl
                                   # binding, residual in the image: calib_factor_exact)
    lm_bias: str = "auto"          # with calib_states, the centroid's residual bias (obs.bias_var_px2):
                                   # state (one (du, dv) px state per landmark shared by all its
                                   # observations, prior from the log's bias_var_px2 of the
                                   # observation that starts it, taken out of each cov_frame) |
                                   # none (white noise like the rest of cov_frame) | auto (state
                                   # where the observation that starts a landmark has the field)
    bias_gm_sigma_px: tuple = (0.0, 0.0)  # with a bias state: the centroid's time-correlated bias
                                   # (u, v) px, a Gauss-Markov state per observation chained along each
                                   # landmark's observations (G, gm_chain_factor); (0, 0): none
    bias_gm_tau_s: tuple = (3.0, 10.0)    # its correlation time (u, v), s
    white_scale: tuple = (1.0, 1.0)       # with the time-correlated bias: the frame's white centroid
                                   # variance (the log's less the bias's) times this (u, v)
    bias_gm_cauchy_k: float = 0.0  # > 0: a Cauchy kernel of this scale on the drift's whitened steps
    far_bearing: bool = False      # an observation dropped only for the frontend's non-linear flag
                                   # (0x400) or max_range_rel_sigma is kept for its bearing alone (the
                                   # image column with calibration states); it starts no landmark
    far_bearing_var_scale: float = 1.0  # with calibration states, that bearing's variance (the
                                   # frame's) times this; the fixed-covariance runs keep theirs
    far_bearing_every_s: float = 0.0  # > 0: of one landmark's far bearings, one at most every this
                                   # many seconds (consecutive views repeat the centroid's drift,
                                   # and hundreds of them turn a small error of their variance
                                   # into an over-confident trajectory); the others are dropped
    far_robust: str = "none"       # none | huber | cauchy: the kernel on the bearing-only factors
                                   # (scale huber_k; `robust` covers them too when set). A far
                                   # landmark partly hidden by something in front moves its
                                   # centroid by a share of a pixel long before its box shows it
                                   # (CYL_OBS_PARTIAL), tens of the bearing's sigmas
    far_init: bool = False         # with far_bearing: a far observation that starts no landmark
                                   # waits in a bearing track (FarTracks); a track whose bearings,
                                   # at the poses' current estimates, triangulate with enough
                                   # parallax starts a landmark from its bearings alone
    far_init_parallax_deg: float = 5.0   # the spread of a track's rays needed to start it, degrees
    far_init_views: int = 5        # and at least this many views from distinct steps
    far_init_window: int = 150     # steps a track waits for its next view before it is dropped
    far_init_clear_m: float = 0.5  # a track triangulated nearer than this to a mapped landmark of
                                   # its class is dropped (that landmark's far views gated badly)
    far_init_range_scale: float = 2.0   # a view joins the track whose point is inside the gate of
                                   # its range-bearing point, the range's sigma times this (a far
                                   # range is biased: it places views, it enters no factor)

    def check(self):
        """The batch re-association's and the starts' constraints: ValueError naming the option
        (the command line's flags) when they are not met."""
        if self.reassoc < 0:
            raise ValueError(f"--reassoc {self.reassoc}: must be >= 0")
        if self.reassoc and not self.batch:
            raise ValueError(f"--reassoc {self.reassoc}: batch re-association needs the batch pass (not --no-batch)")
        if self.reassoc and self.calib_states and self.fixed_cov is None:
            raise ValueError(f"--reassoc {self.reassoc}: batch re-association cannot run with --calib-states")
        if not self.starts or any(not (x > 0) for x in self.starts):
            raise ValueError(f"--starts {self.starts!r}: every odometry sigma scale must be > 0")
        if tuple(self.starts) != (1.0,) and not self.reassoc:
            raise ValueError("--starts needs --reassoc (the re-association scores the passes)")
        sig, tau = np.asarray(self.bias_gm_sigma_px, float), np.asarray(self.bias_gm_tau_s, float)
        if sig.shape != (2,) or tau.shape != (2,) or np.any(~(sig >= 0)) or np.any(~(tau > 0)):
            raise ValueError(f"--bias-gm {tuple(sig)} / --bias-gm-tau {tuple(tau)}: two sigmas >= 0 px "
                             "and two correlation times > 0 s")
        if not (self.merged_var_scale > 0):
            raise ValueError(f"--merged-var-scale {self.merged_var_scale}: must be > 0")
        if not (self.far_bearing_var_scale > 0):
            raise ValueError(f"--far-bearing-scale {self.far_bearing_var_scale}: must be > 0")
        if self.far_robust not in ("none",) + tuple(ROBUST_KERNELS):
            raise ValueError(f"--far-robust {self.far_robust!r}: none, huber or cauchy")
        if self.far_init and not self.far_bearing:
            raise ValueError("--far-init needs --far-bearing (a track's landmark lives on bearings)")
        if not (self.far_init_parallax_deg > 0) or self.far_init_views < 2 or self.far_init_window < 1 \
                or not (self.far_init_range_scale > 0):
            raise ValueError(f"--far-init-parallax {self.far_init_parallax_deg} / --far-init-views "
                             f"{self.far_init_views} / --far-init-window {self.far_init_window} / "
                             f"--far-init-range-scale {self.far_init_range_scale}: parallax > 0 deg, "
                             "views >= 2, window >= 1 step, range scale > 0")
        if not (self.far_bearing_every_s >= 0):
            raise ValueError(f"--far-bearing-every {self.far_bearing_every_s}: must be >= 0 s")
        if np.any(sig > 0) and (not self.calib_states or self.lm_bias == "none"):
            raise ValueError("--bias-gm: the time-correlated bias goes with the landmark's bias state "
                             "(--calib-states, and not --lm-bias none)")


@dataclass
class Result:
    poses: np.ndarray                     # (N, 3) final estimate
    pose_cov: Optional[np.ndarray]        # (N, 3, 3) or None
    isam_poses: np.ndarray                # (N, 3) iSAM2 estimate before the batch pass
    lms: np.ndarray                       # (M, 2)
    lm_cov: Optional[np.ndarray]          # (M, 2, 2)
    lm_class: list
    lm_ids: list                          # known identity per landmark (or None)
    assoc: list                           # (step index, Obs, landmark index) per used observation
    stats: dict = field(default_factory=dict)
    info: Optional["Information"] = None  # the information matrix at the estimate (joint NEES)
    lm_keys: Optional[list] = None        # the graph key of each landmark (L(j) when None)


def drop_reason(o, p):
    """Why an observation is not used ("dropped_flags", "dropped_no_range", "dropped_confidence",
    "dropped_far"), or None: the one rule for every run. With p.far_bearing an observation dropped
    only as far (bearing_only) is used."""
    if o.flags & p.reject_flags & ~(FLAG_NONLINEAR if p.far_bearing else 0):
        return "dropped_flags"
    if (o.flags & FLAG_NO_RANGE) or o.range_m <= 0:
        return "dropped_no_range"
    if o.confidence < p.conf_min:
        return "dropped_confidence"
    if not p.far_bearing and is_far(o, p):
        return "dropped_far"
    return None


def is_far(o, p):
    """The observation's range is too far from linear to use: the frontend's non-linear flag when
    the run rejects it, or a range sigma beyond p.max_range_rel_sigma of the range."""
    return bool(o.flags & p.reject_flags & FLAG_NONLINEAR) or (
        p.max_range_rel_sigma is not None and math.sqrt(max(o.cov[0, 0], 0.0)) > p.max_range_rel_sigma * o.range_m)


def planar_sigma(o, cov):
    """The observation's largest standard deviation in the plane, m (cov: (range, bearing))."""
    return math.sqrt(max(cov[0, 0], o.range_m ** 2 * cov[1, 1]))


def bearing_only(o, p):
    """The run uses this observation for its bearing alone (Params.far_bearing and a far one)."""
    return p.far_bearing and is_far(o, p)


def frame_scale(o, p):
    """The factor on an observation's frame covariance: Params.merged_var_scale for a merged blob
    (CYL_BLOB_MERGED, 0x010) that is not a grouped landmark of several bands (whose bands are
    merged by design), else 1."""
    return p.merged_var_scale if o.flags & FLAG_MERGED and not o.grouped else 1.0


class Slam:
    def __init__(self, params: Params, progress=None, on_step=None):
        """on_step(i, seq, t, pose, used, isam, lms_init): called after each step as the run
        goes (the live view): `pose` the newest pose estimate, `used` the (observation, landmark
        index) pairs added at this step, `isam` the solver (for landmark estimates)."""
        self.p = params
        self.progress = progress
        self.on_step = on_step

    def _odom_noise(self, cov):
        return gtsam.noiseModel.Gaussian.Covariance(np.asarray(cov, float))

    def _robust(self, name=None):
        """The robust kernel observation factors are wrapped in (Params.robust, or `name`), or None."""
        name = self.p.robust if name is None else name
        if name in ROBUST_KERNELS:
            return ROBUST_KERNELS[name].Create(self.p.huber_k)
        if name != "none":
            raise ValueError(f"unknown robust kernel {name!r}")
        return None

    def _obs_noise(self, cov_rb):
        g = gtsam.noiseModel.Gaussian.Covariance(to_gtsam_cov(cov_rb))
        k = self._robust()
        return g if k is None else gtsam.noiseModel.Robust.Create(k, g)

    def _plain_factor(self, k, j, o, c):
        """An observation's factor without calibration states, covariance c (range, bearing):
        range and bearing, or the bearing alone for a far one (Params.far_bearing)."""
        if bearing_only(o, self.p):
            return gtsam.BearingFactor2D(X(k), L(j), gtsam.Rot2(o.bearing_rad), self._bearing_noise(c))
        return gtsam.BearingRangeFactor2D(X(k), L(j), gtsam.Rot2(o.bearing_rad), o.range_m, self._obs_noise(c))

    def _bearing_noise(self, cov_rb):
        """A bearing-only factor's noise: the bearing's variance (cov_rb in (range, bearing) order)."""
        g = gtsam.noiseModel.Isotropic.Sigma(1, math.sqrt(max(cov_rb[1, 1], 1e-18)))
        k = self._far_robust()
        return g if k is None else gtsam.noiseModel.Robust.Create(k, g)

    def _far_robust(self):
        """The robust kernel bearing-only factors are wrapped in (Params.robust when set, else
        Params.far_robust), or None."""
        return self._robust(self.p.far_robust if self.p.robust == "none" else None)

    def _bias_prior(self, o, use_calib):
        """The prior variance (u, v) px^2 of a new landmark's centroid-bias state, or None for no
        state (Params.lm_bias): the variance the frontend gives the bias of the observation that
        starts the landmark."""
        p = self.p
        if not use_calib or p.lm_bias == "none":
            return None
        if o.bias_var_px2 is None:
            if p.lm_bias == "state":
                raise ValueError(f"{o.where}: --lm-bias state needs the observation's bias_var_px2")
            return None
        return np.maximum(o.bias_var_px2, 1e-12)

    def run(self, ds) -> Result:
        """SLAM on a data set. With unknown association, batch re-association and several `starts`,
        one run per start; each run's pairings, re-associated and solved under the nominal odometry
        sigmas, are scored by the negative log-likelihood of that solution: the graph's error, the
        cost of the "no landmark" option (chi2_2(gate_p) / 2) for each observation left unpaired,
        and a BIC penalty of ln(pairings) for each landmark (2 coordinates, half ln n each); the
        least is kept. Online association is greedy: a pairing made with the pose as uncertain as it
        was at that step is not undone, and on clustered landmarks which pairing the gate lets
        through depends on the odometry's sigmas; the whole-run likelihood, not the gate, decides
        between the outcomes."""
        p = self.p
        p.check()
        t0 = time.perf_counter()
        best = self._run(ds, p.starts[0])
        if len(p.starts) == 1 or best.stats["association"] != "unknown":
            return best
        tried = [(p.starts[0], best.stats["assoc_cost"], len(best.lms))]
        for scale in p.starts[1:]:
            res = self._run(ds, scale)
            tried.append((scale, res.stats["assoc_cost"], len(res.lms)))
            if res.stats["assoc_cost"] < best.stats["assoc_cost"]:
                best = res
        best.stats["starts"] = [{"odom_sigma_scale": x, "cost": round(c, 2), "landmarks": m} for x, c, m in tried]
        best.stats["start_chosen"] = best.stats["odom_sigma_scale"]
        best.stats["t_total_s"] = round(time.perf_counter() - t0, 3)
        return best

    def _run(self, ds, scale) -> Result:
        p = self.p
        t0 = time.perf_counter()
        mode = p.assoc
        if mode == "auto":
            if ds.known_ids:
                mode = "known"
            elif any(o.lm_id is not None for st_ in ds.steps for o in st_.obs):
                mode = "mixed"   # identities where the source read them, gating elsewhere
            else:
                mode = "unknown"
        if mode == "known" and not ds.known_ids:
            raise ValueError("known association requested but the observations carry no identities")
        steps = ds.steps
        n = len(steps)
        isam_params = gtsam.ISAM2Params()
        isam = gtsam.ISAM2(isam_params)
        graph = gtsam.NonlinearFactorGraph()       # everything, for the batch pass
        new_f = gtsam.NonlinearFactorGraph()
        new_v = gtsam.Values()
        if p.anchor == "truth" and steps[0].truth is not None:
            start = np.array(steps[0].truth, float)
        else:
            start = np.zeros(3)
        f = gtsam.PriorFactorPose2(X(0), gtsam.Pose2(*start),
                                   gtsam.noiseModel.Diagonal.Sigmas(np.array(p.prior_sigmas)))
        graph.add(f)
        new_f.add(f)
        base_f = [f]
        # the odometry's correlated error as states (odom_factors) where the steps carry them: in
        # the batch graph, but never in iSAM2 (online, each step's inflated variance), and with
        # unknown association and re-association only in the last solve, the pairings made with
        # the inflated model (each re-association pass re-solves the whole graph)
        with_states = any(st_.odom_gm is not None for st_ in steps)
        states_in_batch = with_states and not (mode == "unknown" and p.reassoc)
        base_states = [f]                   # the prior and the odometry with states (the last solve)
        z_init = []                         # the odometry states' (key, initial value)
        frames = []
        new_v.insert(X(0), gtsam.Pose2(*start))
        use_calib = p.calib_states and p.fixed_cov is None
        if use_calib:
            if getattr(ds, "calib_cov", None) is None:
                raise ValueError("calibration states need the log header's camera.calib_cov")
            f = calib_prior(ds.calib_cov)
            graph.add(f)
            new_f.add(f)
            new_v.insert(CALIB, np.zeros(8))
        rbm = None
        if p.calib_model not in ("exact", "linear"):
            raise ValueError(f"unknown calibration model {p.calib_model!r}")
        if use_calib and p.calib_model == "exact":
            rbm, why = range_bearing_model(getattr(ds, "header", None))
            if rbm is None:
                raise ValueError(f"--calib-model exact: {why}")
        if p.lm_bias not in ("auto", "none", "state"):
            raise ValueError(f"unknown landmark bias model {p.lm_bias!r}")
        lm_bias = {}                        # landmark -> its bias state's prior variance (u, v) px^2, or None
        lm_gm = {}                          # landmark -> (its latest time-correlated bias key, that step's t)
        gm_sig = np.asarray(p.bias_gm_sigma_px, float)     # (Params.check has checked them)
        gm_tau = np.asarray(p.bias_gm_tau_s, float)
        white_scale = np.asarray(p.white_scale, float)
        # the fixed-covariance runs replace the whole covariance: no drift states there
        use_gm = bool(np.any(gm_sig > 0)) and use_calib
        cur = start.copy()                  # current estimate of the newest pose
        lms_init = []                       # initial/latest estimate per landmark
        lm_class, lm_ids = [], []
        id_to_lm = {}
        by_class = {}
        assoc = []
        st = dict(obs_total=0, dropped_flags=0, dropped_no_range=0, dropped_confidence=0, dropped_far=0,
                  dropped_ambiguous=0, dropped_imprecise=0, used=0, new_landmarks=0, isam_updates=0,
                  marginal_calls=0, new_by_exclusion=0, dropped_unconfirmed=0, association=mode, by_identity=0, bias_states=0, exact_factors=0, gm_states=0,
                  bearing_only=0, dropped_far_new=0, dropped_far_decimated=0, far_landmarks=0,
                  far_tracks_rejected=0)
        last_update = 0
        merged_into = {}                    # landmark -> the landmark it was merged into
        co_seen = set()                     # (j, k), j < k: landmarks observed in one frame
        step_lms = {}                       # step -> the landmarks observed at it
        last_merge = 0                      # the step of the last search for duplicates
        gate = chi2_2dof(p.gate_p)
        new_thr = chi2_2dof(p.new_p)
        pending = CandidateBuffer(p.init_views, p.init_window, gate)
        tracks = FarTracks(p, gate)

        # a landmark's start and an observation's factor; `i`, `here`, `new_f` and `new_v` are
        # read from the step being processed when they are called
        def new_landmark(o, pos):
            j = len(lms_init)
            lms_init.append(np.asarray(pos, float))
            lm_class.append(o.cls)
            lm_ids.append(o.lm_id)
            by_class.setdefault(o.cls, []).append(j)
            if o.lm_id is not None and mode in ("known", "mixed"):
                id_to_lm[o.lm_id] = j
            new_v.insert(L(j), gtsam.Point2(*pos))
            var = self._bias_prior(o, use_calib)
            lm_bias[j] = var
            if var is not None:
                new_v.insert(B(j), np.zeros(2))
                f = gtsam.PriorFactorVector(B(j), np.zeros(2), gtsam.noiseModel.Diagonal.Variances(var))
                graph.add(f)
                new_f.add(f)
                st["bias_states"] += 1
            st["new_landmarks"] += 1
            return j

        far_last = {}                       # landmark -> the time of its last far bearing used

        def add_observation(k, o, c, j):
            far = bearing_only(o, p)
            if far and p.far_bearing_every_s > 0:
                t = steps[k].t
                if j in far_last and t - far_last[j] < p.far_bearing_every_s:
                    st["dropped_far_decimated"] += 1
                    return
                far_last[j] = t
            if use_calib:
                if o.jac_calib is None:
                    raise ValueError(f"{o.where}: calibration states need jac_calib and cov_frame")
                cf = o.cov_frame * frame_scale(o, p)
                if lm_bias[j] is not None and o.bias_var_px2 is not None:
                    # the bias is the landmark's state now, not noise of this frame: as much of
                    # it as the state's prior covers
                    jpx = o.jac_calib[:, 2:4]
                    cf = cf - jpx @ np.diag(np.minimum(o.bias_var_px2, lm_bias[j])) @ jpx.T
                    if use_gm:
                        # the rest is the frame's white noise and the time-correlated bias: the
                        # white part, scaled, stays here; the other is the G state's
                        ji = np.linalg.inv(jpx)
                        var_px = np.maximum(np.diag(ji @ cf @ ji.T), 1e-8) * white_scale
                        cf = jpx @ np.diag(var_px) @ jpx.T
                if p.fixed_frame_cov is not None:
                    cf = p.fixed_frame_cov
                elif far:
                    cf = cf * p.far_bearing_var_scale   # (the fixed-covariance runs keep theirs)
                bk = []
                if use_gm and lm_bias[j] is None:
                    raise ValueError(f"{o.where}: --bias-gm needs the observation's bias_var_px2 (the "
                                     "landmark's bias state)")
                if lm_bias[j] is not None:
                    bk = [B(j)]
                    if use_gm:
                        t = steps[k].t
                        prev = lm_gm.get(j)
                        if prev is not None and t == prev[1]:
                            gk = prev[0]             # two blobs of one landmark in one frame
                        else:
                            gk = G(st["gm_states"])
                            st["gm_states"] += 1
                            new_v.insert(gk, np.zeros(2))
                            if prev is None:
                                fg = gtsam.PriorFactorVector(gk, np.zeros(2), gtsam.noiseModel.Diagonal.Variances(
                                    np.maximum(gm_sig ** 2, 1e-12)))
                            else:
                                phi = np.exp(-abs(t - prev[1]) / gm_tau)
                                fg = gm_chain_factor(prev[0], gk, phi, gm_sig ** 2 * (1 - phi ** 2),
                                                     p.bias_gm_cauchy_k)
                            graph.add(fg)
                            new_f.add(fg)
                            lm_gm[j] = (gk, t)
                        bk.append(gk)
                if rbm is not None:
                    if o.u_px is None:
                        raise ValueError(f"{o.where}: --calib-model exact needs the observation's u_px, v_px")
                    f = calib_factor_exact(X(k), L(j), o, cf, rbm, self._far_robust() if far else self._robust(), bk,
                                           bearing_only=far)
                    st["exact_factors"] += 1
                else:
                    noise = self._bearing_noise(cf) if far else self._obs_noise(cf)
                    f = calib_factor(X(k), L(j), o, noise, bk, bearing_only=far)
            else:
                f = self._plain_factor(k, j, o, c)
            if far:
                st["bearing_only"] += 1
            graph.add(f)
            new_f.add(f)
            assoc.append((k, o, j))
            if k == i:
                here.append((o, j))
            seen = step_lms.setdefault(k, set())
            co_seen.update((min(j, x), max(j, x)) for x in seen if x != j)
            seen.add(j)
            st["used"] += 1

        for i, s in enumerate(steps):
            if self.progress:
                self.progress(i + 1, n)
            if i > 0:
                if s.odom is None:
                    raise ValueError(f"step {i} has no odometry")
                # iSAM2, online, has each step's inflated variance; the batch graph the odometry's
                # correlated error as states where the step carries them (odom_factors). The
                # gating scale is this pass's only: base_f (the re-association's) is unscaled
                keys = (X(i - 1), X(i), Z(i - 1), Z(i), steps[i - 1].odom_gm is not None)
                online = odom_factors(s, *keys, scale, state=False)[0]
                if with_states:
                    fs, vs = odom_factors(s, *keys)
                    base_states.extend(fs)
                    z_init.extend(vs)
                if states_in_batch:
                    base_f.extend(fs)
                    batch = fs if scale == 1.0 else odom_factors(s, *keys, scale)[0]
                else:
                    base_f.extend(online if scale == 1.0 else odom_factors(s, *keys, state=False)[0])
                    batch = online
                for f in batch:
                    graph.add(f)
                for f in online:
                    new_f.add(f)
                cur = compose(cur, s.odom)
                new_v.insert(X(i), gtsam.Pose2(*cur))
            usable = []
            for o in s.obs:
                st["obs_total"] += 1
                why = drop_reason(o, p)
                if why:
                    st[why] += 1
                else:
                    usable.append(o)
            need = bool(usable) and (mode == "unknown" or
                                     (mode == "mixed" and any(o.lm_id is None for o in usable)))
            if need or i - last_update >= p.update_every or i == n - 1:
                isam.update(new_f, new_v)
                st["isam_updates"] += 1
                new_f = gtsam.NonlinearFactorGraph()
                new_v = gtsam.Values()
                last_update = i
                e = isam.calculateEstimatePose2(X(i))
                cur = np.array([e.x(), e.y(), e.theta()])
                if mode == "unknown" and p.merge_every and i - last_merge >= p.merge_every:
                    last_merge = i
                    ties = gtsam.NonlinearFactorGraph()
                    for f in self._merge(isam, by_class, merged_into, co_seen, gate, st):
                        graph.add(f)
                        ties.add(f)
                    if ties.size():          # at once: this frame is associated on the merged map
                        isam.update(ties, gtsam.Values())
                        st["isam_updates"] += 1
                        e = isam.calculateEstimatePose2(X(i))
                        cur = np.array([e.x(), e.y(), e.theta()])
            if not usable:
                if self.on_step:
                    self.on_step(i, s.seq, s.t, cur, [], isam, lms_init)
                continue
            covs = [p.fixed_cov if p.fixed_cov is not None else
                    (o.cov - o.cov_frame + p.fixed_frame_cov
                     if use_calib and p.fixed_frame_cov is not None and o.cov_frame is not None else
                     o.cov + (frame_scale(o, p) - 1.0) * o.cov_frame if o.cov_frame is not None else o.cov)
                    for o in usable]
            frames.append((i, usable, covs))
            if mode == "known":
                # identities are given: no gating, and a landmark first seen creates it
                targets = [id_to_lm.get(o.lm_id, -1) for o in usable]
            elif mode == "mixed":
                # an observation with an identity is associated by it; the others are gated
                # against every landmark of their class, those made from identities included
                targets = [id_to_lm.get(o.lm_id, -1) if o.lm_id is not None else None for o in usable]
                rest = [k for k, o in enumerate(usable) if o.lm_id is None]
                if rest:
                    got = self._associate(isam, i, cur, [usable[k] for k in rest], [covs[k] for k in rest],
                                          lms_init, lm_class, by_class, gate, new_thr, st)
                    for k, t in zip(rest, got):
                        targets[k] = t
                st["by_identity"] += len(usable) - len(rest)
            else:
                targets = self._associate(isam, i, cur, usable, covs, lms_init, lm_class,
                                          by_class, gate, new_thr, st)
            here = []                       # (observation, landmark) used at this step

            st["dropped_unconfirmed"] += pending.expire(i)
            st["dropped_far_new"] += tracks.expire(i)
            for o, c, j in zip(usable, covs, targets):
                far = bearing_only(o, p)
                if j == -3:
                    st["dropped_ambiguous"] += 1
                    continue
                if j == -4:
                    st["dropped_imprecise"] += 1
                    continue
                if mode == "known" or (mode == "mixed" and o.lm_id is not None):
                    j = id_to_lm.get(o.lm_id, -1)   # may have been created earlier this frame
                elif j == -1 and p.init_views > 1 and not far:
                    cand = pending.add(i, cur, o, c)
                    if cand is None:
                        continue                    # waits in the candidate buffer
                    j = new_landmark(o, pending.mean(cand)[0])
                    for (k, ok, ck) in cand["views"]:
                        add_observation(k, ok, ck, j)
                    continue
                if j == -1 and far:
                    if not p.far_init:
                        st["dropped_far_new"] += 1  # a bearing alone starts no landmark
                        continue
                    by_id = mode == "known" or (mode == "mixed" and o.lm_id is not None)
                    if by_id and planar_sigma(o, c) > p.init_max_sigma:
                        st["dropped_imprecise"] += 1    # the rule gating applies (_associate's -4)
                        continue
                    tr = tracks.add(i, cur, o, c, key=o.lm_id if by_id else None)
                    if tr is None:
                        continue                    # waits in its track
                    poses = {k: (cur if k == i else _pose_of(isam, new_v, k)) for k, _, _ in tr["views"]}
                    pt = tracks.triangulate(tr, poses)
                    if pt is None:
                        continue                    # not yet: waits for more views
                    tracks.remove(tr)
                    if any(math.hypot(*(lms_init[x] - pt)) < p.far_init_clear_m
                           for x in by_class.get(o.cls, []) if x not in merged_into):
                        st["far_tracks_rejected"] += 1
                        st["dropped_far_new"] += len(tr["views"])
                        continue
                    j = new_landmark(tr["views"][0][1], pt)
                    st["far_landmarks"] += 1
                    for (k, ok, ck) in tr["views"]:
                        add_observation(k, ok, ck, j)
                    continue
                if j == -1:
                    j = new_landmark(o, rb_to_world(cur, o.range_m, o.bearing_rad))
                add_observation(i, o, c, j)
            if self.on_step:
                self.on_step(i, s.seq, s.t, cur, here, isam, lms_init)
        if new_f.size() or new_v.size():
            isam.update(new_f, new_v)
            st["isam_updates"] += 1
        est = isam.calculateEstimate()
        t_isam = time.perf_counter() - t0
        st["merged_landmarks"] = len(merged_into)
        st["dropped_unconfirmed"] += pending.expire(n + p.init_window)
        st["dropped_far_new"] += tracks.expire(n + p.far_init_window)
        isam_poses = _poses(est, n)
        if states_in_batch:
            for key, v in z_init:
                est.insert(key, v)
        st["odometry_states"] = len(z_init)
        if p.batch:
            est, st["batch_iterations"] = batch_optimize(graph, est, python_loop=states_in_batch)
        removed = set()
        if p.reassoc and mode == "unknown":
            graph, est, assoc, removed = self._reassociate(frames, base_f, est, graph, assoc, lm_class,
                                                           merged_into, gate, st, rebuild=scale != 1.0)
            n_frames_obs = sum(len(u) for _, u, _ in frames)
            st["assoc_error"] = graph.error(est)     # of the graph the pairings were made with
            st["assoc_cost"] = (st["assoc_error"] + (n_frames_obs - len(assoc)) * gate / 2
                                + len({j for (_, _, j) in assoc}) * math.log(max(len(assoc), 2)))
            if with_states:                  # the last solve, on the pairings made
                cov_of = _covs_by_observation(frames)
                graph, est = self._solve_pairings(base_states, est, [(i, o, cov_of[id(o)], j) for (i, o, j) in assoc],
                                                  z_init)
        st["odom_sigma_scale"] = scale
        t_batch = time.perf_counter() - t0 - t_isam
        poses = _poses(est, n)
        # a merged landmark is the one it was merged into: results list each once
        keep = [j for j in range(len(lms_init)) if j not in merged_into and j not in removed]
        index = {j: x for x, j in enumerate(keep)}
        root = {j: index[_root(merged_into, j)] for j in range(len(lms_init)) if _root(merged_into, j) in index}
        assoc = [(i, o, root[j]) for (i, o, j) in assoc]
        lm_class = [lm_class[j] for j in keep]
        lm_ids = [lm_ids[j] for j in keep]
        lm_keys = [L(j) for j in keep]
        m = len(keep)
        lms = np.array([[est.atPoint2(k)[0], est.atPoint2(k)[1]] for k in lm_keys]).reshape(m, 2)
        pose_cov = lm_cov = info = None
        if p.covariances:
            marg = gtsam.Marginals(graph, est)
            pose_cov = np.array([marg.marginalCovariance(X(i)) for i in range(n)])
            lm_cov = np.array([marg.marginalCovariance(k) for k in lm_keys]).reshape(m, 2, 2)
            # Poses share every earlier odometry step, and landmarks the poses and the calibration:
            # their errors are correlated, and only the joint covariance whitens them together. Its
            # inverse over any set of variables is a Schur complement of the sparse information
            # matrix, cheap at any size (a dense joint covariance of 3,000 poses is not).
            info = Information(graph, est)
        st["t_isam_s"] = round(t_isam, 3)
        st["t_batch_s"] = round(t_batch, 3)
        st["t_total_s"] = round(time.perf_counter() - t0, 3)
        st["n_poses"] = n
        st["n_landmarks"] = m
        st["final_error"] = graph.error(est)
        if use_calib:
            st["calib_error_estimate"] = [float(x) for x in est.atVector(CALIB)]
        return Result(poses=poses, pose_cov=pose_cov, isam_poses=isam_poses, lms=lms,
                      lm_cov=lm_cov, lm_class=lm_class, lm_ids=lm_ids, assoc=assoc, stats=st,
                      info=info, lm_keys=lm_keys)

    def _solve_pairings(self, base_f, est, pairs, states=()):
        """The graph of `base_f` and one range-bearing factor (bearing for a far one) per (step,
        observation, covariance, landmark) of `pairs`, solved by Levenberg-Marquardt from `est` (poses, and the landmarks
        the pairs name) and, when `base_f` holds odometry states, their (key, initial value) pairs
        `states`: (graph, estimate)."""
        graph = gtsam.NonlinearFactorGraph()
        for f in base_f:
            graph.add(f)
        for (i, o, c, j) in pairs:
            graph.add(self._plain_factor(i, j, o, c))
        used = {j for (_, _, _, j) in pairs}
        v = gtsam.Values()
        for key in est.keys():
            sym = gtsam.Symbol(key)
            if sym.chr() == ord("x"):
                v.insert(key, est.atPose2(key))
            elif sym.index() in used:
                v.insert(key, est.atPoint2(key))
        for key, val in states:
            v.insert(key, val)
        return graph, batch_optimize(graph, v, python_loop=bool(states))[0]

    def _reassociate(self, frames, base_f, est, graph, assoc, lm_class, merged_into, gate, st, rebuild=False):
        """Batch re-association (`reassoc` passes at most): every usable observation of every frame
        is paired again, against the landmarks at the batch estimate, with the frame's Hungarian
        assignment of individual distances (d2 <= chi2_2(gate_p), d2 from the observation's
        covariance and the landmark's marginal at the estimated pose, at most one observation a
        landmark; observations the online pass dropped as ambiguous or imprecise take part too).
        Then two landmarks of a class that no frame pairs together and whose difference passes the
        same gate under their marginals become one (the closest pairs first, each landmark in one
        merge a pass); a landmark no observation pairs with is removed. The graph is rebuilt from
        the odometry and these pairings and solved again (Levenberg-Marquardt from the last
        estimate). Passes stop when no pairing changed, or when a pass gives the pairings of the pass
        before the last (a few pairings flipping back and forth). Online, a pairing is made once with the
        uncertain pose of that moment; here each is made again with the whole run's estimate.
        With `rebuild` (an online pass gated with other odometry sigmas than `base_f`'s) the
        graph is first rebuilt from `base_f` and the pairings and solved. Returns the graph, the
        estimate, the pairings and the removed landmarks."""
        p = self.p
        if rebuild:
            cov_of = _covs_by_observation(frames)
            graph, est = self._solve_pairings(base_f, est, [(i, o, cov_of[id(o)], _root(merged_into, j))
                                                            for (i, o, j) in assoc])
        lms = sorted({_root(merged_into, j) for (_, _, j) in assoc})
        cur = {(i, id(o)): _root(merged_into, j) for (i, o, j) in assoc}
        st["reassoc_changed"] = []
        st["reassoc_merges"] = 0
        before = None                        # the pairings of the pass before the last
        for _ in range(p.reassoc):
            marg = gtsam.Marginals(graph, est)
            P = {j: marg.marginalCovariance(L(j)) for j in lms}
            pos = {j: np.array(est.atPoint2(L(j))) for j in lms}
            new = []                         # (step, observation, covariance, landmark)
            for (i, usable, covs) in frames:
                pe = est.atPose2(X(i))
                pose = np.array([pe.x(), pe.y(), pe.theta()])
                cols = [j for j in lms if any(lm_class[j] == o.cls for o in usable)]
                if not cols:
                    continue
                cost = np.full((len(usable), len(cols) + len(usable)), BIG)
                for a, (o, R) in enumerate(zip(usable, covs)):
                    z = np.array([o.range_m, o.bearing_rad])
                    for c, j in enumerate(cols):
                        if lm_class[j] != o.cls:
                            continue
                        h, H = predict_rb(pose, pos[j])
                        nu = z - h
                        nu[1] = wrap(nu[1])
                        Hl = H[:, 3:5]
                        d2 = float(nu @ np.linalg.solve(Hl @ P[j] @ Hl.T + R, nu))
                        if d2 <= gate:
                            cost[a, c] = d2
                    cost[a, len(cols) + a] = gate
                for a, c in enumerate(hungarian(cost)):
                    if c < len(cols) and cost[a, c] < BIG:
                        new.append((i, usable[a], covs[a], cols[c]))
            # duplicates: never paired in one frame, and compatible
            together = set()
            per_step = {}
            for (i, _, _, j) in new:
                per_step.setdefault(i, set()).add(j)
            for js in per_step.values():
                together.update((x, y) for x in js for y in js if x < y)
            lms = sorted({j for (_, _, _, j) in new})
            pairs = []
            for k, x in enumerate(lms):
                for y in lms[k + 1:]:
                    if lm_class[x] == lm_class[y] and (x, y) not in together:
                        dv = pos[x] - pos[y]
                        d2 = float(dv @ np.linalg.solve(P[x] + P[y], dv))
                        if d2 <= gate:
                            pairs.append((d2, x, y))
            into, busy = {}, set()
            for _, x, y in sorted(pairs):
                if x not in busy and y not in busy:
                    busy.update((x, y))
                    into[y] = x
            st["reassoc_merges"] += len(into)
            new = [(i, o, c, into.get(j, j)) for (i, o, c, j) in new]
            lms = [j for j in lms if j not in into]
            now = {(i, id(o)): j for (i, o, _, j) in new}
            changed = sum(1 for key in cur.keys() | now.keys() if cur.get(key) != now.get(key))
            st["reassoc_changed"].append(changed)
            # a 2-cycle (a few pairings flipping back and forth between passes) ends the passes too
            cycle = changed > 0 and now == before
            before, cur = cur, now
            graph, est = self._solve_pairings(base_f, est, new)
            assoc = [(i, o, j) for (i, o, _, j) in new]
            if changed == 0 or cycle:
                st["reassoc_cycle"] = cycle
                break
        removed = set(range(len(lm_class))) - set(lms)
        merged_into.clear()                  # every pairing names its landmark itself now
        return graph, est, assoc, removed

    def _jcbb(self, gated, covs, cands, Sig, nobs):
        """Joint compatibility branch and bound (Neira and Tardos 2001): among the hypotheses that
        pair each observation with an individually compatible candidate (`gated`: (observation,
        landmark) -> (innovation, its 2x5 Jacobian, the pose's and the landmark's rows of Sig)) or
        with none, at most one observation per landmark, the one with the most pairings whose joint
        innovation is compatible (NIS <= chi2_2k(gate_p), with Sig the current pose's and the
        candidates' joint covariance: the pose error, common to all pairings, is counted once), the
        lowest NIS among equals. As in JCBB, a hypothesis grows one observation at a time and each
        extension must pass its own gate, so a hypothesis whose shorter part fails is not reached (the
        result may depend on the observations' order); the search is exhaustive within that, which
        is cheap for the few observations and at most max_cands candidates of a frame. Returns the
        landmark per observation, or None."""
        rows = {}
        for key, (nu, H, idx) in gated.items():
            Hrow = np.zeros((2, Sig.shape[0]))
            Hrow[:, idx] = H
            rows[key] = (nu, Hrow)
        best = {"n": 0, "nis": 0.0, "h": [None] * nobs}

        def nis(hyp):
            pairs = [(a, j) for a, j in enumerate(hyp) if j is not None]
            if not pairs:
                return 0.0
            nu = np.concatenate([rows[p][0] for p in pairs])
            Hm = np.vstack([rows[p][1] for p in pairs])
            S = Hm @ Sig @ Hm.T
            for k, (a, _) in enumerate(pairs):
                S[2 * k:2 * k + 2, 2 * k:2 * k + 2] += covs[a]
            return float(nu @ np.linalg.solve(S, nu))

        def dfs(a, hyp, npair, used):
            if a == nobs:
                d2 = nis(hyp)
                if npair > best["n"] or (npair == best["n"] and d2 < best["nis"]):
                    best.update(n=npair, nis=d2, h=list(hyp))
                return
            if npair + (nobs - a) < best["n"]:
                return                                   # cannot beat the best any more
            for j in cands[a]:
                if (a, j) in rows and j not in used:
                    hyp[a] = j
                    if nis(hyp) <= chi2_2k(self.p.gate_p, npair + 1):
                        dfs(a + 1, hyp, npair + 1, used | {j})
                    hyp[a] = None
            dfs(a + 1, hyp, npair, used)

        dfs(0, [None] * nobs, 0, frozenset())
        return best["h"]

    def _merge(self, isam, by_class, merged_into, co_seen, gate, st):
        """Duplicate landmarks: two of a class, never observed in one frame, within cand_radius + 3
        sigma of each other, whose difference is inside the association gate under their joint marginal
        covariance. The younger is tied to the older by a Point2 equality factor (sigma 1 mm) and
        leaves the association candidates; its observations count as the older's. Returns the new
        factors."""
        out = []
        noise = gtsam.noiseModel.Isotropic.Sigma(2, 1e-3)
        est, spread = {}, {}                # per landmark: estimate, sqrt of its covariance's trace

        def at(j):
            if j not in est:
                est[j] = np.asarray(isam.calculateEstimatePoint2(L(j)), float)
                spread[j] = math.sqrt(np.trace(isam.marginalCovariance(L(j))))
            return est[j], spread[j]
        for cls, js in by_class.items():
            for x, j in enumerate(js):
                if j in merged_into:
                    continue
                for k in js[x + 1:]:
                    if k in merged_into or j in merged_into or (min(j, k), max(j, k)) in co_seen:
                        continue
                    (pj, sj), (pk, sk) = at(j), at(k)
                    dlt = pk - pj
                    if math.hypot(*dlt) > self.p.cand_radius + 3.0 * (sj + sk):
                        continue
                    jm = isam.jointMarginalCovariance([L(j), L(k)])
                    st["marginal_calls"] += 1
                    S = jm.at(L(j), L(j)) + jm.at(L(k), L(k)) - jm.at(L(j), L(k)) - jm.at(L(k), L(j))
                    if float(dlt @ np.linalg.solve(S, dlt)) > gate:
                        continue
                    merged_into[k] = j
                    for a, b in list(co_seen):
                        if k in (a, b):
                            o = b if a == k else a
                            co_seen.add((min(o, j), max(o, j)))
                    out.append(gtsam.BetweenFactorPoint2(L(j), L(k), gtsam.Point2(0.0, 0.0), noise))
            by_class[cls] = [j for j in js if j not in merged_into]
        return out

    def _associate(self, isam, i, cur, usable, covs, lms_init, lm_class, by_class, gate,
                   new_thr, st):
        """Targets per usable observation: landmark index, -1 new landmark, -3 ambiguous,
        -4 would start a landmark but is too imprecise (sigma > init_max_sigma)."""
        zs = [np.array([o.range_m, o.bearing_rad]) for o in usable]
        cands = []
        sig = []
        for o, R in zip(usable, covs):
            w = rb_to_world(cur, o.range_m, o.bearing_rad)
            s_max = planar_sigma(o, R)
            sig.append(s_max)
            rad = self.p.cand_radius + 3.0 * s_max
            cs = []
            for j in by_class.get(o.cls, []):
                lp = lms_init[j]
                dd = math.hypot(lp[0] - w[0], lp[1] - w[1])
                if dd <= rad:
                    cs.append((dd, j))
            cands.append([j for _, j in sorted(cs)[:self.p.max_cands]])
        allc = sorted({j for cs in cands for j in cs})
        if not allc:
            return [-1 if s <= self.p.init_max_sigma else -4 for s in sig]
        # the joint covariance of the pose and every candidate, in this key order (pose: rows 0-2,
        # landmark allc[k]: rows 3 + 2k, 4 + 2k)
        Sig = isam.jointMarginalCovariance([X(i)] + [L(j) for j in allc]).fullMatrix()
        st["marginal_calls"] += 1
        col = {j: k for k, j in enumerate(allc)}
        for j in allc:
            pt = isam.calculateEstimatePoint2(L(j))
            lms_init[j] = np.array([pt[0], pt[1]])
        nobs, ncand = len(usable), len(allc)
        cost = np.full((nobs, ncand + nobs), BIG)
        d2s = [dict() for _ in range(nobs)]
        gated = {}                          # (observation, landmark) -> (innovation, H, rows of Sig)
        for a, (o, z, cs) in enumerate(zip(usable, zs, cands)):
            for j in cs:
                h, H = predict_rb(cur, lms_init[j])
                rows = np.r_[0:3, 3 + 2 * col[j]:5 + 2 * col[j]]
                nu = z - h
                nu[1] = wrap(nu[1])
                d2 = float(nu @ np.linalg.solve(H @ Sig[np.ix_(rows, rows)] @ H.T + covs[a], nu))
                d2s[a][j] = d2
                if d2 <= gate:
                    cost[a, col[j]] = d2
                    gated[a, j] = (nu, H, rows)
            cost[a, ncand + a] = gate
        if self.p.joint:
            pick = self._jcbb(gated, covs, cands, Sig, nobs)
            sol = [col[j] if j is not None else ncand + a for a, j in enumerate(pick)]
        else:
            sol = hungarian(cost)
        taken = {allc[c] for a, c in enumerate(sol) if c < ncand and cost[a, c] < BIG}
        out = []
        for a, c in enumerate(sol):
            if c < ncand and cost[a, c] < BIG:
                out.append(allc[c])
                continue
            near = [j for j in cands[a] if d2s[a].get(j, np.inf) <= new_thr]
            # A landmark gives at most one observation a frame: when every landmark this one might be
            # is taken by another observation of the same frame, it is a landmark not yet mapped
            # (posts closer together than the range noise), not an ambiguous one.
            exclusive = self.p.exclusion and all(j in taken for j in near)
            if near and not exclusive:
                out.append(-3)
            elif sig[a] > self.p.init_max_sigma:
                out.append(-4)
            else:
                out.append(-1)
                if near:
                    st["new_by_exclusion"] += 1
        return out


def _root(merged_into, j):
    while j in merged_into:
        j = merged_into[j]
    return j


def file_view(groups, gate, step, o, cov, w, C, key=None):
    """Files an observation, its point w in the plane with covariance C, into the group of its
    class (in `groups`, each dict(cls, views [(step, obs, cov)], info: the sum of the views'
    information matrices, iw: of information @ point, last: the newest view's step, key)) whose
    mean it is nearest inside the gate, not counting one already seen at this step, or into a new
    one; returns that group. With a key (a landmark identity) the group of that key, ungated."""
    best, bd = None, gate
    for g in groups:
        if g["cls"] != o.cls or g["last"] == step or g.get("key") != key:
            continue
        if key is not None:
            best = g
            break
        m, P = CandidateBuffer.mean(g)
        d = w - m
        d2 = float(d @ np.linalg.solve(P + C, d))
        if d2 <= bd:
            best, bd = g, d2
    if best is None:
        best = dict(cls=o.cls, views=[], info=np.zeros((2, 2)), iw=np.zeros(2), last=step, key=key)
        groups.append(best)
    info = np.linalg.inv(C)
    best["views"].append((step, o, cov))
    best["info"] = best["info"] + info
    best["iw"] = best["iw"] + info @ w
    best["last"] = step
    return best


def expire_groups(groups, step, window):
    """(the groups of file_view seen since step - window, how many views the others held)."""
    keep = [g for g in groups if step - g["last"] <= window]
    return keep, sum(len(g["views"]) for g in groups if step - g["last"] > window)


class CandidateBuffer:
    """Delayed landmark initialisation: observations that would start a landmark wait here until
    `views` of them, from distinct steps and of one class, agree on a point in the plane (each new
    view within the gate of the candidate's mean, their covariances in the plane from range and
    bearing, the pose taken as known); a candidate not seen again within `window` steps is dropped."""

    def __init__(self, views, window, gate):
        self.views, self.window, self.gate = views, window, gate
        self.cands = []                     # dict(cls, views [(step, obs, cov)], info: the sum of the
                                            # views' information matrices, iw: of information @ point,
                                            # last: the step of the newest view)

    @staticmethod
    def _point(pose, o, cov):
        a = pose[2] + o.bearing_rad
        J = np.array([[math.cos(a), -o.range_m * math.sin(a)], [math.sin(a), o.range_m * math.cos(a)]])
        return rb_to_world(pose, o.range_m, o.bearing_rad), J @ cov @ J.T

    def add(self, step, pose, o, cov):
        """File the observation; returns its candidate once confirmed (and leaves it out of the
        buffer), else None."""
        best = file_view(self.cands, self.gate, step, o, cov, *self._point(pose, o, cov))
        if len(best["views"]) >= self.views:
            self.cands.remove(best)
            return best
        return None

    @staticmethod
    def mean(c):
        """The information-weighted mean of a candidate's points and its covariance."""
        P = np.linalg.inv(c["info"])
        return P @ c["iw"], P

    def expire(self, step):
        """Drops the candidates not seen since step - window; returns how many observations they held."""
        self.cands, n = expire_groups(self.cands, step, self.window)
        return n


class FarTracks:
    """Landmarks seen only far away (their range unusable, Params.far_bearing) start from their
    bearings: each such observation joins the track of its class whose point it gates with (the
    range-bearing point in the plane, the range's sigma times far_init_range_scale, the pose taken
    as known) or opens one; a track with far_init_views views from distinct steps whose rays spread
    over far_init_parallax_deg is triangulated from its bearings at the poses' current estimates
    (Gauss-Newton, each view weighted by its bearing variance). A track not seen for
    far_init_window steps is dropped."""

    def __init__(self, p, gate):
        self.p, self.gate = p, gate
        self.tracks = []                    # dict(cls, views [(step, obs, cov)], info, iw, last, rays)

    def _point(self, pose, o, cov):
        k = self.p.far_init_range_scale
        c = np.array(cov, float) * np.array([[k * k, k], [k, 1.0]])
        return CandidateBuffer._point(pose, o, c)

    def add(self, step, pose, o, cov, key=None):
        """File the far observation (key: its landmark identity, when the run associates by
        identity: the track of that identity); returns its track when it has enough views and
        parallax to be triangulated (it stays filed: remove() takes it out), else None."""
        best = file_view(self.tracks, self.gate, step, o, cov, *self._point(pose, o, cov), key=key)
        best.setdefault("rays", [])
        a = pose[2] + o.bearing_rad
        best["rays"].append(a if not best["rays"] else best["rays"][0] + wrap(a - best["rays"][0]))
        if (len(best["views"]) >= self.p.far_init_views
                and max(best["rays"]) - min(best["rays"]) >= math.radians(self.p.far_init_parallax_deg)):
            return best
        return None

    def remove(self, t):
        self.tracks.remove(t)

    def triangulate(self, t, poses):
        """The track's point from its bearings at `poses` (step -> pose), or None when the rays at
        those poses do not meet in front of every view with the parallax asked, or a bearing's
        residual exceeds 6 of its sigmas (a track that mixes two objects)."""
        pt = CandidateBuffer.mean(t)[0].copy()
        P = np.array([poses[k][:2] for k, _, _ in t["views"]], float)
        th = np.array([poses[k][2] for k, _, _ in t["views"]], float)
        b = np.array([o.bearing_rad for _, o, _ in t["views"]], float)
        sig = np.sqrt(np.array([max(c[1, 1], 1e-12) for _, _, c in t["views"]], float))

        def whitened(pt):
            """(point - view positions, the bearings' whitened residuals)."""
            d = pt - P
            return d, wrap(b - (np.arctan2(d[:, 1], d[:, 0]) - th)) / sig
        for _ in range(20):
            d, r = whitened(pt)
            q = np.maximum(np.einsum("ij,ij->i", d, d), 1e-9)
            H = np.c_[-d[:, 1] / q, d[:, 0] / q] / sig[:, None]
            step = np.linalg.lstsq(H, r, rcond=None)[0]
            pt = pt + step
            if not np.all(np.isfinite(pt)):
                return None
            if np.linalg.norm(step) < 1e-7:
                break
        d, r = whitened(pt)
        ray = np.c_[np.cos(th + b), np.sin(th + b)]
        if np.any(np.einsum("ij,ij->i", d, ray) <= 0):
            return None
        ang = np.arctan2(-d[:, 1], -d[:, 0])
        ang = ang[0] + wrap(ang - ang[0])
        if ang.max() - ang.min() < math.radians(self.p.far_init_parallax_deg):
            return None
        if np.any(np.abs(r) > 6.0):
            return None
        return pt

    def expire(self, step):
        """Drops the tracks not seen since step - window; returns how many observations they held."""
        self.tracks, n = expire_groups(self.tracks, step, self.p.far_init_window)
        return n


def _pose_of(isam, new_v, k):
    """Step k's pose estimate: the values not yet given to iSAM2, else iSAM2's."""
    e = new_v.atPose2(X(k)) if new_v.exists(X(k)) else isam.calculateEstimatePose2(X(k))
    return np.array([e.x(), e.y(), e.theta()])


class Information:
    """The information matrix H = J^T J of the graph linearised at the estimate (sparse; robust
    kernels' weights included, as in gtsam.Marginals), with the columns of each variable."""

    def __init__(self, graph, values):
        import scipy.sparse as sp
        keys = sorted(values.keys())      # the column order of GaussianFactorGraph.sparseJacobian_
        self.cols = {}
        c = 0
        for k in keys:
            d = _dim(values, k)
            self.cols[k] = np.arange(c, c + d)
            c += d
        ijs = graph.linearize(values).sparseJacobian_()
        i, j, v = ijs[0].astype(int) - 1, ijs[1].astype(int) - 1, ijs[2]
        keep = j < c                      # the last column is the right-hand side b
        J = sp.csc_matrix((v[keep], (i[keep], j[keep])), shape=(int(i.max()) + 1, c))
        self.H = (J.T @ J).tocsc()
        self.n = c
        # an elimination order for the Schur complements in `nees`: each pose next to its odometry
        # state, step by step (a chain: banded), the other variables (landmarks, calibration) last,
        # in column order: (group, step, pose before state, column) sorted together
        self.rank = np.empty((c, 4), np.int64)
        for k in keys:
            sym = gtsam.Symbol(k)
            ch = chr(sym.chr())
            chain = ch in "xz"
            self.rank[self.cols[k]] = [[0 if chain else 1, sym.index() if chain else 0, ch == "z", col]
                                       for col in self.cols[k]]

    def columns(self, keys):
        return np.concatenate([self.cols[k] for k in keys]) if keys else np.zeros(0, int)

    def nees(self, keys, err):
        """e^T Sigma_S^-1 e for the stacked tangent-space error e of the variables `keys`, Sigma_S
        their joint marginal covariance: Sigma_S^-1 = H_SS - H_SO H_OO^-1 H_OS (O: all others)."""
        import scipy.sparse as sp
        import scipy.sparse.linalg as spl
        s = self.columns(keys)
        o = np.setdiff1d(np.arange(self.n), s)
        e = np.asarray(err, float)
        v = float(e @ (self.H[s][:, s] @ e))
        if len(o):
            r = self.rank[o]
            o = o[np.lexsort((r[:, 3], r[:, 2], r[:, 1], r[:, 0]))]
            Hos = self.H[o][:, s]
            w = Hos @ e
            Hoo = sp.csc_matrix(self.H[o][:, o])
            # symmetric positive definite: no pivoting, the order above (a general fill-reducing
            # order took minutes on five robots' 13,000 poses with their odometry states)
            lu = spl.splu(Hoo, permc_spec="NATURAL", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
            v -= float(w @ lu.solve(w))
        return v


def _dim(values, key):
    sym = gtsam.Symbol(key)
    return {"x": 3, "l": 2}.get(chr(sym.chr()), None) or values.atVector(key).shape[0]


def _poses(values, n, base=0):
    """The poses X(base) .. X(base + n - 1) as an (n, 3) array."""
    out = np.empty((n, 3))
    for i in range(n):
        q = values.atPose2(X(base + i))
        out[i] = (q.x(), q.y(), q.theta())
    return out
