/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- centroid variance from the frame's own evidence (CYL_NOISE_IMAGE, cyl/noise.h). */
#include "cyl/config.h"
#include "cyl/noise.h"
#include "internal.h"
#include "lowbit.h"

#include <math.h>
#include <string.h>

cyl_noise_image_params cyl_noise_image_params_default(void)
{
    cyl_noise_image_params p;
    memset(&p, 0, sizeof p);
    p.fallback_sigma = 2.5;
    p.min_sigma = 0.1;
    p.band_px = 4u;
    p.draws = 32u;
    return p;
}

#if CYL_CONFIG_IMAGE_ESTIMATOR
#define IMG_MAX_IV 64      /* run intervals per row list */
#define IMG_MAX_BAND 4u
#define IMG_MAX_DRAWS 64u
#define IMG_WIN (2u * IMG_MAX_BAND + 1u)
#define IMG_HIST 160       /* |second difference| histogram bins; the last one collects the rest */
#define IMG_NOISE_PER_RUN 8u
#define IMG_NOISE_MIN_SAMPLES 8u

typedef struct iv {
    int32_t a, b;          /* first and last grid column, inclusive */
} iv;

typedef struct img_ctx {
    const cyl_run *runs;
    const cyl_image *img;
    const cyl_colortable *t;
    cyl_grid g;            /* the sampling grid */
    uint8_t cls;
    int sub_h, sub_v;      /* chroma subsampled horizontally / vertically */
    double sig[3];         /* Y, U, V noise std of the draws (the frame's, less 8-bit rounding), levels */
    double sig_frame[3];   /* Y, U, V noise std of the frame's samples (given or estimated), levels */
    uint32_t draws, band, min_run;
    int32_t merge_gap;     /* grid cells; < 0: no merging */
    int32_t bx0, bx1, by0, by1; /* the blob's box, grid cells */
    double v_int;          /* flip variance of an interior cell */
} img_ctx;


static int32_t gx_of(const img_ctx *c, uint32_t i) { return (int32_t)(c->runs[i].x / c->g.sx); }
static int32_t gy_of(const img_ctx *c, uint32_t i) { return (int32_t)(c->runs[i].y / c->g.sy); }

static uint32_t mix32(uint32_t h)
{
    h ^= h >> 16;
    h *= 0x7feb352dU;
    h ^= h >> 15;
    h *= 0x846ca68bU;
    h ^= h >> 16;
    return h;
}

static uint32_t key3(uint32_t a, uint32_t b, uint32_t c)
{
    return mix32(a * 0x9E3779B1U + mix32(b * 0x85EBCA77U + mix32(c + 0x27D4EB2FU)));
}

/* An approximately standard normal number from 32 hash bits: the sum of four uniform bytes
 * (Irwin-Hall), centred and scaled to unit variance (range +-3.46). */
static double gauss_of(uint32_t h)
{
    uint32_t s = (h & 0xFFu) + ((h >> 8) & 0xFFu) + ((h >> 16) & 0xFFu) + (h >> 24);
    return ((double)s - 510.0) / 147.80;
}

static uint8_t clamp_level(double v)
{
    if (v <= 0.0) return 0;
    if (v >= 255.0) return 255;
    return (uint8_t)(v + 0.5);
}

static int in_grid(const img_ctx *c, int32_t gx, int32_t gy)
{
    return gx >= c->g.gx_lo && gx <= c->g.gx_hi && gy >= c->g.gy_lo && gy <= c->g.gy_hi;
}

/* The cell's mean colour, estimated from the frame: the average of the cell and its neighbours
 * along the edge (+-IMG_MEAN_HALF cells in the direction edge_direction() picks; a wider window
 * leaves more of the noise out of the mean but follows a curved edge worse, and at low noise a
 * mean a fraction of a level off puts the flips on the wrong cells).
 *
 * The draws come in pairs, a = mean + e_a and b = mean + e_b. The mean still carries the share vf
 * of the noise variance (1/3 for Y over three cells; more for chroma samples shared by the cells),
 * an error common to every draw of the cell. Noises with variance (1 - vf) sigma^2 each and
 * covariance -vf sigma^2 make a and b two independent frames around the cell's true colour, each
 * with the frame's noise sigma^2, and half the squared difference of two such frames' moments is an
 * unbiased variance however close the true colour is to the class boundary. (Independent draws of
 * variance (1 - vf) sigma^2 read sqrt(1 - vf) of it where edge colours lie evenly across the
 * boundary, and less near one sharp edge.) With e = sigma (p z1 +- q z2): p^2 = (1 - 2 vf) / 2,
 * q^2 = 1/2; vf above 1/2 (a chroma sample shared by two of the three cells) keeps p = 0. */
