/* SPDX-License-Identifier: BSD-3-Clause */
/* Run-length encoding, 4-connected union-find over runs, blob statistics,
 * merging and sorting. See cyl/segment.h for the contract.
 *
 * Design notes
 * - Classification and run-length encoding are fused: no class image is
 *   written. For the 4:2:2 and 4:2:0 formats with x_step 1, the chroma pair
 *   of two neighbouring pixels is looked up once; when it maps to no class
 *   and no run is open, both pixels are skipped without touching Y. Where a
 *   vector path exists (segment_vector.h: SSSE3, NEON), background is skipped
 *   16 pairs at a time on a coarse chroma map; pairs it cannot rule out go
 *   to the scalar code, so results are bit-identical to the scalar path.
 * - Runs are stored only for classified pixels (background is implicit).
 * - Union-find links the larger root to the smaller index, so every run's
 *   parent index is <= its own and a component's root is its first run in
 *   (y, x) order; labels therefore come out in raster order of first runs.
 */
#include "cyl/config.h"
#include "cyl/segment.h"
#include "internal.h"
#include "lowbit.h"
#include "segment_vector.h"

/* cells from one brightness level of the 3-D table to the next */
#define YUV_YSTRIDE (CYL_YUV_NC * CYL_YUV_NC)
#include <math.h>
#include <string.h>

/* a pixel format compiled in (cyl/config.h); a constant, so the other formats' code is dropped */
#define FORMAT_ON(f) ((CYL_CONFIG_FORMATS & CYL_FORMAT_BIT(f)) != 0u)

/* Per-blob accumulators (exact integer sums), in the caller's block. */
typedef struct blob_acc {
    int64_t n, sx, sy, sxx, syy, sxy;
    uint32_t last_run;   /* tail of the blob's run list */
    uint32_t alive;      /* 0 once merged into another blob or dropped */
    uint32_t strong;     /* 1 if some run is of the blob's own class (not a weak one) */
} blob_acc;

const char *cyl_segment_vector_path(void)
{
    return cyl_skip_select().name;
}

cyl_segment_params cyl_segment_params_default(void)
{
    cyl_segment_params p;
    unsigned i;
    memset(&p, 0, sizeof p);
    p.min_run_px = 3;
    p.x_step = 1;
    p.y_step = 1;
    for (i = 0; i < CYL_MAX_CLASSES; i++) {
        p.cls[i].min_area = 9;
        p.cls[i].merge_gap_px = 3;
        p.cls[i].merge_min_density = 0.5;
        p.cls[i].weak_alone_min_area = 0;
    }
    return p;
}

uint32_t cyl_segment_max_runs(uint32_t width, uint32_t height, const cyl_segment_params *p)
{
    uint32_t xs = 1, ys = 1, mr = 1, w = width, h = height;
    uint64_t n;
    if (p) {
        xs = p->x_step ? p->x_step : 1u;
        ys = p->y_step ? p->y_step : 1u;
        mr = p->min_run_px ? p->min_run_px : 1u;
        if (p->roi.width && p->roi.height) { w = p->roi.width; h = p->roi.height; }
    }
    n = (uint64_t)((w + xs - 1u) / xs / mr) * ((h + ys - 1u) / ys);
    return n > 0xFFFFFFFEull ? 0xFFFFFFFEu : (uint32_t)n;
}

#define ALIGN_UP(n, a) (((n) + ((a) - 1u)) & ~(size_t)((a) - 1u))

size_t cyl_segment_mem_size(uint32_t max_runs, uint32_t max_blobs)
{
    /* 64-bit arithmetic: the sum cannot wrap, and is checked against size_t (32-bit targets). */
    uint64_t runs = ((uint64_t)max_runs * sizeof(cyl_run) + 15u) & ~(uint64_t)15u;
    uint64_t blobs = ((uint64_t)max_blobs * sizeof(cyl_blob) + 15u) & ~(uint64_t)15u;
    uint64_t accs = ((uint64_t)max_blobs * sizeof(blob_acc) + 15u) & ~(uint64_t)15u;
    uint64_t total = 16u + runs + blobs + accs;
    if (max_runs >= CYL_NONE || max_blobs >= CYL_NONE) return 0;
    if (total > (uint64_t)(((size_t)-1) >> 1)) return 0;
    return (size_t)total;
}

cyl_status cyl_segmentation_init(cyl_segmentation *seg, void *mem, size_t mem_size,
                                 uint32_t max_runs, uint32_t max_blobs)
{
    size_t need = cyl_segment_mem_size(max_runs, max_blobs);
    uint8_t *p;
    if (!seg || !mem) return CYL_ERR_ARG;
    if (need == 0 || max_runs == 0 || max_blobs == 0) return CYL_ERR_ARG;
    if (mem_size < need) return CYL_ERR_NOMEM;
    memset(seg, 0, sizeof *seg);
    p = (uint8_t *)cyl_align_ptr(mem, 16u);
    seg->runs = (cyl_run *)(void *)p;
    p += ALIGN_UP((size_t)max_runs * sizeof(cyl_run), 16u);
    seg->blobs = (cyl_blob *)(void *)p;
    p += ALIGN_UP((size_t)max_blobs * sizeof(cyl_blob), 16u);
    seg->work = p;
    seg->work_size = ALIGN_UP((size_t)max_blobs * sizeof(blob_acc), 16u);
    seg->max_runs = max_runs;
    seg->max_blobs = max_blobs;
    seg->min_run_px = 1u;
    {
        unsigned k;
        for (k = 0; k < CYL_MAX_CLASSES; k++) seg->merge_gap_px[k] = -1;
    }
    return CYL_OK;
}

/* ---- run-length encoding ------------------------------------------------ */

typedef struct rle_ctx {
    cyl_run *runs;
    uint32_t n, max;
    uint32_t min_run;
    int full;
    cyl_skip_set skip;    /* vector background skip per format (NULL: scalar only) */
    uint32_t skip_rest;   /* rows still to encode without the vector skip / run extension, */
    uint32_t extend_rest; /* after a row in which they did not pay (performance only) */
} rle_ctx;

static int emit(rle_ctx *c, uint32_t x, uint32_t y, uint32_t len, unsigned cls)
{
    cyl_run *r;
    if (len < c->min_run) return 1;
    if (c->n >= c->max) { c->full = 1; return 0; }
    r = &c->runs[c->n];
    r->x = (uint16_t)x;
    r->y = (uint16_t)y;
    r->width = (uint16_t)len;
    r->cls = (uint8_t)cls;
    r->reserved = 0;
    r->blob = c->n;   /* union-find parent: itself */
    r->next = CYL_NONE;
    c->n++;
    return 1;
}

/* Advance the run state by one sample of class cls at position pos (sample
 * index); returns 0 when the run buffer is full. */
#define STEP(cls_expr, pos)                                                   \
    do {                                                                      \
        unsigned c_ = (cls_expr);                                             \
        if (c_ != cur) {                                                      \
            if (cur != CYL_CLASS_NONE &&                                      \
                !emit(ctx, x_img0 + start * xs, y, (pos) - start, cur))       \
                return 0;                                                     \
            cur = c_;                                                         \
            start = (pos);                                                    \
        }                                                                     \
    } while (0)

#if defined(__GNUC__)
#define CYL_HOT_INLINE static inline __attribute__((always_inline))
#else
#define CYL_HOT_INLINE static inline
#endif

/* The vector background skip of one row: its function (NULL: scalar only), the chroma pointers
 * it reads, how many more short skips it may make before the row goes without it, and where to
 * say for how many further rows it should stay off. */
typedef struct bg_skip {
    cyl_skip_fn fn;
    const uint8_t *su, *sv;
    unsigned misses;
    uint32_t *rest_rows;
} bg_skip;

