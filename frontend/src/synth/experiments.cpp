// SPDX-License-Identifier: BSD-3-Clause
// The paper's consistency experiments on rendered frames (docs/synthetic.md).
#include "cylfe/synth_experiments.hpp"
#include "cylfe/error.hpp"
#include "corners.hpp"
#include "random.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace cylfe {
namespace synth {

namespace {
constexpr double kPi = 3.14159265358979323846;

using detail::wrap;

using detail::splitmix;
using Rand = detail::NormalStream;

struct ScreenBox {
    double u0 = 1e30, v0 = 1e30, u1 = -1e30, v1 = -1e30;
    double depth = 0;
    bool valid = true;
    void add(double u, double v) { u0 = std::min(u0, u); u1 = std::max(u1, u); v0 = std::min(v0, v); v1 = std::max(v1, v); }
    bool overlaps(const ScreenBox &o, double m = 0) const
    {
        return u0 - m <= o.u1 && o.u0 - m <= u1 && v0 - m <= o.v1 && o.v0 - m <= v1;
    }
    bool contains(double u, double v, double m = 0) const { return u >= u0 - m && u <= u1 + m && v >= v0 - m && v <= v1 + m; }
};

ScreenBox project_points(const CameraModel &cam, const CameraPose &cp, const std::vector<std::array<double, 3>> &pts)
{
    ScreenBox b;
    double dsum = 0;
    for (auto &p : pts) {
        double q[3] = {p[0] - cp.c[0], p[1] - cp.c[1], p[2] - cp.c[2]};
        double zc = q[0] * cp.f[0] + q[1] * cp.f[1] + q[2] * cp.f[2];
        if (zc < 0.05) { b.valid = false; return b; }
        dsum += zc;
        double u, v;
        project_point(cam, cp, p.data(), &u, &v);
        b.add(u, v);
    }
    b.depth = dsum / pts.size();
    return b;
}

std::vector<std::array<double, 3>> cylinder_points(const Cylinder &c)
{
    std::vector<std::array<double, 3>> pts;
    double R = c.diameter_m / 2;
    for (int k = 0; k < 36; k++) {
        double a = 2 * kPi * k / 36;
        pts.push_back({c.x_m + R * std::cos(a), c.y_m + R * std::sin(a), 0.0});
        pts.push_back({c.x_m + R * std::cos(a), c.y_m + R * std::sin(a), c.height_m});
    }
    return pts;
}

std::vector<std::array<double, 3>> box_points(const Box &b)
{
    std::vector<std::array<double, 3>> pts;
    detail::append_rect_corners(b.x_m, b.y_m, b.yaw_rad, b.size_x_m, b.size_y_m, {0.0, b.size_z_m}, pts);
    return pts;
}

std::vector<std::array<double, 3>> patch_points(const FloorPatch &p)
{
    std::vector<std::array<double, 3>> pts;
    detail::append_rect_corners(p.x_m, p.y_m, p.yaw_rad, p.size_x_m, p.size_y_m, {0.0}, pts);
    return pts;
}

Scene static_scene(const Scene &base)
{
    Scene s = empty_scene();
    s.classes = base.classes;
    s.camera = base.camera;
    s.sigmas = base.sigmas;
    s.imaging = base.imaging;
    s.room = base.room;
    s.room.x_min = -3; s.room.x_max = 7; s.room.y_min = -4; s.room.y_max = 4;
    s.landmark_diameter_m = base.landmark_diameter_m;
    s.landmark_height_m = base.landmark_height_m;
    return s;
}

Cylinder prototype(const Scene &base, int32_t cls)
{
    for (const Cylinder &c : base.cylinders)
        if (c.landmark && c.cls == cls) return c;
    Cylinder c;
    c.cls = cls;
    c.diameter_m = base.landmark_diameter_m;
    c.height_m = base.landmark_height_m;
    c.colour = cls == 0 ? Yuv{137, 68, 194} : Yuv{114, 103, 75};
    return c;
}

} // namespace

// ---- Detect ---------------------------------------------------------------------------------

Detect::Detect(const cyl_colortable &t, const Scene &s)
    : seg_params(cyl_segment_params_default()), obs_params(cyl_observe_params_default_frame()), t_(&t),
      w_(s.camera.width), h_(s.camera.height)
{
    for (size_t c = 0; c < s.classes.size() && c < CYL_MAX_CLASSES; c++) {
        obs_params.size[c].diameter_m = s.landmark_diameter_m;
        obs_params.size[c].height_m = s.landmark_height_m;
    }
    uint32_t max_runs = cyl_segment_max_runs(w_, h_, &seg_params), max_blobs = 8192;
    mem_.resize(cyl_segment_mem_size(max_runs, max_blobs));
    check(cyl_segmentation_init(&seg_, mem_.data(), mem_.size(), max_runs, max_blobs), "cyl_segmentation_init");
}

void Detect::segment(const uint8_t *yuyv)
{
    check(cyl_image_wrap(&img_, CYL_FMT_YUYV, w_, h_, yuyv, 0), "frame");
    check(cyl_segment(t_, &img_, &seg_params, &seg_), "cyl_segment");
    obs_params.image = &img_;
    obs_params.table = t_;
}

const std::vector<cyl_observation> &Detect::observe(const cyl_camera &cam, cyl_noise_estimator est)
{
    obs_params.estimator = est;
    size_t ws = cyl_observe_work_size(&seg_, &obs_params);
    if (work_.size() < ws) work_.resize(ws);
    obs_.resize(std::max<uint32_t>(1, seg_.n_blobs));
    uint32_t n = 0;
    check(cyl_observe(&seg_, &cam, &obs_params, work_.data(), work_.size(), obs_.data(), (uint32_t)obs_.size(), &n),
          "cyl_observe");
    obs_.resize(n);
    return obs_;
}

// ---- Tables 1-3 -----------------------------------------------------------------------------

std::vector<VarianceRow> run_variance_tables(const Scene &base, const cyl_colortable &t, const VarianceConfig &cfg)
{
    std::vector<VarianceRow> rows;
    Scene s = static_scene(base);
    Cylinder lm = prototype(base, 0);
    const double bearing = 0.04;
    const Pose2 robot{-s.camera.offset_m, 0, 0};  // camera at the origin, looking along +x
    Renderer ren(s);
    Detect det(t, s);
    std::vector<uint8_t> frame, work;
    CleanFrame clean;
    std::vector<std::pair<double, bool>> cases;
    for (double r : cfg.ranges_m) cases.push_back({r, false});
    if (cfg.occluded) cases.push_back({cfg.occluded_range_m, true});
    for (size_t ci = 0; ci < cases.size(); ci++) {
        double r = cases[ci].first;
        bool occ = cases[ci].second;
        Scene &sc = ren.mutable_scene();
        sc.cylinders.clear();
        sc.boxes.clear();
        lm.x_m = r * std::cos(bearing);
        lm.y_m = r * std::sin(bearing);
        sc.cylinders.push_back(lm);
        if (occ) {
            // A neutral box at 70% of the range covering the lower left of the landmark.
            Box b;
            b.cls = -1;
            b.colour = Yuv{96, 131, 125};
            double d = 0.7 * r;
            b.x_m = d;
            b.size_x_m = 0.08;
            b.size_y_m = 0.25;
            b.y_m = (lm.y_m + 0.25 * lm.diameter_m) * d / r + b.size_y_m / 2;
            // top of the box on the line of sight to 60% of the landmark's height
            double zc = s.camera.height_floor_m, zt = 0.6 * lm.height_m;
            b.size_z_m = zc - (zc - zt) * d / r;
            sc.boxes.push_back(b);
        }
        ren.render_clean(robot, ren.scene().imaging.exposure, clean);   // exposure: 1 in the scenes, varied by the sweep
        VarianceRow row;
        char lab[64];
        snprintf(lab, sizeof lab, "%s%.1f m", occ ? "occluded " : "", r);
        row.label = lab;
        row.range_m = r;
        row.frames = cfg.frames;
        std::vector<double> cx, cy;
        double sx[kEstimators] = {}, sy[kEstimators] = {}, area = 0;
        for (uint32_t k = 0; k < cfg.frames; k++) {
            ren.finish_yuyv(clean, mix_seed(cfg.seed, ci * 100000 + k, 0x7AB1), frame);
            det.segment(frame.data());
            const cyl_segmentation &seg = det.seg();
            if (seg.class_count[0] == 0) continue;
            const cyl_blob *b = &seg.blobs[seg.class_first[0]];  // largest of class 0
            work.resize(std::max<size_t>(16, cyl_noise_work_size_seg(&seg)));
            cyl_centroid_noise out[kEstimators];
            bool ok = true;
            for (int e = 0; e < kEstimators; e++) {
                cyl_status st = e == CYL_NOISE_IMAGE
                    ? cyl_noise_blob_image(&seg, b, &det.image(), &t, &det.obs_params.image_noise, &out[e])
                    : cyl_noise_blob(&seg, b, (cyl_noise_estimator)e, work.data(), work.size(), &out[e]);
                if (st != CYL_OK) ok = false;
            }
            if (!ok) continue;
            cx.push_back(out[2].cx_px);
            cy.push_back(out[2].cy_px);
            for (int e = 0; e < kEstimators; e++) { sx[e] += out[e].var_x_px2; sy[e] += out[e].var_y_px2; }
            area += out[2].n;
        }
        size_t n = cx.size();
        row.detected = (uint32_t)n;
        if (n > 1) {
            double mx = 0, my = 0;
            for (size_t i = 0; i < n; i++) { mx += cx[i]; my += cy[i]; }
            mx /= n; my /= n;
            double vx = 0, vy = 0;
            for (size_t i = 0; i < n; i++) { vx += (cx[i] - mx) * (cx[i] - mx); vy += (cy[i] - my) * (cy[i] - my); }
            row.actual_x = vx / (n - 1);
            row.actual_y = vy / (n - 1);
            for (int e = 0; e < kEstimators; e++) { row.est_x[e] = sx[e] / n; row.est_y[e] = sy[e] / n; }
            row.mean_area = area / n;
        }
        rows.push_back(row);
    }
    return rows;
}

// ---- Tables 6-7 -----------------------------------------------------------------------------

std::vector<RbSample> run_range_bearing(const Scene &base, const cyl_colortable &t, const RbConfig &cfg)
{
    std::vector<RbSample> out;
    Scene s = static_scene(base);
    const CameraModel truth = s.camera;
    const CameraSigmas sg = s.sigmas;
    const Pose2 robot{0, 0, 0};
    const CameraPose cp = camera_pose(truth, robot);
    Renderer ren(s);
    Detect det(t, s);
    std::vector<uint8_t> frame;
    Rand rnd(mix_seed(cfg.seed, 0xCA11, 0));
    const double W = truth.width, H = truth.height;
    for (uint32_t run = 0; run < cfg.runs; run++) {
        // Calibration error of this run: the estimator's camera is the truth plus an error drawn
        // from the sigmas it is told about.
        CameraModel est = truth;
        CameraSigmas esg = sg;
        if (cfg.calibration_error) {
            est.fx += sg.fx * rnd.normal(); est.fy += sg.fy * rnd.normal();
            est.cx += sg.cx * rnd.normal(); est.cy += sg.cy * rnd.normal();
            est.k1 += sg.k1 * rnd.normal(); est.k2 += sg.k2 * rnd.normal();
            est.p1 += sg.p1 * rnd.normal(); est.p2 += sg.p2 * rnd.normal(); est.k3 += sg.k3 * rnd.normal();
            est.tilt_rad += sg.tilt_rad * rnd.normal(); est.yaw_rad += sg.yaw_rad * rnd.normal();
            est.height_floor_m += sg.height_m * rnd.normal(); est.offset_m += sg.offset_m * rnd.normal();
        } else {
            esg = CameraSigmas{};
            esg.fx = esg.fy = esg.cx = esg.cy = 0;
            esg.tilt_rad = esg.yaw_rad = esg.height_m = esg.offset_m = 0;
        }
        cyl_camera cam = to_cyl_camera(est, esg, s.landmark_height_m);
        // Landmarks of this run: uniform in range and over the visible field, whole in the image,
        // apart from each other.
        Scene &sc = ren.mutable_scene();
        sc.cylinders.clear();
        std::vector<ScreenBox> boxes;
        for (uint32_t k = 0; k < cfg.landmarks_per_run; k++) {
            Cylinder c = prototype(base, (int32_t)((run + k) % std::max<size_t>(1, base.classes.size() >= 2 ? 2 : 1)));
            c.id = k;
            for (int attempt = 0; attempt < 400; attempt++) {
                double r = cfg.range_min_m + (cfg.range_max_m - cfg.range_min_m) * rnd.uni();
                double b = -0.65 + 1.3 * rnd.uni();
                c.x_m = r * std::cos(b);
                c.y_m = r * std::sin(b);
                ScreenBox sb = project_points(truth, cp, cylinder_points(c));
                if (!sb.valid || sb.u0 < 3 || sb.v0 < 3 || sb.u1 > W - 4 || sb.v1 > H - 4) continue;
                bool clash = false;
                for (auto &o : boxes) clash = clash || sb.overlaps(o, 10);
                if (clash) continue;
                boxes.push_back(sb);
                sc.cylinders.push_back(c);
                break;
            }
        }
        double gain = ren.frame_gain(cfg.seed, run, run * 3.7);
        ren.render_yuyv(robot, gain, mix_seed(cfg.seed, run, 0xF00D), frame);
        det.segment(frame.data());
        const std::vector<cyl_observation> &obs = det.observe(cam, cfg.estimator);
        for (size_t k = 0; k < sc.cylinders.size(); k++) {
            const Cylinder &c = sc.cylinders[k];
            const cyl_observation *best = nullptr;
            for (const cyl_observation &o : obs)
                if (o.cls == (uint8_t)c.cls && boxes[k].contains(o.u_px, o.v_px, 2) && (!best || o.area > best->area))
                    best = &o;
            if (!best || (best->flags & (CYL_OBS_CUT | CYL_OBS_INVALID | CYL_OBS_NO_RANGE))) continue;
            RbSample r;
            r.run = run;
            double camx = cp.c[0], camy = cp.c[1];
            double ex = c.x_m - camx, ey = c.y_m - camy, el = std::hypot(ex, ey), R = c.diameter_m / 2;
            double fx = c.x_m - R * ex / el, fy = c.y_m - R * ey / el;
            r.true_range_m = std::hypot(fx, fy);
            r.true_bearing_rad = std::atan2(fy, fx);
            r.axis_range_m = std::hypot(c.x_m, c.y_m);
            r.axis_bearing_rad = std::atan2(c.y_m, c.x_m);
            r.range_m = best->range_m;
            r.bearing_rad = best->bearing_rad;
            r.cov_rr = best->cov_rb[0][0];
            r.cov_rb = best->cov_rb[0][1];
            r.cov_bb = best->cov_rb[1][1];
            double pc[3] = {c.x_m, c.y_m, c.height_m / 2}, u, v;
            project_point(truth, cp, pc, &u, &v);
            r.du_centre_px = best->centroid_u_px - u;
            r.dv_centre_px = best->centroid_v_px - v;
            r.du_point_px = best->u_px - u;
            r.dv_point_px = best->v_px - v;
            r.bias_u_px = best->bias_u_px;
            r.bias_v_px = best->bias_v_px;
            r.var_centroid_u = best->var_u_px2 - best->bias_var_u_px2;
            r.var_centroid_v = best->var_v_px2 - best->bias_var_v_px2;
            r.var_u = best->var_u_px2;
            r.var_v = best->var_v_px2;
            r.confidence = best->confidence;
            out.push_back(r);
        }
    }
    return out;
}

RbStats rb_stats(const std::vector<RbSample> &s, bool face)
{
    RbStats st;
    st.n = s.size();
    if (s.empty()) return st;
    for (const RbSample &r : s) {
        double er = r.range_m - (face ? r.true_range_m : r.axis_range_m);
        double eb = wrap(r.bearing_rad - (face ? r.true_bearing_rad : r.axis_bearing_rad));
        double zr = er / std::sqrt(r.cov_rr), zb = eb / std::sqrt(r.cov_bb);
        st.range_frac1 += std::fabs(zr) <= 1;
        st.range_frac2 += std::fabs(zr) <= 2;
        st.bearing_frac1 += std::fabs(zb) <= 1;
        st.bearing_frac2 += std::fabs(zb) <= 2;
        double det = r.cov_rr * r.cov_bb - r.cov_rb * r.cov_rb;
        st.mean_nees += (r.cov_bb * er * er - 2 * r.cov_rb * er * eb + r.cov_rr * eb * eb) / det;
        st.mean_range_err += er;
        st.mean_bearing_err += eb;
        st.rms_range_z += zr * zr;
        st.rms_bearing_z += zb * zb;
    }
    double n = (double)s.size();
    st.range_frac1 /= n; st.range_frac2 /= n; st.bearing_frac1 /= n; st.bearing_frac2 /= n;
    st.mean_nees /= n; st.mean_range_err /= n; st.mean_bearing_err /= n;
    st.rms_range_z = std::sqrt(st.rms_range_z / n);
    st.rms_bearing_z = std::sqrt(st.rms_bearing_z / n);
    return st;
}

// ---- confidence -----------------------------------------------------------------------------

ConfidenceResult run_confidence(const Scene &s, const cyl_colortable &t, uint32_t frames, uint32_t stride,
                                uint64_t seed)
{
    ConfidenceResult res;
    std::vector<DriveStep> drive = make_drive(s, frames, seed);
    Renderer ren(s);
    Detect det(t, s);
    cyl_camera cam = to_cyl_camera(s);
    std::vector<uint8_t> frame;
    const double W = s.camera.width, H = s.camera.height;
    struct Obj { ScreenBox b; int32_t cls; bool landmark; bool occluded = false; };
    for (uint32_t k = 0; k < frames; k += std::max<uint32_t>(1, stride)) {
        const DriveStep &st = drive[k];
        CameraPose cp = camera_pose(s.camera, st.truth);
        std::vector<Obj> objs;
        for (const Cylinder &c : s.cylinders) objs.push_back({project_points(s.camera, cp, cylinder_points(c)), c.cls, c.landmark});
        for (const Box &b : s.boxes) objs.push_back({project_points(s.camera, cp, box_points(b)), b.cls, false});
        for (const FloorPatch &p : s.patches) objs.push_back({project_points(s.camera, cp, patch_points(p)), p.cls, false});
        // A landmark counts only when nothing nearer overlaps it on screen and it is whole in view.
        for (size_t i = 0; i < objs.size(); i++) {
            Obj &a = objs[i];
            if (!a.b.valid) continue;
            if (a.b.u0 < 1 || a.b.v0 < 1 || a.b.u1 > W - 2 || a.b.v1 > H - 2) a.occluded = true;
            for (size_t j = 0; j < objs.size(); j++)
                if (j != i && objs[j].b.valid && objs[j].b.overlaps(a.b, 2) && objs[j].b.depth < a.b.depth) a.occluded = true;
        }
        double gain = ren.frame_gain(seed, st.seq, st.t_ns * 1e-9);
        ren.render_yuyv(st.truth, gain, mix_seed(seed, st.seq, 0x5EED), frame);
        det.segment(frame.data());
        const std::vector<cyl_observation> &obs = det.observe(cam, CYL_NOISE_LOCAL);
        for (const cyl_observation &o : obs) {
            if (o.flags & (CYL_OBS_CUT | CYL_OBS_INVALID | CYL_OBS_NO_RANGE)) continue;
            if (o.area < 30) continue;  // specks are not objects
            const Obj *match = nullptr;
            int nmatch = 0;
            for (const Obj &a : objs)
                if (a.b.valid && a.cls == (int32_t)o.cls && a.b.contains(o.u_px, o.v_px, 2)) { match = &a; nmatch++; }
            if (nmatch != 1 || match->occluded) continue;
            // For comparison, eq. 7 with the paper's expected width fx D / depth (libcyl's
            // cyl_observe now expects the wider box of an off-axis cylinder under camera tilt:
            // cyl_landmark_expected_size, docs/synthetic.md "Landmark confidence").
            double plain = 0;
            {
                cyl_landmark_size sz = {s.landmark_diameter_m, s.landmark_height_m};
                cyl_confidence pc;
                if (cyl_landmark_confidence(o.w_px, o.h_px, o.depth_m, cam.fx_px, cam.fy_px, &sz,
                                            o.flags & 0x0Fu, &pc) == CYL_OK)
                    plain = pc.confidence;
            }
            if (match->landmark) {
                if (o.range_m >= 0.8 && o.range_m <= 4.0) {
                    res.landmark.push_back(o.confidence);
                    res.landmark_u.push_back(o.u_px);
                    res.landmark_plain.push_back(plain);
                }
            } else {
                res.clutter.push_back(o.confidence);
                res.clutter_plain.push_back(plain);
            }
        }
    }
    for (double c : res.landmark) res.landmark_ok += c >= 0.8;
    for (double c : res.clutter) res.clutter_ok += c <= 0.3;
    if (!res.landmark.empty()) res.landmark_ok /= res.landmark.size();
    if (!res.clutter.empty()) res.clutter_ok /= res.clutter.size();
    for (double c : res.landmark_plain) res.landmark_plain_ok += c >= 0.8;
    for (double c : res.clutter_plain) res.clutter_plain_ok += c <= 0.3;
    if (!res.landmark_plain.empty()) res.landmark_plain_ok /= res.landmark_plain.size();
    if (!res.clutter_plain.empty()) res.clutter_plain_ok /= res.clutter_plain.size();
    return res;
}

} // namespace synth
} // namespace cylfe
