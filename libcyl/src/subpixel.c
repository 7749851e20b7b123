/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- a blob's centroid with its edges placed sub-pixel (cyl/subpixel.h). */
#include "cyl/config.h"
#include "cyl/subpixel.h"
#include "internal.h"
#include "lowbit.h"

#include <math.h>
#include <string.h>

cyl_subpixel_params cyl_subpixel_params_default(void)
{
    cyl_subpixel_params p;
    memset(&p, 0, sizeof p);
    p.reach = 5u;
    p.min_contrast = 8.0;
    return p;
}

#if CYL_CONFIG_SUBPIXEL
typedef struct sp_ctx {
    const cyl_image *img;
    const cyl_colortable *t;
    cyl_grid g;                  /* the sampling grid */
    uint8_t cls;
    int32_t reach;
    double min_c2;               /* min_contrast^2 */
    /* the moments added by moving the edges, grid units */
    double m0, mx, my;
    uint32_t edges, moved;
} sp_ctx;

static void fetch(const sp_ctx *c, int32_t gx, int32_t gy, double col[3])
{
    uint8_t Y, U, V;
    cyl_pixel_fetch(c->img, (uint32_t)gx * c->g.sx + c->g.rx, (uint32_t)gy * c->g.sy + c->g.ry, &Y, &U, &V);
    col[0] = Y;
    col[1] = U;
    col[2] = V;
}

static int of_class(const sp_ctx *c, const double col[3])
{
    return cyl_lowbit[cyl_colortable_mask(c->t, (uint8_t)col[0], (uint8_t)col[1], (uint8_t)col[2])] == c->cls;
}

/* The edge between grid cell (gx, gy), of the blob, and its neighbour (gx - ix, gy - iy) outside it;
 * (ix, iy) is the unit step inwards. Cell p along the line (p = 0 the blob's cell, p = -1 the
 * outside neighbour) lies at (gx, gy) + p (ix, iy); the table's edge is at p = -1/2. Adds the slab
 * between the table's edge and the crossing to the moments. */
static void edge(sp_ctx *c, int32_t gx, int32_t gy, int32_t ix, int32_t iy)
{
    const int32_t R = c->reach;
    double cin[3], cout[3], d[3], dd, sum, delta;
    int32_t p, ox = gx - R * ix, oy = gy - R * iy, jx = gx + (R - 1) * ix, jy = gy + (R - 1) * iy;
    int k, gaps = 0;
    c->edges++;
    if (ox < c->g.gx_lo || ox > c->g.gx_hi || oy < c->g.gy_lo || oy > c->g.gy_hi || jx < c->g.gx_lo || jx > c->g.gx_hi ||
        jy < c->g.gy_lo || jy > c->g.gy_hi)
        return;
    fetch(c, jx, jy, cin);
    fetch(c, ox, oy, cout);
    if (!of_class(c, cin)) return;
    for (k = 0; k < 3; k++) d[k] = cin[k] - cout[k];
    dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    if (!(dd >= c->min_c2) || dd <= 0.0) return;
    /* The samples' sum: a blurred step at e (cells) sampled at p = -R .. R-1 sums to R - 1/2 - e
     * whatever the (symmetric) blur, so the edge moves outwards by sum - R from the table's edge
     * at -1/2 (0 for a sharp edge: R ones). Linear in the samples, so noise does not bias it, and
     * a 4:2:2 chroma pair inside the window adds the same as its two samples would. An outside
     * sample of the blob's class means this is not the blob's outer edge (a hole, a ragged end
     * with more of the blob beyond it); more than one inside sample not of the class means the
     * blob is thinner than the window there (the far inside sample is another part of it across
     * a gap): either way the edge is left alone. One is allowed: noise leaves single-sample
     * holes in a landmark. */
    sum = 1.0;                                   /* p = R - 1: the inside colour itself */
    for (p = -R; p <= R - 2; p++) {
        double col[3];
        if (p == -R) {
            col[0] = cout[0]; col[1] = cout[1]; col[2] = cout[2];
        } else {
            fetch(c, gx + p * ix, gy + p * iy, col);
        }
        if (p < 0 && of_class(c, col)) return;
        if (p >= 0 && !of_class(c, col) && ++gaps > 1) return;
        if (p > -R)
            sum += ((col[0] - cout[0]) * d[0] + (col[1] - cout[1]) * d[1] + (col[2] - cout[2]) * d[2]) / dd;
    }
    delta = sum - (double)R;
    if (delta > (double)R - 0.5) delta = (double)R - 0.5;
    if (delta < 0.5 - (double)R) delta = 0.5 - (double)R;
    c->moved++;
    c->m0 += delta;
    if (ix != 0) {
        const double edge_x = (double)gx - 0.5 * (double)ix;
        c->mx += delta * (edge_x - 0.5 * delta * (double)ix);
        c->my += delta * (double)gy;
    } else {
        const double edge_y = (double)gy - 0.5 * (double)iy;
        c->my += delta * (edge_y - 0.5 * delta * (double)iy);
        c->mx += delta * (double)gx;
    }
}

