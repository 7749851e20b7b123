/* SPDX-License-Identifier: BSD-3-Clause */
/* Colour learning: histograms, the likelihood-ratio decision at a false-positive rate
 * (hand-derived cases), overlap resolution, brightness-dependent chroma, and errors. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdlib.h>
#include <string.h>

#include "cyl/colorlearn.h"
#include "cyl/segment.h"
#include "synth_frames.h"

static cyl_colorhist *hist_new(void)
{
    cyl_colorhist *h = malloc(sizeof *h);
    cyl_colorhist_clear(h);
    return h;
}

static void put(cyl_colorhist *h, uint8_t Y, uint8_t U, uint8_t V, uint32_t n)
{
    h->count[cyl_yuv_cell(Y, U, V)] += n;
    h->total += n;
}

static cyl_learn_params exact_params(void)
{
    cyl_learn_params p = cyl_learn_params_default();
    p.smooth_sigma_cells = 0.0;   /* the counts as they are */
    p.bg_uniform_weight = 0.0;
    p.min_likelihood_ratio = 1.0;
    p.min_positive_count = 0.0;
    p.min_weak_ratio = 1.0;       /* <= min_likelihood_ratio */
    return p;
}

static void test_hist_add(void **state)
{
    canvas c;
    cyl_image img;
    uint8_t *buf, mask[8 * 6];
    size_t cap;
    cyl_roi roi = { 2, 1, 3, 2 };
    cyl_colorhist *h = hist_new();
    (void)state;
    assert_true(canvas_alloc(&c, 8, 6));
    canvas_fill(&c, 100, 60, 200);
    canvas_rect(&c, 0, 0, 4, 6, 20, 130, 131);    /* left half dark grey */
    cap = canvas_format_size(&c, CYL_FMT_YUV444P, 0);
    buf = malloc(cap);
    assert_true(canvas_to_format(&c, CYL_FMT_YUV444P, 0, 0, buf, cap, &img));
    assert_int_equal(cyl_colorhist_add(h, &img, NULL, NULL, 0, 0), CYL_OK);
    assert_int_equal(h->total, 48);
    assert_int_equal(h->count[cyl_yuv_cell(100, 60, 200)], 24);
    assert_int_equal(h->count[cyl_yuv_cell(20, 130, 131)], 24);
    assert_int_equal(cyl_yuv_cell(20, 130, 131), (2u * 64u + 32u) * 64u + 32u);
    /* ROI columns 2..4, rows 1..2: 2 dark + 1 coloured per row */
    cyl_colorhist_clear(h);
    assert_int_equal(cyl_colorhist_add(h, &img, &roi, NULL, 0, 0), CYL_OK);
    assert_int_equal(h->total, 6);
    assert_int_equal(h->count[cyl_yuv_cell(100, 60, 200)], 2);
    /* mask: only bytes equal to 7 count, in full-image coordinates */
    memset(mask, 0, sizeof mask);
    mask[1 * 8 + 4] = 7; mask[2 * 8 + 2] = 7; mask[5 * 8 + 7] = 7;   /* the last is outside the ROI */
    cyl_colorhist_clear(h);
    assert_int_equal(cyl_colorhist_add(h, &img, &roi, mask, 8, 7), CYL_OK);
    assert_int_equal(h->total, 2);
    assert_int_equal(h->count[cyl_yuv_cell(100, 60, 200)], 1);
    assert_int_equal(h->count[cyl_yuv_cell(20, 130, 131)], 1);
    assert_int_equal(cyl_colorhist_add(h, &img, &roi, mask, 7, 7), CYL_ERR_SIZE);
    roi.width = 9;
    assert_int_equal(cyl_colorhist_add(h, &img, &roi, NULL, 0, 0), CYL_ERR_SIZE);
    assert_int_equal(cyl_colorhist_add(NULL, &img, NULL, NULL, 0, 0), CYL_ERR_ARG);
    /* scaled: (100, 60, 200) at gain 1.25 is (125, 128 - 85, 128 + 90) = (125, 43, 218);
     * (20, 130, 131) is (25, 130.5 -> 131, 131.75 -> 132) */
    roi.width = 3;
    cyl_colorhist_clear(h);
    assert_int_equal(cyl_colorhist_add_scaled(h, &img, NULL, NULL, 0, 0, 1.25), CYL_OK);
    assert_int_equal(h->count[cyl_yuv_cell(125, 43, 218)], 24);
    assert_int_equal(h->count[cyl_yuv_cell(25, 131, 132)], 24);
    /* and clipped: gain 3 takes Y 100 to 255, U 60 to 0, V 200 to 255 */
    cyl_colorhist_clear(h);
    assert_int_equal(cyl_colorhist_add_scaled(h, &img, NULL, NULL, 0, 0, 3.0), CYL_OK);
    assert_int_equal(h->count[cyl_yuv_cell(255, 0, 255)], 24);
    assert_int_equal(cyl_colorhist_add_scaled(h, &img, NULL, NULL, 0, 0, 0.0), CYL_ERR_ARG);
    assert_int_equal(cyl_colorhist_add_scaled(h, &img, NULL, NULL, 0, 0, 17.0), CYL_ERR_ARG);
    canvas_free(&c);
    free(buf); free(h);
}

