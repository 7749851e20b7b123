/* SPDX-License-Identifier: BSD-3-Clause */
/* Sub-pixel edges (cyl_subpixel_centroid): on a blurred rectangle whose left side is shaded (its
 * colour nearer the background's, so the table's threshold cuts it further in), the blob's centroid
 * is biased by a third of a pixel while the sub-pixel centroid lies on the rectangle's true centre,
 * with and without noise, in planar 4:4:4 and in YUYV; a sharp-edged rectangle gives the blob's
 * centroid exactly; bad arguments are refused. The truth is the rectangle's own centre, drawn
 * with a Gaussian blur of known width (the pixel's value is the blurred indicator at its centre). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cyl/subpixel.h"
#include "cyl/segment.h"
#include "rng.h"

#define W 160
#define H 120
#define MAX_RUNS 4096
#define MAX_BLOBS 64

static const double kGrey[3] = {120, 128, 128};
static const double kBright[3] = {150, 80, 190};   /* the lit side */
static const double kDark[3] = {112, 104, 160};    /* the shaded side: nearer grey */

/* The rectangle, continuous coordinates (pixel centres at integers). */
static const double XA = 50.3, XB = 101.8, YA = 30.6, YB = 88.1;

typedef struct fixture {
    cyl_colortable table;
    uint8_t frame[W * H * 3];
    cyl_image img;
    void *mem;
    cyl_segmentation seg;
    cyl_segment_params p;
} fixture;

static void fx_open(fixture *f)
{
    size_t ms = cyl_segment_mem_size(MAX_RUNS, MAX_BLOBS);
    unsigned k;
    cyl_colortable_init(&f->table);
    cyl_colortable_set_class(&f->table, 0, "orange", 255, 128, 0);
    /* U <= 112 and V >= 150: the dark side's mix enters the class at 2/3 of the way, the bright
     * side's at a third */
    cyl_colortable_add_box(&f->table, 0, 0, 255, 0, 112, 150, 255);
    f->mem = malloc(ms);
    assert_non_null(f->mem);
    assert_int_equal(cyl_segmentation_init(&f->seg, f->mem, ms, MAX_RUNS, MAX_BLOBS), CYL_OK);
    f->p = cyl_segment_params_default();
    for (k = 0; k < CYL_MAX_CLASSES; k++) { f->p.cls[k].min_area = 1; f->p.cls[k].merge_gap_px = -1; }
}

static uint8_t q8(double v) { return (uint8_t)(v < 0 ? 0 : v > 255 ? 255 : floor(v + 0.5)); }

/* fraction of [a, b] covered at x after a Gaussian blur of std s (s = 0: the indicator) */
static double cover(double x, double a, double b, double s)
{
    if (s <= 0) return (x >= a && x < b) ? 1.0 : 0.0;
    return 0.5 * (erf((x - a) / (s * sqrt(2.0))) - erf((x - b) / (s * sqrt(2.0))));
}

/* The colour of the rectangle at column x: its left half dark, its right half bright (the step
 * between them blurred like the edges). */
static void colour_at(double x, double blur, double out[3])
{
    const double mid = 0.5 * (XA + XB);
    double t = blur > 0 ? 0.5 * (1.0 + erf((x - mid) / (blur * sqrt(2.0)))) : (x >= mid ? 1.0 : 0.0);
    int c;
    for (c = 0; c < 3; c++) out[c] = kDark[c] + t * (kBright[c] - kDark[c]);
}

static double value(int x, int y, int c, double blur)
{
    double w = cover(x, XA, XB, blur) * cover(y, YA, YB, blur), col[3];
    colour_at(x, blur, col);
    return kGrey[c] + w * (col[c] - kGrey[c]);
}

