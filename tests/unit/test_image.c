/* SPDX-License-Identifier: BSD-3-Clause */
/* Image views: byte layouts of each format written by hand, strides, size checks. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>
#include <string.h>

#include "cyl/image.h"

static void expect_px(const cyl_image *img, uint32_t x, uint32_t y, int Y, int U, int V)
{
    uint8_t a, b, c;
    assert_int_equal(cyl_image_pixel(img, x, y, &a, &b, &c), CYL_OK);
    assert_int_equal(a, Y); assert_int_equal(b, U); assert_int_equal(c, V);
}

static void test_packed_layouts(void **state)
{
    /* 3x2 YUYV with stride 10: row = Y0 U0 Y1 V0 Y2 U1 pad V1 ... (odd width: last pair half used) */
    uint8_t yuyv[20] = { 10, 100, 11, 200, 12, 101, 99, 201, 0xEE, 0xEE,
                         20, 110, 21, 210, 22, 111, 99, 211, 0xEE, 0xEE };
    uint8_t uyvy[16] = { 100, 10, 200, 11, 101, 12, 201, 13,
                         110, 20, 210, 21, 111, 22, 211, 23 };
    cyl_image img;
    (void)state;
    assert_int_equal(cyl_image_wrap(&img, CYL_FMT_YUYV, 3, 2, yuyv, 10), CYL_OK);
    expect_px(&img, 0, 0, 10, 100, 200);
    expect_px(&img, 1, 0, 11, 100, 200);
    expect_px(&img, 2, 0, 12, 101, 201);
    expect_px(&img, 2, 1, 22, 111, 211);
    assert_int_equal(cyl_image_wrap(&img, CYL_FMT_YUYV, 3, 2, yuyv, 7), CYL_ERR_SIZE); /* < 8 bytes a row */
    assert_int_equal(cyl_image_wrap(&img, CYL_FMT_UYVY, 4, 2, uyvy, 0), CYL_OK);
    assert_int_equal(img.stride[0], 8);
    expect_px(&img, 3, 0, 13, 101, 201);
    expect_px(&img, 0, 1, 20, 110, 210);
}

static void test_planar_layouts(void **state)
{
    /* 4x2 NV12, stride 5: Y rows of 5 bytes, then one UV row of 5 bytes */
    uint8_t nv12[15] = { 1, 2, 3, 4, 0xEE, 5, 6, 7, 8, 0xEE, 50, 60, 51, 61, 0xEE };
    /* 4x4 I420 tight: Y 16 bytes, U 2x2, V 2x2 */
    uint8_t i420[24];
    uint8_t yuv444[12] = { 1, 2, 3, 4, 10, 20, 30, 40, 100, 110, 120, 130 };
    cyl_image img;
    int k;
    (void)state;
    assert_int_equal(cyl_image_wrap(&img, CYL_FMT_NV12, 4, 2, nv12, 5), CYL_OK);
    expect_px(&img, 0, 0, 1, 50, 60);
    expect_px(&img, 3, 1, 8, 51, 61);
    for (k = 0; k < 16; k++) i420[k] = (uint8_t)k;
    i420[16] = 100; i420[17] = 101; i420[18] = 102; i420[19] = 103;
    i420[20] = 200; i420[21] = 201; i420[22] = 202; i420[23] = 203;
    assert_int_equal(cyl_image_wrap(&img, CYL_FMT_I420, 4, 4, i420, 0), CYL_OK);
    expect_px(&img, 3, 3, 15, 103, 203);
    expect_px(&img, 2, 1, 6, 101, 201);
    assert_int_equal(cyl_image_buffer_size(CYL_FMT_I420, 4, 4, 0), 24);
    assert_int_equal(cyl_image_buffer_size(CYL_FMT_NV12, 5, 3, 0), 5 * 3 + 6 * 2); /* odd: UV row 6 bytes */
    assert_int_equal(cyl_image_wrap(&img, CYL_FMT_YUV444P, 4, 1, yuv444, 0), CYL_OK);
    expect_px(&img, 2, 0, 3, 30, 120);
}

static void test_checks(void **state)
{
    uint8_t buf[64] = { 0 };
    cyl_image img;
    (void)state;
    assert_int_equal(cyl_image_wrap(&img, CYL_FMT_YUYV, 0, 2, buf, 0), CYL_ERR_SIZE);
    assert_int_equal(cyl_image_wrap(&img, CYL_FMT_YUYV, CYL_MAX_DIM + 1, 2, buf, 0), CYL_ERR_SIZE);
    assert_int_equal(cyl_image_wrap(&img, (cyl_pixfmt)0, 2, 2, buf, 0), CYL_ERR_FORMAT);
    assert_int_equal(cyl_image_wrap(&img, CYL_FMT_YUYV, 2, 2, NULL, 0), CYL_ERR_ARG);
    assert_int_equal(cyl_image_buffer_size(CYL_FMT_YUYV, 70000, 70000, 0), 0);
    assert_int_equal(cyl_image_buffer_size(CYL_FMT_YUYV, 2, 2, ((size_t)1 << 28) + 1), 0); /* over the stride limit, on 32 and 64 bit */
    assert_int_equal(cyl_image_wrap(&img, CYL_FMT_I420, 4, 4, buf, 0), CYL_OK);
    img.plane[2] = NULL;
    assert_int_equal(cyl_image_check(&img), CYL_ERR_ARG);
    assert_int_equal(cyl_image_check(NULL), CYL_ERR_ARG);
    {
        uint8_t a, b, c;
        assert_int_equal(cyl_image_wrap(&img, CYL_FMT_YUYV, 2, 2, buf, 0), CYL_OK);
        assert_int_equal(cyl_image_pixel(&img, 2, 0, &a, &b, &c), CYL_ERR_ARG);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_packed_layouts),
        cmocka_unit_test(test_planar_layouts),
        cmocka_unit_test(test_checks),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
