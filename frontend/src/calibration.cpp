// SPDX-License-Identifier: BSD-3-Clause
// cylfe: camera calibration files (see calibration.hpp).
#include "cylfe/calibration.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <cmath>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <vector>
#include <unistd.h>

#include <opencv2/core.hpp>
#include <yaml-cpp/yaml.h>

#include "cylfe/error.hpp"
#include "cylfe/keys.hpp"
#include "cylfe/output_file.hpp"

extern "C" {
#include "cyl/image.h"
}

namespace cylfe {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

struct Ctx {
    const std::string &path;
    [[noreturn]] void fail(const std::string &field, const std::string &what) const
    {
        throw Error(path + ": field '" + field + "': " + what);
    }
};

// Files are parsed with yaml-cpp, not cv::FileStorage: OpenCV 4.6's parser loops forever on
// some malformed files (found by fuzzing, tests/fuzz/known/). Nodes are only read through const
// references, so lookups never insert.
using Node = YAML::Node;

bool present(const Node &n) { return n.IsDefined() && !n.IsNull(); }

double number(const Ctx &c, const Node &n, const std::string &field)
{
    if (!n.IsScalar()) c.fail(field, "expected a number");
    double v = 0;
    if (!YAML::convert<double>::decode(n, v)) c.fail(field, "expected a number, got '" + n.Scalar() + "'");
    return v;
}

// A matrix node: !!opencv-matrix {rows, cols, dt, data}, a ROS {rows, cols, data} map, or a plain
// sequence. Returns the values row-major; checks the element count against rows*cols when given
// (> 0), and a declared size against it before reading the data.
std::vector<double> read_matrix(const Ctx &c, const Node &n, const std::string &field, int rows, int cols)
{
    std::vector<double> v;
    if (!present(n)) c.fail(field, "missing");
    const Node d = n.IsMap() ? n["data"] : n;
    if (n.IsMap()) {
        const Node nr = n["rows"], nc = n["cols"];
        if (present(nr) || present(nc)) {
            double dr = number(c, nr, field + ".rows"), dc = number(c, nc, field + ".cols");
            long long want = rows > 0 ? (long long)rows * cols : 1024;
            if (!(dr >= 1 && dc >= 1 && dr * dc <= (double)want) || dr != std::floor(dr) || dc != std::floor(dc))
                c.fail(field, "declared size " + nr.Scalar() + "x" + nc.Scalar() + " out of range");
        }
    }
    if (!d.IsSequence()) c.fail(field, "expected a matrix (opencv-matrix, {rows, cols, data} or a list)");
    if (d.size() > 1024) c.fail(field, "too many values");
    for (const Node &e : d) v.push_back(number(c, e, field));
    if (rows > 0 && v.size() != size_t(rows) * size_t(cols))
        c.fail(field, "expected " + std::to_string(rows * cols) + " values, got " + std::to_string(v.size()));
    for (double x : v)
        if (!std::isfinite(x)) c.fail(field, "non-finite value");
    return v;
}

bool read_number(const Ctx &c, const Node &root, const std::string &field, double *out, bool required)
{
    const Node n = root[field];
    if (!present(n)) {
        if (required) c.fail(field, "missing");
        return false;
    }
    *out = number(c, n, field);
    if (!std::isfinite(*out)) c.fail(field, "non-finite value");
    return true;
}

// yaml-cpp recurses per nesting level: refuse inputs that could nest deeply before parsing.
void check_shape(const std::string &path, const std::string &text)
{
    if (text.size() > (1u << 20)) throw Error(path + ": not a calibration file: larger than 1 MiB");
    int depth = 0, max_depth = 0;
    for (char ch : text) {
        if (ch == '[' || ch == '{') max_depth = std::max(max_depth, ++depth);
        else if ((ch == ']' || ch == '}') && depth > 0) depth--;
    }
    if (max_depth > 16) throw Error(path + ": not a calibration file: nested more than 16 levels");
}

// Top-level keys of a calibration file. Used: what this loader reads. Accepted and not used: what
// OpenCV's calibration sample and ROS camera_info files also carry, so that such files load. Any
// other key is an error naming it and the nearest known key (a misspelled key must not silently
// become a default: "distortion_coeficients" would be zero distortion).
const char *const kUsedKeys[] = {"image_width", "image_height", "camera_matrix", "distortion_coefficients",
                                 "distortion_model", "intrinsic_covariance", "intrinsic_sigmas", "mount_tilt_deg",
                                 "mount_yaw_deg", "mount_height_m", "mount_offset_m", "mount_tilt_sigma_deg",
                                 "mount_yaw_sigma_deg", "mount_height_sigma_m", "mount_offset_sigma_m"};
const char *const kIgnoredKeys[] = {
    "camera_name", "rectification_matrix", "projection_matrix",                         // ROS camera_info
    "calibration_time", "nframes", "nr_of_frames", "board_width", "board_height", "square_size",
    "aspectRatio", "fix_aspect_ratio", "flags", "fisheye_model", "avg_reprojection_error",
    "per_view_reprojection_errors", "extrinsic_parameters", "image_points", "grid_points"};  // OpenCV sample

// Duplicate keys are errors (YAML says a mapping's keys are unique; yaml-cpp keeps the first);
// unknown keys are errors, or warnings when lenient.
void check_keys(const Ctx &c, const Node &root, int line_offset, bool lenient, std::vector<std::string> *warnings)
{
    std::map<std::string, int> seen;
    std::vector<std::string> all(std::begin(kUsedKeys), std::end(kUsedKeys));
    all.insert(all.end(), std::begin(kIgnoredKeys), std::end(kIgnoredKeys));
    for (auto it = root.begin(); it != root.end(); ++it) {
        if (!it->first.IsScalar()) c.fail("(top level)", "a key that is not a plain name");
        const std::string k = it->first.Scalar();
        const int line = it->first.Mark().line + 1 + line_offset;
        auto s = seen.find(k);
        if (s != seen.end())
            c.fail(k, "given twice (lines " + std::to_string(s->second) + " and " + std::to_string(line) + ")");
        seen[k] = line;
        bool known = std::find(all.begin(), all.end(), k) != all.end();
        if (known) continue;
        std::string msg = c.path + ":" + std::to_string(line) + ": unknown key '" + k + "'" + did_you_mean(k, all);
        if (!lenient) throw Error(msg + "; --lenient reads the file anyway");
        if (warnings) warnings->push_back(msg + ": ignored (--lenient)");
    }
}

} // namespace

