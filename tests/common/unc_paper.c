/* SPDX-License-Identifier: BSD-3-Clause */
#include "unc_paper.h"

void unc_paper_camera(cyl_camera *cam)
{
    static const double sig[CYL_INTR_COUNT] = {0.4565, 0.4399, 0.3216, 0.2826, 0, 0, 0, 0, 0};
    cyl_camera_init(cam);
    cam->width = 768;
    cam->height = 576;
    cam->fx_px = 875.2;
    cam->fy_px = 872.4;
    cam->cx_px = 386.3;
    cam->cy_px = 278.8;
    cyl_camera_set_intrinsic_sigmas(cam, sig);
    cam->tilt_rad = 1.656 * UNC_DEG;
    cam->tilt_sigma_rad = 0.575 * UNC_DEG;
    cam->yaw_rad = 0.0;
    cam->yaw_sigma_rad = 0.443 * UNC_DEG;
    cam->height_m = 0.326;
    cam->height_sigma_m = 3.04e-4;
    cam->offset_m = 0.15;
    cam->offset_sigma_m = 0.005 / 1.96;
    cam->flags = 0;
}

void unc_distorted_camera(cyl_camera *cam)
{
    static const double sig[CYL_INTR_COUNT] = {0.4565, 0.4399, 0.3216, 0.2826,
                                               4e-3, 1e-2, 2e-4, 2e-4, 1e-2};
    unc_paper_camera(cam);
    cam->k1 = -0.25;
    cam->k2 = 0.12;
    cam->p1 = 8e-4;
    cam->p2 = -5e-4;
    cam->k3 = -0.02;
    cyl_camera_set_intrinsic_sigmas(cam, sig);
}
