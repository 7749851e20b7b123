/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- band models and the grouping of blobs into multi-colour landmarks (cyl/landmark.h). */
#include "cyl/config.h"
#include "cyl/landmark.h"

#include <math.h>
#include <string.h>

#define DEG_TO_RAD 0.017453292519943295

cyl_group_params cyl_group_params_default(void)
{
    cyl_group_params p;
    memset(&p, 0, sizeof p);
    p.overlap_min = 0.5;
    p.scale_tol = 0.35;
    p.gap_slack_px = 3.0;
    p.depression_max_deg = 45.0;
    p.max_candidates = 1024u;
    return p;
}

#if CYL_CONFIG_MODELS
static int params_ok(const cyl_group_params *p)
{
    return p->overlap_min >= 0.0 && p->overlap_min <= 1.0 && p->scale_tol >= 0.0 &&
           p->scale_tol < 10.0 && p->gap_slack_px >= 0.0 && p->gap_slack_px < 1e6 &&
           p->depression_max_deg >= 0.0 && p->depression_max_deg < 90.0;
}

static int n_coloured(const cyl_landmark_model *m)
{
    int k, n = 0;
    for (k = 0; k < m->n_bands; k++)
        if (m->band_cls[k] != CYL_BAND_GAP) n++;
    return n;
}

cyl_status cyl_landmark_models_check(const cyl_landmark_model *models, uint32_t n_models)
{
    uint32_t i, j;
    int k;
    if (!models || n_models == 0 || n_models > 0xFFFFu) return CYL_ERR_ARG;
    for (i = 0; i < n_models; i++) {
        const cyl_landmark_model *m = &models[i];
        if (m->n_bands < 1 || m->n_bands > CYL_MODEL_MAX_BANDS) return CYL_ERR_ARG;
        if (m->band_cls[0] == CYL_BAND_GAP || m->band_cls[m->n_bands - 1] == CYL_BAND_GAP)
            return CYL_ERR_ARG;
        for (k = 0; k < m->n_bands; k++) {
            if (m->band_cls[k] != CYL_BAND_GAP && m->band_cls[k] >= CYL_MAX_CLASSES) return CYL_ERR_CLASS;
            if (!(m->band_height_m[k] > 0.0) || !(m->band_height_m[k] < 1e6)) return CYL_ERR_ARG;
        }
        if (!(m->diameter_bottom_m > 0.0) || !(m->diameter_bottom_m < 1e6)) return CYL_ERR_ARG;
        if (m->shape == CYL_SHAPE_CONE) {
            if (!(m->diameter_top_m >= 0.0) || !(m->diameter_top_m < 1e6)) return CYL_ERR_ARG;
        } else if (m->shape != CYL_SHAPE_CYLINDER) {
            return CYL_ERR_ARG;
        }
        if (m->id < -1) return CYL_ERR_ARG;
        for (j = 0; j < i; j++) {
            const cyl_landmark_model *o = &models[j];
            if (o->n_bands == m->n_bands && memcmp(o->band_cls, m->band_cls, m->n_bands) == 0)
                return CYL_ERR_ARG;
        }
    }
    return CYL_OK;
}

#else /* CYL_CONFIG_MODELS */

cyl_status cyl_landmark_models_check(const cyl_landmark_model *models, uint32_t n_models)
{
    (void)models; (void)n_models;
    return CYL_ERR_UNSUPPORTED;
}
#endif

double cyl_landmark_height_m(const cyl_landmark_model *m)
{
    double total = 0.0;
    int k;
    for (k = 0; k < m->n_bands; k++) total += m->band_height_m[k];
    return total;
}

double cyl_landmark_diameter_at_m(const cyl_landmark_model *m, double z_m)
{
    const double total = cyl_landmark_height_m(m);
    double f;
    if (m->shape != CYL_SHAPE_CONE || !(total > 0.0)) return m->diameter_bottom_m;
    f = z_m / total;
    if (f < 0.0) f = 0.0;
    if (f > 1.0) f = 1.0;
    return m->diameter_bottom_m + (m->diameter_top_m - m->diameter_bottom_m) * f;
}

#if CYL_CONFIG_MODELS
typedef struct cand {
    double cost;
    uint32_t blob[CYL_MODEL_MAX_BANDS]; /* per band, CYL_NONE for gaps and empty bands */
    uint16_t model;
    uint8_t n;                          /* blobs assigned */
} cand;

