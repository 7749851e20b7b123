/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- camera description: pinhole intrinsics with Brown-Conrady lens
 * distortion, the camera's mounting on the robot, and the uncertainty of both
 * (paper section 2.3, Tables 4 and 5).
 *
 * Conventions (docs/uncertainty.md):
 *   pixel (u, v): u to the right, v down, pixel centres at integer values (as
 *   cyl_image and OpenCV). Distorted normalised coordinates
 *       x_d = (u - cx) / fx,   y_d = (v - cy) / fy.
 *   Lens model (OpenCV / Bouguet order k1 k2 p1 p2 k3), undistorted (x, y):
 *       r2 = x^2 + y^2,  radial = 1 + k1 r2 + k2 r2^2 + k3 r2^3
 *       x_d = x radial + 2 p1 x y + p2 (r2 + 2 x^2)
 *       y_d = y radial + p1 (r2 + 2 y^2) + 2 p2 x y
 *   Mounting: the optical centre is offset_m (s) forward of the robot centre,
 *   height_m (h) above the plane of the landmarks' centroids, pitched down by
 *   tilt_rad and turned left by yaw_rad (robot frame x forward, y left, z up).
 *
 * Nothing here allocates or does I/O.
 */
#ifndef CYL_CAMERA_H
#define CYL_CAMERA_H

#include <stdint.h>
#include "cyl/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Index of each intrinsic parameter in cyl_camera.intr_cov and in Jacobians. */
enum {
    CYL_INTR_FX = 0, CYL_INTR_FY = 1, CYL_INTR_CX = 2, CYL_INTR_CY = 3,
    CYL_INTR_K1 = 4, CYL_INTR_K2 = 5, CYL_INTR_P1 = 6, CYL_INTR_P2 = 7, CYL_INTR_K3 = 8,
    CYL_INTR_COUNT = 9
};

/* cyl_camera.flags */
#define CYL_CAM_INTR_COV_UNKNOWN 0x1u  /* intrinsic covariance not known (intr_cov is zero) */
#define CYL_CAM_EXTR_SIG_UNKNOWN 0x2u  /* mounting sigmas not known (they are zero) */

typedef struct cyl_camera {
    uint32_t width;            /* image width, px (0 = unknown) */
    uint32_t height;           /* image height, px (0 = unknown) */
    double fx_px;              /* focal length along u, px (> 0) */
    double fy_px;              /* focal length along v, px (> 0) */
    double cx_px;              /* principal point column, px */
    double cy_px;              /* principal point row, px */
    double k1;                 /* radial distortion r^2 coefficient, unitless (normalised coords) */
    double k2;                 /* radial distortion r^4 coefficient, unitless */
    double p1;                 /* tangential distortion coefficient, unitless */
    double p2;                 /* tangential distortion coefficient, unitless */
    double k3;                 /* radial distortion r^6 coefficient, unitless */
    double intr_cov[CYL_INTR_COUNT][CYL_INTR_COUNT];
                               /* covariance of (fx fy cx cy k1 k2 p1 p2 k3), symmetric PSD;
                                  units: px^2 between fx..cy, px between a px and a
                                  distortion term, unitless^2 between distortion terms */
    double tilt_rad;           /* pitch of the optical axis below horizontal, rad (> 0 = looking down) */
    double yaw_rad;            /* heading of the optical axis, rad, counter-clockwise (left) positive */
    double height_m;           /* optical centre above the landmarks' centroid plane, m (> 0) */
    double offset_m;           /* optical centre forward of the robot centre (s), m */
    double tilt_sigma_rad;     /* standard deviation of tilt_rad, rad */
    double yaw_sigma_rad;      /* standard deviation of yaw_rad, rad */
    double height_sigma_m;     /* standard deviation of height_m, m */
    double offset_sigma_m;     /* standard deviation of offset_m, m */
    uint32_t flags;            /* CYL_CAM_* bits */
} cyl_camera;

