# SPDX-License-Identifier: BSD-3-Clause
import json
import os

import numpy as np
import pytest

from conftest import FIXTURES
from cylslam.obslog import ObsLogError, read_obslog

MAL = os.path.join(FIXTURES, "malformed.jsonl")


def test_short_synthetic_log_reads_completely():
    path = os.path.join(FIXTURES, "synth_short.jsonl")
    ds = read_obslog(path)
    # independent count straight from the JSON lines
    recs = [json.loads(l) for l in open(path)]
    n_frames = sum(r["type"] == "frame" for r in recs)
    n_obs = sum(r["type"] == "obs" for r in recs)
    assert len(ds.steps) == n_frames == 300
    assert ds.n_obs() == n_obs
    assert len(ds.truth_landmarks) == 16
    assert ds.classes == ["orange", "green"]
    assert all(s.truth is not None for s in ds.steps)
    assert ds.steps[0].odom is None and all(s.odom is not None for s in ds.steps[1:])
    assert not ds.known_ids and ds.notes == []


def test_malformed_strict_names_file_and_line():
    with pytest.raises(ObsLogError) as e:
        read_obslog(MAL)
    assert str(e.value).startswith(f"{MAL}:7: not valid JSON")


def test_malformed_skip_counts_every_bad_line():
    # line 19, frame 4's odom line, is malformed: skipping it loses a step of the motion, which
    # is an error of its own unless bridged
    with pytest.raises(ObsLogError, match=r"malformed.jsonl:17: frame seq 4 has no odom line"):
        read_obslog(MAL, skip_bad=True)
    ds = read_obslog(MAL, skip_bad=True, bridge_gaps=True)
    assert ds.n_skipped == 5
    text = "\n".join(ds.notes)
    for line in (7, 11, 15, 18, 19):
        assert f"{MAL}:{line}:" in text
    assert "truncated last line" in text and f"{MAL}:23" in text
    assert "unknown type 'future_record'" in text
    assert f"bridged 1 lost odometry step(s)" in text and f"{MAL}:17 (frame seq 4)" in text
    # the good observations are all kept: lines 4, 10, 21
    assert [o.range_m for s in ds.steps for o in s.obs] == [2.0, 1.8, 1.5]
    assert [s.seq for s in ds.steps] == [0, 1, 2, 3, 4, 5]


@pytest.mark.parametrize("line,msg", [
    ('{"type":"obs","seq":0,"t":0,"class":"orange","range_m":1,"bearing_rad":0,"cov_rr":0.01,'
     '"cov_rb":0,"cov_bb":1e-4}', "'obs' line before any 'frame' line"),
    ('{"type":"frame","seq":0,"t":0}\n{"type":"obs","seq":0,"t":0,"class":"orange","range_m":1,'
     '"bearing_rad":0,"cov_rr":0.01,"cov_rb":0}', "missing field 'cov_bb'"),
    ('{"type":"frame","seq":0,"t":0,"n_obs":2}\n{"type":"frame","seq":1,"t":0.1}',
     "announces n_obs=2 but 0 obs lines follow"),
    ('[1,2,3]', "not a JSON object"),
    ('{"type":"frame","seq":0,"t":NaN}', "field 't' is not finite"),
])
def test_each_malformed_kind(tmp_path, line, msg):
    p = tmp_path / "bad.jsonl"
    p.write_text('{"type":"header","format":"cyl-observations","version":1}\n' + line + "\n")
    with pytest.raises(ObsLogError) as e:
        read_obslog(str(p))
    assert msg in str(e.value)
    assert str(e.value).startswith(f"{p}:")


@pytest.mark.parametrize("fields,msg", [
    ('"camera":"truth_landmark"', "header field 'camera' must be an object"),   # fuzz_obslog finding
    ('"classes":"orange"', "header field 'classes' must be a list of strings"),
    ('"source":7', "header field 'source' must be a string"),
    ('"camera":{"calib_cov":[1,2,3]}', "'calib_cov' must be a list of 64 finite numbers"),
    ('"camera":{"calib_cov":[%s]}' % ",".join(["-1"] + ["0"] * 63),
     "camera.calib_cov covariance is not positive semi-definite"),
])
def test_header_fields_checked(tmp_path, fields, msg):
    # each of these used to be silently ignored or to raise a bare AttributeError downstream
    p = tmp_path / "hdr.jsonl"
    p.write_text('{"type":"header","format":"cyl-observations","version":1,' + fields + '}\n'
                 '{"type":"frame","seq":0,"t":0}\n')
    with pytest.raises(ObsLogError) as e:
        read_obslog(str(p))
    assert str(e.value).startswith(f"{p}:1: ") and msg in str(e.value)


