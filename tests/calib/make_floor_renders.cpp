// SPDX-License-Identifier: BSD-3-Clause
// Writes renders of a 9x6 chessboard (7 cm squares) lying on the floor 1 m ahead of the robot, seen
// by the synthetic scene's default camera (cylfe::synth::CameraModel defaults), one per simulated
// start-up (the true tilt, yaw, height jittered by 0.5 deg, 0.4 deg, 0.3 mm), plus that camera's
// intrinsics as a calibration file without covariance. Used by `make calib-data` and the docs.
//   make_floor_renders OUT_DIR [N=10] [SEED=1]
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>

#include <opencv2/imgcodecs.hpp>

#include "calib_testlib.hpp"
#include "cylfe/calib.hpp"

int main(int argc, char **argv)
{
    if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
        std::printf("usage: make_floor_renders OUT_DIR [N=10] [SEED=1]\n");
        return argc < 2 ? 2 : 0;
    }
    std::string dir = argv[1];
    int n = argc > 2 ? std::atoi(argv[2]) : 10;
    unsigned long seed = argc > 3 ? std::strtoul(argv[3], nullptr, 10) : 1;
    calibtest::FloorCamera c;
    calibtest::FloorBoard fb;
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> G(0.0, 1.0);
    cyl_camera cam = calibtest::to_cyl(c);
    cylfe::calib::save_opencv_yaml(dir + "/intrinsics.yaml", cam,
                                   "the synthetic scene's default camera (exact intrinsics, covariance not given)", false);
    for (int i = 0; i < n; i++) {
        calibtest::FloorCamera ci = c;
        ci.tilt_rad += 0.5 * CV_PI / 180 * G(rng);
        ci.yaw_rad += 0.4 * CV_PI / 180 * G(rng);
        ci.height_floor_m += 0.0003 * G(rng);
        char name[64];
        std::snprintf(name, sizeof name, "/startup%02d.png", i + 1);
        if (!cv::imwrite(dir + name, calibtest::render_floor_board(ci, fb, 2.0, seed * 1000 + i))) {
            std::fprintf(stderr, "make_floor_renders: cannot write %s%s\n", dir.c_str(), name);
            return 1;
        }
        std::printf("%s%s: truth h_floor %.5f m tilt %.4f deg yaw %.4f deg\n", dir.c_str(), name, ci.height_floor_m,
                    ci.tilt_rad * 180 / CV_PI, ci.yaw_rad * 180 / CV_PI);
    }
    return 0;
}
