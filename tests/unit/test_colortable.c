/* SPDX-License-Identifier: BSD-3-Clause */
/* Colour table: classification rule, training, serialisation and every corruption. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdlib.h>
#include <string.h>

#include "cyl/colortable.h"
#include "synth_frames.h"

static void test_crc32_reference(void **state)
{
    (void)state;
    /* the standard check value of CRC-32/ISO-HDLC (zlib's crc32) */
    assert_int_equal(cyl_crc32(0, (const uint8_t *)"123456789", 9), 0xCBF43926u);
    assert_int_equal(cyl_crc32(cyl_crc32(0, (const uint8_t *)"1234", 4), (const uint8_t *)"56789", 5), 0xCBF43926u);
    assert_int_equal(cyl_crc32(0, (const uint8_t *)"", 0), 0u);
}

static void test_mask_rule_and_priority(void **state)
{
    cyl_colortable *t = malloc(sizeof *t);
    (void)state;
    cyl_colortable_init(t);
    assert_int_equal(cyl_colortable_mask(t, 100, 100, 100), 0);
    assert_int_equal(cyl_colortable_add_box(t, 3, 50, 100, 10, 20, 30, 40), CYL_OK);
    assert_int_equal(cyl_colortable_add_box(t, 5, 80, 200, 15, 25, 35, 45), CYL_OK);
    assert_int_equal(cyl_colortable_mask(t, 60, 10, 30), 1u << 3);
    assert_int_equal(cyl_colortable_mask(t, 49, 10, 30), 0);          /* Y below class 3's window */
    assert_int_equal(cyl_colortable_mask(t, 90, 16, 36), (1u << 3) | (1u << 5));
    assert_int_equal(cyl_mask_class(cyl_colortable_mask(t, 90, 16, 36)), 3);   /* lowest index wins */
    assert_int_equal(cyl_colortable_mask(t, 150, 16, 36), 1u << 5);   /* per-class Y window */
    assert_int_equal(cyl_mask_class(0), CYL_CLASS_NONE);
    assert_int_equal(cyl_mask_class(0x80), 7);
    assert_int_equal(cyl_colortable_add_box(t, 8, 0, 1, 0, 1, 0, 1), CYL_ERR_CLASS);
    assert_int_equal(cyl_colortable_add_box(t, 1, 5, 4, 0, 1, 0, 1), CYL_ERR_ARG);
    assert_int_equal(cyl_colortable_clear_class(t, 3), CYL_OK);
    assert_int_equal(cyl_colortable_mask(t, 90, 16, 36), 1u << 5);
    assert_int_equal(cyl_colortable_set_class(t, 5, "a-very-long-class-name", 1, 2, 3), CYL_OK);
    assert_string_equal(t->name[5], "a-very-long-cla");
    assert_int_equal(cyl_colortable_find_class(t, "a-very-long-cla"), 5);
    assert_int_equal(cyl_colortable_find_class(t, "missing"), -1);
    free(t);
}

static void test_classify_image(void **state)
{
    canvas c;
    cyl_image img;
    uint8_t buf[4096], out[16 * 8];
    cyl_colortable *t = malloc(sizeof *t);
    cyl_roi roi = { 2, 1, 8, 4 };
    (void)state;
    cyl_colortable_init(t);
    cyl_colortable_add_box(t, 1, 0, 255, 70, 90, 180, 200);
    assert_true(canvas_alloc(&c, 16, 8));
    canvas_fill(&c, 120, 128, 128);
    canvas_rect(&c, 4, 2, 4, 2, 150, 80, 190);
    assert_true(canvas_to_format(&c, CYL_FMT_YUYV, 0, 0, buf, sizeof buf, &img));
    assert_int_equal(cyl_classify(t, &img, &roi, 2, 1, out, 4), CYL_OK);
    /* samples at x = 2,4,6,8 of rows 1..4; the box covers x 4..7, rows 2..3 */
    {
        static const uint8_t N = CYL_CLASS_NONE;
        const uint8_t expect[16] = { N, N, N, N,  N, 1, 1, N,  N, 1, 1, N,  N, N, N, N };
        assert_memory_equal(out, expect, 16);
    }
    assert_int_equal(cyl_classify(t, &img, &roi, 2, 1, out, 3), CYL_ERR_SIZE);
    canvas_free(&c);
    free(t);
}

/* A region of one colour with a few outliers: the outliers are under the
 * threshold, the rectangle is the colour's spread plus the margin. */
