# SPDX-License-Identifier: BSD-3-Clause
"""The rerun live view, headless: the recording it saves reads back with an entity for the
frames (overlay images), the robot, its trajectory, the observations, the landmarks and their
ellipses, the final map and the truth; and watching the run does not change its result."""
import json
import os
import subprocess
import sys

import pytest

from conftest import FIXTURES, HERE

SHORT = os.path.join(FIXTURES, "synth_short.jsonl")
ENV = dict(os.environ, PYTHONPATH=os.path.dirname(HERE))
rerun = pytest.importorskip("rerun")


def _run(*args):
    r = subprocess.run([sys.executable, "-m", "cylslam", "run", SHORT, "--no-plot", "--fixed-cov", "none", *args],
                       capture_output=True, text=True, env=ENV, timeout=300)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout.strip().splitlines()[-1])


def test_rerun_recording_reads_back_with_every_entity(tmp_path):
    from PIL import Image
    from rerun.chunk import RrdReader
    from cylslam.live import ENTITIES
    seqs = [json.loads(line)["seq"] for line in open(SHORT) if '"type":"frame"' in line]
    imgs = tmp_path / "overlay"
    imgs.mkdir()
    for s in seqs[:5]:     # the overlay of a few frames, as `cyl detect --overlay DIR` names them
        Image.new("RGB", (64, 48), (200, 120, 30)).save(imgs / f"frame_{s:06d}.png")
    rrd = tmp_path / "run.rrd"
    with_view = _run("--out", str(tmp_path / "a"), "--rerun", str(rrd), "--rerun-images", str(imgs))
    chunks = RrdReader(str(rrd)).stream().to_chunks()
    paths = {str(c.entity_path).lstrip("/") for c in chunks}
    assert set(ENTITIES) <= paths, set(ENTITIES) - paths
    rows = {}
    for c in chunks:
        rows[str(c.entity_path).lstrip("/")] = rows.get(str(c.entity_path).lstrip("/"), 0) + c.num_rows
    assert rows["world/robot"] == len(seqs)             # one robot pose per step, as the run goes
    assert rows["camera/overlay"] == 5
    without = _run("--out", str(tmp_path / "b"))
    for k in ("ate_m", "landmark_rmse_m", "anees_landmarks", "association_errors"):
        assert with_view[k] == without[k], k
