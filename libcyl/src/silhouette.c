/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- the geometric bias of a landmark's blob centroid (cyl/silhouette.h). */
#include "cyl/config.h"
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

static void mount_of(const cyl_camera *cam, mount *mt)
{
    mt->offset_m = cam->offset_m;
    mt->height_m = cam->height_m;
    mt->cy = cos(cam->yaw_rad);
    mt->sy = sin(cam->yaw_rad);
    mt->ct = cos(cam->tilt_rad);
    mt->st = sin(cam->tilt_rad);
}

/* The radius of the polygon of CYL_SILHOUETTE_POINTS points whose area is the circle's (an
 * inscribed polygon of 48 points is 0.3% smaller). */
static double polygon_radius(double r)
{
    return r * sqrt(6.283185307179586 / (CYL_SILHOUETTE_POINTS * sin(6.283185307179586 / CYL_SILHOUETTE_POINTS)));
}

/* (x, y) order of two points */
static int before(const double *a, const double *b)
{
    return a[0] < b[0] || (a[0] == b[0] && a[1] < b[1]);
}

/* The points of a convex polygon given in cyclic order (n points at c) in (x, y) order, into out:
 * the two chains from its first point in that order to its last are each already in order when the
 * polygon is convex, so one merge sorts them. */
static void convex_sorted(const double (*c)[2], int n, double (*out)[2])
{
    int i, lo = 0, hi = 0, f, b, k = 0;
    for (i = 1; i < n; i++) {
        if (before(c[i], c[lo])) lo = i;
        if (before(c[hi], c[i])) hi = i;
    }
    /* forward chain lo, lo + 1, ..., hi; backward chain lo - 1, lo - 2, ..., hi + 1 (cyclic) */
    f = lo;
    b = (lo + n - 1) % n;
    {
        const int nf = (hi - lo + n) % n + 1, nb = n - nf;
        int tf = 0, tb = 0;
        while (tf < nf || tb < nb) {
            if (tb >= nb || (tf < nf && !before(c[b], c[f]))) {
                out[k][0] = c[f][0]; out[k][1] = c[f][1];
                if (++f == n) f = 0;
                tf++;
            } else {
                out[k][0] = c[b][0]; out[k][1] = c[b][1];
                b = (b == 0 ? n : b) - 1;
                tb++;
            }
            k++;
        }
    }
}

/* The image (normalised coordinates) of the frustum between the circle of radius r1 at height z1
 * and the circle of radius r0 at z0 (above the centroid plane), axis at robot-frame (x, y): the
 * convex hull of the two circles' points, in hull[0 .. k-1] (k returned; 0 if a point is not in
 * front of the camera or the hull is degenerate). */
static int frustum_hull(const mount *mt, double x_m, double y_m, double z1, double r1, double z0, double r0,
                        double hull[NPTS + 1][2])
{
    double p[NPTS][2];   /* the circles' points (top then bottom), then all in (x, y) order */
    int i, j, k = 0, lower;
    {   /* the circles' points by rotation: two sines per call instead of two per point */
        const double da = 6.283185307179586 / CYL_SILHOUETTE_POINTS, cd = cos(da), sd = sin(da);
        double ca = 1.0, sa = 0.0;
        for (i = 0; i < CYL_SILHOUETTE_POINTS; i++) {
            const double t = ca * cd - sa * sd;
            double *q1 = p[i], *q0 = p[CYL_SILHOUETTE_POINTS + i];
            if (!to_normalised(mt, x_m + r1 * ca, y_m + r1 * sa, z1, &q1[0], &q1[1]) ||
                !to_normalised(mt, x_m + r0 * ca, y_m + r0 * sa, z0, &q0[0], &q0[1]))
                return 0;
            sa = sa * cd + ca * sd;
            ca = t;
        }
    }
    /* sort by (x, y): each circle's image is convex with its points in cyclic order, so it comes
     * out in order from one merge of its two chains (into hull, free until the chain below), and
     * one more merge orders both; the insertion sort after them only settles what rounding left
     * out of order (one comparison a point when there is nothing to move) */
    convex_sorted((const double (*)[2])p, CYL_SILHOUETTE_POINTS, hull);
    convex_sorted((const double (*)[2])(p + CYL_SILHOUETTE_POINTS), CYL_SILHOUETTE_POINTS, hull + CYL_SILHOUETTE_POINTS);
    {
        const double (*s1)[2] = (const double (*)[2])hull, (*s0)[2] = (const double (*)[2])(hull + CYL_SILHOUETTE_POINTS);
        int a = 0, b = 0;
        for (i = 0; i < NPTS; i++) {
            const double *q = (b >= CYL_SILHOUETTE_POINTS ||
                               (a < CYL_SILHOUETTE_POINTS && !before(s0[b], s1[a]))) ? s1[a++] : s0[b++];
            p[i][0] = q[0];
            p[i][1] = q[1];
        }
    }
    for (i = 1; i < NPTS; i++) {
        const double t[2] = {p[i][0], p[i][1]};
        for (j = i - 1; j >= 0 && before(t, p[j]); j--) {
            p[j + 1][0] = p[j][0];
            p[j + 1][1] = p[j][1];
        }
        p[j + 1][0] = t[0];
        p[j + 1][1] = t[1];
    }
    /* Andrew's monotone chain: lower hull, then upper hull (every hull comes out with the same
     * orientation, so areas of hulls and of their clipped parts add and subtract) */
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
    return k < 3 ? 0 : k;
}

