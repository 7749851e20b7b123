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
    double rw, rh;
    if (!size || !out) return CYL_ERR_ARG;
    memset(out, 0, sizeof *out);
    if (!(w_px > 0.0) || !(h_px > 0.0) || !(depth_m > 0.0) || !(fx_px > 0.0) || !(fy_px > 0.0) ||
        !(size->diameter_m > 0.0) || !(size->height_m > 0.0) || !isfinite(depth_m))
        return CYL_ERR_ARG;
    out->w_est_px = fx_px * size->diameter_m / depth_m;
    out->h_est_px = fy_px * size->height_m / depth_m;
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
