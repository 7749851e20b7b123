/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- range, bearing and their covariance (paper section 2.3.2). */
#include "cyl/rangebearing.h"
#include "unc_internal.h"

#include <math.h>
#include <string.h>

void cyl_rb_inputs(const cyl_camera *cam, double u_px, double v_px, double in[CYL_IN_COUNT])
{
    in[CYL_IN_U] = u_px;
    in[CYL_IN_V] = v_px;
    in[CYL_IN_FX] = cam->fx_px;
    in[CYL_IN_FY] = cam->fy_px;
    in[CYL_IN_CX] = cam->cx_px;
    in[CYL_IN_CY] = cam->cy_px;
    in[CYL_IN_K1] = cam->k1;
    in[CYL_IN_K2] = cam->k2;
    in[CYL_IN_P1] = cam->p1;
    in[CYL_IN_P2] = cam->p2;
    in[CYL_IN_K3] = cam->k3;
    in[CYL_IN_TILT] = cam->tilt_rad;
    in[CYL_IN_YAW] = cam->yaw_rad;
    in[CYL_IN_H] = cam->height_m;
    in[CYL_IN_S] = cam->offset_m;
}

void cyl_rb_input_cov(const cyl_camera *cam, double var_u_px2, double var_v_px2, double cov_uv_px2,
                      double cov[CYL_IN_COUNT][CYL_IN_COUNT])
{
    int i, j;
    memset(cov, 0, sizeof(double) * CYL_IN_COUNT * CYL_IN_COUNT);
    cov[CYL_IN_U][CYL_IN_U] = var_u_px2;
    cov[CYL_IN_V][CYL_IN_V] = var_v_px2;
    cov[CYL_IN_U][CYL_IN_V] = cov_uv_px2;
    cov[CYL_IN_V][CYL_IN_U] = cov_uv_px2;
    /* CYL_IN_FX..CYL_IN_K3 follow the CYL_INTR_* order */
    for (i = 0; i < CYL_INTR_COUNT; i++)
        for (j = 0; j < CYL_INTR_COUNT; j++) cov[CYL_IN_FX + i][CYL_IN_FX + j] = cam->intr_cov[i][j];
    cov[CYL_IN_TILT][CYL_IN_TILT] = cam->tilt_sigma_rad * cam->tilt_sigma_rad;
    cov[CYL_IN_YAW][CYL_IN_YAW] = cam->yaw_sigma_rad * cam->yaw_sigma_rad;
    cov[CYL_IN_H][CYL_IN_H] = cam->height_sigma_m * cam->height_sigma_m;
    cov[CYL_IN_S][CYL_IN_S] = cam->offset_sigma_m * cam->offset_sigma_m;
}

static void zero_jac(double j[2][CYL_IN_COUNT])
{
    if (j) memset(j, 0, sizeof(double) * 2 * CYL_IN_COUNT);
}

/* The chain for a measured point (u, v) seen by the intrinsics of `in_cam` (only fx..k3 are
 * read) with mounting t, yaw, h, s. xn_out/yn_out receive the undistorted point. */
