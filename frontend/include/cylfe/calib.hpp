// SPDX-License-Identifier: BSD-3-Clause
// cylfe::calib -- the calibration tools' library (docs/calibration.md):
//   * chessboard detection (cv::findChessboardCorners + cv::cornerSubPix),
//   * intrinsic calibration: closed-form start (cv::initCameraMatrix2D + per-view PnP), Ceres
//     refinement of fx fy cx cy k1 k2 p1 p2 k3 and the view poses, the full covariance of the
//     intrinsics with sigma^2 = SSE / (2N - p) (ceres::Covariance), per-view RMS and outliers,
//   * the robot mount's extrinsics from a chessboard lying on the floor (height, tilt, yaw, roll,
//     forward offset) with a per-image covariance, and the start-up statistics (paper Table 5),
//   * colour-table training helpers (image files and raw-log frames -> libcyl images -> the
//     CYLT table through cyl_colortable_train / cyl_colortable_save),
//   * writers: OpenCV FileStorage YAML (through cylfe::save_camera_calibration) and ROS
//     camera_info YAML, both with libcyl's uncertainty and mount fields, written to a temporary
//     file and renamed (no partial output file).
// The lens model is libcyl's (cyl_camera_project / cyl_camera_undistort): nothing here
// re-implements it.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "cylfe/calibration.hpp"

extern "C" {
#include "cyl/camera.h"
#include "cyl/colortable.h"
#include "cyl/image.h"
}

