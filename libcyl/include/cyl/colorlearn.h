/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- learning colour classes from labelled examples.
 *
 * The paper trains a class as a rectangle in chrominance plus a brightness
 * window (cyl_colortable_train). On real camera images that rectangle spans
 * whatever grey, edge or background pixels a training region holds. Here a
 * class is learned as a likelihood ratio instead:
 *
 *  1. Count the training pixels of each class ("positives", e.g. the pixels
 *     inside its labelled boxes) and of the background ("negatives", by
 *     default every pixel outside all labelled boxes) in histograms over the
 *     3-D table's quantised YUV cells (cyl_colorhist, 32 x 64 x 64 cells), in
 *     which chroma may depend on brightness.
 *     A box holds background too (a cone fills half of its box; the edge of a
 *     stripe mixes with the surface it is painted on). Optionally each class
 *     also counts its boxes' surround (a ring of pixels just outside them):
 *     the colours as common around a box as in it are taken out of the
 *     class's density before the ratio (surround_weight).
 *  2. Smooth both with a Gaussian of smooth_sigma_cells cells per axis, so
 *     that colours next to the seen ones (slightly brighter, slightly more
 *     saturated) are covered too, and mix into the background density a
 *     uniform part of weight bg_uniform_weight: a colour never seen in
 *     training is not known to be free of background.
 *  3. A cell's likelihood ratio is L = p_class / p_background. The class
 *     claims every cell with L above the lowest threshold for which the
 *     background pixels it would claim stay within max_bg_fraction (the
 *     false-positive rate, Neyman-Pearson) and never a cell with L below
 *     min_likelihood_ratio.
 *  4. Optionally, a weak class: the cells with L between a second, lower
 *     threshold (chosen the same way from weak_bg_fraction) and the first go
 *     to a second table class marked as the first one's weak evidence
 *     (cyl_colortable_set_weak): segmentation keeps such pixels only where
 *     they touch the class's own (hysteresis, cyl/segment.h).
 *  5. Where two learned classes claim a cell, the one with the larger L keeps
 *     it (a class's own cells before any weak ones); the report says how much
 *     each class lost to each other.
 *
 * The result is written into the table's yuv cells, so segmentation stays a
 * direct lookup. Nothing here allocates: histograms and the workspace are the
 * caller's (cyl_learn_workspace_size()).
 */
#ifndef CYL_COLORLEARN_H
#define CYL_COLORLEARN_H

#include <stddef.h>
#include <stdint.h>
#include "cyl/status.h"
#include "cyl/image.h"
#include "cyl/colortable.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Pixel counts per cell of the 3-D table, indexed like cyl_colortable.yuv
 * flattened: ((Y >> 3) * 64 + (U >> 2)) * 64 + (V >> 2). 512 KiB. */
typedef struct cyl_colorhist {
    uint32_t count[CYL_YUV_CELLS];   /* training pixels per cell */
    uint64_t total;                  /* training pixels added (sum of count) */
} cyl_colorhist;

/* Cell index of a colour. */
static inline uint32_t cyl_yuv_cell(uint8_t Y, uint8_t U, uint8_t V)
{
    return (((uint32_t)(Y >> CYL_YUV_YSHIFT) * CYL_YUV_NC) + (uint32_t)(U >> CYL_YUV_CSHIFT)) * CYL_YUV_NC +
           (uint32_t)(V >> CYL_YUV_CSHIFT);
}

/* Like cyl_colorhist_add(), with each pixel's colour as it would be under an exposure
 * scaled by gain (> 0): Y' = gain Y, U' = 128 + gain (U - 128), V' likewise, rounded and
 * clipped to 0..255. Adding a training image at several gains teaches a class the colours it
 * takes when the light or the exposure changes (photometric augmentation). CYL_ERR_ARG for a
 * gain outside (0, 16]. */
cyl_status cyl_colorhist_add_scaled(cyl_colorhist *h, const cyl_image *img, const cyl_roi *roi,
                                    const uint8_t *mask, size_t mask_stride, uint8_t mask_value,
                                    double gain);

/* Like cyl_colorhist_add_scaled(), with each pixel's colour as it would be under other light: the
 * colour converted to R, G, B (BT.601, full range: R = Y + 1.402 (V - 128),
 * G = Y - 0.344 (U - 128) - 0.714 (V - 128), B = Y + 1.772 (U - 128)), each channel multiplied by its
 * gain (gain_rgb[0] red, [1] green, [2] blue; > 0 and <= 16) and white_add levels added to each
 * (-255..255), clipped to 0..255 as a sensor would, converted back and rounded. Equal gains g with
 * white_add 0 are cyl_colorhist_add_scaled() with gain g; red and blue gains apart model a change of
 * white balance or of the light's colour temperature (warmer: red up, blue down); white_add > 0 a
 * white light added (a highlight: brighter, chroma unchanged, so paler). */
cyl_status cyl_colorhist_add_light(cyl_colorhist *h, const cyl_image *img, const cyl_roi *roi,
                                   const uint8_t *mask, size_t mask_stride, uint8_t mask_value,
                                   const double gain_rgb[3], double white_add);

/* Empty histogram. */
void cyl_colorhist_clear(cyl_colorhist *h);

/* Add the pixels of img inside roi (NULL = whole image) to h. With a mask
 * (one byte per image pixel, mask[y * mask_stride + x] in full-image
 * coordinates, mask_stride >= width) only pixels whose byte equals
 * mask_value count; mask NULL counts every pixel. A count that would pass
 * 2^32 - 1 saturates. */
cyl_status cyl_colorhist_add(cyl_colorhist *h, const cyl_image *img, const cyl_roi *roi,
                             const uint8_t *mask, size_t mask_stride, uint8_t mask_value);

typedef struct cyl_learn_params {
    double max_bg_fraction;      /* false-positive rate: the share of the background density a class
                                    may claim, 0..1 (default 0.0005) */
    double smooth_sigma_cells;   /* Gaussian smoothing of both histograms, sigma in cells per axis
                                    (a cell is 8 Y and 4 U/V levels), 0 = none (default 1.5) */
    double bg_uniform_weight;    /* weight of the uniform colour density mixed into the background
                                    model, 0..1 (default 0.02) */
    double min_likelihood_ratio; /* a cell with a smaller ratio is never claimed (default 4) */
    double min_positive_count;   /* ... nor one whose smoothed count of class pixels is below this,
                                    pixels (default 0.5: stray single pixels claim nothing) */
    double weak_bg_fraction;     /* for classes with a weak class: the share of the background density
                                    the class and its weak class may claim together, >= max_bg_fraction
                                    (default 0.01) */
    double min_weak_ratio;       /* a weak cell's ratio is at least this (default 1.5) */
    double min_class_share;      /* the class keeps at least this share of its own training pixels,
                                    the threshold lowered below the rate's if need be (never under
                                    min_likelihood_ratio); 0..1 (default 0: the rate alone) */
    double surround_weight;      /* background subtraction for classes given a surround histogram:
                                    after smoothing, a cell's class count becomes
                                    max(0, n_box - w * (N_box / N_surround) * n_surround), still divided
                                    by N_box: a colour whose share in the boxes is at most w times its
                                    share around them is not the class's; 0 = off, 0..4 (default 0.5) */
} cyl_learn_params;

/* The defaults above: chosen on training data only (docs/colour-learning.md, "How the
 * defaults were chosen"). */
cyl_learn_params cyl_learn_params_default(void);

/* What learning did for one class. Shares are of training pixels (raw counts,
 * not smoothed). */
typedef struct cyl_learn_report {
    double recall;                /* share of the class's positive pixels in the cells it kept */
    double recall_alone;          /* ... in the cells it claimed before overlaps were resolved */
    double bg_fraction;           /* share of the negative pixels in the cells it kept */
    double lr_threshold;          /* likelihood-ratio threshold the false-positive rate chose */
    uint32_t cells;               /* cells kept */
    double weak_recall;           /* share of its positive pixels in the cells its weak class kept */
    double weak_bg_fraction;      /* share of the negative pixels in them */
    double weak_lr_threshold;     /* the weak class's threshold (0 without a weak class) */
    uint32_t weak_cells;          /* cells its weak class kept */
    double grey_fraction;         /* share of its kept cells whose chroma lies within 8 levels of grey
                                     (U and V both within 128 +- 8) */
    double lost_to[CYL_MAX_CLASSES]; /* share of its positive pixels in cells claimed by both it and
                                        class j that class j kept (larger likelihood ratio) */
} cyl_learn_report;

/* One class to learn. */
typedef struct cyl_learn_class {
    unsigned cls;                    /* its table index */
    unsigned weak_cls;               /* table index for its weak evidence, or CYL_CLASS_NONE */
    const cyl_colorhist *positive;   /* its training pixels */
    const cyl_colorhist *surround;   /* pixels just around its boxes (outside every box), or NULL:
                                        what the boxes' background looks like (surround_weight) */
} cyl_learn_class;

/* Bytes of workspace cyl_colortable_learn() needs for n classes. */
size_t cyl_learn_workspace_size(unsigned n);

/* Learn n classes at once against the background histogram negative (shared by
 * all). Each learned class's (and weak class's) previous colours are replaced
 * (cyl_colortable_clear_class) by its learned cells and the weak relation is
 * set; other classes are untouched. reports (n entries) may be NULL.
 * work: cyl_learn_workspace_size(n) bytes aligned for float.
 * Errors: CYL_ERR_ARG (bad parameter, a table index used twice), CYL_ERR_CLASS,
 * CYL_ERR_NOMEM (workspace), CYL_ERR_EMPTY (a class or the background has no
 * pixels, or a class would claim no cell; the table is then unchanged). */
cyl_status cyl_colortable_learn(cyl_colortable *t, const cyl_learn_class *classes, unsigned n,
                                const cyl_colorhist *negative, const cyl_learn_params *params,
                                void *work, size_t work_size, cyl_learn_report *reports);

#ifdef __cplusplus
}
#endif
#endif /* CYL_COLORLEARN_H */