/* In the row whose runs start at list position *cur (a neighbouring row of the blob; CYL_NONE: not
 * in the blob), does a run reach into grid columns lo..hi? *cur moves past the runs that end before
 * lo, so calls with increasing lo walk the row once. */
static int row_has(const cyl_run *runs, uint32_t *cur, int32_t row, uint32_t sx, int32_t lo, int32_t hi)
{
    while (*cur != CYL_NONE && (int32_t)runs[*cur].y == row &&
           (int32_t)(runs[*cur].x / sx) + (int32_t)runs[*cur].width - 1 < lo)
        *cur = runs[*cur].next;
    return *cur != CYL_NONE && (int32_t)runs[*cur].y == row && (int32_t)(runs[*cur].x / sx) <= hi;
}

static uint32_t next_row(const cyl_run *runs, uint32_t i)
{
    const uint16_t y = runs[i].y;
    while (i != CYL_NONE && runs[i].y == y) i = runs[i].next;
    return i;
}

cyl_status cyl_subpixel_centroid(const cyl_segmentation *seg, const cyl_blob *b, const cyl_image *img,
                                 const cyl_colortable *t, const cyl_subpixel_params *p, cyl_subpixel_result *out)
{
    sp_ctx c;
    cyl_grid g;
    uint32_t row_first, prev_first = CYL_NONE, i;
    int32_t prev_row = INT32_MIN;
    double n = 0.0, sxm = 0.0, sym = 0.0, hx, hy, m0;
    cyl_status st;
    if (!seg || !b || !img || !t || !p || !out) return CYL_ERR_ARG;
    if (p->reach < 2u || p->reach > CYL_SUBPIXEL_MAX_REACH || !(p->min_contrast >= 0.0) || !isfinite(p->min_contrast))
        return CYL_ERR_ARG;
    st = cyl_image_check(img);
    if (st != CYL_OK) return st;
    if (b->cls >= CYL_MAX_CLASSES) return CYL_ERR_ARG;
    if (!cyl_grid_of(seg, img, &g)) return CYL_ERR_ARG;
    if (b->n_runs == 0 || b->first_run == CYL_NONE) return CYL_ERR_EMPTY;
    if (b->first_run >= seg->n_runs) return CYL_ERR_ARG;
    memset(&c, 0, sizeof c);
    c.img = img;
    c.t = t;
    c.g = g;
    c.cls = b->cls;
    c.reach = (int32_t)p->reach;
    c.min_c2 = p->min_contrast * p->min_contrast;

    /* the run chain, checked as cyl_noise_blob checks it: indices in range, rows in order, no
     * more runs than the blob says, no empty run */
    {
        uint32_t cnt = 0;
        int32_t last_y = -1;
        for (i = b->first_run; i != CYL_NONE; i = seg->runs[i].next) {
            if (i >= seg->n_runs || ++cnt > b->n_runs || seg->runs[i].width == 0 ||
                (int32_t)seg->runs[i].y < last_y)
                return CYL_ERR_ARG;
            last_y = (int32_t)seg->runs[i].y;
        }
    }
    for (row_first = b->first_run; row_first != CYL_NONE;) {
        const uint32_t nxt = next_row(seg->runs, row_first);
        const int32_t y = (int32_t)seg->runs[row_first].y, gy = y / (int32_t)c.g.sy;
        /* the rows above and below in the blob, when they are the neighbouring grid rows */
        const uint32_t above = (prev_first != CYL_NONE && prev_row == y - (int32_t)c.g.sy) ? prev_first : CYL_NONE;
        const uint32_t below = (nxt != CYL_NONE && (int32_t)seg->runs[nxt].y == y + (int32_t)c.g.sy) ? nxt : CYL_NONE;
        /* cursors into the rows above and below, for the runs' starts, their cells and their ends:
         * each is asked about columns that only grow along the row, so each walks the row once */
        uint32_t sa = above, sb = below, ua = above, ub = below, ea = above, eb = below;
        for (i = row_first; i != nxt; i = seg->runs[i].next) {
            const int32_t a = (int32_t)(seg->runs[i].x / c.g.sx), e = a + (int32_t)seg->runs[i].width - 1;
            int32_t gx;
            int ends_ok, ende_ok;
            n += (double)(e - a + 1);
            sxm += (double)(e - a + 1) * 0.5 * (double)(a + e);
            sym += (double)(e - a + 1) * (double)gy;
            /* A row's end whose row above (below) is outside the blob and has no blob sample
             * within reach of it is not on a side edge: it is where the blur of a top (bottom)
             * edge fades out of the class -- the top row of a landmark shaded on one side ends
             * half-way across -- and the top's own edges already place it. It is left out. */
            ends_ok = row_has(seg->runs, &sa, y - (int32_t)c.g.sy, c.g.sx, a - c.reach, a + c.reach) &&
                      row_has(seg->runs, &sb, y + (int32_t)c.g.sy, c.g.sx, a - c.reach, a + c.reach);
            if (ends_ok) edge(&c, a, gy, 1, 0);
            for (gx = a; gx <= e; gx++) {
                if (!row_has(seg->runs, &ua, y - (int32_t)c.g.sy, c.g.sx, gx, gx)) edge(&c, gx, gy, 0, 1);
                if (!row_has(seg->runs, &ub, y + (int32_t)c.g.sy, c.g.sx, gx, gx)) edge(&c, gx, gy, 0, -1);
            }
            ende_ok = row_has(seg->runs, &ea, y - (int32_t)c.g.sy, c.g.sx, e - c.reach, e + c.reach) &&
                      row_has(seg->runs, &eb, y + (int32_t)c.g.sy, c.g.sx, e - c.reach, e + c.reach);
            if (ende_ok) edge(&c, e, gy, -1, 0);
        }
        prev_first = row_first;
        prev_row = y;
        row_first = nxt;
    }
    if (n <= 0.0) return CYL_ERR_EMPTY;
    m0 = n + c.m0;
    if (!(m0 > 0.5 * n)) {   /* edges moved by more than half the blob: keep the blob's centroid */
        c.mx = c.my = c.m0 = 0.0;
        c.moved = 0;
        m0 = n;
    }
    hx = sxm / n;
    hy = sym / n;
    out->cx_px = b->cx_px + ((sxm + c.mx) / m0 - hx) * (double)c.g.sx;
    out->cy_px = b->cy_px + ((sym + c.my) / m0 - hy) * (double)c.g.sy;
    out->du_px = out->cx_px - b->cx_px;
    out->dv_px = out->cy_px - b->cy_px;
    out->area_px2 = m0 * (double)c.g.sx * (double)c.g.sy;
    out->edges = c.edges;
    out->edges_moved = c.moved;
    return CYL_OK;
}

#else /* CYL_CONFIG_SUBPIXEL */

cyl_status cyl_subpixel_centroid(const cyl_segmentation *seg, const cyl_blob *b, const cyl_image *img,
                                 const cyl_colortable *t, const cyl_subpixel_params *p, cyl_subpixel_result *out)
{
    (void)seg; (void)b; (void)img; (void)t; (void)p; (void)out;
    return CYL_ERR_UNSUPPORTED;
}
#endif
