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
 * cyl_subpixel_centroid() finds each outer edge of the blob where the image's colour is halfway
 * between the landmark's and the background's: along the row (left and right edges) or the column
 * (top and bottom edges) through each edge sample, the colours `reach` samples outside and
 * `reach - 1` inside the edge are taken as the two sides, every sample in between is projected onto
 * the line from the outside colour to the inside one (s = 0 outside, 1 inside), and the samples'
 * sum gives the edge: a step at e sampled at p = -R .. R-1 (the table's edge at -1/2) sums to
 * R - 1/2 - e for any symmetric blur, so the edge moves outwards by (sum - R), clamped to
 * +-(R - 1/2). The sum is linear in the samples and indifferent to where a 4:2:2 chroma pair falls.
 * The centroid of the blob with each edge sample's slab moved to its edge is returned, with its
 * shift from the blob's own centroid.
 *
 * An edge is left where the table put it when: an outside sample within reach is of the blob's
 * class (a hole narrower than reach, a ragged end with more of the blob beyond it); more than one
 * inside sample is not of the class (the blob is thinner than the window there); the far inside
 * sample is not of the class; a sample lies outside the sampled region; the two sides differ by
 * less than min_contrast; or it is a row's end whose rows above or below have no blob sample within
 * reach (the first and last rows' ends, and where a shaded top fades out of the class half-way
 * across). A sharp edge (no blur) gives s = 0 then 1 across it and moves nothing.
 *
 * Cost: reach pixel reads and table look-ups per edge sample, and for each blob sample a look-up of
 * the runs of its neighbouring rows (O(area x runs per row)); no memory beyond the stack. Works on
 * the sampling grid of the segmentation (x_step, y_step, the ROI's origin).
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
    uint32_t reach;          /* samples from an edge to the colour taken as each side's, 2..8 (default 5:
                                chosen on the unit test's blurred rectangle, docs/uncertainty.md) */
    double min_contrast;     /* least distance between the two sides' colours, levels (Euclidean in
                                Y, U, V) for an edge to be moved (default 8) */
} cyl_subpixel_params;

typedef struct cyl_subpixel_result {
    double cx_px, cy_px;     /* centroid with the edges moved, image px */
    double du_px, dv_px;     /* cx_px, cy_px minus the blob's centroid (cyl_blob.cx_px, cy_px), px */
    double area_px2;         /* area with the edges moved, px^2 (samples times x_step * y_step) */
    uint32_t edges;          /* edge samples looked at (a sample counts once per side it borders;
                                row ends left out as above are not counted) */
    uint32_t edges_moved;    /* of them, those whose edge was moved to its crossing */
} cyl_subpixel_result;

/* The defaults above. */
cyl_subpixel_params cyl_subpixel_params_default(void);

/* The centroid of blob b of seg (made by cyl_segment from img with table t) with its edges placed
 * sub-pixel. Returns CYL_OK, CYL_ERR_ARG (NULL pointer, reach out of range, min_contrast negative
 * or not finite, a segmentation that does not match the image, a blob of an invalid class, a run
 * chain out of range or order) or CYL_ERR_EMPTY (a blob without samples). */
cyl_status cyl_subpixel_centroid(const cyl_segmentation *seg, const cyl_blob *b, const cyl_image *img,
                                 const cyl_colortable *t, const cyl_subpixel_params *p, cyl_subpixel_result *out);

#ifdef __cplusplus
}
#endif

#endif
