/* SPDX-License-Identifier: BSD-3-Clause */
/* Camera model: distortion Jacobian, undistortion round trip and its Jacobians against
 * central differences, camera validation. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <string.h>
#include <math.h>
#include <cmocka.h>

#include "cyl/camera.h"
#include "unc_paper.h"

static double rel_err(double a, double n, double scale)
{
    double d = fabs(n) > scale ? fabs(n) : scale;
    return fabs(a - n) / d;
}

static void test_distort_jacobian(void **st)
{
    cyl_camera cam;
    double x, y, worst = 0;
    (void)st;
    unc_distorted_camera(&cam);
    for (x = -0.45; x <= 0.45; x += 0.05)
        for (y = -0.35; y <= 0.35; y += 0.05) {
            double j[2][2], h = 1e-6, a[2], b[2];
            int c, r;
            cyl_camera_distort(&cam, x, y, NULL, NULL, j);
            for (c = 0; c < 2; c++) {
                double xp = x + (c == 0 ? h : 0), yp = y + (c == 1 ? h : 0);
                double xm = x - (c == 0 ? h : 0), ym = y - (c == 1 ? h : 0);
                cyl_camera_distort(&cam, xp, yp, &a[0], &a[1], NULL);
                cyl_camera_distort(&cam, xm, ym, &b[0], &b[1], NULL);
                for (r = 0; r < 2; r++) {
                    double e = rel_err(j[r][c], (a[r] - b[r]) / (2 * h), 1e-2);
                    if (e > worst) worst = e;
                }
            }
        }
    print_message("distortion Jacobian vs central differences: max rel err %.3g\n", worst);
    assert_true(worst < 1e-6);
}

static void round_trip(const cyl_camera *cam, double *worst_px, double *worst_n)
{
    double u, v;
    for (v = 0; v <= cam->height - 1; v += 6.5)
        for (u = 0; u <= cam->width - 1; u += 7.25) {
            double x, y, u2, v2, xd, yd, x2, y2;
            assert_int_equal(cyl_camera_undistort(cam, u, v, &x, &y), CYL_OK);
            cyl_camera_project(cam, x, y, &u2, &v2);
            if (fabs(u2 - u) > *worst_px) *worst_px = fabs(u2 - u);
            if (fabs(v2 - v) > *worst_px) *worst_px = fabs(v2 - v);
            /* the other way: normalised -> pixel -> normalised */
            cyl_camera_distort(cam, x, y, &xd, &yd, NULL);
            assert_int_equal(cyl_camera_undistort(cam, cam->fx_px * xd + cam->cx_px,
                                                  cam->fy_px * yd + cam->cy_px, &x2, &y2), CYL_OK);
            if (fabs(x2 - x) > *worst_n) *worst_n = fabs(x2 - x);
            if (fabs(y2 - y) > *worst_n) *worst_n = fabs(y2 - y);
        }
}

static void test_round_trip(void **st)
{
    cyl_camera cam;
    double wp = 0, wn = 0;
    (void)st;
    unc_distorted_camera(&cam);
    round_trip(&cam, &wp, &wn);
    /* a strong barrel lens (wide angle) too */
    cam.fx_px = cam.fy_px = 500.0;
    cam.k1 = -0.30; cam.k2 = 0.09; cam.k3 = -0.01; cam.p1 = 1e-3; cam.p2 = 2e-3;
    round_trip(&cam, &wp, &wn);
    print_message("undistort round trip over the image: max %.3g px, %.3g normalised\n", wp, wn);
    assert_true(wp < 1e-9);
    assert_true(wn < 1e-9);
    /* zero distortion: exactly the pinhole */
    unc_paper_camera(&cam);
    {
        double x, y;
        assert_int_equal(cyl_camera_undistort(&cam, 500.0, 100.0, &x, &y), CYL_OK);
        assert_true(fabs(x - (500.0 - 386.3) / 875.2) < 1e-15);
        assert_true(fabs(y - (100.0 - 278.8) / 872.4) < 1e-15);
    }
}