#define IMG_MEAN_HALF 1
typedef struct cell_mean {
    double y, u, v;        /* mean, levels */
    double py, pc;         /* the draws' p (above) for Y and chroma */
    uint32_t x, yy;        /* image coordinates */
} cell_mean;

/* The direction along the edge through a cell: of the four directions (horizontal, vertical and
 * the two diagonals), the one across +-2 cells of which the colour changes least (sum of |dY|,
 * |dU|, |dV|; a neighbour outside the grid is replaced by the cell). The cell's mean is averaged
 * along it; averaging across the edge would pull the mean toward the class boundary. */
static const int32_t kDir[4][2] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};

static int iabs(int a) { return a < 0 ? -a : a; }

static int edge_direction(const img_ctx *c, int32_t gx, int32_t gy)
{
    int best = 0, best_d = 0x7FFFFFFF, k, i;
    for (k = 0; k < 4; k++) {
        int v[2][3], d;
        for (i = 0; i < 2; i++) {
            int32_t s = i ? 2 : -2, qx = gx + s * kDir[k][0], qy = gy + s * kDir[k][1];
            uint8_t Y, U, V;
            if (!in_grid(c, qx, qy)) { qx = gx; qy = gy; }
            cyl_pixel_fetch(c->img, (uint32_t)qx * c->g.sx + c->g.rx, (uint32_t)qy * c->g.sy + c->g.ry, &Y, &U, &V);
            v[i][0] = Y; v[i][1] = U; v[i][2] = V;
        }
        d = iabs(v[1][0] - v[0][0]) + iabs(v[1][1] - v[0][1]) + iabs(v[1][2] - v[0][2]);
        if (d < best_d) { best_d = d; best = k; }
    }
    return best;
}

static void mean_of_cell(const img_ctx *c, int32_t gx, int32_t gy, int dir, cell_mean *m)
{
    int32_t d, cgx = gx;
    double sy = 0.0, su = 0.0, sv = 0.0, sw2 = 0.0;
    int n = 0, nc = 0, grp = 0;
    uint32_t last_key = 0xFFFFFFFFu;
    /* Chroma is averaged around the first cell of the cell's chroma sample (a 4:2:2 pair at full
     * resolution), so that cells sharing a chroma sample get the same chroma mean and flip together
     * in the draws, as they do in the frame. */
    if (c->sub_h && c->g.sx == 1u && (((uint32_t)gx * c->g.sx + c->g.rx) & 1u) && in_grid(c, gx - 1, gy)) cgx = gx - 1;
    for (d = -IMG_MEAN_HALF; d <= IMG_MEAN_HALF; d++) {
        int32_t qx = gx + d * kDir[dir][0], qy = gy + d * kDir[dir][1];
        uint8_t Y, U, V;
        if (!in_grid(c, qx, qy)) continue;
        cyl_pixel_fetch(c->img, (uint32_t)qx * c->g.sx + c->g.rx, (uint32_t)qy * c->g.sy + c->g.ry, &Y, &U, &V);
        sy += Y;
        n++;
    }
    for (d = -IMG_MEAN_HALF; d <= IMG_MEAN_HALF; d++) {
        int32_t qx = cgx + d * kDir[dir][0], qy = gy + d * kDir[dir][1];
        uint32_t x, y, key;
        uint8_t Y, U, V;
        if (!in_grid(c, qx, qy)) continue;
        x = (uint32_t)qx * c->g.sx + c->g.rx;
        y = (uint32_t)qy * c->g.sy + c->g.ry;
        cyl_pixel_fetch(c->img, x, y, &Y, &U, &V);
        su += U; sv += V;
        nc++;
        /* cells sharing a chroma sample are consecutive along any direction */
        key = ((c->sub_v ? y >> 1 : y) << 16) ^ (c->sub_h ? x >> 1 : x);
        if (key != last_key) {
            sw2 += (double)grp * (double)grp;
            grp = 0;
            last_key = key;
        }
        grp++;
    }
    sw2 += (double)grp * (double)grp;
    m->x = (uint32_t)gx * c->g.sx + c->g.rx;
    m->yy = (uint32_t)gy * c->g.sy + c->g.ry;
    {
        const double vfy = 1.0 / n, vfc = sw2 / ((double)nc * (double)nc);
        m->y = sy / n;
        m->u = su / nc;
        m->v = sv / nc;
        m->py = vfy < 0.5 ? sqrt(0.5 - vfy) : 0.0;
        m->pc = vfc < 0.5 ? sqrt(0.5 - vfc) : 0.0;
    }
}

