// SPDX-License-Identifier: BSD-3-Clause
// libcyl's C undistortion and projection against OpenCV (cv::undistortPoints, cv::projectPoints)
// over the whole image, for several lenses; < 1e-6 normalised required (we see ~1e-15).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "cylfe/calibration.hpp"

extern "C" {
#include "cyl/camera.h"
}

#ifndef UNC_CALIB_DIR
#define UNC_CALIB_DIR "calib_data"
#endif

namespace {

struct Lens { double k1, k2, p1, p2, k3; };

cyl_camera make_camera(double f, const Lens &l)
{
    cyl_camera c;
    cyl_camera_init(&c);
    c.width = 768; c.height = 576;
    c.fx_px = f; c.fy_px = f * 0.9968; c.cx_px = 386.3; c.cy_px = 278.8;
    c.k1 = l.k1; c.k2 = l.k2; c.p1 = l.p1; c.p2 = l.p2; c.k3 = l.k3;
    return c;
}

cv::Mat K_of(const cyl_camera &c)
{
    return (cv::Mat_<double>(3, 3) << c.fx_px, 0, c.cx_px, 0, c.fy_px, c.cy_px, 0, 0, 1);
}
cv::Mat D_of(const cyl_camera &c) { return (cv::Mat_<double>(1, 5) << c.k1, c.k2, c.p1, c.p2, c.k3); }

const Lens kLenses[] = {
    {0, 0, 0, 0, 0},                       // pinhole
    {-0.25, 0.12, 8e-4, -5e-4, -0.02},     // moderate barrel (the unit tests' lens)
    {-0.30, 0.09, 1e-3, 2e-3, -0.01},      // strong barrel, tangential
    {0.15, -0.05, -1e-3, 1e-3, 0.01},      // pincushion
};

double max_undistort_diff(const cyl_camera &cam, int max_iter)
{
    std::vector<cv::Point2d> src, dst;
    for (double v = 0; v <= cam.height - 1; v += 8) {
        for (double u = 0; u <= cam.width - 1; u += 8) src.emplace_back(u, v);
        src.emplace_back(cam.width - 1, v);
    }
    for (double u = 0; u <= cam.width - 1; u += 8) src.emplace_back(u, cam.height - 1);
    src.emplace_back(cam.width - 1, cam.height - 1);
    cv::undistortPoints(src, dst, K_of(cam), D_of(cam), cv::noArray(), cv::noArray(),
                        cv::TermCriteria(cv::TermCriteria::COUNT, max_iter, 0));
    double worst = 0;
    for (size_t i = 0; i < src.size(); i++) {
        double x, y;
        EXPECT_EQ(cyl_camera_undistort(&cam, src[i].x, src[i].y, &x, &y), CYL_OK);
        worst = std::fmax(worst, std::fmax(std::fabs(x - dst[i].x), std::fabs(y - dst[i].y)));
    }
    return worst;
}

} // namespace

TEST(UndistortCV, AgreesWithUndistortPointsOverTheImage)
{
    double worst = 0;
    for (const Lens &l : kLenses) {
        for (double f : {875.2, 600.0}) {
            cyl_camera cam = make_camera(f, l);
            double d = max_undistort_diff(cam, 1000);  // OpenCV's fixed point, run to convergence
            EXPECT_LT(d, 1e-6) << "lens k1=" << l.k1 << " f=" << f;
            worst = std::fmax(worst, d);
        }
    }
    std::printf("[ INFO     ] libcyl vs cv::undistortPoints (1000 iterations): max |diff| %.3g normalised\n", worst);
    // OpenCV's default (5 fixed-point iterations) is not converged for a strong lens; ours is
    cyl_camera strong = make_camera(600.0, kLenses[2]);
    std::printf("[ INFO     ] vs cv::undistortPoints default 5 iterations, strong lens: %.3g\n",
                max_undistort_diff(strong, 5));
}

TEST(UndistortCV, ProjectAgreesWithProjectPoints)
{
    for (const Lens &l : kLenses) {
        cyl_camera cam = make_camera(875.2, l);
        std::vector<cv::Point3d> obj;
        for (double y = -0.3; y <= 0.3; y += 0.05)
            for (double x = -0.42; x <= 0.42; x += 0.06) obj.emplace_back(x, y, 1.0);
        std::vector<cv::Point2d> img;
        cv::projectPoints(obj, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K_of(cam), D_of(cam), img);
        for (size_t i = 0; i < obj.size(); i++) {
            double u, v;
            cyl_camera_project(&cam, obj[i].x, obj[i].y, &u, &v);
            EXPECT_NEAR(u, img[i].x, 1e-9);
            EXPECT_NEAR(v, img[i].y, 1e-9);
        }
    }
}

TEST(UndistortCV, PaperCameraFileReadsTheSameInOpenCV)
{
    cylfe::CameraCalibration cal = cylfe::load_camera_calibration(UNC_CALIB_DIR "/paper_camera.yaml");
    cv::FileStorage fs(UNC_CALIB_DIR "/paper_camera.yaml", cv::FileStorage::READ);
    ASSERT_TRUE(fs.isOpened());
    cv::Mat K, D;
    fs["camera_matrix"] >> K;
    fs["distortion_coefficients"] >> D;
    EXPECT_EQ(K.at<double>(0, 0), cal.cam.fx_px);
    EXPECT_EQ(K.at<double>(1, 1), cal.cam.fy_px);
    EXPECT_EQ(K.at<double>(0, 2), cal.cam.cx_px);
    EXPECT_EQ(K.at<double>(1, 2), cal.cam.cy_px);
    EXPECT_EQ((int)fs["image_width"], (int)cal.cam.width);
    EXPECT_EQ(D.total(), 5u);
    EXPECT_LT(max_undistort_diff(cal.cam, 1000), 1e-12);
}
