/* SPDX-License-Identifier: BSD-3-Clause */
/* Segmentation: hand-derived cases and a brute-force reference on random frames. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cyl/segment.h"
#include "synth_frames.h"
#include "ref_segment.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Colours (Y, U, V) used throughout. */
#define ORANGE 150, 80, 190
#define GREEN 140, 60, 70
#define GREY 120, 128, 128

static cyl_colortable table;

static void make_table(void)
{
    cyl_colortable_init(&table);
    cyl_colortable_set_class(&table, 0, "orange", 255, 128, 0);
    cyl_colortable_set_class(&table, 1, "green", 0, 200, 0);
    cyl_colortable_add_box(&table, 0, 40, 250, 70, 90, 180, 200);
    cyl_colortable_add_box(&table, 1, 40, 250, 50, 70, 60, 80);
}

typedef struct fixture {
    canvas c;
    uint8_t *buf;
    size_t cap;
    cyl_image img;
    void *mem;
    cyl_segmentation seg;
    cyl_segment_params p;
} fixture;

static void fx_open(fixture *f, uint32_t w, uint32_t h, uint32_t max_runs, uint32_t max_blobs)
{
    size_t ms;
    make_table();
    assert_true(canvas_alloc(&f->c, w, h));
    canvas_fill(&f->c, GREY);
    f->cap = ((size_t)w * 2 + 400) * h * 3 + 4096;
    f->buf = (uint8_t *)malloc(f->cap);
    ms = cyl_segment_mem_size(max_runs, max_blobs);
    assert_true(ms > 0);
    f->mem = malloc(ms);
    assert_int_equal(cyl_segmentation_init(&f->seg, f->mem, ms, max_runs, max_blobs), CYL_OK);
    f->p = cyl_segment_params_default();
    {
        unsigned k;
        for (k = 0; k < CYL_MAX_CLASSES; k++) { f->p.cls[k].min_area = 1; f->p.cls[k].merge_gap_px = -1; }
    }
}

static void fx_close(fixture *f)
{
    canvas_free(&f->c);
    free(f->buf);
    free(f->mem);
}

static cyl_status fx_run(fixture *f, cyl_pixfmt fmt, size_t stride)
{
    assert_true(canvas_to_format(&f->c, fmt, stride, 0xA5, f->buf, f->cap, &f->img));
    return cyl_segment(&table, &f->img, &f->p, &f->seg);
}

static void test_rectangles_exact(void **state)
{
    fixture f;
    const cyl_blob *b;
    (void)state;
    fx_open(&f, 64, 48, 1000, 100);
    canvas_rect(&f.c, 10, 5, 8, 20, ORANGE);   /* 160 px, centroid (13.5, 14.5) */
    canvas_rect(&f.c, 40, 30, 12, 6, GREEN);   /* 72 px, centroid (45.5, 32.5) */
    canvas_rect(&f.c, 30, 2, 4, 4, ORANGE);    /* 16 px */
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_OK);
    assert_int_equal(f.seg.n_blobs, 3);
    assert_int_equal(f.seg.class_count[0], 2);
    assert_int_equal(f.seg.class_count[1], 1);
    assert_int_equal(f.seg.class_first[1], 2);
    b = &f.seg.blobs[0];
    assert_int_equal(b->cls, 0);
    assert_int_equal(b->area, 160);
    assert_int_equal(b->x0, 10); assert_int_equal(b->x1, 17);
    assert_int_equal(b->y0, 5); assert_int_equal(b->y1, 24);
    assert_int_equal(b->n_runs, 20);
    assert_true(fabs(b->cx_px - 13.5) < 1e-12);
    assert_true(fabs(b->cy_px - 14.5) < 1e-12);
    /* variance of a discrete uniform over n values: (n^2 - 1) / 12 */
    assert_true(fabs(b->mxx_px2 - (64.0 - 1) / 12) < 1e-9);
    assert_true(fabs(b->myy_px2 - (400.0 - 1) / 12) < 1e-9);
    assert_true(fabs(b->mxy_px2) < 1e-9);
    /* tall: major axis along y */
    assert_true(fabs(fabs(b->orientation_rad) - M_PI / 2) < 1e-9);
    assert_true(fabs(b->elongation - (1 - sqrt(63.0 / 399.0))) < 1e-9);
    assert_int_equal(f.seg.blobs[1].area, 16);
    b = &f.seg.blobs[2];
    assert_int_equal(b->cls, 1);
    assert_int_equal(b->area, 72);
    assert_true(fabs(b->cx_px - 45.5) < 1e-12 && fabs(b->cy_px - 32.5) < 1e-12);
    assert_int_equal(b->flags, 0);
    fx_close(&f);
}

static void test_short_runs_vanish(void **state)
{
    fixture f;
    (void)state;
    fx_open(&f, 40, 10, 1000, 100);
    canvas_rect(&f.c, 2, 1, 1, 1, ORANGE);    /* 1 px: dropped */
    canvas_rect(&f.c, 6, 1, 2, 5, ORANGE);    /* 2-wide column: every run has 2 px, dropped */
    canvas_rect(&f.c, 12, 1, 3, 2, ORANGE);   /* 3 px runs: kept, 6 px */
    canvas_rect(&f.c, 20, 4, 10, 1, GREEN);   /* 10 px run */
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_OK);
    assert_int_equal(f.seg.n_blobs, 2);
    assert_int_equal(f.seg.n_runs, 3);
    assert_int_equal(f.seg.blobs[0].area, 6);
    assert_int_equal(f.seg.blobs[1].area, 10);
    /* min_run 1 keeps everything */
    f.p.min_run_px = 1;
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_OK);
    assert_int_equal(f.seg.n_blobs, 4);
    fx_close(&f);
}

static void test_touching_classes_apart(void **state)
{
    fixture f;
    (void)state;
    fx_open(&f, 30, 20, 1000, 100);
    canvas_rect(&f.c, 5, 5, 5, 5, ORANGE);
    canvas_rect(&f.c, 10, 5, 5, 5, GREEN);    /* shares an edge with the orange one */
    canvas_rect(&f.c, 5, 10, 10, 3, GREEN);   /* below both: joins the green one only */
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_OK);
    assert_int_equal(f.seg.n_blobs, 2);
    assert_int_equal(f.seg.blobs[0].cls, 0);
    assert_int_equal(f.seg.blobs[0].area, 25);
    assert_int_equal(f.seg.blobs[1].cls, 1);
    assert_int_equal(f.seg.blobs[1].area, 55);
    fx_close(&f);
}

static void test_diagonal_contact_apart(void **state)
{
    fixture f;
    (void)state;
    fx_open(&f, 30, 20, 1000, 100);
    canvas_rect(&f.c, 2, 2, 4, 4, ORANGE);    /* ends at (5,5) */
    canvas_rect(&f.c, 6, 6, 4, 4, ORANGE);    /* starts at (6,6): corner contact only */
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_OK);
    assert_int_equal(f.seg.n_blobs, 2);
    assert_int_equal(f.seg.blobs[0].area, 16);
    assert_int_equal(f.seg.blobs[1].area, 16);
    /* a U shape joined only at the bottom is one blob */
    canvas_fill(&f.c, GREY);
    canvas_rect(&f.c, 2, 2, 3, 8, ORANGE);
    canvas_rect(&f.c, 10, 2, 3, 8, ORANGE);
    canvas_rect(&f.c, 2, 10, 11, 2, ORANGE);
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_OK);
    assert_int_equal(f.seg.n_blobs, 1);
    assert_int_equal(f.seg.blobs[0].area, 24 + 24 + 22);
    assert_int_equal(f.seg.blobs[0].n_runs, 8 + 8 + 2);
    fx_close(&f);
}

/* Two 10x10 squares side by side with a gap of g px between them. */
static void merge_case(int gap, int32_t merge_gap, double density, int expect_blobs)
{
    fixture f;
    fx_open(&f, 60, 20, 1000, 100);
    canvas_rect(&f.c, 5, 5, 10, 10, ORANGE);
    canvas_rect(&f.c, 15 + gap, 5, 10, 10, ORANGE);
    f.p.cls[0].merge_gap_px = merge_gap;
    f.p.cls[0].merge_min_density = density;
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_OK);
    assert_int_equal(f.seg.n_blobs, expect_blobs);
    if (expect_blobs == 1) {
        const cyl_blob *b = &f.seg.blobs[0];
        const cyl_run *r;
        uint32_t k, n = 0, prev = 0;
        assert_int_equal(b->area, 200);
        assert_int_equal(b->n_components, 2);
        assert_true(b->flags & CYL_BLOB_MERGED);
        assert_int_equal(b->x0, 5);
        assert_int_equal(b->x1, 24 + gap);
        assert_true(fabs(b->cx_px - (9.5 + 19.5 + gap) / 2) < 1e-12);
        assert_int_equal(b->n_runs, 20);
        /* the merged run list stays in (y, x) order and every run points back */
        for (k = b->first_run; k != CYL_NONE; k = r->next, n++) {
            r = &f.seg.runs[k];
            assert_true(n == 0 || k > prev);
            assert_int_equal(r->blob, 0);
            prev = k;
        }
        assert_int_equal(n, 20);
    }
    fx_close(&f);
}

static void test_merge_criterion(void **state)
{
    (void)state;
    merge_case(3, 3, 0.0, 1);     /* gap == limit: merged */
    merge_case(4, 3, 0.0, 2);     /* gap one over: apart */
    merge_case(3, -1, 0.0, 2);    /* merging disabled */
    /* density: 200 px in a box of 23 x 10 = 230 -> 0.8696 */
    merge_case(3, 3, 200.0 / 230.0, 1);
    merge_case(3, 3, 200.0 / 230.0 + 1e-9, 2);
    merge_case(1, 1, 1.0, 2);     /* density 200/210 < 1 */
}

static void test_merge_chain_and_classes(void **state)
{
    fixture f;
    (void)state;
    fx_open(&f, 80, 20, 1000, 100);
    /* three fragments in a row: a-b within the gap, b-c within the gap, a-c not */
    canvas_rect(&f.c, 5, 5, 6, 8, ORANGE);
    canvas_rect(&f.c, 13, 5, 6, 8, ORANGE);
    canvas_rect(&f.c, 21, 5, 6, 8, ORANGE);
    canvas_rect(&f.c, 29, 5, 6, 8, GREEN);   /* other class, also 2 px away: never merged */
    f.p.cls[0].merge_gap_px = 2;
    f.p.cls[0].merge_min_density = 0.5;
    f.p.cls[1].merge_gap_px = 2;
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_OK);
    assert_int_equal(f.seg.n_blobs, 2);
    assert_int_equal(f.seg.blobs[0].area, 144);
    assert_int_equal(f.seg.blobs[0].n_components, 3);
    assert_int_equal(f.seg.blobs[1].cls, 1);
    assert_int_equal(f.seg.blobs[1].area, 48);
    fx_close(&f);
}