/* Per-model geometry derived once per call. */
typedef struct band_geom {
    double width_m[CYL_MODEL_MAX_BANDS];  /* widest diameter of each band, m */
} band_geom;

typedef struct grp_ctx {
    const cyl_segmentation *seg;
    const cyl_landmark_model *models;
    uint32_t n_models;
    const cyl_group_params *p;
    double cos_d, sin_d;
    cand *cands;
    uint32_t n_cands, max_cands;
    int truncated;
    /* the assignment being built */
    uint32_t cur[CYL_MODEL_MAX_BANDS];
    /* restriction of the search to a set of blobs (the ambiguity check), or NULL */
    const uint32_t *only;
    uint32_t n_only;
    int found;                          /* ambiguity check: an assignment using all of `only` */
} grp_ctx;

static void model_geom(const cyl_landmark_model *m, band_geom *g)
{
    double below = 0.0;
    int k;
    for (k = m->n_bands - 1; k >= 0; k--) {
        const double d_bot = cyl_landmark_diameter_at_m(m, below);
        const double d_top = cyl_landmark_diameter_at_m(m, below + m->band_height_m[k]);
        g->width_m[k] = d_bot > d_top ? d_bot : d_top;
        below += m->band_height_m[k];
    }
}

static double blob_w(const cyl_blob *b) { return (double)b->x1 - (double)b->x0 + 1.0; }
static double blob_h(const cyl_blob *b) { return (double)b->y1 - (double)b->y0 + 1.0; }

/* Does blob b fit band k of model m (its box no taller than the band at its scale)? */
static int fits(const grp_ctx *c, const cyl_landmark_model *m, const band_geom *g, int k,
                const cyl_blob *b)
{
    double s = blob_w(b) / g->width_m[k];
    return blob_h(b) <= (1.0 + c->p->scale_tol) * s * m->band_height_m[k] + c->p->gap_slack_px;
}

/* Pair rule for blob a in band i above blob b in band j (i < j). Returns 1 if compatible and adds
 * the pair's cost to *cost. */
static int pair_ok(const grp_ctx *c, const cyl_landmark_model *m, const band_geom *g, int i,
                   const cyl_blob *a, int j, const cyl_blob *b, double *cost)
{
    const cyl_group_params *p = c->p;
    double wa = blob_w(a), wb = blob_w(b);
    double lo_x = a->x0 > b->x0 ? a->x0 : b->x0;
    double hi_x = a->x1 < b->x1 ? a->x1 : b->x1;
    double ov = hi_x - lo_x + 1.0;
    double sa = wa / g->width_m[i], sb = wb / g->width_m[j];
    double smax = sa > sb ? sa : sb, smin = sa > sb ? sb : sa;
    double between = 0.0, span, s, e, lo, hi, gap;
    int k;
    if (ov < p->overlap_min * (wa < wb ? wa : wb)) return 0;
    if (smax > (1.0 + p->scale_tol) * smin) return 0;
    for (k = i + 1; k < j; k++) between += m->band_height_m[k];
    span = m->band_height_m[i] + between + m->band_height_m[j];
    s = 0.5 * (sa + sb);
    e = s * between;
    lo = c->cos_d * e * (1.0 - p->scale_tol) - 0.25 * (wa + wb) * c->sin_d - p->gap_slack_px;
    hi = e * (1.0 + p->scale_tol) + p->gap_slack_px;
    gap = (double)b->y0 - (double)a->y1 - 1.0;
    if (gap < lo || gap > hi) return 0;
    *cost += fabs(log(sa / sb)) + fabs(gap - 0.5 * (lo + hi)) / (s * span);
    return 1;
}

static int in_only(const grp_ctx *c, uint32_t b)
{
    uint32_t i;
    for (i = 0; i < c->n_only; i++)
        if (c->only[i] == b) return 1;
    return 0;
}

/* Depth-first enumeration of the compatible assignments of model mi, band k onwards; `cost` is the
 * sum of the pair costs of the bands assigned so far (each pair's cost is added when its lower
 * blob is placed, so a complete assignment arrives with its cost). With c->only set, blobs are
 * drawn from it and the search stops at the first assignment that uses all of them. */