static cyl_status rb_core(const cyl_camera *in_cam, double u, double v, double t, double yaw,
                          double h, double s, cyl_geom_model model, double out[2], double xy[2],
                          double jac[2][CYL_IN_COUNT], double jac_xy[2][CYL_IN_COUNT],
                          double *xn_out, double *yn_out)
{
    const cyl_camera *cam_p = in_cam;
    double xn, yn, j_uv[2][2], j_intr[2][CYL_INTR_COUNT];
    double jn[2][CYL_IN_COUNT];   /* d(xn, yn)/d(in) */
    double jc[2][CYL_IN_COUNT];   /* d(d_c, theta_c)/d(in) */
    double jl[2][CYL_IN_COUNT];   /* d(x_l, y_l)/d(in) */
    double dc, thc;
    double dd_dxn, dd_dyn, dd_dt, dd_dh, dth_dxn, dth_dyn, dth_dt;
    int no_range = 0, i, k;
    cyl_status st;

    out[0] = out[1] = 0.0;
    if (xy) xy[0] = xy[1] = 0.0;
    zero_jac(jac);
    zero_jac(jac_xy);
    if (!(cam_p->fx_px > 0.0) || !(cam_p->fy_px > 0.0) || !(h > 0.0)) return CYL_ERR_CAMERA;

    /* stage 1: undistortion */
    st = cyl_camera_undistort(cam_p, u, v, &xn, &yn);
    if (st != CYL_OK) return st;
    st = cyl_camera_undistort_jacobian(cam_p, xn, yn, j_uv, j_intr);
    if (st != CYL_OK) return st;
    if (xn_out) *xn_out = xn;
    if (yn_out) *yn_out = yn;
    memset(jn, 0, sizeof jn);
    for (i = 0; i < 2; i++) {
        jn[i][CYL_IN_U] = j_uv[i][0];
        jn[i][CYL_IN_V] = j_uv[i][1];
        for (k = 0; k < CYL_INTR_COUNT; k++) jn[i][CYL_IN_FX + k] = j_intr[i][k];
    }

    /* stage 2: camera-relative range and bearing */
    if (model == CYL_GEOM_PAPER) {
        double w = atan(yn) + t, tw, sw;
        thc = yaw - atan(xn);
        dth_dxn = -1.0 / (1.0 + xn * xn);
        dth_dyn = 0.0;
        dth_dt = 0.0;
        if (!(w > 0.0) || !(w < 1.5707963267948966)) {
            no_range = 1;
            dc = dd_dxn = dd_dyn = dd_dt = dd_dh = 0.0;
        } else {
            tw = tan(w);
            sw = sin(w);
            dc = h / tw;
            dd_dt = -h / (sw * sw);
            dd_dyn = dd_dt / (1.0 + yn * yn);
            dd_dxn = 0.0;
            dd_dh = 1.0 / tw;
        }
    } else if (model == CYL_GEOM_EXACT) {
        double ct = cos(t), stt = sin(t);
        double X = ct - yn * stt, Y = xn, Z = stt + yn * ct;
        double rho2 = X * X + Y * Y, rho = sqrt(rho2);
        if (!(rho > 0.0)) return CYL_ERR_NUMERIC; /* ray straight down: bearing undefined */
        thc = yaw - atan2(Y, X);
        dth_dxn = -X / rho2;
        dth_dyn = (Y / rho2) * (-stt);
        dth_dt = (Y / rho2) * (-Z);
        if (!(Z > 0.0)) {
            no_range = 1;
            dc = dd_dxn = dd_dyn = dd_dt = dd_dh = 0.0;
        } else {
            dc = h * rho / Z;
            dd_dxn = h * (Y / rho) / Z;
            dd_dyn = h * (X / rho) * (-stt) / Z - h * rho / (Z * Z) * ct;
            dd_dt = -h * X / rho - h * rho * X / (Z * Z);
            dd_dh = rho / Z;
        }
    } else {
        return CYL_ERR_ARG;
    }
    for (k = 0; k < CYL_IN_COUNT; k++) {
        jc[0][k] = dd_dxn * jn[0][k] + dd_dyn * jn[1][k];
        jc[1][k] = dth_dxn * jn[0][k] + dth_dyn * jn[1][k];
    }
    jc[0][CYL_IN_TILT] += dd_dt;
    jc[0][CYL_IN_H] += dd_dh;
    jc[1][CYL_IN_TILT] += dth_dt;
    jc[1][CYL_IN_YAW] += 1.0;

    if (no_range) {
        out[1] = thc;
        if (jac)
            for (k = 0; k < CYL_IN_COUNT; k++) jac[1][k] = jc[1][k];
        return CYL_ERR_NO_RANGE;
    }

    /* stage 3: camera -> robot centre (eqs. 17-18) */
    {
        double c = cos(thc), sn = sin(thc);
        double xl = s + dc * c, yl = dc * sn;
        double r2 = xl * xl + yl * yl, r = sqrt(r2);
        if (!(r > 0.0) || !isfinite(r)) return CYL_ERR_NUMERIC;
        for (k = 0; k < CYL_IN_COUNT; k++) {
            jl[0][k] = c * jc[0][k] - dc * sn * jc[1][k];
            jl[1][k] = sn * jc[0][k] + dc * c * jc[1][k];
        }
        jl[0][CYL_IN_S] += 1.0;
        out[0] = r;
        out[1] = atan2(yl, xl);
        if (xy) { xy[0] = xl; xy[1] = yl; }
        if (jac_xy)
            for (k = 0; k < CYL_IN_COUNT; k++) { jac_xy[0][k] = jl[0][k]; jac_xy[1][k] = jl[1][k]; }
        if (jac)
            for (k = 0; k < CYL_IN_COUNT; k++) {
                jac[0][k] = (xl * jl[0][k] + yl * jl[1][k]) / r;
                jac[1][k] = (-yl * jl[0][k] + xl * jl[1][k]) / r2;
            }
    }
    return CYL_OK;
}

