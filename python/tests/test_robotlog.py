# SPDX-License-Identifier: BSD-3-Clause
"""cyl-robotlog: robot logs in (ROS 1 bags, ROS 2 sqlite3 and MCAP bags, CSV odometry) and out,
checked on fixtures made here from the synthetic scene (no outside data)."""
import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

from cyl import rawlog, robotlog

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD = os.environ.get("CYL_BUILD", os.path.join(ROOT, "build"))
CALIB = os.path.join(ROOT, "calib_data", "synthetic_camera.yaml")
TABLE = os.path.join(ROOT, "calib_data", "synthetic.cylt")
needs_tools = pytest.mark.skipif(not os.path.exists(os.path.join(BUILD, "cyl-render")), reason="needs build/ tools")
TOPICS = ["--image-topic", "/camera/image_raw", "--odom-topic", "/odom", "--truth-topic", "/ground_truth",
          "--truth-landmarks-topic", "/truth/landmarks", "--classes", "orange,green", "-q"]


def cli(*args):
    return subprocess.run([sys.executable, "-m", "cyl.robotlog", *args], capture_output=True, text=True)


@pytest.fixture(scope="module")
def drive(tmp_path_factory):
    d = tmp_path_factory.mktemp("drive")
    raw = str(d / "drive.cylraw")
    subprocess.run([os.path.join(BUILD, "cyl-render"), "-o", raw, "-n", "24", "-s", "5", "-q"], check=True)
    return raw


def records(path):
    with rawlog.Reader(path) as r:
        return r.info, list(r)


def detect(raw, out):
    subprocess.run([os.path.join(BUILD, "cyl"), "detect", raw, "--table", TABLE, "--calib", CALIB, "--size",
                    "orange=0.10,0.30", "--size", "green=0.10,0.30", "--out", out, "--quiet"], check=True)
    obs = {}
    for line in open(out):
        r = json.loads(line)
        if r["type"] == "obs":
            obs.setdefault(r["seq"], []).append(r)
    return obs


@needs_tools
@pytest.mark.parametrize("storage", ["mcap", "sqlite3", "ros1"])
def test_bag_round_trip_keeps_every_record(tmp_path, drive, storage):
    bag = str(tmp_path / ("d.bag" if storage == "ros1" else "d"))
    r = cli("write-bag", drive, "-o", bag, "--storage", storage, "--calib", CALIB)
    assert r.returncode == 0, r.stderr
    out = str(tmp_path / "back.cylraw")
    r = cli("import-bag", bag, "-o", out, *TOPICS)
    assert r.returncode == 0, r.stderr
    assert f"({storage})" in r.stderr and "24 frames with odometry" in r.stderr
    ia, a = records(drive)
    ib, b = records(out)
    assert (ia.fourcc, ia.width, ia.height, ia.stride) == (ib.fourcc, ib.width, ib.height, ib.stride)
    assert [x.type for x in a] == [x.type for x in b]
    for x, y in zip(a, b):
        assert x.seq == y.seq and y.t_ns - x.t_ns == 1_000_000_000   # write-bag's default time offset
        if x.type == rawlog.FRAME:
            assert x.payload == y.payload
        elif x.type == rawlog.ODOMETRY:
            (da, ca), (db, cb) = x.odometry(), y.odometry()
            np.testing.assert_allclose(db, da, rtol=0, atol=1e-12)
            np.testing.assert_allclose(cb, ca, rtol=1e-12, atol=1e-20)
        elif x.type == rawlog.TRUTH_POSE:
            np.testing.assert_allclose(y.truth_pose(), x.truth_pose(), rtol=0, atol=1e-12)
        else:
            assert x.truth_landmark() == y.truth_landmark()


