/* SPDX-License-Identifier: BSD-3-Clause */
/* The silhouette's geometric bias (cyl_silhouette_bias_at) against a brute-force reference: rays
 * cast through 4x4 samples of every pixel around the landmark, each intersected with the solid
 * cylinder, the hits' mean pixel position minus the projection of the centre. Straight ahead the
 * offset is vertical only; argument errors. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <string.h>

#include "cyl/silhouette.h"
#include "cyl/rangebearing.h"
#include "cylinder_ref.h"

#define DEG (3.14159265358979323846 / 180.0)

static cyl_camera synthetic_camera(int distorted, double yaw_deg)
{
    cyl_camera c;
    cyl_camera_init(&c);
    c.width = 640; c.height = 480;
    c.fx_px = 570; c.fy_px = 568; c.cx_px = 322.4; c.cy_px = 236.9;
    if (distorted) { c.k1 = -0.12; c.k2 = 0.05; c.p1 = 0.0008; c.p2 = -0.0006; }
    c.tilt_rad = 12 * DEG;
    c.yaw_rad = yaw_deg * DEG;
    c.height_m = 0.326;
    c.offset_m = 0.10;
    return c;
}

static void reference(const cyl_camera *c, double x0, double y0, const cyl_landmark_size *s, double *du, double *dv)
{
    const int ss = 4;
    double su = 0, sv = 0, uc, vc;
    long n = 0;
    int u, v, i, j;
    assert_int_equal(cyl_rb_project(c, x0, y0, &uc, &vc), CYL_OK);
    for (v = (int)vc - 200; v <= (int)vc + 200; v++)
        for (u = (int)uc - 100; u <= (int)uc + 100; u++)
            for (j = 0; j < ss; j++)
                for (i = 0; i < ss; i++) {
                    double pu = u - 0.5 + (i + 0.5) / ss, pv = v - 0.5 + (j + 0.5) / ss, xn, yn;
                    if (cyl_camera_undistort(c, pu, pv, &xn, &yn) != CYL_OK) continue;
                    if (cyl_test_ray_hits_cylinder(c, xn, yn, x0, y0, s->diameter_m, s->height_m)) { su += pu; sv += pv; n++; }
                }
    assert_true(n > 1000);
    *du = su / n - uc;
    *dv = sv / n - vc;
}

static void test_against_ray_casting(void **state)
{
    static const double pos[][2] = {{1.0, 0.0}, {0.9, 0.3}, {1.4, -0.5}, {2.2, 0.6}, {3.0, -1.0}};
    const cyl_landmark_size s = {0.10, 0.30};
    int d, k;
    (void)state;
    for (d = 0; d < 2; d++) {
        cyl_camera c = synthetic_camera(d, d ? 4.0 : 0.0);
        for (k = 0; k < 5; k++) {
            cyl_silhouette_bias b;
            double du, dv;
            assert_int_equal(cyl_silhouette_bias_at(&c, pos[k][0], pos[k][1], &s, 0.25, 0.1, &b), CYL_OK);
            reference(&c, pos[k][0], pos[k][1], &s, &du, &dv);
            print_message("  lens %d at (%.1f, %.1f): model du %+.3f dv %+.3f, ray casting du %+.3f dv %+.3f px\n", d,
                          pos[k][0], pos[k][1], b.du_px, b.dv_px, du, dv);
            assert_true(fabs(b.du_px - du) < 0.03);
            assert_true(fabs(b.dv_px - dv) < 0.03);
            assert_true(fabs(b.var_u_px2 - (0.0625 * b.du_px * b.du_px + 0.01)) < 1e-15);
            assert_true(fabs(b.var_v_px2 - (0.0625 * b.dv_px * b.dv_px + 0.01)) < 1e-15);
        }
    }
}

/* Straight ahead with a pinhole the silhouette is symmetric about the centre's column; the
 * centroid lies above the centre (the top cap is seen from above), more so when nearer. */
static void test_straight_ahead_is_vertical(void **state)
{
    const cyl_landmark_size s = {0.10, 0.30};
    cyl_camera c = synthetic_camera(0, 0.0);
    cyl_silhouette_bias near, far;
    (void)state;
    assert_int_equal(cyl_silhouette_bias_at(&c, 1.0, 0.0, &s, 0.0, 0.0, &near), CYL_OK);
    assert_int_equal(cyl_silhouette_bias_at(&c, 3.0, 0.0, &s, 0.0, 0.0, &far), CYL_OK);
    assert_true(fabs(near.du_px) < 1e-9 && fabs(far.du_px) < 1e-9);
    assert_true(near.dv_px < 0 && near.dv_px < far.dv_px);
    assert_true(near.var_u_px2 == 0.0 && near.var_v_px2 == 0.0);
}

/* ---- landmarks of several bands (cyl_silhouette_bias_model) ---- */

