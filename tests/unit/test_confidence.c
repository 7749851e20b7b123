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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_r),
        cmocka_unit_test(test_whole),
        cmocka_unit_test(test_cut),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
