/* SPDX-License-Identifier: BSD-3-Clause */
/* Centroid variance estimators (paper eqs. 4-6): hand-computed small blobs, and all three
 * estimators against a brute-force evaluation on a pixel grid over thousands of random blobs. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <string.h>
#include <math.h>
#include <cmocka.h>

#include "cyl/noise.h"
#include "rng.h"

#define MAXR 4096

typedef struct hand_seg {
    cyl_run runs[MAXR];
    cyl_blob blob[4];
    cyl_segmentation seg;
} hand_seg;

static void hs_init(hand_seg *h, uint16_t sx, uint16_t sy)
{
    memset(h, 0, sizeof *h);
    h->seg.runs = h->runs;
    h->seg.max_runs = MAXR;
    h->seg.blobs = h->blob;
    h->seg.max_blobs = 4;
    h->seg.x_step = sx;
    h->seg.y_step = sy;
    h->blob[0].first_run = CYL_NONE;
    h->blob[1].first_run = CYL_NONE;
}

/* append a run (image coords) to blob b; runs must be added in (y, x) order per blob */
static void hs_add(hand_seg *h, uint32_t b, uint16_t x, uint16_t y, uint16_t w)
{
    uint32_t i = h->seg.n_runs++, k;
    h->runs[i].x = x;
    h->runs[i].y = y;
    h->runs[i].width = w;
    h->runs[i].blob = b;
    h->runs[i].next = CYL_NONE;
    if (h->blob[b].first_run == CYL_NONE) {
        h->blob[b].first_run = i;
    } else {
        for (k = h->blob[b].first_run; h->runs[k].next != CYL_NONE; k = h->runs[k].next) {}
        h->runs[k].next = i;
    }
    h->blob[b].n_runs++;
    h->blob[b].area += w;
    if (h->seg.n_blobs <= b) h->seg.n_blobs = b + 1;
}

static void run_est(hand_seg *h, uint32_t b, cyl_noise_estimator e, cyl_centroid_noise *o)
{
    static int32_t work[70000];
    assert_int_equal(cyl_noise_blob(&h->seg, &h->blob[b], e, work, sizeof work, o), CYL_OK);
}

static hand_seg HS;

/* single pixel at (0,0): N = 1 on the 3x3 around it, weight (1/9)(8/9);
 * VAR = sum i^2 * 8/81 over 3 rows x i in {-1,0,1} = 6*8/81 = 48/81 */
static void test_single_pixel(void **st)
{
    cyl_centroid_noise o;
    (void)st;
    hs_init(&HS, 1, 1);
    hs_add(&HS, 0, 10, 20, 1);
    run_est(&HS, 0, CYL_NOISE_LOCAL, &o);
    assert_true(fabs(o.var_x_px2 - 48.0 / 81.0) < 1e-12);
    assert_true(fabs(o.var_y_px2 - 48.0 / 81.0) < 1e-12);
    assert_true(fabs(o.cx_px - 10.0) < 1e-12 && fabs(o.cy_px - 20.0) < 1e-12);
    run_est(&HS, 0, CYL_NOISE_UNIFORM, &o);   /* rho = 1 */
    assert_true(o.var_x_px2 == 0.0 && o.var_y_px2 == 0.0);
    run_est(&HS, 0, CYL_NOISE_COLUMN, &o);    /* n_i = h */
    assert_true(o.var_x_px2 == 0.0 && o.var_y_px2 == 0.0);
}

/* 1x2 horizontal pair, m_x = 0.5, n = 2; per window row N(i) = 1,2,2,1 at i = -1..2:
 * VAR_x = 3 [2.25*8 + 0.25*14 + 0.25*14 + 2.25*8] / 81 / 4 = 129/324
 * VAR_y = 2 rows (j = +-1) x (8+14+14+8)/81 / 4 = 22/81 */
static void test_pair(void **st)
{
    cyl_centroid_noise o;
    (void)st;
    hs_init(&HS, 1, 1);
    hs_add(&HS, 0, 0, 0, 2);
    run_est(&HS, 0, CYL_NOISE_LOCAL, &o);
    assert_true(fabs(o.var_x_px2 - 129.0 / 324.0) < 1e-12);
    assert_true(fabs(o.var_y_px2 - 22.0 / 81.0) < 1e-12);
    assert_true(fabs(o.cx_px - 0.5) < 1e-12);
}