/* planar 4:4:4 (yuyv 0) or YUYV (chroma the mean of the pair) */
static void draw(fixture *f, int yuyv, double blur, double sigma, test_rng *rng)
{
    int x, y, c;
    for (y = 0; y < H; y++)
        for (x = 0; x < W; x++) {
            for (c = 0; c < 3; c++) {
                double v = value(x, y, c, blur) + (rng ? sigma * test_rng_normal(rng) : 0.0);
                if (!yuyv) {
                    f->frame[(size_t)c * W * H + (size_t)y * W + (size_t)x] = q8(v);
                } else if (c == 0) {
                    f->frame[(size_t)y * W * 2 + (size_t)x * 2] = q8(v);
                } else if ((x & 1) == 0) {
                    double m = 0.5 * (value(x, y, c, blur) + value(x + 1, y, c, blur)) +
                               (rng ? sigma * test_rng_normal(rng) : 0.0);
                    f->frame[(size_t)y * W * 2 + (size_t)x * 2 + (c == 1 ? 1 : 3)] = q8(m);
                }
            }
        }
    assert_int_equal(cyl_image_wrap(&f->img, yuyv ? CYL_FMT_YUYV : CYL_FMT_YUV444P, W, H, f->frame, 0), CYL_OK);
}

static const cyl_blob *segment(fixture *f)
{
    assert_int_equal(cyl_segment(&f->table, &f->img, &f->p, &f->seg), CYL_OK);
    if (f->seg.class_count[0] == 0) return NULL;
    return &f->seg.blobs[f->seg.class_first[0]];
}

/* A fresh fixture with the noise-free rectangle drawn (4:4:4 unless yuyv) and segmented; its blob. */
static const cyl_blob *drawn(fixture *f, int yuyv, double blur)
{
    const cyl_blob *b;
    fx_open(f);
    draw(f, yuyv, blur, 0.0, NULL);
    b = segment(f);
    assert_non_null(b);
    return b;
}

static const double CX = 0.5 * (XA + XB), CY = 0.5 * (YA + YB);

/* Noise-free, blur 1 px, 4:4:4 and YUYV: the blob's centroid is pulled right by 0.67 px (the
 * shaded left side lost, the lit right side gained); the sub-pixel one is on the centre within
 * 0.05 px (0.06 in YUYV; measured 0.025 and 0.033: the corners, left where the table put them). */
static void test_shaded_rectangle_centred(void **state)
{
    int yuyv;
    (void)state;
    for (yuyv = 0; yuyv <= 1; yuyv++) {
        fixture f;
        const cyl_blob *b;
        cyl_subpixel_params p = cyl_subpixel_params_default();
        cyl_subpixel_result r;
        b = drawn(&f, yuyv, 1.0);
        assert_true(b->cx_px - CX > 0.25);
        assert_int_equal(cyl_subpixel_centroid(&f.seg, b, &f.img, &f.table, &p, &r), CYL_OK);
        assert_true(fabs(r.cx_px - CX) < (yuyv ? 0.06 : 0.05));
        assert_true(fabs(r.cy_px - CY) < 0.03);
        assert_true(fabs(r.du_px - (r.cx_px - b->cx_px)) < 1e-12);
        assert_true(fabs(r.dv_px - (r.cy_px - b->cy_px)) < 1e-12);
        /* every edge sample of a convex blob this size is moved */
        assert_true(r.edges > 200 && r.edges_moved == r.edges);
        /* the area is the rectangle's */
        assert_true(fabs(r.area_px2 - (XB - XA) * (YB - YA)) < 0.01 * (XB - XA) * (YB - YA));
        free(f.mem);
    }
}

/* With noise (2 levels per sample) and a blur of 1.2 px, over 40 frames: the sub-pixel centroid's
 * mean within 0.06 px of the centre (measured 0.024 and 0.042), the blob's 0.7-0.8 px off. */
static void test_noisy_frames_unbiased(void **state)
{
    fixture f;
    test_rng rng;
    cyl_subpixel_params p = cyl_subpixel_params_default();
    double sx = 0, sy = 0, hx = 0;
    int k, yuyv;
    (void)state;
    for (yuyv = 0; yuyv <= 1; yuyv++) {
        sx = sy = hx = 0;
        fx_open(&f);
        test_rng_seed(&rng, 5u + (unsigned)yuyv);
        for (k = 0; k < 40; k++) {
            const cyl_blob *b;
            cyl_subpixel_result r;
            draw(&f, yuyv, 1.2, 2.0, &rng);
            b = segment(&f);
            assert_non_null(b);
            assert_int_equal(cyl_subpixel_centroid(&f.seg, b, &f.img, &f.table, &p, &r), CYL_OK);
            sx += r.cx_px;
            sy += r.cy_px;
            hx += b->cx_px;
        }
        assert_true(fabs(sx / 40 - CX) < 0.06);
        assert_true(fabs(sy / 40 - CY) < 0.03);
        assert_true(hx / 40 - CX > 0.25);
        free(f.mem);
    }
}

