/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- landmarks of more than one colour: band models, and the grouping of a frame's blobs
 * into one landmark each (striped cones, colour-coded cylinders).
 *
 * A landmark model is a vertical sequence of bands, top to bottom. Each band is a colour class
 * or CYL_BAND_GAP, a band the colour table does not classify (a cone's white or black stripe).
 * The shape gives the diameter along the height: a cylinder (one diameter) or a cone or
 * truncated cone (bottom and top diameters, linear in between). The single-colour cylinder of
 * the paper is the one-band model. A model may carry an identity (id >= 0): a coded landmark.
 *
 * The grouping rule (cyl_group_blobs), stated so it can be checked by brute force:
 *  - An assignment gives each coloured band of one model a blob of that band's class or none,
 *    each blob at most once. Its scale: a blob b in band k has s_b = w_b / W_k px per metre,
 *    w_b its box width (px), W_k the band's widest diameter (m: at its bottom for a cone). A
 *    blob fits its band when its box height is at most (1 + scale_tol) s_b H_k + gap_slack_px
 *    (H_k the band's height, m): a taller blob is not that band.
 *  - Two assigned blobs a (band i) and b (band j > i) are compatible when
 *      1. their column extents overlap by at least overlap_min of the narrower one;
 *      2. their scales agree: max(s_a, s_b) / min(s_a, s_b) <= 1 + scale_tol;
 *      3. the rows between them fit the bands between: with s = (s_a + s_b) / 2,
 *         E = s * (sum of H between i and j) and c = cos(depression_max), the gap
 *         g = y0_b - y1_a - 1 (px; negative when the boxes overlap) lies in
 *         [c E (1 - scale_tol) - (w_a + w_b) / 4 * sin(depression_max) - gap_slack_px,
 *          E (1 + scale_tol) + gap_slack_px]
 *         (seen from above, a band's edge is an ellipse: the boxes of touching bands overlap by
 *         up to half its height, and bands look shorter by up to cos(depression));
 *    and an assignment is compatible when all its blobs fit and all its pairs are.
 *  - Its cost is the sum over its pairs of |ln(s_a / s_b)| + |g - E_mid| / (s (sum of H from i
 *    through j)), with E_mid the middle of the gap interval above.
 *  - Groups are chosen greedily: among the compatible assignments of two or more blobs, of every
 *    model, with no blob already taken, the one with the most blobs, then the least cost, then
 *    the lowest model index, then the lowest blob indices band by band (top band first); again
 *    until none is left. Then each blob not taken whose class is a band of some model becomes a
 *    group alone, in blob order, with the model (and band) where it fits that has the fewest
 *    coloured bands (then the lowest model and band index); a blob that fits no band stays
 *    ungrouped.
 *  - Identity: a group of a model with id >= 0 gets that id when every coloured band has its
 *    blob, no other blob of the model's classes has its centre in the group's box
 *    (CYL_GROUP_EXTRA_BAND), and the same blobs do not also form a compatible assignment of
 *    another model (CYL_GROUP_AMBIGUOUS: they could be that landmark, with a band hidden or a
 *    gap misjudged).
 *    Otherwise the id is -1: a code that cannot be read confidently gives no id.
 *
 * No allocation: the caller passes a workspace of cyl_group_work_size() bytes.
 */
#ifndef CYL_LANDMARK_H
#define CYL_LANDMARK_H

#include <stddef.h>
#include <stdint.h>
#include "cyl/status.h"
#include "cyl/segment.h"

#ifdef __cplusplus
extern "C" {
#endif

#define CYL_MODEL_MAX_BANDS 4     /* bands per landmark model */
#define CYL_BAND_GAP 0xFFu        /* cyl_landmark_model.band_cls: a band the table does not classify */

typedef enum cyl_model_shape {
    CYL_SHAPE_CYLINDER = 0,       /* diameter_bottom_m throughout */
    CYL_SHAPE_CONE = 1            /* diameter_bottom_m at the base to diameter_top_m at the top, linear */
} cyl_model_shape;

typedef struct cyl_landmark_model {
    uint8_t n_bands;                              /* 1 .. CYL_MODEL_MAX_BANDS */
    uint8_t band_cls[CYL_MODEL_MAX_BANDS];        /* class of each band, top to bottom, or CYL_BAND_GAP
                                                     (not the first or last band) */
    double band_height_m[CYL_MODEL_MAX_BANDS];    /* height of each band, m (> 0) */
    cyl_model_shape shape;                        /* CYL_SHAPE_CYLINDER or CYL_SHAPE_CONE */
    double diameter_bottom_m;                     /* diameter at the base, m (> 0) */
    double diameter_top_m;                        /* diameter at the top, m (cone only; >= 0) */
    int32_t id;                                   /* identity of a coded landmark, or -1 */
} cyl_landmark_model;

typedef struct cyl_group_params {
    double overlap_min;           /* column overlap of two bands' blobs, fraction of the narrower
                                     one (default 0.5) */
    double scale_tol;             /* relative tolerance of scales and band heights (default 0.35) */
    double gap_slack_px;          /* px added to every vertical tolerance: edge blur, the table's
                                     erosion, min_run_px (default 3) */
    double depression_max_deg;    /* steepest view down onto a landmark, deg (default 45) */
    uint32_t max_candidates;      /* compatible assignments kept for the greedy choice (default
                                     1024; cyl_group_work_size grows with it) */
} cyl_group_params;

/* cyl_group.flags */
#define CYL_GROUP_MISSING_BAND 0x1u  /* a coloured band of the model has no blob */
#define CYL_GROUP_EXTRA_BAND   0x2u  /* another blob of the model's classes has its centre in the
                                        group's box */
#define CYL_GROUP_CUT          0x4u  /* a member blob touches the border of the sampled region */
#define CYL_GROUP_AMBIGUOUS    0x8u  /* the same blobs also fit another model */

typedef struct cyl_group {
    uint16_t model;               /* index of the model in the models array */
    uint8_t n_matched;            /* coloured bands with a blob */
    uint8_t n_coloured;           /* coloured bands of the model */
    uint32_t flags;               /* CYL_GROUP_* */
    uint32_t blob[CYL_MODEL_MAX_BANDS]; /* per band, top to bottom: index in seg->blobs, or
                                     CYL_NONE (gap band, or missing) */
    uint16_t x0, y0, x1, y1;      /* union of the member blobs' boxes, px (inclusive) */
    uint32_t area;                /* samples in the member blobs */
    double cx_px, cy_px;          /* centroid of all member samples, px */
    double scale_px_per_m;        /* mean of the members' scales s_b, px per metre */
    double cost;                  /* the assignment's cost (0 for a single blob) */
    int32_t id;                   /* the model's id when the code was read confidently, else -1 */
    double code_confidence;       /* n_matched / n_coloured, 0 when CYL_GROUP_EXTRA_BAND or
                                     CYL_GROUP_AMBIGUOUS is set */
} cyl_group;

/* The defaults above. */
cyl_group_params cyl_group_params_default(void);

/* CYL_OK, or CYL_ERR_ARG for a model out of its documented ranges (no coloured band, a gap
 * first or last, a non-positive height or diameter) or two models with the same sequence of
 * bands, and CYL_ERR_CLASS for a class index >= CYL_MAX_CLASSES. */
cyl_status cyl_landmark_models_check(const cyl_landmark_model *models, uint32_t n_models);

/* The model's height, m: the sum of its band heights. */
double cyl_landmark_height_m(const cyl_landmark_model *m);

/* The model's diameter, m, at height z_m above its base (clamped to 0 .. its height): the base
 * diameter throughout for a cylinder, linear from base to top for a cone. The one place the shape
 * is interpreted: grouping, observation and silhouette all ask here. */
double cyl_landmark_diameter_at_m(const cyl_landmark_model *m, double z_m);

/* Workspace bytes cyl_group_blobs() needs for a segmentation of up to max_blobs blobs. */
size_t cyl_group_work_size(uint32_t max_blobs, const cyl_group_params *p);

/* Group the blobs of seg by the rule above into out[0 .. cap-1]; *n_out receives the count.
 * Returns CYL_OK, CYL_TRUNCATED (more groups than cap, or more compatible assignments than
 * p->max_candidates: the result is valid for those kept), CYL_ERR_ARG, CYL_ERR_CLASS or
 * CYL_ERR_NOMEM (work smaller than cyl_group_work_size(seg->n_blobs, p)). */
cyl_status cyl_group_blobs(const cyl_segmentation *seg, const cyl_landmark_model *models,
                           uint32_t n_models, const cyl_group_params *p, void *work,
                           size_t work_size, cyl_group *out, uint32_t cap, uint32_t *n_out);

#ifdef __cplusplus
}
#endif
#endif /* CYL_LANDMARK_H */