def test_null_camera_and_calib_cov_count_as_absent(tmp_path):
    for fields in ('"camera":null', '"camera":{"fx":500,"calib_cov":null}'):
        p = tmp_path / "hdr.jsonl"
        p.write_text('{"type":"header","format":"cyl-observations","version":1,' + fields + '}\n'
                     '{"type":"frame","seq":0,"t":0}\n')
        assert read_obslog(str(p)).calib_cov is None


def test_calib_cov_rounded_rank_deficient_is_accepted(tmp_path):
    # a fixed aspect ratio makes the fx/fy block rank 1; printed with 10 digits (older frontends)
    # its smaller eigenvalue can come out slightly negative: still a valid prior
    m = np.zeros((8, 8))
    m[:2, :2] = np.outer([1.0, 1.0 / 0.9987], [1.0, 1.0 / 0.9987]) * 0.20839225
    for i in range(2, 8):
        m[i, i] = 1e-4
    txt = ",".join("%.10g" % v for v in m.ravel())
    assert np.linalg.eigvalsh(np.array([float(x) for x in txt.split(",")]).reshape(8, 8)).min() < 0
    p = tmp_path / "cc.jsonl"
    p.write_text('{"type":"header","format":"cyl-observations","version":1,"camera":{"calib_cov":['
                 + txt + ']}}\n{"type":"frame","seq":0,"t":0}\n')
    assert read_obslog(str(p)).calib_cov.shape == (8, 8)


@pytest.mark.parametrize("line,msg", [
    # found by review, not by the fuzzer: each used to escape as a bare Python exception
    ('{"type":"frame","seq":0,"t":1' + "0" * 400 + '}', "field 't' is not finite"),        # OverflowError
    ('{"type":"frame","seq":0,"t":1' + "0" * 5000 + '}', "not valid JSON"),                # ValueError
    ("[" * 5000 + "]" * 5000, "not valid JSON"),                                           # RecursionError
    ('{"type":"frame","seq":0,"t":0}\n{"type":"obs","seq":0,"t":0,"class":"orange","range_m":1,'
     '"bearing_rad":0,"cov_rr":1.7e308,"cov_rb":1.7e308,"cov_bb":-1e307}', "out of range"),  # inf eigenvalue
    ('{"type":"frame","seq":0,"t":0}\n{"type":"frame","seq":5,"t":1}\n'
     '{"type":"frame","seq":3,"t":2}', "frame seq 3 does not increase (previous 5)"),        # no-odom frame
])
def test_review_findings_are_obslog_errors(tmp_path, line, msg):
    p = tmp_path / "bad.jsonl"
    p.write_text('{"type":"header","format":"cyl-observations","version":1}\n' + line + "\n")
    with pytest.raises(ObsLogError) as e:
        read_obslog(str(p))
    assert msg in str(e.value) and str(e.value).startswith(f"{p}:")


def test_missing_file_is_an_obslog_error(tmp_path):
    with pytest.raises(ObsLogError, match=r"nope.jsonl: cannot read"):
        read_obslog(str(tmp_path / "nope.jsonl"))


def test_header_version_and_format_checked(tmp_path):
    p = tmp_path / "v3.jsonl"
    p.write_text('{"type":"header","format":"cyl-observations","version":3}\n')
    with pytest.raises(ObsLogError, match=r"v3.jsonl:1: unsupported version 3"):
        read_obslog(str(p))
    p.write_text('{"type":"header","format":"other","version":1}\n')
    with pytest.raises(ObsLogError, match=r":1: format 'other'"):
        read_obslog(str(p))
    p.write_text('{"type":"frame","seq":0,"t":0}\n')
    with pytest.raises(ObsLogError, match=r":1: first line must be the header"):
        read_obslog(str(p))


def test_covariances_kept_in_range_bearing_order(tmp_path):
    p = tmp_path / "one.jsonl"
    p.write_text('{"type":"header","format":"cyl-observations","version":1}\n'
                 '{"type":"frame","seq":4,"t":1.5,"n_obs":1}\n'
                 '{"type":"obs","seq":4,"t":1.5,"class":"green","range_m":2.5,"bearing_rad":-0.2,'
                 '"cov_rr":0.04,"cov_rb":0.001,"cov_bb":0.0009,"confidence":0.7,"flags":16,'
                 '"landmark_id":12}\n')
    ds = read_obslog(str(p))
    o = ds.steps[0].obs[0]
    assert np.allclose(o.cov, [[0.04, 0.001], [0.001, 0.0009]])
    assert (o.cls, o.range_m, o.bearing_rad, o.confidence, o.flags, o.lm_id) == \
        ("green", 2.5, -0.2, 0.7, 16, 12)
    assert ds.known_ids


