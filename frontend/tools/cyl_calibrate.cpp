// SPDX-License-Identifier: BSD-3-Clause
// cyl-calibrate: camera intrinsics from chessboard images (Ceres, with the full covariance), and
// the robot mount's extrinsics from a chessboard lying on the floor. docs/calibration.md.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>
#include <unistd.h>

#include "cylfe/version.hpp"
#include "cylfe/calib.hpp"
#include "cylfe/calibration.hpp"
#include "cylfe/error.hpp"

using namespace cylfe;
using namespace cylfe::calib;

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

const char *kUsage =
    "usage: cyl-calibrate intrinsics [options] IMAGE...\n"
    "       cyl-calibrate mount --camera CAL.yaml [options] IMAGE...\n"
    "       cyl-calibrate --help | --version\n"
    "\n"
    "intrinsics: detect a chessboard in each image (cv::findChessboardCorners + cornerSubPix),\n"
    "  start from a closed-form estimate, refine fx fy cx cy k1 k2 p1 p2 k3 and the view poses with\n"
    "  Ceres, and report the full covariance of the intrinsics with sigma^2 = SSE / (2N - p)\n"
    "  (N corners, p free parameters). Images without a board are skipped with a warning; fewer\n"
    "  than 3 usable views is an error.\n"
    "  -o, --out FILE        OpenCV FileStorage YAML with libcyl's uncertainty fields (required\n"
    "                        unless --ros is given)\n"
    "  --ros FILE            also (or only) a ROS camera_info YAML with the same fields\n"
    "  --camera-name NAME    camera_name of the ROS file (default: camera)\n"
    "  --board CxR           inner corners per row x per column (default 9x6)\n"
    "  --square S            square size (default 1; any unit, does not affect intrinsics)\n"
    "  --fix-k3              hold k3 at 0\n"
    "  --zero-tangent        hold p1 = p2 = 0\n"
    "  --fix-aspect[=A]      hold fy/fx at A (default: the closed-form start's ratio)\n"
    "  --outlier-factor F    warn about views whose RMS exceeds F x the overall RMS (default 2)\n"
    "  --subpix-window N     cornerSubPix half window, fixed (default: 11, i.e. 23x23 px as OpenCV's\n"
    "                        sample, reduced to half the corner spacing for small boards)\n"
    "  -q, --quiet           no progress or per-view table\n"
    "\n"
    "mount: the camera's height, tilt, yaw (and roll, reported only) and forward offset on the robot\n"
    "  from images of a chessboard lying flat on the floor at a known place; one image per camera\n"
    "  start-up (the paper's Table 5 procedure: repeat over N power-ups). Writes the mean as the\n"
    "  mount values and the standard deviation over the start-ups as their sigmas (with a single\n"
    "  image: that image's estimation sigma, with a warning) into a copy of the calibration file.\n"
    "  --camera FILE         intrinsic calibration (OpenCV or ROS YAML) (required)\n"
    "  -o, --out FILE        output calibration (OpenCV YAML; may be the --camera file) (required\n"
    "                        unless --ros is given)\n"
    "  --ros FILE            also (or only) the ROS camera_info form\n"
    "  --board CxR           inner corners (default 9x6)\n"
    "  --square M            square size in metres (required)\n"
    "  --board-centre X,Y    robot-frame position (m, x forward, y left) of the centre of the\n"
    "                        inner-corner grid on the floor (required)\n"
    "  --board-axis DEG      direction of the board's rows (the C corners) counter-clockwise from\n"
    "                        the robot's forward axis, modulo 180 (default 90: rows run left-right)\n"
    "  --landmark-height M   landmark height: libcyl's h is the optical centre's height above the\n"
    "                        landmarks' CENTROID plane = floor height - M/2\n"
    "  --centroid-height M   or give the floor-to-centroid offset directly (one of the two is\n"
    "                        required)\n"
    "  --offset M            camera-to-robot-centre offset s measured by hand (default: the mean\n"
    "                        estimate from the images)\n"
    "  --offset-sigma M      its sigma (default: the spread over the images)\n"
    "  --yaw-zero            assume the camera points straight ahead (the paper): yaw 0, with the\n"
    "                        RMS of the measured yaws as its sigma\n"
    "  -q, --quiet\n"
    "\n"
    "exit codes: 0 ok, 1 failed (unreadable image, too few boards, degenerate views, bad\n"
    "calibration file), 2 bad command line. Outputs are written to a temporary file and renamed:\n"
    "a failed run leaves no partial file. Only a regular file is replaced: a device node or FIFO is\n"
    "written in place, a symbolic link through to its file; a dangling link is refused.\n";

