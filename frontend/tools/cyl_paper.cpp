// SPDX-License-Identifier: BSD-3-Clause
// cyl_paper: the paper's Tables 6, 8 and 9 recomputed with libcyl's uncertainty model, printed
// beside the paper's own figures. The camera comes from a calibration file (default
// paper_camera.yaml from the data directory, the paper's Table 4/5 camera). The last line is a JSON object.
//
// Each row is a full observation: the landmark (a cylinder, --diameter x --height m) is placed
// at the row's range and bearing in the robot frame, projected through the camera, rendered as
// the rectangle of pixels it covers, and run through cyl_observe() (local noise estimator,
// centroid, undistortion, geometry, first-order covariance), then cyl_observation_budget().
//
// usage: cyl_paper [--camera FILE] [--model exact|paper] [--diameter M] [--height M]
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "cylfe/version.hpp"
#include "cylfe/calibration.hpp"
#include "cylfe/data_files.hpp"
#include "cylfe/error.hpp"

extern "C" {
#include "cyl/observe.h"
}

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

struct Scene {
    std::vector<cyl_run> runs;
    cyl_blob blob{};
    cyl_segmentation seg{};
};

// The pixels whose centres lie inside the landmark's projected rectangle, as one blob.
void render(const cyl_camera &cam, double x, double y, double D, double H, Scene &s)
{
    double u, v;
    cylfe::check(cyl_rb_project(&cam, x, y, &u, &v), "projecting the landmark");
    cyl_rb_result r;
    cylfe::check(cyl_range_bearing(&cam, CYL_GEOM_EXACT, u, v, 0, 0, 0, &r), "landmark range");
    double w = cam.fx_px * D / r.depth_m, h = cam.fy_px * H / r.depth_m;
    long x0 = std::lround(u - w / 2 + 0.5), x1 = std::lround(u + w / 2 - 0.5);
    long y0 = std::lround(v - h / 2 + 0.5), y1 = std::lround(v + h / 2 - 0.5);
    long W = cam.width ? (long)cam.width : 768, Hh = cam.height ? (long)cam.height : 576;
    s.blob = cyl_blob{};
    if (x0 <= 0) { x0 = 0; s.blob.flags |= CYL_BLOB_TOUCH_LEFT; }
    if (y0 <= 0) { y0 = 0; s.blob.flags |= CYL_BLOB_TOUCH_TOP; }
    if (x1 >= W - 1) { x1 = W - 1; s.blob.flags |= CYL_BLOB_TOUCH_RIGHT; }
    if (y1 >= Hh - 1) { y1 = Hh - 1; s.blob.flags |= CYL_BLOB_TOUCH_BOTTOM; }
    if (x1 < x0 || y1 < y0) throw cylfe::Error("landmark outside the image");
    s.runs.clear();
    for (long yy = y0; yy <= y1; yy++) {
        cyl_run run{};
        run.x = (uint16_t)x0;
        run.y = (uint16_t)yy;
        run.width = (uint16_t)(x1 - x0 + 1);
        run.next = yy < y1 ? (uint32_t)(s.runs.size() + 1) : CYL_NONE;
        s.runs.push_back(run);
    }
    s.blob.first_run = 0;
    s.blob.n_runs = (uint32_t)s.runs.size();
    s.blob.area = (uint32_t)((x1 - x0 + 1) * (y1 - y0 + 1));
    s.blob.x0 = (uint16_t)x0; s.blob.x1 = (uint16_t)x1; s.blob.y0 = (uint16_t)y0; s.blob.y1 = (uint16_t)y1;
    s.seg = cyl_segmentation{};
    s.seg.runs = s.runs.data();
    s.seg.n_runs = s.seg.max_runs = (uint32_t)s.runs.size();
    s.seg.blobs = &s.blob;
    s.seg.n_blobs = s.seg.max_blobs = 1;
    s.seg.x_step = s.seg.y_step = 1;
    s.seg.x_last = (uint32_t)W - 1;
    s.seg.y_last = (uint32_t)Hh - 1;
    s.seg.frame_width = (uint32_t)W;
    s.seg.frame_height = (uint32_t)Hh;
}

cyl_observation observe(const cyl_camera &cam, cyl_geom_model model, double range, double bearing,
                        double D, double H)
{
    Scene s;
    render(cam, range * std::cos(bearing), range * std::sin(bearing), D, H, s);
    cyl_observe_params p = cyl_observe_params_default();
    p.model = model;
    p.size[0].diameter_m = D;
    p.size[0].height_m = H;
    cyl_observation o;
    uint32_t n = 0;
    cylfe::check(cyl_observe(&s.seg, &cam, &p, nullptr, 0, &o, 1, &n), "cyl_observe");
    if (n != 1 || (o.flags & (CYL_OBS_NO_RANGE | CYL_OBS_INVALID)))
        throw cylfe::Error("no range for the landmark at " + std::to_string(range) + " m");
    return o;
}

} // namespace