/* Is the cell of class cls in the simulated frames 2j and 2j + 1, a pair (cell_mean): they share z1
 * and take z2 with opposite signs? Bit 0: frame 2j, bit 1: frame 2j + 1. */
static unsigned pair_in(const img_ctx *c, const cell_mean *m, uint32_t j)
{
    const double q = 0.70710678118654752;
    const uint32_t chx = c->sub_h ? m->x >> 1 : m->x, chy = c->sub_v ? m->yy >> 1 : m->yy;
    const uint32_t h1 = key3(chx, chy, j | 0x80000000u), h2 = key3(chx, chy, j | 0xC0000000u);
    const double y1 = m->py * gauss_of(key3(m->x, m->yy, j)), y2 = q * gauss_of(key3(m->x, m->yy, j | 0x40000000u));
    const double u1 = m->pc * gauss_of(h1), u2 = q * gauss_of(h2);
    const double v1 = m->pc * gauss_of(mix32(h1 ^ 0x5bd1e995u)), v2 = q * gauss_of(mix32(h2 ^ 0x5bd1e995u));
    unsigned r = 0, s;
    for (s = 0; s < 2u; s++) {
        const double sg = s ? -1.0 : 1.0;
        const uint8_t cy_ = clamp_level(m->y + c->sig[0] * (y1 + sg * y2));
        const uint8_t cu = clamp_level(m->u + c->sig[1] * (u1 + sg * u2));
        const uint8_t cv = clamp_level(m->v + c->sig[2] * (v1 + sg * v2));
        if (cyl_lowbit[cyl_colortable_mask(c->t, cy_, cu, cv)] == c->cls) r |= 1u << s;
    }
    return r;
}



/* The variance of a quantity from its values in the k simulated frames: half the mean squared
 * difference within the pairs (an odd last frame is not used). */
static double draw_variance(const double *v, uint32_t k)
{
    const uint32_t pairs = k >> 1;
    uint32_t j;
    double s = 0.0;
    for (j = 0; j + 1u < k; j += 2u) s += 0.5 * (v[j] - v[j + 1u]) * (v[j] - v[j + 1u]);
    return s / (double)pairs;
}

/* ---- noise from the blob's interior ---------------------------------------------------------- */

typedef struct noise_hist {
    uint32_t h[3][IMG_HIST];
} noise_hist;

static void hist_add(noise_hist *nh, int ch, int d)
{
    int a = d < 0 ? -d : d;
    nh->h[ch][a < IMG_HIST - 1 ? a : IMG_HIST - 1]++;
}

/* Variance of the samples from |second differences| (variance 6 sigma^2 for white noise), values
 * beyond max(3, 4 robust sigmas) dropped; returns -1 with too few samples. */
