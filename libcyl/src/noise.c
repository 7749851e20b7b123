/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- centroid variance estimators (paper eqs. 3-6). */
#include "cyl/noise.h"

#include <string.h>

#define NOISE_INF INT64_MAX

typedef struct noise_ctx {
    const cyl_run *runs;
    uint32_t sx, sy;          /* steps */
} noise_ctx;

/* grid coordinates (division skipped for the usual step 1) */
static int64_t gx0_of(const noise_ctx *c, uint32_t i)
{
    return c->sx == 1u ? (int64_t)c->runs[i].x : (int64_t)(c->runs[i].x / c->sx);
}
static int64_t gx1_of(const noise_ctx *c, uint32_t i) { return gx0_of(c, i) + (int64_t)c->runs[i].width - 1; }
static int64_t gy_of(const noise_ctx *c, uint32_t i)
{
    return c->sy == 1u ? (int64_t)c->runs[i].y : (int64_t)(c->runs[i].y / c->sy);
}

/* sum_{i=p}^{q} (i - m)^2, closed form */
static double sumsq(int64_t p, int64_t q, double m)
{
    double cnt = (double)(q - p + 1), mid = 0.5 * (double)(p + q) - m;
    return cnt * mid * mid + cnt * (cnt * cnt - 1.0) / 12.0;
}

size_t cyl_noise_work_size(uint32_t max_box_w)
{
    return ((size_t)max_box_w + 1u) * sizeof(int32_t);
}

size_t cyl_noise_work_size_seg(const cyl_segmentation *seg)
{
    uint32_t w;
    if (!seg || seg->x_step == 0 || seg->x_last < seg->x_origin) return cyl_noise_work_size(0);
    w = (seg->x_last - seg->x_origin) / seg->x_step + 1u;
    return cyl_noise_work_size(w);
}

/* first run of `row` at or after list position i with non-zero width, or CYL_NONE */
static uint32_t row_valid(const noise_ctx *c, uint32_t i, int64_t row)
{
    while (i != CYL_NONE && gy_of(c, i) == row && c->runs[i].width == 0) i = c->runs[i].next;
    if (i == CYL_NONE || gy_of(c, i) != row) return CYL_NONE;
    return i;
}

typedef struct row_stream {
    int64_t row;
    uint32_t e;   /* explicit-cell generator position */
    uint32_t q;   /* evaluation position */
} row_stream;

static uint32_t next_in_row(const noise_ctx *c, uint32_t i, int64_t row)
{
    return row_valid(c, c->runs[i].next, row);
}

/* smallest explicit cell >= cur of this row: cells within one sample of a run end */
static int64_t next_explicit(const noise_ctx *c, row_stream *s, int64_t cur)
{
    while (s->e != CYL_NONE) {
        int64_t a = gx0_of(c, s->e), b = gx1_of(c, s->e);
        if (cur <= a + 1) return cur > a - 1 ? cur : a - 1;
        if (cur <= b + 1) return cur > b - 1 ? cur : b - 1;
        s->e = next_in_row(c, s->e, s->row);
    }
    return NOISE_INF;
}

/* samples of this row in columns [i-1, i+1]; i must not decrease between calls */
static int64_t eval_row(const noise_ctx *c, row_stream *s, int64_t i)
{
    uint32_t t;
    int64_t n = 0;
    while (s->q != CYL_NONE && gx1_of(c, s->q) < i - 1) s->q = next_in_row(c, s->q, s->row);
    for (t = s->q; t != CYL_NONE; t = next_in_row(c, t, s->row)) {
        int64_t a = gx0_of(c, t), b = gx1_of(c, t), lo, hi;
        if (a > i + 1) break;
        lo = a > i - 1 ? a : i - 1;
        hi = b < i + 1 ? b : i + 1;
        if (hi >= lo) n += hi - lo + 1;
    }
    return n;
}

/* One sampled row of the blob as seen by the sweep. */
typedef struct row_info {
    uint32_t start;   /* first run of the row, CYL_NONE if the row is empty */
    uint32_t n;       /* runs in the row */
    int64_t a, b;     /* first run's first and last grid column */
} row_info;

