/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- the geometric bias of a landmark's blob centroid (cyl/silhouette.h). */
#include "cyl/silhouette.h"

#include <math.h>

#define NPTS (2 * CYL_SILHOUETTE_POINTS)
#define PIECE_PX 4.0  /* longest straight piece of the outline taken through the lens, px */

/* The camera's mount, its sines and cosines computed once per call. */
typedef struct mount {
    double offset_m, height_m, cy, sy, ct, st;
} mount;

/* A point at robot-frame (x, y) and z_up above the centroid plane -> undistorted normalised image
 * coordinates (the frames of cyl_rb_project). Returns 0 if the point is not in front. */
static int to_normalised(const mount *m, double x_m, double y_m, double z_up_m, double *xn, double *yn)
{
    const double dx = x_m - m->offset_m, dy = y_m;
    const double Xl = m->cy * dx + m->sy * dy;   /* level frame: forward, right, down */
    const double Yl = m->sy * dx - m->cy * dy;
    const double Zl = m->height_m - z_up_m;
    const double Xc = Yl, Yc = -m->st * Xl + m->ct * Zl, Zc = m->ct * Xl + m->st * Zl;
    if (!(Zc > 1e-9)) return 0;
    *xn = Xc / Zc;
    *yn = Yc / Zc;
    return 1;
}

static double cross(const double *o, const double *a, const double *b)
{
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

cyl_status cyl_silhouette_bias_at(const cyl_camera *cam, double x_m, double y_m, const cyl_landmark_size *size,
                                  double rel_sigma, double sigma_px, cyl_silhouette_bias *out)
{
    double p[NPTS][2], hull[NPTS + 1][2];
    double r, xc, yc, a2 = 0.0, sx = 0.0, sy = 0.0, uc, vc, us, vs;
    mount mt;
    int i, j, k = 0, lower;
    cyl_status s;
    if (!cam || !size || !out || !isfinite(x_m) || !isfinite(y_m) || !(rel_sigma >= 0.0) || !isfinite(rel_sigma) ||
        !(sigma_px >= 0.0) || !isfinite(sigma_px))
        return CYL_ERR_ARG;
    if (!(size->diameter_m > 0.0) || !(size->height_m > 0.0) || !isfinite(size->diameter_m) ||
        !isfinite(size->height_m))
        return CYL_ERR_ARG;
    s = cyl_camera_check(cam);
    if (s != CYL_OK) return s;
    /* the radius of the polygon whose area is the circle's (an inscribed polygon of 48 points is
     * 0.3% smaller) */
    r = 0.5 * size->diameter_m *
        sqrt(6.283185307179586 / (CYL_SILHOUETTE_POINTS * sin(6.283185307179586 / CYL_SILHOUETTE_POINTS)));
    mt.offset_m = cam->offset_m;
    mt.height_m = cam->height_m;
    mt.cy = cos(cam->yaw_rad);
    mt.sy = sin(cam->yaw_rad);
    mt.ct = cos(cam->tilt_rad);
    mt.st = sin(cam->tilt_rad);
    {   /* the circle's points by rotation: two sines per call instead of two per point */
        const double da = 6.283185307179586 / CYL_SILHOUETTE_POINTS, cd = cos(da), sd = sin(da);
        double ca = 1.0, sa = 0.0;
        for (i = 0; i < CYL_SILHOUETTE_POINTS; i++) {
            const double px = x_m + r * ca, py = y_m + r * sa, t = ca * cd - sa * sd;
            if (!to_normalised(&mt, px, py, 0.5 * size->height_m, &p[2 * i][0], &p[2 * i][1]) ||
                !to_normalised(&mt, px, py, -0.5 * size->height_m, &p[2 * i + 1][0], &p[2 * i + 1][1]))
                return CYL_ERR_NO_RANGE;
            sa = sa * cd + ca * sd;
            ca = t;
        }
    }
    if (!to_normalised(&mt, x_m, y_m, 0.0, &xc, &yc)) return CYL_ERR_NO_RANGE;
    /* sort by (x, y): insertion sort, NPTS is small */
    for (i = 1; i < NPTS; i++) {
        double t0 = p[i][0], t1 = p[i][1];
        for (j = i - 1; j >= 0 && (p[j][0] > t0 || (p[j][0] == t0 && p[j][1] > t1)); j--) {
            p[j + 1][0] = p[j][0];
            p[j + 1][1] = p[j][1];
        }
        p[j + 1][0] = t0;
        p[j + 1][1] = t1;
    }
    /* Andrew's monotone chain: lower hull, then upper hull (counter-clockwise in x right, y down
     * is clockwise on screen; the sign of the area is handled below) */
    for (i = 0; i < NPTS; i++) {
        while (k >= 2 && cross(hull[k - 2], hull[k - 1], p[i]) <= 0.0) k--;
        hull[k][0] = p[i][0];
        hull[k][1] = p[i][1];
        k++;
    }
    lower = k + 1;
    for (i = NPTS - 2; i >= 0; i--) {
        while (k >= lower && cross(hull[k - 2], hull[k - 1], p[i]) <= 0.0) k--;
        hull[k][0] = p[i][0];
        hull[k][1] = p[i][1];
        k++;
    }
    k--;  /* the last point repeats the first */
    if (k < 3) return CYL_ERR_NO_RANGE;
    /* Area centroid in the image (shoelace), with the lens: each hull edge, straight in
     * normalised coordinates, is cut into pieces of at most PIECE_PX px whose ends are projected
     * through the lens model (each point once), so a large blob's distortion moves its centroid as
     * it does in the image. */
    {
        double u0, v0;
        cyl_camera_project(cam, hull[0][0], hull[0][1], &u0, &v0);
        for (i = 0; i < k; i++) {
            const double *a = hull[i], *b = hull[(i + 1) % k];
            const double ex = (b[0] - a[0]) * cam->fx_px, ey = (b[1] - a[1]) * cam->fy_px;
            const double len_px = sqrt(ex * ex + ey * ey);
            const int pieces = 1 + (int)(len_px / PIECE_PX);
            int m;
            for (m = 1; m <= pieces; m++) {
                double u1, v1, c;
                const double t = (double)m / pieces;
                cyl_camera_project(cam, a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), &u1, &v1);
                c = u0 * v1 - u1 * v0;
                a2 += c;
                sx += (u0 + u1) * c;
                sy += (v0 + v1) * c;
                u0 = u1;
                v0 = v1;
            }
        }
    }
    if (!(fabs(a2) > 0.0)) return CYL_ERR_NO_RANGE;
    us = sx / (3.0 * a2);
    vs = sy / (3.0 * a2);
    cyl_camera_project(cam, xc, yc, &uc, &vc);
    out->du_px = us - uc;
    out->dv_px = vs - vc;
    out->var_u_px2 = rel_sigma * rel_sigma * out->du_px * out->du_px + sigma_px * sigma_px;
    out->var_v_px2 = rel_sigma * rel_sigma * out->dv_px * out->dv_px + sigma_px * sigma_px;
    out->area_px2 = 0.5 * fabs(a2);
    return CYL_OK;
}
