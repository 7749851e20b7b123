// SPDX-License-Identifier: BSD-3-Clause
// cyl-score: how well a colour table finds labelled objects in held-out images (YOLO labels).
// docs/colour-learning.md.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "cylfe/calib.hpp"
#include "cylfe/calibration.hpp"
#include "cylfe/error.hpp"
#include "cylfe/learn.hpp"
#include "cylfe/progress.hpp"
#include "cylfe/version.hpp"

using namespace cylfe;

namespace {

const char *kUsage =
    "usage: cyl-score --table TABLE.cylt --class NAME=LABEL... [options] IMAGE|DIR|LIST...\n"
    "       cyl-score --help | --version\n"
    "\n"
    "Segments every image with the table (cyl_segment, the detector's first stage) and scores the\n"
    "blobs of each class against the image's YOLO boxes of label id LABEL (DIR/labels/STEM.txt for\n"
    "DIR/images/STEM.jpg, or STEM.txt beside the image; an image without a label file has no boxes).\n"
    "Prints per class: recall at IoU >= 0.5 (one blob per box), recall with a blob's centroid in the\n"
    "box, both again for boxes >= 12 px wide, false blobs per image (area >= 20 px, centroid in no\n"
    "box of the class), frames the class covers more than 5% of, and the segmentation time.\n"
    "The last line is one JSON object.\n"
    "\n"
    "options:\n"
    "  --table FILE        colour table (required)\n"
    "  --class NAME=LABEL  table class NAME against label id LABEL (repeatable, required)\n"
    "  --config FILE.yaml  detector config (cyl detect's; cyl-train learn --config-out writes one): the\n"
    "                      segmentation and the gates that need no camera (area, aspect, fill, mask)\n"
    "  --calib FILE.yaml   camera calibration (cyl detect's --calib; frames of its size): score the\n"
    "                      blobs of the detector's observations instead, after every gate including\n"
    "                      the expected-size gate at the measured range (size_m, size_gate in --config)\n"
    "  --min-area N        drop blobs smaller than N px (default: the segmentation default, 9)\n"
    "  --merge-gap N       merge blobs of a class whose boxes are <= N px apart (default 3; -1 off)\n"
    "  --max-area N        drop blobs larger than N px (default: no limit)\n"
    "  --iou F             IoU a blob needs to find a box (default 0.5)\n"
    "  --fp-min-area N     false positives counted from this area, px (default 20)\n"
    "  --overlay DIR       write DIR/STEM.png per image: classified pixels tinted, label boxes white,\n"
    "                      blobs in their class colour, false blobs red (DIR must exist)\n"
    "  --boxes FILE.csv    one row per labelled box: its best IoU, whether it was found, whether a\n"
    "                      blob's centroid lies in it, the share of its pixels in the class, and the\n"
    "                      blob matched to it (box, area, CYL_BLOB_* flags); one row per false blob\n"
    "                      (matched_iou false_blob, its box and the blob columns)\n"
    "  -q, --quiet         no progress\n"
    "\n"
    "exit codes: 0 ok, 1 failed (unreadable image, label or table), 2 bad command line\n";

struct Usage : std::runtime_error {
    using std::runtime_error::runtime_error;
};

double number(const std::string &opt, const std::string &v, double lo, double hi, bool integer)
{
    char *end = nullptr;
    double d = std::strtod(v.c_str(), &end);
    if (v.empty() || *end || !std::isfinite(d) || d < lo || d > hi || (integer && d != std::floor(d)))
        throw Usage(opt + ": expected " + (integer ? "a whole number" : "a number") + " in [" + std::to_string(lo) +
                    ", " + std::to_string(hi) + "], got '" + v + "'");
    return d;
}

} // namespace