/* Background pairs from sample x (even offset from the row's pairs) on: returns the first x' >= x
 * such that every pair in [x, x') has uv == 0 (and x' + 1 < x1 where a pair may be coloured).
 * Short gaps between runs are walked by the scalar test (4 pairs; with probe 0, at a row's start,
 * the vector skip starts at once); longer ones by the vector skip on the coarse
 * chroma map, then the scalar test again for at most 8 pairs, since a block bit may be set by
 * another chroma of the block. Where the background's chroma keeps falling in blocks the map
 * cannot rule out, the vector skip costs more than it saves: after two short skips it is off for
 * the rest of the row and the next 7 rows. */
CYL_HOT_INLINE uint32_t skip_background(const cyl_colortable *t, const uint8_t *up, const uint8_t *vp,
                                        const unsigned cs, uint32_t x, uint32_t x1, bg_skip *sk, int probe)
{
    const cyl_mask (*uv)[256] = t->uv;
    const uint8_t *pu = up + (x / 2u) * cs, *pv = vp + (x / 2u) * cs;
    uint32_t xlim = x1;
    if (sk->fn) {
        const uint32_t xw = !probe ? x : x + 8u < x1 ? x + 8u : x1;
        while (x + 1u < xw && uv[pu[0]][pv[0]] == 0) { x += 2u; pu += cs; pv += cs; }
        if (x + 1u < xw) return x;   /* a pair that may be coloured */
        if (x + 1u < x1) {
            const uint32_t xs0 = x;
            x = 2u * sk->fn(sk->su, sk->sv, t->chroma_any, x / 2u, x1 / 2u);
            if (x + 16u < x1) xlim = x + 16u;
            pu = up + (x / 2u) * cs; pv = vp + (x / 2u) * cs;
            /* a miss: a short skip that stopped at a pair of no class (the coarse map's false alarm;
             * stopping at a coloured pair is the skip doing its work) */
            if (x - xs0 < 32u && (x + 1u >= x1 || uv[pu[0]][pv[0]] == 0) && --sk->misses == 0) {
                sk->fn = NULL;
                *sk->rest_rows = 7u;
            }
        }
    }
    while (x + 3u < xlim && (uv[pu[0]][pv[0]] | uv[pu[cs]][pv[cs]]) == 0) {
        x += 4u; pu += 2u * cs; pv += 2u * cs;
    }
    return x;
}

/* Samples [x0, x1) of a row of a format whose two horizontal neighbours
 * (even x, x+1) share chroma. yp: luma row, ysz: bytes per luma sample;
 * up/vp: chroma of pair 0 (pixel 0), cs: bytes from one chroma pair to the next.
 * x_step is 1 here, so sample index == image column. Inlined into one copy per
 * format so that ysz and cs are constants. */
CYL_HOT_INLINE int encode_pairs(rle_ctx *ctx, const cyl_colortable *t, uint32_t y,
                                const uint8_t *yp, const unsigned ysz, const uint8_t *up,
                                const uint8_t *vp, const unsigned cs, uint32_t x0, uint32_t x1,
                                cyl_skip_fn skip, cyl_extend_fn extend, const uint8_t *sy,
                                const uint8_t *su, const uint8_t *sv, const unsigned lookup)
{
    const cyl_mask (*uv)[256] = t->uv;
    const cyl_mask *ytab = t->y;
    const cyl_mask *yuv = &t->yuv[0][0][0];
    const cyl_mask live = t->live;
    unsigned cur = CYL_CLASS_NONE, extend_misses = 16u;
    uint32_t x = x0, start = x0, x_img0 = 0, xs = 1;
    bg_skip sk;
    /* rows after one where the vector code did not pay go without it: the next 7 rows without
     * the skip, the next 3 without the run extension (performance only: results never depend
     * on which path ran) */
    sk.fn = skip; sk.su = su; sk.sv = sv; sk.misses = 2u; sk.rest_rows = &ctx->skip_rest;
    if (ctx->skip_rest) { ctx->skip_rest--; sk.fn = NULL; }
    if (ctx->extend_rest) { ctx->extend_rest--; extend = NULL; }
    /* Class of luma Y given the pair's chroma mask m and its 3-D column col. */
    /* lookup (a constant in each inlined copy) leaves out the parts that never reject */
#define PAIR_CLASS(Y)                                                                         \
    cyl_lowbit[lookup == CYL_LOOKUP_UV_Y ? (unsigned)(m & ytab[(Y)])                          \
               : lookup == CYL_LOOKUP_YUV ? (unsigned)(col[((unsigned)(Y) >> CYL_YUV_YSHIFT) * YUV_YSTRIDE] & live) \
               : (unsigned)(m & ytab[(Y)] & col[((unsigned)(Y) >> CYL_YUV_YSHIFT) * YUV_YSTRIDE])]
#define PAIR_COL(U, V) (yuv + ((unsigned)(U) >> CYL_YUV_CSHIFT) * CYL_YUV_NC + ((unsigned)(V) >> CYL_YUV_CSHIFT))
    if (x & 1u) {
        const uint8_t U = up[(x / 2u) * cs], V = vp[(x / 2u) * cs];
        cyl_mask m = uv[U][V];
        const cyl_mask *col = PAIR_COL(U, V);
        STEP(PAIR_CLASS(yp[x * ysz]), x);
        x++;
    }
    while (x + 1u < x1) {
        cyl_mask m;
        const cyl_mask *col;
        if (cur == CYL_CLASS_NONE) {
            /* Background fast path: skip pairs whose chroma is in no class without
             * reading luma (skip_background). */
            const uint8_t *pu = up + (x / 2u) * cs, *pv = vp + (x / 2u) * cs;
            if (uv[pu[0]][pv[0]] == 0) {
                x = skip_background(t, up, vp, cs, x + 2u, x1, &sk, x > x0 + 1u);
                continue;
            }
            m = uv[pu[0]][pv[0]];
            col = PAIR_COL(pu[0], pv[0]);
        } else {
            if (extend) {   /* cur != NONE: start < x */
                /* an open run: extend it 16 pixels at a time (and, as
                 * with the skip, stop trying in a row where runs keep breaking early) */
                const uint32_t xe0 = x;
                x = 2u * extend(t, sy, su, sv, x / 2u, x1 / 2u, cur);
                if (x - xe0 < 16u && --extend_misses == 0) { extend = NULL; ctx->extend_rest = 3u; }
                if (x + 1u >= x1) break;
            }
            {
                const uint8_t U = up[(x / 2u) * cs], V = vp[(x / 2u) * cs];
                m = uv[U][V];
                col = PAIR_COL(U, V);
            }
        }
        STEP(PAIR_CLASS(yp[x * ysz]), x);
        STEP(PAIR_CLASS(yp[(x + 1u) * ysz]), x + 1u);
        x += 2u;
    }
    if (x < x1) {
        const uint8_t U = up[(x / 2u) * cs], V = vp[(x / 2u) * cs];
        cyl_mask m = uv[U][V];
        const cyl_mask *col = PAIR_COL(U, V);
        STEP(PAIR_CLASS(yp[x * ysz]), x);
    }
#undef PAIR_CLASS
#undef PAIR_COL
    if (cur != CYL_CLASS_NONE && !emit(ctx, start, y, x1 - start, cur)) return 0;
    return 1;
}

/* One copy per format and lookup, with constant layouts. */
#define ENCODE_BY_LOOKUP(...)                                                         \
    switch (t->lookup) {                                                              \
    case CYL_LOOKUP_UV_Y: return encode_pairs(__VA_ARGS__, CYL_LOOKUP_UV_Y);         \
    case CYL_LOOKUP_YUV: return encode_pairs(__VA_ARGS__, CYL_LOOKUP_YUV);           \
    default: return encode_pairs(__VA_ARGS__, CYL_LOOKUP_UV_Y | CYL_LOOKUP_YUV);     \
    }
