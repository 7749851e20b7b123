/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- a blob's centroid with its edges placed to a fraction of a pixel.
 *
 * A blob is the set of samples the colour table classifies. Where the image is blurred (optics,
 * chroma filtering), an edge sample is a mix of the landmark's colour and the background's, and the
 * table's boundary in colour space decides how much of the mix still counts: the blob's edge lies
 * where the mix reaches the table's threshold, not where the landmark's edge is. When the two sides
 * of a landmark differ -- the shaded side is darker, so its mix crosses the threshold further in --
 * the blob loses more on one side than the other and its centroid moves: 0.1-0.5 px on the rendered
 * scenes' cylinders, the same sign frame after frame for one view (docs/uncertainty.md, "Sub-pixel
 * edges"). That is a bias, not noise.
 *
 * cyl_subpixel_centroid() finds each edge of the blob where the image's colour is halfway between
 * the landmark's and the background's: along the row (left and right edges) or the column (top and
 * bottom edges) through each edge sample, the colours `reach` samples inside and outside the edge
 * are taken as the two sides, every sample in between is projected onto the line from the outside
 * colour to the inside one (s = 0 outside, 1 inside), and the edge is put where s crosses 1/2,
 * interpolated linearly between samples. A symmetric blur of a step crosses 1/2 at the step for any
 * blur width and any contrast, so the edge no longer depends on where the table's threshold lies.
 * The centroid of the blob with each edge sample's slab moved to its crossing is returned, with its
 * shift from the blob's own centroid.
 *
 * An edge is left where the table put it when the far inside sample is not of the blob's class, the
 * far outside sample is of it (another landmark, or the blob's own other part within reach), a
 * sample lies outside the sampled region, the two sides differ by less than min_contrast, or no
 * crossing lies within reach. A sharp edge (no blur) gives s = 0 then 1 across it: its crossing is
 * the table's edge, and the centroid is the blob's.
 *
 * Cost: O(perimeter x reach) pixel reads and two table look-ups per edge sample; no memory beyond
 * the stack. Works on the sampling grid of the segmentation (x_step, y_step).
 */
#ifndef CYL_SUBPIXEL_H
#define CYL_SUBPIXEL_H

#include <stdint.h>
#include "cyl/status.h"
#include "cyl/image.h"
#include "cyl/colortable.h"
#include "cyl/segment.h"

#ifdef __cplusplus
extern "C" {
#endif

#define CYL_SUBPIXEL_MAX_REACH 8u

typedef struct cyl_subpixel_params {
    uint32_t reach;          /* samples from an edge to the colour taken as each side's, 1..8 (default 3;
                                chosen on the rendered scenes' tuning seeds, docs/uncertainty.md) */
    double min_contrast;     /* least distance between the two sides' colours, levels (Euclidean in
                                Y, U, V) for an edge to be moved (default 8) */
} cyl_subpixel_params;

typedef struct cyl_subpixel_result {
    double cx_px, cy_px;     /* centroid with the edges moved, image px */
    double du_px, dv_px;     /* cx_px, cy_px minus the blob's centroid (cyl_blob.cx_px, cy_px), px */
    double area_px2;         /* area with the edges moved, px^2 (samples times x_step * y_step) */
    uint32_t edges;          /* edge samples (a sample counts once per side it borders) */
    uint32_t edges_moved;    /* of them, those whose edge was moved to its crossing */
} cyl_subpixel_result;

/* The defaults above. */
cyl_subpixel_params cyl_subpixel_params_default(void);

/* The centroid of blob b of seg (made by cyl_segment from img with table t) with its edges placed
 * sub-pixel. Returns CYL_OK, CYL_ERR_ARG (NULL pointer, reach out of range, min_contrast negative
 * or not finite, a segmentation that does not match the image, a blob of an invalid class) or
 * CYL_ERR_EMPTY (a blob without samples). */
cyl_status cyl_subpixel_centroid(const cyl_segmentation *seg, const cyl_blob *b, const cyl_image *img,
                                 const cyl_colortable *t, const cyl_subpixel_params *p, cyl_subpixel_result *out);

#ifdef __cplusplus
}
#endif

#endif