static void test_min_area_and_order(void **state)
{
    fixture f;
    (void)state;
    fx_open(&f, 60, 30, 1000, 100);
    canvas_rect(&f.c, 1, 1, 3, 3, GREEN);     /* 9 */
    canvas_rect(&f.c, 10, 1, 5, 5, GREEN);    /* 25 */
    canvas_rect(&f.c, 20, 1, 4, 4, ORANGE);   /* 16 */
    canvas_rect(&f.c, 30, 10, 4, 4, ORANGE);  /* 16, lower: after the other 16 */
    canvas_rect(&f.c, 40, 10, 3, 1, ORANGE);  /* 3: under min_area 4 */
    f.p.cls[0].min_area = 4;
    f.p.cls[1].min_area = 10;
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_OK);
    assert_int_equal(f.seg.n_blobs, 3);
    assert_int_equal(f.seg.blobs[0].x0, 20);
    assert_int_equal(f.seg.blobs[1].x0, 30);
    assert_int_equal(f.seg.blobs[2].area, 25);
    /* runs of dropped blobs are labelled CYL_NONE */
    {
        uint32_t k, none = 0;
        for (k = 0; k < f.seg.n_runs; k++) if (f.seg.runs[k].blob == CYL_NONE) none++;
        assert_int_equal(none, 3 + 1);
    }
    fx_close(&f);
}

static void test_border_flags(void **state)
{
    fixture f;
    (void)state;
    fx_open(&f, 40, 30, 1000, 100);
    canvas_rect(&f.c, 0, 10, 5, 5, ORANGE);
    canvas_rect(&f.c, 35, 25, 5, 5, GREEN);
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_OK);
    assert_int_equal(f.seg.blobs[0].flags, CYL_BLOB_TOUCH_LEFT);
    assert_int_equal(f.seg.blobs[1].flags, CYL_BLOB_TOUCH_RIGHT | CYL_BLOB_TOUCH_BOTTOM);
    /* inside a ROI the ROI's edges count */
    f.p.roi.x = 2; f.p.roi.y = 2; f.p.roi.width = 30; f.p.roi.height = 20;
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_OK);
    assert_int_equal(f.seg.n_blobs, 1);
    assert_int_equal(f.seg.blobs[0].x0, 2);
    assert_int_equal(f.seg.blobs[0].area, 15);
    assert_int_equal(f.seg.blobs[0].flags, CYL_BLOB_TOUCH_LEFT);
    fx_close(&f);
}

static void test_formats_strides_agree(void **state)
{
    static const cyl_pixfmt fmts[] = { CYL_FMT_YUYV, CYL_FMT_UYVY, CYL_FMT_NV12, CYL_FMT_I420, CYL_FMT_YUV444P };
    fixture f;
    unsigned k;
    (void)state;
    fx_open(&f, 64, 48, 1000, 100);
    /* even-aligned rectangles: chroma subsampling does not change them */
    canvas_rect(&f.c, 4, 4, 10, 20, ORANGE);
    canvas_rect(&f.c, 30, 10, 16, 8, GREEN);
    for (k = 0; k < 5; k++) {
        size_t strides[3] = { 0, 0, 0 };
        unsigned s;
        strides[1] = (fmts[k] == CYL_FMT_YUYV || fmts[k] == CYL_FMT_UYVY) ? 64 * 2 + 36 : 64 + 28;
        strides[2] = strides[1] + 100;
        for (s = 0; s < 3; s++) {
            assert_int_equal(fx_run(&f, fmts[k], strides[s]), CYL_OK);
            assert_int_equal(f.seg.n_blobs, 2);
            assert_int_equal(f.seg.blobs[0].area, 200);
            assert_int_equal(f.seg.blobs[1].area, 128);
            assert_true(fabs(f.seg.blobs[0].cx_px - 8.5) < 1e-12);
        }
    }
    fx_close(&f);
}

static void test_roi_and_step(void **state)
{
    fixture f;
    const cyl_blob *b;
    (void)state;
    fx_open(&f, 64, 48, 1000, 100);
    canvas_rect(&f.c, 10, 10, 20, 12, ORANGE);  /* columns 10..29, rows 10..21 */
    f.p.x_step = 2; f.p.y_step = 3;
    assert_int_equal(fx_run(&f, CYL_FMT_YUYV, 0), CYL_OK);
    assert_int_equal(f.seg.n_blobs, 1);
    b = &f.seg.blobs[0];
    /* sampled columns 10,12,...,28 (10) and rows 12,15,18,21 (4) */
    assert_int_equal(b->area, 40);
    assert_int_equal(b->x0, 10); assert_int_equal(b->x1, 28);
    assert_int_equal(b->y0, 12); assert_int_equal(b->y1, 21);
    assert_true(fabs(b->cx_px - 19.0) < 1e-12);
    assert_true(fabs(b->cy_px - 16.5) < 1e-12);
    assert_int_equal(f.seg.runs[b->first_run].width, 10);
    /* ROI with an odd origin and step 1 on a packed format */
    f.p.x_step = 1; f.p.y_step = 1;
    f.p.roi.x = 13; f.p.roi.y = 11; f.p.roi.width = 21; f.p.roi.height = 5;
    assert_int_equal(fx_run(&f, CYL_FMT_YUYV, 0), CYL_OK);
    assert_int_equal(f.seg.n_blobs, 1);
    assert_int_equal(f.seg.blobs[0].area, 17 * 5);
    assert_int_equal(f.seg.blobs[0].x0, 13);
    /* bad ROI */
    f.p.roi.width = 60;
    assert_int_equal(fx_run(&f, CYL_FMT_YUYV, 0), CYL_ERR_SIZE);
    fx_close(&f);
}

static void test_capacity_truncation(void **state)
{
    fixture f;
    int i;
    (void)state;
    fx_open(&f, 64, 40, 5, 100);
    for (i = 0; i < 8; i++) canvas_rect(&f.c, 2 + 7 * i, 2 + i, 5, 1, ORANGE);  /* 8 runs, one per row */
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_TRUNCATED);
    assert_true(f.seg.truncated & CYL_SEG_RUNS_FULL);
    assert_int_equal(f.seg.n_runs, 5);
    assert_int_equal(f.seg.n_blobs, 5);
    fx_close(&f);

    fx_open(&f, 64, 40, 100, 3);
    for (i = 0; i < 8; i++) canvas_rect(&f.c, 2 + 7 * i, 2 + i, 5, 1, ORANGE);
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_TRUNCATED);
    assert_true(f.seg.truncated & CYL_SEG_BLOBS_FULL);
    assert_int_equal(f.seg.n_runs, 8);
    assert_int_equal(f.seg.n_blobs, 3);
    /* the first three components in raster order are the ones kept */
    assert_int_equal(f.seg.blobs[0].y0, 2);
    assert_int_equal(f.seg.blobs[2].y0, 4);
    fx_close(&f);

    /* memory sizing */
    {
        uint8_t small[64];
        cyl_segmentation s;
        assert_int_equal(cyl_segmentation_init(&s, small, sizeof small, 100, 10), CYL_ERR_NOMEM);
        assert_int_equal(cyl_segment_mem_size(0xFFFFFFFFu, 1), 0);
    }
}

static void test_bad_arguments(void **state)
{
    fixture f;
    (void)state;
    fx_open(&f, 16, 16, 100, 10);
    assert_true(canvas_to_format(&f.c, CYL_FMT_YUYV, 0, 0, f.buf, f.cap, &f.img));
    assert_int_equal(cyl_segment(NULL, &f.img, &f.p, &f.seg), CYL_ERR_ARG);
    assert_int_equal(cyl_segment(&table, NULL, &f.p, &f.seg), CYL_ERR_ARG);
    f.p.min_run_px = 0;
    assert_int_equal(cyl_segment(&table, &f.img, &f.p, &f.seg), CYL_ERR_ARG);
    f.p.min_run_px = 3;
    f.p.cls[2].merge_min_density = NAN;
    assert_int_equal(cyl_segment(&table, &f.img, &f.p, &f.seg), CYL_ERR_ARG);
    f.p.cls[2].merge_min_density = 0.5;
    f.img.stride[0] = 31;  /* smaller than a row of 16 YUYV pixels */
    assert_int_equal(cyl_segment(&table, &f.img, &f.p, &f.seg), CYL_ERR_SIZE);
    f.img.stride[0] = 32;
    f.img.format = (cyl_pixfmt)99;
    assert_int_equal(cyl_segment(&table, &f.img, &f.p, &f.seg), CYL_ERR_FORMAT);
    /* defaults when params are NULL */
    f.img.format = CYL_FMT_YUYV;
    assert_int_equal(cyl_segment(&table, &f.img, NULL, &f.seg), CYL_OK);
    fx_close(&f);
}