struct Usage : std::runtime_error {
    using std::runtime_error::runtime_error;
};

double parse_double(const std::string &opt, const std::string &v)
{
    char *end = nullptr;
    double d = std::strtod(v.c_str(), &end);
    if (v.empty() || *end || !std::isfinite(d)) throw Usage(opt + ": not a number: '" + v + "'");
    return d;
}

void parse_pair(const std::string &opt, const std::string &v, char sep, double &a, double &b)
{
    size_t p = v.find(sep);
    if (p == std::string::npos) throw Usage(opt + ": expected two values separated by '" + std::string(1, sep) + "'");
    a = parse_double(opt, v.substr(0, p));
    b = parse_double(opt, v.substr(p + 1));
}

Board parse_board(const std::string &v)
{
    double c, r;
    parse_pair("--board", v, 'x', c, r);
    if (c < 2 || r < 2 || c != std::floor(c) || r != std::floor(r) || c > 100 || r > 100)
        throw Usage("--board: expected CxR inner corners, each 2..100");
    Board b;
    b.cols = (int)c;
    b.rows = (int)r;
    return b;
}

struct Args {
    std::string cmd, out, ros, camera_name = "camera", camera;
    Board board;
    bool square_given = false;
    IntrinsicOptions io;
    DetectOptions det;
    bool quiet = false;
    BoardPlacement place;
    bool centre_given = false;
    double centroid = NAN, offset = NAN, offset_sigma = NAN;
    bool yaw_zero = false;
    std::vector<std::string> images;
};

