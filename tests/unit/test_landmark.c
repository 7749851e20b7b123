/* SPDX-License-Identifier: BSD-3-Clause */
/* Band models and the grouping of blobs into multi-colour landmarks (cyl/landmark.h): hand-built
 * blob sets with hand-derived groupings, the model checks, and a brute-force reference of the
 * grouping rule on random blob sets. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <string.h>
#include <math.h>
#include <cmocka.h>

#include "cyl/landmark.h"
#include "rng.h"

#define MAXB 32
#define ORANGE 0
#define PINK 1
#define GREEN 2
#define YELLOW 3
#define GAP CYL_BAND_GAP

/* ---- hand-built segmentations: blobs only, sorted by class as cyl_segment() leaves them ---- */
typedef struct frame {
    cyl_blob blobs[MAXB];
    cyl_segmentation seg;
} frame;

static void frame_init(frame *f)
{
    memset(f, 0, sizeof *f);
    f->seg.blobs = f->blobs;
    f->seg.max_blobs = MAXB;
}

/* A solid rectangular blob (inclusive corners). Call in class order. */
static void blob(frame *f, uint8_t cls, int x0, int y0, int x1, int y1)
{
    cyl_blob *b = &f->blobs[f->seg.n_blobs];
    uint32_t c;
    memset(b, 0, sizeof *b);
    b->cls = cls;
    b->x0 = (uint16_t)x0; b->y0 = (uint16_t)y0; b->x1 = (uint16_t)x1; b->y1 = (uint16_t)y1;
    b->area = (uint32_t)((x1 - x0 + 1) * (y1 - y0 + 1));
    b->cx_px = 0.5 * (x0 + x1);
    b->cy_px = 0.5 * (y0 + y1);
    b->first_run = CYL_NONE;
    f->seg.n_blobs++;
    for (c = 0; c < CYL_MAX_CLASSES; c++) f->seg.class_first[c] = f->seg.class_count[c] = 0;
    for (c = 0; c < f->seg.n_blobs; c++) {
        uint8_t k = f->blobs[c].cls;
        if (f->seg.class_count[k]++ == 0) f->seg.class_first[k] = c;
    }
}

static unsigned char work_mem[1u << 16];

static uint32_t group(const frame *f, const cyl_landmark_model *m, uint32_t nm, cyl_group *out,
                      uint32_t cap)
{
    cyl_group_params p = cyl_group_params_default();
    uint32_t n = 99;
    assert_true(cyl_group_work_size(f->seg.n_blobs, &p) <= sizeof work_mem);
    assert_int_equal(cyl_group_blobs(&f->seg, m, nm, &p, work_mem, sizeof work_mem, out, cap, &n), CYL_OK);
    return n;
}

/* A striped cone: orange 0.10 m, an unclassified stripe 0.05 m, orange 0.15 m; base 0.25 m, top
 * 0.05 m, 0.30 m tall. The top band is widest at its bottom (z = 0.20 m): 0.25 - 0.20 * 2/3 =
 * 0.11667 m; the bottom band at the base, 0.25 m. */
static cyl_landmark_model cone_model(void)
{
    cyl_landmark_model m;
    memset(&m, 0, sizeof m);
    m.n_bands = 3;
    m.band_cls[0] = ORANGE; m.band_cls[1] = GAP; m.band_cls[2] = ORANGE;
    m.band_height_m[0] = 0.10; m.band_height_m[1] = 0.05; m.band_height_m[2] = 0.15;
    m.shape = CYL_SHAPE_CONE;
    m.diameter_bottom_m = 0.25;
    m.diameter_top_m = 0.05;
    m.id = -1;
    return m;
}

/* At 200 px/m: top band 23 px wide (0.11667 * 200 = 23.3), 20 px tall; the stripe 10 px; the
 * bottom band 50 x 30 px. */
static void cone_at(frame *f, int cx, int top)
{
    blob(f, ORANGE, cx - 11, top, cx + 11, top + 19);
    blob(f, ORANGE, cx - 25, top + 30, cx + 24, top + 59);
}