static int encode_yuyv(rle_ctx *c, const cyl_colortable *t, uint32_t y, const uint8_t *r, uint32_t x0, uint32_t x1)
{
    ENCODE_BY_LOOKUP(c, t, y, r, 2u, r + 1, r + 3, 4u, x0, x1, c->skip.yuyv, c->skip.ext_yuyv, r, r, NULL)
}
static int encode_uyvy(rle_ctx *c, const cyl_colortable *t, uint32_t y, const uint8_t *r, uint32_t x0, uint32_t x1)
{
    ENCODE_BY_LOOKUP(c, t, y, r + 1, 2u, r, r + 2, 4u, x0, x1, c->skip.uyvy, c->skip.ext_uyvy, r, r, NULL)
}
static int encode_nv12(rle_ctx *c, const cyl_colortable *t, uint32_t y, const uint8_t *r,
                       const uint8_t *uv, uint32_t x0, uint32_t x1)
{
    ENCODE_BY_LOOKUP(c, t, y, r, 1u, uv, uv + 1, 2u, x0, x1, c->skip.nv12, c->skip.ext_nv12, r, uv, NULL)
}
static int encode_i420(rle_ctx *c, const cyl_colortable *t, uint32_t y, const uint8_t *r,
                       const uint8_t *u, const uint8_t *v, uint32_t x0, uint32_t x1)
{
    ENCODE_BY_LOOKUP(c, t, y, r, 1u, u, v, 1u, x0, x1, c->skip.i420, c->skip.ext_i420, r, u, v)
}
#undef ENCODE_BY_LOOKUP

/* Any format and step: one pixel fetch per sample. */
static int encode_generic(rle_ctx *ctx, const cyl_colortable *t, const cyl_image *img,
                          uint32_t y, uint32_t x_img0, uint32_t xs, uint32_t n)
{
    unsigned cur = CYL_CLASS_NONE;
    uint32_t i, start = 0;
    for (i = 0; i < n; i++) {
        uint8_t Y, U, V;
        cyl_pixel_fetch(img, x_img0 + i * xs, y, &Y, &U, &V);
        STEP(cyl_lowbit[cyl_colortable_mask(t, Y, U, V)], i);
    }
    if (cur != CYL_CLASS_NONE && !emit(ctx, x_img0 + start * xs, y, n - start, cur)) return 0;
    return 1;
}
#undef STEP

static int encode_row(rle_ctx *ctx, const cyl_colortable *t, const cyl_image *img,
                      uint32_t y, uint32_t x0, uint32_t xs, uint32_t n)
{
    const uint8_t *r0 = img->plane[0] + (size_t)y * img->stride[0];
    if (xs == 1u) {
        uint32_t x1 = x0 + n;
        /* a format compiled out (cyl/config.h) never gets here: cyl_image_check refuses it */
        switch (img->format) {
        case CYL_FMT_YUYV:
            if (FORMAT_ON(CYL_FMT_YUYV)) return encode_yuyv(ctx, t, y, r0, x0, x1);
            break;
        case CYL_FMT_UYVY:
            if (FORMAT_ON(CYL_FMT_UYVY)) return encode_uyvy(ctx, t, y, r0, x0, x1);
            break;
        case CYL_FMT_NV12:
            if (FORMAT_ON(CYL_FMT_NV12))
                return encode_nv12(ctx, t, y, r0, img->plane[1] + (size_t)(y / 2u) * img->stride[1], x0, x1);
            break;
        case CYL_FMT_I420:
            if (FORMAT_ON(CYL_FMT_I420))
                return encode_i420(ctx, t, y, r0, img->plane[1] + (size_t)(y / 2u) * img->stride[1],
                                   img->plane[2] + (size_t)(y / 2u) * img->stride[2], x0, x1);
            break;
        default:
            break;
        }
    }
    return encode_generic(ctx, t, img, y, x0, xs, n);
}

/* ---- class map (cyl_classify) ---------------------------------------------- */

/* Class indices of samples [x0, x1) of a row of a 4:2:x format (layout as encode_pairs), into
 * o[0, x1 - x0): a chroma pair that maps to no class is written as background without reading
 * luma, and stretches of such pairs are found by skip_background, as in the segmentation; a class
 * that has held for two pairs is extended by the run extension (ext: NULL for none; sy, su, sv its
 * row pointers), which stops being tried in a row where it keeps stopping early, as there. */
CYL_HOT_INLINE void classify_pairs(const cyl_colortable *t, const uint8_t *yp, const unsigned ysz,
                                   const uint8_t *up, const uint8_t *vp, const unsigned cs, uint32_t x0,
                                   uint32_t x1, uint8_t *o, bg_skip *sk, cyl_extend_fn ext,
                                   const uint8_t *sy, const uint8_t *su, const uint8_t *sv)
{
    uint32_t x = x0;
    unsigned prev = CYL_CLASS_NONE, ext_misses = 16u;
#define PIX_CLASS(X) cyl_lowbit[cyl_colortable_mask(t, yp[(X) * ysz], up[((X) / 2u) * cs], vp[((X) / 2u) * cs])]
    if (x & 1u) { o[0] = PIX_CLASS(x); x++; }
    while (x + 1u < x1) {
        const uint8_t U = up[(x / 2u) * cs], V = vp[(x / 2u) * cs];
        const cyl_mask m = t->uv[U][V];
        if (m == 0) {
            const uint32_t xn = skip_background(t, up, vp, cs, x + 2u, x1, sk, 1);
            memset(o + (x - x0), CYL_CLASS_NONE, xn - x);
            x = xn;
            prev = CYL_CLASS_NONE;
            continue;
        }
        {
            const cyl_mask *col = &t->yuv[0][U >> CYL_YUV_CSHIFT][V >> CYL_YUV_CSHIFT];
            const uint8_t Y0 = yp[x * ysz], Y1 = yp[(x + 1u) * ysz];
            const uint8_t c0 = cyl_lowbit[m & t->y[Y0] & col[(unsigned)(Y0 >> CYL_YUV_YSHIFT) * YUV_YSTRIDE]];
            const uint8_t c1 = cyl_lowbit[m & t->y[Y1] & col[(unsigned)(Y1 >> CYL_YUV_YSHIFT) * YUV_YSTRIDE]];
            o[x - x0] = c0;
            o[x + 1u - x0] = c1;
            x += 2u;
            if (c0 != c1 || c0 == CYL_CLASS_NONE) { prev = CYL_CLASS_NONE; continue; }
            if (ext && prev == c0 && x + 1u < x1) {   /* the class has held for two pairs: extend it */
                const uint32_t xe = 2u * ext(t, sy, su, sv, x / 2u, x1 / 2u, c0);
                memset(o + (x - x0), c0, xe - x);
                if (xe - x < 16u && --ext_misses == 0) ext = NULL;
                x = xe;
                prev = CYL_CLASS_NONE;   /* the pair at x decides afresh */
                continue;
            }
            prev = c0;
        }
    }
    if (x < x1) o[x - x0] = PIX_CLASS(x);
#undef PIX_CLASS
}