/* Area moments of a polygon (normalised coordinates, n points) in the image, with the lens: each
 * edge, straight in normalised coordinates, is cut into pieces of at most PIECE_PX px whose ends
 * are projected through the lens model (each point once), so a large blob's distortion moves its
 * centroid as it does in the image. Adds twice the signed area to m[0] and 6 x area x centroid
 * to m[1], m[2] (shoelace). */
static void pixel_moments(const cyl_camera *cam, const double (*poly)[2], int n, double m[3])
{
    double u0, v0;
    int i;
    if (n < 3) return;
    cyl_camera_project(cam, poly[0][0], poly[0][1], &u0, &v0);
    for (i = 0; i < n; i++) {
        const double *a = poly[i], *b = poly[(i + 1) % n];
        const double ex = (b[0] - a[0]) * cam->fx_px, ey = (b[1] - a[1]) * cam->fy_px;
        const double len_px = sqrt(ex * ex + ey * ey);
        const int pieces = 1 + (int)(len_px / PIECE_PX);
        int k;
        for (k = 1; k <= pieces; k++) {
            double u1, v1, c;
            const double t = (double)k / pieces;
            cyl_camera_project(cam, a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), &u1, &v1);
            c = u0 * v1 - u1 * v0;
            m[0] += c;
            m[1] += (u0 + u1) * c;
            m[2] += (v0 + v1) * c;
            u0 = u1;
            v0 = v1;
        }
    }
}

static cyl_status finish(const cyl_camera *cam, const double m[3], double xc, double yc, double rel_sigma,
                         double sigma_px, cyl_silhouette_bias *out)
{
    double uc, vc;
    if (!(fabs(m[0]) > 0.0)) return CYL_ERR_NO_RANGE;
    cyl_camera_project(cam, xc, yc, &uc, &vc);
    out->du_px = m[1] / (3.0 * m[0]) - uc;
    out->dv_px = m[2] / (3.0 * m[0]) - vc;
    out->var_u_px2 = rel_sigma * rel_sigma * out->du_px * out->du_px + sigma_px * sigma_px;
    out->var_v_px2 = rel_sigma * rel_sigma * out->dv_px * out->dv_px + sigma_px * sigma_px;
    out->area_px2 = 0.5 * fabs(m[0]);
    return CYL_OK;
}

static int sigmas_ok(double rel_sigma, double sigma_px)
{
    return rel_sigma >= 0.0 && isfinite(rel_sigma) && sigma_px >= 0.0 && isfinite(sigma_px);
}

cyl_status cyl_silhouette_bias_at(const cyl_camera *cam, double x_m, double y_m, const cyl_landmark_size *size,
                                  double rel_sigma, double sigma_px, cyl_silhouette_bias *out)
{
    double hull[NPTS + 1][2], m[3] = {0.0, 0.0, 0.0}, r, xc, yc;
    mount mt;
    int k;
    cyl_status s;
    if (!cam || !size || !out || !isfinite(x_m) || !isfinite(y_m) || !sigmas_ok(rel_sigma, sigma_px))
        return CYL_ERR_ARG;
    if (!(size->diameter_m > 0.0) || !(size->height_m > 0.0) || !isfinite(size->diameter_m) ||
        !isfinite(size->height_m))
        return CYL_ERR_ARG;
    s = cyl_camera_check(cam);
    if (s != CYL_OK) return s;
    r = polygon_radius(0.5 * size->diameter_m);
    mount_of(cam, &mt);
    k = frustum_hull(&mt, x_m, y_m, 0.5 * size->height_m, r, -0.5 * size->height_m, r, hull);
    if (!k || !to_normalised(&mt, x_m, y_m, 0.0, &xc, &yc)) return CYL_ERR_NO_RANGE;
    pixel_moments(cam, (const double (*)[2])hull, k, m);
    return finish(cam, m, xc, yc, rel_sigma, sigma_px, out);
}

/* subject (convex, n points) clipped to the convex polygon clip (nc points): Sutherland-Hodgman,
 * the result in out (at most n + nc points), its count returned. */
