# SPDX-License-Identifier: BSD-3-Clause
"""Far observations kept for their bearing alone (Params.far_bearing, cylslam run --far-bearing):
which observations it keeps, the bearing-only factors against the full ones and central
differences, and a drive whose far ranges are wrong by a fifth: the bearings help, the ranges do
not reach the map, and no landmark starts from a bearing."""
import gtsam
import numpy as np
import pytest

from cylslam.backend import B, L, X, Params, Slam, calib_factor, calib_factor_exact, drop_reason, rb_jacobians
from cylslam.data import FLAG_CUT, FLAG_NONLINEAR, Dataset, Obs, Step, compose, wrap
from cylslam.metrics import evaluate

from test_calib_states import _exact_setup, _values, numeric


def _obs(flags=0, rng_sigma=0.01, r=2.0):
    return Obs(cls="orange", range_m=r, bearing_rad=0.1, cov=np.diag([rng_sigma ** 2, 1e-4]), flags=flags)


def test_which_observations_are_kept():
    near, far, far_cut = _obs(), _obs(FLAG_NONLINEAR), _obs(FLAG_NONLINEAR | FLAG_CUT)
    p = Params(reject_flags=0x720)
    assert drop_reason(near, p) is None
    assert drop_reason(far, p) == "dropped_flags"
    assert drop_reason(far_cut, p) == "dropped_flags"
    p.far_bearing = True
    assert drop_reason(far, p) is None                       # kept, for its bearing
    assert drop_reason(far_cut, p) == "dropped_flags"        # cut: dropped for that, as before
    # the range-sigma rule likewise
    wide = _obs(rng_sigma=0.3)                                # sigma_r / r = 0.15
    q = Params(max_range_rel_sigma=0.1)
    assert drop_reason(wide, q) == "dropped_far"
    q.far_bearing = True
    assert drop_reason(wide, q) is None
    # a run that does not reject the non-linear flag uses those observations whole
    assert drop_reason(far, Params(reject_flags=0x320, far_bearing=True)) is None


def test_linear_factor_bearing_row():
    rng = np.random.default_rng(3)
    jac = rng.normal(size=(2, 8)) * np.array([1e-3, 1e-3, 1e-3, 1e-3, 5.0, 0.5, 3.0, 1.0])
    pose, lm, delta = np.array([0.1, 0.2, 0.3]), np.array([4.0, -0.5]), rng.normal(size=8) * 1e-3
    o = Obs(cls="orange", range_m=4.3, bearing_rad=-0.15, cov=np.eye(2), jac_calib=jac,
            cov_frame=np.diag([1e-2, 1e-6]))
    full = calib_factor(X(0), L(0), o, gtsam.noiseModel.Unit.Create(2), [B(0)])
    one = calib_factor(X(0), L(0), o, gtsam.noiseModel.Unit.Create(1), [B(0)], bearing_only=True)
    v = _values(pose, lm, delta, bias=[0.3, -0.2])
    assert one.dim() == 1
    assert one.unwhitenedError(v)[0] == pytest.approx(full.unwhitenedError(v)[0], abs=1e-15)
    # its Jacobians are the full factor's bearing row
    a1, _ = one.linearize(v).jacobian()
    a2, _ = full.linearize(v).jacobian()
    assert np.allclose(a1[0], a2[0], atol=1e-15)

    def err(pose_xi=np.zeros(3), lm_=lm, d=delta):
        p = gtsam.Pose2(*pose).retract(pose_xi)
        return one.unwhitenedError(_values([p.x(), p.y(), p.theta()], lm_, d, bias=[0.3, -0.2]))
    num = np.hstack([numeric(lambda x: err(pose_xi=x), np.zeros(3)), numeric(lambda x: err(lm_=x), lm),
                     numeric(lambda x: err(d=x), delta)])
    assert np.allclose(a1[:, :13], num, atol=1e-7)