int main(int argc, char **argv)
{
    if (print_version_if_asked(argc, argv, "cyl-score")) return 0;
    std::string table;
    std::vector<learn::ClassSpec> classes;
    std::vector<std::string> inputs;
    learn::ScoreOptions so;
    bool quiet = false;
    long min_area = -1, merge_gap = -2, max_area = -1;
    std::string config, calib_path;
    try {
        if (argc < 2) throw Usage("no arguments");
        for (int i = 1; i < argc; i++) {
            std::string s = argv[i];
            auto next = [&]() -> std::string {
                if (i + 1 >= argc) throw Usage(s + ": missing value");
                return argv[++i];
            };
            if (s == "-h" || s == "--help") { std::fputs(kUsage, stdout); return kExitOk; }
            else if (s == "--table") table = next();
            else if (s == "--min-area") min_area = (long)number(s, next(), 0, 1e9, true);
            else if (s == "--merge-gap") merge_gap = (long)number(s, next(), -1, 1000, true);
            else if (s == "--max-area") max_area = (long)number(s, next(), 0, 1e9, true);
            else if (s == "--config") config = next();
            else if (s == "--calib") calib_path = next();
            else if (s == "--iou") so.iou = number(s, next(), 0.01, 1, false);
            else if (s == "--fp-min-area") so.fp_min_area = (uint32_t)number(s, next(), 0, 1e9, true);
            else if (s == "--overlay") so.overlay_dir = next();
            else if (s == "--boxes") so.boxes_csv = next();
            else if (s == "-q" || s == "--quiet") quiet = true;
            else if (s == "--class") {
                std::string v = next();
                size_t eq = v.find('=');
                if (eq == std::string::npos || eq == 0) throw Usage("--class: expected NAME=LABEL, got '" + v + "'");
                learn::ClassSpec c;
                c.name = v.substr(0, eq);
                c.label = (int)number("--class " + c.name, v.substr(eq + 1), 0, 1e6, true);
                classes.push_back(c);
            } else if (!s.empty() && s[0] == '-') throw Usage("unknown argument '" + s + "'");
            else inputs.push_back(s);
        }
        if (table.empty()) throw Usage("--table is required");
        if (classes.empty()) throw Usage("give at least one --class NAME=LABEL");
        if (inputs.empty()) throw Usage("give the images to score");
    } catch (const Usage &e) {
        std::fprintf(stderr, "cyl-score: %s\n(cyl-score --help for usage)\n", e.what());
        return kExitUsage;
    }
    try {
        cyl_colortable t;
        calib::load_table(table, t);
        if (!config.empty()) load_detector_config(config, t, so.detector);
        for (unsigned k = 0; k < CYL_MAX_CLASSES; k++) {
            if (min_area >= 0) so.detector.segment.cls[k].min_area = (uint32_t)min_area;
            if (merge_gap >= -1) so.detector.segment.cls[k].merge_gap_px = (int32_t)merge_gap;
            if (max_area >= 0) so.detector.gate[k].max_area_px = (uint32_t)max_area;
        }
        cyl_camera cam{};
        if (!calib_path.empty()) {
            cam = load_mounted_camera_calibration(calib_path).cam;
            so.camera = &cam;
        }
        std::vector<std::string> images = learn::expand_images(inputs);
        Progress bar(!quiet, "scoring", "images");
        learn::ScoreResult r = learn::score(t, images, classes, so, [&](size_t k, size_t n) {
            bar.update((double)k / (double)n, k, 0.0);
        });
        bar.done();
        std::printf("%zu images, segmentation median %.0f us (%.0f us per megapixel)\n", r.images, r.median_us,
                    r.median_us_per_mpx);
        std::printf("%-12s %6s %9s %9s %11s %9s %11s %9s %8s\n", "class", "boxes", "iou>=.5", "centroid", ">=12px:iou",
                    "centroid", "fp/image", "flooded", "");
        std::string js = "{\"images\": " + std::to_string(r.images) + ", \"median_us\": " + std::to_string(r.median_us) +
                         ", \"median_us_per_mpx\": " + std::to_string(r.median_us_per_mpx) + ", \"classes\": {";
        for (size_t i = 0; i < r.classes.size(); i++) {
            const learn::ClassScore &c = r.classes[i];
            const double fp = r.images ? (double)c.false_blobs / (double)r.images : 0.0;
            std::printf("%-12s %6llu %9.3f %9.3f %11.3f %9.3f %11.2f %9llu\n", c.name.c_str(), (unsigned long long)c.boxes,
                        c.recall_iou(), c.recall_centroid(), c.recall_iou_large(), c.recall_centroid_large(), fp,
                        (unsigned long long)c.flooded_frames);
            char b[512];
            std::snprintf(b, sizeof b,
                          "%s\"%s\": {\"boxes\": %llu, \"boxes_min12px\": %llu, \"recall_iou50\": %.4f, "
                          "\"recall_centroid\": %.4f, \"recall_iou50_min12px\": %.4f, \"recall_centroid_min12px\": %.4f, "
                          "\"fp_per_image\": %.4f, \"flooded_frames\": %llu}",
                          i ? ", " : "", c.name.c_str(), (unsigned long long)c.boxes, (unsigned long long)c.boxes_large,
                          c.recall_iou(), c.recall_centroid(), c.recall_iou_large(), c.recall_centroid_large(), fp,
                          (unsigned long long)c.flooded_frames);
            js += b;
        }
        std::printf("%s}}\n", js.c_str());
        return kExitOk;
    } catch (const std::exception &e) {
        std::fprintf(stderr, "cyl-score: error: %s\n", e.what());
        return kExitFailure;
    }
}
