/* SPDX-License-Identifier: BSD-3-Clause */
/* Reference geometry for tests: does the ray through an (undistorted, normalised) image point hit
 * a solid vertical cylinder? Written from the camera conventions of cyl/camera.h and
 * cyl_rb_project() independently of libcyl's silhouette model. */
#ifndef CYL_TEST_CYLINDER_REF_H
#define CYL_TEST_CYLINDER_REF_H
#include "cyl/camera.h"

/* Cylinder of diameter_m x height_m with its centre at robot-frame (x0_m, y0_m) on the centroid
 * plane (cam->height_m below the optical centre). Returns 1 if the ray through (xn, yn) meets it
 * in front of the camera. */
int cyl_test_ray_hits_cylinder(const cyl_camera *cam, double xn, double yn, double x0_m, double y0_m,
                               double diameter_m, double height_m);
/* The ray through (xn, yn) against the solid frustum with its axis at robot-frame (x0_m, y0_m), from
 * height zb_m (radius rb_m) to zt_m (radius rt_m) above the centroid plane: the height at which it
 * first enters the solid, or NAN if it misses (the side by its quadratic, the caps as discs). */
double cyl_test_frustum_entry_z(const cyl_camera *cam, double xn, double yn, double x0_m, double y0_m, double zb_m,
                                double rb_m, double zt_m, double rt_m);
#endif