Args parse(int argc, char **argv)
{
    Args a;
    if (argc < 2) throw Usage("missing subcommand (intrinsics or mount)");
    a.cmd = argv[1];
    if (a.cmd == "-h" || a.cmd == "--help") return a;
    if (a.cmd != "intrinsics" && a.cmd != "mount") throw Usage("unknown subcommand '" + a.cmd + "'");
    for (int i = 2; i < argc; i++) {
        std::string s = argv[i], val;
        bool has_eq = false;
        if (s.rfind("--", 0) == 0 && s.find('=') != std::string::npos) {
            val = s.substr(s.find('=') + 1);
            s.resize(s.find('='));
            has_eq = true;
        }
        auto next = [&]() -> std::string {
            if (has_eq) return val;
            if (i + 1 >= argc) throw Usage(s + ": missing value");
            return argv[++i];
        };
        if (s == "-h" || s == "--help") { a.cmd = "--help"; return a; }
        else if (s == "-o" || s == "--out") a.out = next();
        else if (s == "--ros") a.ros = next();
        else if (s == "--camera-name") a.camera_name = next();
        else if (s == "--board") { double sq = a.board.square; a.board = parse_board(next()); a.board.square = sq; }
        else if (s == "--square") {
            a.board.square = parse_double(s, next());
            if (!(a.board.square > 0)) throw Usage("--square must be positive");
            a.square_given = true;
        }
        else if (s == "--fix-k3") a.io.fix_k3 = true;
        else if (s == "--zero-tangent") a.io.zero_tangent = true;
        else if (s == "--fix-aspect") {
            a.io.fix_aspect = true;
            if (has_eq) {
                a.io.aspect = parse_double(s, val);
                if (!(a.io.aspect > 0)) throw Usage("--fix-aspect: the ratio must be positive");
            }
        }
        else if (s == "--outlier-factor") a.io.outlier_factor = parse_double(s, next());
        else if (s == "--subpix-window") {
            double w = parse_double(s, next());
            if (w < 1 || w > 50 || w != std::floor(w)) throw Usage("--subpix-window: 1..50");
            a.det.subpix_half_window = (int)w;
            a.det.adaptive_window = false;
        }
        else if (s == "-q" || s == "--quiet") a.quiet = true;
        else if (s == "--camera") a.camera = next();
        else if (s == "--board-centre" || s == "--board-center") {
            parse_pair(s, next(), ',', a.place.centre_x_m, a.place.centre_y_m);
            a.centre_given = true;
        }
        else if (s == "--board-axis") a.place.axis_deg = parse_double(s, next());
        else if (s == "--landmark-height") {
            double h = parse_double(s, next());
            if (!(h >= 0)) throw Usage("--landmark-height must be >= 0");
            a.centroid = h / 2;
        }
        else if (s == "--centroid-height") a.centroid = parse_double(s, next());
        else if (s == "--offset") a.offset = parse_double(s, next());
        else if (s == "--offset-sigma") {
            a.offset_sigma = parse_double(s, next());
            if (!(a.offset_sigma >= 0)) throw Usage("--offset-sigma must be >= 0");
        }
        else if (s == "--yaw-zero") a.yaw_zero = true;
        else if (s.size() > 1 && s[0] == '-') throw Usage("unknown option '" + s + "'");
        else a.images.push_back(argv[i]);
    }
    if (a.out.empty() && a.ros.empty()) throw Usage("no output: give -o FILE and/or --ros FILE");
    if (a.images.empty()) throw Usage("no images");
    if (a.cmd == "mount") {
        if (a.camera.empty()) throw Usage("mount: --camera CAL.yaml is required");
        if (!a.square_given) throw Usage("mount: --square M (the square size in metres) is required");
        if (!a.centre_given) throw Usage("mount: --board-centre X,Y is required");
        if (std::isnan(a.centroid))
            throw Usage("mount: --landmark-height M or --centroid-height M is required (libcyl's h is measured "
                        "from the landmarks' centroid plane, not the floor)");
    }
    return a;
}

void warn(const std::string &m) { std::fprintf(stderr, "cyl-calibrate: warning: %s\n", m.c_str()); }

std::vector<View> detect(const Args &a, cv::Size &size)
{
    auto progress = [&](size_t i, size_t n) {
        if (!a.quiet && isatty(2)) std::fprintf(stderr, "\rdetecting chessboards: %zu/%zu%s", i, n, i == n ? "\n" : "");
    };
    return detect_views(a.images, a.board, a.det, size, warn, progress);
}

// The command line for the output file's comment, with the image list summarised.
std::string join_args(int argc, char **argv, const Args &a)
{
    std::string s = "cyl-calibrate";
    for (int i = 1; i < argc; i++) {
        bool img = false;
        for (auto &p : a.images) img = img || p == argv[i];
        if (!img) s += std::string(" ") + argv[i];
    }
    std::string first = a.images.empty() ? "" : a.images[0];
    return s + " + " + std::to_string(a.images.size()) + " image(s) (" + first + (a.images.size() > 1 ? " ...)" : ")");
}