/* Random frames: the library against the brute-force flood fill. */
static void test_bruteforce_random(void **state)
{
    static const cyl_pixfmt fmts[] = { CYL_FMT_YUYV, CYL_FMT_UYVY, CYL_FMT_NV12, CYL_FMT_I420, CYL_FMT_YUV444P };
    static const uint8_t speck[5][3] = { { ORANGE }, { GREEN }, { 200, 120, 170 }, { GREY }, { 150, 200, 170 } };
    test_rng rng;
    int iter, total_blobs = 0, weak_runs = 0, weak_alone_blobs = 0;
    uint32_t max_runs = 200000, max_blobs = 20000;
    size_t ms = cyl_segment_mem_size(max_runs, max_blobs);
    void *mem = malloc(ms);
    ref_blob *ref = (ref_blob *)malloc(sizeof(ref_blob) * 20000);
    cyl_segmentation seg;
    (void)state;
    make_table();
    /* a third, overlapping class to exercise the priority rule */
    cyl_colortable_set_class(&table, 2, "pink", 255, 100, 200);
    cyl_colortable_add_box(&table, 2, 100, 255, 75, 130, 150, 200);
    /* and a brightness-dependent (3-D) part: pink only in every other brightness cell and
     * not at a few chroma cells, so that the lookup's yuv path decides pixels too */
    {
        unsigned yc, uc, vc;
        for (yc = 0; yc < CYL_YUV_NY; yc++)
            for (uc = 0; uc < CYL_YUV_NC; uc++)
                for (vc = 0; vc < CYL_YUV_NC; vc++)
                    if ((yc & 1u) || ((uc + vc) % 3u) == 0) table.yuv[yc][uc][vc] &= (cyl_mask)~(1u << 2);
        assert_int_equal(table.lookup, CYL_LOOKUP_UV_Y);   /* stale: the edit was by hand */
        cyl_colortable_refresh(&table);
        assert_int_equal(table.lookup, CYL_LOOKUP_UV_Y | CYL_LOOKUP_YUV);
    }
    /* and a weak class: 3 is the weak evidence of 1 (green); its colour is the third speck's */
    cyl_colortable_set_class(&table, 3, "green~", 0, 128, 0);
    cyl_colortable_add_box(&table, 3, 100, 255, 190, 210, 160, 180);
    assert_int_equal(cyl_colortable_set_weak(&table, 3, 1), CYL_OK);
    assert_int_equal(cyl_segmentation_init(&seg, mem, ms, max_runs, max_blobs), CYL_OK);
    test_rng_seed(&rng, 20261122);
    for (iter = 0; iter < 3000; iter++) {
        canvas c;
        cyl_image img;
        cyl_segment_params p = cyl_segment_params_default();
        uint32_t w = (uint32_t)test_rng_int(&rng, 1, 90), h = (uint32_t)test_rng_int(&rng, 1, 60);
        cyl_pixfmt fmt = fmts[test_rng_int(&rng, 0, 4)];
        int nrect = (int)test_rng_int(&rng, 0, 12), i, n;
        size_t stride, cap;
        uint8_t *buf;
        unsigned k;
        assert_true(canvas_alloc(&c, w, h));
        canvas_fill(&c, GREY);
        for (i = 0; i < nrect; i++) {
            const int pick = (int)test_rng_int(&rng, 0, 3);
            const uint8_t *col = speck[pick == 3 ? 4 : pick];
            canvas_rect(&c, (int32_t)test_rng_int(&rng, -5, (int64_t)w), (int32_t)test_rng_int(&rng, -5, (int64_t)h),
                        (int32_t)test_rng_int(&rng, 1, 30), (int32_t)test_rng_int(&rng, 1, 30), col[0], col[1], col[2]);
        }
        canvas_speckle(&c, &rng, test_rng_uniform(&rng) * 0.3, speck, 5);
        if (test_rng_int(&rng, 0, 1)) canvas_noise(&c, &rng, 4.0, 6.0);
        stride = test_rng_int(&rng, 0, 1) ? 0 : (size_t)(fmt == CYL_FMT_YUYV || fmt == CYL_FMT_UYVY ? 4 * ((w + 1) / 2) : w) + (size_t)test_rng_int(&rng, 1, 13);
        cap = canvas_format_size(&c, fmt, stride);
        buf = (uint8_t *)malloc(cap);
        assert_true(canvas_to_format(&c, fmt, stride, (uint8_t)test_rng_int(&rng, 0, 255), buf, cap, &img));
        p.min_run_px = (uint16_t)test_rng_int(&rng, 1, 4);
        p.x_step = (uint16_t)(test_rng_int(&rng, 0, 3) ? 1 : test_rng_int(&rng, 2, 3));
        p.y_step = (uint16_t)(test_rng_int(&rng, 0, 3) ? 1 : test_rng_int(&rng, 2, 3));
        if (test_rng_int(&rng, 0, 2) == 0) {
            p.roi.x = (uint32_t)test_rng_int(&rng, 0, (int64_t)w - 1);
            p.roi.y = (uint32_t)test_rng_int(&rng, 0, (int64_t)h - 1);
            p.roi.width = (uint32_t)test_rng_int(&rng, 1, (int64_t)(w - p.roi.x));
            p.roi.height = (uint32_t)test_rng_int(&rng, 1, (int64_t)(h - p.roi.y));
        }
        for (k = 0; k < CYL_MAX_CLASSES; k++) {
            p.cls[k].merge_gap_px = -1;
            p.cls[k].min_area = (uint32_t)test_rng_int(&rng, 0, 6);
        }
        /* sometimes a weak component alone is a blob of green once large enough */
        if (test_rng_int(&rng, 0, 1)) p.cls[1].weak_alone_min_area = (uint32_t)test_rng_int(&rng, 1, 60);
        assert_int_equal(cyl_segment(&table, &img, &p, &seg), CYL_OK);
        n = ref_segment(&table, &img, &p, ref, 20000, NULL);
        assert_int_equal(n, (int)seg.n_blobs);
        for (i = 0; i < n; i++) {
            const cyl_blob *b = &seg.blobs[i];
            const ref_blob *r = &ref[i];
            uint32_t ri, cnt = 0, area = 0, strong = 0;
            assert_int_equal(b->cls, r->cls);
            assert_int_equal(b->area, r->area);
            assert_int_equal(b->x0, r->x0); assert_int_equal(b->x1, r->x1);
            assert_int_equal(b->y0, r->y0); assert_int_equal(b->y1, r->y1);
            assert_int_equal(b->flags & CYL_BLOB_TOUCH_ANY, r->touches);
            assert_int_equal(!!(b->flags & CYL_BLOB_WEAK_ONLY), r->weak_only);
            assert_true(fabs(b->cx_px - r->cx) < 1e-9 && fabs(b->cy_px - r->cy) < 1e-9);
            assert_true(fabs(b->mxx_px2 - r->mxx) < 1e-6 && fabs(b->myy_px2 - r->myy) < 1e-6);
            assert_true(fabs(b->mxy_px2 - r->mxy) < 1e-6);
            for (ri = b->first_run; ri != CYL_NONE; ri = seg.runs[ri].next) {
                assert_int_equal(seg.runs[ri].blob, (uint32_t)i);
                /* runs keep their own class: the blob's, or its weak class's */
                assert_true(seg.runs[ri].cls == b->cls || table.weak_of[seg.runs[ri].cls] == b->cls);
                weak_runs += seg.runs[ri].cls != b->cls;
                strong += seg.runs[ri].cls == b->cls;
                area += seg.runs[ri].width;
                cnt++;
            }
            assert_int_equal(cnt, b->n_runs);
            assert_int_equal(area, b->area);
            if (!strong) {   /* weak runs alone: only where allowed, and large enough */
                assert_true(p.cls[b->cls].weak_alone_min_area > 0 && b->area >= p.cls[b->cls].weak_alone_min_area);
                weak_alone_blobs++;
            }
        }
        total_blobs += n;
        free(buf);
        canvas_free(&c);
    }
    assert_true(total_blobs > 3000); /* the frames were not trivially empty */
    assert_true(weak_runs > 500);    /* and weak runs joined blobs */
    assert_true(weak_alone_blobs > 100);   /* and weak components alone were kept */
    free(mem);
    free(ref);
}

/* Y, U, V of pixel (x, y), read here from each format's layout (independently of the library). */
static void fetch_pixel(const cyl_image *img, uint32_t x, uint32_t y, uint8_t *Y, uint8_t *U, uint8_t *V)
{
    const uint8_t *r0 = img->plane[0] + (size_t)y * img->stride[0];
    const uint8_t *c1 = img->plane[1] + (size_t)(y / 2u) * img->stride[1];
    switch (img->format) {
    case CYL_FMT_YUYV: *Y = r0[2u * x]; *U = r0[(x & ~1u) * 2u + 1u]; *V = r0[(x & ~1u) * 2u + 3u]; break;
    case CYL_FMT_UYVY: *Y = r0[2u * x + 1u]; *U = r0[(x & ~1u) * 2u]; *V = r0[(x & ~1u) * 2u + 2u]; break;
    case CYL_FMT_NV12: *Y = r0[x]; *U = c1[x & ~1u]; *V = c1[(x & ~1u) + 1u]; break;
    case CYL_FMT_I420:
        *Y = r0[x]; *U = c1[x / 2u]; *V = img->plane[2][(size_t)(y / 2u) * img->stride[2] + x / 2u];
        break;
    default: *Y = *U = *V = 0; break;
    }
}

/* The coarse chroma map equals its definition (computed here from uv by brute force)
 * after every kind of table edit. */
static void check_chroma_map(const cyl_colortable *t)
{
    uint8_t m[2][16];
    unsigned u, v;
    memset(m, 0, sizeof m);
    for (u = 0; u < 256; u++)
        for (v = 0; v < 256; v++)
            if (t->uv[u][v]) m[u / 128u][v / 16u] |= (uint8_t)(1u << ((u / 16u) % 8u));
    assert_memory_equal(m, t->chroma_any, sizeof m);
}

static void test_chroma_map_kept(void **state)
{
    test_rng rng;
    cyl_colortable t;
    uint8_t *buf = (uint8_t *)malloc(CYL_TABLE_FILE_MAX_SIZE);
    size_t len;
    int i;
    (void)state;
    test_rng_seed(&rng, 20261202);
    cyl_colortable_init(&t);
    check_chroma_map(&t);
    for (i = 0; i < 200; i++) {
        unsigned cls = (unsigned)test_rng_int(&rng, 0, 7);
        int op = (int)test_rng_int(&rng, 0, 9);
        if (op < 7) {
            uint8_t u0 = (uint8_t)test_rng_int(&rng, 0, 255), v0 = (uint8_t)test_rng_int(&rng, 0, 255);
            uint8_t u1 = (uint8_t)test_rng_int(&rng, u0, u0 + 40 > 255 ? 255 : u0 + 40);
            uint8_t v1 = (uint8_t)test_rng_int(&rng, v0, v0 + 40 > 255 ? 255 : v0 + 40);
            assert_int_equal(cyl_colortable_add_box(&t, cls, 0, 255, u0, u1, v0, v1), CYL_OK);
        } else if (op < 9) {
            assert_int_equal(cyl_colortable_clear_class(&t, cls), CYL_OK);
        } else {
            /* a hand edit, then refresh */
            t.uv[test_rng_int(&rng, 0, 255)][test_rng_int(&rng, 0, 255)] ^= (cyl_mask)(1u << cls);
            cyl_colortable_refresh(&t);
        }
        check_chroma_map(&t);
    }
    /* and a loaded table carries it too */
    assert_int_equal(cyl_colortable_save(&t, buf, CYL_TABLE_FILE_MAX_SIZE, &len), CYL_OK);
    {
        cyl_colortable t2;
        cyl_colortable_init(&t2);
        assert_int_equal(cyl_colortable_load(&t2, buf, len), CYL_OK);
        check_chroma_map(&t2);
        assert_memory_equal(t2.chroma_any, t.chroma_any, sizeof t.chroma_any);
    }
    free(buf);
}

/* Every colour of a class's inner box has that class (the run extension's byte-compare test relies
 * on it): all colours of a box of up to 50,000, else its corners and 50,000 random ones. */