@needs_tools
@pytest.mark.parametrize("storage", ["mcap", "sqlite3", "ros1"])
def test_imported_bag_gives_the_same_observations(tmp_path, drive, storage):
    """The same observation log as the direct path: the SLAM demo's result is then the same too."""
    bag, out = str(tmp_path / ("d.bag" if storage == "ros1" else "d")), str(tmp_path / "back.cylraw")
    assert cli("write-bag", drive, "-o", bag, "--storage", storage, "--calib", CALIB).returncode == 0
    assert cli("import-bag", bag, "-o", out, *TOPICS).returncode == 0
    a, b = detect(drive, str(tmp_path / "a.jsonl")), detect(out, str(tmp_path / "b.jsonl"))
    keys = ("class", "range_m", "bearing_rad", "cov_rr", "cov_rb", "cov_bb", "u_px", "v_px", "bbox_px", "confidence")
    assert sum(map(len, a.values())) > 20
    assert {s: [[o[k] for k in keys] for o in v] for s, v in a.items()} == \
        {s: [[o[k] for k in keys] for o in v] for s, v in b.items()}


@needs_tools
def test_jpeg_bag_finds_the_same_landmarks_within_jpeg_error(tmp_path, drive):
    bag, out = str(tmp_path / "j"), str(tmp_path / "j.cylraw")
    assert cli("write-bag", drive, "-o", bag, "--jpeg", "--calib", CALIB).returncode == 0
    r = cli("import-bag", bag, "-o", out, *TOPICS[:1], "/camera/image_raw/compressed", *TOPICS[2:],
            "--camera-info-out", str(tmp_path / "ci.yaml"))
    assert r.returncode == 0, r.stderr
    assert records(out)[0].fourcc == "YU12"
    a, b = detect(drive, str(tmp_path / "a.jsonl")), detect(out, str(tmp_path / "b.jsonl"))
    du = []
    for s, lst in a.items():
        for o in lst:
            if o["confidence"] < 0.5:
                continue
            near = [q for q in b.get(s, []) if q["class"] == o["class"]]
            assert near, (s, o["class"])
            du.append(min(abs(q["u_px"] - o["u_px"]) for q in near))
    assert len(du) > 10 and max(du) < 2.0 and float(np.median(du)) < 1.0, du
    # the camera_info written out reads back as the camera the bag was made with (less the mount)
    import cyl
    got, want = cyl.load_camera(str(tmp_path / "ci.yaml")).fields(), cyl.load_camera(CALIB).fields()
    for k in ("width", "height", "fx_px", "fy_px", "cx_px", "cy_px", "k1", "k2", "p1", "p2", "k3"):
        assert got[k] == want[k], k


def test_rgb_to_i420_hand_values():
    # BT.601 studio range: white 235/128/128, black 16/128/128, red 82/90/240, green 145/54/34, blue 41/240/110
    px = np.array([[[255, 255, 255]] * 2] * 2 + [[[0, 0, 0]] * 2] * 2 + [[[255, 0, 0]] * 2] * 2 +
                  [[[0, 255, 0]] * 2] * 2 + [[[0, 0, 255]] * 2] * 2, np.uint8).reshape(10, 2, 3)
    b = robotlog.rgb_to_i420(px)
    y, u, v = np.frombuffer(b[:20], np.uint8), np.frombuffer(b[20:25], np.uint8), np.frombuffer(b[25:], np.uint8)
    assert list(y[::4]) == [235, 16, 82, 145, 41]
    assert list(u) == [128, 128, 90, 54, 240]
    assert list(v) == [128, 128, 240, 34, 110]


