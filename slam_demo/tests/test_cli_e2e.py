# SPDX-License-Identifier: BSD-3-Clause
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import FIXTURES, HERE
from cylslam import backend, metrics
from cylslam.obslog import read_obslog

SHORT = os.path.join(FIXTURES, "synth_short.jsonl")
ENV = dict(os.environ, PYTHONPATH=os.path.dirname(HERE))


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "cylslam", *args], capture_output=True,
                          text=True, env=ENV, timeout=120)


@pytest.mark.parametrize("cmd", ["run", "synth", "mrclam", "mrclam-noise", "victoria", "excerpt"])
def test_help(cmd):
    r = _cli(cmd, "--help")
    assert r.returncode == 0 and "usage:" in r.stdout


def test_synthetic_end_to_end_unknown_association():
    ds = read_obslog(SHORT)
    res = backend.Slam(backend.Params(assoc="unknown")).run(ds)
    m = metrics.evaluate(ds, res)
    assert m["association_errors"] == 0
    assert m["landmarks_matched"] == m["landmarks_estimated"]
    assert m["clutter_used"] == 0
    assert res.stats["dropped_confidence"] > 0 and res.stats["dropped_flags"] > 0
    assert m["ate_m"] < 0.05 and m["landmark_rmse_m"] < 0.25
    assert m["ate_m"] < m["ate_isam_m"] + 0.01
    assert 0.3 < m["anees_poses"] < 3.0


def test_cli_run_writes_outputs_and_json_last_line(tmp_path):
    r = _cli("run", SHORT, "--out", str(tmp_path), "--fixed-cov", "mean")
    assert r.returncode == 0, r.stderr
    last = json.loads(r.stdout.strip().splitlines()[-1])
    for k in ("ate_m", "landmark_rmse_m", "anees_landmarks", "association_errors",
              "ate_fixed_cov_m"):
        assert last[k] is not None
    for f in ("trajectory.csv", "landmarks.csv", "summary.json", "plot.png", "trajectory.tum", "truth.tum",
              "trajectory_kitti.txt", "truth_kitti.txt", "landmarks.tum"):
        assert os.path.getsize(tmp_path / f) > 0


def test_evo_reads_the_tum_output_and_agrees_on_ate(tmp_path):
    """evo (the standard trajectory evaluation tool) on trajectory.tum against truth.tum, aligned
    with Umeyama (SE(3), as `evo_ape tum truth.tum trajectory.tum -a`), gives the run's own ATE."""
    from evo.core import metrics as evo_metrics
    from evo.core import sync
    from evo.tools import file_interface
    r = _cli("run", SHORT, "--out", str(tmp_path), "--fixed-cov", "none", "--no-plot")
    assert r.returncode == 0, r.stderr
    ate = json.loads(r.stdout.strip().splitlines()[-1])["ate_m"]
    ref = file_interface.read_tum_trajectory_file(str(tmp_path / "truth.tum"))
    est = file_interface.read_tum_trajectory_file(str(tmp_path / "trajectory.tum"))
    ref, est = sync.associate_trajectories(ref, est)
    est.align(ref, correct_scale=False)
    ape = evo_metrics.APE(evo_metrics.PoseRelation.translation_part)
    ape.process_data((ref, est))
    evo_ate = ape.get_statistic(evo_metrics.StatisticsType.rmse)
    assert ate > 0.001 and abs(evo_ate - ate) < 1e-3, (evo_ate, ate)
    # KITTI files: one 3x4 row-major pose per line, the same poses
    k = np.loadtxt(tmp_path / "trajectory_kitti.txt")
    t = np.loadtxt(tmp_path / "trajectory.tum")
    assert k.shape == (len(t), 12)
    np.testing.assert_allclose(k[:, [3, 7]], t[:, [1, 2]], atol=1e-8)
    np.testing.assert_allclose(np.arctan2(k[:, 4], k[:, 0]), 2 * np.arctan2(t[:, 6], t[:, 7]), atol=1e-9)
    traj = np.genfromtxt(tmp_path / "trajectory.csv", delimiter=",", names=True)
    assert len(traj) == 300


def test_cli_malformed_exit_code_and_message(tmp_path):
    mal = os.path.join(FIXTURES, "malformed.jsonl")
    r = _cli("run", mal, "--no-plot", "--fixed-cov", "none", "--out", "/dev/null/x")
    assert r.returncode == 3
    assert f"{mal}:7: not valid JSON" in r.stderr
    r = _cli("run", mal, "--skip-bad", "--no-plot", "--fixed-cov", "none", "--out", str(tmp_path))
    assert r.returncode == 3 and "frame seq 4 has no odom line" in r.stderr   # a lost step
    r = _cli("run", mal, "--skip-bad", "--bridge-gaps", "--no-plot", "--fixed-cov", "none", "--out",
             str(tmp_path))
    assert r.returncode == 0, r.stderr
    assert "bridged 1 lost odometry step(s)" in r.stdout
    assert "skipped 5 malformed line(s)" in r.stdout
    assert json.loads(r.stdout.strip().splitlines()[-1])["skipped_lines"] == 5


def test_cli_missing_file():
    r = _cli("run", "/nonexistent/log.jsonl")
    assert r.returncode == 3 and "/nonexistent/log.jsonl" in r.stderr


def test_victoria_reader():
    from cylslam.victoria import read_victoria
    ds = read_victoria(max_poses=300)
    assert len(ds.steps) == 300
    full = read_victoria()
    assert len(full.steps) == 6969 and full.n_obs() == 3640
    assert len({o.lm_id for s in full.steps for o in s.obs}) == 151


