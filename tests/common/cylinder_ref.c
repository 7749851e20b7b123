/* SPDX-License-Identifier: BSD-3-Clause */
#include "cylinder_ref.h"

#include <math.h>

int cyl_test_ray_hits_cylinder(const cyl_camera *c, double xn, double yn, double x0, double y0,
                               double diameter_m, double height_m)
{
    const double ct = cos(c->tilt_rad), st = sin(c->tilt_rad), cy = cos(c->yaw_rad), sy = sin(c->yaw_rad);
    /* camera (Xc right, Yc down, Zc forward) -> level (Xl forward, Yl right, Zl down) -> robot */
    const double Xc = xn, Yc = yn, Zc = 1.0;
    const double Yl = Xc, Xl = ct * Zc - st * Yc, Zl = st * Zc + ct * Yc;
    const double dx = cy * Xl + sy * Yl, dy = sy * Xl - cy * Yl, dz = -Zl;
    const double ox = c->offset_m - x0, oy = -y0, oz = c->height_m, r = 0.5 * diameter_m;
    const double a = dx * dx + dy * dy, b = 2 * (ox * dx + oy * dy), q = ox * ox + oy * oy - r * r;
    const double disc = b * b - 4 * a * q;
    double t1, t2, t3, t4;
    if (disc < 0 || a <= 0 || dz >= 0) return 0;  /* misses the infinite cylinder, or looks up */
    t1 = (-b - sqrt(disc)) / (2 * a);
    t2 = (-b + sqrt(disc)) / (2 * a);
    t3 = (0.5 * height_m - oz) / dz;   /* enters z = +H/2 */
    t4 = (-0.5 * height_m - oz) / dz;  /* leaves z = -H/2 */
    if (t1 < t3) t1 = t3;
    if (t2 > t4) t2 = t4;
    return t2 > t1 && t2 > 0;
}
