# SPDX-License-Identifier: BSD-3-Clause
"""One map from several robots: the rigid fit, and two "robots" cut from the MRCLAM fixture (the
first and second half of robot 2's excerpt; the second's start pose unknown to the graph)."""
import dataclasses
import math
import os

import numpy as np
import pytest

from conftest import FIXTURES
from cylslam import metrics, mrclam
from cylslam.backend import Params, Slam
from cylslam.data import Dataset
from cylslam.multi import evaluate_multi, rigid_fit, run_multi

MR = os.path.join(FIXTURES, "mrclam")


def test_rigid_fit_recovers_a_rotation_and_translation():
    rng = np.random.default_rng(2)
    src = rng.uniform(-5, 5, (6, 2))
    a = 0.7
    R = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    t = np.array([1.5, -2.0])
    Rf, tf = rigid_fit(src, src @ R.T + t)
    assert np.allclose(Rf, R) and np.allclose(tf, t)
    # a reflection is never returned
    Rf, _ = rigid_fit(src, src * [1, -1])
    assert np.linalg.det(Rf) == pytest.approx(1.0)


def _halves(ds, k):
    a = Dataset(name="A", steps=ds.steps[:k], truth_landmarks=ds.truth_landmarks, classes=ds.classes, known_ids=True)
    rest = [dataclasses.replace(s) for s in ds.steps[k:]]
    rest[0] = dataclasses.replace(rest[0], odom=None, odom_cov=None)
    b = Dataset(name="B", steps=rest, truth_landmarks=ds.truth_landmarks, classes=ds.classes, known_ids=True)
    return a, b