/* Moments of the eq. 6 weights W = N (9 - N) over the cells of one row, in columns relative to
 * an origin: w = sum W, w1 = sum W i', w2 = sum W i'^2 (so sum W (i - m)^2 = w2 - 2 m' w1 +
 * m'^2 w). Exact in 64-bit integers (|i'| < 2^17, W <= 20). */
typedef struct wacc {
    int64_t w, w1, w2;
} wacc;

static void acc_cell(wacc *a, int64_t W, int64_t i)
{
    a->w += W;
    a->w1 += W * i;
    a->w2 += W * i * i;
}

/* sum of i^2 for i = 0..n (any integer n: the polynomial identity holds for negatives too) */
static int64_t sq_prefix(int64_t n) { return n * (n + 1) * (2 * n + 1) / 6; }

static void acc_stretch(wacc *a, int64_t W, int64_t p, int64_t q)
{
    int64_t cnt = q - p + 1;
    a->w += W * cnt;
    a->w1 += W * ((p + q) * cnt / 2);
    a->w2 += W * (sq_prefix(q) - sq_prefix(p - 1));
}

static int64_t clamp03(int64_t v) { return v < 0 ? 0 : (v > 3 ? 3 : v); }

/* Generic row (any number of runs): merge the runs of the three rows, evaluate N near run
 * ends, close-form the stretches between. Columns relative to ox. */
static void row_generic(const noise_ctx *c, const row_info ri[3], int64_t r, int64_t ox, wacc *acc)
{
    row_stream s[3];
    int64_t cur = NOISE_INF;
    int k;
    for (k = 0; k < 3; k++) {
        s[k].row = r - 1 + k;
        s[k].e = s[k].q = ri[k].start;
        if (s[k].e != CYL_NONE && ri[k].a - 1 < cur) cur = ri[k].a - 1;
    }
    for (;;) {
        int64_t nx = NOISE_INF, N;
        for (k = 0; k < 3; k++) {
            int64_t e = next_explicit(c, &s[k], cur);
            if (e < nx) nx = e;
        }
        if (nx == NOISE_INF) break;
        if (nx > cur) { /* N is constant on [cur, nx - 1] */
            N = eval_row(c, &s[0], cur) + eval_row(c, &s[1], cur) + eval_row(c, &s[2], cur);
            if (N > 0 && N < 9) acc_stretch(acc, N * (9 - N), cur - ox, nx - 1 - ox);
        }
        N = eval_row(c, &s[0], nx) + eval_row(c, &s[1], nx) + eval_row(c, &s[2], nx);
        if (N > 0 && N < 9) acc_cell(acc, N * (9 - N), nx - ox);
        cur = nx + 1;
    }
}

/* Event sweep for a row whose three neighbour rows hold up to ROW_EVENT_RUNS runs in all.
 * N(i) (samples of the three rows in columns i-1..i+1) is a sum of trapezoids, one per run
 * [a, b]; its second difference is +1 at a-1, -1 at a+2, -1 at b, +1 at b+3. With the runs'
 * starts A and ends B sorted (3-way merges of the rows), these are four sorted event streams,
 * merged on the fly. Between event positions the first difference D is constant: D = 0 gives
 * a constant stretch (closed form), D != 0 a ramp of at most 9 cells. Returns 0 if there are
 * too many runs (the caller falls back to row_generic). */