static double hist_sigma(const uint32_t *h)
{
    uint32_t n = 0, cum = 0, k, clip, cnt = 0;
    double med = 0.0, s2 = 0.0;
    for (k = 0; k < IMG_HIST; k++) n += h[k];
    if (n < IMG_NOISE_MIN_SAMPLES) return -1.0;
    for (k = 0; k < IMG_HIST; k++) {
        /* |d| = k stands for [k - 0.5, k + 0.5] (k = 0: [0, 0.5]): interpolate the median */
        double lo = k == 0 ? 0.0 : (double)k - 0.5, width = k == 0 ? 0.5 : 1.0;
        if (2u * (cum + h[k]) >= n) {
            med = lo + width * (0.5 * (double)n - (double)cum) / (double)(h[k] ? h[k] : 1u);
            break;
        }
        cum += h[k];
    }
    clip = (uint32_t)ceil(4.0 * med / 0.6745);
    if (clip < 3u) clip = 3u;
    if (clip > IMG_HIST - 2) clip = IMG_HIST - 2;
    for (k = 0; k <= clip; k++) {
        s2 += (double)k * (double)k * (double)h[k];
        cnt += h[k];
    }
    return sqrt(s2 / (double)cnt / 6.0);
}

/* The row spans of the blob (first run start .. last run end of each row, holes included: the
 * pixels of a hole belong to the same surface, and sampling only classified pixels would truncate
 * the noise at the table's boundary). Returns the next row's first run. */
static uint32_t row_span(const img_ctx *c, uint32_t i, int32_t *row, int32_t *a, int32_t *b)
{
    *row = gy_of(c, i);
    *a = gx_of(c, i);
    for (; i != CYL_NONE && gy_of(c, i) == *row; i = c->runs[i].next)
        *b = gx_of(c, i) + (int32_t)c->runs[i].width - 1;
    return i;
}

static void interior_noise(img_ctx *c, uint32_t first, const cyl_noise_image_params *p)
{
    noise_hist nh;
    uint32_t i;
    int ch;
    /* chroma neighbours must be other chroma samples */
    const int32_t cs = (c->sub_h && c->g.sx == 1u) ? 2 : 1;
    const int32_t margin = (int32_t)c->band + 1 + cs;
    memset(&nh, 0, sizeof nh);
    for (i = first; i != CYL_NONE;) {
        int32_t row, a, b, gx, stride;
        uint32_t x, y, j;
        i = row_span(c, i, &row, &a, &b);
        a += margin;
        b -= margin;
        if (b < a) continue;
        stride = (b - a) / (int32_t)IMG_NOISE_PER_RUN + 1;
        y = (uint32_t)row * c->g.sy + c->g.ry;
        for (gx = a, j = 0; gx <= b && j < IMG_NOISE_PER_RUN; gx += stride, j++) {
            uint8_t Y0, U0, V0, Ym, Um, Vm, Yp, Up, Vp, dummy;
            x = (uint32_t)gx * c->g.sx + c->g.rx;
            cyl_pixel_fetch(c->img, x, y, &Y0, &U0, &V0);
            cyl_pixel_fetch(c->img, x - c->g.sx, y, &Ym, &dummy, &dummy);
            cyl_pixel_fetch(c->img, x + c->g.sx, y, &Yp, &dummy, &dummy);
            hist_add(&nh, 0, (int)Ym - 2 * (int)Y0 + (int)Yp);
            cyl_pixel_fetch(c->img, x - (uint32_t)cs * c->g.sx, y, &dummy, &Um, &Vm);
            cyl_pixel_fetch(c->img, x + (uint32_t)cs * c->g.sx, y, &dummy, &Up, &Vp);
            hist_add(&nh, 1, (int)Um - 2 * (int)U0 + (int)Up);
            hist_add(&nh, 2, (int)Vm - 2 * (int)V0 + (int)Vp);
        }
    }
    for (ch = 0; ch < 3; ch++) {
        const double given = ch == 0 ? p->sigma_y : (ch == 1 ? p->sigma_u : p->sigma_v);
        double s = given > 0.0 ? given : hist_sigma(nh.h[ch]);
        if (s < 0.0) s = p->fallback_sigma;
        c->sig_frame[ch] = s < p->min_sigma ? p->min_sigma : s;
        /* The frame's values are rounded to levels once (variance 1/12, part of s^2); the draws
         * round again, so they get the noise without that share. */
        s = sqrt(s * s > 1.0 / 12.0 ? s * s - 1.0 / 12.0 : 0.0);
        if (s < p->min_sigma) s = p->min_sigma;
        c->sig[ch] = s;
    }
}