static void test_train_region(void **state)
{
    canvas c;
    cyl_image img;
    size_t cap = 64 * 64 * 3;
    uint8_t *buf = malloc(cap), box[6];
    void *work = malloc(cyl_train_workspace_size());
    cyl_colortable *t = malloc(sizeof *t);
    cyl_train_params p = cyl_train_params_default();
    cyl_roi roi = { 8, 8, 40, 40 };
    uint32_t x, y;
    (void)state;
    cyl_colortable_init(t);
    assert_true(canvas_alloc(&c, 64, 64));
    canvas_fill(&c, 60, 128, 128);
    /* region: U in {100,101,102}, V in {150..153}, Y 90..129 (uniform over 40 levels) */
    for (y = 8; y < 48; y++)
        for (x = 8; x < 48; x++) {
            size_t k = (size_t)y * 64 + x;
            c.y[k] = (uint8_t)(90 + (x - 8));
            c.u[k] = (uint8_t)(100 + (x + y) % 3);
            c.v[k] = (uint8_t)(150 + (x * 7 + y) % 4);
        }
    /* one outlier pixel: a single count, under the threshold of max(2, 0.002 * 1600) = 4 */
    c.u[20 * 64 + 20] = 30; c.v[20 * 64 + 20] = 30;
    assert_true(canvas_to_format(&c, CYL_FMT_YUV444P, 0, 0, buf, cap, &img));
    assert_int_equal(cyl_colortable_train(t, 2, &img, &roi, &p, work, cyl_train_workspace_size(), box), CYL_OK);
    assert_int_equal(box[0], 100 - 3); assert_int_equal(box[1], 102 + 3);
    assert_int_equal(box[2], 150 - 3); assert_int_equal(box[3], 153 + 3);
    /* quantiles of Y over 1599 kept pixels (40 per level, one fewer at level 102):
       1% -> 90, 99% -> 129; widened by 16 */
    assert_int_equal(box[4], 90 - 16); assert_int_equal(box[5], 129 + 16);
    assert_int_equal(cyl_colortable_mask(t, 100, 97, 147), 1u << 2);
    assert_int_equal(cyl_colortable_mask(t, 100, 96, 147), 0);
    assert_int_equal(cyl_colortable_mask(t, 100, 30, 30), 0);          /* outlier not learned */
    assert_int_equal(cyl_colortable_mask(t, 73, 100, 150), 0);         /* too dark */
    /* training a second image adds to the class */
    canvas_fill(&c, 200, 60, 60);
    assert_true(canvas_to_format(&c, CYL_FMT_YUV444P, 0, 0, buf, cap, &img));
    assert_int_equal(cyl_colortable_train(t, 2, &img, NULL, &p, work, cyl_train_workspace_size(), box), CYL_OK);
    assert_int_equal(cyl_colortable_mask(t, 100, 100, 150), 1u << 2);
    assert_int_equal(cyl_colortable_mask(t, 200, 60, 60), 1u << 2);
    /* errors */
    assert_int_equal(cyl_colortable_train(t, 9, &img, NULL, &p, work, cyl_train_workspace_size(), NULL), CYL_ERR_CLASS);
    assert_int_equal(cyl_colortable_train(t, 2, &img, NULL, &p, work, 100, NULL), CYL_ERR_NOMEM);
    p.min_bin_fraction = 0.9;  /* a uniform spread over 12 bins: none holds 90% */
    canvas_fill(&c, 100, 0, 0);
    for (x = 0; x < 64 * 64; x++) { c.u[x] = (uint8_t)(x % 12); }
    assert_true(canvas_to_format(&c, CYL_FMT_YUV444P, 0, 0, buf, cap, &img));
    assert_int_equal(cyl_colortable_train(t, 3, &img, NULL, &p, work, cyl_train_workspace_size(), NULL), CYL_ERR_EMPTY);
    canvas_free(&c);
    free(buf); free(work); free(t);
}