#define ROW_EVENT_RUNS 32
static int row_events(const noise_ctx *c, const row_info ri[3], int64_t ox, wacc *acc)
{
    int64_t ra[ROW_EVENT_RUNS], rb[ROW_EVENT_RUNS], A[ROW_EVENT_RUNS + 1], B[ROW_EVENT_RUNS + 1];
    int off[4], i0[3], n = 0, k, h[4];
    int64_t N = 0, D = 0;
    static const int64_t shift[4] = {-1, 2, 0, 3};
    static const int delta[4] = {1, -1, -1, 1};
    if (ri[0].n + ri[1].n + ri[2].n > ROW_EVENT_RUNS) return 0;
    for (k = 0; k < 3; k++) {
        uint32_t t, j;
        off[k] = n;
        for (t = ri[k].start, j = 0; j < ri[k].n; t = c->runs[t].next, j++) {
            ra[n] = gx0_of(c, t);
            rb[n] = ra[n] + (int64_t)c->runs[t].width - 1;
            n++;
        }
    }
    off[3] = n;
    /* 3-way merges: starts into A, ends into B (each row's runs are sorted and disjoint) */
    for (k = 0; k < 3; k++) i0[k] = off[k];
    for (k = 0; k < n; k++) {
        int best = -1, q;
        for (q = 0; q < 3; q++)
            if (i0[q] < off[q + 1] && (best < 0 || ra[i0[q]] < ra[i0[best]])) best = q;
        if (best < 0) break; /* cannot happen: k < n runs remain */
        A[k] = ra[i0[best]++];
    }
    for (k = 0; k < 3; k++) i0[k] = off[k];
    for (k = 0; k < n; k++) {
        int best = -1, q;
        for (q = 0; q < 3; q++)
            if (i0[q] < off[q + 1] && (best < 0 || rb[i0[q]] < rb[i0[best]])) best = q;
        if (best < 0) break; /* cannot happen: k < n runs remain */
        B[k] = rb[i0[best]++];
    }
    A[n] = B[n] = NOISE_INF / 2; /* sentinels */
    h[0] = h[1] = h[2] = h[3] = 0;
    for (;;) {
        int64_t p, nx, end, i;
        int s4;
        p = A[h[0]] + shift[0];
        for (s4 = 1; s4 < 4; s4++) {
            int64_t v = (s4 < 2 ? A[h[s4]] : B[h[s4]]) + shift[s4];
            if (v < p) p = v;
        }
        if (p >= NOISE_INF / 4) break;
        for (s4 = 0; s4 < 4; s4++) {
            const int64_t *L = s4 < 2 ? A : B;
            while (L[h[s4]] + shift[s4] == p) { D += delta[s4]; h[s4]++; }
        }
        nx = A[h[0]] + shift[0];
        for (s4 = 1; s4 < 4; s4++) {
            int64_t v = (s4 < 2 ? A[h[s4]] : B[h[s4]]) + shift[s4];
            if (v < nx) nx = v;
        }
        end = nx >= NOISE_INF / 4 ? p : nx - 1; /* after the last event D = 0 and N = 0 */
        if (D == 0) {
            if (N > 0 && N < 9) acc_stretch(acc, N * (9 - N), p - ox, end - ox);
        } else {
            for (i = p; i <= end; i++) {
                N += D;
                if (N > 0 && N < 9) acc_cell(acc, N * (9 - N), i - ox);
            }
        }
    }
    return 1;
}

/* Dense evaluation for a row whose three neighbour rows span at most ROW_DENSE_SPAN columns
 * (bounded cost per row): the second differences of N (see row_events) in a small array, two
 * prefix sums, every cell of the span visited. Returns 0 if the span is wider. */
