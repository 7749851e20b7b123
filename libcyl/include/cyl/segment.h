/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- run-length encoding and blobs (paper section 3.2, CMVision-style).
 *
 * cyl_segment() does, in one pass over the frame: classification through a
 * cyl_colortable, run-length encoding per row (runs shorter than min_run_px
 * samples are dropped -- the paper's binary opening), 4-connected union-find
 * over runs of the same class into blobs, per-blob statistics, merging of
 * nearby blobs of the same class, and sorting (by class, then area).
 *
 * Weak classes (hysteresis, cyl_colortable_set_weak): the runs of a class W
 * that is the weak evidence of class S connect with S's runs (4-connected,
 * including side by side in a row) and with each other; a component keeps
 * only if it holds at least one run of S (or, when S's weak_alone_min_area is
 * set, has at least that many samples), and its blob has class S. Learned
 * tables use this for colours that are likely but not certain (the pale top
 * of a lit ball next to its saturated side). Runs keep their own class.
 *
 * Sampling: with a region of interest and steps, the frame is read on the
 * grid of sample points (roi.x + i * x_step, roi.y + j * y_step). Runs and
 * blobs are expressed in full-image pixel coordinates of those samples; areas
 * count samples. With the defaults (whole frame, steps 1) grid and image are
 * the same.
 *
 * Memory: the caller passes one block; cyl_segment_mem_size() says how large.
 * Nothing is allocated and no state is kept between calls other than what the
 * caller holds in cyl_segmentation.
 */
#ifndef CYL_SEGMENT_H
#define CYL_SEGMENT_H

#include <stddef.h>
#include <stdint.h>
#include "cyl/status.h"
#include "cyl/image.h"
#include "cyl/colortable.h"