/* ray-cast centroid of the visible parts of the bands in mask, minus the image of the axis point */
static void reference_model(const cyl_camera *c, double x0, double y0, const cyl_landmark_model *m, double base_z,
                            unsigned mask, double *du, double *dv)
{
    const int ss = 3;   /* 3 x 3 rays a pixel: the reference within about 0.02 px, and fast under qemu */
    double su = 0, sv = 0, uc, vc, zb[CYL_MODEL_MAX_BANDS + 1], top;
    double rt = m->shape == CYL_SHAPE_CONE ? 0.5 * m->diameter_top_m : 0.5 * m->diameter_bottom_m;
    long n = 0;
    int u, v, i, j, k;
    zb[m->n_bands] = base_z;
    for (k = m->n_bands - 1; k >= 0; k--) zb[k] = zb[k + 1] + m->band_height_m[k];
    top = zb[0];
    assert_int_equal(cyl_rb_project(c, x0, y0, &uc, &vc), CYL_OK);
    for (v = (int)vc - 220; v <= (int)vc + 220; v++)
        for (u = (int)uc - 150; u <= (int)uc + 150; u++)
            for (j = 0; j < ss; j++)
                for (i = 0; i < ss; i++) {
                    double pu = u - 0.5 + (i + 0.5) / ss, pv = v - 0.5 + (j + 0.5) / ss, xn, yn, z;
                    if (cyl_camera_undistort(c, pu, pv, &xn, &yn) != CYL_OK) continue;
                    z = cyl_test_frustum_entry_z(c, xn, yn, x0, y0, base_z, 0.5 * m->diameter_bottom_m, top, rt);
                    if (isnan(z)) continue;
                    for (k = 0; k < m->n_bands; k++)
                        if (z >= zb[k + 1] && z <= zb[k]) break;
                    if (k < m->n_bands && (mask & (1u << k))) { su += pu; sv += pv; n++; }
                }
    assert_true(n > 1000);
    *du = su / n - uc;
    *dv = sv / n - vc;
}

static void test_model_one_band_is_the_cylinder(void **state)
{
    const cyl_landmark_size s = {0.10, 0.30};
    cyl_landmark_model m;
    cyl_camera c = synthetic_camera(1, 4.0);
    cyl_silhouette_bias a, b;
    (void)state;
    memset(&m, 0, sizeof m);
    m.n_bands = 1; m.band_cls[0] = 0; m.band_height_m[0] = 0.30; m.diameter_bottom_m = 0.10; m.id = -1;
    assert_int_equal(cyl_silhouette_bias_at(&c, 1.4, -0.5, &s, 0.25, 0.1, &a), CYL_OK);
    assert_int_equal(cyl_silhouette_bias_model(&c, 1.4, -0.5, &m, -0.15, 1u, 0.25, 0.1, &b), CYL_OK);
    assert_true(fabs(a.du_px - b.du_px) < 1e-12 && fabs(a.dv_px - b.dv_px) < 1e-12);
    assert_true(fabs(a.area_px2 - b.area_px2) < 1e-9 * a.area_px2);
}

/* A striped cone (orange / unclassified stripe / orange, base 0.25 m, top 0.05 m, 0.30 m) and a
 * three-band coded cylinder, standing on the floor 0.15 m below the centroid plane; the camera
 * 0.326 m above that plane, so it looks down on both. Some bands left out of the mask: the
 * stripe always, one code band. */
static void test_model_against_ray_casting(void **state)
{
    static const double pos[][2] = {{1.0, 0.0}, {2.5, -0.6}};
    cyl_landmark_model cone, code;
    int d, k;
    (void)state;
    memset(&cone, 0, sizeof cone);
    cone.n_bands = 3; cone.band_cls[0] = 0; cone.band_cls[1] = CYL_BAND_GAP; cone.band_cls[2] = 0;
    cone.band_height_m[0] = 0.10; cone.band_height_m[1] = 0.05; cone.band_height_m[2] = 0.15;
    cone.shape = CYL_SHAPE_CONE; cone.diameter_bottom_m = 0.25; cone.diameter_top_m = 0.05; cone.id = -1;
    memset(&code, 0, sizeof code);
    code.n_bands = 3; code.band_cls[0] = 1; code.band_cls[1] = 2; code.band_cls[2] = 1;
    code.band_height_m[0] = code.band_height_m[1] = code.band_height_m[2] = 0.10;
    code.diameter_bottom_m = 0.10; code.id = 5;
    for (d = 0; d < 2; d++) {
        cyl_camera c = synthetic_camera(d, d ? 4.0 : 0.0);
        for (k = 0; k < 2; k++) {
            static const unsigned masks[2][2] = {{0x5u, 0x4u}, {0x7u, 0x6u}};
            int mi, w;
            for (mi = 0; mi < 2; mi++)
                for (w = 0; w < 2; w++) {
                    const cyl_landmark_model *m = mi ? &code : &cone;
                    cyl_silhouette_bias b;
                    double du, dv;
                    assert_int_equal(cyl_silhouette_bias_model(&c, pos[k][0], pos[k][1], m, -0.15, masks[mi][w],
                                                               0.0, 0.0, &b), CYL_OK);
                    reference_model(&c, pos[k][0], pos[k][1], m, -0.15, masks[mi][w], &du, &dv);
                    print_message("  %s mask %x lens %d at (%.1f, %.1f): model du %+.3f dv %+.3f, ray casting "
                                  "du %+.3f dv %+.3f px\n", mi ? "code" : "cone", masks[mi][w], d, pos[k][0],
                                  pos[k][1], b.du_px, b.dv_px, du, dv);
                    assert_true(fabs(b.du_px - du) < 0.04);
                    assert_true(fabs(b.dv_px - dv) < 0.04);
                }
        }
    }
}

