/* SPDX-License-Identifier: BSD-3-Clause */
/* The image centroid-variance estimator (cyl_noise_blob_image): a noise-free hard-edged blob has
 * zero variance; its noise estimate follows the noise put into the frame; and on a soft-edged disc
 * its predicted variance matches the variance of the centroid measured over hundreds of noisy
 * frames segmented again (Monte Carlo), where the shape-only estimator (eq. 6) is far off. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cyl/noise.h"
#include "cyl/segment.h"
#include "rng.h"

#define W 160
#define H 120
#define MAX_RUNS 4096
#define MAX_BLOBS 64

/* Background grey and landmark orange (Y, U, V); the class box puts its U and V thresholds
 * two thirds of the way to orange (a 4:2:2 pair half on the disc is not in the class). */
static const double kGrey[3] = {120, 128, 128};
static const double kOrange[3] = {150, 80, 190};

typedef struct fixture {
    cyl_colortable table;
    uint8_t frame[W * H * 2];
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
    cyl_colortable_add_box(&f->table, 0, 0, 255, 0, 96, 167, 255);
    f->mem = malloc(ms);
    assert_non_null(f->mem);
    assert_int_equal(cyl_segmentation_init(&f->seg, f->mem, ms, MAX_RUNS, MAX_BLOBS), CYL_OK);
    f->p = cyl_segment_params_default();
    for (k = 0; k < CYL_MAX_CLASSES; k++) { f->p.cls[k].min_area = 1; f->p.cls[k].merge_gap_px = -1; }
}

static uint8_t q8(double v) { return (uint8_t)(v < 0 ? 0 : v > 255 ? 255 : floor(v + 0.5)); }

/* A disc of radius r_px centred at (cx, cy) whose edge ramps linearly from orange to grey over
 * ramp_px (0: a hard edge), with Gaussian noise of std sigma (levels) on every Y, U and V sample. */
static void draw(fixture *f, double cx, double cy, double r_px, double ramp_px, double sigma, test_rng *rng)
{
    int x, y, c;
    for (y = 0; y < H; y++)
        for (x = 0; x < W; x += 2) {
            double px[2], val[3] = {0, 0, 0};
            for (c = 0; c < 2; c++) {
                double d = hypot(x + c - cx, y - cy), w;
                if (ramp_px > 0) w = (r_px - d) / ramp_px + 0.5;
                else w = d <= r_px ? 1 : 0;
                px[c] = w < 0 ? 0 : w > 1 ? 1 : w;
            }
            for (c = 0; c < 3; c++) val[c] = 0;
            f->frame[(size_t)y * W * 2 + (size_t)x * 2 + 0] =
                q8(kGrey[0] + px[0] * (kOrange[0] - kGrey[0]) + (rng ? sigma * test_rng_normal(rng) : 0));
            f->frame[(size_t)y * W * 2 + (size_t)x * 2 + 2] =
                q8(kGrey[0] + px[1] * (kOrange[0] - kGrey[0]) + (rng ? sigma * test_rng_normal(rng) : 0));
            for (c = 1; c < 3; c++) {  /* one chroma sample per pixel pair: the mean of the two */
                double m = 0.5 * (px[0] + px[1]);
                val[c] = kGrey[c] + m * (kOrange[c] - kGrey[c]) + (rng ? sigma * test_rng_normal(rng) : 0);
            }
            f->frame[(size_t)y * W * 2 + (size_t)x * 2 + 1] = q8(val[1]);
            f->frame[(size_t)y * W * 2 + (size_t)x * 2 + 3] = q8(val[2]);
        }
    assert_int_equal(cyl_image_wrap(&f->img, CYL_FMT_YUYV, W, H, f->frame, 0), CYL_OK);
}

/* Segments the frame; returns the largest blob of class 0 (NULL if none). */
static const cyl_blob *segment(fixture *f)
{
    assert_int_equal(cyl_segment(&f->table, &f->img, &f->p, &f->seg), CYL_OK);
    if (f->seg.class_count[0] == 0) return NULL;
    return &f->seg.blobs[f->seg.class_first[0]];
}