/* Colour-temperature augmentation, by hand (BT.601 full range). Grey (100, 128, 128) under red gain
 * 1.2 and blue gain 1/1.2: R, G, B = 120, 100, 83.33; Y = 0.299 R + 0.587 G + 0.114 B = 104.08,
 * U = 128 + (B - Y) / 1.772 = 116.29, V = 128 + (R - Y) / 1.402 = 139.36 -> (104, 116, 139).
 * Near white (250, 128, 128): R = 300 clips to 255, B = 208.33; Y = 246.75, U = 106.32,
 * V = 133.89 -> (247, 106, 134). Equal gains are the exposure scaling. White light added: grey
 * (100, 128, 128) + 20 levels is (120, 128, 128); a saturated (100, 60, 200) + 32 is R, G, B =
 * 232.9, 104.0, 11.5 -> (132, 60, 200): brighter, the same chroma; near white (250, 128, 128) + 20
 * clips to (255, 128, 128). */
static void test_hist_light(void **state)
{
    canvas c;
    cyl_image img;
    uint8_t *buf;
    size_t cap;
    cyl_colorhist *h = hist_new(), *h2 = hist_new();
    const double warm[3] = { 1.2, 1.0, 1.0 / 1.2 }, equal[3] = { 1.25, 1.25, 1.25 };
    double bad[3] = { 1.0, 0.0, 1.0 };
    unsigned k;
    (void)state;
    assert_true(canvas_alloc(&c, 8, 6));
    canvas_fill(&c, 100, 128, 128);
    canvas_rect(&c, 0, 0, 4, 6, 250, 128, 128);
    cap = canvas_format_size(&c, CYL_FMT_YUV444P, 0);
    buf = malloc(cap);
    assert_true(canvas_to_format(&c, CYL_FMT_YUV444P, 0, 0, buf, cap, &img));
    assert_int_equal(cyl_colorhist_add_light(h, &img, NULL, NULL, 0, 0, warm, 0.0), CYL_OK);
    assert_int_equal(h->total, 48);
    assert_int_equal(h->count[cyl_yuv_cell(104, 116, 139)], 24);
    assert_int_equal(h->count[cyl_yuv_cell(247, 106, 134)], 24);
    cyl_colorhist_clear(h);
    assert_int_equal(cyl_colorhist_add_light(h, &img, NULL, NULL, 0, 0, equal, 0.0), CYL_OK);
    assert_int_equal(cyl_colorhist_add_scaled(h2, &img, NULL, NULL, 0, 0, 1.25), CYL_OK);
    for (k = 0; k < CYL_YUV_CELLS; k++) assert_int_equal(h->count[k], h2->count[k]);
    assert_int_equal(cyl_colorhist_add_light(h, &img, NULL, NULL, 0, 0, bad, 0.0), CYL_ERR_ARG);
    bad[1] = 17.0;
    assert_int_equal(cyl_colorhist_add_light(h, &img, NULL, NULL, 0, 0, bad, 0.0), CYL_ERR_ARG);
    assert_int_equal(cyl_colorhist_add_light(h, &img, NULL, NULL, 0, 0, NULL, 0.0), CYL_ERR_ARG);
    cyl_colorhist_clear(h);
    bad[1] = 1.0;
    assert_int_equal(cyl_colorhist_add_light(h, &img, NULL, NULL, 0, 0, bad, 20.0), CYL_OK);
    assert_int_equal(h->count[cyl_yuv_cell(120, 128, 128)], 24);
    assert_int_equal(h->count[cyl_yuv_cell(255, 128, 128)], 24);
    assert_int_equal(cyl_colorhist_add_light(h, &img, NULL, NULL, 0, 0, bad, 256.0), CYL_ERR_ARG);
    canvas_rect(&c, 0, 0, 8, 6, 100, 60, 200);
    assert_true(canvas_to_format(&c, CYL_FMT_YUV444P, 0, 0, buf, cap, &img));
    cyl_colorhist_clear(h);
    assert_int_equal(cyl_colorhist_add_light(h, &img, NULL, NULL, 0, 0, bad, 32.0), CYL_OK);
    assert_int_equal(h->count[cyl_yuv_cell(132, 60, 200)], 48);
    canvas_free(&c);
    free(buf); free(h); free(h2);
}

