/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- camera model: Brown-Conrady distortion, its inverse and Jacobians. */
#include "cyl/camera.h"

#include <math.h>
#include <string.h>

void cyl_camera_init(cyl_camera *cam)
{
    if (!cam) return;
    memset(cam, 0, sizeof *cam);
    cam->fx_px = 1.0;
    cam->fy_px = 1.0;
    cam->height_m = 1.0;
    cam->flags = CYL_CAM_INTR_COV_UNKNOWN | CYL_CAM_EXTR_SIG_UNKNOWN;
}

void cyl_camera_set_intrinsic_sigmas(cyl_camera *cam, const double sigma[CYL_INTR_COUNT])
{
    int i;
    if (!cam) return;
    memset(cam->intr_cov, 0, sizeof cam->intr_cov);
    if (!sigma) {
        cam->flags |= CYL_CAM_INTR_COV_UNKNOWN;
        return;
    }
    for (i = 0; i < CYL_INTR_COUNT; i++) cam->intr_cov[i][i] = sigma[i] * sigma[i];
    cam->flags &= ~CYL_CAM_INTR_COV_UNKNOWN;
}

static int finite_all(const double *p, int n)
{
    int i;
    for (i = 0; i < n; i++)
        if (!isfinite(p[i])) return 0;
    return 1;
}

cyl_status cyl_camera_check(const cyl_camera *cam)
{
    int i, j;
    double v[17];
    const double half_pi = 1.5707963267948966;
    if (!cam) return CYL_ERR_ARG;
    v[0] = cam->fx_px; v[1] = cam->fy_px; v[2] = cam->cx_px; v[3] = cam->cy_px;
    v[4] = cam->k1; v[5] = cam->k2; v[6] = cam->p1; v[7] = cam->p2; v[8] = cam->k3;
    v[9] = cam->tilt_rad; v[10] = cam->yaw_rad; v[11] = cam->height_m; v[12] = cam->offset_m;
    v[13] = cam->tilt_sigma_rad; v[14] = cam->yaw_sigma_rad; v[15] = cam->height_sigma_m;
    v[16] = cam->offset_sigma_m;
    if (!finite_all(v, 17)) return CYL_ERR_CAMERA;
    if (!(cam->fx_px > 0.0) || !(cam->fy_px > 0.0) || !(cam->height_m > 0.0)) return CYL_ERR_CAMERA;
    if (!(fabs(cam->tilt_rad) < half_pi) || !(fabs(cam->yaw_rad) < half_pi)) return CYL_ERR_CAMERA;
    for (i = 13; i < 17; i++)
        if (v[i] < 0.0) return CYL_ERR_CAMERA;
    for (i = 0; i < CYL_INTR_COUNT; i++) {
        if (!finite_all(cam->intr_cov[i], CYL_INTR_COUNT)) return CYL_ERR_CAMERA;
        if (cam->intr_cov[i][i] < 0.0) return CYL_ERR_CAMERA;
        for (j = 0; j < i; j++) {
            double a = cam->intr_cov[i][j], b = cam->intr_cov[j][i];
            if (fabs(a - b) > 1e-9 * (fabs(a) + fabs(b)) + 1e-300) return CYL_ERR_CAMERA;
        }
    }
    return CYL_OK;
}

void cyl_camera_distort(const cyl_camera *cam, double x, double y, double *xd, double *yd,
                        double jac[2][2])
{
    double r2 = x * x + y * y;
    double rad = 1.0 + r2 * (cam->k1 + r2 * (cam->k2 + r2 * cam->k3));
    double p1 = cam->p1, p2 = cam->p2;
    if (xd) *xd = x * rad + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
    if (yd) *yd = y * rad + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
    if (jac) {
        double drad = cam->k1 + r2 * (2.0 * cam->k2 + 3.0 * cam->k3 * r2); /* d rad / d r2 */
        jac[0][0] = rad + 2.0 * x * x * drad + 2.0 * p1 * y + 6.0 * p2 * x;
        jac[0][1] = 2.0 * x * y * drad + 2.0 * p1 * x + 2.0 * p2 * y;
        jac[1][0] = 2.0 * x * y * drad + 2.0 * p1 * x + 2.0 * p2 * y;
        jac[1][1] = rad + 2.0 * y * y * drad + 6.0 * p1 * y + 2.0 * p2 * x;
    }
}