static void test_striped_cone(void **st)
{
    cyl_landmark_model m = cone_model();
    cyl_group g[4];
    frame f;
    (void)st;
    frame_init(&f);
    cone_at(&f, 100, 40);
    assert_int_equal(group(&f, &m, 1, g, 4), 1);
    assert_int_equal(g[0].model, 0);
    assert_int_equal(g[0].blob[0], 0);
    assert_int_equal(g[0].blob[1], CYL_NONE);
    assert_int_equal(g[0].blob[2], 1);
    assert_int_equal(g[0].n_matched, 2);
    assert_int_equal(g[0].n_coloured, 2);
    assert_int_equal(g[0].flags, 0);
    assert_int_equal(g[0].x0, 75); assert_int_equal(g[0].x1, 124);
    assert_int_equal(g[0].y0, 40); assert_int_equal(g[0].y1, 99);
    assert_int_equal(g[0].area, 23 * 20 + 50 * 30);
    /* area-weighted centroid: (460 * 100 + 1500 * 99.5) / 1960, (460 * 49.5 + 1500 * 84.5) / 1960 */
    assert_true(fabs(g[0].cx_px - (460.0 * 100 + 1500.0 * 99.5) / 1960.0) < 1e-9);
    assert_true(fabs(g[0].cy_px - (460.0 * 49.5 + 1500.0 * 84.5) / 1960.0) < 1e-9);
    /* scales 23 / 0.116667 = 197.14 and 50 / 0.25 = 200 px/m */
    assert_true(fabs(g[0].scale_px_per_m - 0.5 * (23.0 / (0.25 - 0.2 * 2.0 / 3.0) + 200.0)) < 1e-9);
    assert_int_equal(g[0].id, -1);
    assert_true(fabs(g[0].code_confidence - 1.0) < 1e-12);
}

/* Two cones side by side and a lone orange blob: two groups, then the lone blob as a cone with
 * a band missing. The bands of the two cones never pair across: their columns do not overlap. */
static void test_two_cones_and_clutter(void **st)
{
    cyl_landmark_model m = cone_model();
    cyl_group g[8];
    frame f;
    (void)st;
    frame_init(&f);
    cone_at(&f, 100, 40);   /* blobs 0, 1 */
    cone_at(&f, 200, 50);   /* blobs 2, 3 */
    blob(&f, ORANGE, 300, 10, 309, 19);   /* blob 4: 10 x 10, fits the top band (s = 85.7 px/m) */
    assert_int_equal(group(&f, &m, 1, g, 8), 3);
    /* equal blob counts and equal costs (the same geometry): the lower blob indices first */
    assert_int_equal(g[0].blob[0], 0); assert_int_equal(g[0].blob[2], 1);
    assert_int_equal(g[1].blob[0], 2); assert_int_equal(g[1].blob[2], 3);
    assert_true(g[0].cost == g[1].cost);
    assert_int_equal(g[2].blob[0], 4);
    assert_int_equal(g[2].blob[2], CYL_NONE);
    assert_int_equal(g[2].n_matched, 1);
    assert_int_equal(g[2].flags, CYL_GROUP_MISSING_BAND);
    assert_true(fabs(g[2].code_confidence - 0.5) < 1e-12);
    assert_true(g[2].cost == 0.0);
}

/* The bands upside down (the wide one on top): scales 50 / 0.1167 = 429 and 23 / 0.25 = 92 px/m
 * disagree, so no pair; the wide blob is too tall for... nothing: 30 <= 1.35 * 200 * 0.15 + 3
 * fits the bottom band; the narrow one fits the top band. Two single groups. */
static void test_upside_down(void **st)
{
    cyl_landmark_model m = cone_model();
    cyl_group g[4];
    frame f;
    (void)st;
    frame_init(&f);
    blob(&f, ORANGE, 75, 40, 124, 69);
    blob(&f, ORANGE, 89, 80, 111, 99);
    assert_int_equal(group(&f, &m, 1, g, 4), 2);
    assert_int_equal(g[0].n_matched, 1);
    assert_int_equal(g[1].n_matched, 1);
    /* blob 0 (50 x 30): the top band needs h <= 1.35 * (50 / 0.11667) * 0.10 + 3 = 60.9: fits there
     * first (band order) */
    assert_int_equal(g[0].blob[0], 0);
    assert_int_equal(g[1].blob[0], 1);
}

/* Too far apart vertically: the stripe between is 10 px at this scale; a 40 px gap exceeds
 * 9.93 * 1.35 + 3 = 16.4 px. */
static void test_gap_too_large(void **st)
{
    cyl_landmark_model m = cone_model();
    cyl_group g[4];
    frame f;
    (void)st;
    frame_init(&f);
    blob(&f, ORANGE, 89, 40, 111, 59);
    blob(&f, ORANGE, 75, 100, 124, 129);
    assert_int_equal(group(&f, &m, 1, g, 4), 2);
    assert_int_equal(g[0].n_matched + g[1].n_matched, 2);
}