/* Positives: 900 px at colour a, 100 at colour c. Negatives: 10 px at c, 9990 at b.
 * Ratios: a infinite (no background), c = 0.1 / 0.001 = 100, b = 0. */
static void test_rate_decides_hand_derived(void **state)
{
    cyl_colorhist *pos = hist_new(), *neg = hist_new();
    cyl_colortable *t = malloc(sizeof *t);
    cyl_learn_class lc = { 2, CYL_CLASS_NONE, NULL, NULL };
    size_t ws = cyl_learn_workspace_size(1);
    void *work = malloc(ws);
    cyl_learn_params p = exact_params();
    cyl_learn_report r;
    (void)state;
    put(pos, 120, 200, 60, 900);   /* a */
    put(pos, 120, 90, 90, 100);    /* c */
    put(neg, 120, 90, 90, 10);     /* c */
    put(neg, 60, 128, 128, 9990);  /* b */
    lc.positive = pos;
    cyl_colortable_init(t);
    cyl_colortable_set_class(t, 2, "x", 1, 2, 3);

    p.max_bg_fraction = 0.0005;    /* c would claim 0.001 of the background: not allowed */
    assert_int_equal(cyl_colortable_learn(t, &lc, 1, neg, &p, work, ws, &r), CYL_OK);
    assert_int_equal(r.cells, 1);
    assert_float_equal(r.recall, 0.9, 1e-12);
    assert_float_equal(r.recall_alone, 0.9, 1e-12);
    assert_float_equal(r.bg_fraction, 0.0, 1e-12);
    assert_int_equal(cyl_colortable_mask(t, 120, 200, 60), 1u << 2);
    assert_int_equal(cyl_colortable_mask(t, 127, 203, 63), 1u << 2);   /* same cell */
    assert_int_equal(cyl_colortable_mask(t, 128, 200, 60), 0);          /* next brightness cell */
    assert_int_equal(cyl_colortable_mask(t, 120, 90, 90), 0);
    assert_int_equal(t->uv[200][60], 1u << 2);                          /* uv: the projection */
    assert_int_equal(t->uv[90][90], 0);
    assert_int_equal(t->y[0], 1u << 2);

    p.max_bg_fraction = 0.002;     /* now c fits */
    assert_int_equal(cyl_colortable_learn(t, &lc, 1, neg, &p, work, ws, &r), CYL_OK);
    assert_int_equal(r.cells, 2);
    assert_float_equal(r.recall, 1.0, 1e-12);
    assert_float_equal(r.bg_fraction, 0.001, 1e-12);
    assert_true(r.lr_threshold < 100.0);
    assert_int_equal(cyl_colortable_mask(t, 120, 90, 90), 1u << 2);

    /* a minimum share of the class's pixels lowers the threshold below the rate's: with 0.95,
     * a alone (0.9) is not enough, c joins at the cost of 0.001 of the background */
    p.max_bg_fraction = 0.0005;
    p.min_class_share = 0.95;
    assert_int_equal(cyl_colortable_learn(t, &lc, 1, neg, &p, work, ws, &r), CYL_OK);
    assert_int_equal(r.cells, 2);
    assert_float_equal(r.recall, 1.0, 1e-12);
    assert_float_equal(r.bg_fraction, 0.001, 1e-12);
    p.min_class_share = 0.0;
    p.max_bg_fraction = 0.002;

    p.min_likelihood_ratio = 150;  /* ... unless its ratio (100) is below the floor */
    assert_int_equal(cyl_colortable_learn(t, &lc, 1, neg, &p, work, ws, &r), CYL_OK);
    assert_int_equal(r.cells, 1);
    assert_int_equal(cyl_colortable_mask(t, 120, 90, 90), 0);

    /* the uniform background part: with weight w over K cells, a's ratio is
     * 0.9 / (w / K); with w = 1 it is 0.9 * 131072 = 117965 > 100000 (kept), and
     * a floor of 120000 drops it */
    p = exact_params();
    p.bg_uniform_weight = 1.0;
    p.min_likelihood_ratio = 100000;
    assert_int_equal(cyl_colortable_learn(t, &lc, 1, neg, &p, work, ws, &r), CYL_OK);
    assert_int_equal(r.cells, 1);
    p.min_likelihood_ratio = 120000;
    assert_int_equal(cyl_colortable_learn(t, &lc, 1, neg, &p, work, ws, &r), CYL_ERR_EMPTY);
    free(pos); free(neg); free(t); free(work);
}