cyl_status cyl_rb_eval(const double in[CYL_IN_COUNT], cyl_geom_model model, double out[2],
                       double xy[2], double jac[2][CYL_IN_COUNT], double jac_xy[2][CYL_IN_COUNT])
{
    cyl_camera cam;
    int i;
    if (!in || !out) return CYL_ERR_ARG;
    for (i = 0; i < CYL_IN_COUNT; i++)
        if (!isfinite(in[i])) return CYL_ERR_NUMERIC;
    cam.fx_px = in[CYL_IN_FX]; cam.fy_px = in[CYL_IN_FY];
    cam.cx_px = in[CYL_IN_CX]; cam.cy_px = in[CYL_IN_CY];
    cam.k1 = in[CYL_IN_K1]; cam.k2 = in[CYL_IN_K2]; cam.p1 = in[CYL_IN_P1];
    cam.p2 = in[CYL_IN_P2]; cam.k3 = in[CYL_IN_K3];
    return rb_core(&cam, in[CYL_IN_U], in[CYL_IN_V], in[CYL_IN_TILT], in[CYL_IN_YAW], in[CYL_IN_H],
                   in[CYL_IN_S], model, out, xy, jac, jac_xy, NULL, NULL);
}

/* J S J^T for a 2 x n Jacobian */
static void sandwich(const double *j, const double *cov, double out[2][2])
{
    int a, b, p, q;
    for (a = 0; a < 2; a++)
        for (b = 0; b < 2; b++) {
            double acc = 0.0;
            for (p = 0; p < CYL_IN_COUNT; p++) {
                double t = 0.0;
                if (j[a * CYL_IN_COUNT + p] == 0.0) continue;
                for (q = 0; q < CYL_IN_COUNT; q++) t += cov[p * CYL_IN_COUNT + q] * j[b * CYL_IN_COUNT + q];
                acc += j[a * CYL_IN_COUNT + p] * t;
            }
            out[a][b] = acc;
        }
    out[0][1] = out[1][0] = 0.5 * (out[0][1] + out[1][0]);
}

/* J S J^T with S the block-structured input covariance of cyl_rb_input_cov(), without forming S:
 * the (u, v) 2x2 block, the 9x9 intrinsic block, and the four mounting variances. */
static void propagate(const cyl_camera *cam, double vu, double vv, double cuv,
                      double j[2][CYL_IN_COUNT], double out[2][2])
{
    double d[4], cj[2][CYL_INTR_COUNT];
    int a, b, p, q;
    d[0] = cam->tilt_sigma_rad * cam->tilt_sigma_rad;
    d[1] = cam->yaw_sigma_rad * cam->yaw_sigma_rad;
    d[2] = cam->height_sigma_m * cam->height_sigma_m;
    d[3] = cam->offset_sigma_m * cam->offset_sigma_m;
    for (b = 0; b < 2; b++)
        for (p = 0; p < CYL_INTR_COUNT; p++) {
            double t = 0.0;
            for (q = 0; q < CYL_INTR_COUNT; q++) t += cam->intr_cov[p][q] * j[b][CYL_IN_FX + q];
            cj[b][p] = t;
        }
    for (a = 0; a < 2; a++)
        for (b = a; b < 2; b++) {
            double acc = j[a][CYL_IN_U] * (vu * j[b][CYL_IN_U] + cuv * j[b][CYL_IN_V]) +
                         j[a][CYL_IN_V] * (cuv * j[b][CYL_IN_U] + vv * j[b][CYL_IN_V]);
            for (p = 0; p < CYL_INTR_COUNT; p++) acc += j[a][CYL_IN_FX + p] * cj[b][p];
            for (p = 0; p < 4; p++) acc += j[a][CYL_IN_TILT + p] * d[p] * j[b][CYL_IN_TILT + p];
            out[a][b] = out[b][a] = acc;
        }
}