#define ROW_DENSE_SPAN 64
static int row_dense(const noise_ctx *c, const row_info ri[3], int64_t ox, wacc *acc)
{
    int32_t d2[ROW_DENSE_SPAN + 8];
    int64_t lo = NOISE_INF, hi = -NOISE_INF, i;
    int32_t D = 0, N = 0;
    int k, span;
    for (k = 0; k < 3; k++) {
        uint32_t t, j;
        if (ri[k].n == 0) continue;
        if (ri[k].a < lo) lo = ri[k].a;
        for (t = ri[k].start, j = 1; j < ri[k].n; t = c->runs[t].next, j++) {}
        if (gx1_of(c, t) > hi) hi = gx1_of(c, t);
    }
    if (hi - lo + 1 > ROW_DENSE_SPAN) return 0;
    span = (int)(hi - lo + 1) + 4;       /* cells lo-1 .. hi+2 (N = 0 from hi+2 on) */
    memset(d2, 0, sizeof(int32_t) * (size_t)(span + 2));
    for (k = 0; k < 3; k++) {
        uint32_t t, j;
        for (t = ri[k].start, j = 0; j < ri[k].n; t = c->runs[t].next, j++) {
            int64_t a = gx0_of(c, t) - lo + 1, b = a + (int64_t)c->runs[t].width - 1; /* index 0 = lo-1 */
            d2[a - 1] += 1;
            d2[a + 2] -= 1;
            d2[b] -= 1;
            d2[b + 3] += 1;
        }
    }
    {
        /* W = N (9 - N) is 0 for N = 0 and N = 9: no test (branch-free is faster here) */
        int64_t w = 0, w1 = 0, w2 = 0, x = lo - 1 - ox;
        for (i = 0; i < span; i++, x++) {
            int64_t W;
            D += d2[i];
            N += D;
            W = (int64_t)N * (9 - N);
            w += W;
            w1 += W * x;
            w2 += W * x * x;
        }
        acc->w += w;
        acc->w1 += w1;
        acc->w2 += w2;
    }
    return 1;
}

/* Single pass for the local estimator: reads each run once (validating order and overlap),
 * accumulating the centroid, and slides a window of three rows down the list. Fast path when
 * each of the three rows has at most one run and the runs' left ends and right ends are at
 * least 3 samples apart: N is evaluated only in the left zone [min a - 1, max a + 1] and the
 * right zone [min b - 1, max b + 1]; between them N = 3 x (rows present) exactly. */
typedef struct local_state {
    const cyl_segmentation *seg;
    noise_ctx c;
    uint32_t scan;
    int64_t ox, oy;              /* origin: first run's grid column and row */
    int64_t n;                   /* samples */
    int64_t sgx, sgy;            /* sums of relative grid columns and rows */
    int64_t gx0, gx1;            /* column extent */
    int64_t scan_gy;             /* grid row of the run at scan (valid when scan != CYL_NONE) */
    int bad;                     /* invalid run list seen */
} local_state;

/* load the runs of `row` at the scan position into ri (validating them) */
static inline void local_load_row(local_state *st, int64_t row, row_info *ri)
{
    const noise_ctx *c = &st->c;
    int64_t prev_b = -NOISE_INF;
    ri->start = CYL_NONE;
    ri->n = 0;
    ri->a = ri->b = 0;
    while (st->scan != CYL_NONE) {
        uint32_t i = st->scan;
        int64_t gy = st->scan_gy, a, b, w;
        if (gy > row) return;
        /* (a cycle in the list necessarily breaks the strict (y, x) order checked here) */
        a = gx0_of(c, i);
        b = a + (int64_t)c->runs[i].width - 1;
        if (gy < row || c->runs[i].width == 0 || a <= prev_b) { st->bad = 1; st->scan = CYL_NONE; return; }
        prev_b = b;
        if (a < st->gx0) st->gx0 = a;
        if (b > st->gx1) st->gx1 = b;
        if (ri->n++ == 0) {
            ri->start = i;
            ri->a = a;
            ri->b = b;
        }
        w = (int64_t)c->runs[i].width;
        st->n += w;
        st->sgx += w * (a - st->ox) + w * (w - 1) / 2;
        st->sgy += w * (gy - st->oy);
        st->scan = c->runs[i].next;
        if (st->scan != CYL_NONE) {
            if (st->scan >= st->seg->n_runs) { st->bad = 1; st->scan = CYL_NONE; return; }
            st->scan_gy = gy_of(c, st->scan);
        }
    }
}

