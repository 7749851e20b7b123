// SPDX-License-Identifier: BSD-3-Clause
// The calibration tools: intrinsics against cv::calibrateCamera on OpenCV's sample
// images, the reported sigmas against a Monte Carlo, the mount extrinsics on synthetic floor
// renders, the file writers, colour-table training, and the tools' handling of bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "calib_testlib.hpp"
#include "cylfe/calib.hpp"
#include "cylfe/calibration.hpp"
#include "cylfe/error.hpp"
#include "cylfe/rawlog.hpp"

#ifndef CALIB_BIN
#define CALIB_BIN "build"
#endif

using namespace cylfe;
using namespace cylfe::calib;

namespace {

std::string tmpdir()
{
    static std::string d;
    if (d.empty()) {
        char t[] = "/tmp/cyl_calib_test_XXXXXX";
        d = mkdtemp(t);
    }
    return d;
}

bool exists(const std::string &p) { return access(p.c_str(), F_OK) == 0; }

// remove the temporary directory after the last test
struct CleanupEnv : ::testing::Environment {
    void TearDown() override
    {
        if (!tmpdir().empty() && tmpdir().rfind("/tmp/cyl_calib_test_", 0) == 0)
            (void)!std::system(("rm -rf '" + tmpdir() + "'").c_str());
    }
};
const ::testing::Environment *const kCleanup = ::testing::AddGlobalTestEnvironment(new CleanupEnv);

struct ToolRun {
    int code;
    std::string out;
};
ToolRun run(const std::string &cmd)
{
    std::string full = cmd + " 2>&1";
    FILE *f = popen(full.c_str(), "r");
    ToolRun r{-1, ""};
    if (!f) return r;
    char buf[4096];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, f)) > 0) r.out.append(buf, n);
    int st = pclose(f);
    r.code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    return r;
}

std::string files_in(const std::string &dir)
{
    ToolRun r = run("ls -A " + dir);
    return r.out;
}

// corners of the 13 OpenCV sample images with OpenCV's sample settings (fixed 11 px half window)
const std::vector<View> &sample_views()
{
    static std::vector<View> v;
    if (v.empty()) {
        cv::Size s;
        DetectOptions o;
        o.adaptive_window = false;
        v = detect_views(calibtest::fixture_images(), Board(), o, s, nullptr);
    }
    return v;
}

std::vector<std::vector<cv::Point2f>> sample_corners()
{
    std::vector<std::vector<cv::Point2f>> c;
    for (auto &v : sample_views()) c.push_back(v.corners);
    return c;
}

} // namespace

// ---- intrinsics vs OpenCV -----------------------------------------------------------------------

TEST(Intrinsics, SampleImagesAllDetected)
{
    ASSERT_EQ(sample_views().size(), 13u);
    for (auto &v : sample_views()) EXPECT_EQ(v.corners.size(), 54u) << v.name;
}

TEST(Intrinsics, MatchesOpenCvCalibrateCamera)
{
    auto c = calibtest::compare_with_opencv(sample_corners(), cv::Size(640, 480), Board());
    EXPECT_LT(c.max_param_rel_diff, 1e-3);
    EXPECT_LT(c.rms_diff_px, 1e-3);
    EXPECT_LT(c.max_view_rms_diff, 1e-3);
    // sigma^2 = SSE/(2N - p) is OpenCV 4.6's stdDeviationsIntrinsics times (N - p)/(2N - p)
    EXPECT_LT(c.sigma_ratio_error, 0.01);
    EXPECT_EQ(c.ours.n_points, 702);
    EXPECT_EQ(c.ours.n_params, 87);
    // the anchors' reference on these images (RMS 0.40877 px, fx 536.074, sigma fx 0.928)
    EXPECT_NEAR(c.ours.rms, 0.40877, 2e-5);
    EXPECT_NEAR(c.ours.intr[0], 536.074, 2e-3);
    EXPECT_NEAR(c.ours.sigma[0], 0.928, 1e-3);
    // left02 is the outlying view (1.22 px)
    ASSERT_EQ(c.ours.outliers.size(), 1u);
    EXPECT_EQ(c.ours.outliers[0], 1);
    EXPECT_NEAR(c.ours.view_rms[1], 1.22, 0.01);
    // the covariance is symmetric positive definite
    cv::Mat C(9, 9, CV_64F);
    for (int i = 0; i < 9; i++)
        for (int j = 0; j < 9; j++) {
            EXPECT_NEAR(c.ours.cov[i][j], c.ours.cov[j][i], 1e-12 * (1 + std::fabs(c.ours.cov[i][j])));
            C.at<double>(i, j) = c.ours.cov[i][j];
        }
    cv::Mat ev;
    cv::eigen(C, ev);
    EXPECT_GT(ev.at<double>(8), 0.0);
}

