// SPDX-License-Identifier: BSD-3-Clause
// make calib-check: cyl-calibrate's intrinsics against cv::calibrateCamera on OpenCV's own sample
// images (tests/fixtures/opencv_left), the Monte Carlo of the reported sigmas, and the mount
// extrinsics on synthetic floor renders. The last line printed is a JSON object.
//   calib_check [--mc-runs N] [--mount-renders N] [--seed S]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "calib_testlib.hpp"
#include "cylfe/error.hpp"

using namespace cylfe::calib;

int main(int argc, char **argv)
{
    int mc_runs = 1000, mount_renders = 100;
    unsigned long seed = 7;
    for (int i = 1; i < argc; i++) {
        std::string a = argv[i];
        if ((a == "--mc-runs" || a == "--mount-renders" || a == "--seed") && i + 1 < argc) {
            long v = std::atol(argv[++i]);
            if (a == "--mc-runs") mc_runs = (int)v;
            else if (a == "--mount-renders") mount_renders = (int)v;
            else seed = (unsigned long)v;
        } else if (a == "-h" || a == "--help") {
            std::printf("usage: calib_check [--mc-runs N (1000)] [--mount-renders N (100)] [--seed S]\n");
            return 0;
        } else {
            std::fprintf(stderr, "calib_check: unknown argument '%s'\n", a.c_str());
            return 2;
        }
    }
    if (mc_runs < 10 || mount_renders < 10) {
        std::fprintf(stderr, "calib_check: at least 10 runs and renders\n");
        return 2;
    }
    try {
        Board b;
        cv::Size size;
        // OpenCV's sample settings (cornerSubPix 11 -> 23x23 px, fixed): the reference result
        DetectOptions fixed11;
        fixed11.adaptive_window = false;
        auto views = detect_views(calibtest::fixture_images(), b, fixed11, size,
                                  [](const std::string &m) { std::fprintf(stderr, "warning: %s\n", m.c_str()); });
        std::vector<std::vector<cv::Point2f>> img;
        img.reserve(views.size());
        for (auto &v : views) img.push_back(v.corners);
        calibtest::OcvComparison c = calibtest::compare_with_opencv(img, size, b);
        const double N = c.ours.n_points, p = c.ours.n_params;
        std::printf("== intrinsics on OpenCV's sample images (%s, %zu views, 9x6, N = %.0f corners, p = %.0f)\n",
                    calibtest::fixture_dir().c_str(), views.size(), N, p);
        std::printf("OpenCV 4.6 divides the residual variance by N - p (points), not 2N - p (residuals):\n"
                    "its stdDeviationsIntrinsics are corrected by sqrt((N-p)/(2N-p)) = %.5f (x%.4f too large)\n",
                    std::sqrt((N - p) / (2 * N - p)), std::sqrt((2 * N - p) / (N - p)));
        static const char *pn[9] = {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"};
        std::printf("%-3s %16s %16s %10s | %12s %12s %12s %8s\n", "", "ours (Ceres)", "cv::calibrate", "rel diff",
                    "our sigma", "cv std", "cv corrected", "ratio");
        for (int k = 0; k < 9; k++)
            std::printf("%-3s %16.9g %16.9g %10.2e | %12.6g %12.6g %12.6g %8.5f\n", pn[k], c.ours.intr[k], c.cv_intr[k],
                        std::fabs(c.ours.intr[k] - c.cv_intr[k]) / std::fabs(c.cv_intr[k]), c.ours.sigma[k], c.cv_std[k],
                        c.cv_std_corrected[k], c.ours.sigma[k] / c.cv_std_corrected[k]);
        std::printf("RMS: ours %.6f px, OpenCV %.6f px (diff %.2e); largest per-view RMS difference %.2e px\n",
                    c.ours.rms, c.cv_rms, c.rms_diff_px, c.max_view_rms_diff);
        for (int i : c.ours.outliers)
            std::printf("outlier view: %s RMS %.4f px\n", views[i].name.c_str(), c.ours.view_rms[i]);
        {
            // cyl-calibrate's default detection: the window shrinks to half the corner spacing
            cv::Size s2;
            auto v2 = detect_views(calibtest::fixture_images(), b, DetectOptions(), s2, nullptr);
            std::vector<std::vector<cv::Point2f>> i2;
            i2.reserve(v2.size());
            for (auto &v : v2) i2.push_back(v.corners);
            calibtest::OcvComparison c2 = calibtest::compare_with_opencv(i2, s2, b);
            std::printf("with cyl-calibrate's default (adaptive) window: RMS ours %.6f px, OpenCV %.6f px; max param "
                        "rel diff %.2e, sigma ratio error %.2e; fx %.3f +- %.3f, fy %.3f +- %.3f\n",
                        c2.ours.rms, c2.cv_rms, c2.max_param_rel_diff, c2.sigma_ratio_error, c2.ours.intr[0],
                        c2.ours.sigma[0], c2.ours.intr[1], c2.ours.sigma[1]);
        }

        std::printf("== Monte Carlo: %d synthetic calibrations (13 views, 0.30 px corner noise)\n", mc_runs);
        calibtest::MonteCarlo mc = calibtest::monte_carlo(mc_runs, 0.30, seed, true);
        std::printf("%-3s %14s %14s %14s %14s %9s\n", "", "truth", "mean estimate", "MC spread", "our sigma (rms)",
                    "rel err");
        for (int k = 0; k < 9; k++)
            std::printf("%-3s %14.7g %14.7g %14.6g %14.6g %9.4f\n", pn[k], mc.truth[k], mc.mean[k], mc.spread[k],
                        mc.reported[k], mc.reported[k] / mc.spread[k] - 1);
        std::printf("largest |sigma/spread - 1| = %.4f (standard error of a spread from %d runs: %.3f); largest "
                    "|bias| = %.2f standard errors of the mean\n",
                    mc.max_sigma_error, mc_runs, 1 / std::sqrt(2.0 * (mc_runs - 1)), mc.max_bias_in_sigmas);

        std::printf("== mount extrinsics: %d synthetic renders of a 9x6 board (7 cm squares) on the floor\n",
                    mount_renders);
        calibtest::MountExperiment mx = calibtest::mount_experiment(mount_renders, seed, true, true);
        static const char *mn[5] = {"height floor (m)", "tilt (deg)", "yaw (deg)", "roll (deg)", "offset s (m)"};
        const double sc[5] = {1, 180 / CV_PI, 180 / CV_PI, 180 / CV_PI, 1};
        std::printf("detected %d of %d; %-16s %12s %12s %12s %12s %12s\n", mx.detected, mx.renders, "", "mean err",
                    "err spread", "sigma (rms)", "start-up sd", "true sd");
        for (int k = 0; k < 5; k++)
            std::printf("  %-16s %12.3g %12.3g %12.3g %12.3g %12.3g\n", mn[k], mx.mean_err[k] * sc[k],
                        mx.err_spread[k] * sc[k], mx.sigma_rms[k] * sc[k], mx.startup_spread[k] * sc[k],
                        mx.truth_spread[k] * sc[k]);
        std::printf("within 3 sigma of the truth: %.2f%%, largest |z| %.2f; largest |sigma/spread - 1| %.4f\n",
                    100 * mx.frac_within_3sigma, mx.max_abs_z, mx.max_sigma_error);

        std::printf("{\"max_param_rel_diff\": %.3e, \"rms_diff_px\": %.3e, \"sigma_ratio_error\": %.3e, "
                    "\"mc_sigma_error\": %.4f, \"mc_runs\": %d, \"our_rms_px\": %.6f, \"opencv_rms_px\": %.6f, "
                    "\"sigma_fx\": %.5f, \"sigma_fy\": %.5f, \"sigma_cx\": %.5f, \"sigma_cy\": %.5f, "
                    "\"mount_renders\": %d, \"mount_within_3sigma\": %.4f, \"mount_sigma_error\": %.4f}\n",
                    c.max_param_rel_diff, c.rms_diff_px, c.sigma_ratio_error, mc.max_sigma_error, mc_runs, c.ours.rms,
                    c.cv_rms, c.ours.sigma[0], c.ours.sigma[1], c.ours.sigma[2], c.ours.sigma[3], mx.detected,
                    mx.frac_within_3sigma, mx.max_sigma_error);
        bool ok = c.max_param_rel_diff < 1e-3 && c.rms_diff_px < 1e-3 && c.sigma_ratio_error < 0.01 &&
                  mc.max_sigma_error < 0.10 && mx.frac_within_3sigma > 0.98 && mx.max_sigma_error < 0.20;
        return ok ? 0 : 1;
    } catch (const std::exception &e) {
        std::fprintf(stderr, "calib_check: error: %s\n", e.what());
        return 1;
    }
}
