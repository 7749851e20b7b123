// SPDX-License-Identifier: BSD-3-Clause
// cyl-render: render a synthetic drive (frames, odometry, ground truth) into a raw frame log
// (*.cylraw, docs/formats.md); also writes scene files, the scene's colour table and camera.
#include "cylfe/version.hpp"
#include "cylfe/error.hpp"
#include "cylfe/progress.hpp"
#include "cylfe/rawlog.hpp"
#include "cylfe/synth.hpp"
#include "cylfe/synth_experiments.hpp"
#if __has_include("cylfe/calibration.hpp")
#include "cylfe/calibration.hpp"
#define CYL_RENDER_HAVE_CALIB 1
#endif

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <sys/stat.h>

#include "cylfe/media.hpp"
#include <opencv2/imgproc.hpp>

using namespace cylfe;

namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

void usage(FILE *f)
{
    std::fprintf(f,
        "usage: cyl-render [options]\n"
        "Render a synthetic drive of the robot through a scene of cylinder landmarks into a raw\n"
        "frame log (YUYV frames, odometry with covariance, true poses and landmarks).\n"
        "\n"
        "  -o, --output PATH       raw log to write (default drive.cylraw in the current directory)\n"
        "  -n, --frames N          number of frames (default 1000)\n"
        "  -s, --seed N            random seed: noise, odometry, exposure (default 7)\n"
        "  -S, --scene NAME|PATH   'default', 'hard' or 'multiband' (striped cones and colour-coded\n"
        "                          cylinders) (built in), 'empty', or a scene file (YAML/JSON,\n"
        "                          docs/synthetic.md) (default: default)\n"
        "      --samples N         override the scene's supersampling (N x N per pixel, 1..4)\n"
        "      --calib-error       render with a camera whose calibration differs from the scene's\n"
        "                          by an error drawn once from the scene's sigmas (seeded); the\n"
        "                          scene's camera (--write-camera) is then the imperfect calibration\n"
        "      --write-scene PATH  write the scene as a scene file and exit (a template to edit)\n"
        "      --write-table PATH  train a colour table for the scene's colours on rendered\n"
        "                          frames (libcyl CYLT file) and exit\n"
        "      --write-camera PATH write the scene camera as a calibration YAML and exit\n"
        "      --labels DIR        also write every frame as DIR/images/frame_NNNNNN.png with its\n"
        "                          landmarks' visible boxes as YOLO labels (DIR/labels/, class id =\n"
        "                          colour class; boxes of >= 12 visible px) and DIR/truth.csv\n"
        "                          (frame, landmark id, class, box, px count); DIR must exist\n"
        "  -q, --quiet             no progress bar\n"
        "  -h, --help              this help\n"
        "      --version           the version\n"
        "\n"
        "Outputs: a regular file (or a new path) is written as PATH.part and renamed at the end; a\n"
        "device node or FIFO is written in place, a symbolic link through to its file; a dangling\n"
        "link is refused.\n"
        "Exit codes: 0 ok, 1 failure, 2 bad command line, 130 interrupted (the complete records\n"
        "written so far stay in PATH.part).\n");
}

bool parse_u64(const char *s, uint64_t &v)
{
    char *end = nullptr;
    errno = 0;
    unsigned long long x = std::strtoull(s, &end, 10);
    if (errno || !end || *end || s[0] == '-' || !*s) return false;
    v = x;
    return true;
}

