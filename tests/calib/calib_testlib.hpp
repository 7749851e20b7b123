// SPDX-License-Identifier: BSD-3-Clause
// Test support for the calibration tools: the comparison with cv::calibrateCamera, the Monte
// Carlo of the intrinsic sigmas, and a floor-chessboard renderer with its own camera geometry
// (OpenCV's lens model, independent of libcyl's) for the mount extrinsics.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "cylfe/calib.hpp"

namespace calibtest {

// Directory of the OpenCV sample images (tests/fixtures/opencv_left), from CALIB_FIXTURES.
std::string fixture_dir();
std::vector<std::string> fixture_images();

struct OcvComparison {
    cylfe::calib::IntrinsicResult ours;
    double cv_intr[9] = {0};         // cv::calibrateCamera, flags 0
    double cv_std[9] = {0};          // its stdDeviationsIntrinsics (OpenCV 4.6: sigma^2 = SSE/(N - p))
    double cv_std_corrected[9] = {0};// cv_std * sqrt((N - p) / (2N - p))
    double cv_rms = 0;
    std::vector<double> cv_view_rms;
    double max_param_rel_diff = 0;   // max over the 9 parameters of |ours - cv| / |cv|
    double rms_diff_px = 0;          // |ours - cv|
    double sigma_ratio_error = 0;    // max over the 9 of |our sigma / corrected cv sigma - 1|
    double max_view_rms_diff = 0;
};
OcvComparison compare_with_opencv(const std::vector<std::vector<cv::Point2f>> &img, cv::Size size,
                                  const cylfe::calib::Board &b);

struct MonteCarlo {
    int runs = 0;
    double noise_px = 0;
    double truth[9] = {0};
    double mean[9] = {0};            // mean estimate
    double spread[9] = {0};          // standard deviation of the estimates over the runs
    double reported[9] = {0};        // RMS of the reported sigmas
    double max_sigma_error = 0;      // max over the 9 of |reported / spread - 1|
    double max_bias_in_sigmas = 0;   // max over the 9 of |mean - truth| / (spread / sqrt(runs))
};
// runs synthetic calibrations: 13 board views of a camera like OpenCV's sample, the corners
// projected with OpenCV's projectPoints (not libcyl) plus Gaussian noise of noise_px.
MonteCarlo monte_carlo(int runs, double noise_px, uint64_t seed, bool progress = false);

// ---- floor chessboard renders ----------------------------------------------------------------
struct FloorCamera {
    cv::Size size{640, 480};
    double fx = 570, fy = 568, cx = 322.4, cy = 236.9;
    double k1 = -0.12, k2 = 0.05, p1 = 0.0008, p2 = -0.0006, k3 = 0;
    // mount (robot frame x forward, y left, z up; floor z = 0)
    double height_floor_m = 0.476, tilt_rad = 0.2094, yaw_rad = 0.0, roll_rad = 0.0;
    double offset_m = 0.10, lateral_m = 0.0;
};
struct FloorBoard {
    cylfe::calib::Board board{9, 6, 0.07};
    cylfe::calib::BoardPlacement place{1.0, 0.0, 90.0};
    double margin_squares = 1.0;  // white border around the squares
};
// Render a grey image: the board on a grey floor, 4x4 supersampling, Gaussian blur, noise
// (seeded), 8-bit. Rays from OpenCV's undistortPoints.
cv::Mat render_floor_board(const FloorCamera &cam, const FloorBoard &fb, double noise, uint64_t seed);

cyl_camera to_cyl(const FloorCamera &c);

// Renders of the floor board with a known mount, each "start-up" jittering the true height,
// tilt, yaw and roll (jitter = true) or not, each with its own noise; every render through
// detection and cylfe::calib::estimate_mount. Parameters compared: height_floor, tilt, yaw,
// roll, offset (indices of MountEstimate::sigma 0..4).
struct MountExperiment {
    int renders = 0, detected = 0;
    double max_abs_z = 0;             // max over renders and parameters of |est - truth| / sigma
    double frac_within_3sigma = 0;    // fraction of (render, parameter) pairs within 3 sigma
    double sigma_rms[5] = {0};        // RMS of the per-render sigmas
    double err_spread[5] = {0};       // standard deviation of est - truth over the renders
    double mean_err[5] = {0};         // mean of est - truth
    double max_sigma_error = 0;       // max over the 5 of |sigma_rms / err_spread - 1|
    double max_mean_z = 0;            // max over the 5 of |mean_err| / (err_spread / sqrt(n))
    double truth_spread[5] = {0};     // std of the true values over the start-ups (jitter)
    double startup_spread[5] = {0};   // std of the estimates over the start-ups (summarise_mount)
};
MountExperiment mount_experiment(int renders, uint64_t seed, bool jitter, bool progress = false);

} // namespace calibtest