#ifdef __cplusplus
extern "C" {
#endif

#define CYL_NONE 0xFFFFFFFFu   /* "no index" in run and blob links */

/* One horizontal run of samples of one class. */
typedef struct cyl_run {
    uint16_t x;       /* image column of the first sample, px */
    uint16_t y;       /* image row, px */
    uint16_t width;   /* number of samples; they lie at columns x + k * x_step, k < width */
    uint8_t cls;      /* class index, 0..CYL_MAX_CLASSES-1 */
    uint8_t reserved; /* 0 */
    uint32_t blob;    /* index of the run's blob in cyl_segmentation.blobs, CYL_NONE if dropped */
    uint32_t next;    /* next run of the same blob in (y, x) order, CYL_NONE at the end */
} cyl_run;

/* Blob flags. */
#define CYL_BLOB_TOUCH_LEFT   0x01u  /* has a sample in the first sampled column of the ROI */
#define CYL_BLOB_TOUCH_RIGHT  0x02u  /* ... in the last sampled column */
#define CYL_BLOB_TOUCH_TOP    0x04u  /* ... in the first sampled row */
#define CYL_BLOB_TOUCH_BOTTOM 0x08u  /* ... in the last sampled row */
#define CYL_BLOB_TOUCH_ANY    0x0Fu
#define CYL_BLOB_MERGED       0x10u  /* made of more than one 4-connected component */
#define CYL_BLOB_SPLIT        0x20u  /* one part of a blob cut at a waist (cyl_segment_split) */
#define CYL_BLOB_WEAK_ONLY    0x40u  /* made of weak evidence alone, kept by weak_alone_min_area
                                        (its parts after a split keep the flag) */

/* One blob: 4-connected runs of one class, possibly merged with nearby ones. */
typedef struct cyl_blob {
    uint8_t cls;              /* class index */
    uint8_t flags;            /* CYL_BLOB_* bits */
    uint16_t n_components;    /* 4-connected components merged into it (1 = not merged) */
    uint16_t x0, y0;          /* bounding box, first column and row, px (inclusive) */
    uint16_t x1, y1;          /* bounding box, last column and row, px (inclusive) */
    uint32_t area;            /* samples in the blob (= px with steps 1) */
    uint32_t first_run;       /* index of its first run in cyl_segmentation.runs; follow cyl_run.next */
    uint32_t n_runs;          /* number of runs */
    double cx_px;             /* centroid column, px */
    double cy_px;             /* centroid row, px */
    double mxx_px2;           /* central second moment E[(x-cx)^2], px^2 */
    double myy_px2;           /* central second moment E[(y-cy)^2], px^2 */
    double mxy_px2;           /* central second moment E[(x-cx)(y-cy)], px^2 */
    double orientation_rad;   /* major axis angle from +x (right) towards +y (down), (-pi/2, pi/2] */
    double elongation;        /* 1 - minor/major axis length ratio, 0 (round or square) .. 1 (a line) */
} cyl_blob;

/* Per-class blob rules. */
typedef struct cyl_class_params {
    uint32_t min_area;        /* blobs with fewer samples are dropped, after merging (default 9) */
    int32_t merge_gap_px;     /* merge two blobs of the class when their boxes are at most this many
                                 px apart along x and along y (gap 0 = boxes touch); < 0 disables (default 3) */
    double merge_min_density; /* ... and the merged area / merged bounding-box area (in samples) is at
                                 least this, 0..1 (default 0.5) */
    uint32_t weak_alone_min_area; /* with a weak class: a component of the class's weak runs alone
                                 (no run of the class itself) is a blob of the class when it has at
                                 least this many samples, after merging (0: never, the default) */
} cyl_class_params;

typedef struct cyl_segment_params {
    uint16_t min_run_px;      /* runs shorter than this many samples are dropped (default 3; 1 keeps all) */
    uint16_t x_step;          /* sample every x_step-th column (default 1) */
    uint16_t y_step;          /* sample every y_step-th row (default 1) */
    cyl_roi roi;              /* region of interest (default all zero = whole frame) */
    cyl_class_params cls[CYL_MAX_CLASSES]; /* per-class rules */
    uint8_t scalar_only;      /* 1: use the scalar C99 reference path even where a vector path
                                 exists (comparisons, tests); results are bit-identical either
                                 way (default 0) */
} cyl_segment_params;

/* Defaults described above. */
cyl_segment_params cyl_segment_params_default(void);

/* The vector path cyl_segment() uses on this build and CPU: "avx2" or "ssse3" (x86, chosen
 * at run time unless the build targets them), "neon" (AArch64, or ARMv7 built with NEON) or
 * "scalar" (every other target, Cortex-M included, and builds with -DCYL_NO_SIMD). The
 * vector path skips background 32 pixels at a time (see the design notes in segment.c);
 * where a run may start, the scalar code decides. */
const char *cyl_segment_vector_path(void);

/* Result of cyl_segment(). Set up with cyl_segmentation_init(); reused frame after frame. */
typedef struct cyl_segmentation {
    cyl_run *runs;            /* kept runs, in (y, x) order */
    uint32_t n_runs;          /* runs in use */
    uint32_t max_runs;        /* capacity */
    cyl_blob *blobs;          /* blobs sorted by class (ascending), then area (descending),
                                 then y0, x0 */
    uint32_t n_blobs;         /* blobs in use */
    uint32_t max_blobs;       /* capacity */
    uint32_t class_first[CYL_MAX_CLASSES]; /* index of the first blob of each class */
    uint32_t class_count[CYL_MAX_CLASSES]; /* number of blobs of each class */
    uint32_t x_origin, y_origin; /* first sample of the grid (the ROI's corner), px */
    uint32_t x_last, y_last;  /* last sampled column and row, px */
    uint16_t x_step, y_step;  /* grid steps used */
    uint32_t frame_width, frame_height; /* size of the frame segmented, px */
    uint16_t min_run_px;      /* the params' min_run_px these runs were made with (1 after init) */
    int32_t merge_gap_px[CYL_MAX_CLASSES]; /* each class's merge_gap_px used, px (< 0: no
                                 merging; -1 after init): what cyl_noise_blob_image() redoes */
    uint32_t truncated;       /* 0, or CYL_SEG_RUNS_FULL | CYL_SEG_BLOBS_FULL */
    void *work;               /* internal workspace (inside the caller's block) */
    size_t work_size;
} cyl_segmentation;

#define CYL_SEG_RUNS_FULL  0x1u  /* more runs than max_runs: rows after the overflow were not encoded */
#define CYL_SEG_BLOBS_FULL 0x2u  /* more components than max_blobs: the later ones were dropped */

/* Worst-case run count of a frame (every row full of minimum-length runs). */
uint32_t cyl_segment_max_runs(uint32_t width, uint32_t height, const cyl_segment_params *p);

/* Bytes of memory cyl_segmentation_init() needs for these capacities (0 on overflow). */
size_t cyl_segment_mem_size(uint32_t max_runs, uint32_t max_blobs);

/* Lay out a caller block of mem_size bytes (at least cyl_segment_mem_size(), any alignment). */
cyl_status cyl_segmentation_init(cyl_segmentation *seg, void *mem, size_t mem_size,
                                 uint32_t max_runs, uint32_t max_blobs);

/* Segment one frame. Returns CYL_OK, CYL_TRUNCATED (results valid for what fitted; see
 * seg->truncated), or an error (CYL_ERR_ARG, _FORMAT, _SIZE). Deterministic: the same
 * frame, table and parameters give bit-identical results. */
cyl_status cyl_segment(const cyl_colortable *t, const cyl_image *img,
                       const cyl_segment_params *p, cyl_segmentation *seg);

/* ---- one frame on several cores ------------------------------------------
 * The library runs no threads; a caller that has cores to spare splits the frame into
 * horizontal bands of sampled rows, encodes each band on its own thread into its own run
 * buffer with cyl_segment_band(), and then, on one thread, cyl_segment_join() connects the
 * runs across the seams and builds the blobs. The result is bit-identical to cyl_segment()
 * on the same frame (when no buffer overflows). Classification and run-length encoding are
 * most of the work on busy frames; the join is linear in the runs. */

/* Number of sampled rows of the ROI grid (0 if the ROI does not fit the image). */
uint32_t cyl_segment_rows(const cyl_image *img, const cyl_segment_params *p);

/* Encode sampled rows [row_begin, row_end) of the ROI grid (row j is image row roi.y + j * y_step)
 * into runs[0, *n_runs), in (y, x) order. Reads t and img only: several calls on disjoint bands
 * may run at once. CYL_TRUNCATED when max_runs was too small (the runs that fitted are kept),
 * CYL_ERR_ARG for a bad band. */
cyl_status cyl_segment_band(const cyl_colortable *t, const cyl_image *img, const cyl_segment_params *p,
                            uint32_t row_begin, uint32_t row_end, cyl_run *runs, uint32_t max_runs,
                            uint32_t *n_runs);

/* Join n_bands bands, given top to bottom (band k: band_runs[k][0, band_n_runs[k])), into seg as
 * cyl_segment() would have made it: runs copied into seg->runs, connected within and across
 * bands, then blobs. Same t, img and p as the bands were encoded with. Returns as cyl_segment();
 * CYL_ERR_ARG when the bands are out of row order. */
cyl_status cyl_segment_join(const cyl_colortable *t, const cyl_image *img, const cyl_segment_params *p,
                            const cyl_run *const *band_runs, const uint32_t *band_n_runs, unsigned n_bands,
                            cyl_segmentation *seg);

/* ---- splitting blobs at a waist ---------------------------------------------
 * Two landmarks of one class that touch in the image form one blob: one above the other (a far
 * cone whose base meets the tip of a nearer one), or side by side. Between the two the blob
 * narrows. cyl_segment_split() looks at the blob's row profile (each sampled row's extent, first
 * to last sample of the row) and its column profile (each sampled column's extent, first to last
 * sampled row with a sample), and cuts at the row or column whose extent is the smallest share
 * of the widest entry before it and the widest after it, when that share is below the class's
 * waist_ratio and both parts keep enough rows (columns). The parts are split again if they have
 * a waist of their own. A single cylinder, box, ball or cone (profiles that grow, stay or shrink
 * steadily, or rise to one peak) has no waist. Rows or columns without a sample (the gap
 * between merged pieces) are never a cut. */
#define CYL_SPLIT_ROWS    0x1u   /* cut between rows (landmarks one above the other) */
#define CYL_SPLIT_COLUMNS 0x2u   /* cut between columns (side by side) */

typedef struct cyl_split_params {
    double waist_ratio[CYL_MAX_CLASSES]; /* split a blob of class k at a row (column) whose extent
                                            is below this share of the widest both before and
                                            after it, 0..1 (0: never; default 0) */
    unsigned axes;                       /* CYL_SPLIT_ROWS and/or CYL_SPLIT_COLUMNS (default
                                            CYL_SPLIT_ROWS) */
    uint16_t min_part_lines;             /* each part keeps at least this many sampled rows (a
                                            row cut) or columns (a column cut) (default 4) */
    double min_part_share;               /* ... and this share of the blob's, 0..0.5
                                            (default 0.15) */
} cyl_split_params;

/* Defaults described above (every waist_ratio 0: nothing is split). */
cyl_split_params cyl_split_params_default(void);

/* Bytes of workspace cyl_segment_split() needs after a segmentation of this frame (two counters
 * a sampled row or column, whichever are more, and one a sampled row). */
size_t cyl_segment_split_work_size(const cyl_segmentation *seg);

/* Split seg's blobs at their waists (above), in place: each part becomes a blob with its own
 * statistics and the flag CYL_BLOB_SPLIT (n_components and CYL_BLOB_MERGED stay the whole's),
 * the blobs are sorted again (seg->blobs' order), and runs, class_first and class_count follow.
 * A column cut splits the runs that cross it in two: the right pieces are inserted into
 * seg->runs after their left ones (the array stays in (y, x) order; run indices change). The
 * cut's edges are not colour edges: the image estimator and the sub-pixel edges treat them as
 * they treat any run end. *n_split (may be NULL): cuts made. CYL_TRUNCATED when seg->max_blobs
 * or seg->max_runs stopped a cut (seg->truncated gains CYL_SEG_BLOBS_FULL or
 * CYL_SEG_RUNS_FULL); CYL_ERR_ARG for bad parameters, CYL_ERR_SIZE for a workspace smaller than
 * cyl_segment_split_work_size(). */
cyl_status cyl_segment_split(cyl_segmentation *seg, const cyl_split_params *p, void *work, size_t work_size,
                             uint32_t *n_split);

#ifdef __cplusplus
}
#endif
#endif /* CYL_SEGMENT_H */