static void check_inner_boxes(const cyl_colortable *t, test_rng *rng, int refreshed)
{
    unsigned c;
    for (c = 0; c < CYL_MAX_CLASSES; c++) {
        const uint8_t *lo = t->inner_lo[c], *hi = t->inner_hi[c];
        unsigned long vol;
        if (lo[0] > hi[0] || lo[1] > hi[1] || lo[2] > hi[2]) {
            if (refreshed) {   /* refresh leaves a box empty only for a class no cell centre has */
                unsigned yc, uc, vc;
                for (yc = 0; yc < CYL_YUV_NY; yc++)
                    for (uc = 0; uc < CYL_YUV_NC; uc++)
                        for (vc = 0; vc < CYL_YUV_NC; vc++)
                            assert_int_not_equal(cyl_mask_class(cyl_colortable_mask(t, (uint8_t)(yc * 8u + 4u),
                                                                                    (uint8_t)(uc * 4u + 2u),
                                                                                    (uint8_t)(vc * 4u + 2u))), c);
            }
            continue;
        }
        vol = (unsigned long)(hi[0] - lo[0] + 1u) * (hi[1] - lo[1] + 1u) * (hi[2] - lo[2] + 1u);
        if (vol <= 50000ul) {
            unsigned Y, U, V;
            for (Y = lo[0]; Y <= hi[0]; Y++)
                for (U = lo[1]; U <= hi[1]; U++)
                    for (V = lo[2]; V <= hi[2]; V++)
                        if (cyl_mask_class(cyl_colortable_mask(t, (uint8_t)Y, (uint8_t)U, (uint8_t)V)) != c)
                            fail_msg("class %u: (%u, %u, %u) in its inner box is not of the class", c, Y, U, V);
        } else {
            unsigned i;
            for (i = 0; i < 50008u; i++) {
                const unsigned Y = i < 8u ? (i & 1u ? hi[0] : lo[0]) : (unsigned)test_rng_int(rng, lo[0], hi[0]);
                const unsigned U = i < 8u ? (i & 2u ? hi[1] : lo[1]) : (unsigned)test_rng_int(rng, lo[1], hi[1]);
                const unsigned V = i < 8u ? (i & 4u ? hi[2] : lo[2]) : (unsigned)test_rng_int(rng, lo[2], hi[2]);
                if (cyl_mask_class(cyl_colortable_mask(t, (uint8_t)Y, (uint8_t)U, (uint8_t)V)) != c)
                    fail_msg("class %u: (%u, %u, %u) in its inner box is not of the class", c, Y, U, V);
            }
        }
    }
}

static void test_inner_boxes(void **state)
{
    test_rng rng;
    cyl_colortable t;
    uint8_t *buf = (uint8_t *)malloc(CYL_TABLE_FILE_MAX_SIZE);
    size_t len;
    int i, nonempty = 0;
    (void)state;
    test_rng_seed(&rng, 20261204);
    /* disjoint boxes: each class's inner box is its box, whole */
    cyl_colortable_init(&t);
    for (i = 0; i < CYL_MAX_CLASSES; i++) assert_true(t.inner_lo[i][0] > t.inner_hi[i][0]);   /* empty */
    cyl_colortable_add_box(&t, 0, 60, 240, 70, 90, 180, 200);
    cyl_colortable_add_box(&t, 1, 60, 240, 50, 70, 60, 80);
    cyl_colortable_refresh(&t);
    {
        static const uint8_t want[2][6] = { { 60, 70, 180, 240, 90, 200 }, { 60, 50, 60, 240, 70, 80 } };
        for (i = 0; i < 2; i++) {
            assert_memory_equal(t.inner_lo[i], want[i], 3);
            assert_memory_equal(t.inner_hi[i], want[i] + 3, 3);
        }
    }
    /* an overlapping box of an earlier class empties the later boxes; clearing a class its own */
    cyl_colortable_add_box(&t, 0, 0, 255, 60, 75, 70, 190);
    assert_true(t.inner_lo[0][0] <= t.inner_hi[0][0]);
    assert_true(t.inner_lo[1][0] > t.inner_hi[1][0]);
    check_inner_boxes(&t, &rng, 0);
    cyl_colortable_refresh(&t);
    assert_true(t.inner_lo[1][0] <= t.inner_hi[1][0]);
    /* class 1's new box stays off class 0's added chroma rectangle (U 60-75, V 70-190) */
    assert_true(t.inner_hi[1][1] < 60 || t.inner_lo[1][1] > 75 || t.inner_hi[1][2] < 70 || t.inner_lo[1][2] > 190);
    cyl_colortable_clear_class(&t, 0);
    assert_true(t.inner_lo[0][0] > t.inner_hi[0][0]);
    assert_true(t.inner_lo[1][0] <= t.inner_hi[1][0]);
    /* random tables: boxes, clears, hand edits of uv, y and yuv */
    cyl_colortable_init(&t);
    for (i = 0; i < 150; i++) {
        unsigned cls = (unsigned)test_rng_int(&rng, 0, 7);
        int op = (int)test_rng_int(&rng, 0, 9), refreshed = 0;
        if (op < 6) {
            uint8_t u0 = (uint8_t)test_rng_int(&rng, 0, 255), v0 = (uint8_t)test_rng_int(&rng, 0, 255);
            uint8_t y0 = (uint8_t)test_rng_int(&rng, 0, 200);
            uint8_t u1 = (uint8_t)test_rng_int(&rng, u0, u0 + 40 > 255 ? 255 : u0 + 40);
            uint8_t v1 = (uint8_t)test_rng_int(&rng, v0, v0 + 40 > 255 ? 255 : v0 + 40);
            assert_int_equal(cyl_colortable_add_box(&t, cls, y0, (uint8_t)test_rng_int(&rng, y0, 255), u0, u1, v0, v1),
                             CYL_OK);
            if (op < 3) { cyl_colortable_refresh(&t); refreshed = 1; }
        } else if (op < 7) {
            assert_int_equal(cyl_colortable_clear_class(&t, cls), CYL_OK);
        } else {
            /* hand edits across a class's colours, then refresh */
            unsigned k, yc = (unsigned)test_rng_int(&rng, 0, CYL_YUV_NY - 1);
            for (k = 0; k < 40u; k++) {
                t.uv[test_rng_int(&rng, 0, 255)][test_rng_int(&rng, 0, 255)] ^= (cyl_mask)(1u << cls);
                t.yuv[yc][test_rng_int(&rng, 0, CYL_YUV_NC - 1)][test_rng_int(&rng, 0, CYL_YUV_NC - 1)] ^=
                    (cyl_mask)(1u << test_rng_int(&rng, 0, 7));
            }
            t.y[test_rng_int(&rng, 0, 255)] ^= (cyl_mask)(1u << cls);
            cyl_colortable_refresh(&t);
            refreshed = 1;
        }
        check_inner_boxes(&t, &rng, refreshed);
        if (refreshed) {
            unsigned c;
            for (c = 0; c < CYL_MAX_CLASSES; c++) nonempty += t.inner_lo[c][0] <= t.inner_hi[c][0];
        }
    }
    assert_true(nonempty > 200);   /* boxes were there to check */
    /* a loaded table has the boxes refresh computes */
    assert_int_equal(cyl_colortable_save(&t, buf, CYL_TABLE_FILE_MAX_SIZE, &len), CYL_OK);
    {
        cyl_colortable t2;
        cyl_colortable_refresh(&t);
        cyl_colortable_init(&t2);
        assert_int_equal(cyl_colortable_load(&t2, buf, len), CYL_OK);
        assert_memory_equal(t2.inner_lo, t.inner_lo, sizeof t.inner_lo);
        assert_memory_equal(t2.inner_hi, t.inner_hi, sizeof t.inner_hi);
    }
    free(buf);
}

/* The vector background skip against the scalar reference path: bit-identical runs and
 * blobs on random wide frames (every 4:2:x format, ROIs, odd starts), with random tables
 * whose classes cover small chroma boxes, so that the coarse map's 16x16 blocks are often
 * set by chroma next to the background's (the scalar fallback is exercised), and frames
 * mixing background chroma from everywhere with class colours and specks. */