/* Noise-free frame, hard edge: every edge cell is 16 or more levels of U from the threshold, so no draw
 * of the floor noise (0.1 levels) flips it: the variance is exactly 0 and the centroid that of
 * the segmentation. */
static void test_noise_free_hard_edge_is_certain(void **state)
{
    fixture f;
    cyl_noise_image_params q;
    cyl_centroid_noise o, loc;
    static int32_t work[4096];
    const cyl_blob *b;
    (void)state;
    fx_open(&f);
    draw(&f, 80.3, 60.6, 20, 0, 0, NULL);
    b = segment(&f);
    assert_non_null(b);
    q = cyl_noise_image_params_default();
    assert_int_equal(cyl_noise_blob_image(&f.seg, b, &f.img, &f.table, &q, &o), CYL_OK);
    assert_int_equal(cyl_noise_blob(&f.seg, b, CYL_NOISE_LOCAL, work, sizeof work, &loc), CYL_OK);
    assert_true(o.var_x_px2 < 1e-20 && o.var_y_px2 < 1e-20);  /* 0 but for the moments' round-off */
    assert_true(fabs(o.cx_px - loc.cx_px) < 1e-9 && fabs(o.cy_px - loc.cy_px) < 1e-9);
    assert_int_equal(o.n, loc.n);
    assert_true(o.band_cells > 0);
    assert_true(o.sigma_y <= q.min_sigma + 1e-12 && o.sigma_u <= q.min_sigma + 1e-12);
    assert_true(loc.var_x_px2 > 1e-4);  /* eq. 6 sees the shape only: it is not 0 */
    free(f.mem);
}

/* The noise the estimator reads off the blob's interior follows the noise drawn into the frame
 * (within 15% for sigma 1.5 .. 6 levels; rounding adds 1/12 level^2). */
static void test_noise_estimate_follows_frame(void **state)
{
    static const double sig[] = {1.5, 3.0, 6.0};
    size_t i;
    (void)state;
    for (i = 0; i < sizeof sig / sizeof sig[0]; i++) {
        fixture f;
        test_rng rng;
        cyl_noise_image_params q;
        cyl_centroid_noise o;
        const cyl_blob *b;
        double expect = sqrt(sig[i] * sig[i] + 1.0 / 12.0);
        fx_open(&f);
        test_rng_seed(&rng, 11 + i);
        draw(&f, 80.0, 60.0, 30, 0, sig[i], &rng);
        b = segment(&f);
        assert_non_null(b);
        q = cyl_noise_image_params_default();
        assert_int_equal(cyl_noise_blob_image(&f.seg, b, &f.img, &f.table, &q, &o), CYL_OK);
        assert_true(fabs(o.sigma_y / expect - 1) < 0.15);
        assert_true(fabs(o.sigma_u / expect - 1) < 0.15);
        assert_true(fabs(o.sigma_v / expect - 1) < 0.15);
        /* given sigmas are used as they are */
        q.sigma_y = 2.0; q.sigma_u = 2.5; q.sigma_v = 3.0;
        assert_int_equal(cyl_noise_blob_image(&f.seg, b, &f.img, &f.table, &q, &o), CYL_OK);
        assert_true(o.sigma_y == 2.0 && o.sigma_u == 2.5 && o.sigma_v == 3.0);
        free(f.mem);
    }
}

/* Monte Carlo: a soft-edged disc (2 px ramp) with noise of 2, 4 and 8 levels, 300 frames each.
 * The variance of the segmented centroid over the frames against the mean of the estimate made
 * from each single frame: within 0.65 .. 1.65 (the sample variance of 300 frames alone scatters by
 * about 8%; measured x 1.09 .. 1.58, y 0.98 .. 1.11). Eq. 6, which does not see the noise, is
 * outside that range at two of the levels (9.6 and 4.8 in x). This disc is not the scene the
 * estimator was tuned on, and it is sharper than any rendered condition: its chroma crosses the
 * class boundary at 24 levels/px against a noise of 2, so which 4:2:2 pair flips depends on a
 * fraction of a level; the estimate (from each cell's mean over three cells along the curved edge)
 * puts flips on other pairs than the frames do, and in x, where a pair straddles the edge, it reads
 * high (the safe side). The upper bound was
 * 1.5 for the estimator's earlier form, which read y 0.71 .. 0.89 and x 0.95 .. 1.20 here and
 * 0.57 .. 1.10 on the rendered sweep (docs/uncertainty.md). */