static CameraCalibration load_unchecked(const std::string &path, bool lenient)
{
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error(path + ": cannot open camera calibration file");
    std::stringstream ss;
    ss << f.rdbuf();
    std::string text = ss.str();
    CameraCalibration cal;
    cal.path = path;
    cal.format = text.rfind("%YAML", 0) == 0 ? "opencv" : "ros";
    // OpenCV writes a non-standard "%YAML:1.0" directive: drop that line, keep the rest.
    if (cal.format == "opencv") {
        size_t eol = text.find('\n');
        text = eol == std::string::npos ? std::string() : text.substr(eol + 1);
    }
    check_shape(path, text);
    Node root;
    try {
        root = YAML::Load(text);
    } catch (const YAML::Exception &e) {
        throw Error(path + ": not a readable YAML calibration file: " + e.what());
    }
    Ctx c{path};
    if (!root.IsMap()) throw Error(path + ": not a calibration file: the top level is not a mapping of fields");
    check_keys(c, root, cal.format == "opencv" ? 1 : 0, lenient, &cal.warnings);
    cyl_camera &cam = cal.cam;
    cyl_camera_init(&cam);
    cam.height_m = 0.0;

    double w = 0, h = 0;
    read_number(c, root, "image_width", &w, true);
    read_number(c, root, "image_height", &h, true);
    if (w < 1 || h < 1 || w != std::floor(w) || h != std::floor(h)) c.fail("image_width/image_height", "not positive integers");
    if (w > CYL_MAX_DIM || h > CYL_MAX_DIM)
        c.fail("image_width/image_height", "larger than libcyl's limit of " + std::to_string(CYL_MAX_DIM) + " px");
    cam.width = (uint32_t)w;
    cam.height = (uint32_t)h;

    std::vector<double> K = read_matrix(c, root["camera_matrix"], "camera_matrix", 3, 3);
    if (K[1] != 0.0) c.fail("camera_matrix", "skew is not supported (K[0][1] must be 0)");
    if (K[3] != 0.0 || K[6] != 0.0 || K[7] != 0.0 || K[8] != 1.0) c.fail("camera_matrix", "last row must be 0 0 1 and K[1][0] 0");
    cam.fx_px = K[0];
    cam.cx_px = K[2];
    cam.fy_px = K[4];
    cam.cy_px = K[5];
    if (!(cam.fx_px > 0) || !(cam.fy_px > 0)) c.fail("camera_matrix", "focal lengths must be positive");

    if (cal.format == "ros") {
        const Node m = root["distortion_model"];
        std::string model = present(m) && m.IsScalar() ? m.Scalar() : std::string("plumb_bob");
        if (model != "plumb_bob" && model != "rational_polynomial")
            c.fail("distortion_model", "'" + model + "' is not supported (plumb_bob or rational_polynomial)");
    }
    const Node dn = root["distortion_coefficients"];
    if (present(dn)) {
        std::vector<double> D = read_matrix(c, dn, "distortion_coefficients", 0, 0);
        if (D.size() < 4) c.fail("distortion_coefficients", "expected at least 4 values (k1 k2 p1 p2 [k3])");
        for (size_t i = 5; i < D.size(); i++)
            if (D[i] != 0.0) c.fail("distortion_coefficients", "terms beyond k3 (rational/thin prism) are not supported");
        cam.k1 = D[0]; cam.k2 = D[1]; cam.p1 = D[2]; cam.p2 = D[3];
        cam.k3 = D.size() > 4 ? D[4] : 0.0;
    }

    // uncertainty of the intrinsics
    const Node cn = root["intrinsic_covariance"], sn = root["intrinsic_sigmas"];
    if (present(cn)) {
        std::vector<double> C = read_matrix(c, cn, "intrinsic_covariance", CYL_INTR_COUNT, CYL_INTR_COUNT);
        for (int i = 0; i < CYL_INTR_COUNT; i++)
            for (int j = 0; j < CYL_INTR_COUNT; j++) cam.intr_cov[i][j] = C[i * CYL_INTR_COUNT + j];
        cam.flags &= ~CYL_CAM_INTR_COV_UNKNOWN;
        cal.intrinsic_cov_known = true;
    } else if (present(sn)) {
        std::vector<double> S = read_matrix(c, sn, "intrinsic_sigmas", 0, 0);
        if (S.size() != 4 && S.size() != CYL_INTR_COUNT)
            c.fail("intrinsic_sigmas", "expected 4 (fx fy cx cy) or 9 (+ k1 k2 p1 p2 k3) values");
        double s9[CYL_INTR_COUNT] = {0};
        for (size_t i = 0; i < S.size(); i++) {
            if (S[i] < 0) c.fail("intrinsic_sigmas", "negative standard deviation");
            s9[i] = S[i];
        }
        cyl_camera_set_intrinsic_sigmas(&cam, s9);
        cal.intrinsic_cov_known = true;
    }

    // mounting
    double tilt = 0, yaw = 0, hm = 0, s = 0;
    int nv = read_number(c, root, "mount_tilt_deg", &tilt, false) + read_number(c, root, "mount_yaw_deg", &yaw, false) +
             read_number(c, root, "mount_height_m", &hm, false) + read_number(c, root, "mount_offset_m", &s, false);
    if (nv != 0 && nv != 4)
        c.fail("mount_*", "give all of mount_tilt_deg, mount_yaw_deg, mount_height_m, mount_offset_m or none");
    if (nv == 4) {
        if (!(hm > 0)) c.fail("mount_height_m", "must be positive");
        cam.tilt_rad = tilt * kDeg;
        cam.yaw_rad = yaw * kDeg;
        cam.height_m = hm;
        cam.offset_m = s;
        cal.mount_known = true;
    }
    double st = 0, sy = 0, sh = 0, so = 0;
    int ns = read_number(c, root, "mount_tilt_sigma_deg", &st, false) + read_number(c, root, "mount_yaw_sigma_deg", &sy, false) +
             read_number(c, root, "mount_height_sigma_m", &sh, false) + read_number(c, root, "mount_offset_sigma_m", &so, false);
    if (ns != 0 && ns != 4)
        c.fail("mount_*_sigma_*", "give all four mount sigmas or none");
    if (ns == 4) {
        if (st < 0 || sy < 0 || sh < 0 || so < 0) c.fail("mount_*_sigma_*", "negative standard deviation");
        cam.tilt_sigma_rad = st * kDeg;
        cam.yaw_sigma_rad = sy * kDeg;
        cam.height_sigma_m = sh;
        cam.offset_sigma_m = so;
        cam.flags &= ~CYL_CAM_EXTR_SIG_UNKNOWN;
        cal.mount_sigmas_known = true;
    }
    // validate what the C core will see (a placeholder height when the mount is unknown)
    cyl_camera chk = cam;
    if (!cal.mount_known) chk.height_m = 1.0;
    cyl_status ok = cyl_camera_check(&chk);
    if (ok != CYL_OK) throw Error(path + ": invalid camera: " + cyl_status_str(ok));
    return cal;
}