static void test_undistort_jacobians(void **st)
{
    cyl_camera cam;
    double u, v, worst_uv = 0, worst_in = 0;
    static const double step[CYL_INTR_COUNT] = {1e-2, 1e-2, 1e-2, 1e-2, 1e-6, 1e-6, 1e-7, 1e-7, 1e-6};
    (void)st;
    unc_distorted_camera(&cam);
    for (v = 3; v < 576; v += 57)
        for (u = 5; u < 768; u += 63) {
            double x, y, juv[2][2], jin[2][CYL_INTR_COUNT], xp, yp, xm, ym;
            int c, r;
            assert_int_equal(cyl_camera_undistort(&cam, u, v, &x, &y), CYL_OK);
            assert_int_equal(cyl_camera_undistort_jacobian(&cam, x, y, juv, jin), CYL_OK);
            for (c = 0; c < 2; c++) {
                double h = 1e-3;
                cyl_camera_undistort(&cam, u + (c == 0 ? h : 0), v + (c == 1 ? h : 0), &xp, &yp);
                cyl_camera_undistort(&cam, u - (c == 0 ? h : 0), v - (c == 1 ? h : 0), &xm, &ym);
                for (r = 0; r < 2; r++) {
                    double n = (r == 0 ? xp - xm : yp - ym) / (2 * h);
                    double e = rel_err(juv[r][c], n, 1e-2 / 875.0);
                    if (e > worst_uv) worst_uv = e;
                }
            }
            for (c = 0; c < CYL_INTR_COUNT; c++) {
                cyl_camera cp = cam, cm = cam;
                double *pp = &cp.fx_px, *pm = &cm.fx_px;
                /* fx fy cx cy k1 k2 p1 p2 k3 are consecutive doubles in cyl_camera */
                pp[c] += step[c];
                pm[c] -= step[c];
                cyl_camera_undistort(&cp, u, v, &xp, &yp);
                cyl_camera_undistort(&cm, u, v, &xm, &ym);
                for (r = 0; r < 2; r++) {
                    double n = (r == 0 ? xp - xm : yp - ym) / (2 * step[c]);
                    /* scale: smallest derivative worth resolving for this parameter */
                    double sc = c < 4 ? 1e-6 : 1e-4;
                    double e = rel_err(jin[r][c], n, sc);
                    if (e > worst_in) worst_in = e;
                }
            }
        }
    print_message("undistortion Jacobians vs central differences: d/d(u,v) %.3g, d/d(intrinsics) %.3g\n",
                  worst_uv, worst_in);
    assert_true(worst_uv < 1e-6);
    assert_true(worst_in < 1e-6);
}

static void test_no_inverse(void **st)
{
    cyl_camera cam;
    double x, y;
    (void)st;
    unc_paper_camera(&cam);
    cam.k1 = -1.0; /* x (1 - r^2) peaks at r = 1/sqrt(3): distorted radius > 0.385 has no preimage */
    assert_int_equal(cyl_camera_undistort(&cam, cam.cx_px + 0.5 * cam.fx_px, cam.cy_px, &x, &y),
                     CYL_ERR_NUMERIC);
    assert_int_equal(cyl_camera_undistort(&cam, cam.cx_px + 0.2 * cam.fx_px, cam.cy_px, &x, &y), CYL_OK);
    assert_true(fabs(x * (1 - x * x) - 0.2) < 1e-12);
    assert_true(cyl_camera_unfolded(&cam, 0.5, 0.0));
    assert_false(cyl_camera_unfolded(&cam, 0.6, 0.0));   /* 1 - 3 r^2 < 0 beyond 1/sqrt(3) */
    assert_false(cyl_camera_unfolded(&cam, -1.19, 0.0));
    assert_int_equal(cyl_camera_undistort(&cam, NAN, 3, &x, &y), CYL_ERR_NUMERIC);
}