TEST(Intrinsics, FixedParametersMatchOpenCvFlags)
{
    auto img = sample_corners();
    std::vector<std::vector<cv::Point3f>> obj(img.size(), board_points(Board()));
    IntrinsicOptions o;
    o.fix_k3 = true;
    o.zero_tangent = true;
    IntrinsicResult r = calibrate_intrinsics(obj, img, cv::Size(640, 480), o);
    cv::Mat K, D;
    std::vector<cv::Mat> rv, tv;
    double cv_rms =
        cv::calibrateCamera(obj, img, cv::Size(640, 480), K, D, rv, tv, cv::CALIB_FIX_K3 | cv::CALIB_ZERO_TANGENT_DIST);
    EXPECT_NEAR(r.rms, cv_rms, 1e-3);
    EXPECT_NEAR(r.intr[0], K.at<double>(0, 0), 1e-3 * K.at<double>(0, 0));
    EXPECT_NEAR(r.intr[3], K.at<double>(1, 2), 1e-3 * K.at<double>(1, 2));
    EXPECT_NEAR(r.intr[4], D.at<double>(0), 1e-3 * std::fabs(D.at<double>(0)));
    EXPECT_EQ(r.intr[CYL_INTR_K3], 0.0);
    EXPECT_EQ(r.intr[CYL_INTR_P1], 0.0);
    EXPECT_EQ(r.sigma[CYL_INTR_K3], 0.0);
    EXPECT_EQ(r.sigma[CYL_INTR_P2], 0.0);
    EXPECT_EQ(r.n_params, 6 + 6 * 13);

    IntrinsicOptions a;
    a.fix_aspect = true;
    a.aspect = 1.0;
    IntrinsicResult ra = calibrate_intrinsics(obj, img, cv::Size(640, 480), a);
    cv::Mat Ka = (cv::Mat_<double>(3, 3) << 500, 0, 320, 0, 500, 240, 0, 0, 1), Da;
    double rms_a = cv::calibrateCamera(obj, img, cv::Size(640, 480), Ka, Da, rv, tv,
                                       cv::CALIB_FIX_ASPECT_RATIO | cv::CALIB_USE_INTRINSIC_GUESS);
    EXPECT_NEAR(ra.rms, rms_a, 1e-3);
    EXPECT_DOUBLE_EQ(ra.intr[0], ra.intr[1]);
    EXPECT_NEAR(ra.intr[0], Ka.at<double>(0, 0), 1e-3 * Ka.at<double>(0, 0));
    EXPECT_NEAR(ra.cov[1][1], ra.cov[0][0], 1e-12);
    EXPECT_NEAR(ra.cov[1][2], ra.cov[0][2], 1e-12);
}

TEST(Intrinsics, TooFewOrDegenerateViewsAreErrors)
{
    auto img = sample_corners();
    std::vector<std::vector<cv::Point3f>> obj(2, board_points(Board()));
    std::vector<std::vector<cv::Point2f>> two(img.begin(), img.begin() + 2);
    EXPECT_THROW(calibrate_intrinsics(obj, two, cv::Size(640, 480), IntrinsicOptions()), Error);
    // three copies of one fronto-parallel view: the focal length is not observable
    cv::Mat K = (cv::Mat_<double>(3, 3) << 500, 0, 320, 0, 500, 240, 0, 0, 1);
    std::vector<cv::Point2f> flat;
    cv::projectPoints(board_points(Board()), cv::Vec3d(0, 0, 0), cv::Vec3d(-4, -2.5, 20), K, cv::noArray(), flat);
    std::vector<std::vector<cv::Point2f>> same(3, flat);
    std::vector<std::vector<cv::Point3f>> obj3(3, board_points(Board()));
    try {
        calibrate_intrinsics(obj3, same, cv::Size(640, 480), IntrinsicOptions());
        FAIL() << "a degenerate view set was accepted";
    } catch (const Error &e) {
        EXPECT_NE(std::string(e.what()).find("degenerate"), std::string::npos) << e.what();
    }
}