cyl_status cyl_classify(const cyl_colortable *t, const cyl_image *img, const cyl_roi *roi,
                        unsigned x_step, unsigned y_step, uint8_t *out, size_t out_stride)
{
    cyl_roi r;
    uint32_t x, y, i, j;
    cyl_status s;
    const cyl_skip_set set = cyl_skip_select();
    uint32_t skip_rest = 0;   /* as rle_ctx.skip_rest */
    if (!t || !out) return CYL_ERR_ARG;
    s = cyl_image_check(img);
    if (s != CYL_OK) return s;
    if (x_step == 0 || y_step == 0) return CYL_ERR_ARG;
    if (!cyl_roi_resolve(img, roi, &r)) return CYL_ERR_SIZE;
    if (out_stride < (r.width + x_step - 1u) / x_step) return CYL_ERR_SIZE;
    for (j = 0, y = r.y; y < r.y + r.height; y += y_step, j++) {
        uint8_t *o = out + (size_t)j * out_stride;
        const uint8_t *r0 = img->plane[0] + (size_t)y * img->stride[0];
        const uint8_t *c1 = img->format == CYL_FMT_NV12 || img->format == CYL_FMT_I420
                                ? img->plane[1] + (size_t)(y / 2u) * img->stride[1] : NULL;
        const uint32_t x1 = r.x + r.width;
        bg_skip sk;
        sk.misses = 2u;
        sk.rest_rows = &skip_rest;
        sk.su = img->format == CYL_FMT_YUYV || img->format == CYL_FMT_UYVY ? r0 : c1;
        sk.sv = img->format == CYL_FMT_I420 ? img->plane[2] + (size_t)(y / 2u) * img->stride[2] : NULL;
        sk.fn = img->format == CYL_FMT_YUYV ? set.yuyv : img->format == CYL_FMT_UYVY ? set.uyvy
              : img->format == CYL_FMT_NV12 ? set.nv12 : set.i420;
        if (skip_rest) { skip_rest--; sk.fn = NULL; }
        if (x_step == 1u && img->format == CYL_FMT_YUYV && FORMAT_ON(CYL_FMT_YUYV)) {
            classify_pairs(t, r0, 2u, r0 + 1, r0 + 3, 4u, r.x, x1, o, &sk, set.ext_yuyv, r0, r0, NULL);
        } else if (x_step == 1u && img->format == CYL_FMT_UYVY && FORMAT_ON(CYL_FMT_UYVY)) {
            classify_pairs(t, r0 + 1, 2u, r0, r0 + 2, 4u, r.x, x1, o, &sk, set.ext_uyvy, r0, r0, NULL);
        } else if (x_step == 1u && img->format == CYL_FMT_NV12 && FORMAT_ON(CYL_FMT_NV12)) {
            classify_pairs(t, r0, 1u, c1, c1 + 1, 2u, r.x, x1, o, &sk, set.ext_nv12, r0, c1, NULL);
        } else if (x_step == 1u && img->format == CYL_FMT_I420 && FORMAT_ON(CYL_FMT_I420)) {
            classify_pairs(t, r0, 1u, c1, sk.sv, 1u, r.x, x1, o, &sk, set.ext_i420, r0, c1, sk.sv);
        } else {
            for (i = 0, x = r.x; x < x1; x += x_step, i++) {
                uint8_t Y, U, V;
                cyl_pixel_fetch(img, x, y, &Y, &U, &V);
                o[i] = cyl_lowbit[cyl_colortable_mask(t, Y, U, V)];
            }
        }
    }
    return CYL_OK;
}

/* ---- union-find ------------------------------------------------------------ */

static uint32_t uf_find(cyl_run *r, uint32_t i)
{
    while (r[i].blob != i) {
        r[i].blob = r[r[i].blob].blob; /* path halving keeps parent <= index */
        i = r[i].blob;
    }
    return i;
}

static void uf_union(cyl_run *r, uint32_t a, uint32_t b)
{
    a = uf_find(r, a);
    b = uf_find(r, b);
    if (a < b) r[b].blob = a;
    else if (b < a) r[a].blob = b;
}

/* Join runs of the previous sampled row [pb, pe) with the current one [cb, ce).
 * eq: each class's blob class (itself, or the class it is weak evidence of). */
static void connect_rows(cyl_run *r, uint32_t pb, uint32_t pe, uint32_t cb, uint32_t ce, uint32_t xs,
                         const uint8_t *eq)
{
    uint32_t i = pb, j = cb, a0, a1, b0, b1;
    if (i >= pe || j >= ce) return;
    /* each run's first and last column, recomputed only for the run the walk moves to */
    a0 = r[i].x; a1 = a0 + (uint32_t)(r[i].width - 1u) * xs;
    b0 = r[j].x; b1 = b0 + (uint32_t)(r[j].width - 1u) * xs;
    for (;;) {
        if (a0 <= b1 && b0 <= a1 && eq[r[i].cls] == eq[r[j].cls]) {
            /* a run not yet joined is its own root: it joins i's root (smaller, as i < j) */
            if (r[j].blob == j) r[j].blob = uf_find(r, i);
            else uf_union(r, i, j);
        }
        if (a1 < b1) {
            if (++i >= pe) return;
            a0 = r[i].x; a1 = a0 + (uint32_t)(r[i].width - 1u) * xs;
        } else {
            if (++j >= ce) return;
            b0 = r[j].x; b1 = b0 + (uint32_t)(r[j].width - 1u) * xs;
        }
    }
}

/* With weak classes: join side-by-side runs of a row [cb, ce) whose blob classes agree. */
static void connect_within_row(cyl_run *r, uint32_t cb, uint32_t ce, uint32_t xs, const uint8_t *eq)
{
    uint32_t j;
    for (j = cb + 1u; j < ce; j++)
        if (r[j].x == r[j - 1u].x + (uint32_t)r[j - 1u].width * xs && eq[r[j].cls] == eq[r[j - 1u].cls])
            uf_union(r, j - 1u, j);
}

/* ---- blobs ------------------------------------------------------------------ */

static void acc_add_run(blob_acc *a, const cyl_run *r, uint32_t xs)
{
    int64_t w = r->width, x = r->x, y = r->y, s = xs;
    int64_t s1 = w * (w - 1) / 2;                   /* sum of k, k < w */
    int64_t s2 = (w - 1) * w * (2 * w - 1) / 6;     /* sum of k^2 */
    int64_t sumx = w * x + s * s1;
    a->n += w;
    a->sx += sumx;
    a->sy += w * y;
    a->sxx += w * x * x + 2 * x * s * s1 + s * s * s2;
    a->syy += w * y * y;
    a->sxy += y * sumx;
}

/* Merge two run lists sorted by index into one. */
static uint32_t merge_lists(cyl_run *r, uint32_t a, uint32_t b, uint32_t *tail)
{
    uint32_t head = CYL_NONE, last = CYL_NONE;
    while (a != CYL_NONE || b != CYL_NONE) {
        uint32_t take;
        if (b == CYL_NONE || (a != CYL_NONE && a < b)) { take = a; a = r[a].next; }
        else { take = b; b = r[b].next; }
        if (last == CYL_NONE) head = take; else r[last].next = take;
        last = take;
    }
    if (last != CYL_NONE) r[last].next = CYL_NONE;
    *tail = last;
    return head;
}

static uint32_t box_gap(uint32_t a0, uint32_t a1, uint32_t b0, uint32_t b1)
{
    if (b0 > a1) return b0 - a1 - 1u;
    if (a0 > b1) return a0 - b1 - 1u;
    return 0;
}

static int try_merge(cyl_segmentation *seg, blob_acc *acc, uint32_t ia, uint32_t ib,
                     const cyl_class_params *cp)
{
    cyl_blob *a = &seg->blobs[ia], *b = &seg->blobs[ib];
    uint32_t X0, X1, Y0, Y1;
    double box;
    if (box_gap(a->x0, a->x1, b->x0, b->x1) > (uint32_t)cp->merge_gap_px) return 0;
    if (box_gap(a->y0, a->y1, b->y0, b->y1) > (uint32_t)cp->merge_gap_px) return 0;
    X0 = a->x0 < b->x0 ? a->x0 : b->x0;
    X1 = a->x1 > b->x1 ? a->x1 : b->x1;
    Y0 = a->y0 < b->y0 ? a->y0 : b->y0;
    Y1 = a->y1 > b->y1 ? a->y1 : b->y1;
    /* samples in the merged box: extents are exact multiples of the steps on the sample grid */
    box = (double)((X1 - X0) / seg->x_step + 1u) * /* NOLINT(bugprone-integer-division) */
          (double)((Y1 - Y0) / seg->y_step + 1u);  /* NOLINT(bugprone-integer-division) */
    if ((double)(acc[ia].n + acc[ib].n) < cp->merge_min_density * box) return 0;
    /* b joins a */
    acc[ia].n += acc[ib].n; acc[ia].sx += acc[ib].sx; acc[ia].sy += acc[ib].sy;
    acc[ia].sxx += acc[ib].sxx; acc[ia].syy += acc[ib].syy; acc[ia].sxy += acc[ib].sxy;
    acc[ia].strong |= acc[ib].strong;
    acc[ib].alive = 0;
    a->first_run = merge_lists(seg->runs, a->first_run, b->first_run, &acc[ia].last_run);
    a->n_runs += b->n_runs;
    a->n_components = (uint16_t)((uint32_t)a->n_components + b->n_components > 0xFFFFu
                                     ? 0xFFFFu : a->n_components + b->n_components);
    a->flags |= CYL_BLOB_MERGED;
    a->x0 = (uint16_t)X0; a->x1 = (uint16_t)X1; a->y0 = (uint16_t)Y0; a->y1 = (uint16_t)Y1;
    return 1;
}