/* Coded cylinders, 0.10 m across, bands 0.10 m: A pink/green id 1, C green/pink id 3, B
 * yellow/pink/yellow id 2. At 200 px/m a band is 20 x 20 px. */
static void coded_models(cyl_landmark_model m[4])
{
    int i, k;
    memset(m, 0, 4 * sizeof *m);
    for (i = 0; i < 4; i++) {
        m[i].shape = CYL_SHAPE_CYLINDER;
        m[i].diameter_bottom_m = 0.10;
        for (k = 0; k < CYL_MODEL_MAX_BANDS; k++) m[i].band_height_m[k] = 0.10;
    }
    m[0].n_bands = 2; m[0].band_cls[0] = PINK; m[0].band_cls[1] = GREEN; m[0].id = 1;
    m[1].n_bands = 3; m[1].band_cls[0] = YELLOW; m[1].band_cls[1] = PINK; m[1].band_cls[2] = YELLOW;
    m[1].id = 2;
    m[2].n_bands = 2; m[2].band_cls[0] = GREEN; m[2].band_cls[1] = PINK; m[2].id = 3;
    m[3].n_bands = 3; m[3].band_cls[0] = PINK; m[3].band_cls[1] = GREEN; m[3].band_cls[2] = YELLOW;
    m[3].id = 4;
}

static void test_codes(void **st)
{
    cyl_landmark_model m[4];
    cyl_group g[8];
    frame f;
    uint32_t n, i;
    (void)st;
    coded_models(m);
    /* A at x 100, C at x 200, B at x 300, B without its bottom band at x 400 */
    frame_init(&f);
    blob(&f, PINK, 90, 40, 109, 59);     /* 0: A top */
    blob(&f, PINK, 190, 60, 209, 79);    /* 1: C bottom */
    blob(&f, PINK, 290, 60, 309, 79);    /* 2: B middle */
    blob(&f, PINK, 390, 60, 409, 79);    /* 3: B' middle */
    blob(&f, GREEN, 90, 60, 109, 79);    /* 4: A bottom */
    blob(&f, GREEN, 190, 40, 209, 59);   /* 5: C top */
    blob(&f, YELLOW, 290, 40, 309, 59);  /* 6: B top */
    blob(&f, YELLOW, 290, 80, 309, 99);  /* 7: B bottom */
    blob(&f, YELLOW, 390, 40, 409, 59);  /* 8: B' top */
    /* with models A, B, C only (D, pink/green/yellow, would make A ambiguous: below) */
    n = group(&f, m, 3, g, 8);
    assert_int_equal(n, 4);
    /* B (3 blobs) first, then the two-blob groups by cost and model: A (model 0), B' (model 1),
     * C (model 2). Their costs are equal (the same geometry): two touching bands 20 px wide at
     * 200 px/m, gap 0 against the middle of [-10 sin 45 deg - 3, 3], -5 sin 45 deg = -3.54 px, over 0.2 m * 200 */
    assert_int_equal(g[0].model, 1); assert_int_equal(g[0].id, 2);
    assert_int_equal(g[0].blob[0], 6); assert_int_equal(g[0].blob[1], 2); assert_int_equal(g[0].blob[2], 7);
    assert_int_equal(g[1].model, 0); assert_int_equal(g[1].id, 1); assert_int_equal(g[1].flags, 0);
    assert_int_equal(g[2].model, 1); assert_int_equal(g[2].id, -1);
    assert_int_equal(g[2].flags, CYL_GROUP_MISSING_BAND);
    assert_true(fabs(g[2].code_confidence - 2.0 / 3.0) < 1e-12);
    assert_int_equal(g[3].model, 2); assert_int_equal(g[3].id, 3);
    for (i = 1; i < n; i++) assert_true(fabs(g[i].cost - 5.0 * sqrt(0.5) / 40.0) < 1e-12);
    /* with D: A's blobs are also D with its yellow band hidden, so A has no id */
    n = group(&f, m, 4, g, 8);
    assert_int_equal(n, 4);
    assert_int_equal(g[1].model, 0);
    assert_int_equal(g[1].flags, CYL_GROUP_AMBIGUOUS);
    assert_int_equal(g[1].id, -1);
    assert_true(g[1].code_confidence == 0.0);
    assert_int_equal(g[0].id, 2);   /* B's three blobs fit no other model whole */
    assert_int_equal(g[3].id, 3);
    /* a green speck inside A's pink band: an extra band, no id */
    frame_init(&f);
    blob(&f, PINK, 90, 40, 109, 59);
    blob(&f, GREEN, 90, 60, 109, 79);
    blob(&f, GREEN, 98, 48, 101, 51);
    n = group(&f, m, 3, g, 8);
    assert_int_equal(n, 2);
    assert_int_equal(g[0].model, 0);
    assert_int_equal(g[0].flags, CYL_GROUP_EXTRA_BAND);
    assert_int_equal(g[0].id, -1);
    /* the speck alone: green fits C's top band (the first of the fewest-band models with green) */
    assert_int_equal(g[1].model, 0);
    assert_int_equal(g[1].blob[1], 2);
}