def test_null_fields_allowed_only_on_unusable_observations(tmp_path):
    head = ('{"type":"header","format":"cyl-observations","version":1}\n'
            '{"type":"frame","seq":0,"t":0}\n')
    obs = ('{"type":"obs","seq":0,"t":0,"class":"orange","range_m":0,"bearing_rad":0.1,'
           '"cov_rr":null,"cov_rb":null,"cov_bb":1e-4,"flags":%d}\n')
    p = tmp_path / "n.jsonl"
    p.write_text(head + obs % 0x100)
    ds = read_obslog(str(p))
    assert np.isnan(ds.steps[0].obs[0].cov[0, 0])
    p.write_text(head + obs % 0)
    with pytest.raises(ObsLogError, match=r"n.jsonl:3: field 'cov_rr' must be a number"):
        read_obslog(str(p))


def test_singular_odometry_only_an_error_when_used(tmp_path):
    p = tmp_path / "o.jsonl"
    odo = '{"type":"odom","seq":%d,"t":0,"dx_m":0,"dy_m":0,"dtheta_rad":0,"cov":[0,0,0,0,0,0]}\n'
    p.write_text('{"type":"header","format":"cyl-observations","version":1}\n'
                 '{"type":"frame","seq":0,"t":0}\n' + odo % 0 +
                 '{"type":"frame","seq":1,"t":0.1}\n' + odo % 1)
    with pytest.raises(ObsLogError, match=r"o.jsonl:5: odometry covariance is singular"):
        read_obslog(str(p))



def test_lost_odometry_step_is_an_error_unless_bridged():
    # the odom line of frame 150 lost: the robot's motion in that step is unknown
    from cylslam.obslog import BRIDGE_SIGMAS, parse_obslog
    src = os.path.join(FIXTURES, "synth_short.jsonl")
    text = open(src).read()
    tag = '{"type":"odom","seq":150,'
    assert text.count(tag) == 1
    lines = text.splitlines(keepends=True)
    k = next(i for i, l in enumerate(lines) if l.startswith(tag))
    raw = "".join(lines[:k] + lines[k + 1:]).encode()
    with pytest.raises(ObsLogError, match=r"frame seq 150 has no odom line in a log with odometry"):
        parse_obslog(raw, "lost.jsonl")
    # a malformed odom line skipped by skip_bad is the same loss: still an error, not silence
    bad = lines[:k] + [lines[k].replace('"dx_m":', '"dx_m":"x","dy":', 1)] + lines[k + 1:]
    with pytest.raises(ObsLogError, match=r"frame seq 150 has no odom line"):
        parse_obslog("".join(bad).encode(), "bad.jsonl", skip_bad=True)
    ds = parse_obslog(raw, "lost.jsonl", bridge_gaps=True)
    ref = parse_obslog(text.encode(), "ref.jsonl")
    assert len(ds.steps) == len(ref.steps)
    s = next(s for s in ds.steps if s.seq == 150)
    assert np.allclose(s.odom, 0) and np.allclose(np.sqrt(np.diag(s.odom_cov)), BRIDGE_SIGMAS)
    assert any("bridged 1 lost odometry step" in n and f"lost.jsonl:" in n for n in ds.notes)


def test_log_without_odometry_attaches_observations_to_the_first_pose():
    from cylslam.obslog import parse_obslog
    src = os.path.join(FIXTURES, "synth_short.jsonl")
    raw = "".join(l for l in open(src) if '"type":"odom"' not in l).encode()
    ds = parse_obslog(raw, "camera_only.jsonl")
    ref = parse_obslog(open(src, "rb").read(), "ref.jsonl")
    assert len(ds.steps) == 1 and ds.n_obs() == ref.n_obs()
    assert any("without odometry" in n for n in ds.notes)


def test_incomplete_last_frame_is_dropped_with_a_note():
    # a writer interrupted between a frame line and its odom line: the log ends one step short
    from cylslam.obslog import parse_obslog
    src = os.path.join(FIXTURES, "synth_short.jsonl")
    lines = open(src).read().splitlines(keepends=True)
    k = max(i for i, l in enumerate(lines) if l.startswith('{"type":"odom",'))
    ds = parse_obslog("".join(lines[:k]).encode(), "cut.jsonl")
    ref = parse_obslog(open(src, "rb").read(), "ref.jsonl")
    assert len(ds.steps) == len(ref.steps) - 1
    assert any("the last frame" in n and "dropped as incomplete" in n for n in ds.notes)
