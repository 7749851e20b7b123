/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- variance of a blob's centroid from a single frame (paper section
 * 2.1, eqs. 3-6; paper-model.md "Centroid variance from one frame").
 *
 * Each segmented sample is a Bernoulli trial; the centroid m_x = sum(i X_ij) / n
 * has VAR(m_x) = sum_ij ((i - m_x)/n)^2 rho_ij (1 - rho_ij). The estimators
 * differ in how rho_ij is estimated:
 *   CYL_NOISE_UNIFORM (eq. 4): rho = n / (h w) over the bounding box (h rows, w columns):
 *       VAR(m_x) = h sum_{i in box columns} ((i - m_x)/n)^2 rho (1 - rho)
 *       VAR(m_y) = w sum_{j in box rows}    ((j - m_y)/n)^2 rho (1 - rho)
 *   CYL_NOISE_COLUMN (eq. 5): n_i samples in column i, n_j in row j:
 *       VAR(m_x) = sum_i ((i - m_x)/n)^2 n_i (1 - n_i / h)
 *       VAR(m_y) = sum_j ((j - m_y)/n)^2 n_j (1 - n_j / w)
 *   CYL_NOISE_LOCAL (eq. 6): N(i,j) = this blob's samples in the 3x3 window at (i, j):
 *       VAR(m_x) = sum_{i,j: 0<N<9} ((i - m_x)/n)^2 N/9 (1 - N/9)   (likewise m_y with j)
 *     summed over every grid point with 0 < N < 9, including points just outside the box.
 *     Cost O(runs of the blob + rows of its box), i.e. O(perimeter), no workspace: one pass down
 *     the run list with a window of three rows; per row, N is evaluated only near run ends
 *     (stretches of identical single-run rows: closed form for the whole stretch; single runs:
 *     the left and right end zones, N = 3 x rows present exactly between them; other rows: a
 *     bounded dense sweep of the row's span up to 64 samples, else an event sweep over N's
 *     second differences), all in exact 64-bit integer moments.
 *
 * Sampling grid: with segmentation steps x_step, y_step the "pixels" of the formulas are the
 * samples (grid columns i = x / x_step, rows j = y / y_step; the 3x3 window is 3x3 samples).
 * Variances are computed in grid units and multiplied by x_step^2 (x) and y_step^2 (y) to give
 * px^2. The centroid is in full-image px.
 *
 * Only the blob's own runs (the list from blob->first_run through cyl_run.next) are used;
 * the blob's box, area and centroid are recomputed from them (the blob's stored statistics are
 * not trusted). Runs must be in (y, x) order along the list, disjoint and non-empty, as
 * cyl_segment() produces them (checked: CYL_ERR_ARG otherwise), and on the sampling grid.
 */
#ifndef CYL_NOISE_H
#define CYL_NOISE_H

#include <stddef.h>
#include <stdint.h>
#include "cyl/status.h"
#include "cyl/segment.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum cyl_noise_estimator {
    CYL_NOISE_UNIFORM = 0,  /* eq. 4 */
    CYL_NOISE_COLUMN = 1,   /* eq. 5: columns for x, rows for y */
    CYL_NOISE_LOCAL = 2,    /* eq. 6: 3x3 neighbourhood (the paper's best) */
    CYL_NOISE_IMAGE = 3     /* the frame's own evidence: cyl_noise_blob_image() (needs the image and
                               the colour table) */
} cyl_noise_estimator;

typedef struct cyl_centroid_noise {
    double cx_px;           /* centroid column, px (mean of the samples' columns) */
    double cy_px;           /* centroid row, px */
    double var_x_px2;       /* variance of cx_px, px^2 */
    double var_y_px2;       /* variance of cy_px, px^2 */
    uint32_t n;             /* samples in the blob */
    uint32_t box_w;         /* bounding box width, samples */
    uint32_t box_h;         /* bounding box height, samples */
    double sigma_y;         /* CYL_NOISE_IMAGE: noise std of the frame's Y samples, given or estimated
                               (with 8-bit rounding; at least min_sigma), levels (0 otherwise) */
    double sigma_u;         /* CYL_NOISE_IMAGE: noise std of the U samples used, levels */
    double sigma_v;         /* CYL_NOISE_IMAGE: noise std of the V samples used, levels */
    uint32_t band_cells;    /* CYL_NOISE_IMAGE: grid cells simulated around the edges */
} cyl_centroid_noise;

/* Bytes of workspace cyl_noise_blob() needs for blobs at most max_box_w samples wide:
 * CYL_NOISE_COLUMN needs max_box_w 32-bit counters; the other estimators need none (work may
 * then be NULL). */
size_t cyl_noise_work_size(uint32_t max_box_w);