static void test_vector_path_identical(void **state)
{
    static const cyl_pixfmt fmts[] = { CYL_FMT_YUYV, CYL_FMT_UYVY, CYL_FMT_NV12, CYL_FMT_I420 };
    test_rng rng;
    uint32_t max_runs = 400000, max_blobs = 40000;
    size_t ms = cyl_segment_mem_size(max_runs, max_blobs);
    void *mem_a = malloc(ms), *mem_b = malloc(ms);
    cyl_segmentation sa, sb;
    int iter;
    unsigned long total_runs = 0;
    (void)state;
    assert_int_equal(cyl_segmentation_init(&sa, mem_a, ms, max_runs, max_blobs), CYL_OK);
    assert_int_equal(cyl_segmentation_init(&sb, mem_b, ms, max_runs, max_blobs), CYL_OK);
    test_rng_seed(&rng, 12345);
    for (iter = 0; iter < 600; iter++) {
        cyl_colortable t;
        canvas c;
        cyl_image img;
        cyl_segment_params p = cyl_segment_params_default();
        uint32_t w = (uint32_t)test_rng_int(&rng, 1, 700), h = (uint32_t)test_rng_int(&rng, 1, 12);
        cyl_pixfmt fmt = fmts[test_rng_int(&rng, 0, 3)];
        uint8_t col[3][3], lo[3][2], span[3][2];
        unsigned k, n_cls = (unsigned)test_rng_int(&rng, 1, 3);
        uint32_t i, j;
        double p_col = test_rng_uniform(&rng) * 0.2;
        size_t cap;
        uint8_t *buf;
        cyl_colortable_init(&t);
        for (k = 0; k < n_cls; k++) {
            uint8_t u0 = (uint8_t)test_rng_int(&rng, 0, 230), v0 = (uint8_t)test_rng_int(&rng, 0, 230);
            uint8_t du = (uint8_t)test_rng_int(&rng, 0, 25), dv = (uint8_t)test_rng_int(&rng, 0, 25);
            cyl_colortable_add_box(&t, k, 30, 240, u0, (uint8_t)(u0 + du), v0, (uint8_t)(v0 + dv));
            lo[k][0] = u0; lo[k][1] = v0; span[k][0] = du; span[k][1] = dv;
            col[k][0] = (uint8_t)test_rng_int(&rng, 30, 240);
            col[k][1] = (uint8_t)(u0 + du / 2);
            col[k][2] = (uint8_t)(v0 + dv / 2);
        }
        switch (iter % 3) {
        case 1: {   /* a brightness-dependent part too (lookup: uv, y and yuv) */
            unsigned yc, uc, vc;
            for (yc = 0; yc < CYL_YUV_NY; yc += 2)
                for (uc = 0; uc < CYL_YUV_NC; uc++)
                    for (vc = 0; vc < CYL_YUV_NC; vc++) t.yuv[yc][uc][vc] &= (cyl_mask)~1u;
            cyl_colortable_refresh(&t);
            break;
        }
        case 2: {   /* the learned form: whole chroma cells in uv, y all ones, yuv decides (lookup: yuv) */
            unsigned yc, u, v;
            memset(t.y, 0xFF, sizeof t.y);
            for (u = 0; u < 256; u++)
                for (v = 0; v < 256; v++) {
                    cyl_mask cell = 0;
                    unsigned du, dv;
                    for (du = 0; du < 4u; du++)
                        for (dv = 0; dv < 4u; dv++) cell |= t.uv[(u & ~3u) + du][(v & ~3u) + dv];
                    t.uv[u][v] = cell;
                    for (yc = 0; yc < CYL_YUV_NY; yc++)
                        t.yuv[yc][u >> 2][v >> 2] = (cyl_mask)((yc % 3u) == 0 ? 0 : cell);
                }
            cyl_colortable_refresh(&t);
            assert_int_equal(t.lookup, CYL_LOOKUP_YUV);
            break;
        }
        default:   /* boxes alone; every other such table refreshed, which computes the inner boxes
                      of the run extension (adding a box leaves them empty) */
            if (iter % 2) cyl_colortable_refresh(&t);
            break;
        }
        assert_true(canvas_alloc(&c, w, h));
        for (j = 0; j < h; j++)
            for (i = 0; i < w; i++) {
                size_t o = (size_t)j * w + i;
                if (test_rng_uniform(&rng) < p_col) {
                    k = (unsigned)test_rng_int(&rng, 0, (int64_t)n_cls - 1);
                    c.y[o] = col[k][0]; c.u[o] = col[k][1]; c.v[o] = col[k][2];
                    if (test_rng_int(&rng, 0, 1)) {   /* anywhere in the class's box: often outside
                                                          its inner box, still of the class */
                        c.y[o] = (uint8_t)test_rng_int(&rng, 30, 240);
                        c.u[o] = (uint8_t)(lo[k][0] + test_rng_int(&rng, 0, span[k][0]));
                        c.v[o] = (uint8_t)(lo[k][1] + test_rng_int(&rng, 0, span[k][1]));
                    }
                } else {
                    /* background: grey-ish, or any chroma near a class's block */
                    c.y[o] = (uint8_t)test_rng_int(&rng, 0, 255);
                    if (test_rng_int(&rng, 0, 1)) {
                        c.u[o] = (uint8_t)test_rng_int(&rng, 100, 156);
                        c.v[o] = (uint8_t)test_rng_int(&rng, 100, 156);
                    } else {
                        k = (unsigned)test_rng_int(&rng, 0, (int64_t)n_cls - 1);
                        c.u[o] = (uint8_t)((col[k][1] & 0xF0u) | (unsigned)test_rng_int(&rng, 0, 15));
                        c.v[o] = (uint8_t)((col[k][2] & 0xF0u) | (unsigned)test_rng_int(&rng, 0, 15));
                    }
                }
            }
        for (j = 0; j < 3 && w > 40; j++)   /* a few long coloured stretches */
            canvas_rect(&c, (int32_t)test_rng_int(&rng, 0, (int64_t)w - 1), 0, (int32_t)test_rng_int(&rng, 1, 80),
                        (int32_t)h, col[0][0], col[0][1], col[0][2]);
        cap = canvas_format_size(&c, fmt, 0);
        buf = (uint8_t *)malloc(cap);
        assert_true(canvas_to_format(&c, fmt, 0, 0x5A, buf, cap, &img));
        p.min_run_px = (uint16_t)test_rng_int(&rng, 1, 3);
        if (test_rng_int(&rng, 0, 2) == 0) {
            p.roi.x = (uint32_t)test_rng_int(&rng, 0, (int64_t)w - 1);
            p.roi.y = 0;
            p.roi.width = (uint32_t)test_rng_int(&rng, 1, (int64_t)(w - p.roi.x));
            p.roi.height = h;
        }
        p.scalar_only = 1;
        assert_int_equal(cyl_segment(&t, &img, &p, &sa), CYL_OK);
        p.scalar_only = 0;
        assert_int_equal(cyl_segment(&t, &img, &p, &sb), CYL_OK);
        assert_int_equal(sa.n_runs, sb.n_runs);
        assert_int_equal(sa.n_blobs, sb.n_blobs);
        assert_memory_equal(sa.runs, sb.runs, sizeof(cyl_run) * sa.n_runs);
        assert_memory_equal(sa.blobs, sb.blobs, sizeof(cyl_blob) * sa.n_blobs);
        total_runs += sa.n_runs;
        /* the class map (cyl_classify, whose 4:2:x path shares the vector skip) pixel by pixel */
        {
            cyl_roi roi = p.roi;
            uint32_t rw, rh, x, yy;
            uint8_t *cls;
            if (roi.width == 0) { roi.x = 0; roi.y = 0; roi.width = w; roi.height = h; }
            rw = roi.width; rh = roi.height;
            cls = (uint8_t *)malloc((size_t)rw * rh + 1);
            assert_int_equal(cyl_classify(&t, &img, &roi, 1, 1, cls, rw), CYL_OK);
            for (yy = 0; yy < rh; yy++)
                for (x = 0; x < rw; x++) {
                    uint8_t Y, U, V;
                    fetch_pixel(&img, roi.x + x, roi.y + yy, &Y, &U, &V);
                    if (cls[(size_t)yy * rw + x] != cyl_mask_class(cyl_colortable_mask(&t, Y, U, V)))
                        fail_msg("classify: frame %d pixel (%u, %u)", iter, roi.x + x, roi.y + yy);
                }
            free(cls);
        }
        free(buf);
        canvas_free(&c);
    }
    assert_true(total_runs > 15000);   /* the frames were not trivially empty (about 20,000 runs:
                                          the count varies with the compiler's argument order) */
    free(mem_a);
    free(mem_b);
}

/* Bands encoded separately and joined give what cyl_segment() gives, bit for bit: random frames,
 * steps, ROIs, weak classes and band splits (empty bands included). */
static void test_bands_join_identical(void **state)
{
    static const uint8_t speck[4][3] = { { ORANGE }, { GREEN }, { 200, 120, 170 }, { 150, 200, 170 } };
    static const cyl_pixfmt fmts[] = { CYL_FMT_YUYV, CYL_FMT_NV12, CYL_FMT_I420, CYL_FMT_YUV444P };
    test_rng rng;
    uint32_t max_runs = 100000, max_blobs = 10000;
    size_t ms = cyl_segment_mem_size(max_runs, max_blobs);
    void *mem_a = malloc(ms), *mem_b = malloc(ms);
    cyl_run *band_buf = (cyl_run *)malloc(sizeof(cyl_run) * max_runs);
    cyl_segmentation sa, sb;
    int iter, joined_across = 0;
    (void)state;
    make_table();
    cyl_colortable_set_class(&table, 3, "green~", 0, 128, 0);
    cyl_colortable_add_box(&table, 3, 100, 255, 190, 210, 160, 180);
    assert_int_equal(cyl_colortable_set_weak(&table, 3, 1), CYL_OK);
    assert_int_equal(cyl_segmentation_init(&sa, mem_a, ms, max_runs, max_blobs), CYL_OK);
    assert_int_equal(cyl_segmentation_init(&sb, mem_b, ms, max_runs, max_blobs), CYL_OK);
    test_rng_seed(&rng, 424242);
    for (iter = 0; iter < 400; iter++) {
        canvas c;
        cyl_image img;
        cyl_segment_params p = cyl_segment_params_default();
        uint32_t w = (uint32_t)test_rng_int(&rng, 1, 300), h = (uint32_t)test_rng_int(&rng, 1, 80);
        cyl_pixfmt fmt = fmts[test_rng_int(&rng, 0, 3)];
        uint32_t rows, cut[6], n_runs[5], used = 0, i;
        const cyl_run *band_runs[5];
        unsigned nbands = (unsigned)test_rng_int(&rng, 1, 5), k;
        size_t cap;
        uint8_t *buf;
        int nrect = (int)test_rng_int(&rng, 0, 15);
        assert_true(canvas_alloc(&c, w, h));
        canvas_fill(&c, GREY);
        for (i = 0; i < (uint32_t)nrect; i++) {
            const uint8_t *col = speck[test_rng_int(&rng, 0, 3)];
            canvas_rect(&c, (int32_t)test_rng_int(&rng, -5, (int64_t)w), (int32_t)test_rng_int(&rng, -5, (int64_t)h),
                        (int32_t)test_rng_int(&rng, 1, 60), (int32_t)test_rng_int(&rng, 1, 40), col[0], col[1], col[2]);
        }
        canvas_speckle(&c, &rng, test_rng_uniform(&rng) * 0.2, speck, 4);
        cap = canvas_format_size(&c, fmt, 0);
        buf = (uint8_t *)malloc(cap);
        assert_true(canvas_to_format(&c, fmt, 0, 0, buf, cap, &img));
        p.min_run_px = (uint16_t)test_rng_int(&rng, 1, 3);
        p.x_step = (uint16_t)(test_rng_int(&rng, 0, 3) ? 1 : 2);
        p.y_step = (uint16_t)(test_rng_int(&rng, 0, 3) ? 1 : test_rng_int(&rng, 2, 3));
        if (test_rng_int(&rng, 0, 2) == 0) {
            p.roi.x = (uint32_t)test_rng_int(&rng, 0, (int64_t)w - 1);
            p.roi.y = (uint32_t)test_rng_int(&rng, 0, (int64_t)h - 1);
            p.roi.width = (uint32_t)test_rng_int(&rng, 1, (int64_t)(w - p.roi.x));
            p.roi.height = (uint32_t)test_rng_int(&rng, 1, (int64_t)(h - p.roi.y));
        }
        assert_int_equal(cyl_segment(&table, &img, &p, &sa), CYL_OK);
        rows = cyl_segment_rows(&img, &p);
        assert_true(rows >= 1);
        /* band limits: sorted random cuts, so some bands may be empty */
        cut[0] = 0;
        cut[nbands] = rows;
        for (k = 1; k < nbands; k++) cut[k] = (uint32_t)test_rng_int(&rng, 0, rows);
        for (k = 1; k < nbands; k++) {
            unsigned m;
            for (m = k + 1; m < nbands; m++)
                if (cut[m] < cut[k]) { uint32_t tmp = cut[k]; cut[k] = cut[m]; cut[m] = tmp; }
        }
        for (k = 0; k < nbands; k++) {
            cyl_run *dst = band_buf + used;
            assert_int_equal(cyl_segment_band(&table, &img, &p, cut[k], cut[k + 1], dst, max_runs - used, &n_runs[k]),
                             CYL_OK);
            band_runs[k] = dst;
            used += n_runs[k];
        }
        assert_int_equal(cyl_segment_join(&table, &img, &p, band_runs, n_runs, nbands, &sb), CYL_OK);
        assert_int_equal(sa.n_runs, sb.n_runs);
        assert_int_equal(sa.n_blobs, sb.n_blobs);
        assert_memory_equal(sa.runs, sb.runs, sizeof(cyl_run) * sa.n_runs);
        assert_memory_equal(sa.blobs, sb.blobs, sizeof(cyl_blob) * sa.n_blobs);
        assert_memory_equal(sa.class_first, sb.class_first, sizeof sa.class_first);
        assert_memory_equal(sa.class_count, sb.class_count, sizeof sa.class_count);
        assert_int_equal(sa.x_last, sb.x_last);
        assert_int_equal(sa.y_last, sb.y_last);
        for (i = 0; i < sa.n_blobs; i++)   /* some blob crosses a seam */
            for (k = 1; k < nbands; k++)
                if (cut[k] > 0 && cut[k] < rows && sa.blobs[i].y0 < p.roi.y + cut[k] * p.y_step &&
                    sa.blobs[i].y1 >= p.roi.y + cut[k] * p.y_step) joined_across++;
        /* bands given out of order are refused */
        if (nbands >= 2 && n_runs[0] > 0 && n_runs[nbands - 1] > 0 && cut[1] < cut[nbands - 1]) {
            const cyl_run *rev[2];
            uint32_t nrev[2];
            rev[0] = band_runs[nbands - 1]; nrev[0] = n_runs[nbands - 1];
            rev[1] = band_runs[0]; nrev[1] = n_runs[0];
            assert_int_equal(cyl_segment_join(&table, &img, &p, rev, nrev, 2, &sb), CYL_ERR_ARG);
        }
        assert_int_equal(cyl_segment_band(&table, &img, &p, 0, rows + 1, band_buf, max_runs, &n_runs[0]), CYL_ERR_ARG);
        free(buf);
        canvas_free(&c);
    }
    assert_true(joined_across > 200);
    free(mem_a);
    free(mem_b);
    free(band_buf);
}