static void merge_blobs(cyl_segmentation *seg, blob_acc *acc, uint32_t nb, const cyl_segment_params *p)
{
    int changed = 1;
    while (changed) {
        uint32_t i, j;
        changed = 0;
        for (i = 0; i < nb; i++) {
            const cyl_class_params *cp;
            if (!acc[i].alive) continue;
            cp = &p->cls[seg->blobs[i].cls];
            if (cp->merge_gap_px < 0) continue;
            for (j = i + 1u; j < nb; j++)
                if (acc[j].alive && seg->blobs[j].cls == seg->blobs[i].cls &&
                    try_merge(seg, acc, i, j, cp))
                    changed = 1;
        }
    }
}

static void finish_blob(cyl_segmentation *seg, cyl_blob *b, const blob_acc *a)
{
    double n = (double)a->n, cx, cy, mxx, myy, mxy, d, l1, l2;
    b->area = (uint32_t)a->n;
    cx = (double)a->sx / n;
    cy = (double)a->sy / n;
    mxx = ((double)a->sxx - (double)a->sx * cx) / n;
    myy = ((double)a->syy - (double)a->sy * cy) / n;
    mxy = ((double)a->sxy - (double)a->sx * cy) / n;
    if (mxx < 0) mxx = 0;
    if (myy < 0) myy = 0;
    b->cx_px = cx; b->cy_px = cy;
    b->mxx_px2 = mxx; b->myy_px2 = myy; b->mxy_px2 = mxy;
    b->orientation_rad = (mxy == 0.0 && mxx >= myy) ? 0.0 : 0.5 * atan2(2.0 * mxy, mxx - myy);
    d = sqrt(0.25 * (mxx - myy) * (mxx - myy) + mxy * mxy);
    l1 = 0.5 * (mxx + myy) + d;
    l2 = 0.5 * (mxx + myy) - d;
    if (l2 < 0) l2 = 0;
    b->elongation = l1 > 0 ? 1.0 - sqrt(l2 / l1) : 0.0;
    if (b->x0 == seg->x_origin) b->flags |= CYL_BLOB_TOUCH_LEFT;
    if (b->x1 == seg->x_last) b->flags |= CYL_BLOB_TOUCH_RIGHT;
    if (b->y0 == seg->y_origin) b->flags |= CYL_BLOB_TOUCH_TOP;
    if (b->y1 == seg->y_last) b->flags |= CYL_BLOB_TOUCH_BOTTOM;
}

/* Total order: class ascending, area descending, y0, x0, first run. */
static int blob_before(const cyl_blob *a, const cyl_blob *b)
{
    if (a->cls != b->cls) return a->cls < b->cls;
    if (a->area != b->area) return a->area > b->area;
    if (a->y0 != b->y0) return a->y0 < b->y0;
    if (a->x0 != b->x0) return a->x0 < b->x0;
    return a->first_run < b->first_run;
}

static void sift_down(cyl_blob *v, uint32_t i, uint32_t n)
{
    for (;;) {
        uint32_t c = 2u * i + 1u, m = i;
        cyl_blob tmp;
        if (c < n && blob_before(&v[m], &v[c])) m = c;
        if (c + 1u < n && blob_before(&v[m], &v[c + 1u])) m = c + 1u;
        if (m == i) return;
        tmp = v[i]; v[i] = v[m]; v[m] = tmp;
        i = m;
    }
}

static void sort_blobs(cyl_blob *v, uint32_t n)
{
    uint32_t i;
    if (n < 2) return;
    for (i = n / 2u; i-- > 0;) sift_down(v, i, n);
    for (i = n - 1u; i > 0; i--) {
        cyl_blob tmp = v[0]; v[0] = v[i]; v[i] = tmp;
        sift_down(v, 0, i);
    }
}

/* Each run's blob index from the (sorted) blobs' run lists, CYL_NONE for runs of no blob (dropped),
 * and class_first / class_count. */
static void label_runs(cyl_segmentation *seg)
{
    uint32_t i, k;
    for (i = 0; i < seg->n_runs; i++) seg->runs[i].blob = CYL_NONE;
    for (k = 0; k < CYL_MAX_CLASSES; k++) { seg->class_first[k] = 0; seg->class_count[k] = 0; }
    for (k = 0; k < seg->n_blobs; k++) {
        uint32_t ri;
        for (ri = seg->blobs[k].first_run; ri != CYL_NONE; ri = seg->runs[ri].next) seg->runs[ri].blob = k;
        if (seg->class_count[seg->blobs[k].cls]++ == 0) seg->class_first[seg->blobs[k].cls] = k;
    }
}

static cyl_status check_params(const cyl_segment_params *p)
{
    unsigned i;
    if (p->min_run_px == 0 || p->x_step == 0 || p->y_step == 0) return CYL_ERR_ARG;
    for (i = 0; i < CYL_MAX_CLASSES; i++) {
        double d = p->cls[i].merge_min_density;
        if (!(d >= 0.0 && d <= 1.0)) return CYL_ERR_ARG;
    }
    return CYL_OK;
}

/* Checks shared by cyl_segment(), cyl_segment_band() and cyl_segment_join(): *pp is set to the
 * defaults when NULL; *r receives the resolved ROI and *nx the samples per row. */
static cyl_status prepare(const cyl_colortable *t, const cyl_image *img, const cyl_segment_params **pp,
                          cyl_segment_params *defaults, cyl_roi *r, uint32_t *nx)
{
    cyl_status s;
    if (!t) return CYL_ERR_ARG;
    if (!*pp) { *defaults = cyl_segment_params_default(); *pp = defaults; }
    s = check_params(*pp);
    if (s != CYL_OK) return s;
    s = cyl_image_check(img);
    if (s != CYL_OK) return s;
    if (!cyl_roi_resolve(img, &(*pp)->roi, r)) return CYL_ERR_SIZE;
    *nx = (r->width + (*pp)->x_step - 1u) / (*pp)->x_step;
    return CYL_OK;
}

static void rle_begin(rle_ctx *ctx, cyl_run *runs, uint32_t max_runs, const cyl_segment_params *p)
{
    ctx->runs = runs;
    ctx->n = 0;
    ctx->max = max_runs;
    ctx->min_run = p->min_run_px;
    ctx->full = 0;
    ctx->skip_rest = 0;
    ctx->extend_rest = 0;
    if (p->scalar_only) {
        memset(&ctx->skip, 0, sizeof ctx->skip);
    } else {
        ctx->skip = cyl_skip_select();
    }
}

/* The class each class's runs connect as (a weak class: its strong class); 1 if any is weak. */
static int class_equivalence(const cyl_colortable *t, uint8_t eq[CYL_MAX_CLASSES])
{
    unsigned k;
    int weak = 0;
    for (k = 0; k < CYL_MAX_CLASSES; k++) {
        unsigned w = t->weak_of[k];
        eq[k] = (uint8_t)(w < CYL_MAX_CLASSES && t->weak_of[w] == CYL_CLASS_NONE ? w : k);
        weak |= eq[k] != k;
    }
    return weak;
}

static cyl_status finish(cyl_segmentation *seg, const cyl_image *img, const cyl_segment_params *p,
                         const cyl_roi *r, uint32_t nx, const uint8_t *eq, int weak);