TEST(Intrinsics, MonteCarloSigmasMatchSpread)
{
    // reduced version of make calib-check's 1000 runs
    calibtest::MonteCarlo mc = calibtest::monte_carlo(200, 0.30, 11, false);
    for (int k = 0; k < 9; k++) {
        EXPECT_NEAR(mc.reported[k] / mc.spread[k], 1.0, 0.15) << "parameter " << k;
        EXPECT_LT(std::fabs(mc.mean[k] - mc.truth[k]), 4 * mc.spread[k] / std::sqrt(200.0)) << "parameter " << k;
    }
}

// ---- mount extrinsics -----------------------------------------------------------------------------

TEST(Mount, SyntheticRendersWithinSigmas)
{
    calibtest::MountExperiment x = calibtest::mount_experiment(60, 3, true, false);
    EXPECT_EQ(x.detected, 60);
    EXPECT_GE(x.frac_within_3sigma, 0.98);
    EXPECT_LT(x.max_sigma_error, 0.25);
    EXPECT_LT(x.max_mean_z, 4.0);
    for (int k = 0; k < 5; k++)  // the start-up spread recovers the true jitter
        EXPECT_NEAR(x.startup_spread[k] / x.truth_spread[k], 1.0, 0.2) << "parameter " << k;
}

TEST(Mount, BoardOrientationAndFlip)
{
    // the same scene with the board turned by 180 degrees (the corner order flips) or by 90
    calibtest::FloorCamera c;
    c.yaw_rad = -0.03;
    c.tilt_rad = 0.25;
    calibtest::FloorBoard fb;
    for (double axis : {90.0, 270.0, 0.0}) {
        fb.place.axis_deg = axis;
        fb.board = axis == 0.0 ? Board{6, 9, 0.06} : Board{9, 6, 0.07};
        cv::Mat img = calibtest::render_floor_board(c, fb, 1.0, 5);
        std::vector<cv::Point2f> corners;
        ASSERT_TRUE(find_corners(img, fb.board, DetectOptions(), corners)) << axis;
        MountEstimate e = estimate_mount(calibtest::to_cyl(c), fb.board, fb.place, corners);
        EXPECT_NEAR(e.height_floor_m, c.height_floor_m, 1e-3) << axis;
        EXPECT_NEAR(e.tilt_rad, c.tilt_rad, 1e-3) << axis;
        EXPECT_NEAR(e.yaw_rad, c.yaw_rad, 1e-3) << axis;
        EXPECT_NEAR(e.offset_m, c.offset_m, 2e-3) << axis;
        EXPECT_LT(e.rms_px, 0.3) << axis;
    }
}

// ---- files --------------------------------------------------------------------------------------