/* Background subtraction with the surround. Positives (the box): 600 px of the class's colour a,
 * 400 px of the floor b. Surround: 2000 px of b, 1000 of the wall d. Negatives: 100 px of b,
 * 9900 of e. Without the surround, b's ratio is (400/1000) / (100/10000) = 40: claimed.
 * With weight 1 the surround, scaled to the box's 1000 px (x 1/3), takes 667 px off b (none
 * left) and 0 off a: only a is the class. With weight 0.5 (x 1/6) b keeps 400 - 333.3 = 66.7
 * px, still per the box's 1000: its ratio is 0.0667 / 0.01 = 6.67. */
static void test_surround_subtracted_hand_derived(void **state)
{
    cyl_colorhist *pos = hist_new(), *neg = hist_new(), *sur = hist_new();
    cyl_colortable *t = malloc(sizeof *t);
    cyl_learn_class lc = { 1, CYL_CLASS_NONE, NULL, NULL };
    size_t ws = cyl_learn_workspace_size(1);
    void *work = malloc(ws);
    cyl_learn_params p = exact_params();
    cyl_learn_report r;
    (void)state;
    put(pos, 120, 200, 60, 600);   /* a */
    put(pos, 140, 110, 150, 400);  /* b */
    put(sur, 140, 110, 150, 2000); /* b */
    put(sur, 160, 100, 100, 1000); /* d */
    put(neg, 140, 110, 150, 100);  /* b */
    put(neg, 60, 128, 128, 9900);  /* e */
    lc.positive = pos;
    cyl_colortable_init(t);
    cyl_colortable_set_class(t, 1, "x", 1, 2, 3);
    p.max_bg_fraction = 0.02;
    p.weak_bg_fraction = 0.02;     /* the weak rate is at least the rate (no weak class here) */

    p.surround_weight = 1.0;       /* no surround given: the weight does nothing */
    assert_int_equal(cyl_colortable_learn(t, &lc, 1, neg, &p, work, ws, &r), CYL_OK);
    assert_int_equal(r.cells, 2);
    assert_int_equal(cyl_colortable_mask(t, 140, 110, 150), 1u << 1);
    lc.surround = sur;
    p.surround_weight = 0.0;       /* given, weight 0: the same */
    assert_int_equal(cyl_colortable_learn(t, &lc, 1, neg, &p, work, ws, &r), CYL_OK);
    assert_int_equal(r.cells, 2);

    p.surround_weight = 1.0;
    assert_int_equal(cyl_colortable_learn(t, &lc, 1, neg, &p, work, ws, &r), CYL_OK);
    assert_int_equal(r.cells, 1);
    assert_float_equal(r.recall, 0.6, 1e-12);     /* of the box's raw pixels */
    assert_float_equal(r.bg_fraction, 0.0, 1e-12);
    assert_int_equal(cyl_colortable_mask(t, 120, 200, 60), 1u << 1);
    assert_int_equal(cyl_colortable_mask(t, 140, 110, 150), 0);
    assert_int_equal(cyl_colortable_mask(t, 160, 100, 100), 0);

    /* weight 0.5: b's ratio is 6.67, so a floor of 6.5 keeps it and one of 6.8 does not */
    p.surround_weight = 0.5;
    p.min_likelihood_ratio = 6.5;
    p.min_weak_ratio = 6.5;
    assert_int_equal(cyl_colortable_learn(t, &lc, 1, neg, &p, work, ws, &r), CYL_OK);
    assert_int_equal(r.cells, 2);
    assert_float_equal(r.bg_fraction, 0.01, 1e-12);
    p.min_likelihood_ratio = 6.8;
    p.min_weak_ratio = 6.8;
    assert_int_equal(cyl_colortable_learn(t, &lc, 1, neg, &p, work, ws, &r), CYL_OK);
    assert_int_equal(r.cells, 1);

    /* a class whose every colour is as common around its boxes as in them is nothing */
    p = exact_params();
    p.max_bg_fraction = 0.02;
    p.weak_bg_fraction = 0.02;
    p.surround_weight = 1.0;
    cyl_colorhist_clear(sur);
    put(sur, 120, 200, 60, 600);
    put(sur, 140, 110, 150, 400);
    assert_int_equal(cyl_colortable_learn(t, &lc, 1, neg, &p, work, ws, &r), CYL_ERR_EMPTY);
    p.surround_weight = 4.5;
    assert_int_equal(cyl_colortable_learn(t, &lc, 1, neg, &p, work, ws, &r), CYL_ERR_ARG);
    p.surround_weight = -0.1;
    assert_int_equal(cyl_colortable_learn(t, &lc, 1, neg, &p, work, ws, &r), CYL_ERR_ARG);
    free(pos); free(neg); free(sur); free(t); free(work);
}

