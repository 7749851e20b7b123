/* SPDX-License-Identifier: BSD-3-Clause */
/* Landmark confidence (paper eqs. 7-8) and the border rule, hand-computed values. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <cmocka.h>

#include "cyl/confidence.h"
#include "cyl/segment.h"

static void test_r(void **st)
{
    (void)st;
    assert_true(cyl_conf_r(0.5) == 0.5);
    assert_true(cyl_conf_r(2.0) == 0.5);
    assert_true(cyl_conf_r(1.0) == 1.0);
    assert_true(cyl_conf_r(0.0) == 0.0);
    assert_true(cyl_conf_r(-1.0) == 0.0);
    assert_true(cyl_conf_r(NAN) == 0.0);
}

/* fx = fy = 800 px, D = 0.1 m, H = 0.2 m at depth 2 m: w_est = 40 px, h_est = 80 px */
static void test_whole(void **st)
{
    cyl_landmark_size sz = {0.1, 0.2};
    cyl_confidence c;
    (void)st;
    assert_int_equal(cyl_landmark_confidence(40, 80, 2.0, 800, 800, &sz, 0, &c), CYL_OK);
    assert_true(fabs(c.w_est_px - 40) < 1e-12 && fabs(c.h_est_px - 80) < 1e-12);
    assert_true(fabs(c.confidence - 1.0) < 1e-12 && c.cut == 0);
    assert_int_equal(cyl_landmark_confidence(20, 160, 2.0, 800, 800, &sz, 0, &c), CYL_OK);
    assert_true(fabs(c.confidence - 0.25) < 1e-12);           /* 0.5 * (1/2) */
    assert_true(fabs(c.confidence_uncut - 0.25) < 1e-12);
    assert_int_equal(cyl_landmark_confidence(30, 60, 2.0, 800, 400, &sz, 0, &c), CYL_OK);
    assert_true(fabs(c.confidence - 0.75 * 1.0 / 1.5) < 1e-12); /* h_est = 40: 60/40 -> 1/1.5 */
}

static void test_cut(void **st)
{
    cyl_landmark_size sz = {0.1, 0.2};
    cyl_confidence c;
    (void)st;
    /* cut on the left, visible width 20 of 40: never a whole landmark; height judged alone */
    assert_int_equal(cyl_landmark_confidence(20, 40, 2.0, 800, 800, &sz, CYL_BLOB_TOUCH_LEFT, &c), CYL_OK);
    assert_true(c.confidence == 0.0 && c.cut == CYL_CONF_CUT_X);
    assert_true(fabs(c.confidence_uncut - 0.5) < 1e-12);
    /* cut but already wider than a landmark: penalised */
    assert_int_equal(cyl_landmark_confidence(80, 80, 2.0, 800, 800, &sz, CYL_BLOB_TOUCH_RIGHT, &c), CYL_OK);
    assert_true(fabs(c.confidence_uncut - 0.5) < 1e-12);
    /* top/bottom cut */
    assert_int_equal(cyl_landmark_confidence(40, 10, 2.0, 800, 800, &sz, CYL_BLOB_TOUCH_BOTTOM, &c), CYL_OK);
    assert_true(c.confidence == 0.0 && c.cut == CYL_CONF_CUT_Y && fabs(c.confidence_uncut - 1.0) < 1e-12);
    /* both */
    assert_int_equal(cyl_landmark_confidence(40, 80, 2.0, 800, 800, &sz,
                                             CYL_BLOB_TOUCH_TOP | CYL_BLOB_TOUCH_LEFT, &c), CYL_OK);
    assert_true(c.confidence == 0.0 && c.confidence_uncut == 0.0);
}

static void test_errors(void **st)
{
    cyl_landmark_size sz = {0.1, 0.2}, bad = {0, 0.2};
    cyl_confidence c;
    (void)st;
    assert_int_equal(cyl_landmark_confidence(40, 80, 0.0, 800, 800, &sz, 0, &c), CYL_ERR_ARG);
    assert_int_equal(cyl_landmark_confidence(40, 80, 1.0, 800, 800, &bad, 0, &c), CYL_ERR_ARG);
    assert_int_equal(cyl_landmark_confidence(0, 80, 1.0, 800, 800, &sz, 0, &c), CYL_ERR_ARG);
    assert_int_equal(cyl_landmark_confidence(40, 80, 1.0, 800, 800, NULL, 0, &c), CYL_ERR_ARG);
}

/* Expected box of an upright cylinder off the image centre (confidence.h), by hand:
 * fx 600, fy 500, tilt 0.2 rad, D 0.1 m, H 0.3 m, depth 2 m -> w0 = 30 px, h0 = 75 px. */
static void test_expected_size_geometry(void **st)
{
    cyl_camera cam;
    cyl_landmark_size sz = {0.1, 0.3};
    cyl_confidence c;
    double w, h, den, slant, mag;
    (void)st;
    cyl_camera_init(&cam);
    cam.fx_px = 600; cam.fy_px = 500; cam.cx_px = 320; cam.cy_px = 240; cam.tilt_rad = 0.2;
    cam.height_m = 0.3;
    /* image centre: the plain fx D / depth */
    assert_int_equal(cyl_landmark_expected_size(&cam, 0, 0, 2.0, &sz, &w, &h), CYL_OK);
    assert_true(fabs(w - 30.0) < 1e-12 && fabs(h - 75.0) < 1e-12);
    /* off axis, no distortion: sqrt(1 + xn^2) and the slant of vertical edges */
    den = cos(0.2) - 0.1 * sin(0.2);
    slant = 600.0 / 500.0 * 0.5 * sin(0.2) / den;
    assert_int_equal(cyl_landmark_expected_size(&cam, 0.5, 0.1, 2.0, &sz, &w, &h), CYL_OK);
    assert_true(fabs(w - (30.0 * sqrt(1.25) + 75.0 * slant)) < 1e-9);
    assert_true(fabs(w - 42.85167) < 1e-4);
    /* with k1 = -0.2: local magnification d x_d / d x = 1 + k1 (r^2 + 2 x^2) = 0.848 */
    cam.k1 = -0.2;
    mag = 1.0 - 0.2 * (0.26 + 2 * 0.25);
    assert_int_equal(cyl_landmark_expected_size(&cam, 0.5, 0.1, 2.0, &sz, &w, &h), CYL_OK);
    assert_true(fabs(w - (30.0 * mag * sqrt(1.25) + 75.0 * slant)) < 1e-9);
    /* scoring against the expectation: w = 37.75 < 40, so r(40 / w) = w / 40; r(75 / 75) = 1 */
    assert_int_equal(cyl_landmark_confidence_expected(40.0, 75.0, w, h, 0, &c), CYL_OK);
    assert_true(fabs(w - 37.753473) < 1e-5);
    assert_true(fabs(c.confidence - w / 40.0) < 1e-12);
    /* the plain form is the centred expectation */
    assert_int_equal(cyl_landmark_confidence(30.0, 60.0, 2.0, 600, 500, &sz, 0, &c), CYL_OK);
    assert_true(fabs(c.confidence - 0.8) < 1e-12);
    assert_int_equal(cyl_landmark_expected_size(&cam, 0.5, 0.1, -1.0, &sz, &w, &h), CYL_ERR_ARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_expected_size_geometry),
        cmocka_unit_test(test_r),
        cmocka_unit_test(test_whole),
        cmocka_unit_test(test_cut),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