static void test_monte_carlo_matches_resegmentation(void **state)
{
    static const double sig[] = {2.0, 4.0, 8.0};
    static int32_t work[4096];
    const int frames = 300;
    size_t i;
    int local_outside = 0, image_outside = 0;
    (void)state;
    for (i = 0; i < sizeof sig / sizeof sig[0]; i++) {
        fixture f;
        test_rng rng;
        cyl_noise_image_params q;
        double sx = 0, sy = 0, sxx = 0, syy = 0, ex = 0, ey = 0, lx = 0, ly = 0;
        double vx, vy, rx, ry;
        int k, n = 0;
        fx_open(&f);
        q = cyl_noise_image_params_default();
        test_rng_seed(&rng, 1000 + i);
        for (k = 0; k < frames; k++) {
            cyl_centroid_noise o, loc;
            const cyl_blob *b;
            draw(&f, 80.37, 60.21, 18, 2.0, sig[i], &rng);
            b = segment(&f);
            if (!b) continue;
            assert_int_equal(cyl_noise_blob_image(&f.seg, b, &f.img, &f.table, &q, &o), CYL_OK);
            assert_int_equal(cyl_noise_blob(&f.seg, b, CYL_NOISE_LOCAL, work, sizeof work, &loc), CYL_OK);
            sx += o.cx_px; sxx += o.cx_px * o.cx_px;
            sy += o.cy_px; syy += o.cy_px * o.cy_px;
            ex += o.var_x_px2; ey += o.var_y_px2;
            lx += loc.var_x_px2; ly += loc.var_y_px2;
            n++;
        }
        assert_true(n >= frames - 2);
        vx = (sxx - sx * sx / n) / (n - 1);
        vy = (syy - sy * sy / n) / (n - 1);
        rx = ex / n / vx;
        ry = ey / n / vy;
        print_message("  sigma %.0f: measured var %.5f %.5f px^2, image/measured %.2f %.2f, local/measured %.2f %.2f\n",
                      sig[i], vx, vy, rx, ry, lx / n / vx, ly / n / vy);
        if (!(rx > 0.65 && rx < 1.65 && ry > 0.65 && ry < 1.65)) image_outside++;
        if (!(lx / n / vx > 0.65 && lx / n / vx < 1.65)) local_outside++;
        free(f.mem);
    }
    assert_int_equal(image_outside, 0);
    assert_true(local_outside >= 2);
}

/* Soft edges: the disc with a 6 and a 12 px ramp, noise 2 and 4 levels, 300 frames each. There the
 * edge colours lie evenly across the class boundary, and the draws must give each simulated frame
 * the frame's whole noise around the cell's true colour: draws that add (1 - vf) sigma^2 to a mean
 * still holding vf sigma^2 of the noise read sqrt(1 - vf) of the variance (the estimator's earlier
 * form: mean ratio 0.85 over these eight figures, 0.74 .. 0.95); paired draws are unbiased
 * (measured 1.00, 0.86 .. 1.06). The mean over both axes and the four settings must lie within
 * 0.9 .. 1.15 (each figure scatters by about 8%, their mean by about 3%). */