/* Two classes claim one cell: the one with the larger ratio keeps it, the report says so. */
static void test_overlap_resolved_by_ratio(void **state)
{
    cyl_colorhist *a = hist_new(), *b = hist_new(), *neg = hist_new();
    cyl_colortable *t = malloc(sizeof *t);
    cyl_learn_class lc[2] = { { 0, CYL_CLASS_NONE, NULL, NULL }, { 5, CYL_CLASS_NONE, NULL, NULL } };
    size_t ws = cyl_learn_workspace_size(2);
    void *work = malloc(ws);
    cyl_learn_params p = exact_params();
    cyl_learn_report r[2];
    (void)state;
    put(a, 150, 80, 180, 800);  put(a, 150, 100, 160, 200);   /* shared cell s = (150,100,160) */
    put(b, 150, 60, 200, 500);  put(b, 150, 100, 160, 500);
    put(neg, 60, 128, 128, 1000);
    lc[0].positive = a; lc[1].positive = b;
    cyl_colortable_init(t);
    /* a box class at index 1 stays as it is */
    cyl_colortable_add_box(t, 1, 0, 255, 100, 103, 160, 163);
    p.bg_uniform_weight = 0.5;   /* finite ratios: a's at s is 0.2/bg, b's 0.5/bg */
    assert_int_equal(cyl_colortable_learn(t, lc, 2, neg, &p, work, ws, r), CYL_OK);
    assert_float_equal(r[0].recall_alone, 1.0, 1e-12);
    assert_float_equal(r[0].recall, 0.8, 1e-12);
    assert_float_equal(r[0].lost_to[5], 0.2, 1e-12);
    assert_float_equal(r[1].recall, 1.0, 1e-12);
    assert_float_equal(r[1].lost_to[0], 0.0, 1e-12);
    assert_int_equal(cyl_colortable_mask(t, 150, 100, 160), (1u << 5) | (1u << 1));
    assert_int_equal(cyl_colortable_mask(t, 150, 80, 180), 1u << 0);
    assert_int_equal(cyl_colortable_mask(t, 20, 100, 160), 1u << 1);   /* box class: every brightness */
    /* errors */
    lc[1].cls = 0;
    assert_int_equal(cyl_colortable_learn(t, lc, 2, neg, &p, work, ws, r), CYL_ERR_ARG);
    lc[1].cls = 8;
    assert_int_equal(cyl_colortable_learn(t, lc, 2, neg, &p, work, ws, r), CYL_ERR_CLASS);
    lc[1].cls = 5;
    assert_int_equal(cyl_colortable_learn(t, lc, 2, neg, &p, work, ws - 1, r), CYL_ERR_NOMEM);
    p.max_bg_fraction = 1.5;
    assert_int_equal(cyl_colortable_learn(t, lc, 2, neg, &p, work, ws, r), CYL_ERR_ARG);
    p.max_bg_fraction = 0.01;
    cyl_colorhist_clear(neg);
    assert_int_equal(cyl_colortable_learn(t, lc, 2, neg, &p, work, ws, r), CYL_ERR_EMPTY);
    free(a); free(b); free(neg); free(t); free(work);
}