namespace cylfe {
namespace calib {

// ---- chessboard --------------------------------------------------------------------------

struct Board {
    int cols = 9;          // inner corners per row (along the board's x axis)
    int rows = 6;          // inner corners per column (along y)
    double square = 1.0;   // square size (any unit; metres for the mount)
};

// The board's inner corners in its own frame: (c * square, r * square, 0), row-major, in the
// order cv::findChessboardCorners returns them.
std::vector<cv::Point3f> board_points(const Board &b);

struct DetectOptions {
    int subpix_half_window = 11;  // cv::cornerSubPix winSize (11 -> a 23x23 window, as OpenCV's sample),
                                  // reduced to half the smallest corner spacing when that is smaller
                                  // and adaptive_window is set
    int subpix_max_iter = 30;
    double subpix_eps = 1e-4;
    bool fast_check = true;       // CALIB_CB_FAST_CHECK
    bool adaptive_window = true;  // shrink the window to half the smallest corner spacing
};

// Corners of one grey image; false if the board is not found.
bool find_corners(const cv::Mat &gray, const Board &b, const DetectOptions &o,
                  std::vector<cv::Point2f> &corners);

struct View {
    std::string name;                  // image file (or label)
    std::vector<cv::Point2f> corners;  // board_points() order
};

// Read the images and detect the board in each. An unreadable image or one of a different size
// throws Error naming the file; a board not found, or a degenerate detection (the corners span
// less than min_area_frac of the image), is skipped with a warning through warn().
// image_size receives the common size.
std::vector<View> detect_views(const std::vector<std::string> &paths, const Board &b,
                               const DetectOptions &o, cv::Size &image_size,
                               const std::function<void(const std::string &)> &warn,
                               const std::function<void(size_t, size_t)> &progress = nullptr,
                               double min_area_frac = 0.002);

// ---- intrinsics ----------------------------------------------------------------------------

struct IntrinsicOptions {
    bool fix_k3 = false;          // k3 held at 0
    bool zero_tangent = false;    // p1 = p2 = 0
    bool fix_aspect = false;      // fy / fx held at the initial ratio (aspect below if > 0)
    double aspect = 0.0;          // with fix_aspect: fy / fx (0 = from the closed-form start)
    double outlier_factor = 2.0;  // a view whose RMS exceeds this times the overall RMS is flagged
    int max_iterations = 200;
};

struct IntrinsicResult {
    cv::Size image_size;
    double intr[CYL_INTR_COUNT] = {0};                // fx fy cx cy k1 k2 p1 p2 k3
    double cov[CYL_INTR_COUNT][CYL_INTR_COUNT] = {{0}};  // full covariance (order CYL_INTR_*)
    double sigma[CYL_INTR_COUNT] = {0};               // sqrt(diag(cov))
    double sse = 0;         // sum of squared residuals, px^2
    double rms = 0;         // sqrt(SSE / N) (N = corners; OpenCV's definition)
    double sigma2 = 0;      // SSE / (2N - p), px^2: the residual variance estimate
    int n_points = 0;       // N, corners
    int n_params = 0;       // p, free parameters (intrinsics + 6 per view)
    int iterations = 0;
    std::vector<std::string> names;   // view names
    std::vector<double> view_rms;     // px
    std::vector<cv::Vec3d> rvecs, tvecs;
    std::vector<int> outliers;        // indices of views with RMS > outlier_factor * rms
    cyl_camera camera() const;        // intrinsics + covariance (mount unknown: zero)
};

// Calibrate from corners (all views of the same board). Throws Error if fewer than 3 views, the
// optimisation fails, or the view set is degenerate (the covariance is rank deficient).
IntrinsicResult calibrate_intrinsics(const std::vector<std::vector<cv::Point3f>> &obj,
                                     const std::vector<std::vector<cv::Point2f>> &img,
                                     cv::Size image_size, const IntrinsicOptions &opt,
                                     const std::vector<std::string> &names = {});

// ---- mount extrinsics ------------------------------------------------------------------------

// Where the board lies, in the robot frame (x forward, y left, z up; floor z = 0).
struct BoardPlacement {
    double centre_x_m = 1.0;   // centre of the inner-corner grid
    double centre_y_m = 0.0;
    double axis_deg = 90.0;    // direction of the board's x axis (the rows of `cols` corners),
                               // counter-clockwise from the robot's x axis; modulo 180 degrees
};

// One image's estimate. Angles in radians; the camera pose is a rotation
// Rz(yaw) * Ry(tilt down) * Rx(roll) of the optical axis frame (x forward) in the robot frame.
struct MountEstimate {
    std::string name;
    double height_floor_m = 0;  // optical centre above the floor
    double tilt_rad = 0;        // pitch below horizontal (> 0 looking down)
    double yaw_rad = 0;         // left positive
    double roll_rad = 0;        // about the optical axis, right-handed (right side down > 0)
    double offset_m = 0;        // optical centre forward of the robot centre (s)
    double lateral_m = 0;       // optical centre left of the robot centre
    double cov[6][6] = {{0}};   // of (height_floor, tilt, yaw, roll, offset, lateral) from this image
    double sigma[6] = {0};
    double rms_px = 0;          // reprojection RMS
    int n_points = 0;
};

// Estimate the mount from one image's corners with the intrinsics of cam (libcyl's lens model).
// The covariance is from the pose fit's Jacobian with the corner noise estimated from the
// residuals separately along u and v (sigma_u^2 = SSE_u / (N - 3), likewise v; the fit is then
// repeated weighted by them): a floor board is foreshortened vertically, its corners are less
// precise in v than in u.
MountEstimate estimate_mount(const cyl_camera &cam, const Board &b, const BoardPlacement &pl,
                             const std::vector<cv::Point2f> &corners, const std::string &name = "");

struct MountSummary {
    int n = 0;                       // start-ups (images)
    double mean[6] = {0};            // (height_floor, tilt, yaw, roll, offset, lateral)
    double spread[6] = {0};          // sample standard deviation over the start-ups (n - 1)
    double within[6] = {0};          // RMS of the per-image sigmas (estimation noise alone)
};
MountSummary summarise_mount(const std::vector<MountEstimate> &e);

// ---- colour tables ---------------------------------------------------------------------------

// A frame as libcyl sees it (owns its bytes).
struct Frame {
    std::vector<uint8_t> data;
    cyl_image img{};
    std::string label;
};

// Load a frame: an image file through the frontend's file source (BGR -> I420 as
// cv::cvtColor(COLOR_BGR2YUV_I420), what `cyl` feeds the detector), or frame `index` (0-based)
// of a raw log (*.cylraw, the camera's own bytes, e.g. YUYV). Throws Error naming the file.
Frame load_frame(const std::string &path, long index = 0);

// Train class cls of t from the pixels of frame inside rect (px; must lie inside the image):
// cyl_colortable_train with params. box receives (u_lo, u_hi, v_lo, v_hi, y_lo, y_hi). Throws
// Error (naming the frame's label and the rectangle) if the rectangle is outside the image or
// no UV bin survives the threshold.
void train_rect(cyl_colortable &t, unsigned cls, const Frame &frame, const cv::Rect &rect,
                const cyl_train_params &params, uint8_t box[6]);

// Fraction of the pixels in rect that the table classifies as class cls (cyl_classify).
double class_coverage(const cyl_colortable &t, unsigned cls, const Frame &frame, const cv::Rect &rect);

// The frame as BGR with every classified pixel blended towards its class's display colour
// (alpha = weight of the display colour).
cv::Mat classified_overlay(const cyl_colortable &t, const Frame &frame, double alpha = 0.6);

// Read / write a CYLT table file (write: temporary file + rename). Throws Error naming the file.
void load_table(const std::string &path, cyl_colortable &t);
void save_table(const std::string &path, const cyl_colortable &t);

// ---- files -------------------------------------------------------------------------------------

// Write text to path through "<path>.tmp.<pid>" and rename (cylfe::write_file_atomic).
using cylfe::write_file_atomic;
// OpenCV FileStorage YAML with libcyl's fields: cylfe::save_camera_calibration (atomic; unknown
// mount and intrinsic covariance left out; comment lines after the header).
void save_opencv_yaml(const std::string &path, const cyl_camera &cam, const std::string &comment = "",
                      bool with_mount = true);
// ROS camera_info YAML (camera_calibration's layout) with the same extra fields.
std::string ros_yaml(const cyl_camera &cam, const std::string &camera_name, const std::string &comment = "",
                     bool with_mount = true);
void save_ros_yaml(const std::string &path, const cyl_camera &cam, const std::string &camera_name,
                   const std::string &comment = "", bool with_mount = true);

} // namespace calib
} // namespace cylfe