cyl_status cyl_rb_compute(const cyl_camera *cam, cyl_geom_model model, double u_px, double v_px,
                          double var_u_px2, double var_v_px2, double cov_uv_px2, cyl_rb_result *res)
{
    double out[2], xy[2];
    cyl_status st;
    memset(res, 0, sizeof *res);
    if (!isfinite(u_px) || !isfinite(v_px)) return CYL_ERR_NUMERIC;
    st = rb_core(cam, u_px, v_px, cam->tilt_rad, cam->yaw_rad, cam->height_m, cam->offset_m, model,
                 out, xy, res->jac, res->jac_xy, &res->xn, &res->yn);
    if (st != CYL_OK && st != CYL_ERR_NO_RANGE) return st;
    res->bearing_rad = out[1];
    propagate(cam, var_u_px2, var_v_px2, cov_uv_px2, res->jac, res->cov_rb);
    if (st == CYL_ERR_NO_RANGE) {
        res->flags |= CYL_RB_NO_RANGE;
        res->bearing_cam_rad = out[1];
        res->cov_rb[0][0] = res->cov_rb[0][1] = res->cov_rb[1][0] = 0.0;
        return st;
    }
    res->range_m = out[0];
    res->x_m = xy[0];
    res->y_m = xy[1];
    {
        /* (x, y) = (r cos b, r sin b) and jac_xy = G jac with G = d(x, y)/d(r, b), so
         * jac_xy S jac_xy^T = G cov_rb G^T exactly (no further approximation) */
        double c = xy[0] / out[0], sn = xy[1] / out[0], G[2][2], T[2][2];
        int a, b;
        G[0][0] = c; G[0][1] = -xy[1];
        G[1][0] = sn; G[1][1] = xy[0];
        for (a = 0; a < 2; a++)
            for (b = 0; b < 2; b++) T[a][b] = G[a][0] * res->cov_rb[0][b] + G[a][1] * res->cov_rb[1][b];
        for (a = 0; a < 2; a++)
            for (b = 0; b < 2; b++) res->cov_xy[a][b] = T[a][0] * G[b][0] + T[a][1] * G[b][1];
        res->cov_xy[0][1] = res->cov_xy[1][0] = 0.5 * (res->cov_xy[0][1] + res->cov_xy[1][0]);
    }
    /* camera-relative quantities */
    res->range_cam_m = hypot(xy[0] - cam->offset_m, xy[1]);
    res->bearing_cam_rad = atan2(xy[1], xy[0] - cam->offset_m);
    /* optical-axis depth: |P| / |(xn, yn, 1)| with |P|^2 = d_c^2 + h^2 */
    res->depth_m = sqrt(res->range_cam_m * res->range_cam_m + cam->height_m * cam->height_m) /
                   sqrt(1.0 + res->xn * res->xn + res->yn * res->yn);
    return CYL_OK;
}

cyl_status cyl_range_bearing(const cyl_camera *cam, cyl_geom_model model, double u_px, double v_px,
                             double var_u_px2, double var_v_px2, double cov_uv_px2,
                             cyl_rb_result *res)
{
    cyl_status st;
    if (!cam || !res) return CYL_ERR_ARG;
    memset(res, 0, sizeof *res);
    st = cyl_camera_check(cam);
    if (st != CYL_OK) return st;
    if (!(var_u_px2 >= 0.0) || !(var_v_px2 >= 0.0) || !isfinite(cov_uv_px2)) return CYL_ERR_ARG;
    if (model != CYL_GEOM_EXACT && model != CYL_GEOM_PAPER) return CYL_ERR_ARG;
    return cyl_rb_compute(cam, model, u_px, v_px, var_u_px2, var_v_px2, cov_uv_px2, res);
}

static const int src_first[CYL_SRC_COUNT] = {CYL_IN_U, CYL_IN_CX, CYL_IN_FX, CYL_IN_K1,
                                             CYL_IN_H, CYL_IN_TILT, CYL_IN_YAW, CYL_IN_S};
static const int src_count[CYL_SRC_COUNT] = {2, 2, 2, 5, 1, 1, 1, 1};

