// SPDX-License-Identifier: BSD-3-Clause
// Calibration files -> cyl_camera: the paper camera, OpenCV files without libcyl's fields, ROS
// camera_info, save/load round trip, and errors that name the file and the field.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "cylfe/calibration.hpp"
#include "cylfe/error.hpp"

#ifndef UNC_CALIB_DIR
#define UNC_CALIB_DIR "calib_data"
#endif

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

std::string tmp_file(const std::string &name, const std::string &text)
{
    auto p = std::filesystem::temp_directory_path() / ("cyl_calib_test_" + std::to_string(::getpid()) + "_" + name);
    std::ofstream(p) << text;
    return p.string();
}

// expect load to throw with a message naming the file and containing `needle`
void expect_error(const std::string &path, const std::string &needle)
{
    try {
        cylfe::load_camera_calibration(path);
        ADD_FAILURE() << "no error for " << path;
    } catch (const cylfe::Error &e) {
        std::string m = e.what();
        EXPECT_NE(m.find(path), std::string::npos) << m;
        EXPECT_NE(m.find(needle), std::string::npos) << m;
    }
}

const char *kOpenCVHeader = "%YAML:1.0\n---\n";
const char *kK = "camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
                 "   data: [ 500., 0., 320., 0., 510., 240., 0., 0., 1. ]\n";

} // namespace

TEST(Calibration, PaperCamera)
{
    cylfe::CameraCalibration c = cylfe::load_camera_calibration(UNC_CALIB_DIR "/paper_camera.yaml");
    EXPECT_EQ(c.format, "opencv");
    EXPECT_TRUE(c.intrinsic_cov_known && c.mount_known && c.mount_sigmas_known);
    EXPECT_EQ(c.cam.flags, 0u);
    EXPECT_EQ(c.cam.width, 768u);
    EXPECT_EQ(c.cam.height, 576u);
    EXPECT_DOUBLE_EQ(c.cam.fx_px, 875.2);
    EXPECT_DOUBLE_EQ(c.cam.cy_px, 278.8);
    EXPECT_DOUBLE_EQ(c.cam.intr_cov[CYL_INTR_FX][CYL_INTR_FX], 0.4565 * 0.4565);
    EXPECT_DOUBLE_EQ(c.cam.intr_cov[CYL_INTR_CY][CYL_INTR_CY], 0.2826 * 0.2826);
    EXPECT_DOUBLE_EQ(c.cam.intr_cov[CYL_INTR_FX][CYL_INTR_CX], 0.0);
    EXPECT_NEAR(c.cam.tilt_rad, 1.656 * kDeg, 1e-15);
    EXPECT_NEAR(c.cam.tilt_sigma_rad, 0.575 * kDeg, 1e-15);
    EXPECT_NEAR(c.cam.yaw_sigma_rad, 0.443 * kDeg, 1e-15);
    EXPECT_DOUBLE_EQ(c.cam.height_m, 0.326);
    EXPECT_DOUBLE_EQ(c.cam.height_sigma_m, 3.04e-4);
    EXPECT_DOUBLE_EQ(c.cam.offset_m, 0.15);
    EXPECT_NEAR(c.cam.offset_sigma_m * 1.96, 0.005, 1e-5);
    EXPECT_EQ(cyl_camera_check(&c.cam), CYL_OK);
}

TEST(Calibration, OpenCVFileWithoutUncertainty)
{
    std::string p = tmp_file("plain.yaml", std::string(kOpenCVHeader) + "image_width: 640\nimage_height: 480\n" + kK +
                                               "distortion_coefficients: !!opencv-matrix\n   rows: 5\n   cols: 1\n"
                                               "   dt: d\n   data: [ -0.2, 0.05, 0.001, -0.002, 0.0 ]\n");
    cylfe::CameraCalibration c = cylfe::load_camera_calibration(p);
    EXPECT_FALSE(c.intrinsic_cov_known);
    EXPECT_FALSE(c.mount_known);
    EXPECT_TRUE(c.cam.flags & CYL_CAM_INTR_COV_UNKNOWN);
    EXPECT_TRUE(c.cam.flags & CYL_CAM_EXTR_SIG_UNKNOWN);
    EXPECT_DOUBLE_EQ(c.cam.fy_px, 510.0);
    EXPECT_DOUBLE_EQ(c.cam.k1, -0.2);
    EXPECT_DOUBLE_EQ(c.cam.p2, -0.002);
    EXPECT_DOUBLE_EQ(c.cam.intr_cov[0][0], 0.0);
    std::remove(p.c_str());
}