/* L shape (0,0) (1,0) (0,1): n = 3, box 2x2, rho = 3/4, m = (1/3, 1/3).
 * uniform: VAR_x = 2 * ((1/3)^2 + (2/3)^2) / 9 * 3/16 = 30/1296
 * column:  n_0 = 2 = h contributes 0; n_1 = 1: (2/3)^2 * 1 * (1 - 1/2) / 9 = 2/81 */
static void test_L_shape(void **st)
{
    cyl_centroid_noise o;
    (void)st;
    hs_init(&HS, 1, 1);
    hs_add(&HS, 0, 0, 0, 2);
    hs_add(&HS, 0, 0, 1, 1);
    run_est(&HS, 0, CYL_NOISE_UNIFORM, &o);
    assert_true(fabs(o.var_x_px2 - 30.0 / 1296.0) < 1e-14);
    assert_true(fabs(o.var_y_px2 - 30.0 / 1296.0) < 1e-14);
    run_est(&HS, 0, CYL_NOISE_COLUMN, &o);
    assert_true(fabs(o.var_x_px2 - 2.0 / 81.0) < 1e-14);
    assert_true(fabs(o.var_y_px2 - 2.0 / 81.0) < 1e-14);
    /* the same shape sampled with x_step 2, y_step 3: grid variances scaled by step^2 */
    hs_init(&HS, 2, 3);
    hs_add(&HS, 0, 4, 9, 2);    /* columns 4, 6 */
    hs_add(&HS, 0, 4, 12, 1);
    run_est(&HS, 0, CYL_NOISE_COLUMN, &o);
    assert_true(fabs(o.var_x_px2 - 4.0 * 2.0 / 81.0) < 1e-14);
    assert_true(fabs(o.var_y_px2 - 9.0 * 2.0 / 81.0) < 1e-14);
    assert_true(fabs(o.cx_px - 14.0 / 3.0) < 1e-12);   /* (4 + 6 + 4) / 3 */
    assert_true(fabs(o.cy_px - 10.0) < 1e-12);         /* (9 + 9 + 12) / 3 */
}

/* ---- brute force --------------------------------------------------------- */
#define GW 200  /* wide blobs reach the estimator's event and generic paths (rows > 64 wide) */
#define GH 40
#define M 2   /* margin for the 3x3 windows */

static unsigned char grid[GH + 2 * M][GW + 2 * M];

static void brute(const hand_seg *h, uint32_t b, cyl_noise_estimator e, double *vx, double *vy,
                  double *cx, double *cy)
{
    uint32_t k;
    int i, j, di, dj, x0 = 1 << 30, x1 = -1, y0 = 1 << 30, y1 = -1;
    double n = 0, sx = 0, sy = 0, mx, my, ax = 0, ay = 0;
    int sxs = h->seg.x_step, sys = h->seg.y_step;
    memset(grid, 0, sizeof grid);
    for (k = h->blob[b].first_run; k != CYL_NONE; k = h->runs[k].next) {
        int gx = h->runs[k].x / sxs, gy = h->runs[k].y / sys, w;
        assert_true(gx + h->runs[k].width - 1 < GW && gy < GH);   /* the generator stays on the grid */
        for (w = 0; w < h->runs[k].width; w++) grid[gy + M][gx + w + M] = 1;
    }
    for (j = 0; j < GH + 2 * M; j++)
        for (i = 0; i < GW + 2 * M; i++)
            if (grid[j][i]) {   /* (painting bounded the loops below to the box) */
                n++; sx += i; sy += j;
                if (i < x0) x0 = i;
                if (i > x1) x1 = i;
                if (j < y0) y0 = j;
                if (j > y1) y1 = j;
            }
    mx = sx / n;
    my = sy / n;
    *cx = (mx - M) * sxs;   /* grid index -> px (runs start at multiples of the step here) */
    *cy = (my - M) * sys;
    if (e == CYL_NOISE_LOCAL) {
        for (j = y0 - 1; j <= y1 + 1; j++)
            for (i = x0 - 1; i <= x1 + 1; i++) {
                int N = 0;
                double w;
                for (dj = -1; dj <= 1; dj++)
                    for (di = -1; di <= 1; di++) N += grid[j + dj][i + di];
                w = (N / 9.0) * (1.0 - N / 9.0);
                ax += (i - mx) * (i - mx) * w;
                ay += (j - my) * (j - my) * w;
            }
    } else if (e == CYL_NOISE_UNIFORM) {
        double H = y1 - y0 + 1, W = x1 - x0 + 1, rho = n / (H * W);
        for (i = x0; i <= x1; i++) ax += H * (i - mx) * (i - mx) * rho * (1 - rho);
        for (j = y0; j <= y1; j++) ay += W * (j - my) * (j - my) * rho * (1 - rho);
    } else {
        double H = y1 - y0 + 1, W = x1 - x0 + 1;
        for (i = x0; i <= x1; i++) {
            double ni = 0;
            for (j = 0; j < GH + 2 * M; j++) ni += grid[j][i];
            ax += (i - mx) * (i - mx) * ni * (1 - ni / H);
        }
        for (j = y0; j <= y1; j++) {
            double nj = 0;
            for (i = 0; i < GW + 2 * M; i++) nj += grid[j][i];
            ay += (j - my) * (j - my) * nj * (1 - nj / W);
        }
    }
    *vx = ax / (n * n) * sxs * sxs;
    *vy = ay / (n * n) * sys * sys;
}

