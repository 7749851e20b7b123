// SPDX-License-Identifier: BSD-3-Clause
// The overlay view: what the detector saw and what it reports, drawn on the frame (OpenCV BGR).
//
//   landmark        an observation with confidence >= min_confidence (what the SLAM demo keeps by
//                   default): class-coloured pixels, a 2 px box in the class colour, a label on a
//                   dark background (class, range, bearing, confidence) and, where it means
//                   something, the 95% ellipse of its position projected into the image;
//   low confidence  an observation below min_confidence or without a range: class-coloured
//                   pixels and a 1 px box in the class colour, no label;
//   rejected blob   a blob the detector's gates dropped (area, shape, size, ROI): pixels in grey,
//                   a thin grey box, no label.
// A landmark of several bands (a grouped observation) has each band's pixels in its own class
// colour, the box around all of them, and a label naming its model and identity ("post7 #7").
// Labels that would overlap an earlier one move down, and are left out when there is no room.
// A key in the top-left corner names the three kinds.
#pragma once
#include <vector>

#include <opencv2/core.hpp>

#include "cylfe/pipeline.hpp"

namespace cylfe {

// Convert a libcyl image view to BGR (for display and overlays).
cv::Mat to_bgr(const cyl_image &img);

struct OverlayOptions {
    double min_confidence = 0.5;       // landmark vs low confidence (the SLAM demo's --conf-min default)
    double max_ellipse_rel_range = 0.5; // no ellipse when its 95% half-axis exceeds this share of the range
    bool key = true;                   // draw the key in the top-left corner
};

enum class OverlayKind { Landmark, LowConfidence, Rejected };
OverlayKind overlay_kind(const cyl_observation &o, const OverlayOptions &opt);

// The 95% ellipse of the observation's (x, y) projected into the image as a closed polygon, or
// empty where it would not mean something: no range, an invalid observation, a half-axis larger
// than max_ellipse_rel_range x range, a point that does not project (behind the camera), or a
// polygon reaching more than one image size outside the frame.
std::vector<cv::Point> overlay_ellipse(const cyl_camera &cam, const cyl_observation &o, const OverlayOptions &opt,
                                       cv::Size image);

// Place a label box of `size` at `want` (its top-left), moved down past the boxes in `taken` and
// kept inside `image`; returns false (and leaves `taken` alone) when no place is free.
bool place_label(std::vector<cv::Rect> &taken, cv::Point want, cv::Size size, cv::Size image, cv::Rect *where);

// Draw the detector's last frame onto bgr (in place).
void draw_overlay(cv::Mat &bgr, const Detector &det, const std::vector<cyl_observation> &obs,
                  const OverlayOptions &opt = OverlayOptions());

} // namespace cylfe