void cyl_camera_project(const cyl_camera *cam, double x, double y, double *u, double *v)
{
    double xd, yd;
    cyl_camera_distort(cam, x, y, &xd, &yd, NULL);
    if (u) *u = cam->fx_px * xd + cam->cx_px;
    if (v) *v = cam->fy_px * yd + cam->cy_px;
}

/* g(q) = d/drho [rho (1 + k1 q + k2 q^2 + k3 q^3)] at q = rho^2 = 1 + 3 k1 q + 5 k2 q^2 + 7 k3 q^3 */
static double radial_slope(const cyl_camera *cam, double q)
{
    return 1.0 + q * (3.0 * cam->k1 + q * (5.0 * cam->k2 + 7.0 * cam->k3 * q));
}

int cyl_camera_unfolded(const cyl_camera *cam, double x, double y)
{
    double j[2][2], R = x * x + y * y, A = 21.0 * cam->k3, B = 10.0 * cam->k2, C = 3.0 * cam->k1;
    cyl_camera_distort(cam, x, y, NULL, NULL, j);
    if (!(j[0][0] * j[1][1] - j[0][1] * j[1][0] > 0.0)) return 0;
    /* the radial map is increasing on [0, |(x, y)|] iff g > 0 on [0, R]: g(0) = 1, so check g at
     * R and at the stationary points of g (roots of g' = C + B q + A q^2) inside (0, R) */
    if (!(radial_slope(cam, R) > 0.0)) return 0;
    if (A != 0.0) {
        double disc = B * B - 4.0 * A * C;
        if (disc >= 0.0) {
            double sq = sqrt(disc), q1 = (-B - sq) / (2.0 * A), q2 = (-B + sq) / (2.0 * A);
            if (q1 > 0.0 && q1 < R && !(radial_slope(cam, q1) > 0.0)) return 0;
            if (q2 > 0.0 && q2 < R && !(radial_slope(cam, q2) > 0.0)) return 0;
        }
    } else if (B != 0.0) {
        double q = -C / B;
        if (q > 0.0 && q < R && !(radial_slope(cam, q) > 0.0)) return 0;
    }
    return 1;
}

cyl_status cyl_camera_undistort(const cyl_camera *cam, double u, double v, double *x, double *y)
{
    double xd, yd, cx, cy, ex, ey, res;
    int it;
    if (!cam || !x || !y) return CYL_ERR_ARG;
    if (!isfinite(u) || !isfinite(v)) return CYL_ERR_NUMERIC;
    xd = (u - cam->cx_px) / cam->fx_px;
    yd = (v - cam->cy_px) / cam->fy_px;
    if (cam->k1 == 0.0 && cam->k2 == 0.0 && cam->p1 == 0.0 && cam->p2 == 0.0 && cam->k3 == 0.0) {
        *x = xd; /* pinhole: exact */
        *y = yd;
        return CYL_OK;
    }
    cx = xd;
    cy = yd;
    cyl_camera_distort(cam, cx, cy, &ex, &ey, NULL);
    ex -= xd;
    ey -= yd;
    res = ex * ex + ey * ey;
    for (it = 0; it < CYL_UNDISTORT_MAX_ITER; it++) {
        double j[2][2], det, sx, sy, t = 1.0;
        int half;
        if (res == 0.0) break;
        cyl_camera_distort(cam, cx, cy, NULL, NULL, j);
        det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        if (!(fabs(det) > 1e-12)) return CYL_ERR_NUMERIC;
        sx = (j[1][1] * ex - j[0][1] * ey) / det;
        sy = (-j[1][0] * ex + j[0][0] * ey) / det;
        /* damped step: halve while the residual grows (keeps far corners from diverging) */
        for (half = 0; half < 30; half++) {
            double nx = cx - t * sx, ny = cy - t * sy, fx, fy, nres;
            cyl_camera_distort(cam, nx, ny, &fx, &fy, NULL);
            fx -= xd;
            fy -= yd;
            nres = fx * fx + fy * fy;
            if (nres <= res || half == 29) {
                cx = nx; cy = ny; ex = fx; ey = fy; res = nres;
                break;
            }
            t *= 0.5;
        }
        if (t * sqrt(sx * sx + sy * sy) < CYL_UNDISTORT_TOL * (1.0 + sqrt(cx * cx + cy * cy))) break;
    }
    if (!isfinite(cx) || !isfinite(cy) || it == CYL_UNDISTORT_MAX_ITER) return CYL_ERR_NUMERIC;
    /* accept only a true solution (tolerance well above round-off, far below any pixel) */
    if (sqrt(res) > 1e-11 * (1.0 + sqrt(xd * xd + yd * yd))) return CYL_ERR_NUMERIC;
    /* ... on the lens's own branch: the forward map must not fold between the centre and the
     * solution (a preimage beyond the fold is not the physical ray) */
    if (!cyl_camera_unfolded(cam, cx, cy)) return CYL_ERR_NUMERIC;
    *x = cx;
    *y = cy;
    return CYL_OK;
}