def test_interpolation_and_increments_by_hand():
    t = robotlog.PoseTrack("t")
    t.add(0, (0.0, 0.0, 0.0))
    t.add(1_000_000_000, (1.0, 0.0, math.pi / 2))
    t.add(2_000_000_000, (1.0, 1.0, math.pi / 2))
    p, near, gap = t.at(500_000_000)
    assert p == pytest.approx((0.5, 0.0, math.pi / 4)) and gap == 1.0 and near in (0, 1)
    # the heading takes the shorter arc across +-pi
    u = robotlog.PoseTrack("u")
    u.add(0, (0, 0, math.pi - 0.1))
    u.add(10, (0, 0, -math.pi + 0.1))
    assert abs(abs(u.at(5)[0][2]) - math.pi) < 1e-12
    # increments: the pose of b in a's frame
    assert robotlog.between((1, 0, math.pi / 2), (1, 1, math.pi / 2)) == pytest.approx((1.0, 0.0, 0.0))
    rep = robotlog.ImportReport()
    st = robotlog.odometry_records([0, 1_000_000_000, 2_000_000_000, 3_000_000_000], t, robotlog.OdomNoise(), 2.0,
                                   False, rep)
    assert st[0][0] == (0.0, 0.0, 0.0) and st[3] is None and rep.dropped_after == 1
    assert st[1][0] == pytest.approx((1.0, 0.0, math.pi / 2)) and st[2][0] == pytest.approx((1.0, 0.0, 0.0))
    # no twist covariance: the model (5% of 1 m + 0.1 mm)^2, said so in the report
    assert st[2][1][0] == pytest.approx((0.05 + 1e-4) ** 2) and rep.model_covariance_steps == 2


def test_gaps_refused_unless_bridged_and_then_reported():
    t = robotlog.PoseTrack("odom.csv")
    t.add(0, (0, 0, 0))
    t.add(2_000_000_000, (2, 0, 0))
    with pytest.raises(robotlog.RobotLogError, match=r"odom.csv: an odometry gap of 2.000 s \(at 1.000 s, frame 1\)"):
        robotlog.odometry_records([0, 1_000_000_000], t, robotlog.OdomNoise(), 0.5, False, robotlog.ImportReport())
    rep = robotlog.ImportReport()
    robotlog.odometry_records([0, 1_000_000_000], t, robotlog.OdomNoise(), 0.5, True, rep)
    assert len(rep.bridged_gaps) == 1 and "bridged" in rep.lines()[1]


@needs_tools
def test_csv_odometry_merged_into_a_raw_log(tmp_path, drive):
    _, recs = records(drive)
    frames = [r for r in recs if r.type == rawlog.FRAME]
    truth = {r.seq: r.truth_pose() for r in recs if r.type == rawlog.TRUTH_POSE}
    csvp = tmp_path / "odom.csv"
    with open(csvp, "w") as f:
        f.write("# odometry = the true path, at the frame times shifted by 5 ms\nt_s,x_m,y_m,theta_rad,cov_vx,cov_vxvy,"
                "cov_vxwz,cov_vy,cov_vywz,cov_wz\n")
        for fr in frames:
            x, y, th = truth[fr.seq]
            f.write(f"{fr.t_ns * 1e-9 - 0.005!r},{x!r},{y!r},{th!r},0.01,0,0,0.01,0,0.04\n")
        f.write(f"{frames[-1].t_ns * 1e-9 + 0.05!r},{x!r},{y!r},{th!r},0.01,0,0,0.01,0,0.04\n")
    out = str(tmp_path / "m.cylraw")
    r = cli("merge-odom-csv", drive, str(csvp), "-o", out, "-q")
    assert r.returncode == 0, r.stderr
    _, m = records(out)
    odo = [x.odometry() for x in m if x.type == rawlog.ODOMETRY]
    assert len(odo) == len(frames)
    dt = (frames[2].t_ns - frames[1].t_ns) * 1e-9
    for k in range(2, len(frames) - 1):
        want = robotlog.between(truth[frames[k - 1].seq], truth[frames[k].seq])
        assert odo[k][0] == pytest.approx(want, abs=2e-4)   # interpolated 5 ms off the samples
    assert odo[2][1][0] == pytest.approx(0.01 * dt * dt, rel=1e-3) and odo[2][1][5] == pytest.approx(0.04 * dt * dt, rel=1e-3)


