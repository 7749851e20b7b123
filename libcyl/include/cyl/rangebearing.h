/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- from a pixel to the landmark's range and bearing in the robot
 * frame, with the full first-order covariance and the error budget of the
 * paper's Tables 8 and 9 (paper section 2.3.2; docs/uncertainty.md).
 *
 * Inputs: the 15 quantities of CYL_IN_*: the measured point (u, v), the nine
 * intrinsics, and the mounting tilt, yaw, h, s (cyl_camera). Their covariance
 * is block diagonal: the 2x2 of (u, v) from a noise estimator, the camera's
 * 9x9 intr_cov, and the four mounting variances.
 *
 * Chain:  (u, v, intrinsics) --undistort--> (x_n, y_n)
 *         --model, tilt, yaw, h--> camera range d_c and bearing theta_c
 *         --offset s--> landmark (x, y) = (s + d_c cos theta_c, d_c sin theta_c)
 *         --> range d_r = |(x, y)|, bearing theta_r = atan2(y, x).
 * Models (paper-model.md):
 *   CYL_GEOM_EXACT (default): the pixel ray meets the horizontal plane h below the optical
 *     centre. Level frame (X fwd, Y right, Z down): X = cos t - y_n sin t, Y = x_n,
 *     Z = sin t + y_n cos t;  d_c = h sqrt(X^2 + Y^2) / Z,  theta_c = yaw - atan2(Y, X).
 *     No range when Z <= 0 (ray at or above the horizon).
 *   CYL_GEOM_PAPER: eqs. 11-13 as printed: depression w = atan(y_n) + t, d_c = h / tan(w),
 *     theta_c = yaw - atan(x_n). No range unless 0 < w < pi/2.
 * Jacobians are analytic (chain rule through every stage, undistortion included).
 */
#ifndef CYL_RANGEBEARING_H
#define CYL_RANGEBEARING_H

#include <stdint.h>
#include "cyl/status.h"
#include "cyl/camera.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Input vector layout (units: px; px; px, px, px, px, 1, 1, 1, 1, 1; rad, rad, m, m). */
enum {
    CYL_IN_U = 0, CYL_IN_V = 1,
    CYL_IN_FX = 2, CYL_IN_FY = 3, CYL_IN_CX = 4, CYL_IN_CY = 5,
    CYL_IN_K1 = 6, CYL_IN_K2 = 7, CYL_IN_P1 = 8, CYL_IN_P2 = 9, CYL_IN_K3 = 10,
    CYL_IN_TILT = 11, CYL_IN_YAW = 12, CYL_IN_H = 13, CYL_IN_S = 14,
    CYL_IN_COUNT = 15
};

typedef enum cyl_geom_model {
    CYL_GEOM_EXACT = 0,   /* ray-plane intersection (default) */
    CYL_GEOM_PAPER = 1    /* the paper's eqs. 11-20 as printed */
} cyl_geom_model;

/* Sources of error, grouped as in the paper's Tables 8 and 9. */
typedef enum cyl_source {
    CYL_SRC_SEGMENTATION = 0,    /* centroid (u, v) noise */
    CYL_SRC_PRINCIPAL_POINT = 1, /* cx, cy */
    CYL_SRC_FOCAL = 2,           /* fx, fy */
    CYL_SRC_DISTORTION = 3,      /* k1 k2 p1 p2 k3 */
    CYL_SRC_HEIGHT = 4,          /* h */
    CYL_SRC_TILT = 5,            /* tilt */
    CYL_SRC_YAW = 6,             /* yaw */
    CYL_SRC_POSITION = 7,        /* s */
    CYL_SRC_COUNT = 8
} cyl_source;

/* Result flags (also used in cyl_observation.flags). */
#define CYL_RB_NO_RANGE 0x100u   /* ray at/above the horizon: only the camera bearing is valid */

typedef struct cyl_rb_result {
    uint32_t flags;            /* CYL_RB_* bits */
    double xn, yn;             /* undistorted normalised image point, unitless */
    double range_cam_m;        /* d_c: ground distance from the optical centre, m (0 if no range) */
    double bearing_cam_rad;    /* theta_c: bearing from the camera, rad, left positive */
    double depth_m;            /* distance of the point along the optical axis, m (0 if no range) */
    double range_m;            /* d_r: range from the robot centre, m (0 if no range) */
    double bearing_rad;        /* theta_r: bearing from the robot centre, rad, left positive
                                  (= theta_c when there is no range: the direction at infinity) */
    double x_m, y_m;           /* landmark in the robot frame (x forward, y left), m */
    double jac[2][CYL_IN_COUNT];  /* d(range_m, bearing_rad)/d(inputs): m/unit, rad/unit
                                     (range row zero if no range) */
    double jac_xy[2][CYL_IN_COUNT]; /* d(x_m, y_m)/d(inputs), m/unit */
    double cov_rb[2][2];       /* covariance of (range_m, bearing_rad): [0][0] m^2, [0][1] = [1][0]
                                  m rad, [1][1] rad^2 (only [1][1] meaningful if no range) */
    double cov_xy[2][2];       /* covariance of (x_m, y_m), m^2 */
} cyl_rb_result;