// One frame as an image file with its landmarks' visible boxes (YOLO) and truth rows.
void write_labelled_frame(const std::string &dir, uint64_t k, const cyl_image &img, const synth::Scene &scene,
                          const std::vector<int32_t> &label, std::string &truth_csv)
{
    char stem[32];
    std::snprintf(stem, sizeof stem, "frame_%06llu", (unsigned long long)k);
    const int W = (int)img.width, H = (int)img.height;
    cv::Mat yuyv(H, W, CV_8UC2, const_cast<uint8_t *>(img.plane[0]), img.stride[0]), bgr;
    cv::cvtColor(yuyv, bgr, cv::COLOR_YUV2BGR_YUYV);
    const std::string png = dir + "/images/" + stem + ".png";
    if (!cylfe::media::imwrite(png, bgr)) throw Error(png + ": cannot write image");
    struct Bx { int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1; long n = 0; };
    std::vector<Bx> bx(scene.cylinders.size());
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            int32_t l = label[(size_t)y * W + x];
            if (l < 0) continue;
            Bx &b = bx[(size_t)l];
            b.x0 = std::min(b.x0, x); b.x1 = std::max(b.x1, x);
            b.y0 = std::min(b.y0, y); b.y1 = std::max(b.y1, y);
            b.n++;
        }
    std::string yolo;
    char line[160];
    for (size_t i = 0; i < bx.size(); i++) {
        const Bx &b = bx[i];
        const synth::Cylinder &c = scene.cylinders[i];
        if (b.n < 12 || c.cls < 0) continue;
        std::snprintf(line, sizeof line, "%d %.6f %.6f %.6f %.6f\n", c.cls, (b.x0 + b.x1 + 1) / 2.0 / W,
                      (b.y0 + b.y1 + 1) / 2.0 / H, (b.x1 - b.x0 + 1.0) / W, (b.y1 - b.y0 + 1.0) / H);
        yolo += line;
        std::snprintf(line, sizeof line, "%llu,%u,%d,%d,%d,%d,%d,%ld\n", (unsigned long long)k, c.id, c.cls, b.x0, b.y0,
                      b.x1 + 1, b.y1 + 1, b.n);
        truth_csv += line;
    }
    cylfe::write_file_atomic(dir + "/labels/" + stem + ".txt", yolo);
}

} // namespace