/* A colour whose chroma moves with brightness (a shaded ball: pale when lit, saturated
 * and dark in shadow) against a background that has the lit chroma in the dark and the
 * dark chroma when lit. No chroma rectangle with a brightness window separates them;
 * the 3-D table does. Rendered frames through the histogram, with smoothing on. */
static void test_brightness_dependent_chroma(void **state)
{
    canvas c;
    cyl_image img;
    uint8_t *buf, *mask;
    size_t cap;
    cyl_colorhist *pos = hist_new(), *neg = hist_new();
    cyl_colortable *t = malloc(sizeof *t);
    cyl_learn_class lc = { 0, CYL_CLASS_NONE, NULL, NULL };
    unsigned i;
    size_t ws = cyl_learn_workspace_size(1);
    void *work = malloc(ws);
    cyl_learn_report r;
    test_rng rng;
    (void)state;
    test_rng_seed(&rng, 7);
    assert_true(canvas_alloc(&c, 64, 64));
    mask = calloc(64 * 64, 1);
    canvas_fill(&c, 128, 128, 128);
    canvas_rect(&c, 0, 0, 32, 16, 200, 110, 150);    /* lit object:   Y 200, U 110, V 150 */
    canvas_rect(&c, 0, 16, 32, 16, 70, 90, 175);     /* shaded object: Y 70, U 90, V 175 */
    canvas_rect(&c, 32, 0, 32, 16, 70, 110, 150);    /* background: the lit chroma, dark */
    canvas_rect(&c, 32, 16, 32, 16, 200, 90, 175);   /* background: the shaded chroma, lit */
    canvas_noise(&c, &rng, 2.0, 2.0);
    for (i = 0; i < 64 * 32; i++) mask[i] = (i % 64) < 32;   /* object = left half of rows 0..31 */
    cap = canvas_format_size(&c, CYL_FMT_YUV444P, 0);
    buf = malloc(cap);
    assert_true(canvas_to_format(&c, CYL_FMT_YUV444P, 0, 0, buf, cap, &img));
    assert_int_equal(cyl_colorhist_add(pos, &img, NULL, mask, 64, 1), CYL_OK);
    assert_int_equal(cyl_colorhist_add(neg, &img, NULL, mask, 64, 0), CYL_OK);
    assert_int_equal(pos->total + neg->total, 64 * 64);
    lc.positive = pos;
    cyl_colortable_init(t);
    assert_int_equal(cyl_colortable_learn(t, &lc, 1, neg, NULL, work, ws, &r), CYL_OK);
    assert_true(r.recall > 0.99);
    assert_true(r.bg_fraction < 0.001);
    assert_float_equal(r.grey_fraction, 0.0, 0);
    assert_int_equal(cyl_colortable_mask(t, 200, 110, 150), 1);
    assert_int_equal(cyl_colortable_mask(t, 70, 90, 175), 1);
    assert_int_equal(cyl_colortable_mask(t, 70, 110, 150), 0);
    assert_int_equal(cyl_colortable_mask(t, 200, 90, 175), 0);
    assert_int_equal(cyl_colortable_mask(t, 128, 128, 128), 0);
    /* smoothing generalises to a slightly brighter lit object (one cell up) */
    assert_int_equal(cyl_colortable_mask(t, 209, 110, 150), 1);
    canvas_free(&c);
    free(buf); free(mask); free(pos); free(neg); free(t); free(work);
}

