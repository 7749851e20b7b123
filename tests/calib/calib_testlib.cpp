// SPDX-License-Identifier: BSD-3-Clause
// Test support for the calibration tools (calib_testlib.hpp).
#include "calib_testlib.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <mutex>
#include <random>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#ifndef CALIB_FIXTURES
#define CALIB_FIXTURES "tests/fixtures/opencv_left"
#endif

namespace calibtest {

using cylfe::calib::Board;
using cylfe::calib::IntrinsicOptions;
using cylfe::calib::IntrinsicResult;

std::string fixture_dir() { return CALIB_FIXTURES; }

std::vector<std::string> fixture_images()
{
    std::vector<std::string> v;
    for (int i : {1, 2, 3, 4, 5, 6, 7, 8, 9, 11, 12, 13, 14}) {
        char b[32];
        std::snprintf(b, sizeof b, "/left%02d.jpg", i);
        v.push_back(fixture_dir() + b);
    }
    return v;
}

OcvComparison compare_with_opencv(const std::vector<std::vector<cv::Point2f>> &img, cv::Size size, const Board &b)
{
    OcvComparison c;
    std::vector<std::vector<cv::Point3f>> obj(img.size(), cylfe::calib::board_points(b));
    c.ours = cylfe::calib::calibrate_intrinsics(obj, img, size, IntrinsicOptions());
    cv::Mat K, D, sdi, sde, pve;
    std::vector<cv::Mat> rv, tv;
    c.cv_rms = cv::calibrateCamera(obj, img, size, K, D, rv, tv, sdi, sde, pve, 0);
    double cv9[9] = {K.at<double>(0, 0), K.at<double>(1, 1), K.at<double>(0, 2), K.at<double>(1, 2),
                     D.at<double>(0), D.at<double>(1), D.at<double>(2), D.at<double>(3), D.at<double>(4)};
    const double N = c.ours.n_points, p = c.ours.n_params;
    const double corr = std::sqrt((N - p) / (2 * N - p));
    for (int k = 0; k < 9; k++) {
        c.cv_intr[k] = cv9[k];
        c.cv_std[k] = sdi.at<double>(k);
        c.cv_std_corrected[k] = c.cv_std[k] * corr;
        c.max_param_rel_diff = std::max(c.max_param_rel_diff, std::fabs(c.ours.intr[k] - cv9[k]) / std::fabs(cv9[k]));
        c.sigma_ratio_error = std::max(c.sigma_ratio_error, std::fabs(c.ours.sigma[k] / c.cv_std_corrected[k] - 1));
    }
    c.rms_diff_px = std::fabs(c.ours.rms - c.cv_rms);
    for (int i = 0; i < pve.rows; i++) {
        c.cv_view_rms.push_back(pve.at<double>(i));
        c.max_view_rms_diff = std::max(c.max_view_rms_diff, std::fabs(pve.at<double>(i) - c.ours.view_rms[i]));
    }
    return c;
}

MonteCarlo monte_carlo(int runs, double noise_px, uint64_t seed, bool progress)
{
    MonteCarlo mc;
    mc.runs = runs;
    mc.noise_px = noise_px;
    const double truth[9] = {536.0, 536.0, 342.4, 235.5, -0.265, -0.047, 0.0018, -0.0003, 0.252};
    std::copy(truth, truth + 9, mc.truth);
    const cv::Size size(640, 480);
    cv::Mat K = (cv::Mat_<double>(3, 3) << truth[0], 0, truth[2], 0, truth[1], truth[3], 0, 0, 1);
    cv::Mat D = (cv::Mat_<double>(1, 5) << truth[4], truth[5], truth[6], truth[7], truth[8]);
    Board b;  // 9x6, unit squares
    std::vector<cv::Point3f> bp = cylfe::calib::board_points(b);
    // 13 fixed views: tilted boards at 12..20 squares, all corners inside the image
    std::mt19937_64 prng(12345);
    std::uniform_real_distribution<double> U(-1, 1);
    std::vector<std::vector<cv::Point2f>> clean;
    while (clean.size() < 13) {
        double rx = 0.55 * U(prng), ry = 0.55 * U(prng), rz = 0.3 * U(prng), z = 16 + 4 * U(prng);
        cv::Mat R;
        cv::Rodrigues(cv::Vec3d(rx, ry, rz), R);
        cv::Vec3d c(4, 2.5, 0);  // board centre
        cv::Mat Rc = R * cv::Mat(c);
        cv::Vec3d t(-Rc.at<double>(0) + 3 * U(prng), -Rc.at<double>(1) + 2 * U(prng), z - Rc.at<double>(2));
        std::vector<cv::Point2f> pts;
        cv::projectPoints(bp, cv::Vec3d(rx, ry, rz), t, K, D, pts);
        bool inside = true;
        for (auto &q : pts) inside = inside && q.x > 20 && q.x < size.width - 20 && q.y > 20 && q.y < size.height - 20;
        if (inside) clean.push_back(pts);
    }
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> G(0.0, noise_px);
    std::vector<std::vector<double>> est(9);
    std::vector<double> rep2(9, 0.0);
    std::vector<std::vector<cv::Point3f>> obj(13, bp);
    for (int r = 0; r < runs; r++) {
        std::vector<std::vector<cv::Point2f>> img = clean;
        for (auto &v : img)
            for (auto &q : v) {
                q.x += (float)G(rng);
                q.y += (float)G(rng);
            }
        IntrinsicResult res = cylfe::calib::calibrate_intrinsics(obj, img, size, IntrinsicOptions());
        for (int k = 0; k < 9; k++) {
            est[k].push_back(res.intr[k]);
            rep2[k] += res.sigma[k] * res.sigma[k];
        }
        if (progress && (r + 1) % 25 == 0) std::fprintf(stderr, "monte carlo: %d/%d calibrations\n", r + 1, runs);
    }
    for (int k = 0; k < 9; k++) {
        double m = 0, v = 0;
        for (double x : est[k]) m += x;
        m /= runs;
        for (double x : est[k]) v += (x - m) * (x - m);
        mc.mean[k] = m;
        mc.spread[k] = std::sqrt(v / (runs - 1));
        mc.reported[k] = std::sqrt(rep2[k] / runs);
        mc.max_sigma_error = std::max(mc.max_sigma_error, std::fabs(mc.reported[k] / mc.spread[k] - 1));
        mc.max_bias_in_sigmas =
            std::max(mc.max_bias_in_sigmas, std::fabs(m - truth[k]) / (mc.spread[k] / std::sqrt((double)runs)));
    }
    return mc;
}

// ---- floor chessboard renders -------------------------------------------------------------------

namespace {
struct RayMap {
    std::vector<cv::Point2f> xy;  // undistorted normalised coordinates of every sub-sample
};
constexpr int kSS = 4;

const RayMap &ray_map(const FloorCamera &c)
{
    static std::mutex mu;
    static std::map<std::vector<double>, RayMap> cache;
    std::vector<double> key{(double)c.size.width, (double)c.size.height, c.fx, c.fy, c.cx, c.cy, c.k1, c.k2, c.p1, c.p2, c.k3};
    std::lock_guard<std::mutex> lk(mu);
    auto it = cache.find(key);
    if (it != cache.end()) return it->second;
    std::vector<cv::Point2f> px;
    px.reserve((size_t)c.size.area() * kSS * kSS);
    for (int v = 0; v < c.size.height; v++)
        for (int u = 0; u < c.size.width; u++)
            for (int j = 0; j < kSS; j++)
                for (int i = 0; i < kSS; i++)
                    px.emplace_back(float(u + (i + 0.5) / kSS - 0.5), float(v + (j + 0.5) / kSS - 0.5));
    cv::Mat K = (cv::Mat_<double>(3, 3) << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
    cv::Mat D = (cv::Mat_<double>(1, 5) << c.k1, c.k2, c.p1, c.p2, c.k3);
    RayMap m;
    cv::undistortPoints(px, m.xy, K, D, cv::noArray(), cv::noArray(),
                        cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 50, 1e-12));
    return cache.emplace(key, std::move(m)).first->second;
}
} // namespace

cv::Mat render_floor_board(const FloorCamera &c, const FloorBoard &fb, double noise, uint64_t seed)
{
    const RayMap &rm = ray_map(c);
    // camera axes in the robot frame: R = Rz(yaw) Ry(tilt) Rx(roll) applied to the body frame
    // (x forward, y left, z up); optical right = -y_body, down = -z_body, forward = x_body.
    cv::Matx33d Rz(std::cos(c.yaw_rad), -std::sin(c.yaw_rad), 0, std::sin(c.yaw_rad), std::cos(c.yaw_rad), 0, 0, 0, 1);
    cv::Matx33d Ry(std::cos(c.tilt_rad), 0, std::sin(c.tilt_rad), 0, 1, 0, -std::sin(c.tilt_rad), 0, std::cos(c.tilt_rad));
    cv::Matx33d Rx(1, 0, 0, 0, std::cos(c.roll_rad), -std::sin(c.roll_rad), 0, std::sin(c.roll_rad), std::cos(c.roll_rad));
    cv::Matx33d R = Rz * Ry * Rx;
    cv::Vec3d f = R * cv::Vec3d(1, 0, 0), r = R * cv::Vec3d(0, -1, 0), d = R * cv::Vec3d(0, 0, -1);
    cv::Vec3d C(c.offset_m, c.lateral_m, c.height_floor_m);
    const Board &b = fb.board;
    const double phi = fb.place.axis_deg * CV_PI / 180.0;
    const cv::Vec2d ax(std::cos(phi), std::sin(phi)), ay(-std::sin(phi), std::cos(phi));
    const double sq = b.square, u0 = 0.5 * (b.cols - 1) * sq, v0 = 0.5 * (b.rows - 1) * sq;
    const double m = fb.margin_squares * sq;
    cv::Mat img(c.size, CV_32F);
    size_t k = 0;
    for (int v = 0; v < c.size.height; v++) {
        float *row = img.ptr<float>(v);
        for (int u = 0; u < c.size.width; u++) {
            double acc = 0;
            for (int s = 0; s < kSS * kSS; s++, k++) {
                const double x = rm.xy[k].x, y = rm.xy[k].y;
                cv::Vec3d dir = r * x + d * y + f;
                double val = 150;  // wall / above the horizon
                if (dir[2] < -1e-9) {
                    double lam = -C[2] / dir[2];
                    double px = C[0] + lam * dir[0] - fb.place.centre_x_m, py = C[1] + lam * dir[1] - fb.place.centre_y_m;
                    double bu = px * ax[0] + py * ax[1] + u0, bv = px * ay[0] + py * ay[1] + v0;
                    val = 105;  // floor
                    if (bu > -sq - m && bu < b.cols * sq + m && bv > -sq - m && bv < b.rows * sq + m) {
                        val = 215;  // paper
                        if (bu > -sq && bu < b.cols * sq && bv > -sq && bv < b.rows * sq) {
                            long i = (long)std::floor(bu / sq), j = (long)std::floor(bv / sq);
                            if (((i + j) & 1) == 0) val = 25;
                        }
                    }
                }
                acc += val;
            }
            row[u] = (float)(acc / (kSS * kSS));
        }
    }
    cv::GaussianBlur(img, img, cv::Size(0, 0), 0.7);
    cv::Mat n(c.size, CV_32F);
    cv::RNG rng(seed);
    rng.fill(n, cv::RNG::NORMAL, 0.0, noise);
    img += n;
    cv::Mat out;
    img.convertTo(out, CV_8U);
    return out;
}

cyl_camera to_cyl(const FloorCamera &c)
{
    cyl_camera cam;
    cyl_camera_init(&cam);
    cam.width = (uint32_t)c.size.width;
    cam.height = (uint32_t)c.size.height;
    cam.fx_px = c.fx;
    cam.fy_px = c.fy;
    cam.cx_px = c.cx;
    cam.cy_px = c.cy;
    cam.k1 = c.k1;
    cam.k2 = c.k2;
    cam.p1 = c.p1;
    cam.p2 = c.p2;
    cam.k3 = c.k3;
    return cam;
}

MountExperiment mount_experiment(int renders, uint64_t seed, bool jitter, bool progress)
{
    MountExperiment x;
    x.renders = renders;
    FloorCamera nominal;
    nominal.yaw_rad = 1.5 * CV_PI / 180;
    nominal.roll_rad = 0.4 * CV_PI / 180;
    FloorBoard fb;
    cyl_camera cam = to_cyl(nominal);
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> G(0.0, 1.0);
    std::vector<std::array<double, 5>> err, tru;
    std::vector<cylfe::calib::MountEstimate> es;
    std::vector<double> sig2(5, 0.0);
    int inside = 0, total = 0;
    for (int i = 0; i < renders; i++) {
        FloorCamera c = nominal;
        if (jitter) {
            c.height_floor_m += 0.002 * G(rng);
            c.tilt_rad += 0.5 * CV_PI / 180 * G(rng);
            c.yaw_rad += 0.4 * CV_PI / 180 * G(rng);
            c.roll_rad += 0.3 * CV_PI / 180 * G(rng);
            c.offset_m += 0.002 * G(rng);
        }
        cv::Mat img = render_floor_board(c, fb, 2.0, seed * 1000003u + (uint64_t)i);
        std::vector<cv::Point2f> corners;
        if (!cylfe::calib::find_corners(img, fb.board, cylfe::calib::DetectOptions(), corners)) continue;
        x.detected++;
        auto e = cylfe::calib::estimate_mount(cam, fb.board, fb.place, corners, "render " + std::to_string(i));
        es.push_back(e);
        const double est[5] = {e.height_floor_m, e.tilt_rad, e.yaw_rad, e.roll_rad, e.offset_m};
        const double tr[5] = {c.height_floor_m, c.tilt_rad, c.yaw_rad, c.roll_rad, c.offset_m};
        std::array<double, 5> d, t;
        for (int k = 0; k < 5; k++) {
            d[k] = est[k] - tr[k];
            t[k] = tr[k];
            double z = std::fabs(d[k]) / e.sigma[k];
            x.max_abs_z = std::max(x.max_abs_z, z);
            inside += z <= 3.0;
            total++;
            sig2[k] += e.sigma[k] * e.sigma[k];
        }
        err.push_back(d);
        tru.push_back(t);
        if (progress && (i + 1) % 10 == 0) std::fprintf(stderr, "mount renders: %d/%d\n", i + 1, renders);
    }
    const int n = (int)err.size();
    if (n < 3) return x;
    x.frac_within_3sigma = (double)inside / total;
    cylfe::calib::MountSummary sum = cylfe::calib::summarise_mount(es);
    for (int k = 0; k < 5; k++) {
        double m = 0, v = 0, tm = 0, tv = 0;
        for (int i = 0; i < n; i++) {
            m += err[i][k];
            tm += tru[i][k];
        }
        m /= n;
        tm /= n;
        for (int i = 0; i < n; i++) {
            v += (err[i][k] - m) * (err[i][k] - m);
            tv += (tru[i][k] - tm) * (tru[i][k] - tm);
        }
        x.mean_err[k] = m;
        x.err_spread[k] = std::sqrt(v / (n - 1));
        x.truth_spread[k] = std::sqrt(tv / (n - 1));
        x.startup_spread[k] = sum.spread[k];
        x.sigma_rms[k] = std::sqrt(sig2[k] / n);
        x.max_sigma_error = std::max(x.max_sigma_error, std::fabs(x.sigma_rms[k] / x.err_spread[k] - 1));
        x.max_mean_z = std::max(x.max_mean_z, std::fabs(m) / (x.err_spread[k] / std::sqrt((double)n)));
    }
    return x;
}

} // namespace calibtest