int run_intrinsics(const Args &a, const std::string &cmdline)
{
    cv::Size size;
    std::vector<View> views = detect(a, size);
    if (views.size() < 3)
        throw Error("only " + std::to_string(views.size()) + " of " + std::to_string(a.images.size()) +
                    " images have a usable chessboard; at least 3 are needed");
    std::vector<std::vector<cv::Point3f>> obj(views.size(), board_points(a.board));
    std::vector<std::vector<cv::Point2f>> img;
    std::vector<std::string> names;
    for (auto &v : views) {
        img.push_back(v.corners);
        names.push_back(v.name);
    }
    if (!a.quiet) std::fprintf(stderr, "refining %zu views with Ceres...\n", views.size());
    IntrinsicResult r = calibrate_intrinsics(obj, img, size, a.io, names);
    static const char *pn[CYL_INTR_COUNT] = {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"};
    std::printf("views %zu of %zu, corners N = %d, free parameters p = %d, iterations %d\n", views.size(),
                a.images.size(), r.n_points, r.n_params, r.iterations);
    std::printf("RMS reprojection error %.5f px (sqrt(SSE/N)); sigma_px = sqrt(SSE/(2N-p)) = %.5f px\n", r.rms,
                std::sqrt(r.sigma2));
    for (int k = 0; k < CYL_INTR_COUNT; k++)
        std::printf("  %-3s %14.8g  +- %.6g\n", pn[k], r.intr[k], r.sigma[k]);
    if (!a.quiet) {
        std::printf("per-view RMS (px):\n");
        for (size_t i = 0; i < views.size(); i++)
            std::printf("  %-50s %.4f%s\n", names[i].c_str(), r.view_rms[i],
                        r.view_rms[i] > a.io.outlier_factor * r.rms ? "  <- outlier" : "");
    }
    for (int i : r.outliers)
        warn(names[i] + ": view RMS " + std::to_string(r.view_rms[i]) + " px is more than " +
             std::to_string(a.io.outlier_factor) + "x the overall " + std::to_string(r.rms) +
             " px: check the detection (blur, a mis-ordered board) or drop the image");
    cyl_camera cam = r.camera();
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "\n%zu views, N = %d corners, p = %d, RMS %.5f px, sigma_px %.5f px\n"
                  "intrinsic_covariance = (J^T J)^-1 SSE/(2N - p) (docs/calibration.md); no mount fields: "
                  "add them with cyl-calibrate mount",
                  views.size(), r.n_points, r.n_params, r.rms, std::sqrt(r.sigma2));
    std::string comment = "written by: " + cmdline + buf;
    if (!a.out.empty()) save_opencv_yaml(a.out, cam, comment, false);
    if (!a.ros.empty()) save_ros_yaml(a.ros, cam, a.camera_name, comment, false);
    if (!a.quiet)
        std::fprintf(stderr, "wrote %s%s%s\n", a.out.c_str(), a.out.empty() || a.ros.empty() ? "" : " and ",
                     a.ros.c_str());
    return kExitOk;
}