void cyl_error_budget_compute(const double *jac, const double *cov, cyl_error_budget *b)
{
    double full[2][2];
    int g, a, p, q;
    if (!jac || !cov || !b) return;
    memset(b, 0, sizeof *b);
    sandwich(jac, cov, full);
    b->total_var_range_m2 = full[0][0];
    b->total_var_bearing_rad2 = full[1][1];
    b->cross_share_range = b->cross_share_bearing = 1.0;
    for (g = 0; g < CYL_SRC_COUNT; g++) {
        int lo = src_first[g], hi = src_first[g] + src_count[g];
        for (a = 0; a < 2; a++) {
            double v = 0.0, sens = 0.0;
            for (p = lo; p < hi; p++) {
                double jp = jac[a * CYL_IN_COUNT + p];
                sens += jp * jp;
                for (q = lo; q < hi; q++) v += jp * cov[p * CYL_IN_COUNT + q] * jac[a * CYL_IN_COUNT + q];
            }
            if (a == 0) { b->var_range_m2[g] = v; b->sens_range[g] = sens; }
            else { b->var_bearing_rad2[g] = v; b->sens_bearing[g] = sens; }
        }
        b->share_range[g] = full[0][0] > 0.0 ? b->var_range_m2[g] / full[0][0] : 0.0;
        b->share_bearing[g] = full[1][1] > 0.0 ? b->var_bearing_rad2[g] / full[1][1] : 0.0;
        b->cross_share_range -= b->share_range[g];
        b->cross_share_bearing -= b->share_bearing[g];
    }
    if (!(full[0][0] > 0.0)) b->cross_share_range = 0.0;
    if (!(full[1][1] > 0.0)) b->cross_share_bearing = 0.0;
}

const char *cyl_source_name(cyl_source s)
{
    switch (s) {
    case CYL_SRC_SEGMENTATION: return "segmentation noise";
    case CYL_SRC_PRINCIPAL_POINT: return "principal point";
    case CYL_SRC_FOCAL: return "focal length";
    case CYL_SRC_DISTORTION: return "distortion";
    case CYL_SRC_HEIGHT: return "camera height";
    case CYL_SRC_TILT: return "camera tilt";
    case CYL_SRC_YAW: return "camera yaw";
    case CYL_SRC_POSITION: return "camera position";
    default: return "unknown source";
    }
}

cyl_status cyl_error_budget_at(const cyl_camera *cam, cyl_geom_model model, double u_px, double v_px,
                               double var_u_px2, double var_v_px2, double cov_uv_px2,
                               cyl_error_budget *b)
{
    cyl_rb_result r;
    double cov[CYL_IN_COUNT][CYL_IN_COUNT];
    cyl_status st;
    if (!b) return CYL_ERR_ARG;
    memset(b, 0, sizeof *b);
    st = cyl_range_bearing(cam, model, u_px, v_px, var_u_px2, var_v_px2, cov_uv_px2, &r);
    if (st != CYL_OK && st != CYL_ERR_NO_RANGE) return st;
    cyl_rb_input_cov(cam, var_u_px2, var_v_px2, cov_uv_px2, cov);
    cyl_error_budget_compute(&r.jac[0][0], &cov[0][0], b);
    return st;
}

cyl_status cyl_rb_project(const cyl_camera *cam, double x_m, double y_m, double *u_px, double *v_px)
{
    double dx, dy, ct, st, cy, sy, Xl, Yl, Zl, Xc, Yc, Zc;
    cyl_status s;
    if (!cam || !u_px || !v_px) return CYL_ERR_ARG;
    s = cyl_camera_check(cam);
    if (s != CYL_OK) return s;
    /* level camera frame: X forward along the optical axis's heading, Y right, Z down */
    dx = x_m - cam->offset_m;
    dy = y_m;
    cy = cos(cam->yaw_rad);
    sy = sin(cam->yaw_rad);
    Xl = cy * dx + sy * dy;
    Yl = sy * dx - cy * dy;   /* right = -(left component in the yawed frame) */
    Zl = cam->height_m;
    ct = cos(cam->tilt_rad);
    st = sin(cam->tilt_rad);
    Xc = Yl;
    Yc = -st * Xl + ct * Zl;
    Zc = ct * Xl + st * Zl;
    if (!(Zc > 0.0)) return CYL_ERR_NO_RANGE;
    cyl_camera_project(cam, Xc / Zc, Yc / Zc, u_px, v_px);
    return CYL_OK;
}