static void enumerate(grp_ctx *c, uint16_t mi, const band_geom *g, int k, uint8_t n, double cost)
{
    const cyl_landmark_model *m = &c->models[mi];
    const cyl_blob *bl = c->seg->blobs;
    uint8_t cls;
    uint32_t b, first, last;
    if (c->found || (c->truncated && !c->only)) return;
    if (k == m->n_bands) {
        if (c->only) {
            if (n == c->n_only) c->found = 1;
            return;
        }
        if (n < 2) return;
        if (c->n_cands == c->max_cands) {
            c->truncated = 1;
            return;
        }
        {
            cand *d = &c->cands[c->n_cands++];
            memcpy(d->blob, c->cur, sizeof d->blob);
            d->model = mi;
            d->n = n;
            d->cost = cost;
        }
        return;
    }
    cls = m->band_cls[k];
    c->cur[k] = CYL_NONE;
    enumerate(c, mi, g, k + 1, n, cost);   /* the band left empty (always, for a gap) */
    if (cls == CYL_BAND_GAP) return;
    first = c->seg->class_first[cls];
    last = first + c->seg->class_count[cls];
    for (b = first; b < last && b < c->seg->n_blobs; b++) {
        double pc = 0.0;
        int i, ok;
        if (c->only && !in_only(c, b)) continue;
        if (!fits(c, m, g, k, &bl[b])) continue;
        ok = 1;
        for (i = 0; i < k && ok; i++) {
            if (c->cur[i] == CYL_NONE) continue;
            if (c->cur[i] == b || !pair_ok(c, m, g, i, &bl[c->cur[i]], k, &bl[b], &pc)) ok = 0;
        }
        if (!ok) continue;
        c->cur[k] = b;
        enumerate(c, mi, g, k + 1, (uint8_t)(n + 1), cost + pc);
        c->cur[k] = CYL_NONE;
        if (c->found) return;
    }
}

/* Order of the greedy choice: more blobs, less cost, lower model, lower blob indices. */
static int cand_before(const cand *a, const cand *b)
{
    int k;
    if (a->n != b->n) return a->n > b->n;
    if (a->cost != b->cost) return a->cost < b->cost;
    if (a->model != b->model) return a->model < b->model;
    for (k = 0; k < CYL_MODEL_MAX_BANDS; k++)
        if (a->blob[k] != b->blob[k]) return a->blob[k] < b->blob[k];
    return 0;
}

static void sift_down(cand *v, uint32_t root, uint32_t n)
{
    for (;;) {
        uint32_t child = 2u * root + 1u, top = root;
        cand t;
        /* a max-heap of "comes later" so the sorted array runs first to last */
        if (child < n && cand_before(&v[top], &v[child])) top = child;
        if (child + 1u < n && cand_before(&v[top], &v[child + 1u])) top = child + 1u;
        if (top == root) return;
        t = v[root];
        v[root] = v[top];
        v[top] = t;
        root = top;
    }
}

static void sort_cands(cand *v, uint32_t n)
{
    uint32_t i;
    if (n < 2) return;
    for (i = n / 2u; i-- > 0;) sift_down(v, i, n);
    for (i = n - 1u; i > 0; i--) {
        cand t = v[0];
        v[0] = v[i];
        v[i] = t;
        sift_down(v, 0, i);
    }
}

size_t cyl_group_work_size(uint32_t max_blobs, const cyl_group_params *p)
{
    size_t cands;
    if (!p) return 0;
    cands = (size_t)p->max_candidates * sizeof(cand);
    if (p->max_candidates != 0 && cands / p->max_candidates != sizeof(cand)) return 0;
    return cands + (size_t)max_blobs + 16u;
}

static int model_has_class(const cyl_landmark_model *m, uint8_t cls)
{
    int k;
    for (k = 0; k < m->n_bands; k++)
        if (m->band_cls[k] == cls) return 1;
    return 0;
}