/* One-band model: the paper's cylinder, a group per blob, never missing a band. */
static void test_single_band(void **st)
{
    cyl_landmark_model m;
    cyl_group g[4];
    frame f;
    (void)st;
    memset(&m, 0, sizeof m);
    m.n_bands = 1; m.band_cls[0] = ORANGE; m.band_height_m[0] = 0.2; m.diameter_bottom_m = 0.1;
    m.id = -1;
    frame_init(&f);
    blob(&f, ORANGE, 10, 10, 29, 49);
    blob(&f, ORANGE, 50, 10, 69, 49);
    blob(&f, PINK, 80, 10, 99, 49);       /* no model has pink: ungrouped */
    assert_int_equal(group(&f, &m, 1, g, 4), 2);
    assert_int_equal(g[0].flags, 0);
    assert_int_equal(g[0].n_coloured, 1);
    assert_true(g[0].code_confidence == 1.0);
    assert_int_equal(g[1].blob[0], 1);
}

static void test_checks(void **st)
{
    cyl_landmark_model m[2];
    cyl_group_params p = cyl_group_params_default();
    cyl_group g[2];
    frame f;
    uint32_t n;
    (void)st;
    m[0] = cone_model();
    assert_int_equal(cyl_landmark_models_check(m, 1), CYL_OK);
    m[1] = m[0];
    assert_int_equal(cyl_landmark_models_check(m, 2), CYL_ERR_ARG);   /* same bands twice */
    m[1].band_cls[2] = PINK;
    assert_int_equal(cyl_landmark_models_check(m, 2), CYL_OK);
    m[1].band_cls[2] = GAP;
    assert_int_equal(cyl_landmark_models_check(m, 2), CYL_ERR_ARG);   /* gap last */
    m[1].band_cls[2] = CYL_MAX_CLASSES;
    assert_int_equal(cyl_landmark_models_check(m, 2), CYL_ERR_CLASS);
    m[1] = m[0]; m[1].band_cls[0] = PINK; m[1].band_height_m[1] = 0.0;
    assert_int_equal(cyl_landmark_models_check(m, 2), CYL_ERR_ARG);
    m[1].band_height_m[1] = 0.05; m[1].n_bands = 5;
    assert_int_equal(cyl_landmark_models_check(m, 2), CYL_ERR_ARG);
    m[1].n_bands = 3; m[1].diameter_bottom_m = 0.0;
    assert_int_equal(cyl_landmark_models_check(m, 2), CYL_ERR_ARG);
    m[1].diameter_bottom_m = 0.2; m[1].id = -2;
    assert_int_equal(cyl_landmark_models_check(m, 2), CYL_ERR_ARG);
    assert_int_equal(cyl_landmark_models_check(m, 0), CYL_ERR_ARG);
    /* work, capacity, parameters */
    frame_init(&f);
    cone_at(&f, 100, 40);
    cone_at(&f, 200, 40);
    assert_int_equal(cyl_group_blobs(&f.seg, m, 1, &p, work_mem, cyl_group_work_size(4, &p) - 1, g, 2, &n),
                     CYL_ERR_NOMEM);
    assert_int_equal(cyl_group_blobs(&f.seg, m, 1, &p, work_mem, sizeof work_mem, g, 1, &n), CYL_TRUNCATED);
    assert_int_equal(n, 1);
    p.max_candidates = 1;   /* the two cones are two candidates */
    assert_int_equal(cyl_group_blobs(&f.seg, m, 1, &p, work_mem, sizeof work_mem, g, 2, &n), CYL_TRUNCATED);
    p = cyl_group_params_default();
    p.depression_max_deg = 90.0;
    assert_int_equal(cyl_group_blobs(&f.seg, m, 1, &p, work_mem, sizeof work_mem, g, 2, &n), CYL_ERR_ARG);
    p = cyl_group_params_default();
    assert_int_equal(cyl_group_blobs(NULL, m, 1, &p, work_mem, sizeof work_mem, g, 2, &n), CYL_ERR_ARG);
}