/* Flip variance of an interior cell, per cell: at the same places as the noise, the draws'
 * variance of the blob-cell count of the cell's chroma group (the two pixels of a 4:2:2 pair
 * flip together when chroma decides), divided by the group's size; the mean over the places. */
static void interior_flips(img_ctx *c, uint32_t first)
{
    uint32_t i, k, places = 0;
    double acc = 0.0;
    const int32_t margin = (int32_t)c->band + 3;
    const int32_t group = (c->sub_h && c->g.sx == 1u) ? 2 : 1;
    for (i = first; i != CYL_NONE;) {
        int32_t a, b, gx, stride, gy;
        uint32_t j;
        i = row_span(c, i, &gy, &a, &b);
        a += margin;
        b -= margin;
        if (b < a) continue;
        stride = (b - a) / (int32_t)IMG_NOISE_PER_RUN + 1;
        for (gx = a, j = 0; gx <= b && j < IMG_NOISE_PER_RUN; gx += stride, j++) {
            double cnt[IMG_MAX_DRAWS];
            cell_mean cm[2];
            int32_t g0 = group == 2 ? (int32_t)(((uint32_t)gx * c->g.sx + c->g.rx) & ~1u) - (int32_t)c->g.rx : gx;
            int q;
            for (q = 0; q < group; q++) mean_of_cell(c, g0 + q, gy, 0, &cm[q]);
            for (k = 0; k < c->draws; k++) cnt[k] = 0.0;
            for (k = 0; k + 1u < c->draws; k += 2u)
                for (q = 0; q < group; q++) {
                    const unsigned pr = pair_in(c, &cm[q], k >> 1);
                    cnt[k] += (double)(pr & 1u);
                    cnt[k + 1u] += (double)(pr >> 1);
                }
            acc += draw_variance(cnt, c->draws) / (double)group;
            places++;
        }
    }
    c->v_int = places ? acc / (double)places : 0.0;
}

/* ---- interval lists ---------------------------------------------------------------------------- */

/* Runs of grid row `row` starting at list position i (the row's first run), grown by g columns
 * on each side (g < 0 shrinks; empty results skipped), appended to out. Returns -1 on overflow. */
static int row_intervals(const img_ctx *c, uint32_t i, int32_t row, int32_t g, iv *out, int *n)
{
    for (; i != CYL_NONE && gy_of(c, i) == row; i = c->runs[i].next) {
        int32_t a = gx_of(c, i) - g, b = gx_of(c, i) + (int32_t)c->runs[i].width - 1 + g;
        if (b < a) continue;
        if (*n >= IMG_MAX_IV) return -1;
        out[*n].a = a;
        out[*n].b = b;
        (*n)++;
    }
    return 0;
}

/* sort by start (insertion: the lists are a few sorted rows concatenated) and merge overlapping
 * or adjacent intervals */
static int sort_merge(iv *v, int n)
{
    int i, j, m = 0;
    for (i = 1; i < n; i++) {
        iv x = v[i];
        for (j = i; j > 0 && v[j - 1].a > x.a; j--) v[j] = v[j - 1];
        v[j] = x;
    }
    for (i = 0; i < n; i++) {
        if (m > 0 && v[i].a <= v[m - 1].b + 1) {
            if (v[i].b > v[m - 1].b) v[m - 1].b = v[i].b;
        } else {
            v[m++] = v[i];
        }
    }
    return m;
}

/* a := a intersect b (both sorted, disjoint); returns the new length */
static int intersect(iv *a, int na, const iv *b, int nb, iv *tmp)
{
    int i = 0, j = 0, m = 0;
    while (i < na && j < nb) {
        int32_t lo = a[i].a > b[j].a ? a[i].a : b[j].a, hi = a[i].b < b[j].b ? a[i].b : b[j].b;
        if (lo <= hi) tmp[m++] = (iv){lo, hi};
        if (a[i].b < b[j].b) i++; else j++;
    }
    memcpy(a, tmp, sizeof(iv) * (size_t)m);
    return m;
}

/* ---- the estimator --------------------------------------------------------------------------- */