/* Fill a group from an assignment; flags other than EXTRA/AMBIGUOUS, which come later. */
static void fill_group(const grp_ctx *c, uint16_t mi, const band_geom *g, const uint32_t *blob,
                       double cost, cyl_group *o)
{
    const cyl_landmark_model *m = &c->models[mi];
    double sx = 0.0, sy = 0.0, ss = 0.0;
    int k, first = 1;
    memset(o, 0, sizeof *o);
    o->model = mi;
    o->n_coloured = (uint8_t)n_coloured(m);
    o->cost = cost;
    o->id = -1;
    for (k = 0; k < CYL_MODEL_MAX_BANDS; k++) o->blob[k] = CYL_NONE;
    for (k = 0; k < m->n_bands; k++) {
        const cyl_blob *b;
        if (blob[k] == CYL_NONE) continue;
        b = &c->seg->blobs[blob[k]];
        o->blob[k] = blob[k];
        o->n_matched++;
        if (first) {
            o->x0 = b->x0; o->y0 = b->y0; o->x1 = b->x1; o->y1 = b->y1;
            first = 0;
        } else {
            if (b->x0 < o->x0) o->x0 = b->x0;
            if (b->y0 < o->y0) o->y0 = b->y0;
            if (b->x1 > o->x1) o->x1 = b->x1;
            if (b->y1 > o->y1) o->y1 = b->y1;
        }
        o->area += b->area;
        sx += (double)b->area * b->cx_px;
        sy += (double)b->area * b->cy_px;
        ss += blob_w(b) / g->width_m[k];
        if (b->flags & CYL_BLOB_TOUCH_ANY) o->flags |= CYL_GROUP_CUT;
    }
    if (o->area > 0) {
        o->cx_px = sx / (double)o->area;
        o->cy_px = sy / (double)o->area;
    }
    if (o->n_matched > 0) o->scale_px_per_m = ss / (double)o->n_matched;
    if (o->n_matched < o->n_coloured) o->flags |= CYL_GROUP_MISSING_BAND;
}

/* EXTRA_BAND, AMBIGUOUS, id and code confidence of a filled group. */
static void judge_group(grp_ctx *c, cyl_group *o)
{
    const cyl_landmark_model *m = &c->models[o->model];
    uint32_t members[CYL_MODEL_MAX_BANDS] = {CYL_NONE, CYL_NONE, CYL_NONE, CYL_NONE}, n = 0, b, mi;
    int k;
    for (k = 0; k < CYL_MODEL_MAX_BANDS; k++)
        if (o->blob[k] != CYL_NONE) members[n++] = o->blob[k];
    for (b = 0; b < c->seg->n_blobs; b++) {
        const cyl_blob *x = &c->seg->blobs[b];
        uint32_t i;
        int member = 0;
        for (i = 0; i < n; i++)
            if (members[i] == b) member = 1;
        if (member || !model_has_class(m, x->cls)) continue;
        if (x->cx_px >= o->x0 && x->cx_px <= o->x1 && x->cy_px >= o->y0 && x->cy_px <= o->y1) {
            o->flags |= CYL_GROUP_EXTRA_BAND;
            break;
        }
    }
    c->only = members;
    c->n_only = n;
    for (mi = 0; mi < c->n_models && !(o->flags & CYL_GROUP_AMBIGUOUS); mi++) {
        band_geom g;
        if (mi == o->model) continue;
        model_geom(&c->models[mi], &g);
        c->found = 0;
        enumerate(c, (uint16_t)mi, &g, 0, 0, 0.0);
        if (c->found) o->flags |= CYL_GROUP_AMBIGUOUS;
    }
    c->only = NULL;
    c->n_only = 0;
    c->found = 0;
    if (o->flags & (CYL_GROUP_EXTRA_BAND | CYL_GROUP_AMBIGUOUS)) {
        o->code_confidence = 0.0;
    } else {
        o->code_confidence = (double)o->n_matched / (double)o->n_coloured;
        if (o->n_matched == o->n_coloured && m->id >= 0) o->id = m->id;
    }
}