TEST(Files, YamlRoundTripBothFormats)
{
    IntrinsicResult r = calibrate_intrinsics(std::vector<std::vector<cv::Point3f>>(13, board_points(Board())),
                                             sample_corners(), cv::Size(640, 480), IntrinsicOptions());
    cyl_camera cam = r.camera();
    std::string a = tmpdir() + "/cv.yaml", b = tmpdir() + "/ros.yaml";
    save_opencv_yaml(a, cam, "a comment\nsecond line", false);
    save_ros_yaml(b, cam, "left", "a comment", false);
    for (const std::string &p : {a, b}) {
        CameraCalibration c = load_camera_calibration(p);
        EXPECT_EQ(c.format, p == a ? "opencv" : "ros");
        EXPECT_TRUE(c.intrinsic_cov_known);
        EXPECT_FALSE(c.mount_known) << "an intrinsic calibration must not claim a mount";
        EXPECT_EQ(c.cam.width, 640u);
        EXPECT_NEAR(c.cam.fx_px, cam.fx_px, 1e-8);
        EXPECT_NEAR(c.cam.k3, cam.k3, 1e-10);
        for (int i = 0; i < 9; i++)
            for (int j = 0; j < 9; j++)
                EXPECT_NEAR(c.cam.intr_cov[i][j], cam.intr_cov[i][j], 1e-9 * (std::fabs(cam.intr_cov[i][j]) + 1e-12));
    }
    // with the mount
    cam.tilt_rad = 0.2;
    cam.yaw_rad = -0.01;
    cam.height_m = 0.3;
    cam.offset_m = 0.1;
    cam.tilt_sigma_rad = 0.01;
    cam.yaw_sigma_rad = 0.005;
    cam.height_sigma_m = 3e-4;
    cam.offset_sigma_m = 2e-3;
    cam.flags &= ~CYL_CAM_EXTR_SIG_UNKNOWN;
    save_ros_yaml(b, cam, "left");
    CameraCalibration c = load_camera_calibration(b);
    EXPECT_TRUE(c.mount_known);
    EXPECT_TRUE(c.mount_sigmas_known);
    EXPECT_NEAR(c.cam.tilt_rad, 0.2, 1e-10);
    EXPECT_NEAR(c.cam.height_sigma_m, 3e-4, 1e-12);
    // no temporary files left behind
    std::string ls = files_in(tmpdir());
    EXPECT_EQ(ls.find(".tmp"), std::string::npos) << ls;
}

TEST(Files, FailedWriteLeavesNothing)
{
    EXPECT_THROW(write_file_atomic(tmpdir() + "/no/such/dir/x.yaml", "x"), Error);
    cyl_camera cam;
    cyl_camera_init(&cam);
    EXPECT_THROW(save_opencv_yaml(tmpdir() + "/no/such/dir/x.yaml", cam), Error);
}

// ---- colour tables --------------------------------------------------------------------------------

namespace {
// A grey BGR image with an orange and a green rectangle (with a little noise).
cv::Mat patches_image()
{
    cv::Mat img(240, 320, CV_8UC3, cv::Scalar(120, 120, 120));
    cv::rectangle(img, cv::Rect(40, 60, 60, 100), cv::Scalar(20, 120, 240), cv::FILLED);   // orange (BGR)
    cv::rectangle(img, cv::Rect(200, 80, 50, 90), cv::Scalar(60, 170, 40), cv::FILLED);    // green
    cv::Mat n(img.size(), CV_8UC3);
    cv::randn(n, cv::Scalar::all(0), cv::Scalar::all(3));
    cv::Mat out;
    cv::add(img, n, out, cv::noArray(), CV_8U);
    return out;
}
} // namespace

TEST(ColourTable, TrainFromImageFileClassifiesTheRegion)
{
    std::string png = tmpdir() + "/patches.png";
    ASSERT_TRUE(cv::imwrite(png, patches_image()));
    Frame f = load_frame(png);
    EXPECT_EQ(f.img.format, CYL_FMT_I420);
    cyl_colortable t;
    cyl_colortable_init(&t);
    ASSERT_EQ(cyl_colortable_set_class(&t, 0, "orange", 255, 128, 0), CYL_OK);
    uint8_t box[6];
    train_rect(t, 0, f, cv::Rect(50, 70, 40, 80), cyl_train_params_default(), box);
    EXPECT_GT(class_coverage(t, 0, f, cv::Rect(40, 60, 60, 100)), 0.97);
    EXPECT_LT(class_coverage(t, 0, f, cv::Rect(200, 80, 50, 90)), 0.01);
    EXPECT_LT(class_coverage(t, 0, f, cv::Rect(0, 0, 30, 30)), 0.01);
    EXPECT_THROW(train_rect(t, 0, f, cv::Rect(300, 200, 40, 80), cyl_train_params_default(), box), Error);
    std::string tab = tmpdir() + "/t.cylt";
    save_table(tab, t);
    cyl_colortable u;
    load_table(tab, u);
    cyl_colortable_refresh(&t);   // as loading does (the inner boxes, which adding a box leaves empty)
    EXPECT_EQ(0, std::memcmp(&t, &u, sizeof t));
    // a corrupted table is refused with the file's name
    {
        std::fstream fs(tab, std::ios::in | std::ios::out | std::ios::binary);
        fs.seekp(1000);
        fs.put('\x55');
    }
    try {
        load_table(tab, u);
        FAIL();
    } catch (const Error &e) {
        EXPECT_NE(std::string(e.what()).find(tab), std::string::npos);
    }
}