#if CYL_CONFIG_MODELS
#define CLIP_MAX (2 * NPTS + 4)
static int clip_convex(const double (*subject)[2], int n, const double (*clip)[2], int nc,
                       double (*out)[2], double (*tmp)[2])
{
    double orient = 0.0;
    int i, e, cnt = n;
    for (i = 0; i < nc; i++) {
        const double *a = clip[i], *b = clip[(i + 1) % nc];
        orient += a[0] * b[1] - b[0] * a[1];
    }
    orient = orient > 0.0 ? 1.0 : -1.0;
    for (i = 0; i < n; i++) {
        out[i][0] = subject[i][0];
        out[i][1] = subject[i][1];
    }
    for (e = 0; e < nc && cnt > 0; e++) {
        const double *a = clip[e], *b = clip[(e + 1) % nc];
        int j, m = 0;
        for (j = 0; j < cnt; j++) {
            tmp[j][0] = out[j][0];
            tmp[j][1] = out[j][1];
        }
        for (j = 0; j < cnt; j++) {
            const double *p = tmp[j], *q = tmp[(j + 1) % cnt];
            const double dp = orient * cross(a, b, p), dq = orient * cross(a, b, q);
            if (dp >= 0.0 && m < CLIP_MAX) {
                out[m][0] = p[0];
                out[m][1] = p[1];
                m++;
            }
            if (((dp >= 0.0) != (dq >= 0.0)) && m < CLIP_MAX) {
                const double t = dp / (dp - dq);
                out[m][0] = p[0] + t * (q[0] - p[0]);
                out[m][1] = p[1] + t * (q[1] - p[1]);
                m++;
            }
        }
        cnt = m;
    }
    return cnt;
}

cyl_status cyl_silhouette_bias_model(const cyl_camera *cam, double x_m, double y_m,
                                     const cyl_landmark_model *model, double base_z_m, uint32_t band_mask,
                                     double rel_sigma, double sigma_px, cyl_silhouette_bias *out)
{
    double hull[NPTS + 1][2], occ[NPTS + 1][2], cut[CLIP_MAX][2], tmp[CLIP_MAX][2];
    double m[3] = {0.0, 0.0, 0.0}, z_band[CYL_MODEL_MAX_BANDS + 1], xc, yc;
    double r_bot;
    mount mt;
    int k, counted = 0;
    cyl_status s;
    if (!cam || !model || !out || !isfinite(x_m) || !isfinite(y_m) || !isfinite(base_z_m) ||
        !sigmas_ok(rel_sigma, sigma_px))
        return CYL_ERR_ARG;
    s = cyl_landmark_models_check(model, 1);
    if (s != CYL_OK) return CYL_ERR_ARG;
    if (band_mask == 0 || (band_mask >> model->n_bands) != 0) return CYL_ERR_ARG;
    s = cyl_camera_check(cam);
    if (s != CYL_OK) return s;
    mount_of(cam, &mt);
    /* band k spans z_band[k + 1] .. z_band[k] (top to bottom; z above the centroid plane) */
    z_band[model->n_bands] = base_z_m;
    for (k = model->n_bands - 1; k >= 0; k--) z_band[k] = z_band[k + 1] + model->band_height_m[k];
    r_bot = polygon_radius(0.5 * model->diameter_bottom_m);
#define RADIUS_AT(z) polygon_radius(0.5 * cyl_landmark_diameter_at_m(model, (z) - base_z_m))
    for (k = 0; k < model->n_bands; k++) {
        const double z1 = z_band[k], z0 = z_band[k + 1];
        double mk[3] = {0.0, 0.0, 0.0}, mc[3] = {0.0, 0.0, 0.0};
        int nh, no = 0, nc;
        if (!(band_mask & (1u << k))) continue;
        nh = frustum_hull(&mt, x_m, y_m, z1, RADIUS_AT(z1), z0, RADIUS_AT(z0), hull);
        if (!nh) return CYL_ERR_NO_RANGE;
        pixel_moments(cam, (const double (*)[2])hull, nh, mk);
        /* what hides part of the band: seen from above its top, the landmark above it; from below
         * its bottom, the landmark below it (the whole is convex, so each part is a frustum) */
        if (mt.height_m > z1 && k > 0)
            no = frustum_hull(&mt, x_m, y_m, z_band[0], RADIUS_AT(z_band[0]), z1, RADIUS_AT(z1), occ);
        else if (mt.height_m < z0 && k < model->n_bands - 1)
            no = frustum_hull(&mt, x_m, y_m, z0, RADIUS_AT(z0), base_z_m, r_bot, occ);
        if (no) {
            nc = clip_convex((const double (*)[2])hull, nh, (const double (*)[2])occ, no, cut, tmp);
            pixel_moments(cam, (const double (*)[2])cut, nc, mc);
        }
        m[0] += mk[0] - mc[0];
        m[1] += mk[1] - mc[1];
        m[2] += mk[2] - mc[2];
        counted++;
    }
#undef RADIUS_AT
    if (!counted || !to_normalised(&mt, x_m, y_m, 0.0, &xc, &yc)) return CYL_ERR_NO_RANGE;
    return finish(cam, m, xc, yc, rel_sigma, sigma_px, out);
}

#else /* CYL_CONFIG_MODELS */

cyl_status cyl_silhouette_bias_model(const cyl_camera *cam, double x_m, double y_m,
                                     const cyl_landmark_model *model, double base_z_m, uint32_t band_mask,
                                     double rel_sigma, double sigma_px, cyl_silhouette_bias *out)
{
    (void)cam; (void)x_m; (void)y_m; (void)model; (void)base_z_m; (void)band_mask; (void)rel_sigma;
    (void)sigma_px; (void)out;
    return CYL_ERR_UNSUPPORTED;
}
#endif