static void test_file_round_trip_and_corruption(void **state)
{
    cyl_colortable *a = malloc(sizeof *a), *b = malloc(sizeof *b);
    uint8_t *buf = malloc(CYL_TABLE_FILE_SIZE + 16), *bad = malloc(CYL_TABLE_FILE_SIZE + 16);
    size_t len = 0;
    (void)state;
    cyl_colortable_init(a);
    cyl_colortable_set_class(a, 0, "orange", 255, 128, 0);
    cyl_colortable_set_class(a, 7, "green", 0, 255, 0);
    cyl_colortable_add_box(a, 0, 10, 200, 20, 40, 200, 220);
    cyl_colortable_add_box(a, 7, 30, 250, 40, 60, 20, 30);
    cyl_colortable_refresh(a);   /* loading refreshes: the inner boxes as well */
    assert_int_equal(cyl_colortable_save(a, buf, CYL_TABLE_FILE_SIZE - 1, &len), CYL_ERR_NOMEM);
    assert_int_equal(cyl_colortable_save(a, buf, CYL_TABLE_FILE_SIZE + 16, &len), CYL_OK);
    assert_int_equal(len, CYL_TABLE_FILE_SIZE);
    assert_memory_equal(buf, "CYLT\x01\x00\x08\x00", 8);
    memset(b, 0x33, sizeof *b);
    assert_int_equal(cyl_colortable_load(b, buf, len), CYL_OK);
    assert_memory_equal(a, b, sizeof *a);

    /* every corruption has its own code, and leaves the destination untouched */
    cyl_colortable_init(b);
    assert_int_equal(cyl_colortable_load(b, buf, 0), CYL_ERR_FILE_TRUNCATED);
    assert_int_equal(cyl_colortable_load(b, buf, 3), CYL_ERR_FILE_TRUNCATED);
    assert_int_equal(cyl_colortable_load(b, buf, 6), CYL_ERR_FILE_TRUNCATED);
    assert_int_equal(cyl_colortable_load(b, buf, len - 1), CYL_ERR_FILE_TRUNCATED);
    assert_int_equal(cyl_colortable_load(b, buf, 1000), CYL_ERR_FILE_TRUNCATED);
    memcpy(bad, buf, len); bad[0] = 'X';
    assert_int_equal(cyl_colortable_load(b, bad, len), CYL_ERR_FILE_MAGIC);
    memcpy(bad, buf, len); bad[4] = 3;
    assert_int_equal(cyl_colortable_load(b, bad, len), CYL_ERR_FILE_VERSION);
    memcpy(bad, buf, len); bad[424 + 20 * 256 + 45] ^= 0x01;   /* one bit of the UV table */
    assert_int_equal(cyl_colortable_load(b, bad, len), CYL_ERR_FILE_CHECKSUM);
    memcpy(bad, buf, len); bad[len - 1] ^= 0x80;                /* the checksum itself */
    assert_int_equal(cyl_colortable_load(b, bad, len), CYL_ERR_FILE_CHECKSUM);
    memcpy(bad, buf, len); bad[len] = 0;
    assert_int_equal(cyl_colortable_load(b, bad, len + 1), CYL_ERR_FILE_CORRUPT); /* trailing bytes */
    /* an unterminated class name with a valid checksum */
    memcpy(bad, buf, len);
    memset(bad + 8, 'a', 16);
    {
        uint32_t crc = cyl_crc32(0, bad, len - 4);
        bad[len - 4] = (uint8_t)crc; bad[len - 3] = (uint8_t)(crc >> 8);
        bad[len - 2] = (uint8_t)(crc >> 16); bad[len - 1] = (uint8_t)(crc >> 24);
    }
    assert_int_equal(cyl_colortable_load(b, bad, len), CYL_ERR_FILE_CORRUPT);
    /* a wrong class count with a valid checksum */
    memcpy(bad, buf, len); bad[6] = 16;
    {
        uint32_t crc = cyl_crc32(0, bad, len - 4);
        bad[len - 4] = (uint8_t)crc; bad[len - 3] = (uint8_t)(crc >> 8);
        bad[len - 2] = (uint8_t)(crc >> 16); bad[len - 1] = (uint8_t)(crc >> 24);
    }
    assert_int_equal(cyl_colortable_load(b, bad, len), CYL_ERR_FILE_CORRUPT);
    {
        cyl_colortable *empty = malloc(sizeof *empty);
        cyl_colortable_init(empty);
        assert_memory_equal(b, empty, sizeof *b);   /* untouched by every failed load */
        free(empty);
    }
    assert_string_equal(cyl_status_str(CYL_ERR_FILE_CHECKSUM), "table file checksum mismatch (corrupt)");
    free(a); free(b); free(buf); free(bad);
}