int run_mount(const Args &a, const std::string &cmdline)
{
    CameraCalibration cal = load_camera_calibration(a.camera);
    cyl_camera cam = cal.cam;
    cv::Size size;
    std::vector<View> views = detect(a, size);
    if (cam.width && cam.height && (size.width != (int)cam.width || size.height != (int)cam.height))
        throw Error("the images are " + std::to_string(size.width) + "x" + std::to_string(size.height) + " but " +
                    a.camera + " is calibrated for " + std::to_string(cam.width) + "x" + std::to_string(cam.height));
    if (views.empty()) throw Error("no image has a usable chessboard");
    std::vector<MountEstimate> es;
    es.reserve(views.size());
    for (auto &v : views) es.push_back(estimate_mount(cam, a.board, a.place, v.corners, v.name));
    MountSummary s = summarise_mount(es);
    std::printf("%-40s %9s %9s %9s %9s %9s %9s %7s\n", "image", "h_floor/m", "tilt/deg", "yaw/deg", "roll/deg",
                "s/m", "lat/m", "rms/px");
    for (auto &e : es)
        std::printf("%-40s %9.5f %9.4f %9.4f %9.4f %9.5f %9.5f %7.3f\n", e.name.c_str(), e.height_floor_m,
                    e.tilt_rad / kDeg, e.yaw_rad / kDeg, e.roll_rad / kDeg, e.offset_m, e.lateral_m, e.rms_px);
    const double sc[6] = {1, 1 / kDeg, 1 / kDeg, 1 / kDeg, 1, 1};
    const char *nm[6] = {"height above floor (m)", "tilt (deg)", "yaw (deg)", "roll (deg, reported only)",
                         "offset s (m)", "lateral (m)"};
    std::printf("over %d start-ups: mean, spread (std over start-ups), within (per-image estimation sigma)\n", s.n);
    for (int i = 0; i < 6; i++)
        std::printf("  %-26s %11.6f  spread %.3g  within %.3g\n", nm[i], s.mean[i] * sc[i], s.spread[i] * sc[i],
                    s.within[i] * sc[i]);
    const double *sig = s.spread;
    if (s.n < 2) {
        warn("one image only: the sigmas are that image's estimation sigmas, not the start-up spread (paper Table 5 "
             "repeats over 10 start-ups)");
        sig = s.within;
    }
    cam.height_m = s.mean[0] - a.centroid;
    cam.height_sigma_m = sig[0];
    cam.tilt_rad = s.mean[1];
    cam.tilt_sigma_rad = sig[1];
    if (a.yaw_zero) {
        double q = 0;
        for (auto &e : es) q += e.yaw_rad * e.yaw_rad;
        cam.yaw_rad = 0;
        cam.yaw_sigma_rad = std::sqrt(q / es.size());
    } else {
        cam.yaw_rad = s.mean[2];
        cam.yaw_sigma_rad = sig[2];
    }
    cam.offset_m = std::isnan(a.offset) ? s.mean[4] : a.offset;
    cam.offset_sigma_m = std::isnan(a.offset_sigma) ? sig[4] : a.offset_sigma;
    cam.flags &= ~CYL_CAM_EXTR_SIG_UNKNOWN;
    if (!(cam.height_m > 0))
        throw Error("the optical centre is not above the landmarks' centroid plane (h = " + std::to_string(cam.height_m) +
                    " m): check --landmark-height / --centroid-height");
    if (std::fabs(s.mean[3]) > 2 * kDeg)
        warn("camera roll " + std::to_string(s.mean[3] / kDeg) + " deg: libcyl's model has no roll; level the camera");
    cyl_status st = cyl_camera_check(&cam);
    if (st != CYL_OK) throw Error("the resulting camera is invalid: " + std::string(cyl_status_str(st)));
    std::printf("libcyl mount: h = %.5f m (floor %.5f - centroid %.5f) +- %.3g, tilt %.4f +- %.3g deg, yaw %.4f +- %.3g "
                "deg, s %.4f +- %.3g m\n",
                cam.height_m, s.mean[0], a.centroid, cam.height_sigma_m, cam.tilt_rad / kDeg, cam.tilt_sigma_rad / kDeg,
                cam.yaw_rad / kDeg, cam.yaw_sigma_rad / kDeg, cam.offset_m, cam.offset_sigma_m);
    char buf[768];
    std::snprintf(buf, sizeof buf,
                  "\nintrinsics from %s; mount from %d start-up image(s): mean, sigma = %s;\n"
                  "mount_height_m is above the landmarks' centroid plane (floor height %.5f m - %.5f m)",
                  a.camera.c_str(), s.n, s.n > 1 ? "std over start-ups" : "one image's estimation sigma",
                  s.mean[0], a.centroid);
    std::string comment = "written by: " + cmdline + buf;
    if (!a.out.empty()) save_opencv_yaml(a.out, cam, comment);
    if (!a.ros.empty()) save_ros_yaml(a.ros, cam, a.camera_name, comment);
    return kExitOk;
}

} // namespace

int main(int argc, char **argv)
{
    if (cylfe::print_version_if_asked(argc, argv, "cyl-calibrate")) return 0;
    Args a;
    try {
        a = parse(argc, argv);
    } catch (const Usage &e) {
        std::fprintf(stderr, "cyl-calibrate: %s\n(cyl-calibrate --help for usage)\n", e.what());
        return kExitUsage;
    }
    if (a.cmd == "--help" || a.cmd == "-h") {
        std::fputs(kUsage, stdout);
        return kExitOk;
    }
    try {
        return a.cmd == "intrinsics" ? run_intrinsics(a, join_args(argc, argv, a)) : run_mount(a, join_args(argc, argv, a));
    } catch (const std::exception &e) {  // cylfe::Error included
        std::fprintf(stderr, "cyl-calibrate: error: %s\n", e.what());
        return kExitFailure;
    }
}