/* A sharp edge (no blur): s is 0 outside and 1 inside, the crossing is the table's edge, and the
 * centroid is the blob's, exactly. */
static void test_sharp_edge_keeps_centroid(void **state)
{
    fixture f;
    const cyl_blob *b;
    cyl_subpixel_params p = cyl_subpixel_params_default();
    cyl_subpixel_result r;
    (void)state;
    b = drawn(&f, 0, 0.0);
    assert_int_equal(cyl_subpixel_centroid(&f.seg, b, &f.img, &f.table, &p, &r), CYL_OK);
    assert_true(r.edges_moved > 100);   /* every edge looked at and found where the table put it */
    assert_true(fabs(r.du_px) < 1e-9 && fabs(r.dv_px) < 1e-9);
    assert_true(fabs(r.area_px2 - (double)b->area) < 1e-9);
    free(f.mem);
}

/* A sampling grid of 2 x 2 from an ROI at (3, 1) (grid columns at odd x, rows at odd y), blur
 * 2 px: the edges are found on the grid, the centre within 0.1 px (the blob's 1.3 px off). */
static void test_subsampled_grid(void **state)
{
    fixture f;
    const cyl_blob *b;
    cyl_subpixel_params p = cyl_subpixel_params_default();
    cyl_subpixel_result r;
    (void)state;
    fx_open(&f);
    f.p.x_step = 2;
    f.p.y_step = 2;
    f.p.roi.x = 3;
    f.p.roi.y = 1;
    f.p.roi.width = W - 3;
    f.p.roi.height = H - 1;
    draw(&f, 0, 2.0, 0.0, NULL);
    b = segment(&f);
    assert_non_null(b);
    assert_int_equal(cyl_subpixel_centroid(&f.seg, b, &f.img, &f.table, &p, &r), CYL_OK);
    assert_true(fabs(r.cx_px - CX) < 0.1);
    assert_true(fabs(r.cy_px - CY) < 0.05);
    assert_true(fabs(b->cx_px - CX) > 0.2);
    free(f.mem);
}

/* Gaps near the edge, 2 samples of background: a hole 3 px inside the left edge (12 rows), whose
 * far side is a run end with the blob's own class among its outside samples; and a slit 2 rows
 * below the top (rows 33-34, 12 columns, away from the shading's step), so that the top edge's window there crosses the slit
 * into the rest of the blob. Neither is taken for an edge, and the correction is the same as
 * without the gaps (within 0.05 px); taking the hole's side for an edge, or summing the slit's
 * background into the top edge, moves it by about 0.2 px. */
static void test_gaps_left_alone(void **state)
{
    int k;
    (void)state;
    for (k = 0; k < 2; k++) {
        fixture f;
        const cyl_blob *b;
        cyl_subpixel_params p = cyl_subpixel_params_default();
        cyl_subpixel_result r0, r1;
        int x, y, c;
        const int x0 = k == 0 ? 54 : 85, x1 = k == 0 ? 56 : 97, y0 = k == 0 ? 50 : 33, y1 = k == 0 ? 62 : 35;
        b = drawn(&f, 0, 1.0);
        assert_int_equal(cyl_subpixel_centroid(&f.seg, b, &f.img, &f.table, &p, &r0), CYL_OK);
        for (y = y0; y < y1; y++)
            for (x = x0; x < x1; x++)
                for (c = 0; c < 3; c++) f.frame[(size_t)c * W * H + (size_t)y * W + (size_t)x] = (uint8_t)kGrey[c];
        b = segment(&f);
        assert_non_null(b);
        assert_int_equal(cyl_subpixel_centroid(&f.seg, b, &f.img, &f.table, &p, &r1), CYL_OK);
        assert_true(fabs(r1.du_px - r0.du_px) < 0.05);
        assert_true(fabs(r1.dv_px - r0.dv_px) < 0.05);
        assert_true(r1.edges_moved <= r0.edges_moved);
        free(f.mem);
    }
}

