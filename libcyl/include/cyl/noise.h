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
    CYL_NOISE_LOCAL = 2     /* eq. 6: 3x3 neighbourhood (default; the paper's best) */
} cyl_noise_estimator;

typedef struct cyl_centroid_noise {
    double cx_px;           /* centroid column, px (mean of the samples' columns) */
    double cy_px;           /* centroid row, px */
    double var_x_px2;       /* variance of cx_px, px^2 */
    double var_y_px2;       /* variance of cy_px, px^2 */
    uint32_t n;             /* samples in the blob */
    uint32_t box_w;         /* bounding box width, samples */
    uint32_t box_h;         /* bounding box height, samples */
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

#ifdef __cplusplus
}
#endif
#endif /* CYL_NOISE_H */