/* Version 2: a table with a 3-D part saves as version 2 and loads back identical; a table
 * without one saves as version 1; a version-1 file loads with every 3-D cell all ones. */
static void test_file_version_2(void **state)
{
    cyl_colortable *a = malloc(sizeof *a), *b = malloc(sizeof *b);
    uint8_t *buf = malloc(CYL_TABLE_FILE_MAX_SIZE + 16), *bad = malloc(CYL_TABLE_FILE_MAX_SIZE + 16);
    size_t len = 0, i;
    int ones = 1;
    (void)state;
    assert_int_equal(CYL_TABLE_FILE_SIZE_V2, CYL_TABLE_FILE_SIZE + CYL_YUV_CELLS);
    cyl_colortable_init(a);
    assert_false(cyl_colortable_has_yuv(a));
    cyl_colortable_set_class(a, 1, "ball", 255, 255, 0);
    cyl_colortable_add_box(a, 1, 0, 255, 0, 255, 0, 255);
    a->yuv[3][10][20] &= (cyl_mask)~2u;                   /* dark (Y 24..31), U 40..43, V 80..83: not ball */
    assert_true(cyl_colortable_has_yuv(a));
    assert_int_equal(a->lookup, CYL_LOOKUP_UV_Y);
    cyl_colortable_refresh(a);   /* the box covers every colour: only the 3-D table rejects */
    assert_int_equal(a->lookup, CYL_LOOKUP_YUV);
    assert_int_equal(cyl_colortable_mask(a, 24, 40, 80), 0);
    assert_int_equal(cyl_colortable_mask(a, 32, 40, 80), 2);    /* the next brightness cell */
    assert_int_equal(cyl_colortable_mask(a, 31, 44, 83), 2);    /* the next U cell */
    assert_int_equal(cyl_colortable_save(a, buf, CYL_TABLE_FILE_SIZE_V2 - 1, &len), CYL_ERR_NOMEM);
    assert_int_equal(cyl_colortable_save(a, buf, CYL_TABLE_FILE_MAX_SIZE, &len), CYL_OK);
    assert_int_equal(len, CYL_TABLE_FILE_SIZE_V2);
    assert_memory_equal(buf, "CYLT\x02\x00\x08\x00", 8);
    assert_int_equal(buf[CYL_TABLE_FILE_SIZE - 4 + (3 * 64 + 10) * 64 + 20], 0xFD);
    memset(b, 0x33, sizeof *b);
    assert_int_equal(cyl_colortable_load(b, buf, len), CYL_OK);
    assert_memory_equal(a, b, sizeof *a);
    assert_int_equal(cyl_colortable_load(b, buf, len - 1), CYL_ERR_FILE_TRUNCATED);
    assert_int_equal(cyl_colortable_load(b, buf, CYL_TABLE_FILE_SIZE), CYL_ERR_FILE_TRUNCATED);
    memcpy(bad, buf, len); bad[CYL_TABLE_FILE_SIZE + 100] ^= 1;   /* one 3-D cell */
    assert_int_equal(cyl_colortable_load(b, bad, len), CYL_ERR_FILE_CHECKSUM);
    /* clearing the class restores all-ones cells: the table saves as version 1 again */
    cyl_colortable_clear_class(a, 1);
    assert_false(cyl_colortable_has_yuv(a));
    assert_true(a->lookup & CYL_LOOKUP_UV_Y);
    assert_int_equal(cyl_colortable_mask(a, 24, 40, 80), 0);
    assert_int_equal(cyl_colortable_save(a, buf, CYL_TABLE_FILE_MAX_SIZE, &len), CYL_OK);
    assert_int_equal(len, CYL_TABLE_FILE_SIZE);
    assert_int_equal(buf[4], 1);
    /* a version-1 file over a table that had a 3-D part: all ones after the load */
    memset(b->yuv, 0, sizeof b->yuv);
    assert_int_equal(cyl_colortable_load(b, buf, len), CYL_OK);
    for (i = 0; i < CYL_YUV_CELLS; i++) ones &= (&b->yuv[0][0][0])[i] == 0xFF;
    assert_true(ones);
    free(a); free(b); free(buf); free(bad);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_crc32_reference),
        cmocka_unit_test(test_mask_rule_and_priority),
        cmocka_unit_test(test_classify_image),
        cmocka_unit_test(test_train_region),
        cmocka_unit_test(test_file_version_2),
        cmocka_unit_test(test_file_round_trip_and_corruption),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