CameraCalibration load_camera_calibration(const std::string &path, bool lenient)
{
    try {
        return load_unchecked(path, lenient);
    } catch (const Error &) {
        throw;
    } catch (const std::exception &e) {
        // Anything a parser or a conversion still throws on malformed input (found by fuzzing):
        // an error naming the file.
        throw Error(path + ": unreadable calibration file: " + e.what());
    }
}

CameraCalibration load_mounted_camera_calibration(const std::string &path, bool lenient)
{
    CameraCalibration cal = load_camera_calibration(path, lenient);
    if (!cal.mount_known)
        throw Error(path + ": no mount fields (mount_tilt_deg, mount_height_m, ...): range and bearing need the "
                           "camera's mounting");
    return cal;
}

void write_file_atomic(const std::string &path, const std::string &text)
{
    OutputPlan plan = plan_output(path, ".tmp." + std::to_string(getpid()));
    FILE *f = std::fopen(plan.write_to.c_str(), "wb");
    if (!f) throw Error(path + ": cannot write: " + std::strerror(errno));
    bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
    ok = (std::fflush(f) == 0) && ok;
    ok = (std::fclose(f) == 0) && ok;
    if (!ok) {
        int e = errno;
        if (plan.staged) std::remove(plan.write_to.c_str());
        throw Error(path + ": cannot write: " + std::strerror(e));
    }
    try {
        finish_output(plan);
    } catch (...) {
        std::remove(plan.write_to.c_str());
        throw;
    }
}