TEST(ColourTable, TrainFromRawLogFrame)
{
    // a YUYV raw log whose frame 1 has a bright patch with distinct chroma
    const uint32_t w = 64, h = 48;
    StreamInfo in;
    in.fourcc = fourcc_from_pixfmt(CYL_FMT_YUYV);
    in.width = w;
    in.height = h;
    in.stride = w * 2;
    in.frame_bytes = w * h * 2;
    in.source = "test";
    std::string log = tmpdir() + "/f.cylraw";
    {
        RawLogWriter wr(log, in);
        for (int k = 0; k < 3; k++) {
            std::vector<uint8_t> fr(in.frame_bytes);
            for (uint32_t y = 0; y < h; y++)
                for (uint32_t x = 0; x < w; x += 2) {
                    bool patch = k == 1 && x >= 16 && x < 40 && y >= 10 && y < 30;
                    uint8_t *p = &fr[y * in.stride + x * 2];
                    p[0] = p[2] = patch ? 150 : 100;
                    p[1] = patch ? 60 : 128;   // U
                    p[3] = patch ? 200 : 128;  // V
                }
            wr.frame((uint64_t)k, k * 1000000, fr.data(), fr.size());
        }
        wr.close();
    }
    Frame f = load_frame(log, 1);
    EXPECT_EQ(f.img.format, CYL_FMT_YUYV);
    cyl_colortable t;
    cyl_colortable_init(&t);
    cyl_colortable_set_class(&t, 2, "pink", 255, 0, 255);
    uint8_t box[6];
    train_rect(t, 2, f, cv::Rect(18, 12, 20, 16), cyl_train_params_default(), box);
    EXPECT_LE(box[0], 60);
    EXPECT_GE(box[1], 60);
    EXPECT_LE(box[2], 200);
    EXPECT_GE(box[3], 200);
    EXPECT_GT(class_coverage(t, 2, f, cv::Rect(16, 10, 24, 20)), 0.99);
    EXPECT_EQ(class_coverage(t, 2, load_frame(log, 0), cv::Rect(16, 10, 24, 20)), 0.0);
    EXPECT_THROW(load_frame(log, 3), Error);
}

// ---- the tools ------------------------------------------------------------------------------------

TEST(Tools, CalibrateIntrinsicsEndToEnd)
{
    std::string dir = calibtest::fixture_dir(), out = tmpdir() + "/ocv.yaml", ros = tmpdir() + "/ocv_ros.yaml";
    ToolRun r = run(std::string(CALIB_BIN) + "/cyl-calibrate intrinsics -q -o " + out + " --ros " + ros + " " + dir + "/*.jpg");
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_NE(r.out.find("left02.jpg"), std::string::npos) << "the outlier view is named\n" << r.out;
    CameraCalibration a = load_camera_calibration(out), b = load_camera_calibration(ros);
    EXPECT_NEAR(a.cam.fx_px, b.cam.fx_px, 1e-6);
    EXPECT_GT(a.cam.intr_cov[0][0], 0.0);
    EXPECT_FALSE(a.mount_known);
}

