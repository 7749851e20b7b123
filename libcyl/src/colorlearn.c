/* SPDX-License-Identifier: BSD-3-Clause */
/* Learning colour classes as likelihood ratios over the 3-D table (cyl/colorlearn.h). */
#include "cyl/colorlearn.h"
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

cyl_status cyl_colorhist_add(cyl_colorhist *h, const cyl_image *img, const cyl_roi *roi,
                             const uint8_t *mask, size_t mask_stride, uint8_t mask_value)
{
    cyl_roi r;
    uint32_t x, y;
    cyl_status s;
    if (!h) return CYL_ERR_ARG;
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
            c = &h->count[cyl_yuv_cell(Y, U, V)];
            if (*c != UINT32_MAX) { (*c)++; h->total++; }
        }
    }
    return CYL_OK;
}

cyl_learn_params cyl_learn_params_default(void)
{
    cyl_learn_params p;
    p.max_bg_fraction = 0.001;
    p.smooth_sigma_cells = 1.0;
    p.bg_uniform_weight = 0.02;
    p.min_likelihood_ratio = 4.0;
    p.min_positive_count = 0.5;
    return p;
}

size_t cyl_learn_workspace_size(unsigned n)
{
    /* background density, scratch, one likelihood-ratio array per class */
    return ((size_t)n + 2u) * K * sizeof(float);
}

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