/* Workspace size for any blob of this segmentation (its sampled width). */
size_t cyl_noise_work_size_seg(const cyl_segmentation *seg);

/* Centroid and its variance for blob b of seg (uses seg->runs, seg->x_step, seg->y_step and
 * b->first_run only). work: at least cyl_noise_work_size(box width) bytes aligned for uint32_t
 * (CYL_NOISE_COLUMN only). Returns CYL_OK, CYL_ERR_ARG (NULL, bad estimator, zero steps, a run
 * index out of range), CYL_ERR_EMPTY (no samples) or CYL_ERR_NOMEM (work too small). */
cyl_status cyl_noise_blob(const cyl_segmentation *seg, const cyl_blob *b, cyl_noise_estimator est,
                          void *work, size_t work_size, cyl_centroid_noise *out);

/* ---- CYL_NOISE_IMAGE: the variance the frame itself predicts ------------------------------------
 *
 * Eqs. 4-6 see only the blob's shape; the frame-to-frame scatter of a centroid depends on how close
 * each edge pixel's colour is to the colour table's boundary, relative to the sensor noise. This
 * estimator measures both in the frame (docs/uncertainty.md, "The image estimator"):
 *   1. noise: the std of Y, U and V from second differences along the blob's interior (robust:
 *      values beyond 4 robust sigmas are dropped), at most 8 places per run, so O(runs);
 *   2. edges: every grid cell within band_px cells (Chebyshev) of both a blob cell and a non-blob
 *      cell is re-classified `draws` times: its colour estimated as the mean of the cell and its
 *      two neighbours along the edge (chroma interpolated at the same offsets from the cell's
 *      chroma sample), plus Gaussian noise drawn in pairs whose two members are independent frames
 *      of that std around the cell's colour (the noise left in the mean is cancelled within the
 *      pair); deterministic draws from a hash of the cell, chroma draws shared by the pixels that
 *      share a chroma sample; through the same colour table and class precedence as cyl_segment;
 *   3. per row, each draw is run-length encoded again as cyl_segment did (runs shorter than the
 *      segmentation's min_run_px dropped; a run counts if it touches the blob's runs in this or a
 *      neighbouring row, or lies within the class's merge_gap_px of the blob's box: both read from
 *      seg, which records them), giving the row's moments
 *      sum (x - m_x) and sum (y - m_y);
 *   4. VAR(m_x) = sum over rows of the variance of the row moment / n^2 (half the mean squared
 *      difference within the pairs of draws; rows that share chroma samples, as in 4:2:0, are
 *      summed first), likewise VAR(m_y).
 * This is eq. 3's sum ((i - m_x)/n)^2 rho (1 - rho) with rho taken from the frame instead of the
 * shape, plus the correlations of a row's cells. Cost O(band cells x draws) = O(perimeter).
 * Interior cells farther than band_px from every edge are taken as certain. */
typedef struct cyl_noise_image_params {
    double sigma_y;          /* noise std of the Y samples, levels, including 8-bit rounding (the draws
                                add sqrt(sigma^2 - 1/12) and round); 0 = estimate from the blob (default 0) */
    double sigma_u;          /* ... of the U samples, levels; 0 = estimate (default 0) */
    double sigma_v;          /* ... of the V samples, levels; 0 = estimate (default 0) */
    double fallback_sigma;   /* levels, for a channel the blob has too few interior samples to
                                estimate (default 2.5) */
    double min_sigma;        /* floor on every std used for the draws, levels (default 0.1) */
    uint32_t band_px;        /* half-width of the simulated band around the edges, grid cells, 1..4
                                (default 4: set on the tuning seed 1 of the imaging sweep,
                                docs/uncertainty.md; no held-out seed was used) */
    uint32_t draws;          /* simulated frames, in pairs, 2..64 (default 32; an odd last one is
                                not used) */
} cyl_noise_image_params;

/* The defaults above. */
cyl_noise_image_params cyl_noise_image_params_default(void);

/* Centroid and its variance for blob b of seg by CYL_NOISE_IMAGE. img and t must be the frame and
 * colour table seg was made from (same ROI grid). No workspace. Returns CYL_OK, CYL_ERR_ARG (NULL,
 * bad parameters, runs as for cyl_noise_blob, a blob outside the image), CYL_ERR_EMPTY, or the
 * image's cyl_image_check() error. A blob with a row of more than 64 run intervals in its band
 * (a very ragged blob) gets the CYL_NOISE_LOCAL variance instead, and band_cells = 0. */
cyl_status cyl_noise_blob_image(const cyl_segmentation *seg, const cyl_blob *b, const cyl_image *img,
                                const cyl_colortable *t, const cyl_noise_image_params *p,
                                cyl_centroid_noise *out);

#ifdef __cplusplus
}
#endif
#endif /* CYL_NOISE_H */
