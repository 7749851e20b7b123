// SPDX-License-Identifier: BSD-3-Clause
// cylfe: camera calibration files -> the C camera description (cyl_camera, libcyl/camera.h).
//
// Two formats, detected from the content:
//   * OpenCV FileStorage YAML ("%YAML:1.0" header; what cv::FileStorage and OpenCV's
//     calibration samples write): camera_matrix and distortion_coefficients as !!opencv-matrix,
//     image_width, image_height;
//   * ROS camera_info YAML (camera_calibration / camera_info_manager): image_width,
//     image_height, camera_matrix {rows, cols, data}, distortion_model (plumb_bob or
//     rational_polynomial: first 5 terms; equidistant is refused), distortion_coefficients.
// plus, in either, libcyl's own optional uncertainty and mounting fields
// (docs/uncertainty.md; calib_data/paper_camera.yaml is the reference example):
//   intrinsic_sigmas: [fx, fy, cx, cy, k1, k2, p1, p2, k3]     standard deviations (px, 1)
//   intrinsic_covariance: 9x9 matrix in the same order         (takes precedence over sigmas)
//   mount_tilt_deg, mount_yaw_deg, mount_height_m, mount_offset_m             values
//   mount_tilt_sigma_deg, mount_yaw_sigma_deg, mount_height_sigma_m,
//   mount_offset_sigma_m                                                       standard deviations
// Files without the uncertainty fields still load: the intrinsic covariance and/or the mounting
// sigmas are then zero and marked unknown (cyl_camera.flags CYL_CAM_INTR_COV_UNKNOWN,
// CYL_CAM_EXTR_SIG_UNKNOWN). Files without the mounting values load with mount_known = false
// (enough for undistortion; range and bearing need the mount).
// Errors throw cylfe::Error naming the file and the field.
#pragma once
#include <string>
#include <vector>

extern "C" {
#include "cyl/camera.h"
}

namespace cylfe {

struct CameraCalibration {
    cyl_camera cam{};                 // the C camera description
    std::string path;                 // file it came from
    std::string format;               // "opencv" or "ros"
    bool intrinsic_cov_known = false; // intrinsic_sigmas or intrinsic_covariance present
    bool mount_known = false;         // all four mount values present
    bool mount_sigmas_known = false;  // all four mount sigmas present
    std::vector<std::string> warnings; // lenient loads: each unknown key, "FILE:LINE: ..."
};

// Load a calibration file (either format). Throws cylfe::Error on a missing file, unparsable
// YAML, a missing or malformed required field, a key given twice, an unknown top-level key (naming
// the nearest known one; with lenient, a warning in .warnings instead), or an invalid camera
// (cyl_camera_check).
CameraCalibration load_camera_calibration(const std::string &path, bool lenient = false);

// The same for measuring range and bearing: also an Error when the file has no mount fields.
CameraCalibration load_mounted_camera_calibration(const std::string &path, bool lenient = false);

// Write cam as OpenCV FileStorage YAML with libcyl's fields, through "<path>.tmp.<pid>" renamed
// into place (a good file is never replaced by a partial one). The intrinsic covariance is left
// out when cam.flags has CYL_CAM_INTR_COV_UNKNOWN, the mount_* fields when with_mount is false (an
// intrinsic calibration: the mount is unknown when read back). Each line of `comment` becomes a
// "# " line after the YAML header. Throws Error naming the file.
void save_camera_calibration(const std::string &path, const cyl_camera &cam, bool with_mount = true,
                             const std::string &comment = "");

// Write text to path through "<path>.tmp.<pid>" and rename -- over a regular file only: a device
// node or FIFO is written directly, a symlink through (cylfe/output_file.hpp). Throws Error naming
// the file.
void write_file_atomic(const std::string &path, const std::string &text);

} // namespace cylfe
