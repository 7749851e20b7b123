// SPDX-License-Identifier: BSD-3-Clause
// cylfe::learn -- colour classes from labelled images, and scoring a table against labels
// (docs/colour-learning.md):
//   * label files: YOLO txt ("<class> <cx> <cy> <w> <h>", normalised; the format of the
//     RoboCup and FRC image sets and of cyl-train --gui's --save-labels), fractional
//     coordinates kept as they are,
//   * learning: positives = pixels inside a class's boxes, negatives = every other pixel of the
//     training images (plus explicit negative images), through libcyl's cyl_colortable_learn,
//     with a report per class (recall, background claimed, overlaps, warnings),
//   * scoring: segmentation of held-out images against their boxes (recall at IoU >= 0.5 and
//     with the centroid in the box, false blobs per image, frames a class floods, speed).
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "cylfe/calib.hpp"
#include "cylfe/pipeline.hpp"
extern "C" {
#include "cyl/colorlearn.h"
#include "cyl/segment.h"
}

namespace cylfe {
namespace learn {

// One labelled box, in px of its image: [x0, x1) x [y0, y1), fractional.
struct Box {
    int label = 0;        // the label file's class id
    double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    double width() const { return x1 - x0; }
    double height() const { return y1 - y0; }
};

// Read a YOLO label file for an image of width x height px. Strict: a line that is not five
// numbers, a negative class id or a box outside [0, 1] (beyond rounding) is an Error naming the
// file and line. Empty lines are skipped; a missing final newline is fine.
std::vector<Box> read_yolo(const std::string &path, int width, int height);

// Write boxes as a YOLO label file (temporary file + rename).
void write_yolo(const std::string &path, const std::vector<Box> &boxes, int width, int height);

// The label file of an image: DIR/labels/STEM.txt when the image is DIR/images/STEM.EXT (the
// YOLO layout), else STEM.txt beside the image. Returns "" if neither exists.
std::string find_label_file(const std::string &image);

// Image paths from arguments: a directory contributes its image files (jpg, jpeg, png, bmp),
// sorted; a file named *.list or *.txt that is not a label file contributes one path per line
// (relative to the list's folder); anything else is an image.
std::vector<std::string> expand_images(const std::vector<std::string> &args);

// A class to learn: its name in the table and its id in the label files.
struct ClassSpec {
    std::string name;
    int label = 0;
    int index = -1;   // table index (-1: the next free one)
};

struct LearnOptions {
    cyl_learn_params params = cyl_learn_params_default();
    double inset = 0.0;                   // trim this fraction of a box's width/height off each side
    double surround = 0.25;               // each class's surround: the background pixels within this fraction
                                          // of a box's width/height (at least 2 px) around its boxes; 0 = none
                                          // (params.surround_weight says how much of it is taken out)
    bool other_boxes_negative = true;     // boxes of labels not being learned count as background
    std::vector<std::string> negative_images;  // extra background images (every pixel negative)
    double flood_fraction = 0.03;         // warn when a class covers more than this of a training frame
    bool weak = true;                     // give each class a weak class (hysteresis; NAME~ in the table)
    bool weak_from_top = false;           // place weak classes at the highest free indices (else lowest)
    std::vector<double> gains{0.8, 1.0, 1.25};  // every training pixel counted at each of these exposure gains
                                          // (cyl_colorhist_add_scaled: photometric augmentation)
    std::vector<double> colour_temperatures{0.0};  // ... and at each of these light colours: t gives red gain
                                          // 1 + t, blue gain 1 / (1 + t) (warmer for t > 0; -0.5 < t <= 1)
    std::vector<double> white_lifts{0.0, 16.0};  // ... and with each of these white lights added, levels per channel
                                          // (a highlight: brighter and paler; cyl_colorhist_add_light)
};

struct ClassReport {
    std::string name;
    unsigned index = 0;
    unsigned weak_index = CYL_CLASS_NONE;
    uint64_t positive_px = 0, boxes = 0;
    cyl_learn_report r{};
    double aspect_min = 0.0, aspect_max = 0.0;  // width/height of its boxes away from the frame's edges
    double worst_frame_share = 0.0;       // largest share of a training frame the class covers
    std::string worst_frame;
    std::vector<std::string> warnings;
    // Weak blobs alone (choose_weak_alone): what the class's training images said. Not evaluated
    // when no detector config was written.
    struct WeakAlone {
        bool evaluated = false;
        uint32_t area_px = 0;             // weak_alone_min_area chosen for the config (0: off)
        uint32_t tried_area_px = 0;       // the area tried
        uint64_t found_off = 0, found_on = 0;   // training boxes found at IoU >= 0.5 without / with it
        double fp_off = 0.0, fp_on = 0.0;       // false blobs per training image without / with it
    } weak_alone;
};

struct LearnResult {
    std::vector<ClassReport> classes;
    uint64_t negative_px = 0;
    size_t images = 0;
};

// A training frame with its boxes (frame.label names it in messages).
struct LabelledFrame {
    calib::Frame frame;
    std::vector<Box> boxes;
};

// Learn the classes into t (other classes of t stay). progress(i, n) is called per image.
LearnResult learn_from_labels(cyl_colortable &t, const std::vector<std::string> &images,
                              const std::vector<ClassSpec> &classes, const LearnOptions &o,
                              const std::function<void(size_t, size_t)> &progress = nullptr);

// The same from frames in memory (cyl-train --gui).
LearnResult learn_from_frames(cyl_colortable &t, const std::vector<LabelledFrame> &frames,
                              const std::vector<ClassSpec> &classes, const LearnOptions &o);

// Weak blobs alone, per class, from the training images (docs/colour-learning.md). Each class of
// r is scored (score() below, cfg's camera-free gates) on the images it was learned from, with
// cfg's weak_alone_min_area 0 and area_px: it keeps area_px when that finds more of its boxes at
// IoU >= 0.5 and its false blobs stay at most max_fp_per_image, else 0. Writes the choice into
// cfg.segment.cls[index].weak_alone_min_area and the figures into r.classes[].weak_alone.
constexpr uint32_t kWeakAloneAreaPx = 700;           // chosen on the tuning data (docs/colour-learning.md)
constexpr double kWeakAloneMaxFalsePerImage = 1.0;   // the real-image benchmark's false-blob limit
void choose_weak_alone(const cyl_colortable &t, const std::vector<std::string> &images,
                       const std::vector<ClassSpec> &classes, uint32_t area_px, double max_fp_per_image,
                       DetectorConfig &cfg, LearnResult &r);

// Human-readable report (several lines) and one JSON object.
std::string report_text(const LearnResult &r, const cyl_colortable &t);
std::string report_json(const LearnResult &r, const cyl_colortable &t);

// ---- scoring ------------------------------------------------------------------------------------

struct ScoreOptions {
    DetectorConfig detector;        // segmentation settings and the gates that need no camera
    const cyl_camera *camera = nullptr;  // if set (frames of its size): the blobs scored are those of the
                                    // detector's observations (cylfe::Detector: the size gate at the measured
                                    // range too, with the config's sizes); else every blob the gates keep
    double iou = 0.5;               // a box is found when a blob's box overlaps it this much
    uint32_t fp_min_area = 20;      // false positives counted from this area, px
    double min_box_px = 12;         // the "large boxes" figures: boxes at least this wide, px
    double flood_fraction = 0.05;   // a frame is flooded when a class covers more than this
    std::string boxes_csv;          // if set: one CSV row per labelled box (how it was found)
    std::string overlay_dir;        // if set: one PNG per image (classified pixels tinted, label boxes
                                    // white, found blobs in the class colour, false blobs red)
};

struct ClassScore {
    std::string name;
    int label = 0;
    uint64_t boxes = 0, boxes_large = 0;
    uint64_t found_iou = 0, found_iou_large = 0;        // one blob per box (greedy by IoU)
    uint64_t found_centroid = 0, found_centroid_large = 0;
    uint64_t false_blobs = 0;                           // area >= fp_min_area, centroid in no box
    uint64_t flooded_frames = 0;
    double recall_iou() const { return boxes ? (double)found_iou / boxes : 0.0; }
    double recall_iou_large() const { return boxes_large ? (double)found_iou_large / boxes_large : 0.0; }
    double recall_centroid() const { return boxes ? (double)found_centroid / boxes : 0.0; }
    double recall_centroid_large() const { return boxes_large ? (double)found_centroid_large / boxes_large : 0.0; }
};

struct ScoreResult {
    std::vector<ClassScore> classes;
    size_t images = 0;
    double median_us = 0.0;         // cyl_segment per image, median
    double median_us_per_mpx = 0.0;
};

ScoreResult score(const cyl_colortable &t, const std::vector<std::string> &images,
                  const std::vector<ClassSpec> &classes, const ScoreOptions &o,
                  const std::function<void(size_t, size_t)> &progress = nullptr);

} // namespace learn
} // namespace cylfe
