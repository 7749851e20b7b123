// SPDX-License-Identifier: BSD-3-Clause
// Scenes: the built-in default, scene files (cv::FileStorage YAML/JSON), the libcyl camera.
#include "cylfe/synth.hpp"
#include "cylfe/error.hpp"
#include "cylfe/keys.hpp"

#include <opencv2/core.hpp>

#include <algorithm>
#include <cerrno>
#include <map>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace cylfe {
namespace synth {

namespace {
constexpr double kDeg = 3.14159265358979323846 / 180.0;
const Yuv kOrange{137, 68, 194};   // BT.601 of RGB (230, 110, 30)
const Yuv kGreen{114, 103, 75};    // BT.601 of RGB (40, 160, 70)
const Yuv kNeutral{96, 131, 125};  // dark blue-grey occluders
// multiband_scene's further classes and the cones' stripe (BT.601: Y = .299 R + .587 G + .114 B,
// U = 128 + .564 (B - Y), V = 128 + .713 (R - Y))
const Yuv kBlue{79, 196, 93};      // RGB (30, 80, 200)
const Yuv kPink{118, 174, 201};    // RGB (220, 50, 200)
const Yuv kWhite{200, 128, 128};   // the cones' unclassified stripe
} // namespace

Scene empty_scene()
{
    Scene s;
    s.name = "empty";
    return s;
}

Scene default_scene()
{
    Scene s;
    s.name = "default";
    struct L { double x, y; int cls; };
    const L lms[] = {
        {-3.6, 2.4, 0}, {0.0, 2.5, 0}, {3.7, 2.2, 0}, {-3.9, -0.6, 0}, {1.4, 0.0, 0}, {2.0, -2.6, 0}, {-1.6, -2.7, 0},
        {-1.8, 2.6, 1}, {1.9, 2.7, 1}, {3.9, 0.4, 1}, {-1.4, 0.1, 1}, {3.4, -2.5, 1}, {0.1, -2.6, 1}, {-3.6, -2.6, 1},
    };
    uint32_t id = 0;
    for (const L &l : lms) {
        Cylinder c;
        c.id = id++;
        c.cls = l.cls;
        c.landmark = true;
        c.x_m = l.x;
        c.y_m = l.y;
        c.diameter_m = s.landmark_diameter_m;
        c.height_m = s.landmark_height_m;
        c.colour = l.cls == 0 ? kOrange : kGreen;
        s.cylinders.push_back(c);
    }
    // Clutter in landmark colours, wrong size or shape.
    Cylinder pole;
    pole.landmark = false;
    pole.diameter_m = 0.03;
    pole.height_m = 1.2;
    pole.id = 100; pole.cls = 1; pole.x_m = -2.5; pole.y_m = 3.0; pole.colour = kGreen; s.cylinders.push_back(pole);
    pole.id = 101; pole.cls = 0; pole.x_m = 4.1; pole.y_m = 1.3; pole.colour = kOrange; s.cylinders.push_back(pole);
    Box flat;  // a flat orange box lying on the floor
    flat.cls = 0; flat.x_m = -0.7; flat.y_m = 2.0; flat.yaw_rad = 20 * kDeg;
    flat.size_x_m = 0.5; flat.size_y_m = 0.35; flat.size_z_m = 0.06; flat.colour = kOrange;
    s.boxes.push_back(flat);
    Box tall;  // a wide, tall green cabinet
    tall.cls = 1; tall.x_m = 1.0; tall.y_m = -3.15; tall.yaw_rad = 0;
    tall.size_x_m = 0.6; tall.size_y_m = 0.4; tall.size_z_m = 0.9; tall.colour = kGreen;
    s.boxes.push_back(tall);
    // Neutral occluders.
    Box occ;
    occ.cls = -1; occ.size_x_m = 0.35; occ.size_y_m = 0.35; occ.size_z_m = 0.6; occ.colour = kNeutral;
    occ.x_m = -2.9; occ.y_m = 1.9; occ.yaw_rad = 10 * kDeg; s.boxes.push_back(occ);
    occ.x_m = 2.9; occ.y_m = -1.9; occ.yaw_rad = -25 * kDeg; s.boxes.push_back(occ);
    FloorPatch mat;
    mat.cls = 0; mat.x_m = 3.8; mat.y_m = -1.3; mat.yaw_rad = 30 * kDeg; mat.size_x_m = 0.6; mat.size_y_m = 0.4;
    mat.colour = kOrange; s.patches.push_back(mat);
    mat.cls = 1; mat.x_m = -3.0; mat.y_m = 1.0; mat.yaw_rad = -10 * kDeg; mat.size_x_m = 0.5; mat.size_y_m = 0.5;
    mat.colour = kGreen; s.patches.push_back(mat);
    return s;
}

cyl_camera to_cyl_camera(const CameraModel &c, const CameraSigmas &sg, double landmark_height_m)
{
    cyl_camera cam;
    cyl_camera_init(&cam);
    cam.width = c.width;
    cam.height = c.height;
    cam.fx_px = c.fx; cam.fy_px = c.fy; cam.cx_px = c.cx; cam.cy_px = c.cy;
    cam.k1 = c.k1; cam.k2 = c.k2; cam.p1 = c.p1; cam.p2 = c.p2; cam.k3 = c.k3;
    double sig[CYL_INTR_COUNT] = {sg.fx, sg.fy, sg.cx, sg.cy, sg.k1, sg.k2, sg.p1, sg.p2, sg.k3};
    cyl_camera_set_intrinsic_sigmas(&cam, sig);
    cam.tilt_rad = c.tilt_rad;
    cam.yaw_rad = c.yaw_rad;
    cam.height_m = c.height_floor_m - landmark_height_m / 2;
    cam.offset_m = c.offset_m;
    cam.tilt_sigma_rad = sg.tilt_rad;
    cam.yaw_sigma_rad = sg.yaw_rad;
    cam.height_sigma_m = sg.height_m;
    cam.offset_sigma_m = sg.offset_m;
    cam.flags &= ~(uint32_t)(CYL_CAM_INTR_COV_UNKNOWN | CYL_CAM_EXTR_SIG_UNKNOWN);
    return cam;
}

CameraModel perturb_camera(const CameraModel &c, const CameraSigmas &sg, uint64_t seed)
{
    uint64_t st = mix_seed(seed, 0xCA1Bu, 0);
    auto normal = [&st]() {
        auto next = [&st]() {
            uint64_t z = (st += 0x9E3779B97F4A7C15ull);
            z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
            z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
            return (((z ^ (z >> 31)) >> 11) + 0.5) * (1.0 / 9007199254740992.0);
        };
        double u1 = next(), u2 = next();
        return std::sqrt(-2 * std::log(u1)) * std::cos(2 * 3.14159265358979323846 * u2);
    };
    CameraModel e = c;
    e.fx += sg.fx * normal(); e.fy += sg.fy * normal(); e.cx += sg.cx * normal(); e.cy += sg.cy * normal();
    e.k1 += sg.k1 * normal(); e.k2 += sg.k2 * normal(); e.p1 += sg.p1 * normal(); e.p2 += sg.p2 * normal();
    e.k3 += sg.k3 * normal();
    e.tilt_rad += sg.tilt_rad * normal(); e.yaw_rad += sg.yaw_rad * normal();
    e.height_floor_m += sg.height_m * normal(); e.offset_m += sg.offset_m * normal();
    return e;
}

cyl_camera to_cyl_camera(const Scene &s) { return to_cyl_camera(s.camera, s.sigmas, s.landmark_height_m); }

// ---- scene files ------------------------------------------------------------------------

namespace {

// Reads scene-file fields and remembers, for every mapping it reads from, which keys it asked for;
// check_unknown() then finds the keys of those mappings that nothing asked for (misspellings):
// errors naming the mapping and the nearest key it knows.
struct Reader {
    std::string path;
    struct Asked {
        cv::FileNode node;
        std::string where;
        std::vector<std::string> keys;
    };
    std::map<std::pair<size_t, size_t>, Asked> asked;   // by the node's (block, offset) in the file