def test_exact_factor_column_row():
    """The exact factor's bearing-only form is the full one's column (u px) residual, with the
    centroid's u variance as its noise, and its pose and landmark Jacobians match central
    differences."""
    d0 = np.array([0.3, -0.2, 0.4, 0.1, np.radians(0.5), np.radians(0.2), 0.001, 0.002])
    rbm, o, pose, lm, cov_px = _exact_setup(u=420.0, v=190.0, d_true=d0)
    full = calib_factor_exact(X(0), L(0), o, o.cov_frame, rbm)
    one = calib_factor_exact(X(0), L(0), o, o.cov_frame, rbm, bearing_only=True)
    assert one.dim() == 1
    assert np.allclose(one.noiseModel().covariance(), cov_px[:1, :1], rtol=1e-9)
    for lm2 in (lm, lm + [0.05, -0.03], lm + [-0.4, 0.2]):
        v = _values(pose, lm2, d0 * 0.5)
        assert one.unwhitenedError(v)[0] == pytest.approx(full.unwhitenedError(v)[0], rel=1e-12, abs=1e-12)
    at = _values(pose + [0.01, -0.02, 0.003], lm + [0.3, -0.1], d0)
    a, _ = one.linearize(at).jacobian()

    def werr(pose_xi=np.zeros(3), lm_=None):
        p = gtsam.Pose2(*pose + [0.01, -0.02, 0.003]).retract(pose_xi)
        return one.whitenedError(_values([p.x(), p.y(), p.theta()], lm + [0.3, -0.1] if lm_ is None else lm_, d0))
    num = np.hstack([numeric(lambda x: werr(pose_xi=x), np.zeros(3)), numeric(lambda x: werr(lm_=x), lm + [0.3, -0.1])])
    assert abs(werr()[0]) > 1.0                      # a real residual
    assert np.allclose(a[:, :5], num, rtol=1e-5, atol=1e-8)


def _drive(rng, steps=120, far_bias=1.2):
    """A robot on a circle of radius 1.5 m. Landmarks 0-2 near (seen whole every step); landmark 3
    seen whole at the first step and at every later step flagged non-linear, its range a fifth too
    long (a far range's error is far from its Gaussian) while its bearing is right; landmark 4 seen
    only flagged."""
    lms = np.array([[2.5, 0.5], [-2.0, 1.5], [0.5, -2.5], [6.0, 5.0], [-6.0, -5.5]])
    q = np.diag([0.01 ** 2, 0.005 ** 2, 0.01 ** 2])
    truth, odo = [np.array([1.5, 0.0, np.pi / 2])], [None]
    d = np.array([2 * np.pi * 1.5 / steps, 0.0, 2 * np.pi / steps])
    for _ in range(steps - 1):
        truth.append(compose(truth[-1], d))
        odo.append(d + np.linalg.cholesky(q) @ rng.standard_normal(3))
    sb, sr = 0.004, 0.03
    out = []
    for k, p in enumerate(truth):
        obs = []
        for j, lm in enumerate(lms):
            b, r, _, _ = rb_jacobians(p, lm)
            far = j == 4 or (j == 3 and k > 0)
            rs = sr * (r / 2.0) ** 2
            z_r = r * (far_bias if far else 1.0) + rng.normal() * rs
            z_b = b + rng.normal() * sb
            obs.append(Obs(cls="orange", range_m=z_r, bearing_rad=float(wrap(z_b)), cov=np.diag([rs ** 2, sb ** 2]),
                           lm_id=j, flags=FLAG_NONLINEAR if far else 0))
        out.append(Step(t=0.1 * k, seq=k, odom=odo[k], odom_cov=None if k == 0 else q, truth=p, obs=obs))
    return Dataset(name="far", steps=out, truth_landmarks={j: (*lm, "orange") for j, lm in enumerate(lms)},
                   classes=["orange"], known_ids=True)


def test_far_ranges_do_not_reach_the_map():
    rng = np.random.default_rng(5)
    errs = {"drop": [], "whole": [], "bearing": []}
    nees3 = []
    for _ in range(6):
        ds = _drive(rng)
        runs = {"drop": Params(reject_flags=0x720), "whole": Params(reject_flags=0x320),
                "bearing": Params(reject_flags=0x720, far_bearing=True)}
        for name, p in runs.items():
            res = Slam(p).run(ds)
            ids = list(res.lm_ids)
            if name == "bearing":
                assert res.stats["bearing_only"] == 119     # landmark 3's flagged views
                assert res.stats["dropped_far_new"] == 120  # landmark 4: a bearing starts nothing
                assert 4 not in ids
            j3 = ids.index(3)
            e = res.lms[j3] - np.array([6.0, 5.0])
            errs[name].append(np.linalg.norm(e))
            if name == "bearing":
                nees3.append(e @ np.linalg.solve(res.lm_cov[j3], e))
                assert evaluate(ds, res)["association_errors"] == 0
    # whole: the long ranges drag the landmark out (by about half a metre); dropped: one view
    # places it; bearings from around the circle place it well and consistently
    assert min(errs["whole"]) > 0.3
    assert np.median(errs["bearing"]) < 0.5 * np.median(errs["drop"])
    assert np.mean(nees3) < 4.0                     # 2 dof, 6 runs: mean 2, no range bias in it


