/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl uncertainty model: helpers shared by rangebearing.c and observe.c (not installed). */
#ifndef CYL_UNC_INTERNAL_H
#define CYL_UNC_INTERNAL_H
#include "cyl/rangebearing.h"

/* cyl_range_bearing() for a camera already accepted by cyl_camera_check() and valid variances. */
cyl_status cyl_rb_compute(const cyl_camera *cam, cyl_geom_model model, double u_px, double v_px,
                          double var_u_px2, double var_v_px2, double cov_uv_px2, cyl_rb_result *res);
#endif