def test_real_frontend_log_reads_unchanged():
    """150 frames written by the project's frontend (`cyl detect synthetic:7`), as is."""
    ds = read_obslog(os.path.join(FIXTURES, "frontend_short.jsonl"))
    assert len(ds.steps) == 150 and ds.n_obs() == 355 and len(ds.truth_landmarks) == 14
    res = backend.Slam(backend.Params(assoc="unknown")).run(ds)
    m = metrics.evaluate(ds, res)
    assert m["association_errors"] == 0 and m["clutter_used"] == 0
    assert m["ate_m"] < 0.02 and m["landmark_rmse_m"] < 0.1


def test_fixed_covariance_that_maps_nothing_is_reported_failed(monkeypatch, capsys):
    # A fixed covariance 1e-12 times the mean gates every observation out: no landmark is mapped,
    # so that run is no baseline (its "ATE" would be dead reckoning's) and is reported as failed.
    from cylslam import cli
    monkeypatch.setattr(cli, "FIXED_GRID", (1e-12,))
    ds = read_obslog(SHORT)
    args = cli.build_parser().parse_args(["run", SHORT, "--no-plot", "--fixed-cov", "grid"])
    s = cli.process(ds, args, "t", None)
    assert "fixed_cov_failed" in s and "ate_fixed_cov_m" not in s
    cli.print_summary(s)
    assert "FAILED" in capsys.readouterr().out
    assert not any("fixed-cov" in f for f in cli.check_synthetic(s))


def test_cli_unwritable_output_is_a_clear_error():
    # /proc refuses new folders: exit 4 with the path named, no traceback, before any work
    r = _cli("run", SHORT, "--no-plot", "--fixed-cov", "none", "--out", "/proc/nope/x")
    assert r.returncode == 4, r.stderr
    assert "/proc/nope/x: cannot create the output folder" in r.stderr
    assert "Traceback" not in r.stderr


def test_cli_run_reads_stdin(tmp_path):
    # `run -` reads the log from standard input (as behind `cyl detect ... --out -`)
    with open(SHORT, "rb") as fh:
        r = subprocess.run([sys.executable, "-m", "cylslam", "run", "-", "--no-plot", "--fixed-cov", "none",
                            "--out", str(tmp_path)], stdin=fh, capture_output=True, text=True, env=ENV, timeout=120)
    assert r.returncode == 0, r.stderr
    last = json.loads(r.stdout.strip().splitlines()[-1])
    ref = json.loads(_cli("run", SHORT, "--no-plot", "--fixed-cov", "none", "--out",
                          str(tmp_path / "f")).stdout.strip().splitlines()[-1])
    assert last["ate_m"] == ref["ate_m"] and last["association_errors"] == ref["association_errors"]
    r = subprocess.run([sys.executable, "-m", "cylslam", "run", "-", "--no-plot"], input="{\"type\":",
                       capture_output=True, text=True, env=ENV, timeout=60)
    assert r.returncode == 3 and "<stdin>:1" in r.stderr


def test_cli_run_behind_cyl_detect_pipe(tmp_path):
    # the frontend's stdout straight into the back end: cyl detect ... --out - | cylslam run -
    cyl = os.path.join(os.path.dirname(os.path.dirname(HERE)), "build", "cyl")
    if not os.path.exists(cyl):
        pytest.skip("build/cyl not built (make test builds it first)")
    det = subprocess.Popen([cyl, "detect", "synthetic:3", "--max-frames", "60", "--size", "orange=0.10,0.30",
                            "--size", "green=0.10,0.30", "--out", "-", "--quiet"],
                           stdout=subprocess.PIPE, cwd=os.path.dirname(os.path.dirname(HERE)))
    r = subprocess.run([sys.executable, "-m", "cylslam", "run", "-", "--no-plot", "--fixed-cov", "none",
                        "--out", str(tmp_path)], stdin=det.stdout, capture_output=True, text=True, env=ENV,
                       timeout=300)
    det.stdout.close()
    assert det.wait(timeout=60) == 0
    assert r.returncode == 0, r.stderr
    assert "60 poses" in r.stdout
    assert json.loads(r.stdout.strip().splitlines()[-1])["ate_m"] < 0.05


def test_version_is_the_librarys():
    import re
    import cylslam
    hdr = open(os.path.join(os.path.dirname(os.path.dirname(HERE)), "libcyl", "include", "cyl", "version.h")).read()
    v = re.search(r'#define CYL_VERSION_STRING "([^"]+)"', hdr).group(1)
    assert cylslam.__version__ == v
    r = _cli("--version")
    assert r.returncode == 0 and r.stdout.strip() == f"cylslam {v}"


@pytest.mark.parametrize("extra,why", [(["--reassoc", "-1"], "must be >= 0"),
                                       (["--reassoc", "3", "--no-batch"], "needs the batch pass"),
                                       (["--reassoc", "3", "--calib-states"], "cannot run with --calib-states"),
                                       (["--starts", "1,0.5"], "--starts needs --reassoc")])
def test_reassoc_conflicts_are_usage_errors(tmp_path, extra, why):
    r = subprocess.run([sys.executable, "-m", "cylslam", "run", os.path.join(FIXTURES, "synth_short.jsonl"),
                        "--no-plot", "--out", str(tmp_path / "o")] + extra,
                       capture_output=True, text=True, env=ENV)
    assert r.returncode == 2 and why in r.stderr and "Traceback" not in r.stderr
    assert not (tmp_path / "o").exists()        # refused before any work
