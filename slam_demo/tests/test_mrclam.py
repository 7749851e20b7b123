# SPDX-License-Identifier: BSD-3-Clause
import math
import os
import time

import numpy as np
import pytest

from conftest import FIXTURES
from cylslam import backend, metrics, mrclam

MR = os.path.join(FIXTURES, "mrclam")


def _rows(name):
    return [l.split() for l in open(os.path.join(MR, name)) if not l.startswith("#") and l.strip()]


def test_integration_of_constant_commands_is_an_exact_arc():
    # v = 0.2 m/s, w = 0.5 rad/s for 2 s: a circle of radius 0.4 m
    odo = np.array([[0.0, 0.2, 0.5], [2.0, 0.0, 0.0]])
    P = mrclam.integrate(odo)
    th = 1.0
    assert np.allclose(P[1], [0.4 * math.sin(th), 0.4 * (1 - math.cos(th)), th])
    q = mrclam.dr_at(odo, P, np.array([1.0, 3.0]))
    assert np.allclose(q[0], [0.4 * math.sin(0.5), 0.4 * (1 - math.cos(0.5)), 0.5])
    assert np.allclose(q[1], P[1])      # v = 0 after t = 2


def test_reader_maps_barcodes_and_drops_robots():
    ds = mrclam.read_mrclam(MR, 2)
    bc = {int(b): int(s) for s, b in _rows("Barcodes.dat")}
    t0 = min(float(r[0]) for r in _rows("Robot2_Odometry.dat"))
    meas = [(float(r[0]), int(r[1])) for r in _rows("Robot2_Measurement.dat")]
    lm = [(t, bc[b]) for t, b in meas if b in bc and bc[b] >= 6 and t >= t0]
    robots = [1 for t, b in meas if b in bc and bc[b] <= 5]
    unknown = [1 for t, b in meas if b not in bc]
    got = sorted(o.lm_id for s in ds.steps for o in s.obs)
    assert got == sorted(s for _, s in lm)
    assert f"dropped {len(robots)} of other robots, {len(unknown)} of unknown barcodes" in ds.notes[0]
    assert len(ds.truth_landmarks) == 15 and all(6 <= k <= 20 for k in ds.truth_landmarks)
    # steps are at most 0.5 s apart; every observation sits at its step's time (< 50 ms)
    ts = np.array([s.t for s in ds.steps])
    assert np.all(np.diff(ts) <= 0.5 + 1e-6) and np.all(np.diff(ts) > 0)
    assert ds.known_ids


def test_range_dependent_noise_option():
    c = mrclam.meas_cov(4.0, "range")
    assert np.allclose(np.sqrt(np.diag(c)), [0.03 * 4 + 0.02, 0.01])
    assert np.allclose(np.sqrt(np.diag(mrclam.meas_cov(4.0, "fixed"))), [0.1, 0.01])


def test_two_minute_excerpt_known_association():
    ds = mrclam.read_mrclam(MR, 2)
    t = time.perf_counter()
    res = backend.Slam(backend.Params(assoc="known", robust="huber")).run(ds)
    dt = time.perf_counter() - t
    m = metrics.evaluate(ds, res)
    assert m["ate_m"] <= 0.15
    assert m["ate_m"] < m["ate_isam_m"] + 0.02
    assert m["association_errors"] == 0 and m["landmarks_matched"] == len(res.lms)
    assert dt < 10


def test_several_starts_keep_the_least_cost_solution():
    """Unknown association on the two-minute excerpt with three starts (online odometry sigmas x1,
    x0.5, x2): the kept run is the one of least penalised cost, identical to a run of that start
    alone, and its cost is the error of the graph the pairings were made with (the odometry's
    variance inflated, as online) plus the 'no landmark' cost of each unpaired observation plus
    ln(pairings) per landmark (the last solve, with the odometry's states, is another graph)."""
    from cylslam.noise_model import DEFAULT_PATH, NoiseModel
    model = NoiseModel.load(DEFAULT_PATH)
    ds = mrclam.read_mrclam(MR, 2, noise="learned", model=model)
    rob, k = model.factor_kernel()

    def params(starts):
        return backend.Params(assoc="unknown", robust=rob, huber_k=k, exclusion=True, reassoc=20, starts=starts)
    res = backend.Slam(params((1.0, 0.5, 2.0))).run(ds)
    tried = res.stats["starts"]
    assert [t["odom_sigma_scale"] for t in tried] == [1.0, 0.5, 2.0]
    best = min(tried, key=lambda t: t["cost"])
    assert res.stats["start_chosen"] == best["odom_sigma_scale"]
    assert len({t["cost"] for t in tried}) > 1          # the starts do end differently
    alone = backend.Slam(params((best["odom_sigma_scale"],))).run(ds)
    assert np.allclose(alone.poses, res.poses) and len(alone.lms) == len(res.lms)
    gate = backend.chi2_2dof(0.99)
    p1 = params((1.0,))
    usable = sum(1 for s in ds.steps for o in s.obs if backend.drop_reason(o, p1) is None)
    assert res.stats["odometry_states"] == len(ds.steps) - 1
    want = (res.stats["assoc_error"] + (usable - len(res.assoc)) * gate / 2
            + len(res.lms) * math.log(len(res.assoc)))
    assert res.stats["assoc_cost"] == pytest.approx(want, rel=1e-9)
    with pytest.raises(ValueError, match="re-association"):
        backend.Slam(backend.Params(assoc="unknown", starts=(1.0, 0.5))).run(ds)
    with pytest.raises(ValueError, match="> 0"):
        backend.Slam(backend.Params(assoc="unknown", reassoc=2, starts=(1.0, 0.0))).run(ds)