static cyl_status local_estimator(const cyl_segmentation *seg, const noise_ctx *c, uint32_t first,
                                  cyl_centroid_noise *out)
{
    local_state st;
    row_info ri[3];
    /* exact 64-bit totals: |i'|, |dy| <= CYL_MAX_DIM + 2 bound them below 2^63 */
    int64_t ax_w = 0, ax_w1 = 0, ax_w2 = 0, ay_w1 = 0, ay_w2 = 0;
    int64_t r, ox, gy1;
    double mx, my, n2;
    if (first == CYL_NONE) return CYL_ERR_EMPTY;
    if (first >= seg->n_runs) return CYL_ERR_ARG;
    memset(&st, 0, sizeof st);
    st.seg = seg;
    st.c = *c;
    st.scan = first;
    st.scan_gy = gy_of(c, first);
    st.ox = ox = gx0_of(c, first);
    st.gx0 = NOISE_INF;
    st.gx1 = -NOISE_INF;
    st.oy = gy_of(c, first);
    ri[0].start = ri[1].start = CYL_NONE;
    ri[0].n = ri[1].n = 0;
    ri[0].a = ri[0].b = ri[1].a = ri[1].b = 0;
    local_load_row(&st, st.oy, &ri[2]);
    gy1 = st.oy;
    r = st.oy - 1;
    while (ri[0].n + ri[1].n + ri[2].n != 0 || st.scan != CYL_NONE) {
        wacc row = {0, 0, 0};
        if (st.bad) return CYL_ERR_ARG;
        if (ri[2].n) gy1 = r + 1;
        if (ri[0].n == 1 && ri[1].n == 1 && ri[2].n == 1 && ri[0].a == ri[1].a &&
            ri[1].a == ri[2].a && ri[0].b == ri[1].b && ri[1].b == ri[2].b &&
            ri[1].b >= ri[1].a + 3) {
            /* Three identical runs (the inside of a landmark): N = 3, 6 at a-1, a and 6, 3 at b,
             * b+1, W = 18 each. Every following row whose run is the same again is the same case:
             * count such rows K and add them in closed form. */
            int64_t a = ri[1].a, b = ri[1].b, a0 = a - ox, b0 = b - ox, K = 1, dy0 = r - st.oy;
            row_info nxt;
            for (;;) {
                /* fast peek: is row r+2 exactly one run [a, b]? (anything else: full load) */
                uint32_t i = st.scan, nx;
                if (i != CYL_NONE && st.scan_gy == r + 2 && gx0_of(c, i) == a &&
                    (int64_t)seg->runs[i].width == b - a + 1) {
                    nx = seg->runs[i].next;
                    if (nx == CYL_NONE || (nx < seg->n_runs && gy_of(c, nx) > r + 2)) {
                        int64_t w = b - a + 1;
                        st.n += w;
                        st.sgx += w * a0 + w * (w - 1) / 2;
                        st.sgy += w * (r + 2 - st.oy);
                        st.scan = nx;
                        if (nx != CYL_NONE) st.scan_gy = gy_of(c, nx);
                        ri[0] = ri[1];
                        ri[1] = ri[2];
                        ri[2].start = i;
                        r++;
                        gy1 = r + 1;
                        K++;
                        continue;
                    }
                }
                local_load_row(&st, r + 2, &nxt);
                if (st.bad) return CYL_ERR_ARG;
                ri[0] = ri[1];
                ri[1] = ri[2];
                ri[2] = nxt;
                r++;
                if (nxt.n) gy1 = r + 1;
                if (!(nxt.n == 1 && nxt.a == a && nxt.b == b)) break;
                K++;
            }
            ax_w += 72 * K;
            ax_w1 += K * 36 * (a0 + b0);
            ax_w2 += K * 18 * ((a0 - 1) * (a0 - 1) + a0 * a0 + b0 * b0 + (b0 + 1) * (b0 + 1));
            ay_w1 += 72 * (K * dy0 + K * (K - 1) / 2);
            ay_w2 += 72 * (sq_prefix(dy0 + K - 1) - sq_prefix(dy0 - 1));
            continue;
        }
        if (ri[0].n + ri[1].n + ri[2].n != 0) {
            if (ri[0].n <= 1 && ri[1].n <= 1 && ri[2].n <= 1) {
                int64_t minA = NOISE_INF, maxA = -NOISE_INF, minB = NOISE_INF, maxB = -NOISE_INF, i;
                int k, P = 0;
                for (k = 0; k < 3; k++) {
                    if (ri[k].n == 0) continue;
                    P++;
                    if (ri[k].a < minA) minA = ri[k].a;
                    if (ri[k].a > maxA) maxA = ri[k].a;
                    if (ri[k].b < minB) minB = ri[k].b;
                    if (ri[k].b > maxB) maxB = ri[k].b;
                }
                if (minB >= maxA + 3) {
                    {
                        for (i = minA - 1; i <= maxA + 1; i++) {
                            int64_t N = 0;
                            for (k = 0; k < 3; k++)
                                if (ri[k].n) N += clamp03(i - ri[k].a + 2);
                            acc_cell(&row, N * (9 - N), i - ox); /* W = 0 at N = 0, 9 */
                        }
                        for (i = minB - 1; i <= maxB + 1; i++) {
                            int64_t N = 0;
                            for (k = 0; k < 3; k++)
                                if (ri[k].n) N += clamp03(ri[k].b - i + 2);
                            acc_cell(&row, N * (9 - N), i - ox);
                        }
                        if (P < 3 && maxA + 2 <= minB - 2)
                            acc_stretch(&row, 3 * P * (9 - 3 * P), maxA + 2 - ox, minB - 2 - ox);
                    }
                } else if (!row_dense(&st.c, ri, ox, &row) && !row_events(&st.c, ri, ox, &row)) {
                    row_generic(&st.c, ri, r, ox, &row);
                }
            } else if (!row_dense(&st.c, ri, ox, &row) && !row_events(&st.c, ri, ox, &row)) {
                row_generic(&st.c, ri, r, ox, &row);
            }
            {
                int64_t dy = r - st.oy;
                ax_w += row.w;
                ax_w1 += row.w1;
                ax_w2 += row.w2;
                ay_w1 += row.w * dy;
                ay_w2 += row.w * dy * dy;
            }
        }
        ri[0] = ri[1];
        ri[1] = ri[2];
        local_load_row(&st, r + 2, &ri[2]);
        r++;
    }
    if (st.bad) return CYL_ERR_ARG;
    if (st.n == 0) return CYL_ERR_EMPTY;
    mx = (double)st.sgx / (double)st.n;
    my = (double)st.sgy / (double)st.n;
    n2 = 81.0 * (double)st.n * (double)st.n;
    out->n = (uint32_t)st.n;
    /* samples lie at image columns x_first + step * (grid column - ox): same for rows */
    out->cx_px = (double)seg->runs[first].x + (double)c->sx * mx;
    out->cy_px = (double)seg->runs[first].y + (double)c->sy * my;
    out->box_h = (uint32_t)(gy1 - st.oy + 1);
    out->box_w = (uint32_t)(st.gx1 - st.gx0 + 1);
    out->var_x_px2 = ((double)ax_w2 - 2.0 * mx * (double)ax_w1 + mx * mx * (double)ax_w) / n2 *
                     (double)c->sx * (double)c->sx;
    out->var_y_px2 = ((double)ay_w2 - 2.0 * my * (double)ay_w1 + my * my * (double)ax_w) / n2 *
                     (double)c->sy * (double)c->sy;
    return CYL_OK;
}

