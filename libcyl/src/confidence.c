/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- landmark confidence (paper eqs. 7-8). */
#include "cyl/confidence.h"
#include "cyl/segment.h"

#include <math.h>
#include <string.h>

double cyl_conf_r(double x)
{
    if (!(x > 0.0) || !isfinite(x)) return 0.0;
    return x <= 1.0 ? x : 1.0 / x;
}

cyl_status cyl_landmark_confidence(double w_px, double h_px, double depth_m, double fx_px,
                                   double fy_px, const cyl_landmark_size *size,
                                   uint32_t touch_flags, cyl_confidence *out)
{
    if (!size || !out) return CYL_ERR_ARG;
    if (!(depth_m > 0.0) || !(fx_px > 0.0) || !(fy_px > 0.0) || !(size->diameter_m > 0.0) ||
        !(size->height_m > 0.0) || !isfinite(depth_m)) {
        memset(out, 0, sizeof *out);
        return CYL_ERR_ARG;
    }
    return cyl_landmark_confidence_expected(w_px, h_px, fx_px * size->diameter_m / depth_m,
                                            fy_px * size->height_m / depth_m, touch_flags, out);
}

cyl_status cyl_landmark_expected_size(const cyl_camera *cam, double xn, double yn, double depth_m,
                                      const cyl_landmark_size *size, double *w_est_px, double *h_est_px)
{
    double jac[2][2], xd, yd, t, den, w0, h0, slant = 0.0;
    if (!cam || !size || !w_est_px || !h_est_px) return CYL_ERR_ARG;
    if (!(depth_m > 0.0) || !isfinite(depth_m) || !(cam->fx_px > 0.0) || !(cam->fy_px > 0.0) ||
        !(size->diameter_m > 0.0) || !(size->height_m > 0.0) || !isfinite(xn) || !isfinite(yn))
        return CYL_ERR_ARG;
    t = cam->tilt_rad;
    w0 = cam->fx_px * size->diameter_m / depth_m;
    h0 = cam->fy_px * size->height_m / depth_m;
    den = cos(t) - yn * sin(t);
    if (den > 0.0) slant = fabs(cam->fx_px / cam->fy_px * xn * sin(t) / den);
    cyl_camera_distort(cam, xn, yn, &xd, &yd, jac);
    *w_est_px = w0 * jac[0][0] * sqrt(1.0 + xn * xn) + h0 * slant;
    *h_est_px = h0;
    return CYL_OK;
}

cyl_status cyl_landmark_confidence_expected(double w_px, double h_px, double w_est_px, double h_est_px,
                                            uint32_t touch_flags, cyl_confidence *out)
{
    double rw, rh;
    if (!out) return CYL_ERR_ARG;
    memset(out, 0, sizeof *out);
    if (!(w_px > 0.0) || !(h_px > 0.0) || !(w_est_px > 0.0) || !(h_est_px > 0.0) || !isfinite(w_est_px) ||
        !isfinite(h_est_px))
        return CYL_ERR_ARG;
    out->w_est_px = w_est_px;
    out->h_est_px = h_est_px;
    out->ratio_w = w_px / out->w_est_px;
    out->ratio_h = h_px / out->h_est_px;
    if (touch_flags & (CYL_BLOB_TOUCH_LEFT | CYL_BLOB_TOUCH_RIGHT)) out->cut |= CYL_CONF_CUT_X;
    if (touch_flags & (CYL_BLOB_TOUCH_TOP | CYL_BLOB_TOUCH_BOTTOM)) out->cut |= CYL_CONF_CUT_Y;
    rw = cyl_conf_r(out->ratio_w);
    rh = cyl_conf_r(out->ratio_h);
    if (out->cut == 0) {
        out->confidence = rw * rh;
        out->confidence_uncut = out->confidence;
        return CYL_OK;
    }
    out->confidence = 0.0;
    if (out->cut == (CYL_CONF_CUT_X | CYL_CONF_CUT_Y)) {
        out->confidence_uncut = 0.0;
        return CYL_OK;
    }
    if (out->cut & CYL_CONF_CUT_X) rw = out->ratio_w <= 1.0 ? 1.0 : rw;
    if (out->cut & CYL_CONF_CUT_Y) rh = out->ratio_h <= 1.0 ? 1.0 : rh;
    out->confidence_uncut = rw * rh;
    return CYL_OK;
}