/* ---- brute-force reference: every assignment of every model over every blob, the greedy choice
 * by repeated scans, the singles and the identity, written from the header's rule ---- */
typedef struct ref_group {
    uint32_t model;
    uint32_t blob[CYL_MODEL_MAX_BANDS];
    uint32_t flags;
    int32_t id;
} ref_group;

static double ref_width(const cyl_landmark_model *m, int k)
{
    double tot = 0, below = 0, d0, d1;
    int j;
    for (j = 0; j < m->n_bands; j++) tot += m->band_height_m[j];
    for (j = k + 1; j < m->n_bands; j++) below += m->band_height_m[j];
    if (m->shape != CYL_SHAPE_CONE) return m->diameter_bottom_m;
    d0 = m->diameter_bottom_m + (m->diameter_top_m - m->diameter_bottom_m) * below / tot;
    d1 = m->diameter_bottom_m + (m->diameter_top_m - m->diameter_bottom_m) * (below + m->band_height_m[k]) / tot;
    return d0 > d1 ? d0 : d1;
}

/* compatibility and cost of an assignment (blob indices per band, CYL_NONE for none); -1 if not */
static double ref_cost(const frame *f, const cyl_landmark_model *m, const cyl_group_params *p,
                       const uint32_t *a)
{
    double cost = 0, cd = cos(p->depression_max_deg * 0.017453292519943295);
    double sd = sin(p->depression_max_deg * 0.017453292519943295);
    int i, j, k;
    for (i = 0; i < m->n_bands; i++) {
        const cyl_blob *x;
        double w, h;
        if (a[i] == CYL_NONE) continue;
        x = &f->blobs[a[i]];
        if (m->band_cls[i] == GAP || x->cls != m->band_cls[i]) return -1;
        w = x->x1 - x->x0 + 1.0; h = x->y1 - x->y0 + 1.0;
        if (h > (1.0 + p->scale_tol) * (w / ref_width(m, i)) * m->band_height_m[i] + p->gap_slack_px) return -1;
        for (j = i + 1; j < m->n_bands; j++) {
            const cyl_blob *y;
            double wy, sa, sb, s, between = 0, e, lo, hi, g, ov;
            if (a[j] == CYL_NONE) continue;
            if (a[j] == a[i]) return -1;
            y = &f->blobs[a[j]];
            wy = y->x1 - y->x0 + 1.0;
            ov = (double)(x->x1 < y->x1 ? x->x1 : y->x1) - (double)(x->x0 > y->x0 ? x->x0 : y->x0) + 1.0;
            if (ov < p->overlap_min * (w < wy ? w : wy)) return -1;
            sa = w / ref_width(m, i); sb = wy / ref_width(m, j);
            if ((sa > sb ? sa : sb) > (1.0 + p->scale_tol) * (sa > sb ? sb : sa)) return -1;
            for (k = i + 1; k < j; k++) between += m->band_height_m[k];
            s = 0.5 * (sa + sb);
            e = s * between;
            lo = cd * e * (1.0 - p->scale_tol) - 0.25 * (w + wy) * sd - p->gap_slack_px;
            hi = e * (1.0 + p->scale_tol) + p->gap_slack_px;
            g = (double)y->y0 - (double)x->y1 - 1.0;
            if (g < lo || g > hi) return -1;
            cost += fabs(log(sa / sb)) + fabs(g - 0.5 * (lo + hi)) /
                    (s * (m->band_height_m[i] + between + m->band_height_m[j]));
        }
    }
    return cost;
}

/* next assignment in odometer order over n blobs (+ none) per band; 0 when done */
static int next_assign(uint32_t *a, int bands, uint32_t n)
{
    int k;
    for (k = bands - 1; k >= 0; k--) {
        if (a[k] == CYL_NONE) { a[k] = 0; if (n > 0) return 1; }
        else if (a[k] + 1 < n) { a[k]++; return 1; }
        a[k] = CYL_NONE;
    }
    return 0;
}

static int count_assigned(const uint32_t *a, int bands)
{
    int k, n = 0;
    for (k = 0; k < bands; k++) n += a[k] != CYL_NONE;
    return n;
}