typedef struct row_lists {
    iv d[IMG_MAX_IV];      /* cells within band of a blob cell (dilation) */
    iv e[IMG_MAX_IV];      /* cells whose whole window is blob (erosion): certain */
    iv conn[IMG_MAX_IV];   /* blob runs of this and the neighbouring rows: a run touching them counts */
    iv own[IMG_MAX_IV];    /* blob runs of this row */
    iv row[IMG_MAX_IV];    /* one row's eroded runs */
    iv tmp[IMG_MAX_IV];
    int nd, ne, nconn, nown;
} row_lists;

/* first-run index of each grid row of the window, found by walking the list once */
typedef struct row_index {
    uint32_t lead;         /* next list position not yet indexed */
    uint32_t first[IMG_WIN];
    int32_t row_of[IMG_WIN];
} row_index;

static uint32_t row_first(const img_ctx *c, row_index *ri, int32_t row)
{
    uint32_t slot = (uint32_t)(row - c->g.gy_lo + (int32_t)IMG_WIN * 8192) % IMG_WIN;
    while (ri->lead != CYL_NONE && gy_of(c, ri->lead) <= row) {
        int32_t r = gy_of(c, ri->lead);
        uint32_t s = (uint32_t)(r - c->g.gy_lo + (int32_t)IMG_WIN * 8192) % IMG_WIN;
        ri->first[s] = ri->lead;
        ri->row_of[s] = r;
        while (ri->lead != CYL_NONE && gy_of(c, ri->lead) == r) ri->lead = c->runs[ri->lead].next;
    }
    return ri->row_of[slot] == row ? ri->first[slot] : CYL_NONE;
}

static int build_lists(const img_ctx *c, row_index *ri, int32_t row, row_lists *L)
{
    const int32_t R = (int32_t)c->band;
    int32_t r;
    int have_all = 1;
    L->nd = L->ne = L->nconn = L->nown = 0;
    for (r = row - R; r <= row + R; r++) {
        uint32_t f = row_first(c, ri, r);
        if (f == CYL_NONE) { have_all = 0; continue; }
        if (row_intervals(c, f, r, R, L->d, &L->nd) < 0) return -1;
        if (r >= row - 1 && r <= row + 1 && row_intervals(c, f, r, 0, L->conn, &L->nconn) < 0) return -1;
        if (r == row && row_intervals(c, f, r, 0, L->own, &L->nown) < 0) return -1;
    }
    L->nd = sort_merge(L->d, L->nd);
    L->nconn = sort_merge(L->conn, L->nconn);
    if (have_all) {
        for (r = row - R; r <= row + R; r++) {
            int n = 0;
            uint32_t f = row_first(c, ri, r);
            if (r == row - R) {
                if (row_intervals(c, f, r, -R, L->e, &L->ne) < 0) return -1;
            } else {
                if (row_intervals(c, f, r, -R, L->row, &n) < 0) return -1;
                L->ne = intersect(L->e, L->ne, L->row, n, L->tmp);
            }
        }
    }
    return 0;
}

static int overlaps(const iv *v, int n, int *cur, int32_t a, int32_t b)
{
    while (*cur < n && v[*cur].b < a) (*cur)++;
    return *cur < n && v[*cur].a <= b;
}

/* Per-draw run state of one row. */
typedef struct draw_state {
    int32_t start[IMG_MAX_DRAWS];
    int ic[IMG_MAX_DRAWS];     /* cursor into the connectivity list */
    uint8_t open[IMG_MAX_DRAWS];
} draw_state;

static void close_run(const img_ctx *c, const row_lists *L, draw_state *ds, uint32_t k, int32_t end,
                      int row_in_merge, double m_x, double wy, double *mx, double *my)
{
    int32_t len = end - ds->start[k] + 1;
    ds->open[k] = 0;
    if ((uint32_t)len >= c->min_run && (overlaps(L->conn, L->nconn, &ds->ic[k], ds->start[k], end) ||
                                        (c->merge_gap >= 0 && row_in_merge && ds->start[k] <= c->bx1 + c->merge_gap &&
                                         end >= c->bx0 - c->merge_gap))) {
        double cnt = (double)len, mid = 0.5 * ((double)ds->start[k] + (double)end);
        mx[k] += cnt * (mid - m_x);
        my[k] += cnt * wy;
    }
}