cyl_status cyl_colortable_learn(cyl_colortable *t, const unsigned *cls,
                                const cyl_colorhist *const *positive, unsigned n,
                                const cyl_colorhist *negative, const cyl_learn_params *params,
                                void *work, size_t work_size, cyl_learn_report *reports)
{
    cyl_learn_params p = params ? *params : cyl_learn_params_default();
    float *bg, *tmp, *lr[CYL_MAX_CLASSES];
    float thr[CYL_MAX_CLASSES];
    unsigned i, j, c;
    double eps, nneg;

    if (!t || !cls || !positive || !negative || n == 0) return CYL_ERR_ARG;
    if (n > CYL_MAX_CLASSES) return CYL_ERR_ARG;
    if (!(p.max_bg_fraction >= 0.0 && p.max_bg_fraction <= 1.0) ||
        !(p.smooth_sigma_cells >= 0.0 && p.smooth_sigma_cells <= 2.0) ||
        !(p.bg_uniform_weight >= 0.0 && p.bg_uniform_weight <= 1.0) ||
        !(p.min_likelihood_ratio >= 0.0 && p.min_likelihood_ratio < 1e30) ||
        !(p.min_positive_count >= 0.0 && p.min_positive_count < 1e30))
        return CYL_ERR_ARG;
    for (i = 0; i < n; i++) {
        if (cls[i] >= CYL_MAX_CLASSES) return CYL_ERR_CLASS;
        if (!positive[i]) return CYL_ERR_ARG;
        for (j = 0; j < i; j++)
            if (cls[j] == cls[i]) return CYL_ERR_ARG;
    }
    if (!work) return CYL_ERR_ARG;
    if (work_size < cyl_learn_workspace_size(n) || ((uintptr_t)work % sizeof(float)) != 0)
        return CYL_ERR_NOMEM;
    if (negative->total == 0) return CYL_ERR_EMPTY;
    for (i = 0; i < n; i++)
        if (positive[i]->total == 0) return CYL_ERR_EMPTY;

    bg = (float *)work;
    tmp = bg + K;
    for (i = 0; i < n; i++) lr[i] = tmp + (size_t)(i + 1u) * K;

    /* Background density per cell, with the uniform part. */
    smoothed(negative, bg, p.smooth_sigma_cells);
    nneg = (double)negative->total;
    eps = p.bg_uniform_weight;
    for (c = 0; c < K; c++)
        bg[c] = (float)((1.0 - eps) * (double)bg[c] / nneg + eps / (double)K);

    /* Per class: likelihood ratio, then the threshold the false-positive rate allows. */
    for (i = 0; i < n; i++) {
        double npos = (double)positive[i]->total, lo, hi, maxlr = 0.0;
        float *L = lr[i];
        int it;
        smoothed(positive[i], L, p.smooth_sigma_cells);
        for (c = 0; c < K; c++) {
            double cnt = (double)L[c], v = 0.0;
            if (cnt >= p.min_positive_count && cnt > 0.0) {
                /* no background density at all (only without the uniform part): certain */
                v = bg[c] > 0.0f ? (cnt / npos) / (double)bg[c] : 1e30;
                if (v < p.min_likelihood_ratio) v = 0.0;
            }
            L[c] = (float)v;
            if (v > maxlr) maxlr = v;
        }
        if (maxlr <= 0.0) return CYL_ERR_EMPTY;
        /* Lowest threshold (>= min ratio) whose claimed background stays within the rate:
         * claimed_bg falls as the threshold rises; bisect in log space. */
        lo = p.min_likelihood_ratio > 1e-30 ? p.min_likelihood_ratio : 1e-30;
        if (claimed_bg(L, bg, (float)lo) * (1.0 + 1e-9) <= p.max_bg_fraction || lo >= maxlr) {
            thr[i] = (float)lo;
        } else {
            lo = log(lo);
            hi = log(maxlr);
            for (it = 0; it < 60; it++) {
                double mid = 0.5 * (lo + hi);
                if (claimed_bg(L, bg, (float)exp(mid)) <= p.max_bg_fraction) hi = mid;
                else lo = mid;
            }
            thr[i] = (float)exp(hi);
        }
        /* strictly-greater comparisons below; a threshold at the min ratio keeps cells at it */
        if ((double)thr[i] <= p.min_likelihood_ratio) thr[i] = (float)(p.min_likelihood_ratio * (1.0 - 1e-6));
        {
            uint32_t kept = 0;
            for (c = 0; c < K; c++) kept += L[c] > thr[i];
            if (kept == 0) return CYL_ERR_EMPTY;
        }
    }

    /* Reports before resolution, then resolution: a cell claimed by several keeps the
     * class with the largest ratio. */
    if (reports) {
        for (i = 0; i < n; i++) {
            cyl_learn_report *r = &reports[i];
            uint64_t alone = 0;
            memset(r, 0, sizeof *r);
            r->lr_threshold = thr[i];
            for (c = 0; c < K; c++)
                if (lr[i][c] > thr[i]) alone += positive[i]->count[c];
            r->recall_alone = (double)alone / (double)positive[i]->total;
        }
    }
    for (c = 0; c < K; c++) {
        unsigned best = n;
        float bestv = 0.0f;
        unsigned nclaim = 0;
        for (i = 0; i < n; i++)
            if (lr[i][c] > thr[i]) {
                nclaim++;
                if (best == n || lr[i][c] > bestv) { best = i; bestv = lr[i][c]; }
            }
        if (nclaim > 1 && reports)
            for (i = 0; i < n; i++)
                if (i != best && lr[i][c] > thr[i])
                    reports[i].lost_to[cls[best]] += (double)positive[i]->count[c];
        /* keep the winner's ratio; the losers' become 0 (tmp marks nothing here) */
        for (i = 0; i < n; i++)
            if (i != best) lr[i][c] = 0.0f;
    }

    /* Write the classes into the table. */
    for (i = 0; i < n; i++) {
        const cyl_mask bit = (cyl_mask)(1u << cls[i]);
        cyl_mask *cell = &t->yuv[0][0][0];
        unsigned u, v, yv;
        cyl_colortable_clear_class(t, cls[i]);
        for (yv = 0; yv < 256; yv++) t->y[yv] |= bit;
        for (c = 0; c < K; c++)
            if (!(lr[i][c] > thr[i])) cell[c] &= (cyl_mask)~bit;
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

    cyl_colortable_refresh(t);

    if (reports) {
        for (i = 0; i < n; i++) {
            cyl_learn_report *r = &reports[i];
            uint64_t kept_pos = 0, kept_neg = 0;
            uint32_t cells = 0, grey = 0;
            for (c = 0; c < K; c++) {
                unsigned u, v;
                if (!(lr[i][c] > thr[i])) continue;
                cells++;
                kept_pos += positive[i]->count[c];
                kept_neg += negative->count[c];
                u = (c / NC) % NC;
                v = c % NC;
                {
                    /* cell centre in 8-bit chroma */
                    double uc = (u + 0.5) * (1u << CYL_YUV_CSHIFT), vc = (v + 0.5) * (1u << CYL_YUV_CSHIFT);
                    if (fabs(uc - 128.0) <= 8.0 && fabs(vc - 128.0) <= 8.0) grey++;
                }
            }
            r->cells = cells;
            r->recall = (double)kept_pos / (double)positive[i]->total;
            r->bg_fraction = (double)kept_neg / nneg;
            r->grey_fraction = cells ? (double)grey / (double)cells : 0.0;
            for (j = 0; j < CYL_MAX_CLASSES; j++) r->lost_to[j] /= (double)positive[i]->total;
        }
    }
    return CYL_OK;
}
