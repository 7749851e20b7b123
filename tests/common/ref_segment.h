/* SPDX-License-Identifier: BSD-3-Clause */
/* Brute-force reference segmentation for tests: per-pixel classification
 * through cyl_image_pixel(), per-row run filtering, flood-fill labelling of
 * 4-connected samples of one class. Slow and obvious on purpose. No merging. */
#ifndef CYL_TEST_REF_SEGMENT_H
#define CYL_TEST_REF_SEGMENT_H
#include "cyl/segment.h"

typedef struct ref_blob {
    unsigned cls;
    uint32_t x0, y0, x1, y1, area;
    double cx, cy, mxx, myy, mxy;
    uint32_t first_x, first_y;   /* first sample in raster order */
    int touches;                  /* CYL_BLOB_TOUCH_* bits */
    int weak_only;                /* of a class's weak evidence alone (no run of the class itself) */
} ref_blob;

/* Returns the number of blobs written (<= max_blobs), or -1 on allocation failure.
 * label_out (optional, grid size nx*ny) receives each sample's blob index or -1. */
int ref_segment(const cyl_colortable *t, const cyl_image *img, const cyl_segment_params *p,
                ref_blob *out, int max_blobs, int *label_out);
#endif