    cv::FileNode get(const cv::FileNode &n, const char *key)
    {
        Asked &a = asked[{n.blockIdx, n.ofs}];
        if (a.where.empty()) { a.node = n; a.where = "?"; }
        a.keys.emplace_back(key);
        return n[key];
    }
    void section(const cv::FileNode &n, const std::string &where)
    {
        Asked &a = asked[{n.blockIdx, n.ofs}];
        a.node = n;
        a.where = where;
    }
    // a nested mapping, named by its key
    cv::FileNode sub(const cv::FileNode &n, const char *key)
    {
        cv::FileNode f = get(n, key);
        if (f.isMap()) section(f, key);
        return f;
    }
    void check_unknown() const
    {
        for (const auto &e : asked) {
            const Asked &a = e.second;
            if (!a.node.isMap()) continue;
            for (const std::string &k : a.node.keys())
                if (std::find(a.keys.begin(), a.keys.end(), k) == a.keys.end())
                    throw Error(path + ": " + a.where + ": unknown key '" + k + "'" + did_you_mean(k, a.keys));
        }
    }
    void num(const cv::FileNode &n, const char *key, double &v, double scale = 1.0)
    {
        cv::FileNode f = get(n, key);
        if (f.empty()) return;
        if (!f.isReal() && !f.isInt()) throw Error(path + ": field '" + key + "' must be a number");
        v = (double)f * scale;
    }
    void num(const cv::FileNode &n, const char *key, uint32_t &v)
    {
        cv::FileNode f = get(n, key);
        if (f.empty()) return;
        if (!f.isInt() || (int)f < 0) throw Error(path + ": field '" + key + "' must be a non-negative integer");
        v = (uint32_t)(int)f;
    }
    void str(const cv::FileNode &n, const char *key, std::string &v)
    {
        cv::FileNode f = get(n, key);
        if (f.empty()) return;
        if (!f.isString()) throw Error(path + ": field '" + key + "' must be a string");
        v = (std::string)f;
    }
    void yuv(const cv::FileNode &n, const char *key, Yuv &c)
    {
        cv::FileNode f = get(n, key);
        if (f.empty()) return;
        if (!f.isSeq() || f.size() != 3) throw Error(path + ": field '" + key + "' must be [Y, U, V]");
        c.y = (double)f[0]; c.u = (double)f[1]; c.v = (double)f[2];
    }
    int32_t cls(const cv::FileNode &n, const std::vector<std::string> &classes)
    {
        cv::FileNode f = get(n, "class");
        if (f.empty()) return -1;
        if (f.isInt()) return (int32_t)(int)f;
        std::string name = (std::string)f;
        if (name == "none" || name.empty()) return -1;
        for (size_t i = 0; i < classes.size(); i++)
            if (classes[i] == name) return (int32_t)i;
        throw Error(path + ": unknown class '" + name + "' (not in 'classes')");
    }
};

} // namespace

Scene load_scene(const std::string &path)
{
    {
        FILE *f = std::fopen(path.c_str(), "rb");
        if (!f) throw Error(path + ": cannot open scene file: " + std::strerror(errno));
        std::fclose(f);
    }
    cv::FileStorage fs;
    try {
        if (!fs.open(path, cv::FileStorage::READ)) throw Error(path + ": cannot open scene file");
    } catch (const cv::Exception &e) {
        throw Error(path + ": cannot parse scene file: " + e.what());
    }
    Reader r;
    r.path = path;
    Scene s = empty_scene();
    cv::FileNode root = fs.root();
    r.section(root, "(top level)");
    r.str(root, "name", s.name);
    const cv::FileNode classes = r.get(root, "classes");
    if (!classes.empty()) {
        s.classes.clear();
        for (const auto &it : classes) s.classes.push_back((std::string)it);
    }
    r.num(root, "landmark_diameter_m", s.landmark_diameter_m);
    r.num(root, "landmark_height_m", s.landmark_height_m);
    cv::FileNode n = r.sub(root, "room");
    if (!n.empty()) {
        r.num(n, "x_min", s.room.x_min); r.num(n, "x_max", s.room.x_max);
        r.num(n, "y_min", s.room.y_min); r.num(n, "y_max", s.room.y_max);
        r.num(n, "wall_height_m", s.room.wall_height_m); r.num(n, "floor_texture", s.room.floor_texture);
        r.yuv(n, "floor", s.room.floor); r.yuv(n, "wall", s.room.wall); r.yuv(n, "ceiling", s.room.ceiling);
    }
    n = r.sub(root, "camera");
    if (!n.empty()) {
        CameraModel &c = s.camera;
        r.num(n, "width", c.width); r.num(n, "height", c.height);
        r.num(n, "fx", c.fx); r.num(n, "fy", c.fy); r.num(n, "cx", c.cx); r.num(n, "cy", c.cy);
        r.num(n, "k1", c.k1); r.num(n, "k2", c.k2); r.num(n, "p1", c.p1); r.num(n, "p2", c.p2); r.num(n, "k3", c.k3);
        r.num(n, "tilt_deg", c.tilt_rad, kDeg); r.num(n, "yaw_deg", c.yaw_rad, kDeg);
        r.num(n, "height_floor_m", c.height_floor_m); r.num(n, "offset_m", c.offset_m);
    }
    n = r.sub(root, "sigmas");
    if (!n.empty()) {
        CameraSigmas &g = s.sigmas;
        r.num(n, "fx", g.fx); r.num(n, "fy", g.fy); r.num(n, "cx", g.cx); r.num(n, "cy", g.cy);
        r.num(n, "k1", g.k1); r.num(n, "k2", g.k2); r.num(n, "p1", g.p1); r.num(n, "p2", g.p2); r.num(n, "k3", g.k3);
        r.num(n, "tilt_deg", g.tilt_rad, kDeg); r.num(n, "yaw_deg", g.yaw_rad, kDeg);
        r.num(n, "height_m", g.height_m); r.num(n, "offset_m", g.offset_m);
    }
    n = r.sub(root, "imaging");
    if (!n.empty()) {
        Imaging &im = s.imaging;
        r.num(n, "samples", im.samples);
        r.num(n, "blur_sigma_px", im.blur_sigma_px); r.num(n, "chroma_blur_px", im.chroma_blur_px);
        r.num(n, "noise_y", im.noise_y); r.num(n, "noise_c", im.noise_c);
        r.num(n, "exposure", im.exposure); r.num(n, "exposure_jitter", im.exposure_jitter);
        r.num(n, "illum_amplitude", im.illum_amplitude); r.num(n, "illum_period_s", im.illum_period_s);
        r.num(n, "ambient", im.ambient); r.num(n, "diffuse", im.diffuse);
        r.num(n, "light_az_deg", im.light_az_rad, kDeg); r.num(n, "light_el_deg", im.light_el_rad, kDeg);
        r.num(n, "illum_gradient_per_m", im.illum_gradient_per_m);
        r.num(n, "wb_drift", im.wb_drift); r.num(n, "wb_period_s", im.wb_period_s);
        if (!(im.wb_period_s > 0)) throw Error(path + ": imaging.wb_period_s must be > 0");
    }
    n = r.sub(root, "trajectory");
    if (!n.empty()) {
        TrajectoryParams &t = s.trajectory;
        r.str(n, "type", t.type);
        if (t.type != "figure8" && t.type != "ellipse")
            throw Error(path + ": trajectory.type must be figure8 or ellipse");
        r.num(n, "centre_x_m", t.centre_x_m); r.num(n, "centre_y_m", t.centre_y_m);
        r.num(n, "a_m", t.a_m); r.num(n, "b_m", t.b_m); r.num(n, "speed_mps", t.speed_mps);
        r.num(n, "fps", t.fps); r.num(n, "phase0", t.phase0);
    }
    n = r.sub(root, "odometry");
    if (!n.empty()) {
        OdometryNoise &o = s.odometry;
        r.num(n, "k_long", o.k_long); r.num(n, "k_lat", o.k_lat); r.num(n, "k_rot", o.k_rot);
        r.num(n, "k_rot_d", o.k_rot_d); r.num(n, "min_xy", o.min_xy); r.num(n, "min_theta", o.min_theta);
    }
    uint32_t next_id = 0;
    size_t i_cylinders = 0;
    for (const auto &it : r.get(root, "cylinders")) {
        r.section(it, "cylinders[" + std::to_string(i_cylinders++) + "]");
        Cylinder c;
        c.diameter_m = s.landmark_diameter_m;
        c.height_m = s.landmark_height_m;
        double lm = 1, id = next_id;
        r.num(it, "id", id);
        r.num(it, "landmark", lm);
        c.id = (uint32_t)id;
        next_id = c.id + 1;
        c.landmark = lm != 0;
        c.cls = r.cls(it, s.classes);
        r.num(it, "x_m", c.x_m); r.num(it, "y_m", c.y_m);
        r.num(it, "diameter_m", c.diameter_m); r.num(it, "height_m", c.height_m);
        r.yuv(it, "colour", c.colour);
        if (c.diameter_m <= 0 || c.height_m <= 0) throw Error(path + ": cylinder with non-positive size");
        const std::string where = "cylinders[" + std::to_string(i_cylinders - 1) + "]";
        r.num(it, "diameter_top_m", c.diameter_top_m);
        if (std::isnan(c.diameter_top_m))
            throw Error(std::string(path).append(": ").append(where).append(".diameter_top_m must be a number (< 0: a cylinder)"));
        const cv::FileNode bands = r.get(it, "bands");
        if (!bands.empty()) {
            if (!bands.isSeq())
                throw Error(std::string(path).append(": ").append(where).append(".bands must be a sequence of bands {height_m, class, colour}, top to bottom"));
            size_t j = 0;
            double sum = 0;
            for (const auto &bn : bands) {
                const std::string bw = where + ".bands[" + std::to_string(j++) + "]";
                if (!bn.isMap()) throw Error(std::string(path).append(": ").append(bw).append(" must be a mapping {height_m, class, colour}"));
                r.section(bn, bw);
                Band b;
                if (bn["height_m"].empty()) throw Error(std::string(path).append(": ").append(bw).append(".height_m is missing"));
                r.num(bn, "height_m", b.height_m);
                if (!(b.height_m > 0)) throw Error(std::string(path).append(": ").append(bw).append(".height_m must be > 0"));
                b.cls = r.cls(bn, s.classes);
                r.yuv(bn, "colour", b.colour);
                sum += b.height_m;
                c.bands.push_back(b);
            }
            if (!c.bands.empty() && !(std::fabs(sum - c.height_m) <= 1e-9)) {
                char buf[160];
                std::snprintf(buf, sizeof buf, ": the heights (height_m) of the bands sum to %.9g m, not the height_m %.9g m",
                              sum, c.height_m);
                throw Error(std::string(path).append(": ").append(where).append(".bands").append(buf));
            }
        }
        s.cylinders.push_back(c);
    }
    size_t i_boxes = 0;
    for (const auto &it : r.get(root, "boxes")) {
        r.section(it, "boxes[" + std::to_string(i_boxes++) + "]");
        Box b;
        b.cls = r.cls(it, s.classes);
        r.num(it, "x_m", b.x_m); r.num(it, "y_m", b.y_m); r.num(it, "yaw_deg", b.yaw_rad, kDeg);
        r.num(it, "size_x_m", b.size_x_m); r.num(it, "size_y_m", b.size_y_m); r.num(it, "size_z_m", b.size_z_m);
        r.yuv(it, "colour", b.colour);
        s.boxes.push_back(b);
    }
    size_t i_patches = 0;
    for (const auto &it : r.get(root, "patches")) {
        r.section(it, "patches[" + std::to_string(i_patches++) + "]");
        FloorPatch p;
        p.cls = r.cls(it, s.classes);
        r.num(it, "x_m", p.x_m); r.num(it, "y_m", p.y_m); r.num(it, "yaw_deg", p.yaw_rad, kDeg);
        r.num(it, "size_x_m", p.size_x_m); r.num(it, "size_y_m", p.size_y_m);
        r.yuv(it, "colour", p.colour);
        r.num(it, "shadow", p.shadow);
        if (!(p.shadow >= 0 && p.shadow <= 1)) throw Error(path + ": patches[" + std::to_string(i_patches - 1) + "].shadow must be in [0, 1]");
        s.patches.push_back(p);
    }
    r.check_unknown();
    return s;
}

void save_scene(const std::string &path, const Scene &s)
{
    cv::FileStorage fs(path, cv::FileStorage::WRITE);
    if (!fs.isOpened()) throw Error(path + ": cannot write scene file");
    auto yuv = [&](const char *k, const Yuv &c) { fs << k << "[" << c.y << c.u << c.v << "]"; };
    auto cname = [&](int32_t c) { return c >= 0 && (size_t)c < s.classes.size() ? s.classes[c] : std::string("none"); };
    fs << "name" << s.name;
    fs << "classes" << "[";
    for (auto &c : s.classes) fs << c;
    fs << "]";
    fs << "landmark_diameter_m" << s.landmark_diameter_m << "landmark_height_m" << s.landmark_height_m;
    fs << "room" << "{" << "x_min" << s.room.x_min << "x_max" << s.room.x_max << "y_min" << s.room.y_min
       << "y_max" << s.room.y_max << "wall_height_m" << s.room.wall_height_m << "floor_texture" << s.room.floor_texture;
    yuv("floor", s.room.floor); yuv("wall", s.room.wall); yuv("ceiling", s.room.ceiling);
    fs << "}";
    const CameraModel &c = s.camera;
    fs << "camera" << "{" << "width" << (int)c.width << "height" << (int)c.height << "fx" << c.fx << "fy" << c.fy
       << "cx" << c.cx << "cy" << c.cy << "k1" << c.k1 << "k2" << c.k2 << "p1" << c.p1 << "p2" << c.p2 << "k3" << c.k3
       << "tilt_deg" << c.tilt_rad / kDeg << "yaw_deg" << c.yaw_rad / kDeg << "height_floor_m" << c.height_floor_m
       << "offset_m" << c.offset_m << "}";
    const CameraSigmas &g = s.sigmas;
    fs << "sigmas" << "{" << "fx" << g.fx << "fy" << g.fy << "cx" << g.cx << "cy" << g.cy << "k1" << g.k1 << "k2" << g.k2
       << "p1" << g.p1 << "p2" << g.p2 << "k3" << g.k3 << "tilt_deg" << g.tilt_rad / kDeg << "yaw_deg" << g.yaw_rad / kDeg
       << "height_m" << g.height_m << "offset_m" << g.offset_m << "}";
    const Imaging &im = s.imaging;
    fs << "imaging" << "{" << "samples" << (int)im.samples << "blur_sigma_px" << im.blur_sigma_px
       << "chroma_blur_px" << im.chroma_blur_px << "noise_y" << im.noise_y << "noise_c" << im.noise_c
       << "exposure" << im.exposure << "exposure_jitter" << im.exposure_jitter << "illum_amplitude" << im.illum_amplitude
       << "illum_period_s" << im.illum_period_s << "ambient" << im.ambient << "diffuse" << im.diffuse
       << "light_az_deg" << im.light_az_rad / kDeg << "light_el_deg" << im.light_el_rad / kDeg
       << "illum_gradient_per_m" << im.illum_gradient_per_m << "wb_drift" << im.wb_drift << "wb_period_s" << im.wb_period_s
       << "}";
    const TrajectoryParams &t = s.trajectory;
    fs << "trajectory" << "{" << "type" << t.type << "centre_x_m" << t.centre_x_m << "centre_y_m" << t.centre_y_m
       << "a_m" << t.a_m << "b_m" << t.b_m << "speed_mps" << t.speed_mps << "fps" << t.fps << "phase0" << t.phase0 << "}";
    const OdometryNoise &o = s.odometry;
    fs << "odometry" << "{" << "k_long" << o.k_long << "k_lat" << o.k_lat << "k_rot" << o.k_rot << "k_rot_d" << o.k_rot_d
       << "min_xy" << o.min_xy << "min_theta" << o.min_theta << "}";
    fs << "cylinders" << "[";
    for (const Cylinder &cy : s.cylinders) {
        fs << "{" << "id" << (int)cy.id << "class" << cname(cy.cls) << "landmark" << (int)cy.landmark << "x_m" << cy.x_m
           << "y_m" << cy.y_m << "diameter_m" << cy.diameter_m << "height_m" << cy.height_m;
        yuv("colour", cy.colour);
        // written only when used: scene files of one-colour cylinders stay as they were
        if (cy.diameter_top_m >= 0) fs << "diameter_top_m" << cy.diameter_top_m;
        if (!cy.bands.empty()) {
            fs << "bands" << "[";
            for (const Band &b : cy.bands) {
                fs << "{" << "height_m" << b.height_m << "class" << cname(b.cls);
                yuv("colour", b.colour);
                fs << "}";
            }
            fs << "]";
        }
        fs << "}";
    }
    fs << "]";
    fs << "boxes" << "[";
    for (const Box &b : s.boxes) {
        fs << "{" << "class" << cname(b.cls) << "x_m" << b.x_m << "y_m" << b.y_m << "yaw_deg" << b.yaw_rad / kDeg
           << "size_x_m" << b.size_x_m << "size_y_m" << b.size_y_m << "size_z_m" << b.size_z_m;
        yuv("colour", b.colour);
        fs << "}";
    }
    fs << "]";
    fs << "patches" << "[";
    for (const FloorPatch &p : s.patches) {
        fs << "{" << "class" << cname(p.cls) << "x_m" << p.x_m << "y_m" << p.y_m << "yaw_deg" << p.yaw_rad / kDeg
           << "size_x_m" << p.size_x_m << "size_y_m" << p.size_y_m << "shadow" << p.shadow;
        yuv("colour", p.colour);
        fs << "}";
    }
    fs << "]";
    fs.release();
}

Scene hard_scene()
{
    Scene s = default_scene();
    s.name = "hard";
    s.room.floor = {120, 105, 152};   // wood: the landmarks' orange hue at 40% of its saturation
    s.room.floor_texture = 12.0;
    s.room.wall = {150, 114, 118};    // olive: the green landmarks' hue, half saturated
    s.imaging.illum_gradient_per_m = 0.07;
    s.imaging.illum_amplitude = 0.2;
    s.imaging.exposure_jitter = 0.05;
    s.imaging.wb_drift = 6.0;
    s.imaging.wb_period_s = 50.0;
    struct C { double x, y, sx, sy, sz, yaw_deg; Yuv col; };
    const C clutter[] = {
        {-1.2, 3.1, 0.5, 0.3, 0.45, 15, {120, 92, 168}},    // dull orange crate
        {2.6, 2.9, 0.4, 0.4, 0.35, -20, {104, 114, 100}},   // dull green bin
        {-3.8, -1.2, 0.3, 0.5, 0.5, 40, {86, 104, 206}},    // red-orange box
        {3.9, 2.2, 0.35, 0.35, 0.3, 0, {178, 62, 148}},     // yellow box
        {-0.6, -3.0, 0.6, 0.3, 0.25, 5, {130, 100, 160}},   // tan cardboard
    };
    for (const C &c : clutter) {
        Box b;
        b.cls = -1;
        b.x_m = c.x; b.y_m = c.y; b.yaw_rad = c.yaw_deg * kDeg;
        b.size_x_m = c.sx; b.size_y_m = c.sy; b.size_z_m = c.sz;
        b.colour = c.col;
        s.boxes.push_back(b);
    }
    // cast shadows on the floor (darkening, colour kept)
    const double sh[][4] = {{0.0, 2.2, 1.4, 0.45}, {1.5, -2.0, 1.0, 0.5}, {-2.4, -2.3, 1.2, 0.4}, {3.2, 0.3, 0.8, 0.5}};
    for (const auto &x : sh) {
        FloorPatch p;
        p.x_m = x[0]; p.y_m = x[1]; p.size_x_m = x[2]; p.size_y_m = 0.8; p.yaw_rad = 25 * kDeg;
        p.shadow = x[3];
        s.patches.push_back(p);
    }
    return s;
}

Scene multiband_scene()
{
    Scene s = default_scene();  // its room, camera, imaging, drive and odometry
    s.name = "multiband";
    s.classes = {"orange", "green", "blue", "pink"};
    s.cylinders.clear();
    s.boxes.clear();
    s.patches.clear();
    s.landmark_diameter_m = 0.10;
    s.landmark_height_m = 0.30;
    const Yuv kColour[] = {kOrange, kGreen, kBlue, kPink};
    auto band = [&](double h, int32_t cls) {
        Band b;
        b.height_m = h;
        b.cls = cls;
        b.colour = cls < 0 ? kWhite : kColour[cls];
        return b;
    };
    uint32_t id = 0;
    // Striped traffic cones: orange / white / orange (top to bottom), 0.30 m tall, 0.25 m at the
    // base, 0.05 m at the top. The default scene's places of orange landmarks.
    const double cones[][2] = {{-3.6, 2.4}, {3.7, 2.2}, {-3.9, -0.6}, {1.4, 0.0}, {2.0, -2.6}, {-1.6, -2.7}};
    for (const auto &p : cones) {
        Cylinder c;
        c.id = id++;
        c.cls = 0;
        c.landmark = true;
        c.x_m = p[0];
        c.y_m = p[1];
        c.diameter_m = 0.25;
        c.diameter_top_m = 0.05;
        c.height_m = 0.30;
        c.colour = kOrange;
        c.bands = {band(0.10, 0), band(0.05, -1), band(0.15, 0)};
        s.cylinders.push_back(c);
    }
    // Colour-coded cylinders, 0.10 m x 0.30 m: three 0.10 m bands of green (1), blue (2), pink (3),
    // top to bottom, no two neighbours alike (they would read as one band); all codes distinct and
    // of one length, so none is part of another. The default scene's places of green landmarks
    // and one orange one.
    struct Coded { double x, y; int32_t code[3]; };
    const Coded coded[] = {
        {0.0, 2.5, {1, 2, 3}},  {-1.8, 2.6, {1, 3, 2}}, {1.9, 2.7, {2, 1, 3}},  {3.9, 0.4, {2, 3, 1}},
        {-1.4, 0.1, {3, 1, 2}}, {3.4, -2.5, {3, 2, 1}}, {0.1, -2.6, {1, 2, 1}}, {-3.6, -2.6, {3, 1, 3}},
    };
    for (const Coded &k : coded) {
        Cylinder c;
        c.id = id++;
        c.cls = k.code[0];  // the class the truth reports: the top band's
        c.landmark = true;
        c.x_m = k.x;
        c.y_m = k.y;
        c.diameter_m = s.landmark_diameter_m;
        c.height_m = s.landmark_height_m;
        c.colour = kColour[k.code[0]];
        for (int32_t cls : k.code) c.bands.push_back(band(0.10, cls));
        s.cylinders.push_back(c);
    }
    Box flat;  // a flat orange box lying on the floor (clutter in a landmark colour)
    flat.cls = 0; flat.x_m = -0.7; flat.y_m = 2.0; flat.yaw_rad = 20 * kDeg;
    flat.size_x_m = 0.5; flat.size_y_m = 0.35; flat.size_z_m = 0.06; flat.colour = kOrange;
    s.boxes.push_back(flat);
    Box occ;  // a neutral occluder
    occ.cls = -1; occ.size_x_m = 0.35; occ.size_y_m = 0.35; occ.size_z_m = 0.6; occ.colour = kNeutral;
    occ.x_m = -2.9; occ.y_m = 1.9; occ.yaw_rad = 10 * kDeg;
    s.boxes.push_back(occ);
    return s;
}

Scene scene_by_name(const std::string &n)
{
    if (n == "default") return default_scene();
    if (n == "empty") return empty_scene();
    if (n == "hard") return hard_scene();
    if (n == "multiband") return multiband_scene();
    return load_scene(n);
}

} // namespace synth
} // namespace cylfe