static void test_check(void **st)
{
    cyl_camera cam, c;
    (void)st;
    unc_distorted_camera(&cam);
    assert_int_equal(cyl_camera_check(&cam), CYL_OK);
    assert_int_equal(cyl_camera_check(NULL), CYL_ERR_ARG);
    c = cam; c.fx_px = 0; assert_int_equal(cyl_camera_check(&c), CYL_ERR_CAMERA);
    c = cam; c.fy_px = -3; assert_int_equal(cyl_camera_check(&c), CYL_ERR_CAMERA);
    c = cam; c.height_m = 0; assert_int_equal(cyl_camera_check(&c), CYL_ERR_CAMERA);
    c = cam; c.tilt_sigma_rad = -1e-3; assert_int_equal(cyl_camera_check(&c), CYL_ERR_CAMERA);
    c = cam; c.intr_cov[2][2] = -1; assert_int_equal(cyl_camera_check(&c), CYL_ERR_CAMERA);
    c = cam; c.intr_cov[0][2] = 0.01; assert_int_equal(cyl_camera_check(&c), CYL_ERR_CAMERA);
    c.intr_cov[2][0] = 0.01; assert_int_equal(cyl_camera_check(&c), CYL_OK);
    c = cam; c.k2 = INFINITY; assert_int_equal(cyl_camera_check(&c), CYL_ERR_CAMERA);
    c = cam; c.tilt_rad = 2.0; assert_int_equal(cyl_camera_check(&c), CYL_ERR_CAMERA);
    cyl_camera_init(&c);
    assert_int_equal(cyl_camera_check(&c), CYL_OK);
    assert_true(c.flags & CYL_CAM_INTR_COV_UNKNOWN);
    cyl_camera_set_intrinsic_sigmas(&c, NULL);
    assert_true(c.intr_cov[0][0] == 0.0);
}

/* Bad-input matrix: NaN, infinite or negative sigmas and covariances are refused. */
static void test_bad_sigmas_refused(void **st)
{
    cyl_camera c;
    double s9[CYL_INTR_COUNT] = {0.5, 0.5, 0.3, 0.3, 0, 0, 0, 0, 0};
    (void)st;
    cyl_camera_init(&c);
    c.fx_px = c.fy_px = 500; c.height_m = 0.3;
    assert_int_equal(cyl_camera_check(&c), CYL_OK);
    c.tilt_sigma_rad = NAN;      assert_int_equal(cyl_camera_check(&c), CYL_ERR_CAMERA); c.tilt_sigma_rad = 0;
    c.yaw_sigma_rad = -1e-3;     assert_int_equal(cyl_camera_check(&c), CYL_ERR_CAMERA); c.yaw_sigma_rad = 0;
    c.height_sigma_m = INFINITY; assert_int_equal(cyl_camera_check(&c), CYL_ERR_CAMERA); c.height_sigma_m = 0;
    c.offset_sigma_m = -INFINITY; assert_int_equal(cyl_camera_check(&c), CYL_ERR_CAMERA); c.offset_sigma_m = 0;
    s9[2] = NAN;
    cyl_camera_set_intrinsic_sigmas(&c, s9);
    assert_int_equal(cyl_camera_check(&c), CYL_ERR_CAMERA);
    cyl_camera_set_intrinsic_sigmas(&c, NULL);
    c.intr_cov[0][0] = -1.0;     assert_int_equal(cyl_camera_check(&c), CYL_ERR_CAMERA); c.intr_cov[0][0] = 0;
    c.tilt_rad = NAN;            assert_int_equal(cyl_camera_check(&c), CYL_ERR_CAMERA);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bad_sigmas_refused),
        cmocka_unit_test(test_distort_jacobian),
        cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_undistort_jacobians),
        cmocka_unit_test(test_no_inverse),
        cmocka_unit_test(test_check),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
