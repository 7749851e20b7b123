// SPDX-License-Identifier: BSD-3-Clause
// cyl: the libcyl command-line frontend. `cyl --help` lists the commands.
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>


#include "cylfe/version.hpp"
#include "cylfe/calibration.hpp"
#include "cylfe/data_files.hpp"
#include "cylfe/error.hpp"
#include "cylfe/media.hpp"
#include "cylfe/overlay.hpp"
#include "cylfe/pipeline.hpp"
#include "cylfe/progress.hpp"
#include "cylfe/rawlog.hpp"
#include "cylfe/sources.hpp"
#include "cylfe/synth.hpp"
#include "cylfe/v4l2.hpp"

using namespace cylfe;

namespace {

volatile std::sig_atomic_t g_interrupted = 0;

void on_signal(int)
{
    g_interrupted = 1;
    V4L2Source::request_stop();
}

const char *kUsage =
    "usage: cyl <command> [options]      (cyl --help, cyl --version)\n"
    "\n"
    "Find coloured cylinder landmarks and report range, bearing, colour, confidence and their\n"
    "covariance for every frame.\n"
    "\n"
    "commands:\n"
    "  detect SOURCE        run detection, write the observation log (JSON Lines, docs/formats.md)\n"
    "  record SOURCE        record a source to a raw frame log (.cylraw)\n"
    "  info FILE.cylraw     describe a raw frame log\n"
    "  info CAMERA.yaml     the camera a calibration file gives, as libcyl sees it (JSON)\n"
    "  devices              list V4L2 devices              (same as --list-devices)\n"
    "  formats [DEVICE]     list a device's pixel formats  (same as --list-formats)\n"
    "  controls [DEVICE]    list a device's controls       (same as --list-controls)\n"
    "\n"
    "SOURCE is one of:\n"
    "  /dev/videoN, v4l2:DEVICE      a V4L2 camera (YUYV, UYVY, NV12, YU12, or MJPG decoded to YUYV)\n"
    "  FILE.cylraw, raw:FILE         a recorded raw frame log\n"
    "  IMAGE, VIDEO, file:PATH       image or video files (through OpenCV)\n"
    "  synthetic[:SEED]              the built-in synthetic scene, with odometry and ground truth\n"
    "\n"
    "detect options:\n"
    "  --table FILE         colour table (libcyl CYLT file); synthetic default synthetic.cylt from the\n"
    "                       data directory (CYL_DATA_DIR, else PREFIX/share/cyl or calib_data/)\n"
    "  --calib FILE         camera calibration (OpenCV or ROS YAML, with libcyl's mount and sigma\n"
    "                       fields); for the synthetic source the default is the scene's own camera\n"
    "  --out FILE|-         observation log (default -, stdout); a regular file is written as\n"
    "                       FILE.part and renamed when the run ends; a device node or FIFO is\n"
    "                       written in place, a symlink through to its file, a dangling one refused\n"
    "  --model exact|paper  geometric model (default exact)\n"
    "  --estimator image|local|column|uniform   centroid variance estimator (default image: from the\n"
    "                       frame's own noise and the table's boundary; local/column/uniform: the\n"
    "                       paper's eqs. 6/5/4, from the blob's shape only)\n"
    "  --edges subpixel|table   where a blob's edges lie (default subpixel: where the colour is halfway\n"
    "                       between the landmark's and the background's, so a shaded side does not move\n"
    "                       the centroid; table: where the colour table cut it)\n"
    "  --silhouette-sigma U,V   what the silhouette model and the edges leave of the centroid's bias,\n"
    "                       px (default 0.05,0.125 with sub-pixel edges, 0.25,0.25 with the table's;\n"
    "                       measure your camera's, docs/uncertainty.md)\n"
    "  --size CLASS=D,H     physical landmark size of a class in m (diameter, height), repeatable;\n"
    "                       needed for confidence (synthetic default: the scene's)\n"
    "  --centroid-var-floor PX2   lower bound on each centroid variance, px^2 (default 0): a\n"
    "                       model-error term for the centroid's geometric bias (docs/synthetic.md)\n"
    "  --partial-aspect-min F   flag an observation 0x800 (partly hidden) when its blob's\n"
    "                       width-to-height ratio is under F, or over 1/F, times a whole\n"
    "                       landmark's there (default 0.8; 0: off; docs/uncertainty.md)\n"
    "  --partial-offset-max F   ... and, where its range is accurate, when its centroid lies\n"
    "                       more than F of the box's width from the box's middle column (a side\n"
    "                       not classified; default 0.04; 0: off)\n"
    "  --partial-area-min F     ... and when its blob's area is under F times the area of a\n"
    "                       whole landmark's silhouette there (default 0: off)\n"
    "  --partial-side-max F     ... and when the landmark's colour goes on beyond one side of its\n"
    "                       box more than beyond the other, by more than F of a 3 px strip\n"
    "                       (side_colour_rel; default 0: off; docs/uncertainty.md)\n"
    "  --subpixel-rel-sigma R   uncertainty of the sub-pixel edges' shift of a blob's centroid,\n"
    "                       as a share of the shift, added to its bias variance (default 0:\n"
    "                       none; docs/uncertainty.md, \"Other scenes\")\n"
    "  --missing-part-share S   a part missing from a blob's box (aspect_rel away from 1) moves\n"
    "                       its centroid by up to half of it: S of that shift is added as a\n"
    "                       bias sigma (default 0: none; 0.5 for scenes whose blobs lose\n"
    "                       parts: docs/uncertainty.md)\n"
    "  --side-sigma C           the landmark's colour beyond one side of a blob's box moves its\n"
    "                       centroid: C x (|side_colour_rel| - D) x the box's width is added as\n"
    "                       a sigma of its u, px (default 0.25; 0: none; docs/uncertainty.md)\n"
    "  --side-sigma-free D      |side_colour_rel| up to D adds nothing (default 0.1, 0..1)\n"
    "  --overlay DIR|FILE.avi   write overlay images (PNG per frame) or a video\n"
    "  --show               show the overlay in a window (needs a display; q or Esc stops)\n"
    "clutter rejection (per class with CLASS=VALUE, every class with VALUE; the command line\n"
    "overrides --config):\n"
    "  --config FILE.yaml   detector config file: all of the below per class (docs/formats.md)\n"
    "  --roi X,Y,W,H        look only inside this rectangle, px\n"
    "  --mask FILE.png      blobs whose centroid falls on a zero pixel are dropped (the robot's body)\n"
    "  --min-area [C=]N     drop blobs under N px (default 9)\n"
    "  --max-area [C=]N     drop blobs over N px (default: no limit)\n"
    "  --merge-gap [C=]N    merge blobs of a class whose boxes are <= N px apart (default 3; -1 off)\n"
    "  --size-gate [C=]F    drop a blob more than F times larger (or, away from the frame's edges,\n"
    "                       smaller) than a landmark of the class's --size at its range (default 0: off)\n"
    "  --max-frames N       stop after N frames\n"
    "  --realtime           replay raw logs at the recorded pace (default: as fast as possible)\n"
    "  --quiet              no progress or summary on stderr\n"
    "  --lenient            unknown keys in the --calib file are warnings, not errors (a key given\n"
    "                       twice is always an error)\n"
    "record options: --out FILE.cylraw (required), --max-frames N\n"
    "V4L2 options: --format FOURCC --size-px WxH --fps F --buffers N --timeout-ms MS --input N\n"
    "              --fixed-exposure (turn auto exposure, white balance and gain off: colour tables\n"
    "              need fixed exposure and white balance) --set-control NAME=VALUE (repeatable)\n"
    "synthetic options: --frames N --seed S --scene FILE|NAME\n"
    "\n"
    "exit codes: 0 success, 1 failure (message names the file, line, field or device),\n"
    "            2 bad command line, 130 interrupted (outputs closed cleanly)\n";

struct Args {
    std::string cmd, source, table, calib, out = "-", overlay, model = "exact", estimator = "image", edges = "subpixel";
    std::string config, roi, mask;
    std::vector<std::string> sizes, controls, min_area, max_area, merge_gap, size_gate;
    double var_floor_px2 = 0.0;
    double partial_aspect_min = -1.0;   // < 0: libcyl's default
    double partial_area_min = -1.0;     // < 0: libcyl's default
    double partial_offset_max = -1.0;   // < 0: libcyl's default
    double partial_side_max = -1.0;     // < 0: libcyl's default
    double subpixel_rel_sigma = -1.0;   // < 0: libcyl's default
    double missing_part_share = -1.0;   // < 0: libcyl's default
    double side_sigma_rel = -1.0;       // < 0: libcyl's default
    double side_sigma_free = -1.0;      // < 0: libcyl's default
    std::string silhouette_sigma;
    uint64_t max_frames = 0;
    bool show = false, quiet = false, fixed_exposure = false, lenient = false;
    SourceOptions src;
};

[[noreturn]] void usage_error(const std::string &msg)
{
    std::fprintf(stderr, "cyl: %s\n(see cyl --help)\n", msg.c_str());
    std::exit(kExitUsage);
}

uint64_t parse_u64(const std::string &opt, const std::string &v)
{
    char *end = nullptr;
    errno = 0;
    unsigned long long x = std::strtoull(v.c_str(), &end, 10);
    if (v.empty() || *end || errno || v[0] == '-') usage_error(opt + ": expected a whole number, got '" + v + "'");
    return x;
}

double parse_double(const std::string &opt, const std::string &v)
{
    char *end = nullptr;
    double x = std::strtod(v.c_str(), &end);
    if (v.empty() || *end || !(x == x)) usage_error(opt + ": expected a number, got '" + v + "'");
    return x;
}

// a number in [lo, hi], else the usage error "OPT: must be LO..HI (0: ZERO)"
double parse_in_range(const std::string &opt, const std::string &v, double lo, double hi, const char *zero)
{
    const double x = parse_double(opt, v);
    if (!(x >= lo && x <= hi)) {
        char msg[64];
        std::snprintf(msg, sizeof msg, ": must be %g..%g (0: %s)", lo, hi, zero);
        usage_error(opt + msg);
    }
    return x;
}

Args parse(int argc, char **argv)
{
    Args a;
    std::vector<std::string> pos;
    for (int i = 1; i < argc; i++) {
        std::string s = argv[i];
        auto val = [&](const std::string &name) -> std::string {
            if (i + 1 >= argc) usage_error(name + " needs a value");
            return argv[++i];
        };
        if (s == "-h" || s == "--help") { std::fputs(kUsage, stdout); std::exit(0); }
        else if (s == "--list-devices") a.cmd = "devices";
        else if (s == "--list-formats") a.cmd = "formats";
        else if (s == "--list-controls") a.cmd = "controls";
        else if (s == "--table") a.table = val(s);
        else if (s == "--calib") a.calib = val(s);
        else if (s == "--out" || s == "-o") a.out = val(s);
        else if (s == "--model") a.model = val(s);
        else if (s == "--estimator") a.estimator = val(s);
        else if (s == "--edges") a.edges = val(s);
        else if (s == "--silhouette-sigma") a.silhouette_sigma = val(s);
        else if (s == "--size") a.sizes.push_back(val(s));
        else if (s == "--config") a.config = val(s);
        else if (s == "--roi") a.roi = val(s);
        else if (s == "--mask") a.mask = val(s);
        else if (s == "--min-area") a.min_area.push_back(val(s));
        else if (s == "--max-area") a.max_area.push_back(val(s));
        else if (s == "--merge-gap") a.merge_gap.push_back(val(s));
        else if (s == "--size-gate") a.size_gate.push_back(val(s));
        else if (s == "--centroid-var-floor") {
            a.var_floor_px2 = parse_double(s, val(s));
            if (a.var_floor_px2 < 0) usage_error("--centroid-var-floor: must be >= 0 px^2");
        }
        else if (s == "--partial-offset-max") a.partial_offset_max = parse_in_range(s, val(s), 0, 1, "off");
        else if (s == "--partial-side-max") a.partial_side_max = parse_in_range(s, val(s), 0, 2, "off");
        else if (s == "--missing-part-share") a.missing_part_share = parse_in_range(s, val(s), 0, 10, "none");
        else if (s == "--side-sigma") a.side_sigma_rel = parse_in_range(s, val(s), 0, 10, "none");
        else if (s == "--side-sigma-free") a.side_sigma_free = parse_in_range(s, val(s), 0, 1, "every view");
        else if (s == "--subpixel-rel-sigma") a.subpixel_rel_sigma = parse_in_range(s, val(s), 0, 10, "none");
        else if (s == "--partial-area-min") a.partial_area_min = parse_in_range(s, val(s), 0, 1, "off");
        else if (s == "--partial-aspect-min") a.partial_aspect_min = parse_in_range(s, val(s), 0, 2, "off");
        else if (s == "--overlay") {
            a.overlay = val(s);
            const std::string &o = a.overlay;
            const size_t slash = o.find_last_of('/'), dot = o.find_last_of('.');
            const size_t base = slash == std::string::npos ? 0 : slash + 1;   // the file name's first char
            const bool has_ext = dot != std::string::npos && dot > base && dot + 1 < o.size();
            if (has_ext && o.compare(dot, std::string::npos, ".avi") != 0)
                usage_error("--overlay " + o + ": the video is written as MJPG in an .avi file; give FILE.avi, or a "
                            "folder for one PNG per frame");
        }
        else if (s == "--show") a.show = true;
        else if (s == "--max-frames") a.max_frames = parse_u64(s, val(s));
        else if (s == "--realtime") a.src.realtime = true;
        else if (s == "--quiet" || s == "-q") a.quiet = true;
        else if (s == "--lenient") a.lenient = true;
        else if (s == "--device") a.src.v4l2.device = val(s);
        else if (s == "--format") {
            std::string f = val(s);
            if (f.size() != 4) usage_error("--format: a four-character code such as YUYV, got '" + f + "'");
            a.src.v4l2.fourcc = fourcc(f[0], f[1], f[2], f[3]);
        } else if (s == "--size-px") {
            std::string v = val(s);
            unsigned w = 0, h = 0;
            char x = 0;
            if (std::sscanf(v.c_str(), "%u%c%u", &w, &x, &h) != 3 || x != 'x' || !w || !h)
                usage_error("--size-px: expected WIDTHxHEIGHT, got '" + v + "'");
            a.src.v4l2.width = w;
            a.src.v4l2.height = h;
        } else if (s == "--fps") a.src.v4l2.fps = parse_double(s, val(s));
        else if (s == "--buffers") a.src.v4l2.buffers = (unsigned)parse_u64(s, val(s));
        else if (s == "--timeout-ms") a.src.v4l2.timeout_ms = (int)parse_u64(s, val(s));
        else if (s == "--input") a.src.v4l2.input = (int)parse_u64(s, val(s));
        else if (s == "--fixed-exposure") a.fixed_exposure = true;
        else if (s == "--set-control") a.controls.push_back(val(s));
        else if (s == "--frames") a.src.frames = parse_u64(s, val(s));
        else if (s == "--seed") a.src.seed = parse_u64(s, val(s));
        else if (s == "--scene") a.src.scene = val(s);
        else if (s.size() > 1 && s[0] == '-') usage_error("unknown option '" + s + "'");
        else pos.push_back(s);
    }
    size_t k = 0;
    if (a.cmd.empty()) {
        if (pos.empty()) usage_error("no command given");
        a.cmd = pos[k++];
    }
    if (k < pos.size()) a.source = pos[k++];
    if (k < pos.size()) usage_error("unexpected argument '" + pos[k] + "'");
    return a;
}

bool is_synthetic(const std::string &s) { return s == "synthetic" || s.rfind("synthetic:", 0) == 0; }

cyl_colortable load_table(const std::string &path)
{
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error(path + ": cannot open colour table: " + std::strerror(errno));
    std::vector<uint8_t> buf((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    cyl_colortable t;
    cyl_status s = cyl_colortable_load(&t, buf.data(), buf.size());
    if (s != CYL_OK) throw Error(path + ": " + cyl_status_str(s));
    return t;
}

double now_s()
{
    timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void apply_v4l2_options(Source &src, const Args &a, bool quiet)
{
    V4L2Source *v = dynamic_cast<V4L2Source *>(&src);
    if (!v) {
        if (a.fixed_exposure || !a.controls.empty())
            throw Error("--fixed-exposure and --set-control apply to V4L2 sources only");
        return;
    }
    if (a.fixed_exposure)
        for (const std::string &c : v->lock_auto_controls())
            if (!quiet) std::fprintf(stderr, "cyl: %s\n", c.c_str());
    for (const std::string &c : a.controls) {
        size_t eq = c.find('=');
        if (eq == std::string::npos) usage_error("--set-control: expected NAME=VALUE, got '" + c + "'");
        v->set_control(c.substr(0, eq), c.substr(eq + 1));
    }
}

// [CLASS=]VALUE options: one class, or every class without CLASS=.
template <typename F>
void per_class(const std::vector<std::string> &opts, const char *name, const cyl_colortable &table,
               const std::string &table_path, F apply)
{
    for (const std::string &o : opts) {
        size_t eq = o.find('=');
        std::string v = eq == std::string::npos ? o : o.substr(eq + 1);
        double x = parse_double(name, v);
        if (eq == std::string::npos) {
            for (unsigned k = 0; k < CYL_MAX_CLASSES; k++) apply(k, x, v);
            continue;
        }
        int cls = cyl_colortable_find_class(&table, o.substr(0, eq).c_str());
        if (cls < 0) usage_error(std::string(name) + ": class '" + o.substr(0, eq) + "' is not in " + table_path);
        apply((unsigned)cls, x, v);
    }
}

void apply_clutter_options(const Args &a, const cyl_colortable &table, const std::string &table_path, DetectorConfig &cfg)
{
    if (!a.roi.empty()) {
        unsigned x, y, w, h;
        char c1, c2, c3, end;
        if (std::sscanf(a.roi.c_str(), "%u%c%u%c%u%c%u%c", &x, &c1, &y, &c2, &w, &c3, &h, &end) != 7 || c1 != ',' ||
            c2 != ',' || c3 != ',' || !w || !h)
            usage_error("--roi: expected X,Y,W,H in px (W, H > 0), got '" + a.roi + "'");
        cfg.segment.roi = {x, y, w, h};
    }
    if (!a.mask.empty()) load_detector_mask(a.mask, cfg);
    auto whole = [](const char *name, double x, const std::string &v, double lo) {
        if (!(x >= lo && x <= 1e9 && x == std::floor(x)))
            usage_error(std::string(name) + ": expected a whole number >= " + std::to_string((int)lo) + ", got '" + v + "'");
    };
    per_class(a.min_area, "--min-area", table, table_path, [&](unsigned k, double x, const std::string &v) {
        whole("--min-area", x, v, 0);
        cfg.segment.cls[k].min_area = (uint32_t)x;
    });
    per_class(a.max_area, "--max-area", table, table_path, [&](unsigned k, double x, const std::string &v) {
        whole("--max-area", x, v, 0);
        cfg.gate[k].max_area_px = (uint32_t)x;
    });
    per_class(a.merge_gap, "--merge-gap", table, table_path, [&](unsigned k, double x, const std::string &v) {
        whole("--merge-gap", x, v, -1);
        cfg.segment.cls[k].merge_gap_px = (int32_t)x;
    });
    per_class(a.size_gate, "--size-gate", table, table_path, [&](unsigned k, double x, const std::string &v) {
        if (!(x == 0 || (x >= 1 && x <= 100))) usage_error("--size-gate: 0 (off) or a factor >= 1, got '" + v + "'");
        cfg.gate[k].size_gate = x;
    });
}

int cmd_detect(const Args &a)
{
    if (a.source.empty()) usage_error("detect: no SOURCE given");
    cyl_geom_model model;
    cyl_noise_estimator est;
    if (!parse_model(a.model, &model)) usage_error("--model: exact or paper, got '" + a.model + "'");
    if (!parse_estimator(a.estimator, &est)) usage_error("--estimator: image, local, column or uniform, got '" + a.estimator + "'");
    if (a.edges != "subpixel" && a.edges != "table") usage_error("--edges: subpixel or table, got '" + a.edges + "'");
    if (a.show) {  // without a display Qt aborts the process (exit 134) inside cv::imshow
        const char *d = std::getenv("DISPLAY"), *w = std::getenv("WAYLAND_DISPLAY");
        if ((!d || !*d) && (!w || !*w))
            usage_error("--show needs a display (DISPLAY and WAYLAND_DISPLAY are unset); write the overlay "
                        "with --overlay DIR|FILE.avi instead");
    }
    bool synthetic = is_synthetic(a.source);
    std::string table_path = a.table.empty() && synthetic ? cylfe::data_file("synthetic.cylt") : a.table;
    if (table_path.empty()) usage_error("detect: --table is required");
    if (a.calib.empty() && !synthetic) usage_error("detect: --calib is required");

    cyl_colortable table = load_table(table_path);
    DetectorConfig cfg;
    if (!a.config.empty()) load_detector_config(a.config, table, cfg);
    apply_clutter_options(a, table, table_path, cfg);
    cfg.observe.model = model;
    cfg.observe.estimator = est;
    if (a.edges == "table") {   // the blob's own edges, with libcyl's sigmas for them
        const cyl_observe_params d = cyl_observe_params_default();
        cfg.observe.subpixel = 0;
        cfg.observe.silhouette_sigma_u_px = d.silhouette_sigma_u_px;
        cfg.observe.silhouette_sigma_v_px = d.silhouette_sigma_v_px;
        cfg.observe.group_silhouette_sigma_u_px = d.group_silhouette_sigma_u_px;
        cfg.observe.group_silhouette_sigma_v_px = d.group_silhouette_sigma_v_px;
    }
    if (!a.silhouette_sigma.empty()) {
        const size_t comma = a.silhouette_sigma.find(',');
        if (comma == std::string::npos) usage_error("--silhouette-sigma: expected U,V in px, got '" + a.silhouette_sigma + "'");
        const double su = parse_double("--silhouette-sigma", a.silhouette_sigma.substr(0, comma));
        const double sv = parse_double("--silhouette-sigma", a.silhouette_sigma.substr(comma + 1));
        if (!(su >= 0 && sv >= 0 && su < 100 && sv < 100)) usage_error("--silhouette-sigma: each must be 0..100 px");
        cfg.observe.silhouette_sigma_u_px = su;
        cfg.observe.silhouette_sigma_v_px = sv;
    }
    cfg.observe.min_var_px2 = a.var_floor_px2;
    if (a.partial_aspect_min >= 0) cfg.observe.partial_aspect_min = a.partial_aspect_min;
    if (a.partial_area_min >= 0) cfg.observe.partial_area_min = a.partial_area_min;
    if (a.partial_offset_max >= 0) cfg.observe.partial_offset_max = a.partial_offset_max;
    if (a.partial_side_max >= 0) cfg.observe.partial_side_max = a.partial_side_max;
    if (a.subpixel_rel_sigma >= 0) cfg.observe.subpixel_rel_sigma = a.subpixel_rel_sigma;
    if (a.missing_part_share >= 0) cfg.observe.missing_part_share = a.missing_part_share;
    if (a.side_sigma_rel >= 0) cfg.observe.side_sigma_rel = a.side_sigma_rel;
    if (a.side_sigma_free >= 0) cfg.observe.side_sigma_free = a.side_sigma_free;
    cyl_camera cam;
    if (!a.calib.empty()) {
        CameraCalibration cal = load_mounted_camera_calibration(a.calib, a.lenient);
        for (const std::string &w : cal.warnings) std::fprintf(stderr, "cyl: warning: %s\n", w.c_str());
        cam = cal.cam;
    }
    if (synthetic) {
        synth::Scene scene = synth::scene_by_name(a.src.scene.empty() ? "default" : a.src.scene);
        if (a.calib.empty()) cam = synth::to_cyl_camera(scene);
        for (size_t i = 0; i < scene.classes.size() && i < CYL_MAX_CLASSES; i++)
            cfg.observe.size[i] = {scene.landmark_diameter_m, scene.landmark_height_m};
    }
    for (const std::string &s : a.sizes) {
        std::string name;
        cyl_landmark_size size{};
        if (!parse_size_option(s, name, size)) usage_error("--size: expected CLASS=DIAMETER,HEIGHT in m, got '" + s + "'");
        int cls = cyl_colortable_find_class(&table, name.c_str());
        if (cls < 0) {
            std::string msg = "--size: class '";
            msg += name;
            msg += "' is not in ";
            msg += table_path;
            usage_error(msg);
        }
        cfg.observe.size[cls] = size;
    }
    // A class without a size gets confidence 0 on every observation, and a SLAM back end that
    // filters on confidence then uses none of them: say so. (A weak class, NAME~, makes no blobs of
    // its own: its pixels join its class's.)
    // The classes of landmark models are observed as parts of their models (which have sizes).
    const uint32_t grouped = model_classes(cfg);
    for (unsigned k = 0; k < CYL_MAX_CLASSES; k++)
        if (table.name[k][0] && table.weak_of[k] == CYL_CLASS_NONE && !(grouped & (1u << k)) &&
            !(cfg.observe.size[k].diameter_m > 0 && cfg.observe.size[k].height_m > 0))
            std::fprintf(stderr, "cyl: warning: class '%s' has no landmark size (--size %s=D,H): its observations get "
                                 "confidence 0\n", table.name[k], table.name[k]);

    std::unique_ptr<Source> src = open_source(a.source, a.src);
    apply_v4l2_options(*src, a, a.quiet);
    // The calibration holds for the image size it was made at only.
    if (src->info().width != cam.width || src->info().height != cam.height)
        throw Error((a.calib.empty() ? std::string("the camera") : a.calib) + ": calibrated for " +
                    std::to_string(cam.width) + "x" + std::to_string(cam.height) + " px, but " + a.source + " gives " +
                    std::to_string(src->info().width) + "x" + std::to_string(src->info().height) +
                    " px frames: calibrate at this size or capture at the calibrated one (--size-px)");
    Detector det(table, cam, cfg);
    ObservationLog::Header hdr;
    hdr.source = src->info().source.empty() ? a.source : src->info().source;
    hdr.model = model_name(model);
    hdr.estimator = estimator_name(est);
    hdr.table = &table;
    hdr.camera = &cam;
    hdr.model_names = cfg.model_names;
    ObservationLog log(a.out, hdr);

    bool overlay_dir = false;
    cylfe::media::VideoWriter video;
    if (!a.overlay.empty()) {
        std::string o = a.overlay;
        if (o.size() > 4 && o.compare(o.size() - 4, 4, ".avi") == 0) {
            if (!video.open(o, cylfe::media::VideoWriter::fourcc('M', 'J', 'P', 'G'), 15.0,
                            cv::Size((int)src->info().width, (int)src->info().height)))
                throw Error(o + ": cannot open video for writing");
        } else {
            struct stat st;
            if (::stat(o.c_str(), &st) == 0 && !S_ISDIR(st.st_mode))
                throw Error(o + ": --overlay names an existing file that is not a folder");
            if (mkdir(o.c_str(), 0777) != 0 && errno != EEXIST) throw Error(o + ": cannot create folder: " + std::strerror(errno));
            overlay_dir = true;
        }
    }
    Progress progress(!a.quiet && a.out != "-", "detecting", "frames");
    SourceEvent ev;
    uint64_t frames = 0, observations = 0, truncated = 0;
    double t0 = now_s();
    // --max-frames N: the records that follow the N-th frame (its odometry and truth) are kept; the
    // loop stops at the next frame. A live camera stops at the N-th frame itself.
    const bool live = dynamic_cast<V4L2Source *>(src.get()) != nullptr;
    while (!g_interrupted && !(live && a.max_frames && frames >= a.max_frames) && src->next(ev)) {
        if (ev.kind == RecordType::Frame && a.max_frames && frames >= a.max_frames) break;
        switch (ev.kind) {
        case RecordType::Frame: {
            const std::vector<cyl_observation> &obs = det.process(ev.image);
            log.frame(ev.header.seq, ev.header.t_ns, obs, &det.boxes());
            frames++;
            observations += obs.size();
            truncated += det.truncated();
            if (overlay_dir || video.is_open() || a.show) {
                cv::Mat bgr = to_bgr(ev.image);
                draw_overlay(bgr, det, obs);
                if (overlay_dir) {
                    char name[64];
                    std::snprintf(name, sizeof name, "/frame_%06llu.png", (unsigned long long)ev.header.seq);
                    if (!cylfe::media::imwrite(a.overlay + name, bgr)) throw Error(a.overlay + name + ": cannot write image");
                }
                if (video.is_open()) video.write(bgr);
                if (a.show) {
                    cylfe::media::imshow("cyl", bgr);
                    int key = cylfe::media::wait_key(1);
                    if (key == 'q' || key == 27) g_interrupted = 1;
                }
            }
            if ((frames & 15) == 0) progress.update(src->progress(), frames, frames / (now_s() - t0 + 1e-9));
            break;
        }
        case RecordType::Odometry: log.odometry(ev.header.seq, ev.header.t_ns, ev.odometry); break;
        case RecordType::TruthPose: log.truth_pose(ev.header.seq, ev.header.t_ns, ev.truth_pose); break;
        case RecordType::TruthLandmark: log.truth_landmark(ev.truth_landmark); break;
        }
    }
    progress.update(src->progress(), frames, frames / (now_s() - t0 + 1e-9));
    progress.done();
    log.close();
    if (video.is_open()) video.close();
    double dt = now_s() - t0;
    if (!a.quiet)
        std::fprintf(stderr, "cyl detect: %llu frames, %llu observations, %.1f frames/s, %llu dropped by the source%s%s\n",
                     (unsigned long long)frames, (unsigned long long)observations, frames / (dt + 1e-9),
                     (unsigned long long)src->dropped(),
                     truncated ? ", some frames exceeded the run/blob capacity" : "",
                     g_interrupted ? ", interrupted" : "");
    if (auto *r = dynamic_cast<RawLogSource *>(src.get()))
        if (r->truncated()) std::fprintf(stderr, "cyl detect: warning: %s ends with a truncated record (ignored)\n", a.source.c_str());
    return g_interrupted ? kExitInterrupted : kExitOk;
}

int cmd_record(const Args &a)
{
    if (a.source.empty()) usage_error("record: no SOURCE given");
    if (a.out == "-" || a.out.empty()) usage_error("record: --out FILE.cylraw is required");
    std::unique_ptr<Source> src = open_source(a.source, a.src);
    apply_v4l2_options(*src, a, a.quiet);
    StreamInfo info = src->info();
    RawLogWriter w(a.out, info);
    Progress progress(!a.quiet, "recording", "frames");
    SourceEvent ev;
    uint64_t frames = 0;
    double t0 = now_s();
    // --max-frames N: the records that follow the N-th frame (its odometry and truth) are kept; the
    // loop stops at the next frame. A live camera stops at the N-th frame itself.
    const bool live = dynamic_cast<V4L2Source *>(src.get()) != nullptr;
    while (!g_interrupted && !(live && a.max_frames && frames >= a.max_frames) && src->next(ev)) {
        if (ev.kind == RecordType::Frame && a.max_frames && frames >= a.max_frames) break;
        switch (ev.kind) {
        case RecordType::Frame:
            w.frame(ev.header.seq, ev.header.t_ns, ev.data, ev.header.size, ev.header.flags);
            frames++;
            if ((frames & 15) == 0) progress.update(src->progress(), frames, frames / (now_s() - t0 + 1e-9));
            break;
        case RecordType::Odometry: w.odometry(ev.header.seq, ev.header.t_ns, ev.odometry); break;
        case RecordType::TruthPose: w.truth_pose(ev.header.seq, ev.header.t_ns, ev.truth_pose); break;
        case RecordType::TruthLandmark: w.truth_landmark(ev.header.t_ns, ev.truth_landmark); break;
        }
    }
    progress.done();
    w.close();
    if (!a.quiet)
        std::fprintf(stderr, "cyl record: %llu frames (%llu records) to %s, %llu dropped by the source%s\n",
                     (unsigned long long)frames, (unsigned long long)w.records(), a.out.c_str(),
                     (unsigned long long)src->dropped(), g_interrupted ? ", interrupted" : "");
    return g_interrupted ? kExitInterrupted : kExitOk;
}

// `cyl info CAMERA.yaml`: the camera a calibration file gives, as libcyl sees it (cyl/camera.h
// field names and units), one JSON object; every number at full precision.
int info_camera(const Args &a)
{
    CameraCalibration cal = load_camera_calibration(a.source, a.lenient);
    for (const std::string &w : cal.warnings) std::fprintf(stderr, "cyl: warning: %s\n", w.c_str());
    const cyl_camera &c = cal.cam;
    std::printf("{\"file\":%s,\"format\":\"%s\",\"mount_known\":%s,\"intrinsic_cov_known\":%s,"
                "\"mount_sigmas_known\":%s,\"camera\":{\"width\":%u,\"height\":%u",
                json_quote(a.source).c_str(), cal.format.c_str(), cal.mount_known ? "true" : "false",
                cal.intrinsic_cov_known ? "true" : "false", cal.mount_sigmas_known ? "true" : "false", c.width, c.height);
    const std::pair<const char *, double> f[] = {
        {"fx_px", c.fx_px}, {"fy_px", c.fy_px}, {"cx_px", c.cx_px}, {"cy_px", c.cy_px}, {"k1", c.k1}, {"k2", c.k2},
        {"p1", c.p1}, {"p2", c.p2}, {"k3", c.k3}, {"tilt_rad", c.tilt_rad}, {"yaw_rad", c.yaw_rad},
        {"height_m", c.height_m}, {"offset_m", c.offset_m}, {"tilt_sigma_rad", c.tilt_sigma_rad},
        {"yaw_sigma_rad", c.yaw_sigma_rad}, {"height_sigma_m", c.height_sigma_m}, {"offset_sigma_m", c.offset_sigma_m}};
    for (const auto &kv : f) std::printf(",\"%s\":%.17g", kv.first, kv.second);
    std::printf(",\"flags\":%u,\"intr_cov\":[", c.flags);
    for (int i = 0; i < CYL_INTR_COUNT; i++)
        for (int j = 0; j < CYL_INTR_COUNT; j++) std::printf("%s%.17g", i || j ? "," : "", c.intr_cov[i][j]);
    std::printf("]}}\n");
    return kExitOk;
}

int cmd_info(const Args &a)
{
    if (a.source.empty()) usage_error("info: no FILE given");
    const size_t dot = a.source.find_last_of('.');
    const std::string ext = dot == std::string::npos ? "" : a.source.substr(dot);
    if (ext == ".yaml" || ext == ".yml") return info_camera(a);
    RawLogReader r(a.source);
    const StreamInfo &i = r.info();
    std::map<uint32_t, uint64_t> counts;
    RecordHeader h;
    std::vector<uint8_t> p;
    int64_t t_first = 0, t_last = 0;
    uint64_t frames = 0;
    while (r.next(h, p)) {
        counts[(uint32_t)h.type]++;
        if (h.type == RecordType::Frame) {
            if (!frames) t_first = h.t_ns;
            t_last = h.t_ns;
            frames++;
        }
    }
    std::printf("file: %s\nformat: %s %ux%u, stride %u, %u bytes/frame\nsource: %s\nflags:%s%s\n", a.source.c_str(),
                fourcc_str(i.fourcc).c_str(), i.width, i.height, i.stride, i.frame_bytes, i.source.c_str(),
                (i.flags & StreamInfo::kMonotonic) ? " monotonic-clock" : "",
                (i.flags & StreamInfo::kHasTruth) ? " ground-truth" : "");
    std::printf("records: %llu frames, %llu odometry, %llu truth poses, %llu truth landmarks\n",
                (unsigned long long)counts[1], (unsigned long long)counts[2], (unsigned long long)counts[3],
                (unsigned long long)counts[4]);
    if (frames > 1)
        std::printf("duration: %.3f s, %.2f frames/s\n", (double)(t_last - t_first) * 1e-9,
                    (double)(frames - 1) / ((double)(t_last - t_first) * 1e-9));
    if (r.truncated()) std::printf("warning: the last record is truncated (an interrupted recording)\n");
    return kExitOk;
}

int cmd_devices()
{
    std::vector<V4L2DeviceInfo> d = v4l2_list_devices();
    if (d.empty()) std::printf("no V4L2 devices found (/dev/video*)\n");
    for (const auto &x : d)
        std::printf("%-14s %-10s %-28s %-24s %s\n", x.path.c_str(), x.driver.c_str(), x.card.c_str(), x.bus.c_str(),
                    x.capture ? "capture" : "(no capture)");
    return kExitOk;
}

int cmd_formats(const Args &a)
{
    std::string dev = a.source.empty() ? a.src.v4l2.device : a.source;
    for (const auto &f : v4l2_list_formats(dev)) {
        std::printf("%s  %-32s %s", fourcc_str(f.fourcc).c_str(), f.description.c_str(), f.supported ? "libcyl" : "      ");
        if (f.stepwise && f.sizes.size() == 2)
            std::printf("  %ux%u .. %ux%u", f.sizes[0].first, f.sizes[0].second, f.sizes[1].first, f.sizes[1].second);
        else
            for (const auto &s : f.sizes) std::printf("  %ux%u", s.first, s.second);
        std::printf("\n");
    }
    return kExitOk;
}

int cmd_controls(const Args &a)
{
    std::string dev = a.source.empty() ? a.src.v4l2.device : a.source;
    for (const auto &c : v4l2_list_controls(dev)) {
        std::printf("0x%08x %-36s %lld (min %lld max %lld default %lld)%s%s\n", c.id, c.name.c_str(), (long long)c.value,
                    (long long)c.minimum, (long long)c.maximum, (long long)c.default_value, c.read_only ? " read-only" : "",
                    c.inactive ? " inactive" : "");
        for (size_t i = 0; i < c.menu.size(); i++)
            if (!c.menu[i].empty()) std::printf("             %zu: %s\n", i, c.menu[i].c_str());
    }
    return kExitOk;
}

} // namespace

int main(int argc, char **argv)
{
    if (cylfe::print_version_if_asked(argc, argv, "cyl")) return 0;
    Args a = parse(argc, argv);
    struct sigaction sa;
    std::memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
    try {
        if (a.cmd == "detect") return cmd_detect(a);
        if (a.cmd == "record") return cmd_record(a);
        if (a.cmd == "info") return cmd_info(a);
        if (a.cmd == "devices") return cmd_devices();
        if (a.cmd == "formats") return cmd_formats(a);
        if (a.cmd == "controls") return cmd_controls(a);
        usage_error("unknown command '" + a.cmd + "'");
    } catch (const std::exception &e) {
        std::fprintf(stderr, "cyl: error: %s\n", e.what());
        return kExitFailure;
    }
}