/* sum_{i=p}^{q} (i - m)^2 */
static double sumsq(int32_t p, int32_t q, double m)
{
    double cnt = (double)(q - p + 1), mid = 0.5 * ((double)p + (double)q) - m;
    return cnt * mid * mid + cnt * (cnt * cnt - 1.0) / 12.0;
}

/* Simulate row `row` in every draw: add the kept cells' moments to mx[k] (sum of gx - m_x) and
 * my[k] (their count times wy = row - m_y); add the interior cells' independent flips to
 * *vx, *vy. Returns the number of simulated (band) cells. */
static uint32_t simulate_row(const img_ctx *c, const row_lists *L, int32_t row, double m_x, double wy,
                             double *mx, double *my, double *vx, double *vy)
{
    draw_state ds;
    uint32_t k, band = 0;
    int i, ie = 0;
    const int row_in_merge = row >= c->by0 - c->merge_gap && row <= c->by1 + c->merge_gap;
    memset(&ds, 0, sizeof ds);
    for (i = 0; i < L->ne; i++) {
        *vx += c->v_int * sumsq(L->e[i].a, L->e[i].b, m_x);
        *vy += c->v_int * (double)(L->e[i].b - L->e[i].a + 1) * wy * wy;
    }
    for (i = 0; i < L->nd; i++) {
        int32_t x;
        for (x = L->d[i].a; x <= L->d[i].b + 1; x++) {
            int certain = 0, simulated = 0;
            unsigned pr = 0;      /* the current pair's two frames (pair_in) */
            cell_mean cm = {0.0, 0.0, 0.0, 0.0, 0.0, 0u, 0u};
            if (x <= L->d[i].b) {
                while (ie < L->ne && L->e[ie].b < x) ie++;
                certain = ie < L->ne && L->e[ie].a <= x;
                simulated = !certain && in_grid(c, x, row);
            }
            if (simulated) {
                band++;
                mean_of_cell(c, x, row, edge_direction(c, x, row), &cm);
            }
            for (k = 0; k < c->draws; k++) {
                int in;
                if (simulated && !(k & 1u)) pr = pair_in(c, &cm, k >> 1);
                in = certain || (simulated && ((pr >> (k & 1u)) & 1u));
                if (in && !ds.open[k]) { ds.open[k] = 1; ds.start[k] = x; }
                else if (!in && ds.open[k]) close_run(c, L, &ds, k, x - 1, row_in_merge, m_x, wy, mx, my);
            }
        }
    }
    return band;
}


