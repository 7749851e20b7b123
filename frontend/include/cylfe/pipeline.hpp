// SPDX-License-Identifier: BSD-3-Clause
// Source -> libcyl -> observations: the detector and the observation log (docs/formats.md).
#pragma once
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "cylfe/rawlog.hpp"

extern "C" {
#include "cyl/colortable.h"
#include "cyl/segment.h"
#include "cyl/observe.h"
}

namespace cylfe {

struct DetectorConfig {
    cyl_segment_params segment = cyl_segment_params_default();
    cyl_observe_params observe = cyl_observe_params_default();
    uint32_t max_runs = 65536;   // run capacity per frame
    uint32_t max_blobs = 4096;   // blob capacity per frame
    uint32_t max_observations = 1024;
};

// Owns the caller-side memory libcyl needs and runs segmentation + observation per frame.
class Detector {
public:
    Detector(const cyl_colortable &table, const cyl_camera &camera, const DetectorConfig &config);
    // Process one frame. Throws Error on invalid frames; capacity truncation is reported by
    // truncated(). The returned vector is valid until the next call.
    const std::vector<cyl_observation> &process(const cyl_image &img);
    const cyl_segmentation &segmentation() const { return seg_; }
    const cyl_colortable &table() const { return table_; }
    const cyl_camera &camera() const { return camera_; }
    const DetectorConfig &config() const { return config_; }
    bool truncated() const { return truncated_; }

private:
    cyl_colortable table_;
    cyl_camera camera_;
    DetectorConfig config_;
    std::vector<uint8_t> seg_mem_, obs_work_;
    cyl_segmentation seg_{};
    std::vector<cyl_observation> obs_;
    bool truncated_ = false;
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
    };
    ObservationLog(const std::string &path, const Header &header);
    ~ObservationLog();
    ObservationLog(const ObservationLog &) = delete;
    ObservationLog &operator=(const ObservationLog &) = delete;

    void frame(uint64_t seq, int64_t t_ns, const std::vector<cyl_observation> &obs);
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
    uint64_t lines_ = 0;
};

// Names used in logs and on the command line.
const char *model_name(cyl_geom_model m);
const char *estimator_name(cyl_noise_estimator e);
bool parse_model(const std::string &s, cyl_geom_model *m);
bool parse_estimator(const std::string &s, cyl_noise_estimator *e);

} // namespace cylfe