static void test_vector_path_name(void **state)
{
    const char *n = cyl_segment_vector_path();
    (void)state;
    assert_true(strcmp(n, "avx2") == 0 || strcmp(n, "ssse3") == 0 || strcmp(n, "neon") == 0 ||
                strcmp(n, "scalar") == 0);
#if defined(__aarch64__) && !defined(CYL_NO_SIMD)
    assert_string_equal(n, "neon");
#endif
#if defined(__arm__) && !defined(__ARM_NEON)
    assert_string_equal(n, "scalar");
#endif
#if defined(CYL_EXPECT_VECTOR_PATH)   /* a build that forces a path (mk/config.mk) */
    assert_string_equal(n, CYL_EXPECT_VECTOR_PATH);
#endif
}

static void test_deterministic(void **state)
{
    static const uint8_t speck[2][3] = { { ORANGE }, { GREEN } };
    fixture f;
    test_rng rng;
    cyl_blob *first;
    cyl_run *runs;
    uint32_t nb, nr;
    (void)state;
    fx_open(&f, 160, 120, 20000, 2000);
    f.p = cyl_segment_params_default();
    test_rng_seed(&rng, 7);
    canvas_rect(&f.c, 20, 20, 30, 60, ORANGE);
    canvas_rect(&f.c, 52, 20, 20, 60, ORANGE);
    canvas_speckle(&f.c, &rng, 0.2, speck, 2);
    canvas_noise(&f.c, &rng, 3, 3);
    assert_int_equal(fx_run(&f, CYL_FMT_YUYV, 0), CYL_OK);
    nb = f.seg.n_blobs; nr = f.seg.n_runs;
    first = (cyl_blob *)malloc(sizeof(cyl_blob) * nb);
    runs = (cyl_run *)malloc(sizeof(cyl_run) * nr);
    memcpy(first, f.seg.blobs, sizeof(cyl_blob) * nb);
    memcpy(runs, f.seg.runs, sizeof(cyl_run) * nr);
    memset(f.seg.blobs, 0x5A, sizeof(cyl_blob) * nb);
    assert_int_equal(fx_run(&f, CYL_FMT_YUYV, 0), CYL_OK);
    assert_int_equal(f.seg.n_blobs, nb);
    assert_int_equal(f.seg.n_runs, nr);
    assert_memory_equal(first, f.seg.blobs, sizeof(cyl_blob) * nb);
    assert_memory_equal(runs, f.seg.runs, sizeof(cyl_run) * nr);
    free(first); free(runs);
    fx_close(&f);
}

/* The segmentation records the run filter and each class's merge gap it used (the image
 * estimator redoes both); cyl_segmentation_init starts from "keep every run, no merging". */
static void test_records_its_parameters(void **state)
{
    fixture f;
    (void)state;
    fx_open(&f, 64, 48, 512, 16);
    assert_int_equal(f.seg.min_run_px, 1);
    assert_int_equal(f.seg.merge_gap_px[3], -1);
    f.p.min_run_px = 4;
    f.p.cls[1].merge_gap_px = 7;
    assert_int_equal(fx_run(&f, CYL_FMT_YUYV, 0), CYL_OK);
    assert_int_equal(f.seg.min_run_px, 4);
    assert_int_equal(f.seg.merge_gap_px[1], 7);
    assert_int_equal(f.seg.merge_gap_px[0], -1);
    fx_close(&f);
}

/* ---- splitting at a waist --------------------------------------------------- */

/* A cone-like shape: rows ytop..ytop+rows-1, each one run centred on cx whose width goes
 * linearly from w_top to w_bottom. */
static void draw_taper(canvas *c, int32_t cx, int32_t ytop, int32_t rows, int32_t w_top, int32_t w_bottom,
                       uint8_t Y, uint8_t U, uint8_t V)
{
    int32_t j;
    for (j = 0; j < rows; j++) {
        const int32_t w = rows > 1 ? w_top + (int32_t)lround((double)(w_bottom - w_top) * j / (rows - 1)) : w_top;
        canvas_rect(c, cx - w / 2, ytop + j, w, 1, Y, U, V);
    }
}

/* The segmentation's invariants after a split: every run of a blob's list is labelled with the
 * blob, runs in (y, x) order within a list and in the array, the statistics that the runs give (area, box, run
 * count, centroid), the blobs' order, class_first and class_count. */
static void check_split_consistent(const cyl_segmentation *seg)
{
    uint32_t k, ri, labelled = 0, cnt[CYL_MAX_CLASSES] = { 0 };
    for (k = 0; k < seg->n_blobs; k++) {
        const cyl_blob *b = &seg->blobs[k];
        uint32_t area = 0, n = 0, x0 = 0xFFFF, x1 = 0, y0 = 0xFFFF, y1 = 0, py = 0, px = 0;
        double sx = 0, sy = 0;
        for (ri = b->first_run; ri != CYL_NONE; ri = seg->runs[ri].next) {
            const cyl_run *r = &seg->runs[ri];
            const uint32_t xe = r->x + (uint32_t)(r->width - 1u) * seg->x_step;
            uint32_t q;
            assert_int_equal(r->blob, k);
            assert_int_equal(r->cls, b->cls);
            if (n) assert_true(r->y > py || (r->y == py && r->x > px));
            py = r->y; px = r->x;
            for (q = 0; q < r->width; q++) { sx += r->x + (double)q * seg->x_step; sy += r->y; }
            area += r->width; n++;
            if (r->x < x0) x0 = r->x;
            if (xe > x1) x1 = xe;
            if (r->y < y0) y0 = r->y;
            if (r->y > y1) y1 = r->y;
        }
        labelled += n;
        assert_int_equal(b->area, area); assert_int_equal(b->n_runs, n);
        assert_int_equal(b->x0, x0); assert_int_equal(b->x1, x1);
        assert_int_equal(b->y0, y0); assert_int_equal(b->y1, y1);
        assert_true(fabs(b->cx_px - sx / area) < 1e-9 && fabs(b->cy_px - sy / area) < 1e-9);
        if (k > 0) {
            const cyl_blob *a = &seg->blobs[k - 1];
            assert_true(a->cls < b->cls || (a->cls == b->cls && (a->area > b->area ||
                        (a->area == b->area && (a->y0 < b->y0 || (a->y0 == b->y0 && a->x0 <= b->x0))))));
        }
        if (cnt[b->cls]++ == 0) assert_int_equal(seg->class_first[b->cls], k);
    }
    for (k = 0; k < CYL_MAX_CLASSES; k++) assert_int_equal(seg->class_count[k], cnt[k]);
    for (ri = 0, k = 0; ri < seg->n_runs; ri++) {
        k += seg->runs[ri].blob != CYL_NONE;
        if (ri > 0) {   /* the array in (y, x) order */
            const cyl_run *a = &seg->runs[ri - 1], *r = &seg->runs[ri];
            assert_true(r->y > a->y || (r->y == a->y && r->x > a->x));
        }
    }
    assert_int_equal(k, labelled);
}

static cyl_status fx_split(fixture *f, const cyl_split_params *sp, uint32_t *n_split)
{
    const size_t ws = cyl_segment_split_work_size(&f->seg);
    void *work = malloc(ws ? ws : 1);
    cyl_status st = cyl_segment_split(&f->seg, sp, work, ws, n_split);
    free(work);
    return st;
}

/* Two orange cones, the far one's base on the near one's tip, and a green one alone: the pair is
 * cut at the tip's row, and each part's statistics are those of its cone segmented alone. */
static void test_split_stacked_cones(void **state)
{
    fixture f, g;
    cyl_split_params sp = cyl_split_params_default();
    cyl_blob alone[2];
    uint32_t n_split = 99, k;
    (void)state;
    fx_open(&f, 120, 100, 4000, 64);
    fx_open(&g, 120, 100, 4000, 64);
    /* far cone: rows 10..29, 4 -> 20 px wide; near cone: rows 30..79, 6 -> 40 px wide */
    draw_taper(&f.c, 40, 10, 20, 4, 20, ORANGE);
    draw_taper(&f.c, 40, 30, 50, 6, 40, ORANGE);
    draw_taper(&f.c, 95, 20, 40, 4, 24, GREEN);
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_OK);
    assert_int_equal(f.seg.n_blobs, 2);
    assert_int_equal(f.seg.blobs[0].y0, 10); assert_int_equal(f.seg.blobs[0].y1, 79);
    /* each alone */
    draw_taper(&g.c, 40, 10, 20, 4, 20, ORANGE);
    assert_int_equal(fx_run(&g, CYL_FMT_YUV444P, 0), CYL_OK);
    alone[1] = g.seg.blobs[0];
    canvas_fill(&g.c, GREY);
    draw_taper(&g.c, 40, 30, 50, 6, 40, ORANGE);
    assert_int_equal(fx_run(&g, CYL_FMT_YUV444P, 0), CYL_OK);
    alone[0] = g.seg.blobs[0];
    /* waist ratio 0 (the default): nothing happens, no workspace needed */
    assert_int_equal(cyl_segment_split(&f.seg, &sp, NULL, 0, &n_split), CYL_OK);
    assert_int_equal(n_split, 0);
    assert_int_equal(f.seg.n_blobs, 2);
    /* green only: the orange pair stays whole */
    sp.waist_ratio[1] = 0.9;
    assert_int_equal(fx_split(&f, &sp, &n_split), CYL_OK);
    assert_int_equal(n_split, 0);
    /* orange: the tip row (30) is 6 px against 20 above and 40 below, a share of 0.3 */
    sp.waist_ratio[0] = 0.25;
    assert_int_equal(fx_split(&f, &sp, &n_split), CYL_OK);
    assert_int_equal(n_split, 0);
    sp.waist_ratio[0] = 0.35;
    assert_int_equal(fx_split(&f, &sp, &n_split), CYL_OK);
    assert_int_equal(n_split, 1);
    assert_int_equal(f.seg.n_blobs, 3);
    check_split_consistent(&f.seg);
    for (k = 0; k < 2; k++) {
        const cyl_blob *b = &f.seg.blobs[k], *a = &alone[k];
        assert_int_equal(b->cls, 0);
        assert_int_equal(b->flags, CYL_BLOB_SPLIT);
        assert_int_equal(b->area, a->area); assert_int_equal(b->n_runs, a->n_runs);
        assert_int_equal(b->x0, a->x0); assert_int_equal(b->x1, a->x1);
        assert_int_equal(b->y0, a->y0); assert_int_equal(b->y1, a->y1);
        assert_true(fabs(b->cx_px - a->cx_px) < 1e-12 && fabs(b->cy_px - a->cy_px) < 1e-12);
        assert_true(fabs(b->mxx_px2 - a->mxx_px2) < 1e-9 && fabs(b->myy_px2 - a->myy_px2) < 1e-9);
        assert_true(fabs(b->mxy_px2 - a->mxy_px2) < 1e-9);
        assert_true(fabs(b->elongation - a->elongation) < 1e-9);
    }
    assert_int_equal(f.seg.blobs[2].cls, 1);
    assert_int_equal(f.seg.blobs[2].flags, 0);
    assert_int_equal(f.seg.class_first[1], 2);
    /* split again: the parts have no waist of their own */
    assert_int_equal(fx_split(&f, &sp, &n_split), CYL_OK);
    assert_int_equal(n_split, 0);
    fx_close(&f);
    fx_close(&g);
}