cyl_status cyl_segment(const cyl_colortable *t, const cyl_image *img,
                       const cyl_segment_params *p, cyl_segmentation *seg)
{
    cyl_segment_params defaults;
    cyl_roi r;
    rle_ctx ctx;
    uint32_t nx, y, prev_b = 0, prev_e = 0;
    uint8_t eq[CYL_MAX_CLASSES];
    int weak;
    cyl_status s;

    if (!seg || !seg->runs || !seg->blobs || !seg->work) return CYL_ERR_ARG;
    s = prepare(t, img, &p, &defaults, &r, &nx);
    if (s != CYL_OK) return s;
    weak = class_equivalence(t, eq);

    /* 1. classify + run-length encode, connecting each row to the previous one */
    rle_begin(&ctx, seg->runs, seg->max_runs, p);
    for (y = r.y; y < r.y + r.height; y += p->y_step) {
        uint32_t b = ctx.n;
        int ok = encode_row(&ctx, t, img, y, r.x, p->x_step, nx);
        if (weak) connect_within_row(seg->runs, b, ctx.n, p->x_step, eq);
        connect_rows(seg->runs, prev_b, prev_e, b, ctx.n, p->x_step, eq);
        prev_b = b;
        prev_e = ctx.n;
        if (!ok) break;
    }
    seg->n_runs = ctx.n;
    seg->truncated = ctx.full ? CYL_SEG_RUNS_FULL : 0u;
    return finish(seg, img, p, &r, nx, eq, weak);
}

uint32_t cyl_segment_rows(const cyl_image *img, const cyl_segment_params *p)
{
    cyl_segment_params defaults;
    cyl_roi r;
    if (!p) { defaults = cyl_segment_params_default(); p = &defaults; }
    if (!img || p->y_step == 0 || !cyl_roi_resolve(img, &p->roi, &r)) return 0;
    return (r.height + p->y_step - 1u) / p->y_step;
}

cyl_status cyl_segment_band(const cyl_colortable *t, const cyl_image *img, const cyl_segment_params *p,
                            uint32_t row_begin, uint32_t row_end, cyl_run *runs, uint32_t max_runs,
                            uint32_t *n_runs)
{
    cyl_segment_params defaults;
    cyl_roi r;
    rle_ctx ctx;
    uint32_t nx, j, rows;
    cyl_status s;

    if (!runs || !n_runs) return CYL_ERR_ARG;
    *n_runs = 0;
    s = prepare(t, img, &p, &defaults, &r, &nx);
    if (s != CYL_OK) return s;
    rows = (r.height + p->y_step - 1u) / p->y_step;
    if (row_begin > row_end || row_end > rows) return CYL_ERR_ARG;
    rle_begin(&ctx, runs, max_runs, p);
    for (j = row_begin; j < row_end; j++)
        if (!encode_row(&ctx, t, img, r.y + j * p->y_step, r.x, p->x_step, nx)) break;
    *n_runs = ctx.n;
    return ctx.full ? CYL_TRUNCATED : CYL_OK;
}

cyl_status cyl_segment_join(const cyl_colortable *t, const cyl_image *img, const cyl_segment_params *p,
                            const cyl_run *const *band_runs, const uint32_t *band_n_runs, unsigned n_bands,
                            cyl_segmentation *seg)
{
    cyl_segment_params defaults;
    cyl_roi r;
    uint32_t nx, i, n = 0, prev_b = 0, prev_e = 0, row_b = 0;
    uint8_t eq[CYL_MAX_CLASSES];
    unsigned k;
    int weak;
    cyl_status s;

    if (!seg || !seg->runs || !seg->blobs || !seg->work || (n_bands && (!band_runs || !band_n_runs)))
        return CYL_ERR_ARG;
    s = prepare(t, img, &p, &defaults, &r, &nx);
    if (s != CYL_OK) return s;
    weak = class_equivalence(t, eq);
    seg->truncated = 0;
    /* gather the bands' runs in order, as cyl_segment() would have written them */
    for (k = 0; k < n_bands; k++) {
        if (band_n_runs[k] && !band_runs[k]) return CYL_ERR_ARG;
        for (i = 0; i < band_n_runs[k]; i++) {
            cyl_run *d;
            if (n >= seg->max_runs) { seg->truncated = CYL_SEG_RUNS_FULL; break; }
            d = &seg->runs[n];
            *d = band_runs[k][i];
            if (n > 0 && (d->y < seg->runs[n - 1u].y ||
                          (d->y == seg->runs[n - 1u].y && d->x <= seg->runs[n - 1u].x)))
                return CYL_ERR_ARG;   /* the bands must be in row order */
            d->blob = n;
            d->next = CYL_NONE;
            n++;
        }
    }
    /* connect row by row: runs of a row with those of the sampled row above */
    for (i = 0; i <= n; i++) {
        if (i < n && i > row_b && seg->runs[i].y == seg->runs[row_b].y) continue;
        if (i > row_b) {   /* row [row_b, i) */
            if (weak) connect_within_row(seg->runs, row_b, i, p->x_step, eq);
            if (prev_e > prev_b && (uint32_t)seg->runs[prev_b].y + p->y_step == seg->runs[row_b].y)
                connect_rows(seg->runs, prev_b, prev_e, row_b, i, p->x_step, eq);
            prev_b = row_b;
            prev_e = i;
            row_b = i;
        }
    }
    seg->n_runs = n;
    return finish(seg, img, p, &r, nx, eq, weak);
}

/* Steps 2-5, on the connected runs seg->runs[0, seg->n_runs) of the ROI r. */
static cyl_status finish(cyl_segmentation *seg, const cyl_image *img, const cyl_segment_params *p,
                         const cyl_roi *r, uint32_t nx, const uint8_t *eq, int weak)
{
    blob_acc *acc;
    cyl_run *runs = seg->runs;
    const uint32_t xs = p->x_step, ys = p->y_step, n_runs = seg->n_runs;
    uint32_t i, nb = 0, k;

    seg->n_blobs = 0;
    seg->x_step = (uint16_t)xs;
    seg->y_step = (uint16_t)ys;
    seg->x_origin = r->x;
    seg->y_origin = r->y;
    seg->x_last = r->x + (nx - 1u) * xs;
    seg->y_last = r->y + ((r->height - 1u) / ys) * ys;
    seg->frame_width = img->width;
    seg->frame_height = img->height;
    seg->min_run_px = p->min_run_px;
    for (k = 0; k < CYL_MAX_CLASSES; k++) seg->merge_gap_px[k] = p->cls[k].merge_gap_px;

    /* 2. labels, in one pass: each run's root (a parent's index is never larger than its run's,
     *    and every earlier run already points at its root, so one step reaches it), and the roots
     *    numbered in raster order. A run's label is parked in its `next` field (a root's first,
     *    read by the runs after it) until step 3 moves it to `blob`. */
    for (i = 0; i < n_runs; i++) {
        const uint32_t root = runs[runs[i].blob].blob;
        runs[i].blob = root;
        if (root == i) {
            if (nb < seg->max_blobs) runs[i].next = nb++;
            else { runs[i].next = CYL_NONE; seg->truncated |= CYL_SEG_BLOBS_FULL; }
        } else {
            runs[i].next = runs[root].next;
        }
    }

    /* 3. accumulate statistics and run lists */
    acc = (blob_acc *)seg->work;
    for (k = 0; k < nb; k++) {
        memset(&acc[k], 0, sizeof acc[k]);
        acc[k].alive = 1;
    }
    for (i = 0; i < n_runs; i++) {
        cyl_run *rn = &runs[i];
        uint32_t bi = rn->next, xe;
        cyl_blob *b;
        rn->blob = bi;
        rn->next = CYL_NONE;
        if (bi == CYL_NONE) continue;
        b = &seg->blobs[bi];
        xe = rn->x + (uint32_t)(rn->width - 1u) * xs;
        if (acc[bi].n == 0) {
            memset(b, 0, sizeof *b);
            b->cls = eq[rn->cls];
            b->n_components = 1;
            b->x0 = rn->x; b->x1 = (uint16_t)xe; b->y0 = rn->y; b->y1 = rn->y;
            b->first_run = i;
        } else {
            runs[acc[bi].last_run].next = i;
            if (rn->x < b->x0) b->x0 = rn->x;
            if (xe > b->x1) b->x1 = (uint16_t)xe;
            b->y1 = rn->y;
        }
        acc[bi].last_run = i;
        acc[bi].strong |= rn->cls == b->cls;
        b->n_runs++;
        acc_add_run(&acc[bi], rn, xs);
    }

    /* 4. merge nearby blobs of a class, finish, filter, compact, sort */
    merge_blobs(seg, acc, nb, p);
    k = 0;
    for (i = 0; i < nb; i++) {
        if (!acc[i].alive || acc[i].n < (int64_t)p->cls[seg->blobs[i].cls].min_area) continue;
        if (weak && !acc[i].strong) {   /* weak evidence alone is no blob, unless it is large */
            const uint32_t alone = p->cls[seg->blobs[i].cls].weak_alone_min_area;
            if (alone == 0 || acc[i].n < (int64_t)alone) continue;
        }
        if (k != i) seg->blobs[k] = seg->blobs[i];
        if (weak && !acc[i].strong) seg->blobs[k].flags |= CYL_BLOB_WEAK_ONLY;
        finish_blob(seg, &seg->blobs[k], &acc[i]);
        k++;
    }
    seg->n_blobs = k;
    sort_blobs(seg->blobs, k);

    /* 5. final labels */
    label_runs(seg);
    return seg->truncated ? CYL_TRUNCATED : CYL_OK;
}