static int ref_uses_exactly(const uint32_t *a, int bands, const uint32_t *set, int n_set)
{
    int i, k;
    if (count_assigned(a, bands) != n_set) return 0;
    for (i = 0; i < n_set; i++) {
        int hit = 0;
        for (k = 0; k < bands; k++) hit |= a[k] == set[i];
        if (!hit) return 0;
    }
    return 1;
}

static uint32_t ref_group_blobs(const frame *f, const cyl_landmark_model *m, uint32_t nm,
                                const cyl_group_params *p, ref_group *out)
{
    uint8_t used[MAXB] = {0};
    uint32_t n = 0, mi, i;
    int k;
    for (;;) {   /* the greedy rounds */
        uint32_t best_a[CYL_MODEL_MAX_BANDS], best_m = CYL_NONE;
        int best_n = 0;
        double best_c = 0;
        for (mi = 0; mi < nm; mi++) {
            uint32_t a[CYL_MODEL_MAX_BANDS];
            for (k = 0; k < CYL_MODEL_MAX_BANDS; k++) a[k] = CYL_NONE;
            while (next_assign(a, m[mi].n_bands, f->seg.n_blobs)) {
                int cnt = count_assigned(a, m[mi].n_bands), free_all = 1, better;
                double c;
                if (cnt < 2) continue;
                for (k = 0; k < m[mi].n_bands; k++) if (a[k] != CYL_NONE && used[a[k]]) free_all = 0;
                if (!free_all) continue;
                c = ref_cost(f, &m[mi], p, a);
                if (c < 0) continue;
                better = best_m == CYL_NONE || cnt > best_n || (cnt == best_n && c < best_c);
                if (!better && best_m != CYL_NONE && cnt == best_n && c == best_c) {
                    if (mi < best_m) better = 1;
                    else if (mi == best_m) {
                        for (k = 0; k < CYL_MODEL_MAX_BANDS; k++)
                            if (a[k] != best_a[k]) { better = a[k] < best_a[k]; break; }
                    }
                }
                if (better) { best_m = mi; best_n = cnt; best_c = c; memcpy(best_a, a, sizeof a); }
            }
        }
        if (best_m == CYL_NONE) break;
        out[n].model = best_m;
        memcpy(out[n].blob, best_a, sizeof best_a);
        for (k = 0; k < CYL_MODEL_MAX_BANDS; k++) if (best_a[k] != CYL_NONE) used[best_a[k]] = 1;
        n++;
    }
    for (i = 0; i < f->seg.n_blobs; i++) {   /* singles */
        uint32_t best_m = CYL_NONE;
        int best_k = -1, best_nc = 99;
        if (used[i]) continue;
        for (mi = 0; mi < nm; mi++) {
            int nc = 0;
            for (k = 0; k < m[mi].n_bands; k++) nc += m[mi].band_cls[k] != GAP;
            for (k = 0; k < m[mi].n_bands; k++) {
                uint32_t a[CYL_MODEL_MAX_BANDS] = {CYL_NONE, CYL_NONE, CYL_NONE, CYL_NONE};
                a[k] = i;
                if (m[mi].band_cls[k] == GAP || ref_cost(f, &m[mi], p, a) < 0) continue;
                if (nc < best_nc) { best_m = mi; best_k = k; best_nc = nc; }
                break;
            }
        }
        if (best_m == CYL_NONE) continue;
        out[n].model = best_m;
        for (k = 0; k < CYL_MODEL_MAX_BANDS; k++) out[n].blob[k] = CYL_NONE;
        out[n].blob[best_k] = i;
        used[i] = 1;
        n++;
    }
    for (i = 0; i < n; i++) {   /* flags and identity */
        const cyl_landmark_model *gm = &m[out[i].model];
        uint32_t set[CYL_MODEL_MAX_BANDS], b;
        int n_set = 0, nc = 0, x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
        out[i].flags = 0;
        for (k = 0; k < gm->n_bands; k++) {
            if (gm->band_cls[k] != GAP) nc++;
            if (out[i].blob[k] == CYL_NONE) continue;
            b = out[i].blob[k];
            set[n_set++] = b;
            if (f->blobs[b].x0 < x0) x0 = f->blobs[b].x0;
            if (f->blobs[b].y0 < y0) y0 = f->blobs[b].y0;
            if (f->blobs[b].x1 > x1) x1 = f->blobs[b].x1;
            if (f->blobs[b].y1 > y1) y1 = f->blobs[b].y1;
            if (f->blobs[b].flags & CYL_BLOB_TOUCH_ANY) out[i].flags |= CYL_GROUP_CUT;
        }
        if (n_set < nc) out[i].flags |= CYL_GROUP_MISSING_BAND;
        for (b = 0; b < f->seg.n_blobs; b++) {
            int member = 0, cls_in = 0, j;
            for (j = 0; j < n_set; j++) member |= set[j] == b;
            for (k = 0; k < gm->n_bands; k++) cls_in |= gm->band_cls[k] == f->blobs[b].cls;
            if (!member && cls_in && f->blobs[b].cx_px >= x0 && f->blobs[b].cx_px <= x1 &&
                f->blobs[b].cy_px >= y0 && f->blobs[b].cy_px <= y1)
                out[i].flags |= CYL_GROUP_EXTRA_BAND;
        }
        for (mi = 0; mi < nm; mi++) {
            uint32_t a[CYL_MODEL_MAX_BANDS];
            if (mi == out[i].model) continue;
            for (k = 0; k < CYL_MODEL_MAX_BANDS; k++) a[k] = CYL_NONE;
            while (next_assign(a, m[mi].n_bands, f->seg.n_blobs))
                if (ref_uses_exactly(a, m[mi].n_bands, set, n_set) && ref_cost(f, &m[mi], p, a) >= 0) {
                    out[i].flags |= CYL_GROUP_AMBIGUOUS;
                    break;
                }
        }
        out[i].id = (!(out[i].flags & (CYL_GROUP_EXTRA_BAND | CYL_GROUP_AMBIGUOUS)) && n_set == nc &&
                     gm->id >= 0) ? gm->id : -1;
    }
    return n;
}