cyl_status cyl_noise_blob(const cyl_segmentation *seg, const cyl_blob *b, cyl_noise_estimator est,
                          void *work, size_t work_size, cyl_centroid_noise *out)
{
    noise_ctx c;
    uint32_t i, steps = 0;
    uint64_t n = 0;
    int64_t gx0 = NOISE_INF, gx1 = -NOISE_INF, gy0 = NOISE_INF, gy1 = -NOISE_INF;
    int64_t prev_y = -1, prev_b = -1;
    double sum_gx = 0.0, sum_gy = 0.0, sum_x = 0.0, sum_y = 0.0, mx, my, vx = 0.0, vy = 0.0, nn;
    uint32_t W, H;

    if (!seg || !b || !out || !seg->runs || seg->x_step == 0 || seg->y_step == 0) return CYL_ERR_ARG;
    if (est != CYL_NOISE_UNIFORM && est != CYL_NOISE_COLUMN && est != CYL_NOISE_LOCAL) return CYL_ERR_ARG;
    memset(out, 0, sizeof *out);
    c.runs = seg->runs;
    c.sx = seg->x_step;
    c.sy = seg->y_step;

    if (est == CYL_NOISE_LOCAL) return local_estimator(seg, &c, b->first_run, out);

    /* pass 1: validate the list, count, box, centroid */
    for (i = b->first_run; i != CYL_NONE; i = seg->runs[i].next) {
        const cyl_run *r;
        int64_t a, e, gy;
        double w;
        if (i >= seg->n_runs || ++steps > seg->n_runs) return CYL_ERR_ARG;
        r = &seg->runs[i];
        if (r->width == 0) return CYL_ERR_ARG;
        a = gx0_of(&c, i);
        e = gx1_of(&c, i);
        gy = gy_of(&c, i);
        if (gy < prev_y || (gy == prev_y && a <= prev_b)) return CYL_ERR_ARG; /* order / overlap */
        prev_y = gy;
        prev_b = e;
        w = (double)r->width;
        n += r->width;
        sum_gx += w * (double)a + w * (w - 1.0) / 2.0;
        sum_gy += w * (double)gy;
        sum_x += w * (double)r->x + (double)c.sx * w * (w - 1.0) / 2.0;
        sum_y += w * (double)r->y;
        if (a < gx0) gx0 = a;
        if (e > gx1) gx1 = e;
        if (gy < gy0) gy0 = gy;
        if (gy > gy1) gy1 = gy;
    }
    if (n == 0) return CYL_ERR_EMPTY;
    nn = (double)n;
    mx = sum_gx / nn;
    my = sum_gy / nn;
    W = (uint32_t)(gx1 - gx0 + 1);
    H = (uint32_t)(gy1 - gy0 + 1);
    out->n = (uint32_t)n;
    out->box_w = W;
    out->box_h = H;
    out->cx_px = sum_x / nn;
    out->cy_px = sum_y / nn;

    if (est == CYL_NOISE_UNIFORM) {
        double rho = nn / ((double)W * (double)H), q = rho * (1.0 - rho);
        vx = (double)H * q * sumsq(gx0, gx1, mx);
        vy = (double)W * q * sumsq(gy0, gy1, my);
    } else if (est == CYL_NOISE_COLUMN) {
        int32_t *cnt = (int32_t *)work;
        int32_t run = 0;
        int64_t row = NOISE_INF;
        double nrow = 0.0;
        uint32_t k;
        if (!work || work_size < cyl_noise_work_size(W)) return CYL_ERR_NOMEM;
        memset(cnt, 0, ((size_t)W + 1u) * sizeof *cnt);
        for (i = b->first_run; i != CYL_NONE; i = seg->runs[i].next) {
            int64_t gy;
            if (seg->runs[i].width == 0) continue;
            cnt[gx0_of(&c, i) - gx0]++;
            cnt[gx1_of(&c, i) - gx0 + 1]--;
            gy = gy_of(&c, i);
            if (gy != row) {
                if (row != NOISE_INF) {
                    double d = (double)row - my;
                    vy += d * d * nrow * (1.0 - nrow / (double)W);
                }
                row = gy;
                nrow = 0.0;
            }
            nrow += (double)seg->runs[i].width;
        }
        {
            double d = (double)row - my;
            vy += d * d * nrow * (1.0 - nrow / (double)W);
        }
        for (k = 0; k < W; k++) {
            double ni, d;
            run += cnt[k];
            ni = (double)run;
            d = (double)(gx0 + (int64_t)k) - mx;
            vx += d * d * ni * (1.0 - ni / (double)H);
        }
    }
    out->var_x_px2 = vx / (nn * nn) * (double)c.sx * (double)c.sx;
    out->var_y_px2 = vy / (nn * nn) * (double)c.sy * (double)c.sy;
    return CYL_OK;
}