BAD_CSV = {
    "t_s,x_m,y_m\n0,0,0\n": "header lacks theta_rad",
    "t_s,x_m,y_m,theta_rad,speed\n0,0,0,0,1\n": "unknown column(s) speed",
    "t_s,x_m,y_m,theta_rad\n0,0,0,0\n0.1,abc,0,0\n": "data line 3: not a number",
    "t_s,x_m,y_m,theta_rad\n0.2,0,0,0\n0.1,0,0,0\n": "data line 3: out-of-order timestamp 0.100000000 s",
    "t_s,x_m,y_m,theta_rad,cov_vx\n0,0,0,0,1\n": "give all six covariance columns",
}


@needs_tools
@pytest.mark.parametrize("text", sorted(BAD_CSV))
def test_bad_csv_names_the_line_or_column(tmp_path, drive, text):
    p = tmp_path / "bad.csv"
    p.write_text(text)
    out = tmp_path / "x.cylraw"
    r = cli("merge-odom-csv", drive, str(p), "-o", str(out), "-q")
    assert r.returncode == 1 and BAD_CSV[text] in r.stderr and str(p) in r.stderr, r.stderr
    assert not out.exists() and not (tmp_path / "x.cylraw.part").exists()


def _bag_with(tmp_path, msgs):
    """A ROS 2 MCAP bag with the given (topic, msgtype, t_ns, fill) messages."""
    from pathlib import Path
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore
    ts = get_typestore(Stores.ROS2_HUMBLE)
    path = tmp_path / "bag"
    w = Writer(Path(path), version=9, storage_plugin=StoragePlugin.MCAP)
    w.open()
    conns = {}
    for k, (topic, typ, t, fill) in enumerate(msgs):   # logged in the order given; header stamps as given
        if topic not in conns:
            conns[topic] = w.add_connection(topic, typ, typestore=ts)
        m = robotlog._default(ts, typ)
        m.header = robotlog._header(ts, t, "x")
        fill(m)
        w.write(conns[topic], S + 1000 * k, ts.serialize_cdr(m, typ))
    w.close()
    return str(path)


def _image(enc="yuv422_yuy2", w=4, h=2):
    def fill(m):
        m.width, m.height, m.encoding, m.step = w, h, enc, 2 * w
        m.data = np.full(2 * w * h, 128, np.uint8)
    return fill


def _odom(x):
    def fill(m):
        m.pose.pose.position.x = x
        m.pose.pose.orientation.w = 1.0
    return fill


IMG, ODO = "sensor_msgs/msg/Image", "nav_msgs/msg/Odometry"
CAM_ODOM = ["--image-topic", "/cam", "--odom-topic", "/odom"]
S = 1_000_000_000
BAD_BAGS = {
    "missing_topic": ([("/cam", IMG, S, _image()), ("/odom", ODO, S, _odom(0))],
                      ["--image-topic", "/camera", "--odom-topic", "/odom"],
                      "no topic '/camera' (the camera images); the bag has: /cam [sensor_msgs/msg/Image], /odom"),
    "wrong_type": ([("/cam", IMG, S, _image()), ("/odom", ODO, S, _odom(0))], ["--image-topic", "/odom", "--odom-topic",
                                                                                "/odom"],
                   "topic '/odom' is nav_msgs/msg/Odometry, not sensor_msgs/msg/Image or sensor_msgs/msg/CompressedImage"),
    "encoding": ([("/cam", IMG, S, _image("bayer_rggb8")), ("/odom", ODO, S, _odom(0))], CAM_ODOM,
                 "/cam, image 0: image encoding 'bayer_rggb8' is not supported"),
    "odom_order": ([("/cam", IMG, 2 * S, _image()), ("/odom", ODO, 2 * S, _odom(0)), ("/odom", ODO, S, _odom(1))],
                   CAM_ODOM, "/odom, message 1: out-of-order timestamp 1.000000000 s after 2.000000000 s"),
    "no_stamp": ([("/cam", IMG, 0, _image()), ("/odom", ODO, S, _odom(0))], CAM_ODOM,
                 "image 0 has no timestamp (header stamp 0)"),
    "gap": ([("/cam", IMG, S, _image()), ("/cam", IMG, 2 * S, _image()), ("/odom", ODO, S, _odom(0)),
             ("/odom", ODO, 3 * S, _odom(1))], CAM_ODOM,
            "an odometry gap of 2.000 s (at 2.000 s, frame 1) is longer than 0.5 s; --bridge-gaps"),
    "no_odom_topic": ([("/cam", IMG, S, _image())], ["--image-topic", "/cam"],
                      "no odometry given (--odom-topic or --tf ODOM_FRAME:ROBOT_FRAME)"),
}