/* Pack a camera and a measured point into the input vector. */
void cyl_rb_inputs(const cyl_camera *cam, double u_px, double v_px, double in[CYL_IN_COUNT]);

/* Input covariance: (u, v) block from var_u_px2, var_v_px2, cov_uv_px2; intrinsics block
 * from cam->intr_cov; diagonal mounting variances from the sigmas. */
void cyl_rb_input_cov(const cyl_camera *cam, double var_u_px2, double var_v_px2, double cov_uv_px2,
                      double cov[CYL_IN_COUNT][CYL_IN_COUNT]);

/* Evaluate the chain at an input vector. out[0] = range_m, out[1] = bearing_rad (robot frame);
 * xy (may be NULL) = landmark (x_m, y_m); jac / jac_xy (may be NULL) = analytic Jacobians.
 * Returns CYL_ERR_NO_RANGE (bearing out[1] and jac[1] still valid, out[0] = 0), CYL_ERR_NUMERIC
 * (undistortion failed, landmark at the robot centre, non-finite values), CYL_ERR_CAMERA (fx, fy
 * or h not positive) or CYL_OK. */
cyl_status cyl_rb_eval(const double in[CYL_IN_COUNT], cyl_geom_model model, double out[2],
                       double xy[2], double jac[2][CYL_IN_COUNT], double jac_xy[2][CYL_IN_COUNT]);

/* Full computation for a measured point with its pixel covariance: range, bearing, Jacobians,
 * cov_rb = J S J^T and cov_xy. Returns CYL_OK, CYL_ERR_NO_RANGE (res->flags has CYL_RB_NO_RANGE
 * and res->bearing_rad / cov_rb[1][1] hold the camera bearing and its variance), or an error. */
cyl_status cyl_range_bearing(const cyl_camera *cam, cyl_geom_model model, double u_px, double v_px,
                             double var_u_px2, double var_v_px2, double cov_uv_px2,
                             cyl_rb_result *res);

/* The inverse of the exact model: the pixel (u, v) at which a point of the landmarks' centroid
 * plane (h below the optical centre) at robot-frame (x_m, y_m) is seen, through the lens model.
 * Returns CYL_ERR_NO_RANGE if the point is not in front of the camera (optical-axis depth <= 0),
 * CYL_ERR_CAMERA for an invalid camera. Used by tests, the paper tool and renderers. */
cyl_status cyl_rb_project(const cyl_camera *cam, double x_m, double y_m, double *u_px, double *v_px);

/* Error budget of one observation (paper Tables 8, 9). */
typedef struct cyl_error_budget {
    double total_var_range_m2;              /* J S J^T [0][0], m^2 */
    double total_var_bearing_rad2;          /* J S J^T [1][1], rad^2 */
    double var_range_m2[CYL_SRC_COUNT];     /* range variance with only this source's variances kept, m^2 */
    double var_bearing_rad2[CYL_SRC_COUNT]; /* bearing variance likewise, rad^2 */
    double share_range[CYL_SRC_COUNT];      /* var_range_m2[i] / total_var_range_m2, 0..1 */
    double share_bearing[CYL_SRC_COUNT];    /* var_bearing_rad2[i] / total_var_bearing_rad2, 0..1 */
    double cross_share_range;               /* part of the total from covariances between groups
                                               (e.g. fx-cx terms of a full intr_cov); 1 - sum of shares */
    double cross_share_bearing;             /* same for the bearing */
    double sens_range[CYL_SRC_COUNT];       /* range variance when each input of this source has
                                               variance 1 (its SI unit^2: px^2, rad^2, m^2, 1) and
                                               all others 0, m^2 per unit^2 */
    double sens_bearing[CYL_SRC_COUNT];     /* bearing likewise, rad^2 per unit^2 */
} cyl_error_budget;

/* Budget from a Jacobian (cyl_rb_result.jac: pass &res.jac[0][0], row-major 2 x CYL_IN_COUNT)
 * and the input covariance (cyl_rb_input_cov: &cov[0][0], row-major CYL_IN_COUNT^2). Flat
 * pointers so that C callers can pass non-const arrays without ISO C qualifier warnings. */
void cyl_error_budget_compute(const double *jac, const double *cov, cyl_error_budget *b);

/* Budget of a measured point: cyl_range_bearing() + cyl_rb_input_cov() + the above.
 * Same returns as cyl_range_bearing() (for no range only the bearing half is filled). */
cyl_status cyl_error_budget_at(const cyl_camera *cam, cyl_geom_model model, double u_px, double v_px,
                               double var_u_px2, double var_v_px2, double cov_uv_px2,
                               cyl_error_budget *b);

/* Name of a source ("segmentation noise", "principal point", ...). */
const char *cyl_source_name(cyl_source s);

#ifdef __cplusplus
}
#endif
#endif /* CYL_RANGEBEARING_H */