/* ---- splitting at a waist ---------------------------------------------------- */

cyl_split_params cyl_split_params_default(void)
{
    cyl_split_params p;
    unsigned k;
    for (k = 0; k < CYL_MAX_CLASSES; k++) p.waist_ratio[k] = 0.0;
    p.axes = CYL_SPLIT_ROWS;
    p.min_part_lines = 4;
    p.min_part_share = 0.15;
    return p;
}

/* Sampled rows and columns of seg's grid (0 before a segmentation). */
static uint32_t grid_rows(const cyl_segmentation *seg)
{
    if (seg->y_step == 0 || seg->y_last < seg->y_origin) return 0;
    return (seg->y_last - seg->y_origin) / seg->y_step + 1u;
}

static uint32_t grid_cols(const cyl_segmentation *seg)
{
    if (seg->x_step == 0 || seg->x_last < seg->x_origin) return 0;
    return (seg->x_last - seg->x_origin) / seg->x_step + 1u;
}

size_t cyl_segment_split_work_size(const cyl_segmentation *seg)
{
    uint32_t rows, cols;
    if (!seg) return 0;
    rows = grid_rows(seg);
    cols = grid_cols(seg);
    /* two profiles of the longer axis, and the runs a column cut crosses (one a row at most) */
    return (2u * (size_t)(rows > cols ? rows : cols) + rows) * sizeof(uint32_t);
}

/* Statistics of the run list starting at first (CYL_NONE-terminated) into b (class and the flags
 * other than the touches kept). */
static void blob_from_runs(cyl_segmentation *seg, cyl_blob *b, uint32_t first)
{
    blob_acc a;
    uint32_t ri;
    const uint32_t xs = seg->x_step;
    memset(&a, 0, sizeof a);
    b->first_run = first;
    b->n_runs = 0;
    b->flags = (uint8_t)(b->flags & ~CYL_BLOB_TOUCH_ANY);
    b->x0 = 0xFFFFu; b->x1 = 0; b->y0 = seg->runs[first].y;
    for (ri = first; ri != CYL_NONE; ri = seg->runs[ri].next) {
        const cyl_run *r = &seg->runs[ri];
        const uint32_t xe = r->x + (uint32_t)(r->width - 1u) * xs;
        if (r->x < b->x0) b->x0 = r->x;
        if (xe > b->x1) b->x1 = (uint16_t)xe;
        b->y1 = r->y;
        b->n_runs++;
        acc_add_run(&a, r, xs);
    }
    finish_blob(seg, b, &a);
}

/* The waist of a profile ext[0..n-1] (0: no sample there, never a cut): the index j whose ext[j]
 * is the least share of m = min(widest before j, widest after j), below ratio, with at least
 * `need` entries on each side (ties: the first). 0 for none; *share_num / *share_den the share.
 * suf: n counters of workspace. */
static uint32_t profile_waist(const uint32_t *ext, uint32_t *suf, uint32_t n, uint32_t need, double ratio,
                              uint32_t *share_num, uint32_t *share_den)
{
    uint32_t j, best_j = 0, pre = 0, best_ext = 0, best_m = 0;
    if (need < 1u) need = 1u;
    if (n < 2u * need) return 0;
    suf[n - 1u] = ext[n - 1u];
    for (j = n - 1u; j-- > 0;) suf[j] = ext[j] > suf[j + 1u] ? ext[j] : suf[j + 1u];
    for (j = 0; j + need <= n; j++) {
        if (j >= need) {
            const uint32_t after = j + 1u < n ? suf[j + 1u] : 0u;
            const uint32_t m = pre < after ? pre : after;
            /* below the ratio, and the least share so far (compared exactly: on a tie the
             * first stays) */
            if (m > 0 && ext[j] > 0 && (double)ext[j] < ratio * (double)m &&
                (best_j == 0 || (uint64_t)ext[j] * best_m < (uint64_t)best_ext * m)) {
                best_ext = ext[j];
                best_m = m;
                best_j = j;
            }
        }
        if (ext[j] > pre) pre = ext[j];
    }
    *share_num = best_ext;
    *share_den = best_m;
    return best_j;
}

/* Entries each part keeps along an axis of n entries. */
static uint32_t part_need(const cyl_split_params *p, uint32_t n)
{
    uint32_t need = (uint32_t)ceil(p->min_part_share * (double)n);
    return need < p->min_part_lines ? p->min_part_lines : need;
}

/* Blob b's row profile: each sampled row's extent, first sample of its first run to last sample
 * of its last run, in samples (0 where the blob has no run in the row: the gap between merged
 * pieces). Returns the rows. */
static uint32_t row_profile(const cyl_segmentation *seg, const cyl_blob *b, uint32_t *ext)
{
    const uint32_t ys = seg->y_step, xs = seg->x_step;
    const uint32_t rows = (uint32_t)(b->y1 - b->y0) / ys + 1u;
    uint32_t j, ri, lo = 0, row = CYL_NONE;
    for (j = 0; j < rows; j++) ext[j] = 0;
    for (ri = b->first_run; ri != CYL_NONE; ri = seg->runs[ri].next) {
        const cyl_run *r = &seg->runs[ri];
        const uint32_t jr = (uint32_t)(r->y - b->y0) / ys;
        if (jr != row) { row = jr; lo = r->x; }
        ext[jr] = (r->x - lo) / xs + r->width;   /* runs of a row come in x order */
    }
    return rows;
}

/* Blob b's column profile: each sampled column's extent, its first to its last sampled row with
 * a sample, in rows (0 where the column has none). top: workspace of the columns. */
static uint32_t col_profile(const cyl_segmentation *seg, const cyl_blob *b, uint32_t *ext, uint32_t *top)
{
    const uint32_t ys = seg->y_step, xs = seg->x_step;
    const uint32_t cols = (uint32_t)(b->x1 - b->x0) / xs + 1u;
    uint32_t j, ri;
    for (j = 0; j < cols; j++) ext[j] = 0;
    for (ri = b->first_run; ri != CYL_NONE; ri = seg->runs[ri].next) {
        const cyl_run *r = &seg->runs[ri];
        const uint32_t j0 = (uint32_t)(r->x - b->x0) / xs, jy = (uint32_t)(r->y - b->y0) / ys;
        for (j = j0; j < j0 + r->width; j++) {
            if (ext[j] == 0) top[j] = jy;   /* rows come in order: the first is the top */
            ext[j] = jy - top[j] + 1u;
        }
    }
    return cols;
}

