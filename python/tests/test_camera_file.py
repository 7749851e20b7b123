# SPDX-License-Identifier: BSD-3-Clause
"""cyl.load_camera: calibration files read into a libcyl camera, field for field what the C++
tools read (`cyl info FILE.yaml` prints the camera they see), with the same strictness."""
import glob
import json
import os
import subprocess

import pytest

import cyl

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD = os.environ.get("CYL_BUILD", os.path.join(ROOT, "build"))
CYL = os.path.join(BUILD, "cyl")
CAMERAS = sorted(f for f in glob.glob(os.path.join(ROOT, "calib_data", "*.yaml")) if "scene" not in f)
needs_cyl = pytest.mark.skipif(not os.path.exists(CYL), reason="needs build/cyl")


def c_tool(path, *extra):
    r = subprocess.run([CYL, "info", path, *extra], capture_output=True, text=True)
    return r.returncode, (json.loads(r.stdout) if r.returncode == 0 else None), r.stderr


@needs_cyl
@pytest.mark.parametrize("path", CAMERAS, ids=[os.path.basename(p) for p in CAMERAS])
def test_every_shipped_camera_reads_as_the_c_tools_read_it(path):
    rc, want, err = c_tool(path)
    assert rc == 0, err
    cam = cyl.load_camera(path)
    got = cam.fields()
    assert cam.format == want["format"]
    assert (cam.mount_known, cam.intrinsic_cov_known, cam.mount_sigmas_known) == \
        (want["mount_known"], want["intrinsic_cov_known"], want["mount_sigmas_known"])
    w = want["camera"]
    for k in cyl.Camera._FIELDS:
        assert got[k] == w[k], (k, got[k], w[k])   # the same decimal text, parsed to the same double
    assert [x for row in got["intr_cov"] for x in row] == w["intr_cov"]


def test_shipped_cameras_are_there():
    names = {os.path.basename(p) for p in CAMERAS}
    assert {"synthetic_camera.yaml", "paper_camera.yaml", "opencv_sample.yaml", "opencv_sample_ros.yaml"} <= names


BAD = {
    # name: (file text, the error both readers give, after "PATH")
    "misspelled_key": ("image_width: 640\nimage_height: 480\ncamera_matrix: [500, 0, 320, 0, 500, 240, 0, 0, 1]\n"
                       "distortion_coeficients: [0.1, 0, 0, 0, 0]\n",
                       ":4: unknown key 'distortion_coeficients' (did you mean 'distortion_coefficients'?)"),
    "duplicate_key": ("image_width: 640\nimage_height: 480\nimage_width: 320\n"
                      "camera_matrix: [500, 0, 320, 0, 500, 240, 0, 0, 1]\n",
                      ": field 'image_width': given twice (lines 1 and 3)"),
    "partial_mount": ("image_width: 640\nimage_height: 480\ncamera_matrix: [500, 0, 320, 0, 500, 240, 0, 0, 1]\n"
                      "mount_tilt_deg: 10\n",
                      ": field 'mount_*': give all of mount_tilt_deg, mount_yaw_deg, mount_height_m, mount_offset_m or none"),
    "skew": ("image_width: 640\nimage_height: 480\ncamera_matrix: [500, 1, 320, 0, 500, 240, 0, 0, 1]\n",
             ": field 'camera_matrix': skew is not supported (K[0][1] must be 0)"),
    "short_matrix": ("image_width: 640\nimage_height: 480\ncamera_matrix: [500, 0, 320, 0, 500, 240, 0, 0]\n",
                     ": field 'camera_matrix': expected 9 values, got 8"),
    "negative_sigma": ("image_width: 640\nimage_height: 480\ncamera_matrix: [500, 0, 320, 0, 500, 240, 0, 0, 1]\n"
                       "intrinsic_sigmas: [1, 1, -1, 1]\n", ": field 'intrinsic_sigmas': negative standard deviation"),
    "not_a_number": ("image_width: wide\nimage_height: 480\ncamera_matrix: [500, 0, 320, 0, 500, 240, 0, 0, 1]\n",
                     ": field 'image_width': expected a number, got 'wide'"),
    "ros_model": ("image_width: 640\nimage_height: 480\ncamera_matrix: {rows: 3, cols: 3, data: [500, 0, 320, 0, 500, "
                  "240, 0, 0, 1]}\ndistortion_model: equidistant\n",
                  ": field 'distortion_model': 'equidistant' is not supported (plumb_bob or rational_polynomial)"),
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_bad_files_fail_the_same_way_in_both_readers(tmp_path, name):
    text, msg = BAD[name]
    p = tmp_path / f"{name}.yaml"
    p.write_text(text)
    with pytest.raises(cyl.CameraFileError) as e:
        cyl.load_camera(str(p))
    assert str(e.value).startswith(str(p) + msg), str(e.value)
    if os.path.exists(CYL):
        rc, _, err = c_tool(str(p))
        assert rc == 1 and (str(p) + msg) in err, err


def test_lenient_reads_unknown_keys_with_a_warning(tmp_path):
    p = tmp_path / "typo.yaml"
    p.write_text(BAD["misspelled_key"][0])
    cam = cyl.load_camera(str(p), lenient=True)
    assert cam.fields()["k1"] == 0.0           # the misspelled distortion is ignored, and said so
    assert len(cam.warnings) == 1 and "ignored (lenient)" in cam.warnings[0]


def test_missing_file_names_it(tmp_path):
    with pytest.raises(cyl.CameraFileError, match="nope.yaml: cannot open camera calibration file"):
        cyl.load_camera(str(tmp_path / "nope.yaml"))


def test_ros_and_opencv_files_of_one_calibration_agree():
    a = cyl.load_camera(os.path.join(ROOT, "calib_data", "opencv_sample.yaml")).fields()
    b = cyl.Camera.load(os.path.join(ROOT, "calib_data", "opencv_sample_ros.yaml")).fields()
    for k in ("fx_px", "fy_px", "cx_px", "cy_px", "k1", "k2", "p1", "p2", "k3"):
        assert a[k] == pytest.approx(b[k], rel=1e-9), k