def test_fixed_baseline_is_the_mean_of_the_whole_observations():
    """The fixed-covariance baseline's matrix is the mean over the observations the main run used
    for range and bearing: a far observation's range variance, which no factor uses, is left out
    (with it the mean's range sigma reached metres and the fixed runs mapped nothing)."""
    from cylslam.backend import Result
    from cylslam.cli import mean_obs_cov
    near = [_obs() for _ in range(3)]
    far = [_obs(FLAG_NONLINEAR, rng_sigma=2.0, r=8.0) for _ in range(5)]
    res = Result(poses=None, pose_cov=None, isam_poses=None, lms=None, lm_cov=None, lm_class=None, lm_ids=None,
                 assoc=[(0, o, 0) for o in near + far])
    p = Params(reject_flags=0x720, far_bearing=True)
    assert np.allclose(mean_obs_cov(res, p), np.diag([0.01 ** 2, 1e-4]))
    p.far_bearing = False                           # (a run that used them whole: all of them)
    assert mean_obs_cov(res, p)[0, 0] == pytest.approx((3 * 0.01 ** 2 + 5 * 4.0) / 8)


def test_command_line():
    """cylslam run: on by default, one bearing a landmark every 0.5 s (what the tuning drives chose);
    --no-far-bearing turns it off; a scale <= 0 is a usage error (exit 2) naming the option."""
    import os
    import subprocess
    import sys
    from cylslam.cli import _params, build_parser
    a = build_parser().parse_args(["run", "x.jsonl"])
    p = _params(a)
    assert p.far_bearing and p.far_bearing_var_scale == 1.0 and p.far_bearing_every_s == 0.5
    assert not _params(build_parser().parse_args(["run", "x.jsonl", "--no-far-bearing"])).far_bearing
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    r = subprocess.run([sys.executable, "-m", "cylslam", "run", os.path.join(here, "tests", "fixtures", "synth_short.jsonl"),
                        "--far-bearing-scale", "0"], capture_output=True, text=True,
                       env=dict(os.environ, PYTHONPATH=here), timeout=120)
    assert r.returncode == 2 and "--far-bearing-scale 0.0: must be > 0" in r.stderr


def test_batch_reassociation_keeps_far_bearings():
    """Unknown association with batch re-association rebuilds the graph from its pairings: a far
    observation stays a bearing there (_plain_factor), so its long range does not reach the map --
    the landmark is where the online pass (bearings too) puts it, not where the ranges used whole do."""
    from dataclasses import replace
    err = {}
    for name, reject, far_bearing, reassoc in (("bearing", 0x720, True, 2), ("online", 0x720, True, 0),
                                               ("whole", 0x320, False, 2)):
        e = []
        for run in range(3):
            ds = _drive(np.random.default_rng(100 + run), far_bias=1.1)
            ds.known_ids = False
            for s in ds.steps:
                s.obs = [replace(o, lm_id=None) for o in s.obs]
            res = Slam(Params(reject_flags=reject, far_bearing=far_bearing, assoc="unknown", reassoc=reassoc,
                              covariances=False)).run(ds)
            e.append(np.min(np.linalg.norm(np.asarray(res.lms) - [6.0, 5.0], axis=1)))
            if far_bearing:
                assert res.stats["bearing_only"] > 50
        err[name] = np.median(e)
    assert err["bearing"] < 0.08 and err["online"] < 0.08
    assert err["whole"] > 0.15


def test_one_far_bearing_a_landmark_every_interval():
    """far_bearing_every_s: of one landmark's far views (every 0.1 s here) one at most every
    interval is used, counted as dropped_far_decimated; near views are never thinned."""
    ds = _drive(np.random.default_rng(3))
    n_far = 119                                    # landmark 3's flagged views, steps 1-119
    for every, kept in ((0.0, n_far), (0.5, 24), (1.0, 12)):
        res = Slam(Params(reject_flags=0x720, far_bearing=True, far_bearing_every_s=every, covariances=False)).run(ds)
        assert res.stats["bearing_only"] == kept
        assert res.stats["dropped_far_decimated"] == n_far - kept
        assert sum(1 for (_, o, _) in res.assoc if not o.flags) == 3 * 120 + 1   # every near view
    with pytest.raises(ValueError, match="--far-bearing-every -1.0: must be >= 0 s"):
        Params(far_bearing_every_s=-1.0).check()