@pytest.mark.parametrize("name", sorted(BAD_BAGS))
def test_import_errors_are_clear(tmp_path, name):
    msgs, args, want = BAD_BAGS[name]
    bag = _bag_with(tmp_path, msgs)
    out = tmp_path / "o.cylraw"
    r = cli("import-bag", bag, "-o", str(out), *args, "-q")
    assert r.returncode == 1, (r.returncode, r.stderr)
    assert want in r.stderr, r.stderr
    assert not out.exists() and not (tmp_path / "o.cylraw.part").exists()


def test_gap_bridged_when_asked_and_reported(tmp_path):
    msgs, args, _ = BAD_BAGS["gap"]
    bag = _bag_with(tmp_path, msgs)
    r = cli("import-bag", bag, "-o", str(tmp_path / "o.cylraw"), *args, "--bridge-gaps", "-q")
    assert r.returncode == 0, r.stderr
    assert "bridged" in r.stderr and "no twist covariance" in r.stderr


def test_frames_without_odometry_when_asked(tmp_path):
    bag = _bag_with(tmp_path, [("/cam", IMG, S, _image()), ("/cam", IMG, 2 * S, _image())])
    r = cli("import-bag", bag, "-o", str(tmp_path / "o.cylraw"), "--image-topic", "/cam", "--no-odometry", "-q")
    assert r.returncode == 0, r.stderr
    info, recs = records(str(tmp_path / "o.cylraw"))
    assert (info.fourcc, info.width, info.height) == ("YUYV", 4, 2)
    assert [x.type for x in recs] == [rawlog.FRAME, rawlog.FRAME]


def test_command_line():
    r = cli("--version")
    assert r.returncode == 0 and r.stdout.startswith("cyl-robotlog ")
    r = cli("import-bag")
    assert r.returncode == 2 and "required" in r.stderr


@needs_tools
def test_observation_log_as_mcap_reads_back_whole(tmp_path, drive):
    """Every record of the observation log, covariances included, comes back from the MCAP file
    through the mcap library, on its channel, with its JSON schema."""
    from mcap.reader import make_reader
    log = str(tmp_path / "o.jsonl")
    detect(drive, log)
    out = str(tmp_path / "o.mcap")
    r = cli("obs-to-mcap", log, "-o", out)
    assert r.returncode == 0, r.stderr
    want = [json.loads(line) for line in open(log)]
    got = []
    with open(out, "rb") as f:
        rd = make_reader(f)
        for schema, channel, message in rd.iter_messages(log_time_order=False):
            rec = json.loads(message.data)
            assert channel.topic == "/cyl/" + rec["type"] and schema.encoding == "jsonschema"
            assert json.loads(schema.data)["title"].startswith("cyl.")
            got.append(rec)
    assert got == want                         # every field, in order (floats exactly: JSON round trip)
    assert sum(1 for x in got if x["type"] == "obs") > 20 and all("cov_rr" in x for x in got if x["type"] == "obs")