/* Cut blob b's run list before row `cut` (image y): b keeps the rows above, the rows from `cut`
 * on start the list returned. */
static uint32_t cut_rows(cyl_segmentation *seg, const cyl_blob *b, uint32_t cut)
{
    uint32_t ri, prev = CYL_NONE;
    /* both parts have rows (the waist's limits), so the cut lies strictly inside the list */
    for (ri = b->first_run; seg->runs[ri].y < cut; ri = seg->runs[ri].next) prev = ri;
    seg->runs[prev].next = CYL_NONE;
    return ri;
}

/* Index of run `old` after inserting one run after each run of cross[0..nc-1] (ascending). */
static uint32_t shifted(const uint32_t *cross, uint32_t nc, uint32_t old)
{
    uint32_t lo = 0, hi = nc;   /* count the crossings below old */
    if (old == CYL_NONE) return old;
    while (lo < hi) {
        const uint32_t mid = lo + (hi - lo) / 2u;
        if (cross[mid] < old) lo = mid + 1u; else hi = mid;
    }
    return old + lo;
}

/* Cut blob b's runs before column `cut` (image x): the runs that cross it are split in two, the
 * new right pieces inserted in the run array after their left pieces (the array stays in (y, x)
 * order; every index in seg is renumbered). b keeps the left samples; returns the first run of the
 * right ones. CYL_NONE, with nothing changed, when the run array is full. cross: workspace of the
 * blob's rows. */
static uint32_t cut_cols(cyl_segmentation *seg, cyl_blob *b, uint32_t cut, uint32_t *cross)
{
    const uint32_t xs = seg->x_step;
    uint32_t nc = 0, ri, i, k, left_tail = CYL_NONE, right_first = CYL_NONE, right_tail = CYL_NONE, left_first = CYL_NONE;
    for (ri = b->first_run; ri != CYL_NONE; ri = seg->runs[ri].next) {
        const cyl_run *r = &seg->runs[ri];
        if (r->x < cut && r->x + (uint32_t)(r->width - 1u) * xs >= cut) cross[nc++] = ri;
    }
    if (seg->n_runs + nc > seg->max_runs) return CYL_NONE;
    /* open a slot after each crossing run: move the runs above the first one up, from the top,
     * then renumber (none crosses when every run meeting the cut starts at it) */
    if (nc) {
        for (i = seg->n_runs; i-- > cross[0] + 1u;) seg->runs[shifted(cross, nc, i)] = seg->runs[i];
        seg->n_runs += nc;
        for (i = 0; i < seg->n_runs; i++) seg->runs[i].next = shifted(cross, nc, seg->runs[i].next);
        for (k = 0; k < seg->n_blobs; k++) seg->blobs[k].first_run = shifted(cross, nc, seg->blobs[k].first_run);
    }
    for (k = 0; k < nc; k++) cross[k] += k;   /* their new places (the slot is at +1) */
    /* deal the runs out, in order, to two lists; a crossing run's right piece takes its slot */
    for (ri = b->first_run, k = 0; ri != CYL_NONE;) {
        cyl_run *r = &seg->runs[ri];
        const uint32_t next = r->next;
        uint32_t to_left = CYL_NONE, to_right = CYL_NONE;
        if (k < nc && cross[k] == ri) {
            cyl_run *q = &seg->runs[ri + 1u];
            const uint16_t w_left = (uint16_t)((cut - r->x) / xs);
            *q = *r;
            q->x = (uint16_t)cut;
            q->width = (uint16_t)(r->width - w_left);
            r->width = w_left;
            to_left = ri;
            to_right = ri + 1u;
            k++;
        } else if (r->x < cut) {
            to_left = ri;
        } else {
            to_right = ri;
        }
        if (to_left != CYL_NONE) {
            if (left_tail == CYL_NONE) left_first = to_left; else seg->runs[left_tail].next = to_left;
            left_tail = to_left;
        }
        if (to_right != CYL_NONE) {
            if (right_tail == CYL_NONE) right_first = to_right; else seg->runs[right_tail].next = to_right;
            right_tail = to_right;
        }
        ri = next;
    }
    seg->runs[left_tail].next = CYL_NONE;
    seg->runs[right_tail].next = CYL_NONE;
    b->first_run = left_first;
    return right_first;
}

cyl_status cyl_segment_split(cyl_segmentation *seg, const cyl_split_params *p, void *work, size_t work_size,
                             uint32_t *n_split)
{
    uint32_t i = 0, k, cuts = 0, full = 0;
    uint32_t *prof, *aux, *cross;
    int any = 0;
    if (n_split) *n_split = 0;
    if (!seg || !p || !seg->runs || !seg->blobs) return CYL_ERR_ARG;
    if (!(p->min_part_share >= 0.0 && p->min_part_share <= 0.5)) return CYL_ERR_ARG;
    if (p->axes == 0 || (p->axes & ~(unsigned)(CYL_SPLIT_ROWS | CYL_SPLIT_COLUMNS))) return CYL_ERR_ARG;
    for (k = 0; k < CYL_MAX_CLASSES; k++) {
        if (!(p->waist_ratio[k] >= 0.0 && p->waist_ratio[k] <= 1.0)) return CYL_ERR_ARG;
        any |= p->waist_ratio[k] > 0.0;
    }
    if (!any || seg->n_blobs == 0) return CYL_OK;
    if (!work || work_size < cyl_segment_split_work_size(seg)) return CYL_ERR_SIZE;
    {
        const uint32_t rows = grid_rows(seg), cols = grid_cols(seg), n = rows > cols ? rows : cols;
        prof = (uint32_t *)work;
        aux = prof + n;
        cross = aux + n;
    }
    /* a blob that was cut is examined again (its first part), and the second parts appended at
     * the end in turn: a part may have a waist of its own */
    while (i < seg->n_blobs) {
        cyl_blob *b = &seg->blobs[i];
        const double ratio = p->waist_ratio[b->cls];
        uint32_t jr = 0, jc = 0, rn = 0, rd = 1, cn = 0, cd = 1, second = CYL_NONE;
        if (ratio > 0.0 && (p->axes & CYL_SPLIT_ROWS)) {
            const uint32_t n = row_profile(seg, b, prof);
            jr = profile_waist(prof, aux, n, part_need(p, n), ratio, &rn, &rd);
        }
        if (ratio > 0.0 && (p->axes & CYL_SPLIT_COLUMNS)) {
            const uint32_t n = col_profile(seg, b, prof, aux);
            jc = profile_waist(prof, aux, n, part_need(p, n), ratio, &cn, &cd);
        }
        if (jr && jc) {   /* both axes have a waist: the narrower share (rows on a tie) */
            if ((uint64_t)cn * rd < (uint64_t)rn * cd) jr = 0; else jc = 0;
        }
        if ((!jr && !jc) || seg->n_blobs >= seg->max_blobs) {
            full |= (jr || jc) ? CYL_SEG_BLOBS_FULL : 0u;
            i++;
            continue;
        }
        if (jr) {
            second = cut_rows(seg, b, b->y0 + jr * seg->y_step);
        } else {
            second = cut_cols(seg, b, b->x0 + jc * seg->x_step, cross);
            if (second == CYL_NONE) {   /* no room for the split runs */
                full |= CYL_SEG_RUNS_FULL;
                i++;
                continue;
            }
        }
        {
            cyl_blob *nb = &seg->blobs[seg->n_blobs++];
            *nb = *b;
            nb->flags |= CYL_BLOB_SPLIT;
            blob_from_runs(seg, nb, second);
        }
        b->flags |= CYL_BLOB_SPLIT;
        blob_from_runs(seg, b, b->first_run);
        cuts++;
    }
    if (cuts) {
        sort_blobs(seg->blobs, seg->n_blobs);
        label_runs(seg);
    }
    if (n_split) *n_split = cuts;
    if (full) {
        seg->truncated |= full;
        return CYL_TRUNCATED;
    }
    return CYL_OK;
}