/* random run set for blob b inside a box of the grid: rows with 0..4 disjoint runs */
static void random_blob(hand_seg *h, test_rng *r, uint32_t bi, int row_step_mode)
{
    int bw = (int)test_rng_int(r, 1, test_rng_int(r, 0, 2) == 0 ? GW : 48), bh = (int)test_rng_int(r, 1, GH);
    int ox = (int)test_rng_int(r, 0, GW - bw), oy = (int)test_rng_int(r, 0, GH - bh), y;
    int shape = (int)test_rng_int(r, 0, 4);
    if (shape == 4) {
        /* combs: many short runs per row (over 32 in three rows: the estimator's fallback path) */
        for (y = oy; y < oy + bh; y++) {
            int x = ox;
            if (row_step_mode && test_rng_int(r, 0, 5) == 0) continue;
            while (x < ox + bw) {
                int w = (int)test_rng_int(r, 1, 2);
                if (x + w > ox + bw) w = ox + bw - x;
                hs_add(h, bi, (uint16_t)(x * h->seg.x_step), (uint16_t)(y * h->seg.y_step), (uint16_t)w);
                x += w + 1;
            }
        }
        if (h->blob[bi].first_run == CYL_NONE)
            hs_add(h, bi, (uint16_t)(ox * h->seg.x_step), (uint16_t)(oy * h->seg.y_step), 1);
        return;
    }
    if (shape == 3) {
        /* one run per row, ends jittering by up to 2 samples: the estimator's fast path */
        int a = ox + bw / 3, b = ox + (2 * bw) / 3;
        for (y = oy; y < oy + bh; y++) {
            a += (int)test_rng_int(r, -2, 2);
            b += (int)test_rng_int(r, -2, 2);
            if (a < ox) a = ox;
            if (a > ox + bw - 1) a = ox + bw - 1;
            if (b > ox + bw - 1) b = ox + bw - 1;
            if (b < a) b = a;
            if (row_step_mode && test_rng_int(r, 0, 9) == 0) continue;
            hs_add(h, bi, (uint16_t)(a * h->seg.x_step), (uint16_t)(y * h->seg.y_step),
                   (uint16_t)(b - a + 1));
        }
        if (h->blob[bi].first_run == CYL_NONE)
            hs_add(h, bi, (uint16_t)(ox * h->seg.x_step), (uint16_t)(oy * h->seg.y_step), 1);
        return;
    }
    for (y = oy; y < oy + bh; y++) {
        int x = ox, nr = 0;
        if (row_step_mode && test_rng_int(r, 0, 5) == 0) continue; /* gap rows */
        while (x < ox + bw && nr < 5) {
            int gap = shape == 0 ? (int)test_rng_int(r, 0, 3) : (int)test_rng_int(r, 0, bw / 2 + 1);
            int w;
            x += (nr == 0 && shape == 2) ? 0 : gap;
            if (x >= ox + bw) break;
            w = (int)test_rng_int(r, 1, ox + bw - x);
            if (shape == 2 && nr == 0) w = ox + bw - x; /* solid-ish rows */
            hs_add(h, bi, (uint16_t)(x * h->seg.x_step), (uint16_t)(y * h->seg.y_step), (uint16_t)w);
            x += w + 1;
            nr++;
        }
    }
    if (h->blob[bi].first_run == CYL_NONE)
        hs_add(h, bi, (uint16_t)(ox * h->seg.x_step), (uint16_t)(oy * h->seg.y_step), 1);
}