/* Single shapes have no waist along rows or columns, even at a ratio of 1: a cylinder (rectangle), a cone, one upside
 * down, a ball, a box seen from a corner (a hexagon-like taper up then down). */
static void test_split_single_shapes(void **state)
{
    fixture f;
    cyl_split_params sp = cyl_split_params_default();
    uint32_t n_split = 99;
    unsigned k;
    (void)state;
    for (k = 0; k < CYL_MAX_CLASSES; k++) sp.waist_ratio[k] = 1.0;
    sp.axes = CYL_SPLIT_ROWS | CYL_SPLIT_COLUMNS;
    sp.min_part_lines = 1;
    sp.min_part_share = 0.0;
    fx_open(&f, 240, 100, 8000, 64);
    canvas_rect(&f.c, 5, 10, 20, 60, ORANGE);
    draw_taper(&f.c, 50, 10, 60, 4, 40, ORANGE);
    draw_taper(&f.c, 100, 10, 60, 40, 4, ORANGE);
    canvas_ellipse(&f.c, 150.3, 40.6, 18.2, 25.7, ORANGE);
    draw_taper(&f.c, 205, 10, 30, 10, 40, ORANGE);
    draw_taper(&f.c, 205, 40, 40, 40, 12, ORANGE);
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_OK);
    assert_int_equal(f.seg.n_blobs, 5);
    assert_int_equal(fx_split(&f, &sp, &n_split), CYL_OK);
    assert_int_equal(n_split, 0);
    assert_int_equal(f.seg.n_blobs, 5);
    fx_close(&f);
}

/* Two standing cones side by side, their bases touching in the bottom row: one blob, no row waist,
 * a column waist where the bases meet. Cut along columns, each part is its cone (to the column the
 * cut falls on: the two columns either side of the contact are equally narrow). */
static void test_split_side_by_side(void **state)
{
    fixture f;
    cyl_split_params sp = cyl_split_params_default();
    uint32_t n_split = 99, area_a, area_b;
    (void)state;
    fx_open(&f, 120, 80, 4000, 64);
    draw_taper(&f.c, 40, 20, 40, 4, 30, ORANGE);   /* columns 25..54 at the bottom row (59) */
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_OK);
    area_a = f.seg.blobs[0].area;
    canvas_fill(&f.c, GREY);
    draw_taper(&f.c, 70, 20, 40, 4, 30, ORANGE);   /* columns 55..84 */
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_OK);
    area_b = f.seg.blobs[0].area;
    draw_taper(&f.c, 40, 20, 40, 4, 30, ORANGE);
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_OK);
    assert_int_equal(f.seg.n_blobs, 1);
    assert_int_equal(f.seg.blobs[0].area, area_a + area_b);
    sp.waist_ratio[0] = 0.5;
    assert_int_equal(fx_split(&f, &sp, &n_split), CYL_OK);   /* rows only (the default): no waist */
    assert_int_equal(n_split, 0);
    sp.axes = CYL_SPLIT_ROWS | CYL_SPLIT_COLUMNS;
    assert_int_equal(fx_split(&f, &sp, &n_split), CYL_OK);
    assert_int_equal(n_split, 1);
    assert_int_equal(f.seg.n_blobs, 2);
    check_split_consistent(&f.seg);
    {
        /* blobs sorted by area: find which part is the left one */
        const cyl_blob *l = f.seg.blobs[0].x0 < f.seg.blobs[1].x0 ? &f.seg.blobs[0] : &f.seg.blobs[1];
        const cyl_blob *r = l == &f.seg.blobs[0] ? &f.seg.blobs[1] : &f.seg.blobs[0];
        assert_int_equal(l->x0, 25); assert_int_equal(r->x1, 84);
        assert_true(l->x1 == 53 || l->x1 == 54);
        assert_int_equal(r->x0, l->x1 + 1);
        /* the contact column holds at most the bottom rows' samples */
        assert_true(abs((int)l->area - (int)area_a) <= 2 && abs((int)r->area - (int)area_b) <= 2);
        assert_true(fabs(l->cx_px - 39.5) < 0.5 && fabs(r->cx_px - 69.5) < 0.5);
        assert_int_equal(l->flags, CYL_BLOB_SPLIT);
        assert_int_equal(r->flags, CYL_BLOB_SPLIT);
    }
    fx_close(&f);
    /* a run array with no room for the crossing runs' right pieces: no cut, and it says so */
    fx_open(&f, 120, 80, 79, 64);   /* 39 rows of two runs, the bottom row one */
    draw_taper(&f.c, 40, 20, 40, 4, 30, ORANGE);
    draw_taper(&f.c, 70, 20, 40, 4, 30, ORANGE);
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_OK);
    assert_int_equal(f.seg.n_runs, 79);
    assert_int_equal(fx_split(&f, &sp, &n_split), CYL_TRUNCATED);
    assert_int_equal(n_split, 0);
    assert_int_equal(f.seg.n_blobs, 1);
    assert_true(f.seg.truncated & CYL_SEG_RUNS_FULL);
    check_split_consistent(&f.seg);
    fx_close(&f);
}

/* Two pieces merged across a gap of empty rows: the gap rows have no extent and are never a cut,
 * but a real waist inside a merged blob is. */
static void test_split_merged_gap(void **state)
{
    fixture f;
    cyl_split_params sp = cyl_split_params_default();
    uint32_t n_split = 99;
    (void)state;
    fx_open(&f, 80, 100, 4000, 64);
    f.p.cls[0].merge_gap_px = 3;
    f.p.cls[0].merge_min_density = 0.0;
    canvas_rect(&f.c, 20, 10, 20, 30, ORANGE);   /* rows 10..39 */
    canvas_rect(&f.c, 20, 42, 20, 30, ORANGE);   /* rows 42..71: two empty rows between */
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_OK);
    assert_int_equal(f.seg.n_blobs, 1);
    assert_true(f.seg.blobs[0].flags & CYL_BLOB_MERGED);
    sp.waist_ratio[0] = 1.0;
    assert_int_equal(fx_split(&f, &sp, &n_split), CYL_OK);
    assert_int_equal(n_split, 0);
    /* a 4 px neck in the lower piece (rows 55..56) is a waist: cut at row 55 */
    canvas_rect(&f.c, 20, 55, 20, 2, GREY);
    canvas_rect(&f.c, 28, 55, 4, 2, ORANGE);
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_OK);
    assert_int_equal(f.seg.n_blobs, 1);
    sp.waist_ratio[0] = 0.5;
    assert_int_equal(fx_split(&f, &sp, &n_split), CYL_OK);
    assert_int_equal(n_split, 1);
    check_split_consistent(&f.seg);
    assert_int_equal(f.seg.blobs[0].y0, 10); assert_int_equal(f.seg.blobs[0].y1, 54);
    assert_int_equal(f.seg.blobs[1].y0, 55); assert_int_equal(f.seg.blobs[1].y1, 71);
    /* the parts keep the parent's component count and merged flag */
    assert_int_equal(f.seg.blobs[0].flags, CYL_BLOB_MERGED | CYL_BLOB_SPLIT);
    assert_int_equal(f.seg.blobs[1].flags, CYL_BLOB_MERGED | CYL_BLOB_SPLIT);
    fx_close(&f);
}

/* Brute-force reference on a mask of grid samples (m[gy * GW + gx], 1 = the part's): the row
 * profile (each grid row's first to last sample, in samples) and the column profile (each grid
 * column's first to last sampled row with a sample, in rows); every row and column tried: the least
 * share ext / min(widest before, widest after), below the ratio, the first on a tie, each part at
 * least `need` rows (columns); the row cut when both axes have one and its share is not larger;
 * then each part again. Appends each final part's (x0, y0, area) key to out; returns their count. */
enum { GW = 240, GH = 120 };

static int ref_profile_cut(const uint32_t *ext, unsigned n, double ratio, const cyl_split_params *sp,
                           uint32_t *num, uint32_t *den)
{
    unsigned need = (unsigned)ceil(sp->min_part_share * n), j, i, best = 0;
    uint32_t be = 0, bm = 0;
    if (need < sp->min_part_lines) need = sp->min_part_lines;
    if (need < 1u) need = 1u;
    if (n < 2u * need) return 0;
    for (j = need; j + need <= n; j++) {
        uint32_t before = 0, after = 0, m;
        for (i = 0; i < j; i++) if (ext[i] > before) before = ext[i];
        for (i = j + 1u; i < n; i++) if (ext[i] > after) after = ext[i];
        m = before < after ? before : after;
        if (m == 0 || ext[j] == 0 || (double)ext[j] >= ratio * m) continue;
        if (best == 0 || (uint64_t)ext[j] * bm < (uint64_t)be * m) { best = j; be = ext[j]; bm = m; }
    }
    *num = be; *den = bm;
    return (int)best;
}

