/* SPDX-License-Identifier: BSD-3-Clause */
/* Learning colour classes as likelihood ratios over the 3-D table (cyl/colorlearn.h). */
#include "cyl/colorlearn.h"
#include "cyl/config.h"
#include "internal.h"
#include <math.h>
#include <string.h>

#define K CYL_YUV_CELLS
#define NC CYL_YUV_NC
#define NY CYL_YUV_NY
#define MAX_RADIUS 6

void cyl_colorhist_clear(cyl_colorhist *h)
{
    if (h) memset(h, 0, sizeof *h);
}

#if CYL_CONFIG_LEARN
static double clip_channel(double x)
{
    return x < 0.0 ? 0.0 : (x > 255.0 ? 255.0 : x);
}

/* x rounded to the nearest level and clipped to 0..255 */
static uint8_t clip_level(double x)
{
    if (!(x > 0.0)) return 0;
    if (x > 255.0) return 255;
    return (uint8_t)floor(x + 0.5);
}

/* A colour as it would be under the channel gains g (red, green, blue) with white levels added to
 * each channel. Equal gains and no white light scale Y and
 * the chroma offsets (exposure); otherwise through R, G, B (BT.601 full range), each channel
 * clipped as a sensor would. */
static void map_colour(uint8_t *Y, uint8_t *U, uint8_t *V, const double g[3], double white)
{
    if (g[0] == g[1] && g[1] == g[2] && white == 0.0) {
        if (g[0] == 1.0) return;
        *Y = clip_level(g[0] * (double)*Y);
        *U = clip_level(128.0 + g[0] * ((double)*U - 128.0));
        *V = clip_level(128.0 + g[0] * ((double)*V - 128.0));
    } else {
        const double u = (double)*U - 128.0, v = (double)*V - 128.0;
        const double R = clip_channel(g[0] * ((double)*Y + 1.402 * v) + white);
        const double G = clip_channel(g[1] * ((double)*Y - 0.344136 * u - 0.714136 * v) + white);
        const double B = clip_channel(g[2] * ((double)*Y + 1.772 * u) + white);
        const double Yo = 0.299 * R + 0.587 * G + 0.114 * B;
        *Y = clip_level(Yo);
        *U = clip_level(128.0 + (B - Yo) / 1.772);
        *V = clip_level(128.0 + (R - Yo) / 1.402);
    }
}

cyl_status cyl_colorhist_add(cyl_colorhist *h, const cyl_image *img, const cyl_roi *roi,
                             const uint8_t *mask, size_t mask_stride, uint8_t mask_value)
{
    const double one[3] = { 1.0, 1.0, 1.0 };
    return cyl_colorhist_add_light(h, img, roi, mask, mask_stride, mask_value, one, 0.0);
}

cyl_status cyl_colorhist_add_scaled(cyl_colorhist *h, const cyl_image *img, const cyl_roi *roi,
                                    const uint8_t *mask, size_t mask_stride, uint8_t mask_value,
                                    double gain)
{
    const double g[3] = { gain, gain, gain };
    return cyl_colorhist_add_light(h, img, roi, mask, mask_stride, mask_value, g, 0.0);
}

cyl_status cyl_colorhist_add_light(cyl_colorhist *h, const cyl_image *img, const cyl_roi *roi,
                                   const uint8_t *mask, size_t mask_stride, uint8_t mask_value,
                                   const double gain_rgb[3], double white_add)
{
    cyl_roi r;
    uint32_t x, y;
    cyl_status s;
    unsigned k;
    if (!h || !gain_rgb) return CYL_ERR_ARG;
    for (k = 0; k < 3; k++)
        if (!(gain_rgb[k] > 0.0 && gain_rgb[k] <= 16.0)) return CYL_ERR_ARG;
    if (!(white_add >= -255.0 && white_add <= 255.0)) return CYL_ERR_ARG;
    s = cyl_image_check(img);
    if (s != CYL_OK) return s;
    if (mask && mask_stride < img->width) return CYL_ERR_SIZE;
    if (!cyl_roi_resolve(img, roi, &r)) return CYL_ERR_SIZE;
    for (y = r.y; y < r.y + r.height; y++) {
        const uint8_t *m = mask ? mask + (size_t)y * mask_stride : NULL;
        for (x = r.x; x < r.x + r.width; x++) {
            uint8_t Y, U, V;
            uint32_t *c;
            if (m && m[x] != mask_value) continue;
            cyl_pixel_fetch(img, x, y, &Y, &U, &V);
            map_colour(&Y, &U, &V, gain_rgb, white_add);
            c = &h->count[cyl_yuv_cell(Y, U, V)];
            if (*c != UINT32_MAX) { (*c)++; h->total++; }
        }
    }
    return CYL_OK;
}