static void test_soft_edges_are_unbiased(void **state)
{
    static const double ramp[] = {6.0, 12.0}, sig[] = {2.0, 4.0};
    const int frames = 300;
    double sum = 0.0;
    int figures = 0;
    size_t a, i;
    (void)state;
    for (a = 0; a < 2; a++)
        for (i = 0; i < 2; i++) {
            fixture f;
            test_rng rng;
            cyl_noise_image_params q;
            double sx = 0, sy = 0, sxx = 0, syy = 0, ex = 0, ey = 0, vx, vy;
            int k, n = 0;
            fx_open(&f);
            q = cyl_noise_image_params_default();
            test_rng_seed(&rng, 2000 + 10 * a + i);
            for (k = 0; k < frames; k++) {
                cyl_centroid_noise o;
                const cyl_blob *b;
                draw(&f, 80.37, 60.21, 18, ramp[a], sig[i], &rng);
                b = segment(&f);
                if (!b) continue;
                assert_int_equal(cyl_noise_blob_image(&f.seg, b, &f.img, &f.table, &q, &o), CYL_OK);
                sx += o.cx_px; sxx += o.cx_px * o.cx_px;
                sy += o.cy_px; syy += o.cy_px * o.cy_px;
                ex += o.var_x_px2; ey += o.var_y_px2;
                n++;
            }
            assert_true(n >= frames - 2);
            vx = (sxx - sx * sx / n) / (n - 1);
            vy = (syy - sy * sy / n) / (n - 1);
            print_message("  ramp %.0f px, sigma %.0f: image/measured %.2f %.2f\n", ramp[a], sig[i], ex / n / vx, ey / n / vy);
            sum += ex / n / vx + ey / n / vy;
            figures += 2;
            free(f.mem);
        }
    print_message("  mean %.3f\n", sum / figures);
    assert_true(sum / figures > 0.9 && sum / figures < 1.15);
}

static void test_bad_arguments(void **state)
{
    fixture f;
    cyl_noise_image_params q;
    cyl_centroid_noise o;
    const cyl_blob *b;
    (void)state;
    fx_open(&f);
    draw(&f, 80, 60, 20, 0, 0, NULL);
    b = segment(&f);
    assert_non_null(b);
    q = cyl_noise_image_params_default();
    assert_int_equal(cyl_noise_blob_image(NULL, b, &f.img, &f.table, &q, &o), CYL_ERR_ARG);
    assert_int_equal(cyl_noise_blob_image(&f.seg, NULL, &f.img, &f.table, &q, &o), CYL_ERR_ARG);
    assert_int_equal(cyl_noise_blob_image(&f.seg, b, NULL, &f.table, &q, &o), CYL_ERR_ARG);
    assert_int_equal(cyl_noise_blob_image(&f.seg, b, &f.img, NULL, &q, &o), CYL_ERR_ARG);
    assert_int_equal(cyl_noise_blob_image(&f.seg, b, &f.img, &f.table, NULL, &o), CYL_ERR_ARG);
    assert_int_equal(cyl_noise_blob_image(&f.seg, b, &f.img, &f.table, &q, NULL), CYL_ERR_ARG);
    q.band_px = 0;
    assert_int_equal(cyl_noise_blob_image(&f.seg, b, &f.img, &f.table, &q, &o), CYL_ERR_ARG);
    q = cyl_noise_image_params_default(); q.band_px = 5;
    assert_int_equal(cyl_noise_blob_image(&f.seg, b, &f.img, &f.table, &q, &o), CYL_ERR_ARG);
    q = cyl_noise_image_params_default(); q.draws = 1;
    assert_int_equal(cyl_noise_blob_image(&f.seg, b, &f.img, &f.table, &q, &o), CYL_ERR_ARG);
    q = cyl_noise_image_params_default(); q.draws = 65;
    assert_int_equal(cyl_noise_blob_image(&f.seg, b, &f.img, &f.table, &q, &o), CYL_ERR_ARG);
    q = cyl_noise_image_params_default(); q.sigma_y = -1;
    assert_int_equal(cyl_noise_blob_image(&f.seg, b, &f.img, &f.table, &q, &o), CYL_ERR_ARG);
    q = cyl_noise_image_params_default(); q.sigma_u = NAN;
    assert_int_equal(cyl_noise_blob_image(&f.seg, b, &f.img, &f.table, &q, &o), CYL_ERR_ARG);
    free(f.mem);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_noise_free_hard_edge_is_certain),
        cmocka_unit_test(test_noise_estimate_follows_frame),
        cmocka_unit_test(test_monte_carlo_matches_resegmentation),
        cmocka_unit_test(test_soft_edges_are_unbiased),
        cmocka_unit_test(test_bad_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