def test_triangulate_from_bearings():
    """FarTracks.triangulate: bearings from known poses give the point back; rays that spread less
    than the parallax asked, or a view 40 sigmas off (a track that mixes two objects), give None."""
    from cylslam.backend import FarTracks
    pt = np.array([4.0, 3.0])
    p = Params(far_bearing=True, far_init=True, far_init_parallax_deg=5.0, far_init_views=3)
    tracks = FarTracks(p, gate=9.21)
    sb = 1e-3
    poses, views = {}, []
    for k in range(8):
        pose = np.array([0.2 * k, -0.1 * k, 0.05 * k])
        b = wrap(np.arctan2(pt[1] - pose[1], pt[0] - pose[0]) - pose[2])
        r = np.hypot(*(pt - pose[:2])) * 1.15          # a far range: 15% long, it only places the view
        poses[k] = pose
        views.append(Obs(cls="orange", range_m=r, bearing_rad=float(b), cov=np.diag([0.3 ** 2, sb ** 2])))
    got = None
    for k, o in enumerate(views):
        got = tracks.add(k, poses[k], o, o.cov)
    assert got is not None and len(tracks.tracks) == 1 and len(got["views"]) == 8
    assert np.allclose(tracks.triangulate(got, poses), pt, atol=1e-6)
    # the same rays, the parallax asked beyond their spread (about 18 degrees)
    spread = np.degrees(max(got["rays"]) - min(got["rays"]))
    assert 15 < spread < 21
    assert FarTracks(Params(far_bearing=True, far_init=True, far_init_parallax_deg=spread + 1),
                     9.21).triangulate(got, poses) is None
    # one bearing 40 sigmas off
    k0, o0, c0 = got["views"][4]
    bad = dict(got, views=list(got["views"]))
    bad["views"][4] = (k0, Obs(cls="orange", range_m=o0.range_m, bearing_rad=o0.bearing_rad + 40 * sb, cov=c0), c0)
    assert tracks.triangulate(bad, poses) is None
    # a view of a point elsewhere opens its own track
    o = Obs(cls="orange", range_m=3.0, bearing_rad=-1.2, cov=np.diag([0.3 ** 2, sb ** 2]))
    assert tracks.add(9, poses[7], o, o.cov) is None and len(tracks.tracks) == 2


def test_far_init_maps_a_landmark_seen_only_far():
    """Landmark 4 of the circle drive is only ever seen far, its range a fifth too long: with
    far_init it starts from its bearings (one track, triangulated) and sits where it is, its
    covariance consistent over the runs; without, it is never mapped."""
    rng = np.random.default_rng(11)
    errs, nees = [], []
    for _ in range(6):
        ds = _drive(rng)
        res = Slam(Params(reject_flags=0x720, far_bearing=True, far_init=True)).run(ds)
        assert res.stats["far_landmarks"] == 1
        assert evaluate(ds, res)["association_errors"] == 0
        j4 = list(res.lm_ids).index(4)
        e = res.lms[j4] - np.array([-6.0, -5.5])
        errs.append(np.linalg.norm(e))
        nees.append(e @ np.linalg.solve(res.lm_cov[j4], e))
        assert 4 not in Slam(Params(reject_flags=0x720, far_bearing=True, covariances=False)).run(ds).lm_ids
    assert np.median(errs) < 0.1                    # its ranges, used whole, would put it ~1.6 m out
    assert np.mean(nees) < 4.0                      # 2 dof, 6 runs: mean 2


def test_far_init_options():
    """cylslam run: far-init on by default with the far bearings, off with --no-far-bearing (not an
    error), an explicit --far-init without them a usage error; the parallax default 5 degrees."""
    from cylslam.cli import _params, build_parser
    p = _params(build_parser().parse_args(["run", "x.jsonl"]))
    assert p.far_init and p.far_init_parallax_deg == 5.0 and p.far_robust == "cauchy"
    p = _params(build_parser().parse_args(["run", "x.jsonl", "--no-far-bearing"]))
    assert not p.far_init
    p.check()
    assert not _params(build_parser().parse_args(["run", "x.jsonl", "--no-far-init"])).far_init
    p = _params(build_parser().parse_args(["run", "x.jsonl", "--no-far-bearing", "--far-init"]))
    with pytest.raises(ValueError, match="--far-init needs --far-bearing"):
        p.check()
    with pytest.raises(ValueError, match="--far-init needs --far-bearing"):
        Params(far_init=True).check()
    with pytest.raises(ValueError, match="views >= 2"):
        Params(far_bearing=True, far_init=True, far_init_views=1).check()


def test_fixed_baseline_with_no_whole_observation():
    """Every landmark seen only far away: all start from bearings, no observation is used for range
    and bearing, and the fixed-covariance baseline reports why it has no matrix (the mean of no
    observation was NaN before)."""
    from dataclasses import replace
    from cylslam.cli import build_parser, process
    ds = _drive(np.random.default_rng(4))
    for s in ds.steps:
        s.obs = [replace(o, flags=FLAG_NONLINEAR) for o in s.obs]
    args = build_parser().parse_args(["run", "x.jsonl", "--assoc", "known", "--no-plot", "--no-progress"])
    summary = process(ds, args, "far only", None)
    assert summary["stats"]["far_landmarks"] >= 4
    assert "no observation was used for range and bearing" in summary["fixed_cov_failed"]
    assert "ate_fixed_cov_m" not in summary