cyl_status cyl_camera_undistort_jacobian(const cyl_camera *cam, double x, double y,
                                         double j_uv[2][2], double j_intr[2][CYL_INTR_COUNT])
{
    double jd[2][2], inv[2][2], det, xd, yd, r2, dD[2][CYL_INTR_COUNT];
    int r, k;
    if (!cam) return CYL_ERR_ARG;
    cyl_camera_distort(cam, x, y, &xd, &yd, jd);
    det = jd[0][0] * jd[1][1] - jd[0][1] * jd[1][0];
    if (!(fabs(det) > 1e-12) || !isfinite(det)) return CYL_ERR_NUMERIC;
    inv[0][0] = jd[1][1] / det;
    inv[0][1] = -jd[0][1] / det;
    inv[1][0] = -jd[1][0] / det;
    inv[1][1] = jd[0][0] / det;
    if (j_uv) {
        /* d(xd)/du = 1/fx, d(yd)/dv = 1/fy */
        j_uv[0][0] = inv[0][0] / cam->fx_px;
        j_uv[0][1] = inv[0][1] / cam->fy_px;
        j_uv[1][0] = inv[1][0] / cam->fx_px;
        j_uv[1][1] = inv[1][1] / cam->fy_px;
    }
    if (j_intr) {
        /* F(x; q) = D(x; k) - xd(u, v; f, c) = 0  =>  dx/dq = -Jd^-1 dF/dq */
        r2 = x * x + y * y;
        for (r = 0; r < 2; r++)
            for (k = 0; k < CYL_INTR_COUNT; k++) dD[r][k] = 0.0;
        /* -d(xd)/dq for the pinhole part: xd = (u - cx)/fx */
        dD[0][CYL_INTR_FX] = xd / cam->fx_px;
        dD[0][CYL_INTR_CX] = 1.0 / cam->fx_px;
        dD[1][CYL_INTR_FY] = yd / cam->fy_px;
        dD[1][CYL_INTR_CY] = 1.0 / cam->fy_px;
        /* d D / d distortion */
        dD[0][CYL_INTR_K1] = x * r2;
        dD[0][CYL_INTR_K2] = x * r2 * r2;
        dD[0][CYL_INTR_K3] = x * r2 * r2 * r2;
        dD[0][CYL_INTR_P1] = 2.0 * x * y;
        dD[0][CYL_INTR_P2] = r2 + 2.0 * x * x;
        dD[1][CYL_INTR_K1] = y * r2;
        dD[1][CYL_INTR_K2] = y * r2 * r2;
        dD[1][CYL_INTR_K3] = y * r2 * r2 * r2;
        dD[1][CYL_INTR_P1] = r2 + 2.0 * y * y;
        dD[1][CYL_INTR_P2] = 2.0 * x * y;
        for (r = 0; r < 2; r++)
            for (k = 0; k < CYL_INTR_COUNT; k++)
                j_intr[r][k] = -(inv[r][0] * dD[0][k] + inv[r][1] * dD[1][k]);
    }
    return CYL_OK;
}