def test_obs_to_mcap_rejects_other_files(tmp_path):
    p = tmp_path / "x.jsonl"
    p.write_text('{"type":"header","format":"something","version":1}\n')
    r = cli("obs-to-mcap", str(p), "-o", str(tmp_path / "x.mcap"))
    assert r.returncode == 1 and "x.jsonl:1: not a cyl-observations log" in r.stderr
    p.write_text('{"type":"header","format":"cyl-observations","version":2}\n{"type":"blob"}\n')
    r = cli("obs-to-mcap", str(p), "-o", str(tmp_path / "x.mcap"))
    assert r.returncode == 1 and "x.jsonl:2: record type 'blob' is not one of" in r.stderr
    assert not (tmp_path / "x.mcap").exists()


@needs_tools
@pytest.mark.parametrize("storage", ["mcap", "ros1"])
def test_odometry_from_a_tf_chain(tmp_path, drive, storage):
    """Odometry as the chain odom -> base_footprint (moving, /tf) -> base_link (/tf_static): the
    composed pose gives the log's increments back; without covariance in TF, the model's."""
    bag = str(tmp_path / ("t.bag" if storage == "ros1" else "t"))
    r = cli("write-bag", drive, "-o", bag, "--storage", storage, "--tf")
    assert r.returncode == 0, r.stderr
    out = str(tmp_path / "tf.cylraw")
    r = cli("import-bag", bag, "-o", out, "--image-topic", "/camera/image_raw", "--tf", "odom:base_link", "-q")
    assert r.returncode == 0, r.stderr
    assert "no twist covariance in the log: the odometry noise model was used" in r.stderr
    _, a = records(drive)
    _, b = records(out)
    oa = [x.odometry() for x in a if x.type == rawlog.ODOMETRY]
    ob = [x.odometry() for x in b if x.type == rawlog.ODOMETRY]
    assert len(oa) == len(ob) == 24
    for (da, _), (db, cb) in zip(oa[1:], ob[1:]):
        np.testing.assert_allclose(db, da, rtol=0, atol=1e-9)
        assert cb == pytest.approx(robotlog.OdomNoise().cov(db))
    # a frame name that is not in the tree: the error lists the frames there are
    r = cli("import-bag", bag, "-o", str(tmp_path / "x.cylraw"), "--image-topic", "/camera/image_raw",
            "--tf", "odom:base_lnk", "-q")
    assert r.returncode == 1
    assert "no transform chain from 'odom' to 'base_lnk' (frames in /tf and /tf_static: base_footprint, base_link, odom)" \
        in r.stderr, r.stderr


@needs_tools
@pytest.mark.skipif(os.geteuid() != 0, reason="mknod needs root")
def test_writers_leave_device_nodes_and_fifos_alone(tmp_path, drive):
    """As the C++ tools: a character device and a FIFO are written in place, never replaced."""
    import stat
    import threading
    dev, fifo = tmp_path / "null", tmp_path / "fifo"
    os.mknod(dev, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
    os.mkfifo(fifo)
    log = str(tmp_path / "o.jsonl")
    detect(drive, log)
    r = cli("obs-to-mcap", log, "-o", str(dev))
    assert r.returncode == 0, r.stderr
    r = cli("merge-odom-csv", drive, str(tmp_path / "none.csv"), "-o", str(dev))   # fails: nothing written
    assert r.returncode == 1
    bag = str(tmp_path / "b")
    assert cli("write-bag", drive, "-o", bag).returncode == 0
    sink = []
    reader = threading.Thread(target=lambda: sink.append(len(open(fifo, "rb").read())))
    reader.start()
    for out in (str(dev), str(fifo)):
        r = cli("import-bag", bag, "-o", out, *TOPICS)
        assert r.returncode == 0, r.stderr
    reader.join(30)
    assert stat.S_ISCHR(os.stat(dev).st_mode) and stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert sink and sink[0] > 24 * 614400              # the raw log went through the FIFO
    assert not list(tmp_path.glob("*.part"))