cyl_status cyl_noise_blob_image(const cyl_segmentation *seg, const cyl_blob *b, const cyl_image *img,
                                const cyl_colortable *t, const cyl_noise_image_params *p,
                                cyl_centroid_noise *out)
{
    img_ctx c;
    cyl_grid g;
    row_index ri;
    row_lists L;
    double ux[IMG_MAX_DRAWS], uy[IMG_MAX_DRAWS];
    double m_x, m_y, acc_x = 0.0, acc_y = 0.0, n2;
    int32_t row, gy0, gy1;
    uint32_t i, k, unit = 0, band_cells = 0;
    int have_unit = 0;
    cyl_status st;
    if (!seg || !b || !img || !t || !p || !out) return CYL_ERR_ARG;
    if (p->band_px < 1u || p->band_px > IMG_MAX_BAND || p->draws < 2u || p->draws > IMG_MAX_DRAWS ||
        !(p->fallback_sigma >= 0.0) || !(p->min_sigma >= 0.0) ||
        !(p->sigma_y >= 0.0) || !(p->sigma_u >= 0.0) || !(p->sigma_v >= 0.0) ||
        !(p->fallback_sigma < 256.0) || !(p->sigma_y < 256.0) || !(p->sigma_u < 256.0) ||
        !(p->sigma_v < 256.0) || !(p->min_sigma < 256.0))
        return CYL_ERR_ARG;
    st = cyl_image_check(img);
    if (st != CYL_OK) return st;
    if (b->cls >= CYL_MAX_CLASSES) return CYL_ERR_ARG;
    if (!cyl_grid_of(seg, img, &g)) return CYL_ERR_ARG;
    /* validation, centroid, box and the fallback variance */
    st = cyl_noise_blob(seg, b, CYL_NOISE_LOCAL, NULL, 0, out);
    if (st != CYL_OK) return st;

    memset(&c, 0, sizeof c);
    c.runs = seg->runs;
    c.img = img;
    c.t = t;
    c.g = g;
    c.cls = b->cls;
    c.sub_h = img->format != CYL_FMT_YUV444P;
    c.sub_v = img->format == CYL_FMT_NV12 || img->format == CYL_FMT_I420;
    c.draws = p->draws;
    c.band = p->band_px;
    /* the segmentation's own run filter and this class's merging (a hand-made segmentation that
     * never went through cyl_segment has 0: every run kept) */
    c.min_run = seg->min_run_px ? seg->min_run_px : 1u;
    c.merge_gap = seg->merge_gap_px[b->cls] < 0 ? -1 : (int32_t)((uint32_t)seg->merge_gap_px[b->cls] / c.g.sx);
    c.bx0 = (int32_t)(b->x0 / c.g.sx);
    c.bx1 = (int32_t)(b->x1 / c.g.sx);
    c.by0 = (int32_t)(b->y0 / c.g.sy);
    c.by1 = (int32_t)(b->y1 / c.g.sy);
    interior_noise(&c, b->first_run, p);
    interior_flips(&c, b->first_run);
    out->sigma_y = c.sig_frame[0];
    out->sigma_u = c.sig_frame[1];
    out->sigma_v = c.sig_frame[2];

    /* centroid in grid units */
    m_x = ((out->cx_px - (double)c.g.rx) / (double)c.g.sx);
    m_y = ((out->cy_px - (double)c.g.ry) / (double)c.g.sy);
    gy0 = gy_of(&c, b->first_run);
    gy1 = gy0;
    for (i = b->first_run; i != CYL_NONE; i = c.runs[i].next) gy1 = gy_of(&c, i);

    memset(&ri, 0, sizeof ri);
    ri.lead = b->first_run;
    for (k = 0; k < IMG_WIN; k++) { ri.row_of[k] = INT32_MIN; ri.first[k] = CYL_NONE; }
    memset(ux, 0, sizeof ux);
    memset(uy, 0, sizeof uy);
    for (row = gy0 - (int32_t)c.band; row <= gy1 + (int32_t)c.band; row++) {
        uint32_t y_img, u;
        if (row < c.g.gy_lo || row > c.g.gy_hi) continue;
        if (build_lists(&c, &ri, row, &L) < 0) {
            /* too ragged for the bounded lists: keep the local estimate */
            out->band_cells = 0;
            return CYL_OK;
        }
        y_img = (uint32_t)row * c.g.sy + c.g.ry;
        u = c.sub_v ? y_img >> 1 : y_img;
        if (have_unit && u != unit) {
            acc_x += draw_variance(ux, c.draws);
            acc_y += draw_variance(uy, c.draws);
            memset(ux, 0, sizeof ux);
            memset(uy, 0, sizeof uy);
        }
        unit = u;
        have_unit = 1;
        band_cells += simulate_row(&c, &L, row, m_x, (double)row - m_y, ux, uy, &acc_x, &acc_y);
    }
    if (have_unit) {
        acc_x += draw_variance(ux, c.draws);
        acc_y += draw_variance(uy, c.draws);
    }
    n2 = (double)out->n * (double)out->n;
    out->var_x_px2 = acc_x / n2 * (double)c.g.sx * (double)c.g.sx;
    out->var_y_px2 = acc_y / n2 * (double)c.g.sy * (double)c.g.sy;
    out->band_cells = band_cells;
    return CYL_OK;
}

#else /* CYL_CONFIG_IMAGE_ESTIMATOR */

cyl_status cyl_noise_blob_image(const cyl_segmentation *seg, const cyl_blob *b, const cyl_image *img,
                                const cyl_colortable *t, const cyl_noise_image_params *p,
                                cyl_centroid_noise *out)
{
    (void)seg; (void)b; (void)img; (void)t; (void)p; (void)out;
    return CYL_ERR_UNSUPPORTED;
}
#endif
