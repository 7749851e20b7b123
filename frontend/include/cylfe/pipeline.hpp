// SPDX-License-Identifier: BSD-3-Clause
// Source -> libcyl -> observations: the detector and the observation log (docs/formats.md).
#pragma once
#include <array>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "cylfe/rawlog.hpp"

extern "C" {
#include "cyl/colortable.h"
#include "cyl/segment.h"
#include "cyl/observe.h"
#include "cyl/landmark.h"
}

namespace cylfe {

// Clutter rejection after segmentation, per class (the segmentation's own rules -- region of
// interest, minimum area, merging -- live in DetectorConfig::segment).
struct ClassGate {
    uint32_t max_area_px = 0;   // drop blobs larger than this, px (0: no limit)
    double aspect_min = 0.0;    // drop blobs whose box width/height is below this (0: off) ...
    double aspect_max = 0.0;    // ... or above this (0: off). A blob cut by the frame's left or right edge
                                // (width a lower bound) meets only the upper limit, one cut at the top or
                                // bottom (height a lower bound) only the lower, one cut both ways neither
    double min_fill = 0.0;      // drop blobs covering less than this share of their box (0: off)
    double size_gate = 0.0;     // drop an observation whose blob is more than size_gate times larger,
                                // or (untouched by the frame's edges) smaller, than a landmark of the
                                // class at its measured range in both width and height (0: off)
};

struct DetectorConfig {
    cyl_segment_params segment = cyl_segment_params_default();
    cyl_observe_params observe = cyl_observe_params_default_frame();  // image and table set per frame
    ClassGate gate[CYL_MAX_CLASSES];
    cyl_split_params split = cyl_split_params_default();  // blobs cut at a waist (two landmarks touching)
    std::vector<uint8_t> mask;   // width*height bytes, 0 = not a landmark (the robot's own body); empty: none
    uint32_t mask_width = 0, mask_height = 0;
    uint32_t max_runs = 65536;   // run capacity per frame
    uint32_t max_blobs = 4096;   // blob capacity per frame
    uint32_t max_observations = 1024;
    // Landmarks of several bands (the config's `landmarks:` section, cyl/landmark.h). When there
    // are models, the blobs of their classes are grouped and observed as landmarks
    // (cyl_observe_groups); the blobs of other classes are observed one by one as before.
    std::vector<cyl_landmark_model> models;
    std::vector<std::string> model_names;   // one per model
    double plane_height_m = 0.0;            // height above the floor of the plane the camera's
                                            // mount_height_m is counted from, m
    cyl_group_params group = cyl_group_params_default();
};

// The classes some landmark model uses, as a bit mask (bit k: class k).
uint32_t model_classes(const DetectorConfig &cfg);

// Cut the blobs of seg at their waists by cfg.split (cyl_segment_split, which does nothing when no
// class has a waist ratio); work grows as needed. Returns the status (CYL_TRUNCATED: blob capacity).
cyl_status split_blobs(const DetectorConfig &cfg, cyl_segmentation &seg, std::vector<uint8_t> &work);

// The waist cut's axes by name, "rows", "columns" or "both" (CYL_SPLIT_* bits; 0 for another
// name), and back.
unsigned split_axes_from_name(const std::string &name);
const char *split_axes_name(unsigned axes);

// The gates that need no camera (area, aspect, fill, mask) on one blob of a frame.
bool blob_passes(const DetectorConfig &cfg, const cyl_blob &b, uint32_t frame_width, uint32_t frame_height);
// The mask's verdict on a point of a frame (true: keep; no mask, or one of another size: true).
bool mask_keeps(const DetectorConfig &cfg, double x_px, double y_px, uint32_t frame_width, uint32_t frame_height);

// Read a detector config file (YAML, docs/formats.md) into cfg, naming the class indices through
// table. Unknown keys and classes are errors naming the line; the mask path is relative to the
// file's folder.
void load_detector_config(const std::string &path, const cyl_colortable &table, DetectorConfig &cfg);

// A landmark size option, "NAME=DIAMETER,HEIGHT" in m (each in (0, 1000]): false when malformed.
bool parse_size_option(const std::string &spec, std::string &name, cyl_landmark_size &size);

// The detector config file's text for cfg (what differs from the defaults), for the classes of table.
std::string detector_config_yaml(const DetectorConfig &cfg, const cyl_colortable &table, const std::string &comment);

// Load a mask image (any OpenCV-readable format; non-zero = keep) into cfg.
void load_detector_mask(const std::string &path, DetectorConfig &cfg);

// A JSON string literal for s (quotes included, escaped as the observation log writes it).
std::string json_quote(const std::string &s);

// Owns the caller-side memory libcyl needs and runs segmentation + observation per frame.
class Detector {
public:
    Detector(const cyl_colortable &table, const cyl_camera &camera, const DetectorConfig &config);
    // Process one frame. Throws Error on invalid frames; capacity truncation is reported by
    // truncated(). The returned vector is valid until the next call.
    const std::vector<cyl_observation> &process(const cyl_image &img);
    const std::vector<cyl_observation> &last_observations() const { return obs_; }
    const cyl_segmentation &segmentation() const { return seg_; }
    const cyl_colortable &table() const { return table_; }
    const cyl_camera &camera() const { return camera_; }
    const DetectorConfig &config() const { return config_; }
    bool truncated() const { return truncated_; }
    uint64_t rejected() const { return rejected_; }   // observations the gates dropped so far
    // The box of each observation of the last frame (x0, y0, x1, y1, px inclusive): its blob's, or
    // for a grouped landmark the union of its blobs'.
    const std::vector<std::array<uint16_t, 4>> &boxes() const { return boxes_; }
    // The blobs of each observation of the last frame (indices in segmentation().blobs, CYL_NONE
    // for none): its blob, or a grouped landmark's blobs band by band.
    const std::vector<std::array<uint32_t, CYL_MODEL_MAX_BANDS>> &members() const { return members_; }

private:
    cyl_colortable table_;
    cyl_camera camera_;
    DetectorConfig config_;
    std::vector<uint8_t> seg_mem_, obs_work_, split_work_;
    cyl_segmentation seg_{};
    std::vector<cyl_observation> obs_;
    std::vector<std::array<uint16_t, 4>> boxes_;
    std::vector<std::array<uint32_t, CYL_MODEL_MAX_BANDS>> members_;
    std::vector<uint8_t> group_work_;
    std::vector<cyl_group> groups_;
    std::vector<uint32_t> group_of_blob_;
    bool truncated_ = false;
    uint64_t rejected_ = 0;
};

// JSON Lines observation log. path "-" writes to stdout; otherwise it writes "<path>.part"
// and renames it on close() -- over a regular file only: a device node or FIFO is written
// directly, a symlink is written through (cylfe/output_file.hpp). Every event is flushed, so
// an interrupted run keeps every complete line.
class ObservationLog {
public:
    struct Header {
        std::string source, model, estimator;
        const cyl_colortable *table = nullptr;
        const cyl_camera *camera = nullptr;
        std::vector<std::string> model_names;   // the detector's landmark models, if any
    };
    ObservationLog(const std::string &path, const Header &header);
    ~ObservationLog();
    ObservationLog(const ObservationLog &) = delete;
    ObservationLog &operator=(const ObservationLog &) = delete;

    // boxes: each observation's box (Detector::boxes()), or null
    void frame(uint64_t seq, int64_t t_ns, const std::vector<cyl_observation> &obs,
               const std::vector<std::array<uint16_t, 4>> *boxes = nullptr);
    void odometry(uint64_t seq, int64_t t_ns, const Odometry &o);
    void truth_pose(uint64_t seq, int64_t t_ns, const TruthPose &p);
    void truth_landmark(const TruthLandmark &l);
    void close();
    uint64_t lines() const { return lines_; }

private:
    void write(const std::string &line);
    std::string path_, part_;  // part_: where the bytes go (plan_.write_to)
    OutputPlan plan_;
    FILE *f_ = nullptr;
    bool is_stdout_ = false;
    const cyl_colortable *table_ = nullptr;
    std::vector<std::string> model_names_;
    uint64_t lines_ = 0;
};

// Names used in logs and on the command line.
const char *model_name(cyl_geom_model m);
const char *estimator_name(cyl_noise_estimator e);
bool parse_model(const std::string &s, cyl_geom_model *m);
bool parse_estimator(const std::string &s, cyl_noise_estimator *e);

} // namespace cylfe
