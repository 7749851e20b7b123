// SPDX-License-Identifier: BSD-3-Clause
// cylfe::calib -- files: atomic writes, the calibration YAML writers, colour tables, frames.
#include "cylfe/calib.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <unistd.h>

#include "cylfe/calibration.hpp"
#include "cylfe/error.hpp"
#include "cylfe/rawlog.hpp"
#include "cylfe/sources.hpp"

namespace cylfe {
namespace calib {

namespace {
constexpr double kDeg = 3.14159265358979323846 / 180.0;


std::string read_all(const std::string &path)
{
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error(path + ": cannot open: " + std::strerror(errno));
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

std::string commented(const std::string &comment)
{
    std::string out;
    std::istringstream is(comment);
    std::string line;
    while (std::getline(is, line)) out += "# " + line + "\n";
    return out;
}

std::string num(double v)
{
    char b[64];
    std::snprintf(b, sizeof b, "%.12g", v);
    std::string s(b);
    if (s.find_first_of(".eEn") == std::string::npos) s += ".";  // keep it a YAML float
    return s;
}

std::string ros_matrix(const std::string &name, int rows, int cols, const double *d)
{
    std::string s = name + ":\n  rows: " + std::to_string(rows) + "\n  cols: " + std::to_string(cols) + "\n  data: [";
    for (int i = 0; i < rows * cols; i++) s += (i ? ", " : "") + num(d[i]);
    return s + "]\n";
}
} // namespace

void save_opencv_yaml(const std::string &path, const cyl_camera &cam, const std::string &comment, bool with_mount)
{
    save_camera_calibration(path, cam, with_mount, comment);
}

std::string ros_yaml(const cyl_camera &cam, const std::string &camera_name, const std::string &comment,
                     bool with_mount)
{
    std::string s = commented(comment);
    s += "image_width: " + std::to_string(cam.width) + "\n";
    s += "image_height: " + std::to_string(cam.height) + "\n";
    s += "camera_name: " + (camera_name.empty() ? std::string("camera") : camera_name) + "\n";
    double K[9] = {cam.fx_px, 0, cam.cx_px, 0, cam.fy_px, cam.cy_px, 0, 0, 1};
    s += ros_matrix("camera_matrix", 3, 3, K);
    s += "distortion_model: plumb_bob\n";
    double D[5] = {cam.k1, cam.k2, cam.p1, cam.p2, cam.k3};
    s += ros_matrix("distortion_coefficients", 1, 5, D);
    double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    s += ros_matrix("rectification_matrix", 3, 3, R);
    double P[12] = {cam.fx_px, 0, cam.cx_px, 0, 0, cam.fy_px, cam.cy_px, 0, 0, 0, 1, 0};
    s += ros_matrix("projection_matrix", 3, 4, P);
    if (!(cam.flags & CYL_CAM_INTR_COV_UNKNOWN)) {
        s += "# libcyl: covariance of (fx fy cx cy k1 k2 p1 p2 k3), px^2 / px / 1 (docs/calibration.md)\n";
        double C[CYL_INTR_COUNT * CYL_INTR_COUNT];
        for (int i = 0; i < CYL_INTR_COUNT; i++)
            for (int j = 0; j < CYL_INTR_COUNT; j++) C[i * CYL_INTR_COUNT + j] = cam.intr_cov[i][j];
        s += ros_matrix("intrinsic_covariance", CYL_INTR_COUNT, CYL_INTR_COUNT, C);
    }
    if (!with_mount) return s;
    s += "# libcyl: mounting on the robot (h above the landmarks' centroid plane) and its sigmas\n";
    s += "mount_tilt_deg: " + num(cam.tilt_rad / kDeg) + "\n";
    s += "mount_yaw_deg: " + num(cam.yaw_rad / kDeg) + "\n";
    s += "mount_height_m: " + num(cam.height_m) + "\n";
    s += "mount_offset_m: " + num(cam.offset_m) + "\n";
    s += "mount_tilt_sigma_deg: " + num(cam.tilt_sigma_rad / kDeg) + "\n";
    s += "mount_yaw_sigma_deg: " + num(cam.yaw_sigma_rad / kDeg) + "\n";
    s += "mount_height_sigma_m: " + num(cam.height_sigma_m) + "\n";
    s += "mount_offset_sigma_m: " + num(cam.offset_sigma_m) + "\n";
    return s;
}

void save_ros_yaml(const std::string &path, const cyl_camera &cam, const std::string &camera_name,
                   const std::string &comment, bool with_mount)
{
    write_file_atomic(path, ros_yaml(cam, camera_name, comment, with_mount));
}

void load_table(const std::string &path, cyl_colortable &t)
{
    std::string b = read_all(path);
    cyl_status s = cyl_colortable_load(&t, reinterpret_cast<const uint8_t *>(b.data()), b.size());
    if (s != CYL_OK) throw Error(path + ": not a valid colour table (CYLT): " + cyl_status_str(s));
}

void save_table(const std::string &path, const cyl_colortable &t)
{
    std::string b(CYL_TABLE_FILE_MAX_SIZE, '\0');
    size_t n = 0;
    check(cyl_colortable_save(&t, reinterpret_cast<uint8_t *>(&b[0]), b.size(), &n), path + ": serialising the table");
    b.resize(n);
    write_file_atomic(path, b);
}

Frame load_frame(const std::string &path, long index)
{
    Frame fr;
    auto ends = [&](const char *s) {
        size_t n = std::strlen(s);
        return path.size() >= n && path.compare(path.size() - n, n, s) == 0;
    };
    std::unique_ptr<Source> src;
    if (ends(".cylraw"))
        src.reset(new RawLogSource(path, false));
    else {
        if (index != 0) throw Error(path + ": --frame applies to raw logs (.cylraw) only");
        if (access(path.c_str(), R_OK) != 0) throw Error(path + ": cannot open image: " + std::strerror(errno));
        src.reset(new FileSource({path}));
    }
    SourceEvent ev;
    long k = 0;
    for (;;) {
        if (!src->next(ev))
            throw Error(path + ": no frame " + std::to_string(index) + " (the file has " + std::to_string(k) + ")");
        if (ev.kind != RecordType::Frame) continue;
        if (k++ == index) break;
    }
    const StreamInfo &in = src->info();
    size_t n = cyl_image_buffer_size(ev.image.format, ev.image.width, ev.image.height,
                                     in.stride);
    if (n == 0 || n > ev.header.size) throw Error(path + ": frame " + std::to_string(index) + " is truncated");
    fr.data.assign(ev.data, ev.data + n);
    check(cyl_image_wrap(&fr.img, ev.image.format, ev.image.width, ev.image.height, fr.data.data(),
                         in.stride),
          path + ": frame");
    fr.label = path + (ends(".cylraw") ? "#" + std::to_string(index) : "");
    return fr;
}

} // namespace calib
} // namespace cylfe