static void test_model_bad_arguments(void **state)
{
    cyl_landmark_model m;
    cyl_camera c = synthetic_camera(0, 0.0);
    cyl_silhouette_bias b;
    (void)state;
    memset(&m, 0, sizeof m);
    m.n_bands = 2; m.band_cls[0] = 0; m.band_cls[1] = 1; m.band_height_m[0] = m.band_height_m[1] = 0.1;
    m.diameter_bottom_m = 0.1; m.id = -1;
    assert_int_equal(cyl_silhouette_bias_model(&c, 1, 0, &m, -0.15, 0x3u, 0.25, 0.1, &b), CYL_OK);
    assert_int_equal(cyl_silhouette_bias_model(&c, 1, 0, &m, -0.15, 0x0u, 0.25, 0.1, &b), CYL_ERR_ARG);
    assert_int_equal(cyl_silhouette_bias_model(&c, 1, 0, &m, -0.15, 0x4u, 0.25, 0.1, &b), CYL_ERR_ARG);
    assert_int_equal(cyl_silhouette_bias_model(&c, 1, 0, NULL, -0.15, 0x1u, 0.25, 0.1, &b), CYL_ERR_ARG);
    assert_int_equal(cyl_silhouette_bias_model(&c, 1, 0, &m, NAN, 0x1u, 0.25, 0.1, &b), CYL_ERR_ARG);
    assert_int_equal(cyl_silhouette_bias_model(&c, -1, 0, &m, -0.15, 0x1u, 0.25, 0.1, &b), CYL_ERR_NO_RANGE);
    m.band_height_m[1] = 0.0;
    assert_int_equal(cyl_silhouette_bias_model(&c, 1, 0, &m, -0.15, 0x1u, 0.25, 0.1, &b), CYL_ERR_ARG);
}

static void test_bad_arguments(void **state)
{
    const cyl_landmark_size s = {0.10, 0.30}, zero = {0.0, 0.30}, flat = {0.10, 0.0};
    cyl_camera c = synthetic_camera(0, 0.0);
    cyl_silhouette_bias b;
    (void)state;
    assert_int_equal(cyl_silhouette_bias_at(NULL, 1, 0, &s, 0.25, 0.1, &b), CYL_ERR_ARG);
    assert_int_equal(cyl_silhouette_bias_at(&c, 1, 0, NULL, 0.25, 0.1, &b), CYL_ERR_ARG);
    assert_int_equal(cyl_silhouette_bias_at(&c, 1, 0, &s, 0.25, 0.1, NULL), CYL_ERR_ARG);
    assert_int_equal(cyl_silhouette_bias_at(&c, 1, 0, &zero, 0.25, 0.1, &b), CYL_ERR_ARG);
    assert_int_equal(cyl_silhouette_bias_at(&c, 1, 0, &flat, 0.25, 0.1, &b), CYL_ERR_ARG);
    assert_int_equal(cyl_silhouette_bias_at(&c, 1, 0, &s, -0.1, 0.1, &b), CYL_ERR_ARG);
    assert_int_equal(cyl_silhouette_bias_at(&c, NAN, 0, &s, 0.25, 0.1, &b), CYL_ERR_ARG);
    assert_int_equal(cyl_silhouette_bias_at(&c, 1, 0, &s, 0.25, -0.1, &b), CYL_ERR_ARG);
    assert_int_equal(cyl_silhouette_bias_at(&c, 1, 0, &s, 0.25, INFINITY, &b), CYL_ERR_ARG);
    /* behind the camera */
    assert_int_equal(cyl_silhouette_bias_at(&c, -1.0, 0, &s, 0.25, 0.1, &b), CYL_ERR_NO_RANGE);
    c.fx_px = -1;
    assert_int_not_equal(cyl_silhouette_bias_at(&c, 1, 0, &s, 0.25, 0.1, &b), CYL_OK);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_against_ray_casting),
        cmocka_unit_test(test_straight_ahead_is_vertical),
        cmocka_unit_test(test_bad_arguments),
        cmocka_unit_test(test_model_one_band_is_the_cylinder),
        cmocka_unit_test(test_model_against_ray_casting),
        cmocka_unit_test(test_model_bad_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