/* A weak class (hysteresis). Positives: 800 px at a, 100 at c, 100 at d; negatives: 10 at
 * c, 200 at d, 9790 at b. Ratios a infinite, c 100, d 0.1 / 0.02 = 5. At a rate of 0.002
 * the class keeps a and c; d (0.02 more) goes to the weak class, within 0.05. Then
 * segmentation: d next to a joins a's blob, d alone is dropped. */
static void test_weak_class_hysteresis(void **state)
{
    cyl_colorhist *pos = hist_new(), *neg = hist_new();
    cyl_colortable *t = malloc(sizeof *t);
    cyl_learn_class lc = { 1, 4, NULL, NULL };
    size_t ws = cyl_learn_workspace_size(1), ms;
    void *work = malloc(ws), *mem;
    cyl_learn_params p = exact_params();
    cyl_learn_report r;
    canvas c;
    cyl_image img;
    uint8_t *buf;
    size_t cap;
    cyl_segmentation seg;
    cyl_segment_params sp = cyl_segment_params_default();
    unsigned k;
    (void)state;
    put(pos, 120, 200, 60, 800);   /* a */
    put(pos, 120, 90, 90, 100);    /* c */
    put(pos, 200, 160, 100, 100);  /* d */
    put(neg, 120, 90, 90, 10);
    put(neg, 200, 160, 100, 200);
    put(neg, 60, 128, 128, 9790);  /* b */
    lc.positive = pos;
    p.min_likelihood_ratio = 4.0;
    p.min_weak_ratio = 1.0;
    p.max_bg_fraction = 0.002;
    p.weak_bg_fraction = 0.05;
    cyl_colortable_init(t);
    cyl_colortable_set_class(t, 1, "ball", 255, 255, 0);
    cyl_colortable_set_class(t, 4, "ball~", 128, 128, 0);
    assert_int_equal(cyl_colortable_learn(t, &lc, 1, neg, &p, work, ws, &r), CYL_OK);
    assert_int_equal(r.cells, 2);
    assert_int_equal(r.weak_cells, 1);
    assert_float_equal(r.recall, 0.9, 1e-12);
    assert_float_equal(r.weak_recall, 0.1, 1e-12);
    assert_float_equal(r.weak_bg_fraction, 0.02, 1e-12);
    assert_int_equal(cyl_colortable_mask(t, 120, 200, 60), 1u << 1);
    assert_int_equal(cyl_colortable_mask(t, 200, 160, 100), 1u << 4);
    assert_int_equal(t->weak_of[4], 1);
    assert_int_equal(t->weak_of[1], CYL_CLASS_NONE);
    assert_int_equal(t->lookup, CYL_LOOKUP_YUV);

    /* 40 x 20 frame: a at x 5..14 rows 5..9; d right of it (x 15..24, rows 5..9: side by side
     * in each row) and below it (x 5..14, rows 10..12); d alone at x 30..37 rows 5..12 */
    assert_true(canvas_alloc(&c, 40, 20));
    canvas_fill(&c, 60, 128, 128);
    canvas_rect(&c, 5, 5, 10, 5, 120, 200, 60);
    canvas_rect(&c, 15, 5, 10, 5, 200, 160, 100);
    canvas_rect(&c, 5, 10, 10, 3, 200, 160, 100);
    canvas_rect(&c, 30, 5, 8, 8, 200, 160, 100);
    cap = canvas_format_size(&c, CYL_FMT_YUV444P, 0);
    buf = malloc(cap);
    assert_true(canvas_to_format(&c, CYL_FMT_YUV444P, 0, 0, buf, cap, &img));
    ms = cyl_segment_mem_size(1000, 1000);
    mem = malloc(ms);
    assert_int_equal(cyl_segmentation_init(&seg, mem, ms, 1000, 1000), CYL_OK);
    for (k = 0; k < CYL_MAX_CLASSES; k++) sp.cls[k].merge_gap_px = -1;
    assert_int_equal(cyl_segment(t, &img, &sp, &seg), CYL_OK);
    assert_int_equal(seg.n_blobs, 1);
    assert_int_equal(seg.blobs[0].cls, 1);
    assert_int_equal(seg.blobs[0].area, 50 + 50 + 30);
    assert_int_equal(seg.blobs[0].x0, 5); assert_int_equal(seg.blobs[0].x1, 24);
    assert_int_equal(seg.blobs[0].y0, 5); assert_int_equal(seg.blobs[0].y1, 12);
    assert_int_equal(seg.class_count[4], 0);
    /* without the relation, d is a class of its own */
    assert_int_equal(cyl_colortable_set_weak(t, 4, CYL_CLASS_NONE), CYL_OK);
    assert_int_equal(cyl_segment(t, &img, &sp, &seg), CYL_OK);
    assert_int_equal(seg.n_blobs, 4);   /* a; d right of it, d below it (not 4-connected to each other), d alone */
    /* the relation's rules */
    assert_int_equal(cyl_colortable_set_weak(t, 4, 4), CYL_ERR_ARG);
    assert_int_equal(cyl_colortable_set_weak(t, 4, 1), CYL_OK);
    assert_int_equal(cyl_colortable_set_weak(t, 1, 2), CYL_ERR_ARG);   /* 1 has a weak class itself */
    assert_int_equal(cyl_colortable_set_weak(t, 2, 4), CYL_ERR_ARG);   /* 4 is weak */
    assert_int_equal(cyl_colortable_set_weak(t, 9, 1), CYL_ERR_CLASS);
    /* it survives a file round trip (version 2) */
    {
        uint8_t *fb = malloc(CYL_TABLE_FILE_MAX_SIZE);
        cyl_colortable *u = malloc(sizeof *u);
        size_t len;
        assert_int_equal(cyl_colortable_save(t, fb, CYL_TABLE_FILE_MAX_SIZE, &len), CYL_OK);
        assert_int_equal(fb[8 + 4 * 20 + 19], 2);   /* class 4's record: 1 + weak_of */
        assert_int_equal(cyl_colortable_load(u, fb, len), CYL_OK);
        assert_memory_equal(u, t, sizeof *t);
        free(fb); free(u);
    }
    canvas_free(&c);
    free(buf); free(mem); free(pos); free(neg); free(t); free(work);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hist_add),
        cmocka_unit_test(test_hist_light),
        cmocka_unit_test(test_rate_decides_hand_derived),
        cmocka_unit_test(test_surround_subtracted_hand_derived),
        cmocka_unit_test(test_overlap_resolved_by_ratio),
        cmocka_unit_test(test_brightness_dependent_chroma),
        cmocka_unit_test(test_weak_class_hysteresis),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