#else /* CYL_CONFIG_LEARN */

cyl_status cyl_colorhist_add_scaled(cyl_colorhist *h, const cyl_image *img, const cyl_roi *roi,
                                    const uint8_t *mask, size_t mask_stride, uint8_t mask_value,
                                    double gain)
{
    (void)h; (void)img; (void)roi; (void)mask; (void)mask_stride; (void)mask_value; (void)gain;
    return CYL_ERR_UNSUPPORTED;
}

cyl_status cyl_colorhist_add_light(cyl_colorhist *h, const cyl_image *img, const cyl_roi *roi,
                                   const uint8_t *mask, size_t mask_stride, uint8_t mask_value,
                                   const double gain_rgb[3], double white_add)
{
    (void)h; (void)img; (void)roi; (void)mask; (void)mask_stride; (void)mask_value; (void)gain_rgb;
    (void)white_add;
    return CYL_ERR_UNSUPPORTED;
}

cyl_status cyl_colorhist_add(cyl_colorhist *h, const cyl_image *img, const cyl_roi *roi,
                             const uint8_t *mask, size_t mask_stride, uint8_t mask_value)
{
    (void)h; (void)img; (void)roi; (void)mask; (void)mask_stride; (void)mask_value;
    return CYL_ERR_UNSUPPORTED;
}
#endif /* CYL_CONFIG_LEARN */

cyl_learn_params cyl_learn_params_default(void)
{
    cyl_learn_params p;
    p.max_bg_fraction = 0.0005;
    p.smooth_sigma_cells = 1.5;
    p.bg_uniform_weight = 0.02;
    p.min_likelihood_ratio = 4.0;
    p.min_positive_count = 0.5;
    p.weak_bg_fraction = 0.01;
    p.min_weak_ratio = 1.5;
    p.min_class_share = 0.0;
    p.surround_weight = 0.5;
    return p;
}

size_t cyl_learn_workspace_size(unsigned n)
{
    /* background density, scratch, one likelihood-ratio array per class */
    return ((size_t)n + 2u) * K * sizeof(float);
}

#if CYL_CONFIG_LEARN

/* Gaussian smoothing of a K-cell array along one axis (in place). stride: cells
 * between neighbours on the axis; len: cells on it; outer/inner: how the other
 * two axes are walked. */
static void smooth_axis(float *a, unsigned len, size_t stride, const float *kern, int rad)
{
    float line[NC > NY ? NC : NY];
    size_t base;
    unsigned i;
    int k;
    for (base = 0; base < K; base++) {
        /* base must be the first cell of a line: its coordinate on the axis is 0 */
        if ((base / stride) % len != 0) continue;
        for (i = 0; i < len; i++) line[i] = a[base + i * stride];
        for (i = 0; i < len; i++) {
            float acc = 0.0f;
            for (k = -rad; k <= rad; k++) {
                int j = (int)i + k;
                if (j < 0 || j >= (int)len) continue;
                acc += kern[k + rad] * line[j];
            }
            a[base + i * stride] = acc;
        }
    }
}

/* Smoothed density of a histogram: counts convolved with a separable Gaussian,
 * in pixels (not normalised). */
static void smoothed(const cyl_colorhist *h, float *out, double sigma)
{
    float kern[2 * MAX_RADIUS + 1];
    int rad = 0, k;
    unsigned i;
    for (i = 0; i < K; i++) out[i] = (float)h->count[i];
    if (!(sigma > 0.0)) return;
    rad = (int)ceil(3.0 * sigma);
    if (rad > MAX_RADIUS) rad = MAX_RADIUS;
    {
        double sum = 0.0;
        for (k = -rad; k <= rad; k++) sum += exp(-0.5 * (double)(k * k) / (sigma * sigma));
        for (k = -rad; k <= rad; k++)
            kern[k + rad] = (float)(exp(-0.5 * (double)(k * k) / (sigma * sigma)) / sum);
    }
    smooth_axis(out, NC, 1u, kern, rad);                 /* V */
    smooth_axis(out, NC, NC, kern, rad);                 /* U */
    smooth_axis(out, NY, (size_t)NC * NC, kern, rad);    /* Y */
}

/* Background density claimed by cells with ratio > thr. */
static double claimed_bg(const float *lr, const float *bg, float thr)
{
    double s = 0.0;
    unsigned i;
    for (i = 0; i < K; i++)
        if (lr[i] > thr) s += bg[i];
    return s;
}