def test_two_robots_one_map_places_the_second_by_shared_landmarks():
    ds = mrclam.read_mrclam(MR, 2)
    a, b = _halves(ds, len(ds.steps) // 2)
    p = Params(assoc="known", robust="huber")
    res = run_multi([a, b], ["A", "B"], p)
    assert res.robots == ["A", "B"] and not res.notes
    m = evaluate_multi([a, b], ["A", "B"], res)
    # robot B's start is nowhere in the graph but it lands in the joint frame: its positions are as
    # close to truth as robot A's, and as those of the whole excerpt mapped as one robot
    single = metrics.evaluate(ds, Slam(p).run(ds))
    for lab in ("A", "B"):
        assert m["robots"][lab]["aligned_rmse_joint_frame_m"] < 0.15
    assert m["joint_aligned_rmse_m"] == pytest.approx(single["ate_m"], abs=0.03)
    # landmarks: the excerpt as one robot 0.131 m, as two robots 0.200 m (each half's map less certain)
    assert m["landmark_rmse_aligned_m"] < single["landmark_rmse_aligned_m"] + 0.1
    # the second robot's start, never given, is found within 0.2 m of its true pose
    start_b = res.poses["B"][0]
    assert math.hypot(*(start_b[:2] - b.steps[0].truth[:2])) < 0.2 + m["joint_aligned_rmse_m"]


def test_a_robot_sharing_no_landmark_is_left_out_with_a_note():
    ds = mrclam.read_mrclam(MR, 2)
    a, b = _halves(ds, len(ds.steps) // 2)
    steps = [dataclasses.replace(s, obs=[dataclasses.replace(o, lm_id=o.lm_id + 100) for o in s.obs]) for s in b.steps]
    b = dataclasses.replace(b, steps=steps)
    res = run_multi([a, b], ["A", "B"], Params(assoc="known", robust="huber"))
    assert res.robots == ["A"]
    assert any("B: shares 0 landmark(s)" in n for n in res.notes)


def test_mrclam_summary_combines_the_runs(tmp_path):
    import json
    import subprocess
    import sys
    script = os.path.join(os.path.dirname(__file__), "..", "..", "scripts", "mrclam_summary.py")
    base = {"aligned_rmse_max_m": 0.1, "anees_landmarks_max": 2.0, "landmarks_min": 14, "landmarks_max": 16,
            "parameters": {"assoc": "known"}, "multi_aligned_rmse_max_m": 0.2, "multi_landmark_rmse_m": 0.3,
            "multi_anees_landmarks": 1.0}
    for name, extra in (("known", {"multi_aligned_rmse_max_m": 0.12, "multi_landmark_rmse_m": 0.05}),
                        ("unknown", {"aligned_rmse_max_m": 0.9, "landmarks_min": 20}),
                        ("fixed-known", {"multi_landmark_rmse_m": 0.07})):
        (tmp_path / f"mrclam-{name}.json").write_text("progress line\n" + json.dumps({**base, **extra}) + "\n")
    r = subprocess.run([sys.executable, script, str(tmp_path)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    s = json.loads(r.stdout)
    assert s["unknown_aligned_rmse_max_m"] == 0.9 and s["unknown_landmarks_min"] == 20
    assert s["multi_landmark_rmse_m"] == 0.05 and s["fixed_multi_landmark_rmse_m"] == 0.07
    assert s["known_landmark_anees_max"] == 2.0
    (tmp_path / "mrclam-unknown.json").unlink()
    r = subprocess.run([sys.executable, script, str(tmp_path)], capture_output=True, text=True)
    assert r.returncode == 3 and "mrclam-unknown.json" in r.stderr
    (tmp_path / "mrclam-unknown.json").write_text(json.dumps({"aligned_rmse_max_m": 1.0}) + "\n")
    r = subprocess.run([sys.executable, script, str(tmp_path)], capture_output=True, text=True)
    assert r.returncode == 3 and "lacks" in r.stderr and "Traceback" not in r.stderr


def test_cli_multi_summary_has_what_the_summary_reads(tmp_path):
    # the keys scripts/mrclam_summary.py reads, from a real run (the fixture: robot 2, 2 minutes)
    import json
    import subprocess
    import sys
    from conftest import HERE
    env = dict(os.environ, PYTHONPATH=os.path.dirname(HERE))
    out = tmp_path / "s.json"
    r = subprocess.run([sys.executable, "-m", "cylslam", "mrclam", "--dir", MR, "--robot", "2", "--multi",
                        "--noise", "learned", "--no-plot", "--summary-out", str(out)],
                       capture_output=True, text=True, env=env, timeout=300)
    assert r.returncode == 0, r.stderr
    s = json.loads(out.read_text())
    assert s == json.loads(r.stdout.strip().splitlines()[-1])
    for k in ("aligned_rmse_max_m", "anees_landmarks_max", "landmarks_min", "landmarks_max",
              "multi_aligned_rmse_max_m", "multi_landmark_rmse_m", "multi_anees_landmarks", "parameters"):
        assert s[k] is not None, k
    assert s["parameters"]["noise"] == "learned" and s["parameters"]["robust"] == "cauchy"
    assert s["parameters"]["reassoc"] == 0 and s["parameters"]["exclusion"] is False
    assert s["parameters"]["odom_corr"] == "state"      # the one map carries the odometry's states
    assert s["multi_aligned_rmse_max_m"] < 0.2
    # an output directory that does not exist: refused before the run
    r = subprocess.run([sys.executable, "-m", "cylslam", "mrclam", "--dir", MR, "--robot", "2",
                        "--summary-out", str(tmp_path / "no" / "s.json")], capture_output=True, text=True, env=env)
    assert r.returncode == 4 and "no such directory" in r.stderr
    # --noise-model without --noise learned
    r = subprocess.run([sys.executable, "-m", "cylslam", "mrclam", "--dir", MR, "--robot", "2",
                        "--noise-model", str(out)], capture_output=True, text=True, env=env)
    assert r.returncode == 2 and "--noise learned" in r.stderr
    # --odom-corr without --noise learned: the fixed models have no correlation to use
    r = subprocess.run([sys.executable, "-m", "cylslam", "mrclam", "--dir", MR, "--robot", "2",
                        "--odom-corr", "inflate"], capture_output=True, text=True, env=env)
    assert r.returncode == 2 and "--odom-corr needs --noise learned" in r.stderr


def test_robots_with_identities_on_some_observations_only():
    # as with coded and plain landmarks: every other observation without its identity; each robot
    # alone is mapped with mixed association, and the one map takes the observations with one
    ds = mrclam.read_mrclam(MR, 2)
    a, b = _halves(ds, len(ds.steps) // 2)
    out = []
    for d in (a, b):
        k = 0
        steps = []
        for s in d.steps:
            obs = []
            for o in s.obs:
                obs.append(o if k % 2 == 0 else dataclasses.replace(o, lm_id=None))
                k += 1
            steps.append(dataclasses.replace(s, obs=obs))
        out.append(dataclasses.replace(d, steps=steps, known_ids=False))
    res = run_multi(out, ["A", "B"], Params(robust="huber"))
    assert res.robots == ["A", "B"]
    n_id = sum(1 for d in out for s in d.steps for o in s.obs if o.lm_id is not None)
    assert res.stats["observations_used"] == n_id
    m = evaluate_multi(out, ["A", "B"], res)
    assert m["joint_aligned_rmse_m"] < 0.15


def test_multiband_check_names_each_missed_target():
    # scripts/multiband.py --check: the targets of make multiband, each missed one named
    import importlib.util
    path = os.path.join(os.path.dirname(__file__), "..", "..", "scripts", "multiband.py")
    spec = importlib.util.spec_from_file_location("multiband_script", path)
    mb = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mb)
    good = {"single_observation_frac": 0.95, "id_correct_frac": 1.0, "id_wrong_confident_frac": 0.005,
            "range_bias_rel_max": 0.01, "slam_association_errors_with_ids": 0,
            "slam_ate_with_ids_le_gated_frac": 1.0, "cone_confidence_frac": 0.9}
    assert mb.check(good) == []
    for key, bad in (("single_observation_frac", 0.949), ("id_correct_frac", 0.98), ("id_wrong_confident_frac", 0.006),
                     ("range_bias_rel_max", 0.0101), ("range_bias_rel_max", float("nan")),
                     ("slam_association_errors_with_ids", 1), ("slam_ate_with_ids_le_gated_frac", 0.667),
                     ("cone_confidence_frac", 0.89), ("cone_confidence_frac", None)):
        missed = mb.check({**good, key: bad})
        assert len(missed) == 1 and missed[0].startswith(key), (key, bad, missed)