/* Random blob sets: 1-3 landmarks of random models at random scales, bands jittered by +-2 px and
 * dropped at random, plus clutter; classes sorted as cyl_segment() sorts them. */
static void random_frame(test_rng *r, const cyl_landmark_model *m, uint32_t nm, frame *f)
{
    struct { uint8_t cls; int x0, y0, x1, y1; } raw[MAXB];
    int nraw = 0, nl = (int)test_rng_int(r, 1, 3), l, k, c, i;
    for (l = 0; l < nl; l++) {
        const cyl_landmark_model *mm = &m[test_rng_int(r, 0, (int64_t)nm - 1)];
        double s = 60 + 240 * test_rng_uniform(r), cx = 40 + 300 * test_rng_uniform(r);
        double y = 10 + 100 * test_rng_uniform(r);
        for (k = 0; k < mm->n_bands && nraw < MAXB - 6; k++) {
            double w = s * ref_width(mm, k), h = s * mm->band_height_m[k];
            if (mm->band_cls[k] != GAP && test_rng_uniform(r) > 0.15) {
                raw[nraw].cls = mm->band_cls[k];
                raw[nraw].x0 = (int)(cx - w / 2) + (int)test_rng_int(r, -2, 2);
                raw[nraw].x1 = raw[nraw].x0 + (int)w - 1 + (int)test_rng_int(r, -2, 2);
                raw[nraw].y0 = (int)y + (int)test_rng_int(r, -2, 2);
                raw[nraw].y1 = (int)(y + h) - 1 + (int)test_rng_int(r, -2, 2);
                if (raw[nraw].x1 < raw[nraw].x0) raw[nraw].x1 = raw[nraw].x0;
                if (raw[nraw].y1 < raw[nraw].y0) raw[nraw].y1 = raw[nraw].y0;
                if (raw[nraw].x0 < 0) raw[nraw].x0 = 0;
                if (raw[nraw].y0 < 0) raw[nraw].y0 = 0;
                nraw++;
            }
            y += h;
        }
    }
    for (i = (int)test_rng_int(r, 0, 4); i > 0 && nraw < MAXB; i--) {
        raw[nraw].cls = (uint8_t)test_rng_int(r, 0, 3);
        raw[nraw].x0 = (int)test_rng_int(r, 0, 380);
        raw[nraw].y0 = (int)test_rng_int(r, 0, 200);
        raw[nraw].x1 = raw[nraw].x0 + (int)test_rng_int(r, 0, 40);
        raw[nraw].y1 = raw[nraw].y0 + (int)test_rng_int(r, 0, 40);
        nraw++;
    }
    frame_init(f);
    for (c = 0; c < 4; c++)
        for (i = 0; i < nraw; i++)
            if (raw[i].cls == c) {
                blob(f, raw[i].cls, raw[i].x0, raw[i].y0, raw[i].x1, raw[i].y1);
                if (raw[i].x0 == 0) f->blobs[f->seg.n_blobs - 1].flags |= CYL_BLOB_TOUCH_LEFT;
            }
}