void save_camera_calibration(const std::string &path, const cyl_camera &cam, bool with_mount,
                             const std::string &comment)
{
    cv::FileStorage fs(".yml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
    fs << "image_width" << (int)cam.width << "image_height" << (int)cam.height;
    cv::Mat K = (cv::Mat_<double>(3, 3) << cam.fx_px, 0, cam.cx_px, 0, cam.fy_px, cam.cy_px, 0, 0, 1);
    cv::Mat D = (cv::Mat_<double>(1, 5) << cam.k1, cam.k2, cam.p1, cam.p2, cam.k3);
    fs << "camera_matrix" << K << "distortion_coefficients" << D;
    if (!(cam.flags & CYL_CAM_INTR_COV_UNKNOWN)) {
        cv::Mat C(CYL_INTR_COUNT, CYL_INTR_COUNT, CV_64F);
        for (int i = 0; i < CYL_INTR_COUNT; i++)
            for (int j = 0; j < CYL_INTR_COUNT; j++) C.at<double>(i, j) = cam.intr_cov[i][j];
        fs << "intrinsic_covariance" << C;
    }
    if (with_mount) {
        fs << "mount_tilt_deg" << cam.tilt_rad / kDeg << "mount_yaw_deg" << cam.yaw_rad / kDeg
           << "mount_height_m" << cam.height_m << "mount_offset_m" << cam.offset_m;
        fs << "mount_tilt_sigma_deg" << cam.tilt_sigma_rad / kDeg << "mount_yaw_sigma_deg"
           << cam.yaw_sigma_rad / kDeg << "mount_height_sigma_m" << cam.height_sigma_m << "mount_offset_sigma_m"
           << cam.offset_sigma_m;
    }
    std::string text = fs.releaseAndGetString(), lines;
    std::istringstream is(comment);
    for (std::string line; std::getline(is, line);) lines += "# " + line + "\n";
    size_t pos = text.find("---\n");
    if (pos != std::string::npos) text.insert(pos + 4, lines);
    write_file_atomic(path, text);
}

} // namespace cylfe
