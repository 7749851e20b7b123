// SPDX-License-Identifier: BSD-3-Clause
// The paper's consistency experiments on the synthetic camera (docs/synthetic.md):
// Tables 1-3 (centroid variance estimators against frame-to-frame variance), Tables 6-7 (range
// and bearing errors against their sigmas with calibration errors drawn per run), the
// landmark-confidence check, and the colour table trained on rendered frames.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "cylfe/synth.hpp"

extern "C" {
#include "cyl/colortable.h"
#include "cyl/segment.h"
#include "cyl/observe.h"
}

namespace cylfe {
namespace synth {

// Train one class per scene class on rendered views of the scene's landmarks (libcyl's
// cyl_colortable_train, several ranges, bearings and exposures). log (optional) receives one
// line per training image. params: NULL = libcyl's defaults with min_bin_fraction 0.02 and
// uv_margin 1 (docs/synthetic.md says why).
void train_colortable(const Scene &scene, cyl_colortable *t, uint64_t seed, std::string *log = nullptr,
                      const cyl_train_params *params = nullptr);

// Segmentation + observation with caller-owned libcyl memory.
class Detect {
public:
    Detect(const cyl_colortable &t, const Scene &s);
    // Segment a YUYV frame of the scene's size.
    void segment(const uint8_t *yuyv);
    // Observations with camera cam (estimator as given).
    const std::vector<cyl_observation> &observe(const cyl_camera &cam, cyl_noise_estimator est);
    const cyl_segmentation &seg() const { return seg_; }
    const cyl_image &image() const { return img_; }   // the last frame segmented
    cyl_segment_params seg_params;
    cyl_observe_params obs_params;

private:
    const cyl_colortable *t_;
    uint32_t w_, h_;
    std::vector<uint8_t> mem_, work_;
    cyl_segmentation seg_{};
    cyl_image img_{};
    std::vector<cyl_observation> obs_;
};

// ---- Tables 1-3 -----------------------------------------------------------------------------
constexpr int kEstimators = CYL_NOISE_IMAGE + 1;
struct VarianceRow {
    std::string label;          // "1.0 m", "occluded 1.6 m", ...
    double range_m = 0;
    uint32_t frames = 0, detected = 0;
    double mean_area = 0;
    double actual_x = 0, actual_y = 0;      // measured variance of the centroid over the frames, px^2
    // mean estimator output, indexed by cyl_noise_estimator (uniform, column, local, image), px^2
    double est_x[kEstimators] = {0, 0, 0, 0};
    double est_y[kEstimators] = {0, 0, 0, 0};
};
struct VarianceConfig {
    std::vector<double> ranges_m{1.0, 1.6, 2.4, 3.4};
    bool occluded = true;       // add the partially occluded landmark (Table 2)
    double occluded_range_m = 1.6;
    uint32_t frames = 400;
    uint64_t seed = 1;
};
std::vector<VarianceRow> run_variance_tables(const Scene &base, const cyl_colortable &t, const VarianceConfig &c);

// ---- Tables 6-7 -----------------------------------------------------------------------------
struct RbSample {
    uint32_t run = 0;
    double true_range_m = 0, true_bearing_rad = 0;   // visible-face point (observe.h's claim)
    double axis_range_m = 0, axis_bearing_rad = 0;   // the landmark's axis: the truth
    double range_m = 0, bearing_rad = 0;             // measured
    double cov_rr = 0, cov_rb = 0, cov_bb = 0;
    double du_centre_px = 0, dv_centre_px = 0;       // blob centroid - projection of the landmark centre
    double du_point_px = 0, dv_point_px = 0;         // measurement point (centroid less the modelled
                                                     // silhouette bias) - projection of the centre
    double bias_u_px = 0, bias_v_px = 0;             // the modelled silhouette bias taken out
    double var_centroid_u = 0, var_centroid_v = 0;   // the estimator's centroid variance, px^2
    double var_u = 0, var_v = 0;
    double confidence = 0;
};
struct RbConfig {
    uint32_t runs = 500;            // calibration error drawn once per run
    uint32_t landmarks_per_run = 3; // landmarks in the run's frame
    double range_min_m = 0.8, range_max_m = 4.0;
    bool calibration_error = true;  // false: pixel-noise-only (estimator camera exact, sigmas 0)
    uint64_t seed = 7;
    cyl_noise_estimator estimator = CYL_NOISE_IMAGE;  // the frontend's default
};
std::vector<RbSample> run_range_bearing(const Scene &base, const cyl_colortable &t, const RbConfig &c);

struct RbStats {
    size_t n = 0;
    double range_frac1 = 0, range_frac2 = 0, bearing_frac1 = 0, bearing_frac2 = 0;
    double mean_nees = 0;
    double mean_range_err = 0, mean_bearing_err = 0;  // m, rad
    double rms_range_z = 0, rms_bearing_z = 0;
};
// Errors against the landmark's axis (its true position: the default) or against the visible
// face point at the centroid height (what libcyl's observe.h says the range measures).
RbStats rb_stats(const std::vector<RbSample> &s, bool against_face = false);

// ---- confidence -----------------------------------------------------------------------------
struct ConfidenceResult {
    std::vector<double> landmark, clutter;  // confidences of uncut, unoccluded observations
    std::vector<double> landmark_u;         // their centroid columns, px
    // eq. 7 with the paper's expected width fx D / depth, for comparison with libcyl's
    // expectation (cyl_landmark_expected_size: obliquity, lens and the slant under camera tilt)
    std::vector<double> landmark_plain, clutter_plain;
    double landmark_plain_ok = 0, clutter_plain_ok = 0;
    double landmark_ok = 0;   // fraction >= 0.8
    double clutter_ok = 0;    // fraction <= 0.3
};
ConfidenceResult run_confidence(const Scene &s, const cyl_colortable &t, uint32_t frames, uint32_t stride,
                                uint64_t seed);

// ---- plots (OpenCV drawing) ------------------------------------------------------------------
// Histogram of normalised errors with the N(0,1) density; title and axis labels.
void plot_normalised_hist(const std::string &path, const std::string &title, const std::vector<double> &z);
// Estimator output against measured variance (log-log) with y = x and the factor-2 band.
void plot_variance(const std::string &path, const std::vector<VarianceRow> &rows);

} // namespace synth
} // namespace cylfe