int main(int argc, char **argv)
{
    if (cylfe::print_version_if_asked(argc, argv, "cyl-render")) return 0;
    std::string out = "drive.cylraw", scene_name = "default", write_scene, write_table, write_camera, labels_dir;
    uint64_t frames = 1000, seed = 7, samples = 0;
    bool quiet = false, calib_error = false;
    for (int i = 1; i < argc; i++) {
        std::string a = argv[i];
        auto val = [&](const char *name) -> const char * {
            if (i + 1 >= argc) {
                std::fprintf(stderr, "cyl-render: %s needs a value (see --help)\n", name);
                std::exit(kExitUsage);
            }
            return argv[++i];
        };
        if (a == "-h" || a == "--help") { usage(stdout); return kExitOk; }
        else if (a == "-o" || a == "--output") out = val("--output");
        else if (a == "-S" || a == "--scene") scene_name = val("--scene");
        else if (a == "--write-scene") write_scene = val("--write-scene");
        else if (a == "--write-table") write_table = val("--write-table");
        else if (a == "--write-camera") write_camera = val("--write-camera");
        else if (a == "--labels") labels_dir = val("--labels");
        else if (a == "-q" || a == "--quiet") quiet = true;
        else if (a == "--calib-error") calib_error = true;
        else if (a == "-n" || a == "--frames" || a == "-s" || a == "--seed" || a == "--samples") {
            const char *v = val(a.c_str());
            uint64_t x;
            if (!parse_u64(v, x)) {
                std::fprintf(stderr, "cyl-render: %s: '%s' is not a non-negative integer\n", a.c_str(), v);
                return kExitUsage;
            }
            if (a == "-n" || a == "--frames") frames = x;
            else if (a == "--samples") samples = x;
            else seed = x;
        } else {
            std::fprintf(stderr, "cyl-render: unknown option '%s' (see --help)\n", a.c_str());
            return kExitUsage;
        }
    }
    if (frames == 0 || frames > 10000000) {
        std::fprintf(stderr, "cyl-render: --frames must be 1..10000000\n");
        return kExitUsage;
    }
    if (samples > 4) {
        std::fprintf(stderr, "cyl-render: --samples must be 1..4\n");
        return kExitUsage;
    }
    try {
        synth::Scene scene = synth::scene_by_name(scene_name);
        if (samples) scene.imaging.samples = (uint32_t)samples;
        if (!write_scene.empty()) {
            synth::save_scene(write_scene, scene);
            std::fprintf(stderr, "cyl-render: wrote scene %s\n", write_scene.c_str());
            return kExitOk;
        }
        if (!write_table.empty()) {
            cyl_colortable t;
            std::string log;
            synth::train_colortable(scene, &t, seed, &log);
            std::vector<uint8_t> buf(CYL_TABLE_FILE_MAX_SIZE);
            size_t n = 0;
            check(cyl_colortable_save(&t, buf.data(), buf.size(), &n), "cyl_colortable_save");
            cylfe::write_file_atomic(write_table, std::string(buf.begin(), buf.begin() + (std::ptrdiff_t)n));
            if (!quiet) std::fputs(log.c_str(), stderr);
            std::fprintf(stderr, "cyl-render: wrote colour table %s (%zu classes)\n", write_table.c_str(),
                         scene.classes.size());
            return kExitOk;
        }
        if (!write_camera.empty()) {
#ifdef CYL_RENDER_HAVE_CALIB
            cyl_camera cam = synth::to_cyl_camera(scene);
            save_camera_calibration(write_camera, cam);
            std::fprintf(stderr, "cyl-render: wrote camera %s\n", write_camera.c_str());
            return kExitOk;
#else
            std::fprintf(stderr, "cyl-render: built without calibration support\n");
            return kExitFailure;
#endif
        }
        std::signal(SIGINT, on_signal);
        std::signal(SIGTERM, on_signal);
        if (calib_error) {
            synth::CameraModel t = synth::perturb_camera(scene.camera, scene.sigmas, seed);
            std::fprintf(stderr, "cyl-render: true camera = calibration + error: fx %+.3f fy %+.3f cx %+.3f cy %+.3f px, "
                         "tilt %+.4f yaw %+.4f deg, height %+.5f offset %+.5f m\n", t.fx - scene.camera.fx,
                         t.fy - scene.camera.fy, t.cx - scene.camera.cx, t.cy - scene.camera.cy,
                         (t.tilt_rad - scene.camera.tilt_rad) * 57.29577951308232, (t.yaw_rad - scene.camera.yaw_rad) * 57.29577951308232,
                         t.height_floor_m - scene.camera.height_floor_m, t.offset_m - scene.camera.offset_m);
            scene.camera = t;
        }
        synth::SyntheticSource src(scene, (uint32_t)frames, seed);
        std::string truth_csv;
        if (!labels_dir.empty()) {
            struct stat st;
            if (::stat(labels_dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
                throw Error(labels_dir + ": --labels needs an existing folder");
            for (const char *sub : {"/images", "/labels"})
                if (mkdir((labels_dir + sub).c_str(), 0777) != 0 && errno != EEXIST)
                    throw Error(labels_dir + sub + ": cannot create folder: " + std::strerror(errno));
            src.set_labels(true);
            truth_csv = "frame,landmark_id,class,x0_px,y0_px,x1_px,y1_px,visible_px\n";
        }
        RawLogWriter w(out, src.info());
        SourceEvent ev;
        auto t0 = std::chrono::steady_clock::now();
        uint64_t nframes = 0;
        cylfe::Progress progress(!quiet, "rendering", "frames");
        while (!g_stop && src.next(ev)) {
            switch (ev.kind) {
            case RecordType::Frame:
                w.frame(ev.header.seq, ev.header.t_ns, ev.data, ev.header.size);
                if (!labels_dir.empty()) write_labelled_frame(labels_dir, nframes, ev.image, scene, src.labels(), truth_csv);
                nframes++;
                break;
            case RecordType::Odometry: w.odometry(ev.header.seq, ev.header.t_ns, ev.odometry); break;
            case RecordType::TruthPose: w.truth_pose(ev.header.seq, ev.header.t_ns, ev.truth_pose); break;
            case RecordType::TruthLandmark: w.truth_landmark(ev.header.t_ns, ev.truth_landmark); break;
            }
            if (ev.kind == RecordType::Frame) {
                double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
                progress.update(src.progress(), nframes, nframes / (el + 1e-9));
            }
        }
        if (!g_stop) {
            double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            progress.update(1.0, nframes, nframes / (el + 1e-9));
        }
        progress.done();
        if (g_stop) {
            std::fprintf(stderr, "cyl-render: interrupted after %llu frames; complete records are in %s\n",
                         (unsigned long long)nframes, w.written_to().c_str());
            return kExitInterrupted;
        }
        w.close();
        if (!labels_dir.empty()) cylfe::write_file_atomic(labels_dir + "/truth.csv", truth_csv);
        double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::fprintf(stderr, "cyl-render: wrote %s: %llu frames %ux%u YUYV, %llu records, %.1f s (%.1f ms/frame)\n",
                     out.c_str(), (unsigned long long)nframes, src.info().width, src.info().height,
                     (unsigned long long)w.records(), el, 1000 * el / std::max<uint64_t>(1, nframes));
    } catch (const std::exception &e) {
        std::fprintf(stderr, "\ncyl-render: %s\n", e.what());
        return kExitFailure;
    }
    return kExitOk;
}