static void test_brute_force(void **st)
{
    cyl_landmark_model m[6];
    cyl_group_params p = cyl_group_params_default();
    test_rng r;
    int trial, multi = 0, ids = 0;
    (void)st;
    coded_models(m);
    m[4] = cone_model();
    memset(&m[5], 0, sizeof m[5]);
    m[5].n_bands = 1; m[5].band_cls[0] = GREEN; m[5].band_height_m[0] = 0.3;
    m[5].diameter_bottom_m = 0.1; m[5].id = 7;
    test_rng_seed(&r, 20261203);
    for (trial = 0; trial < 400; trial++) {
        frame f;
        cyl_group g[MAXB];
        ref_group ref[MAXB];
        uint32_t n, nr, i, nm = (uint32_t)test_rng_int(&r, 1, 6);
        int k;
        /* model subsets: the first nm of a rotation, so ambiguity between models varies */
        cyl_landmark_model ms[6];
        int rot = (int)test_rng_int(&r, 0, 5);
        for (i = 0; i < nm; i++) ms[i] = m[(i + (uint32_t)rot) % 6];
        random_frame(&r, ms, nm, &f);
        assert_int_equal(cyl_group_blobs(&f.seg, ms, nm, &p, work_mem, sizeof work_mem, g, MAXB, &n), CYL_OK);
        nr = ref_group_blobs(&f, ms, nm, &p, ref);
        if (n != nr) fail_msg("trial %d: %u groups, reference %u", trial, n, nr);
        for (i = 0; i < n; i++) {
            if (g[i].model != ref[i].model || g[i].flags != ref[i].flags || g[i].id != ref[i].id)
                fail_msg("trial %d group %u: model %u flags %x id %d, reference %u %x %d", trial, i,
                         g[i].model, g[i].flags, g[i].id, ref[i].model, ref[i].flags, ref[i].id);
            for (k = 0; k < CYL_MODEL_MAX_BANDS; k++)
                if (g[i].blob[k] != ref[i].blob[k])
                    fail_msg("trial %d group %u band %d: blob %u, reference %u", trial, i, k,
                             g[i].blob[k], ref[i].blob[k]);
            multi += g[i].n_matched >= 2;
            ids += g[i].id >= 0;
        }
    }
    /* the random sets exercised the rule: many multi-blob groups and decoded ids */
    assert_true(multi > 200);
    assert_true(ids > 100);
}

/* The shape in one place: the cone above is 0.30 m tall, 0.25 m wide at the base and 0.05 m at the
 * top, so 0.25 - 0.20 * 2/3 = 0.11667 m at z = 0.20 m; below the base and above the top the end
 * diameters; a cylinder its base diameter at every height. */
static void test_diameter_at(void **st)
{
    cyl_landmark_model m = cone_model();
    (void)st;
    assert_float_equal(cyl_landmark_height_m(&m), 0.30, 1e-12);
    assert_float_equal(cyl_landmark_diameter_at_m(&m, 0.0), 0.25, 1e-12);
    assert_float_equal(cyl_landmark_diameter_at_m(&m, 0.20), 0.25 - 0.20 * 2.0 / 3.0, 1e-12);
    assert_float_equal(cyl_landmark_diameter_at_m(&m, 0.30), 0.05, 1e-12);
    assert_float_equal(cyl_landmark_diameter_at_m(&m, -1.0), 0.25, 1e-12);
    assert_float_equal(cyl_landmark_diameter_at_m(&m, 9.0), 0.05, 1e-12);
    m.shape = CYL_SHAPE_CYLINDER;
    assert_float_equal(cyl_landmark_diameter_at_m(&m, 0.20), 0.25, 1e-12);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_striped_cone),
        cmocka_unit_test(test_two_cones_and_clutter),
        cmocka_unit_test(test_upside_down),
        cmocka_unit_test(test_gap_too_large),
        cmocka_unit_test(test_codes),
        cmocka_unit_test(test_single_band),
        cmocka_unit_test(test_checks),
        cmocka_unit_test(test_brute_force),
        cmocka_unit_test(test_diameter_at),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