static void check_blob(hand_seg *h, uint32_t b, double *maxrel)
{
    int e;
    for (e = 0; e < 3; e++) {
        cyl_centroid_noise o;
        double vx, vy, cx, cy, ex, ey;
        run_est(h, b, (cyl_noise_estimator)e, &o);
        brute(h, b, (cyl_noise_estimator)e, &vx, &vy, &cx, &cy);
        ex = fabs(o.var_x_px2 - vx) / (fabs(vx) + 1e-300);
        ey = fabs(o.var_y_px2 - vy) / (fabs(vy) + 1e-300);
        if (vx == 0.0) ex = fabs(o.var_x_px2) > 1e-15;
        if (vy == 0.0) ey = fabs(o.var_y_px2) > 1e-15;
        if (ex > 1e-9 || ey > 1e-9)
            print_message("estimator %d: ours (%.17g, %.17g) brute (%.17g, %.17g) n=%u box %ux%u\n", e,
                          o.var_x_px2, o.var_y_px2, vx, vy, o.n, o.box_w, o.box_h);
        if (ex > *maxrel) *maxrel = ex;
        if (ey > *maxrel) *maxrel = ey;
        assert_true(ex < 1e-9);
        assert_true(ey < 1e-9);
        assert_true(fabs(o.cx_px - cx) < 1e-9 && fabs(o.cy_px - cy) < 1e-9);
    }
}

static void test_random_vs_brute_force(void **st)
{
    test_rng r;
    int t;
    double maxrel = 0.0;
    (void)st;
    test_rng_seed(&r, 0xC0FFEEu);
    for (t = 0; t < 4000; t++) {
        hs_init(&HS, (uint16_t)test_rng_int(&r, 1, 3), (uint16_t)test_rng_int(&r, 1, 3));
        random_blob(&HS, &r, 0, t & 1);
        check_blob(&HS, 0, &maxrel);
    }
    print_message("local/column/uniform vs brute force: 4000 random blobs x 3 estimators, "
                  "max relative error %.3g\n", maxrel);
}

/* two blobs whose runs interleave in the run array: each estimator sees only its own runs */
static void test_interleaved_blobs(void **st)
{
    test_rng r;
    int t;
    double maxrel = 0.0;
    (void)st;
    test_rng_seed(&r, 42u);
    for (t = 0; t < 1000; t++) {
        int y;
        hs_init(&HS, 1, 1);
        for (y = 0; y < GH; y++) {
            /* each row: alternate runs of blob 0 and 1, random widths, disjoint */
            int x = (int)test_rng_int(&r, 0, 3), k = (int)test_rng_int(&r, 0, 1);
            if (test_rng_int(&r, 0, 3) == 0) continue;
            while (x < GW - 1) {
                int w = (int)test_rng_int(&r, 1, 6);
                if (x + w > GW) w = GW - x;
                hs_add(&HS, (uint32_t)k, (uint16_t)x, (uint16_t)y, (uint16_t)w);
                x += w + (int)test_rng_int(&r, 0, 2);
                k ^= 1;
            }
        }
        if (HS.blob[0].first_run == CYL_NONE || HS.blob[1].first_run == CYL_NONE) continue;
        check_blob(&HS, 0, &maxrel);
        check_blob(&HS, 1, &maxrel);
    }
}