static unsigned ref_split_mask(const uint8_t *m, double ratio, const cyl_split_params *sp, uint32_t ys,
                               uint32_t xs, uint64_t *out)
{
    int gx, gy, x0 = GW, x1 = -1, y0 = GH, y1 = -1, jr = 0, jc = 0;
    uint32_t ext[GW > GH ? GW : GH] = { 0 }, rn = 0, rd = 1, cn = 0, cd = 1, area = 0;
    unsigned n;
    uint8_t *a, *b;
    for (gy = 0; gy < GH; gy++)
        for (gx = 0; gx < GW; gx++)
            if (m[gy * GW + gx]) {
                if (gx < x0) x0 = gx;
                if (gx > x1) x1 = gx;
                if (gy < y0) y0 = gy;
                if (gy > y1) y1 = gy;
                area++;
            }
    if (sp->axes & CYL_SPLIT_ROWS) {
        for (gy = y0; gy <= y1; gy++) {
            int lo = -1, hi = -1;
            for (gx = x0; gx <= x1; gx++) if (m[gy * GW + gx]) { if (lo < 0) lo = gx; hi = gx; }
            ext[gy - y0] = lo < 0 ? 0u : (uint32_t)(hi - lo + 1);
        }
        jr = ref_profile_cut(ext, (unsigned)(y1 - y0 + 1), ratio, sp, &rn, &rd);
    }
    if (sp->axes & CYL_SPLIT_COLUMNS) {
        for (gx = x0; gx <= x1; gx++) {
            int lo = -1, hi = -1;
            for (gy = y0; gy <= y1; gy++) if (m[gy * GW + gx]) { if (lo < 0) lo = gy; hi = gy; }
            ext[gx - x0] = lo < 0 ? 0u : (uint32_t)(hi - lo + 1);
        }
        jc = ref_profile_cut(ext, (unsigned)(x1 - x0 + 1), ratio, sp, &cn, &cd);
    }
    if (jr && jc) {
        if ((uint64_t)cn * rd < (uint64_t)rn * cd) jr = 0; else jc = 0;
    }
    if (!jr && !jc) {
        out[0] = ((uint64_t)(y0 * ys) << 40) | ((uint64_t)(x0 * xs) << 24) | area;
        return 1;
    }
    a = (uint8_t *)calloc(GW * GH, 1);
    b = (uint8_t *)calloc(GW * GH, 1);
    for (gy = y0; gy <= y1; gy++)
        for (gx = x0; gx <= x1; gx++)
            if (m[gy * GW + gx]) {
                const int first = jr ? gy < y0 + jr : gx < x0 + jc;
                (first ? a : b)[gy * GW + gx] = 1;
            }
    n = ref_split_mask(a, ratio, sp, ys, xs, out);
    n += ref_split_mask(b, ratio, sp, ys, xs, out + n);
    free(a);
    free(b);
    return n;
}

static int cmp_u64(const void *x, const void *y)
{
    const uint64_t a = *(const uint64_t *)x, b = *(const uint64_t *)y;
    return (a > b) - (a < b);
}

/* Random shapes, sampled every row and every second row and column, cut along rows, columns or both: the
 * parts cyl_segment_split() makes are those of the brute-force reference on the shapes' masks.
 * Each shape is a stack of centred runs (one a row, random widths or a random walk of them) or a
 * row of centred columns (one a column, random heights or a random walk), so it is 4-connected
 * through its centre line; rows or columns with gaps appear when the stack is read the other
 * way. Every run and every sample survives, once: the parts' areas add up to the shapes'. */
static void test_split_bruteforce_random(void **state)
{
    enum { SHAPES = 4 };
    fixture f;
    test_rng rng;
    unsigned trial, total_cuts = 0, col_trials_cut = 0;
    uint8_t *mask = (uint8_t *)malloc(GW * GH);
    (void)state;
    test_rng_seed(&rng, 20261205u);
    fx_open(&f, GW, GH, 40000, 512);
    for (trial = 0; trial < 400; trial++) {
        const uint32_t ys = (trial & 1u) ? 2u : 1u, xs = (trial & 2u) ? 2u : 1u;
        uint32_t n_split, area_all = 0, area_parts = 0;
        uint64_t expect[512], got[512];
        unsigned n_exp = 0, n_got = 0, s, k;
        cyl_split_params sp = cyl_split_params_default();
        sp.waist_ratio[0] = 0.2 + 0.7 * test_rng_uniform(&rng);
        sp.min_part_lines = (uint16_t)test_rng_int(&rng, 1, 5);
        sp.min_part_share = 0.3 * test_rng_uniform(&rng);
        sp.axes = (unsigned)test_rng_int(&rng, 1, 3);
        canvas_fill(&f.c, GREY);
        f.p.y_step = (uint16_t)ys;
        f.p.x_step = (uint16_t)xs;
        f.p.min_run_px = (uint16_t)(xs == 1u ? 3u : 2u);
        for (s = 0; s < SHAPES; s++) {
            const int walk = (int)test_rng_int(&rng, 0, 1), by_cols = (int)test_rng_int(&rng, 0, 1);
            const int32_t cx = 30 + 60 * (int32_t)s;
            const int32_t len = by_cols ? (int32_t)test_rng_int(&rng, 4, 54) : (int32_t)test_rng_int(&rng, 4, 100);
            const int32_t top = (int32_t)test_rng_int(&rng, 0, 10) * 2;
            int32_t j, cur = (int32_t)test_rng_int(&rng, 4, 50);
            for (j = 0; j < len; j++) {
                if (walk) {
                    cur += (int32_t)test_rng_int(&rng, -6, 6);
                    if (cur < 4) cur = 4;
                    if (cur > 54) cur = 54;
                } else {
                    cur = (int32_t)test_rng_int(&rng, 4, 54);
                }
                if (by_cols) canvas_rect(&f.c, cx - len / 2 + j, 60 - cur, 1, 2 * cur, ORANGE);   /* rows 6..113 */
                else canvas_rect(&f.c, cx - cur / 2, top + j, cur, 1, ORANGE);
            }
        }
        assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_OK);
        assert_int_equal(f.seg.n_blobs, SHAPES);
        /* the reference, on each blob's samples as a mask on the grid */
        for (k = 0; k < f.seg.n_blobs; k++) {
            uint32_t ri;
            memset(mask, 0, GW * GH);
            for (ri = f.seg.blobs[k].first_run; ri != CYL_NONE; ri = f.seg.runs[ri].next) {
                const cyl_run *r = &f.seg.runs[ri];
                uint32_t q;
                for (q = 0; q < r->width; q++) mask[(r->y / ys) * GW + r->x / xs + q] = 1;
            }
            area_all += f.seg.blobs[k].area;
            n_exp += ref_split_mask(mask, sp.waist_ratio[0], &sp, ys, xs, expect + n_exp);
        }
        assert_int_equal(fx_split(&f, &sp, &n_split), CYL_OK);
        assert_int_equal(n_split, n_exp - SHAPES);
        total_cuts += n_split;
        col_trials_cut += n_split > 0 && (sp.axes & CYL_SPLIT_COLUMNS);
        check_split_consistent(&f.seg);
        for (k = 0; k < f.seg.n_blobs; k++) {
            const cyl_blob *b = &f.seg.blobs[k];
            got[n_got++] = ((uint64_t)b->y0 << 40) | ((uint64_t)b->x0 << 24) | b->area;
            area_parts += b->area;
        }
        assert_int_equal(area_parts, area_all);
        assert_int_equal(n_got, n_exp);
        qsort(expect, n_exp, sizeof expect[0], cmp_u64);
        qsort(got, n_got, sizeof got[0], cmp_u64);
        for (k = 0; k < n_got; k++) assert_true(got[k] == expect[k]);
    }
    /* the trials exercised cuts, recursive and column ones included */
    assert_true(total_cuts > 400);
    assert_true(col_trials_cut > 100);
    free(mask);
    fx_close(&f);
}

/* Full blob table: the cut is not made, the segmentation says so; bad parameters; small workspace. */
static void test_split_capacity_and_arguments(void **state)
{
    fixture f;
    cyl_split_params sp = cyl_split_params_default();
    uint32_t n_split = 99;
    uint8_t small[8];
    (void)state;
    fx_open(&f, 80, 100, 4000, 1);
    draw_taper(&f.c, 40, 10, 20, 4, 20, ORANGE);
    draw_taper(&f.c, 40, 30, 50, 6, 40, ORANGE);
    assert_int_equal(fx_run(&f, CYL_FMT_YUV444P, 0), CYL_OK);
    sp.waist_ratio[0] = 0.5;
    assert_int_equal(fx_split(&f, &sp, &n_split), CYL_TRUNCATED);
    assert_int_equal(n_split, 0);
    assert_int_equal(f.seg.n_blobs, 1);
    assert_true(f.seg.truncated & CYL_SEG_BLOBS_FULL);
    assert_int_equal(f.seg.blobs[0].flags, 0);
    check_split_consistent(&f.seg);
    /* the workspace: two counters a sampled row or column (100 rows, 80 columns), one a row */
    assert_int_equal(cyl_segment_split_work_size(&f.seg), (2u * 100u + 100u) * sizeof(uint32_t));
    assert_int_equal(cyl_segment_split_work_size(NULL), 0);
    assert_int_equal(cyl_segment_split(&f.seg, &sp, small, sizeof small, &n_split), CYL_ERR_SIZE);
    assert_int_equal(cyl_segment_split(&f.seg, &sp, NULL, 0, &n_split), CYL_ERR_SIZE);
    assert_int_equal(cyl_segment_split(NULL, &sp, small, sizeof small, &n_split), CYL_ERR_ARG);
    assert_int_equal(cyl_segment_split(&f.seg, NULL, small, sizeof small, &n_split), CYL_ERR_ARG);
    sp.waist_ratio[3] = 1.5;
    assert_int_equal(cyl_segment_split(&f.seg, &sp, small, sizeof small, &n_split), CYL_ERR_ARG);
    sp.waist_ratio[3] = -0.1;
    assert_int_equal(cyl_segment_split(&f.seg, &sp, small, sizeof small, &n_split), CYL_ERR_ARG);
    sp.waist_ratio[3] = NAN;
    assert_int_equal(cyl_segment_split(&f.seg, &sp, small, sizeof small, &n_split), CYL_ERR_ARG);
    sp.waist_ratio[3] = 0.0;
    sp.min_part_share = 0.6;
    assert_int_equal(cyl_segment_split(&f.seg, &sp, small, sizeof small, &n_split), CYL_ERR_ARG);
    sp.min_part_share = 0.15;
    sp.axes = 0;
    assert_int_equal(cyl_segment_split(&f.seg, &sp, small, sizeof small, &n_split), CYL_ERR_ARG);
    sp.axes = 4;
    assert_int_equal(cyl_segment_split(&f.seg, &sp, small, sizeof small, &n_split), CYL_ERR_ARG);
    fx_close(&f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rectangles_exact),
        cmocka_unit_test(test_short_runs_vanish),
        cmocka_unit_test(test_touching_classes_apart),
        cmocka_unit_test(test_diagonal_contact_apart),
        cmocka_unit_test(test_merge_criterion),
        cmocka_unit_test(test_merge_chain_and_classes),
        cmocka_unit_test(test_min_area_and_order),
        cmocka_unit_test(test_border_flags),
        cmocka_unit_test(test_formats_strides_agree),
        cmocka_unit_test(test_roi_and_step),
        cmocka_unit_test(test_capacity_truncation),
        cmocka_unit_test(test_bad_arguments),
        cmocka_unit_test(test_records_its_parameters),
        cmocka_unit_test(test_bruteforce_random),
        cmocka_unit_test(test_deterministic),
        cmocka_unit_test(test_chroma_map_kept),
        cmocka_unit_test(test_inner_boxes),
        cmocka_unit_test(test_vector_path_identical),
        cmocka_unit_test(test_vector_path_name),
        cmocka_unit_test(test_bands_join_identical),
        cmocka_unit_test(test_split_stacked_cones),
        cmocka_unit_test(test_split_single_shapes),
        cmocka_unit_test(test_split_side_by_side),
        cmocka_unit_test(test_split_merged_gap),
        cmocka_unit_test(test_split_bruteforce_random),
        cmocka_unit_test(test_split_capacity_and_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
