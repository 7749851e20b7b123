/* SPDX-License-Identifier: BSD-3-Clause */
/* The paper's Pioneer camera (Tables 4 and 5) for the uncertainty tests, plus the choices
 * documented in docs/uncertainty.md (s, its sigma, image size, no distortion). The same values
 * are in calib_data/paper_camera.yaml, which the C++ tools read. */
#ifndef CYL_TEST_UNC_PAPER_H
#define CYL_TEST_UNC_PAPER_H
#include "cyl/camera.h"

#define UNC_DEG (3.14159265358979323846 / 180.0)

/* Table 4/5 camera, s = 0.15 m, sigma_s = 0.005/1.96 m, 768x576, zero distortion (sigma 0). */
void unc_paper_camera(cyl_camera *cam);

/* Same camera with a moderate lens distortion and distortion sigmas (for tests that need the
 * distortion path exercised): k1 -0.25, k2 0.12, p1 8e-4, p2 -5e-4, k3 -0.02. */
void unc_distorted_camera(cyl_camera *cam);
#endif