static void test_errors(void **st)
{
    cyl_centroid_noise o;
    int32_t small[2];
    (void)st;
    hs_init(&HS, 1, 1);
    hs_add(&HS, 0, 0, 0, 5);
    hs_add(&HS, 0, 0, 1, 5);
    assert_int_equal(cyl_noise_blob(&HS.seg, &HS.blob[0], CYL_NOISE_COLUMN, small, sizeof small, &o),
                     CYL_ERR_NOMEM);
    assert_int_equal(cyl_noise_blob(&HS.seg, &HS.blob[0], CYL_NOISE_LOCAL, NULL, 0, &o), CYL_OK);
    assert_int_equal(cyl_noise_blob(&HS.seg, &HS.blob[0], (cyl_noise_estimator)7, NULL, 0, &o),
                     CYL_ERR_ARG);
    assert_int_equal(cyl_noise_work_size(5), 6 * sizeof(int32_t));
    /* out-of-order list */
    HS.runs[0].y = 3;
    assert_int_equal(cyl_noise_blob(&HS.seg, &HS.blob[0], CYL_NOISE_LOCAL, NULL, 0, &o), CYL_ERR_ARG);
    /* cycle */
    HS.runs[0].y = 0;
    HS.runs[1].next = 0;
    assert_int_equal(cyl_noise_blob(&HS.seg, &HS.blob[0], CYL_NOISE_LOCAL, NULL, 0, &o), CYL_ERR_ARG);
    HS.blob[0].first_run = CYL_NONE;
    assert_int_equal(cyl_noise_blob(&HS.seg, &HS.blob[0], CYL_NOISE_LOCAL, NULL, 0, &o), CYL_ERR_EMPTY);
}

/* A large solid rectangle: only its border contributes, so the local estimator equals the
 * closed form of its four edges and four corners, and it runs in time ~ rows, not area. */
static void test_big_rectangle(void **st)
{
    static hand_seg big;
    cyl_centroid_noise o;
    int y, W = 4000, H = 3000;
    double n = (double)W * H, mx = (W - 1) / 2.0, vx = 0;
    (void)st;
    hs_init(&big, 1, 1);
    for (y = 0; y < H; y++) {
        big.runs[big.seg.n_runs].x = 1;
        big.runs[big.seg.n_runs].y = (uint16_t)(y + 1);
        big.runs[big.seg.n_runs].width = (uint16_t)W;
        big.runs[big.seg.n_runs].next = (y + 1 < H) ? big.seg.n_runs + 1 : CYL_NONE;
        big.seg.n_runs++;
        if (big.seg.n_runs == MAXR) break;
    }
    big.blob[0].first_run = 0;
    run_est(&big, 0, CYL_NOISE_LOCAL, &o);
    /* var_x by hand, grid columns relative to the box (0..W-1), rows 0..H-1:
     * columns -1 and W (outside): N = 3 on rows 1..H-2, 2 on rows 0 and H-1, 2 at rows -1/H? no:
     * corners (-1,-1): N = 1. Column -1: rows -1 and H -> N=1; rows 0, H-1 -> N=2; others N=3.
     * Column 0 (inside): rows -1, H -> N=2; rows 0, H-1 -> N=4; others N=6.
     * Columns 1..W-2: rows -1, H -> N=3; rows 0, H-1 -> N=6; others 9. Mirror for W-1, W. */
    {
        double w1 = 8.0 / 81, w2 = 14.0 / 81, w3 = 18.0 / 81, w4 = 20.0 / 81, w6 = 18.0 / 81;
        double e0 = (-1 - mx) * (-1 - mx), e1 = (0 - mx) * (0 - mx), s = 0;
        int i;
        double colout = 2 * w1 + 2 * w2 + (H - 2) * w3;
        double colin = 2 * w2 + 2 * w4 + (H - 2) * w6;
        for (i = 1; i <= W - 2; i++) s += (i - mx) * (i - mx);
        vx = 2 * (e0 * colout + e1 * colin) + s * (2 * w3 + 2 * w6);
        vx /= n * n;
    }
    assert_true(fabs(o.var_x_px2 - vx) < 1e-9 * vx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_single_pixel),
        cmocka_unit_test(test_pair),
        cmocka_unit_test(test_L_shape),
        cmocka_unit_test(test_random_vs_brute_force),
        cmocka_unit_test(test_interleaved_blobs),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_big_rectangle),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
