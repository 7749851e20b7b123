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

/* The ray through normalised (xn, yn) against the solid frustum with its axis at robot-frame
 * (x0, y0), from zb (radius rb) to zt (radius rt), z above the centroid plane: the height of the
 * first point where it enters, or NAN if it misses. Written from the conventions of
 * cylinder_ref.c: the side by its quadratic, the caps as discs, the smallest positive t. */
double cyl_test_frustum_entry_z(const cyl_camera *c, double xn, double yn, double x0, double y0, double zb, double rb,
                           double zt, double rt)
{
    const double ct = cos(c->tilt_rad), st = sin(c->tilt_rad), cy = cos(c->yaw_rad), sy = sin(c->yaw_rad);
    const double Yl = xn, Xl = ct - st * yn, Zl = st + ct * yn;
    const double dx = cy * Xl + sy * Yl, dy = sy * Xl - cy * Yl, dz = -Zl;
    const double ox = c->offset_m - x0, oy = -y0, oz = c->height_m;
    const double k = (rt - rb) / (zt - zb), a0 = rb - k * zb;   /* R(z) = a0 + k z */
    const double A = dx * dx + dy * dy - k * k * dz * dz;
    const double B = 2 * (ox * dx + oy * dy - k * (a0 + k * oz) * dz);
    const double C = ox * ox + oy * oy - (a0 + k * oz) * (a0 + k * oz);
    double best = INFINITY, zbest = NAN, disc = B * B - 4 * A * C;
    int i;
    if (disc >= 0 && A != 0) {
        for (i = -1; i <= 1; i += 2) {
            double t = (-B + i * sqrt(disc)) / (2 * A), z = oz + t * dz;
            if (t > 0 && z >= zb && z <= zt && a0 + k * z >= 0 && t < best) { best = t; zbest = z; }
        }
    }
    if (dz != 0) {
        double zs[2] = {zt, zb}, rs[2] = {rt, rb};
        for (i = 0; i < 2; i++) {
            double t = (zs[i] - oz) / dz, qx = ox + t * dx, qy = oy + t * dy;
            if (t > 0 && qx * qx + qy * qy <= rs[i] * rs[i] && t < best) { best = t; zbest = zs[i]; }
        }
    }
    return zbest;
}