int main(int argc, char **argv)
{
    if (cylfe::print_version_if_asked(argc, argv, "cyl_paper")) return 0;
    std::string cam_path;
    cyl_geom_model model = CYL_GEOM_EXACT;
    double D = 0.10, H = 0.10;  // largest fully visible at the 1.19 m row (docs)
    for (int i = 1; i < argc; i++) {
        std::string a = argv[i];
        auto val = [&]() -> std::string {
            if (i + 1 >= argc) { std::fprintf(stderr, "cyl_paper: %s needs a value\n", a.c_str()); std::exit(cylfe::kExitUsage); }
            return argv[++i];
        };
        if (a == "--camera") cam_path = val();
        else if (a == "--model") {
            std::string m = val();
            if (m == "exact") model = CYL_GEOM_EXACT;
            else if (m == "paper") model = CYL_GEOM_PAPER;
            else { std::fprintf(stderr, "cyl_paper: --model exact|paper\n"); return cylfe::kExitUsage; }
        } else if (a == "--diameter") D = std::stod(val());
        else if (a == "--height") H = std::stod(val());
        else if (a == "-h" || a == "--help") {
            std::printf("usage: cyl_paper [--camera FILE] [--model exact|paper] [--diameter M] [--height M] [--version]\n"
                        "  --camera FILE   default paper_camera.yaml from the data directory (CYL_DATA_DIR,\n"
                        "                  else PREFIX/share/cyl or the repository's calib_data/)\n");
            return 0;
        } else { std::fprintf(stderr, "cyl_paper: unknown argument %s\n", a.c_str()); return cylfe::kExitUsage; }
    }
    try {
        if (cam_path.empty()) cam_path = cylfe::data_file("paper_camera.yaml");
        cylfe::CameraCalibration cal = cylfe::load_mounted_camera_calibration(cam_path);
        const cyl_camera &cam = cal.cam;
        const char *mname = model == CYL_GEOM_EXACT ? "exact" : "paper";
        std::printf("libcyl uncertainty vs the paper -- camera %s, model %s, landmark %.2f x %.2f m, "
                    "local noise estimator\n", cam_path.c_str(), mname, D, H);
        std::printf("camera: f = (%.1f, %.1f) px, c = (%.1f, %.1f) px, tilt %.3f +- %.3f deg, yaw %.3f +- %.3f deg, "
                    "h %.3f +- %.2g m, s %.3f +- %.2g m\n\n", cam.fx_px, cam.fy_px, cam.cx_px, cam.cy_px,
                    cam.tilt_rad / kDeg, cam.tilt_sigma_rad / kDeg, cam.yaw_rad / kDeg, cam.yaw_sigma_rad / kDeg,
                    cam.height_m, cam.height_sigma_m, cam.offset_m, cam.offset_sigma_m);

        // ---- Table 6 ----
        static const double actual[6] = {2.97, 2.89, 1.83, 1.62, 1.45, 1.17};
        static const double calc[6] = {2.86, 2.84, 1.92, 1.68, 1.44, 1.19};
        static const double sig_p[6] = {0.34, 0.33, 0.14, 0.11, 0.079, 0.052};
        std::printf("Table 6: sigma of the range from the robot centre (bearing 0, at the paper's calculated range)\n");
        std::printf("  actual  calc   sigma paper  sigma ours  ours/paper  var_v px^2  nonlinear  cut\n");
        double rmin = 1e300, rmax = 0;
        for (int i = 0; i < 6; i++) {
            cyl_observation o = observe(cam, model, calc[i], 0.0, D, H);
            double sg = std::sqrt(o.cov_rb[0][0]), ratio = sg / sig_p[i];
            rmin = std::fmin(rmin, ratio);
            rmax = std::fmax(rmax, ratio);
            std::printf("  %5.2f   %5.2f  %8.3f    %9.4f   %8.3f    %9.2g   %-9s  %s\n", actual[i], calc[i], sig_p[i],
                        sg, ratio, o.var_v_px2, (o.flags & CYL_OBS_NONLINEAR) ? "yes" : "no",
                        (o.flags & CYL_OBS_CUT) ? "yes" : "no");
        }
        std::printf("  ratio ours/paper %.3f .. %.3f, largest/smallest %.3f\n\n", rmin, rmax, rmax / rmin);

        // ---- Tables 8 and 9 at 1.36 m, 13.2 deg ----
        cyl_observation o = observe(cam, model, 1.36, 13.2 * kDeg, D, H);
        cyl_error_budget b;
        cylfe::check(cyl_observation_budget(&o, &cam, model, &b), "error budget");
        static const char *p8_angle[CYL_SRC_COUNT] = {"< 1%", "< 1%", "< 1%", "-", "<< 1%", "3%", "96%", "< 1%"};
        static const char *p8_dist[CYL_SRC_COUNT] = {"< 1%", "< 1%", "<< 1%", "-", "<< 1%", "99%", "< 1%", "< 1%"};
        std::printf("Table 8: share of the output variance at %.3f m, %.2f deg (paper: 1.36 m, 13.2 deg)\n",
                    o.range_m, o.bearing_rad / kDeg);
        std::printf("  %-20s %12s %12s %12s %12s\n", "source", "angle paper", "angle ours", "dist paper", "dist ours");
        for (int g = 0; g < CYL_SRC_COUNT; g++)
            std::printf("  %-20s %12s %11.3f%% %12s %11.3f%%\n", cyl_source_name((cyl_source)g), p8_angle[g],
                        100 * b.share_bearing[g], p8_dist[g], 100 * b.share_range[g]);
        std::printf("  %-20s %12s %12.3g %12s %12.3g   (ours: rad^2 = %.3g deg^2; m^2)\n", "total variance",
                    "0.0012", b.total_var_bearing_rad2, "0.0020", b.total_var_range_m2,
                    b.total_var_bearing_rad2 / (kDeg * kDeg));
        std::printf("  cross-covariance remainder: angle %.2g%%, distance %.2g%%\n\n",
                    100 * b.cross_share_bearing, 100 * b.cross_share_range);

        // Table 9 in the paper's units: angles in deg (inputs and output), lengths in m, pixels px
        struct Row { cyl_source s; const char *pa, *pd; double in_scale; };
        const double d2 = 1.0 / (kDeg * kDeg);   // rad^2 -> deg^2
        const Row rows[] = {
            {CYL_SRC_TILT, "1.46e-2", "2.08e-2", kDeg * kDeg},
            {CYL_SRC_YAW, "0.80", "3.62e-7", kDeg * kDeg},
            {CYL_SRC_HEIGHT, "30.4", "43.22", 1.0},
            {CYL_SRC_POSITION, "93.4", "0.95", 1.0},
            {CYL_SRC_PRINCIPAL_POINT, "6.0e-5", "3.06e-3", 1.0},
            {CYL_SRC_FOCAL, "2.08e-4", "1.35e-6", 1.0},
            {CYL_SRC_SEGMENTATION, "1.2e-3", "1.0e-4", 1.0},
            {CYL_SRC_DISTORTION, "-", "-", 1.0},
        };
        std::printf("Table 9: sensitivity, output variance with that source's variance = 1 (deg^2 for tilt/yaw,\n"
                    "         m^2 for height/position, px^2 for pixels, 1 for distortion); others 0\n");
        std::printf("  %-20s %12s %12s %12s %12s\n", "source", "angle paper", "angle ours", "dist paper", "dist ours");
        std::printf("  %-20s %12s %12s %12s %12s\n", "", "deg^2", "deg^2", "m^2", "m^2");
        for (const Row &r : rows)
            std::printf("  %-20s %12s %12.3g %12s %12.3g\n", cyl_source_name(r.s), r.pa,
                        b.sens_bearing[r.s] * d2 * r.in_scale, r.pd, b.sens_range[r.s] * r.in_scale);
        std::printf("\n");
        std::printf("{\"range_sigma_ratio_min\": %.4f, \"range_sigma_ratio_max\": %.4f, "
                    "\"range_sigma_ratio_spread\": %.4f, \"tilt_share_range\": %.4f, \"yaw_share_bearing\": %.4f, "
                    "\"total_var_range_m2\": %.4g, \"total_var_bearing_rad2\": %.4g, \"model\": \"%s\", "
                    "\"camera\": \"%s\"}\n",
                    rmin, rmax, rmax / rmin, b.share_range[CYL_SRC_TILT], b.share_bearing[CYL_SRC_YAW],
                    b.total_var_range_m2, b.total_var_bearing_rad2, mname, cam_path.c_str());
    } catch (const std::exception &e) {
        std::fprintf(stderr, "cyl_paper: %s\n", e.what());
        return cylfe::kExitFailure;
    }
    return 0;
}
