// SPDX-License-Identifier: BSD-3-Clause
// The overlay view: classified pixels, blob boxes, range/bearing text and the 95% uncertainty
// ellipse of each landmark's position, drawn on the frame (OpenCV BGR image).
#pragma once
#include <vector>

#include <opencv2/core.hpp>

#include "cylfe/pipeline.hpp"

namespace cylfe {

// Convert a libcyl image view to BGR (for display and overlays).
cv::Mat to_bgr(const cyl_image &img);

// Draw the detector's last frame onto bgr (in place).
void draw_overlay(cv::Mat &bgr, const Detector &det, const std::vector<cyl_observation> &obs);

} // namespace cylfe