/* Lowest threshold >= floor whose claimed background stays within rate (claimed_bg
 * falls as the threshold rises: bisection in log space). Cells strictly above it are
 * claimed. */
static float rate_threshold(const float *L, const float *bg, double floor_ratio, double maxlr, double rate)
{
    double lo = floor_ratio > 1e-30 ? floor_ratio : 1e-30, hi;
    int it;
    float thr;
    if (claimed_bg(L, bg, (float)lo) <= rate || lo >= maxlr) {
        thr = (float)lo;
    } else {
        lo = log(lo);
        hi = log(maxlr);
        for (it = 0; it < 60; it++) {
            double mid = 0.5 * (lo + hi);
            if (claimed_bg(L, bg, (float)exp(mid)) <= rate) hi = mid;
            else lo = mid;
        }
        thr = (float)exp(hi);
    }
    /* a threshold at the floor keeps the cells at the floor itself */
    if ((double)thr <= floor_ratio) thr = (float)(floor_ratio * (1.0 - 1e-6));
    return thr;
}

/* Share of a class's (raw) training pixels in the cells with ratio > thr. */
static double class_share(const float *L, const cyl_colorhist *pos, float thr)
{
    uint64_t k = 0;
    unsigned c;
    for (c = 0; c < K; c++)
        if (L[c] > thr) k += pos->count[c];
    return (double)k / (double)pos->total;
}

static void set_cells(cyl_colortable *t, unsigned cls, const float *L, float lo, float hi)
{
    const cyl_mask bit = (cyl_mask)(1u << cls);
    cyl_mask *cell = &t->yuv[0][0][0];
    unsigned u, v, yv, c;
    cyl_colortable_clear_class(t, cls);
    for (yv = 0; yv < 256; yv++) t->y[yv] |= bit;
    for (c = 0; c < K; c++)
        if (!(L[c] > lo && L[c] <= hi)) cell[c] &= (cyl_mask)~bit;
    for (u = 0; u < NC; u++)
        for (v = 0; v < NC; v++) {
            int any = 0;
            unsigned yc, du, dv;
            for (yc = 0; yc < NY && !any; yc++) any = (t->yuv[yc][u][v] & bit) != 0;
            if (!any) continue;
            for (du = 0; du < (1u << CYL_YUV_CSHIFT); du++)
                for (dv = 0; dv < (1u << CYL_YUV_CSHIFT); dv++)
                    t->uv[(u << CYL_YUV_CSHIFT) + du][(v << CYL_YUV_CSHIFT) + dv] |= bit;
        }
}