TEST(Tools, CalibrateBadInput)
{
    std::string bin = std::string(CALIB_BIN) + "/cyl-calibrate", dir = calibtest::fixture_dir();
    std::string out = tmpdir() + "/bad.yaml";
    // too few boards: two images with a board, one without (a blank image)
    std::string blank = tmpdir() + "/blank.png";
    cv::imwrite(blank, cv::Mat(480, 640, CV_8UC1, cv::Scalar(128)));
    ToolRun r = run(bin + " intrinsics -o " + out + " " + dir + "/left01.jpg " + dir + "/left03.jpg " + blank);
    EXPECT_EQ(r.code, kExitFailure) << r.out;
    EXPECT_NE(r.out.find(blank + ": chessboard"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("at least 3"), std::string::npos) << r.out;
    EXPECT_FALSE(exists(out));
    // an unreadable image is named
    std::string junk = tmpdir() + "/junk.jpg";
    std::ofstream(junk) << "not a jpeg";
    r = run(bin + " intrinsics -o " + out + " " + dir + "/left01.jpg " + junk);
    EXPECT_EQ(r.code, kExitFailure);
    EXPECT_NE(r.out.find(junk), std::string::npos) << r.out;
    EXPECT_FALSE(exists(out));
    // a skipped image is a warning only
    r = run(bin + " intrinsics -q -o " + out + " " + dir + "/left0[1-6].jpg " + blank);
    EXPECT_EQ(r.code, 0) << r.out;
    EXPECT_NE(r.out.find("warning"), std::string::npos);
    EXPECT_TRUE(exists(out));
    // command-line errors
    EXPECT_EQ(run(bin + " intrinsics " + dir + "/left01.jpg").code, kExitUsage);
    EXPECT_EQ(run(bin + " intrinsics --board 9 -o x.yaml a.jpg").code, kExitUsage);
    EXPECT_EQ(run(bin + " frobnicate").code, kExitUsage);
    EXPECT_EQ(run(bin + " --help").code, 0);
    ToolRun m = run(bin + " mount --camera " + out + " --square 0.05 --board-centre 1,0 -o " + out + " " + blank);
    EXPECT_EQ(m.code, kExitUsage);
    EXPECT_NE(m.out.find("--landmark-height"), std::string::npos) << m.out;
    // a malformed calibration file is named with its field
    std::string badcal = tmpdir() + "/badcal.yaml";
    std::ofstream(badcal) << "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\ncamera_matrix: [1, 2]\n";
    m = run(bin + " mount --camera " + badcal + " --square 0.05 --board-centre 1,0 --landmark-height 0.3 -o " +
            tmpdir() + "/m.yaml " + blank);
    EXPECT_EQ(m.code, kExitFailure);
    EXPECT_NE(m.out.find("camera_matrix"), std::string::npos) << m.out;
    EXPECT_FALSE(exists(tmpdir() + "/m.yaml"));
}

TEST(Tools, CalibrateMountEndToEnd)
{
    calibtest::FloorCamera c;
    c.yaw_rad = 0.02;
    calibtest::FloorBoard fb;
    cyl_camera cam = calibtest::to_cyl(c);
    cam.intr_cov[0][0] = 0.25;
    cam.flags &= ~CYL_CAM_INTR_COV_UNKNOWN;
    std::string cal = tmpdir() + "/floorcam.yaml";
    save_opencv_yaml(cal, cam, "", false);
    std::string imgs;
    for (int i = 0; i < 5; i++) {
        calibtest::FloorCamera ci = c;
        ci.tilt_rad += 0.004 * (i - 2);
        std::string p = tmpdir() + "/floor" + std::to_string(i) + ".png";
        cv::imwrite(p, calibtest::render_floor_board(ci, fb, 2.0, 100 + i));
        imgs += " " + p;
    }
    std::string out = tmpdir() + "/mounted.yaml";
    ToolRun r = run(std::string(CALIB_BIN) + "/cyl-calibrate mount -q --camera " + cal +
                " --square 0.07 --board-centre 1.0,0 --board-axis 90 --landmark-height 0.3 -o " + out + imgs);
    ASSERT_EQ(r.code, 0) << r.out;
    CameraCalibration m = load_camera_calibration(out);
    EXPECT_TRUE(m.mount_known && m.mount_sigmas_known);
    EXPECT_NEAR(m.cam.height_m, c.height_floor_m - 0.15, 1e-3);
    EXPECT_NEAR(m.cam.tilt_rad, c.tilt_rad, 1e-3);
    EXPECT_NEAR(m.cam.tilt_sigma_rad, 0.004 * std::sqrt(2.5), 0.002);  // std of -2..2 steps of 0.004
    EXPECT_NEAR(m.cam.yaw_rad, 0.02, 1e-3);
    EXPECT_NEAR(m.cam.offset_m, c.offset_m, 2e-3);
    EXPECT_NEAR(m.cam.fx_px, c.fx, 1e-9);
    EXPECT_NEAR(m.cam.intr_cov[0][0], 0.25, 1e-12);  // the intrinsics pass through
    // an input without covariance gives an output without covariance (not a zero one)
    cam.flags |= CYL_CAM_INTR_COV_UNKNOWN;
    save_opencv_yaml(cal, cam, "", false);
    std::string ros = tmpdir() + "/mounted_ros.yaml";
    r = run(std::string(CALIB_BIN) + "/cyl-calibrate mount -q --camera " + cal +
            " --square 0.07 --board-centre 1.0,0 --centroid-height 0.15 -o " + out + " --ros " + ros + imgs);
    ASSERT_EQ(r.code, 0) << r.out;
    for (const std::string &p : {out, ros}) {
        CameraCalibration m2 = load_camera_calibration(p);
        EXPECT_FALSE(m2.intrinsic_cov_known) << p;
        EXPECT_TRUE(m2.mount_known) << p;
        EXPECT_NEAR(m2.cam.height_m, m.cam.height_m, 1e-9) << p;
    }
}

TEST(Tools, TrainCommandLine)
{
    std::string bin = std::string(CALIB_BIN) + "/cyl-train";
    std::string png = tmpdir() + "/patches2.png", out = tmpdir() + "/cli.cylt";
    ASSERT_TRUE(cv::imwrite(png, patches_image()));
    ToolRun r = run(bin + " -o " + out + " --class orange --color 255,128,0 --image " + png +
                " --rect 50,70,40,80 --class green --image " + png + " --rect 205,90,40,70");
    ASSERT_EQ(r.code, 0) << r.out;
    cyl_colortable t;
    load_table(out, t);
    EXPECT_STREQ(t.name[0], "orange");
    EXPECT_STREQ(t.name[1], "green");
    EXPECT_EQ(t.rgb[0][1], 128);
    Frame f = load_frame(png);
    EXPECT_GT(class_coverage(t, 0, f, cv::Rect(40, 60, 60, 100)), 0.97);
    EXPECT_GT(class_coverage(t, 1, f, cv::Rect(200, 80, 50, 90)), 0.97);
    // add to an existing table, replacing one class
    ToolRun r2 = run(bin + " -o " + out + " --base " + out + " --class green --replace --image " + png + " --rect 50,70,40,80");
    ASSERT_EQ(r2.code, 0) << r2.out;
    load_table(out, t);
    EXPECT_LT(class_coverage(t, 1, f, cv::Rect(200, 80, 50, 90)), 0.01);
    // bad input: nothing written, messages name the culprit
    std::string out2 = tmpdir() + "/never.cylt";
    ToolRun b1 = run(bin + " -o " + out2 + " --class orange --image " + png + " --rect 300,200,50,50");
    EXPECT_EQ(b1.code, kExitFailure);
    EXPECT_NE(b1.out.find("300,200,50,50"), std::string::npos) << b1.out;
    ToolRun b2 = run(bin + " -o " + out2 + " --class orange --image " + tmpdir() + "/missing.png --rect 1,1,5,5");
    EXPECT_EQ(b2.code, kExitFailure);
    EXPECT_NE(b2.out.find("missing.png"), std::string::npos) << b2.out;
    ToolRun b3 = run(bin + " -o " + out2 + " --class orange --image " + png + " --rect 1,2,3");
    EXPECT_EQ(b3.code, kExitUsage);
    ToolRun b4 = run(bin + " -o " + out2 + " --base " + png + " --class x --image " + png + " --rect 1,1,5,5");
    EXPECT_EQ(b4.code, kExitFailure);
    EXPECT_NE(b4.out.find("CYLT"), std::string::npos) << b4.out;
    EXPECT_FALSE(exists(out2));
    EXPECT_EQ(run(bin + " --help").code, 0);
    std::string ls = files_in(tmpdir());
    EXPECT_EQ(ls.find(".tmp"), std::string::npos) << ls;
}