TEST(Calibration, RosCameraInfo)
{
    std::string p = tmp_file("ros.yaml",
                             "image_width: 640\nimage_height: 480\ncamera_name: narrow_stereo\n"
                             "camera_matrix:\n  rows: 3\n  cols: 3\n  data: [500.0, 0.0, 320.5, 0.0, 501.0, 240.25, 0.0, 0.0, 1.0]\n"
                             "distortion_model: plumb_bob\n"
                             "distortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [-0.2, 0.05, 0.001, -0.002, 0.0]\n"
                             "rectification_matrix:\n  rows: 3\n  cols: 3\n  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]\n"
                             "intrinsic_sigmas: [0.5, 0.5, 0.3, 0.3]\n");
    cylfe::CameraCalibration c = cylfe::load_camera_calibration(p);
    EXPECT_EQ(c.format, "ros");
    EXPECT_DOUBLE_EQ(c.cam.cx_px, 320.5);
    EXPECT_DOUBLE_EQ(c.cam.cy_px, 240.25);
    EXPECT_DOUBLE_EQ(c.cam.k2, 0.05);
    EXPECT_TRUE(c.intrinsic_cov_known);
    EXPECT_DOUBLE_EQ(c.cam.intr_cov[CYL_INTR_CX][CYL_INTR_CX], 0.09);
    EXPECT_DOUBLE_EQ(c.cam.intr_cov[CYL_INTR_K1][CYL_INTR_K1], 0.0);
    std::remove(p.c_str());
    p = tmp_file("ros_fish.yaml", "image_width: 640\nimage_height: 480\n"
                                  "camera_matrix:\n  rows: 3\n  cols: 3\n  data: [500.0, 0.0, 320.5, 0.0, 501.0, 240.25, 0.0, 0.0, 1.0]\n"
                                  "distortion_model: equidistant\n");
    expect_error(p, "distortion_model");
    std::remove(p.c_str());
}

TEST(Calibration, SaveLoadRoundTrip)
{
    cylfe::CameraCalibration a = cylfe::load_camera_calibration(UNC_CALIB_DIR "/paper_camera.yaml");
    a.cam.k1 = -0.1;
    a.cam.intr_cov[0][2] = a.cam.intr_cov[2][0] = 0.05;
    auto p = (std::filesystem::temp_directory_path() / ("cyl_calib_rt_" + std::to_string(::getpid()) + ".yaml")).string();
    cylfe::save_camera_calibration(p, a.cam);
    cylfe::CameraCalibration b = cylfe::load_camera_calibration(p);
    EXPECT_DOUBLE_EQ(b.cam.k1, -0.1);
    EXPECT_DOUBLE_EQ(b.cam.intr_cov[0][2], 0.05);
    EXPECT_NEAR(b.cam.tilt_rad, a.cam.tilt_rad, 1e-15);
    EXPECT_DOUBLE_EQ(b.cam.offset_sigma_m, a.cam.offset_sigma_m);
    EXPECT_EQ(b.cam.flags, 0u);
    std::remove(p.c_str());
}

TEST(Calibration, ErrorsNameFileAndField)
{
    expect_error("/nonexistent/dir/cam.yaml", "cannot open");
    std::string base = std::string(kOpenCVHeader) + "image_width: 640\nimage_height: 480\n";
    std::string p = tmp_file("nok.yaml", base);
    expect_error(p, "'camera_matrix'");
    std::remove(p.c_str());
    p = tmp_file("badk.yaml", base + "camera_matrix: !!opencv-matrix\n   rows: 2\n   cols: 3\n   dt: d\n   data: [1,0,0,0,1,0]\n");
    expect_error(p, "'camera_matrix'");
    std::remove(p.c_str());
    p = tmp_file("nowidth.yaml", std::string(kOpenCVHeader) + kK);
    expect_error(p, "'image_width'");
    std::remove(p.c_str());
    p = tmp_file("negsig.yaml", base + kK + "intrinsic_sigmas: [0.5, -0.5, 0.3, 0.3]\n");
    expect_error(p, "'intrinsic_sigmas'");
    std::remove(p.c_str());
    p = tmp_file("partmount.yaml", base + kK + "mount_tilt_deg: 2\nmount_height_m: 0.3\n");
    expect_error(p, "mount_");
    std::remove(p.c_str());
    p = tmp_file("badnum.yaml", base + kK + "mount_tilt_deg: steep\nmount_yaw_deg: 0\nmount_height_m: 0.3\nmount_offset_m: 0.1\n");
    expect_error(p, "'mount_tilt_deg'");
    std::remove(p.c_str());
    p = tmp_file("garbage.yaml", "%YAML:1.0\n---\n: : [\n");
    expect_error(p, "YAML");
    std::remove(p.c_str());
}