cyl_status cyl_colortable_learn(cyl_colortable *t, const cyl_learn_class *classes, unsigned n,
                                const cyl_colorhist *negative, const cyl_learn_params *params,
                                void *work, size_t work_size, cyl_learn_report *reports)
{
    cyl_learn_params p = params ? *params : cyl_learn_params_default();
    float *bg, *tmp, *lr[CYL_MAX_CLASSES];
    float thr[CYL_MAX_CLASSES], wthr[CYL_MAX_CLASSES];
    unsigned i, j, c, used = 0;
    double eps, nneg;

    if (!t || !classes || !negative || n == 0) return CYL_ERR_ARG;
    if (n > CYL_MAX_CLASSES) return CYL_ERR_ARG;
    if (!(p.max_bg_fraction >= 0.0 && p.max_bg_fraction <= 1.0) ||
        !(p.smooth_sigma_cells >= 0.0 && p.smooth_sigma_cells <= 2.0) ||
        !(p.bg_uniform_weight >= 0.0 && p.bg_uniform_weight <= 1.0) ||
        !(p.min_likelihood_ratio >= 0.0 && p.min_likelihood_ratio < 1e30) ||
        !(p.min_positive_count >= 0.0 && p.min_positive_count < 1e30) ||
        !(p.weak_bg_fraction >= p.max_bg_fraction && p.weak_bg_fraction <= 1.0) ||
        !(p.min_weak_ratio >= 0.0 && p.min_weak_ratio <= p.min_likelihood_ratio) ||
        !(p.min_class_share >= 0.0 && p.min_class_share <= 1.0) ||
        !(p.surround_weight >= 0.0 && p.surround_weight <= 4.0))
        return CYL_ERR_ARG;
    for (i = 0; i < n; i++) {
        const cyl_learn_class *k = &classes[i];
        if (k->cls >= CYL_MAX_CLASSES) return CYL_ERR_CLASS;
        if (k->weak_cls >= CYL_MAX_CLASSES && k->weak_cls != CYL_CLASS_NONE) return CYL_ERR_CLASS;
        if (!k->positive) return CYL_ERR_ARG;
        if (used & (1u << k->cls)) return CYL_ERR_ARG;
        used |= 1u << k->cls;
        if (k->weak_cls != CYL_CLASS_NONE) {
            if (used & (1u << k->weak_cls)) return CYL_ERR_ARG;
            used |= 1u << k->weak_cls;
        }
    }
    /* a class not learned here must not be the weak evidence of one that is (its
     * relation would dangle), nor have one of these as its weak class */
    for (j = 0; j < CYL_MAX_CLASSES; j++) {
        unsigned w = t->weak_of[j];
        if (used & (1u << j)) continue;
        if (w < CYL_MAX_CLASSES && (used & (1u << w))) return CYL_ERR_ARG;
    }
    if (!work) return CYL_ERR_ARG;
    if (work_size < cyl_learn_workspace_size(n) || ((uintptr_t)work % sizeof(float)) != 0)
        return CYL_ERR_NOMEM;
    if (negative->total == 0) return CYL_ERR_EMPTY;
    for (i = 0; i < n; i++)
        if (classes[i].positive->total == 0) return CYL_ERR_EMPTY;

    bg = (float *)work;
    tmp = bg + K;
    for (i = 0; i < n; i++) lr[i] = tmp + (size_t)(i + 1u) * K;

    /* Background density per cell, with the uniform part. */
    smoothed(negative, bg, p.smooth_sigma_cells);
    nneg = (double)negative->total;
    eps = p.bg_uniform_weight;
    for (c = 0; c < K; c++)
        bg[c] = (float)((1.0 - eps) * (double)bg[c] / nneg + eps / (double)K);

    /* Per class: likelihood ratio, then the thresholds the false-positive rates allow. */
    for (i = 0; i < n; i++) {
        const cyl_colorhist *pos = classes[i].positive;
        double npos = (double)pos->total, maxlr = 0.0;
        double floor_ratio = classes[i].weak_cls != CYL_CLASS_NONE ? p.min_weak_ratio : p.min_likelihood_ratio;
        float *L = lr[i];
        uint32_t kept = 0;
        smoothed(pos, L, p.smooth_sigma_cells);
        if (classes[i].surround && classes[i].surround->total > 0 && p.surround_weight > 0.0) {
            /* take out what the boxes share with their surround, scaled to the boxes' pixels;
               the density stays per box pixel (npos), so the ratio floors keep their meaning */
            const double scale = p.surround_weight * npos / (double)classes[i].surround->total;
            double left = 0.0;
            smoothed(classes[i].surround, tmp, p.smooth_sigma_cells);
            for (c = 0; c < K; c++) {
                double v = (double)L[c] - scale * (double)tmp[c];
                L[c] = v > 0.0 ? (float)v : 0.0f;
                left += (double)L[c];
            }
            if (!(left > 0.0)) return CYL_ERR_EMPTY;
        }
        for (c = 0; c < K; c++) {
            double cnt = (double)L[c], v = 0.0;
            if (cnt >= p.min_positive_count && cnt > 0.0) {
                /* no background density at all (only without the uniform part): certain */
                v = bg[c] > 0.0f ? (cnt / npos) / (double)bg[c] : 1e30;
                if (v < floor_ratio) v = 0.0;
            }
            L[c] = (float)v;
            if (v > maxlr) maxlr = v;
        }
        if (maxlr <= 0.0) return CYL_ERR_EMPTY;
        thr[i] = rate_threshold(L, bg, p.min_likelihood_ratio, maxlr, p.max_bg_fraction);
        if (p.min_class_share > 0.0 && class_share(L, pos, thr[i]) < p.min_class_share) {
            /* lower the threshold (bisection in log space) until the class keeps its share */
            double lo = log(p.min_likelihood_ratio > 1e-30 ? p.min_likelihood_ratio : 1e-30), hi = log((double)thr[i]);
            int it;
            if (class_share(L, pos, (float)exp(lo)) < p.min_class_share) {
                thr[i] = (float)(exp(lo) * (1.0 - 1e-6));
            } else {
                for (it = 0; it < 60; it++) {
                    double mid = 0.5 * (lo + hi);
                    if (class_share(L, pos, (float)exp(mid)) >= p.min_class_share) lo = mid;
                    else hi = mid;
                }
                thr[i] = (float)exp(lo);
            }
        }
        wthr[i] = classes[i].weak_cls != CYL_CLASS_NONE
                      ? rate_threshold(L, bg, p.min_weak_ratio, maxlr, p.weak_bg_fraction) : thr[i];
        if (wthr[i] > thr[i]) wthr[i] = thr[i];
        for (c = 0; c < K; c++) kept += L[c] > thr[i];
        if (kept == 0) return CYL_ERR_EMPTY;
    }

    /* Reports before resolution, then resolution: a cell claimed by several keeps the
     * class with the largest ratio among those claiming it as their own, else among the
     * weak claims. Losers' ratios become 0. */
    if (reports) {
        for (i = 0; i < n; i++) {
            cyl_learn_report *r = &reports[i];
            uint64_t alone = 0;
            memset(r, 0, sizeof *r);
            r->lr_threshold = thr[i];
            r->weak_lr_threshold = classes[i].weak_cls != CYL_CLASS_NONE ? wthr[i] : 0.0;
            for (c = 0; c < K; c++)
                if (lr[i][c] > thr[i]) alone += classes[i].positive->count[c];
            r->recall_alone = (double)alone / (double)classes[i].positive->total;
        }
    }
    for (c = 0; c < K; c++) {
        unsigned best = n;
        float bestv = 0.0f;
        int strong = 0;
        for (i = 0; i < n; i++) {
            const float v = lr[i][c];
            const int s_i = v > thr[i];
            if (!(v > wthr[i])) continue;
            if (best == n || s_i > strong || (s_i == strong && v > bestv)) { best = i; bestv = v; strong = s_i; }
        }
        if (best == n) continue;
        for (i = 0; i < n; i++) {
            if (i == best || !(lr[i][c] > wthr[i])) continue;
            if (reports && lr[i][c] > thr[i]) reports[i].lost_to[classes[best].cls] += (double)classes[i].positive->count[c];
            lr[i][c] = 0.0f;
        }
    }

    /* Write the classes into the table. */
    for (i = 0; i < n; i++) {
        const unsigned w = classes[i].weak_cls;
        set_cells(t, classes[i].cls, lr[i], thr[i], 3.4e38f);
        cyl_colortable_set_weak(t, classes[i].cls, CYL_CLASS_NONE);
        if (w != CYL_CLASS_NONE) {
            set_cells(t, w, lr[i], wthr[i], thr[i]);
            cyl_colortable_set_weak(t, w, CYL_CLASS_NONE);
        }
    }
    for (i = 0; i < n; i++)
        if (classes[i].weak_cls != CYL_CLASS_NONE) cyl_colortable_set_weak(t, classes[i].weak_cls, classes[i].cls);
    cyl_colortable_refresh(t);

    if (reports) {
        for (i = 0; i < n; i++) {
            cyl_learn_report *r = &reports[i];
            const cyl_colorhist *pos = classes[i].positive;
            uint64_t kept_pos = 0, kept_neg = 0, weak_pos = 0, weak_neg = 0;
            uint32_t cells = 0, grey = 0, wcells = 0;
            for (c = 0; c < K; c++) {
                unsigned u, v;
                if (lr[i][c] > thr[i]) {
                    cells++;
                    kept_pos += pos->count[c];
                    kept_neg += negative->count[c];
                    u = (c / NC) % NC;
                    v = c % NC;
                    {
                        /* cell centre in 8-bit chroma */
                        double uc = (u + 0.5) * (1u << CYL_YUV_CSHIFT), vc = (v + 0.5) * (1u << CYL_YUV_CSHIFT);
                        if (fabs(uc - 128.0) <= 8.0 && fabs(vc - 128.0) <= 8.0) grey++;
                    }
                } else if (classes[i].weak_cls != CYL_CLASS_NONE && lr[i][c] > wthr[i]) {
                    wcells++;
                    weak_pos += pos->count[c];
                    weak_neg += negative->count[c];
                }
            }
            r->cells = cells;
            r->recall = (double)kept_pos / (double)pos->total;
            r->bg_fraction = (double)kept_neg / nneg;
            r->grey_fraction = cells ? (double)grey / (double)cells : 0.0;
            r->weak_cells = wcells;
            r->weak_recall = (double)weak_pos / (double)pos->total;
            r->weak_bg_fraction = (double)weak_neg / nneg;
            for (j = 0; j < CYL_MAX_CLASSES; j++) r->lost_to[j] /= (double)pos->total;
        }
    }
    return CYL_OK;
}

#else /* CYL_CONFIG_LEARN */

cyl_status cyl_colortable_learn(cyl_colortable *t, const cyl_learn_class *classes, unsigned n,
                                const cyl_colorhist *negative, const cyl_learn_params *params,
                                void *work, size_t work_size, cyl_learn_report *reports)
{
    (void)t; (void)classes; (void)n; (void)negative; (void)params; (void)work; (void)work_size; (void)reports;
    return CYL_ERR_UNSUPPORTED;
}
#endif