/* Undistortion: Newton iterations on the forward model, at most this many, stopping when the
 * step is below CYL_UNDISTORT_TOL (normalised units) -- see cyl_camera_undistort(). */
#define CYL_UNDISTORT_MAX_ITER 50
#define CYL_UNDISTORT_TOL 1e-14

/* Zero everything, then fx = fy = 1, h = 1 (a valid identity camera; flags say
 * the covariances are unknown). */
void cyl_camera_init(cyl_camera *cam);

/* Set intr_cov to diag(sigma^2) from nine standard deviations in the
 * order of CYL_INTR_*; a NULL sigma zeroes it. Clears CYL_CAM_INTR_COV_UNKNOWN
 * unless sigma is NULL. */
void cyl_camera_set_intrinsic_sigmas(cyl_camera *cam, const double sigma[CYL_INTR_COUNT]);

/* Check a camera: finite values, fx, fy > 0, height_m > 0, |tilt|, |yaw| < pi/2,
 * non-negative sigmas, intr_cov symmetric with a non-negative diagonal.
 * Returns CYL_OK or CYL_ERR_CAMERA (CYL_ERR_ARG for NULL). */
cyl_status cyl_camera_check(const cyl_camera *cam);

/* Forward lens model in normalised coordinates: undistorted (x, y) -> distorted (xd, yd).
 * If jac is not NULL it receives d(xd, yd)/d(x, y), row-major [2][2]. */
void cyl_camera_distort(const cyl_camera *cam, double x, double y, double *xd, double *yd,
                        double jac[2][2]);

/* Undistorted normalised point -> pixel (u, v). */
void cyl_camera_project(const cyl_camera *cam, double x, double y, double *u, double *v);

/* Pixel (u, v) -> undistorted normalised (x, y): inverts the forward model by Newton's method
 * (2x2 Jacobian, step halving when the residual grows), starting from the distorted point, at
 * most CYL_UNDISTORT_MAX_ITER iterations, converged when the Newton step is below
 * CYL_UNDISTORT_TOL * (1 + |x|); the result is accepted when the residual is below 1e-11
 * (normalised) and it lies where the model is one-to-one (cyl_camera_unfolded). Round trip
 * distort(undistort(p)) = p to < 1e-9 px (tested). Returns CYL_ERR_NUMERIC on non-finite input,
 * a singular Jacobian, a point beyond the fold of the lens model (no physical preimage) or no
 * convergence. */
cyl_status cyl_camera_undistort(const cyl_camera *cam, double u, double v, double *x, double *y);

/* 1 if the lens model is one-to-one between the image centre and normalised point (x, y): the
 * forward Jacobian has a positive determinant at (x, y) and the radial map
 * rho (1 + k1 rho^2 + k2 rho^4 + k3 rho^6) increases on [0, |(x, y)|] (exact: its slope, a
 * cubic in rho^2, is checked at the interval's end and at its stationary points).
 * cyl_camera_undistort() rejects solutions where this is 0 (beyond the fold of the model). */
int cyl_camera_unfolded(const cyl_camera *cam, double x, double y);

/* Jacobians of the undistorted point (x, y) = undistort(u, v; intrinsics) at a solution (x, y)
 * of undistort, by the implicit-function theorem on the forward model:
 *   j_uv[r][c]   = d(x, y)[r] / d(u, v)[c]        (1/px)
 *   j_intr[r][k] = d(x, y)[r] / d intrinsic k     (order CYL_INTR_*)
 * Either output may be NULL. Returns CYL_ERR_NUMERIC if the forward Jacobian is singular. */
cyl_status cyl_camera_undistort_jacobian(const cyl_camera *cam, double x, double y,
                                         double j_uv[2][2], double j_intr[2][CYL_INTR_COUNT]);

#ifdef __cplusplus
}
#endif
#endif /* CYL_CAMERA_H */