/* Too little contrast between the sides: every edge stays where the table put it. */
static void test_low_contrast_left_alone(void **state)
{
    fixture f;
    const cyl_blob *b;
    cyl_subpixel_params p = cyl_subpixel_params_default();
    cyl_subpixel_result r;
    (void)state;
    b = drawn(&f, 0, 1.0);
    p.min_contrast = 200.0;
    assert_int_equal(cyl_subpixel_centroid(&f.seg, b, &f.img, &f.table, &p, &r), CYL_OK);
    assert_int_equal(r.edges_moved, 0);
    assert_true(r.edges > 0);
    assert_true(fabs(r.du_px) < 1e-12 && fabs(r.dv_px) < 1e-12);
    free(f.mem);
}

static void test_bad_arguments(void **state)
{
    fixture f;
    const cyl_blob *b;
    cyl_subpixel_params p = cyl_subpixel_params_default();
    cyl_subpixel_result r;
    (void)state;
    b = drawn(&f, 0, 1.0);
    assert_int_equal(cyl_subpixel_centroid(NULL, b, &f.img, &f.table, &p, &r), CYL_ERR_ARG);
    assert_int_equal(cyl_subpixel_centroid(&f.seg, NULL, &f.img, &f.table, &p, &r), CYL_ERR_ARG);
    assert_int_equal(cyl_subpixel_centroid(&f.seg, b, NULL, &f.table, &p, &r), CYL_ERR_ARG);
    assert_int_equal(cyl_subpixel_centroid(&f.seg, b, &f.img, NULL, &p, &r), CYL_ERR_ARG);
    assert_int_equal(cyl_subpixel_centroid(&f.seg, b, &f.img, &f.table, NULL, &r), CYL_ERR_ARG);
    assert_int_equal(cyl_subpixel_centroid(&f.seg, b, &f.img, &f.table, &p, NULL), CYL_ERR_ARG);
    p.reach = 0;
    assert_int_equal(cyl_subpixel_centroid(&f.seg, b, &f.img, &f.table, &p, &r), CYL_ERR_ARG);
    p.reach = 1;   /* the sum of one side's sample alone says nothing */
    assert_int_equal(cyl_subpixel_centroid(&f.seg, b, &f.img, &f.table, &p, &r), CYL_ERR_ARG);
    p.reach = CYL_SUBPIXEL_MAX_REACH + 1;
    assert_int_equal(cyl_subpixel_centroid(&f.seg, b, &f.img, &f.table, &p, &r), CYL_ERR_ARG);
    p = cyl_subpixel_params_default();
    p.min_contrast = -1;
    assert_int_equal(cyl_subpixel_centroid(&f.seg, b, &f.img, &f.table, &p, &r), CYL_ERR_ARG);
    p.min_contrast = NAN;
    assert_int_equal(cyl_subpixel_centroid(&f.seg, b, &f.img, &f.table, &p, &r), CYL_ERR_ARG);
    p = cyl_subpixel_params_default();
    {   /* an image of another size than the segmentation's */
        cyl_image small;
        assert_int_equal(cyl_image_wrap(&small, CYL_FMT_YUV444P, W / 2, H / 2, f.frame, 0), CYL_OK);
        assert_int_equal(cyl_subpixel_centroid(&f.seg, b, &small, &f.table, &p, &r), CYL_ERR_ARG);
    }
    {   /* a run chain that claims fewer runs than it has, or points past the runs */
        cyl_blob bad = *b;
        bad.n_runs = 3;
        assert_int_equal(cyl_subpixel_centroid(&f.seg, &bad, &f.img, &f.table, &p, &r), CYL_ERR_ARG);
        bad = *b;
        bad.first_run = f.seg.n_runs + 5;
        assert_int_equal(cyl_subpixel_centroid(&f.seg, &bad, &f.img, &f.table, &p, &r), CYL_ERR_ARG);
    }
    {   /* a blob without runs */
        cyl_blob empty = *b;
        empty.n_runs = 0;
        assert_int_equal(cyl_subpixel_centroid(&f.seg, &empty, &f.img, &f.table, &p, &r), CYL_ERR_EMPTY);
    }
    free(f.mem);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_shaded_rectangle_centred),
        cmocka_unit_test(test_noisy_frames_unbiased),
        cmocka_unit_test(test_sharp_edge_keeps_centroid),
        cmocka_unit_test(test_subsampled_grid),
        cmocka_unit_test(test_gaps_left_alone),
        cmocka_unit_test(test_low_contrast_left_alone),
        cmocka_unit_test(test_bad_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