cyl_status cyl_group_blobs(const cyl_segmentation *seg, const cyl_landmark_model *models,
                           uint32_t n_models, const cyl_group_params *p, void *work,
                           size_t work_size, cyl_group *out, uint32_t cap, uint32_t *n_out)
{
    grp_ctx c;
    uint8_t *used;
    uintptr_t addr;
    uint32_t mi, i, n = 0;
    int out_full = 0;
    cyl_status st;
    if (n_out) *n_out = 0;
    if (!seg || !models || !p || !n_out || (!out && cap > 0) || (!work && work_size > 0))
        return CYL_ERR_ARG;
    if (!params_ok(p)) return CYL_ERR_ARG;
    if (seg->n_blobs > 0 && !seg->blobs) return CYL_ERR_ARG;
    st = cyl_landmark_models_check(models, n_models);
    if (st != CYL_OK) return st;
    if (cyl_group_work_size(seg->n_blobs, p) == 0 || work_size < cyl_group_work_size(seg->n_blobs, p))
        return CYL_ERR_NOMEM;
    memset(&c, 0, sizeof c);
    c.seg = seg;
    c.models = models;
    c.n_models = n_models;
    c.p = p;
    c.cos_d = cos(p->depression_max_deg * DEG_TO_RAD);
    c.sin_d = sin(p->depression_max_deg * DEG_TO_RAD);
    addr = (uintptr_t)work;
    c.cands = (cand *)(void *)((unsigned char *)work + ((16u - (addr & 15u)) & 15u));
    c.max_cands = p->max_candidates;
    used = (uint8_t *)(c.cands + c.max_cands);
    memset(used, 0, seg->n_blobs);

    for (mi = 0; mi < n_models; mi++) {
        band_geom g;
        int k;
        model_geom(&models[mi], &g);
        for (k = 0; k < CYL_MODEL_MAX_BANDS; k++) c.cur[k] = CYL_NONE;
        enumerate(&c, (uint16_t)mi, &g, 0, 0, 0.0);
    }
    sort_cands(c.cands, c.n_cands);
    for (i = 0; i < c.n_cands; i++) {
        const cand *d = &c.cands[i];
        band_geom g;
        int k, free_all = 1;
        for (k = 0; k < CYL_MODEL_MAX_BANDS; k++)
            if (d->blob[k] != CYL_NONE && used[d->blob[k]]) free_all = 0;
        if (!free_all) continue;
        if (n == cap) {
            out_full = 1;
            break;
        }
        for (k = 0; k < CYL_MODEL_MAX_BANDS; k++)
            if (d->blob[k] != CYL_NONE) used[d->blob[k]] = 1;
        model_geom(&models[d->model], &g);
        fill_group(&c, d->model, &g, d->blob, d->cost, &out[n++]);
    }
    /* blobs left alone */
    for (i = 0; i < seg->n_blobs && !out_full; i++) {
        const cyl_blob *b = &seg->blobs[i];
        uint32_t best_m = CYL_NONE;
        int best_k = -1, best_nc = 0;
        if (used[i]) continue;
        for (mi = 0; mi < n_models; mi++) {
            const cyl_landmark_model *m = &models[mi];
            int nc = n_coloured(m), k;
            band_geom g;
            if (best_m != CYL_NONE && nc >= best_nc) continue;
            model_geom(m, &g);
            for (k = 0; k < m->n_bands; k++) {
                if (m->band_cls[k] != b->cls || !fits(&c, m, &g, k, b)) continue;
                best_m = mi;
                best_k = k;
                best_nc = nc;
                break;
            }
        }
        if (best_m == CYL_NONE) continue;
        if (n == cap) {
            out_full = 1;
            break;
        }
        {
            uint32_t blob[CYL_MODEL_MAX_BANDS];
            band_geom g;
            int k;
            for (k = 0; k < CYL_MODEL_MAX_BANDS; k++) blob[k] = CYL_NONE;
            blob[best_k] = i;
            used[i] = 1;
            model_geom(&models[best_m], &g);
            fill_group(&c, (uint16_t)best_m, &g, blob, 0.0, &out[n++]);
        }
    }
    for (i = 0; i < n; i++) judge_group(&c, &out[i]);
    *n_out = n;
    return (out_full || c.truncated) ? CYL_TRUNCATED : CYL_OK;
}

#else /* CYL_CONFIG_MODELS */

size_t cyl_group_work_size(uint32_t max_blobs, const cyl_group_params *p)
{
    (void)max_blobs; (void)p;
    return 0;
}

cyl_status cyl_group_blobs(const cyl_segmentation *seg, const cyl_landmark_model *models,
                           uint32_t n_models, const cyl_group_params *p, void *work,
                           size_t work_size, cyl_group *out, uint32_t cap, uint32_t *n_out)
{
    (void)seg; (void)models; (void)n_models; (void)p; (void)work; (void)work_size; (void)out; (void)cap;
    if (n_out) *n_out = 0;
    return CYL_ERR_UNSUPPORTED;
}
#endif
