# SPDX-License-Identifier: BSD-3-Clause
"""A merged blob's frame covariance times Params.merged_var_scale (cylslam run --merged-var-scale,
default 2): a Monte Carlo in which the merged views' centroid noise is four times what their
cov_frame says; scaled, the landmarks and poses are consistent, unscaled they are over-confident. Both the
calibration-state factor (cov_frame) and the plain factor (cov) take the scale."""
import numpy as np
import pytest

from cylslam.backend import Params, Slam, frame_scale
from cylslam.data import FLAG_MERGED, Obs
from cylslam.metrics import evaluate
from test_landmark_bias import JPX, _drive


def _merged_drive(rng):
    """The bias test's circle drive with no shared bias; every view of landmarks 0 and 1 is a
    merged blob whose centroid carries white noise of four times the variance its cov_frame states."""
    var_white = np.array([0.02, 0.02])
    ds = _drive(rng, var_white, np.zeros(2))
    for s in ds.steps:
        for o in s.obs:
            if o.lm_id in (0, 1):
                o.flags |= FLAG_MERGED
                dz = JPX @ (rng.normal(size=2) * np.sqrt(3 * var_white))   # three times more
                o.range_m -= dz[0]
                o.bearing_rad -= dz[1]
    return ds


def test_frame_scale():
    p = Params(merged_var_scale=2.5)
    assert frame_scale(Obs(cls="a", range_m=1, bearing_rad=0, cov=np.eye(2), flags=0x10), p) == 2.5
    assert frame_scale(Obs(cls="a", range_m=1, bearing_rad=0, cov=np.eye(2), flags=0x400), p) == 1.0
    # a landmark of several bands: merged by design
    assert frame_scale(Obs(cls="a", range_m=1, bearing_rad=0, cov=np.eye(2), flags=0x10, grouped=True), p) == 1.0
    with pytest.raises(ValueError, match="--merged-var-scale 0: must be > 0"):
        Params(merged_var_scale=0).check()


def test_run_default():
    from cylslam.cli import _params, build_parser
    assert _params(build_parser().parse_args(["run", "x.jsonl"])).merged_var_scale == 2.0
    assert _params(build_parser().parse_args(["run", "x.jsonl", "--merged-var-scale", "1"])).merged_var_scale == 1.0


@pytest.mark.parametrize("calib", [True, False])
@pytest.mark.parametrize("scale", [1.0, 4.0])
def test_merged_noise_monte_carlo(calib, scale):
    rng = np.random.default_rng(23)
    lm, pose = [], []
    for _ in range(12):
        ds = _merged_drive(rng)
        res = Slam(Params(calib_states=calib, lm_bias="none", batch=True, merged_var_scale=scale)).run(ds)
        m = evaluate(ds, res)
        lm.append(m["anees_landmarks_joint"])
        pose.append(m["anees_poses_joint"])
    if scale == 4.0:
        # 12 runs of 8 landmark dof: chi-square 96 / 96 (sd 0.14); poses 12 x 240 dof (sd 0.026)
        assert 0.7 < np.mean(lm) < 1.35
        assert 0.93 < np.mean(pose) < 1.07
    else:
        # half the views four times as noisy as stated: over-confident landmarks and poses
        assert np.mean(lm) > 1.35
        assert np.mean(pose) > 1.07


def test_grouped_read_from_the_log(tmp_path):
    from cylslam.obslog import read_obslog
    head = '{"type":"header","format":"cyl-observations","version":2}\n{"type":"frame","seq":0,"t":0}\n'
    ob = ('{"type":"obs","seq":0,"t":0,"class":"orange","range_m":2,"bearing_rad":0.1,"cov_rr":0.01,'
          '"cov_rb":0,"cov_bb":0.0001,"flags":16%s}\n')
    f = tmp_path / "g.jsonl"
    f.write_text(head + ob % ',"landmark_model":"cone"' + ob % "")
    obs = read_obslog(str(f)).steps[0].obs
    assert [o.grouped for o in obs] == [True, False]
    assert [frame_scale(o, Params(merged_var_scale=2)) for o in obs] == [1.0, 2.0]
