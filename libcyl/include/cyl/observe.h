/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- from a frame's blobs to landmark observations with uncertainty
 * (the whole of paper section 2 in one call; docs/uncertainty.md).
 *
 * For every blob of an observed class, in the order of seg->blobs:
 *   1. measurement point = the blob's centroid (mean of its samples, px; with params.subpixel
 *      with its edges placed sub-pixel, cyl/subpixel.h) and its variance by the chosen estimator
 *      (cyl_noise_blob). The camera height h is the height of the optical
 *      centre above the landmark's centroid, so the ray through the blob centroid meets the
 *      plane h below the camera at the landmark's centroid height. Measured on rendered
 *      cylinders seen from above (docs/synthetic.md, "Bias of the blob centroid"): that point
 *      lies 0.6-1.4 cm beyond the cylinder's AXIS, not on its visible face -- the silhouette's
 *      centroid is pulled towards the far edge of the top cap -- so the range is the axis's
 *      (adding the radius would bias it by +5 cm).
 *   2. range, bearing, their 2x2 covariance and the (x, y) covariance (cyl_range_bearing),
 *      input covariance: diag(var_u, var_v) + the camera's intrinsic covariance + mounting
 *      sigmas.
 *   3. confidence (cyl_landmark_confidence) at the depth of the measured point.
 * Rays at or above the horizon give an observation flagged CYL_OBS_NO_RANGE (bearing and its
 * variance valid, range 0, confidence 0); blobs whose point cannot be undistorted are flagged
 * CYL_OBS_INVALID. No allocation: the caller gives the output array and a workspace.
 */
#ifndef CYL_OBSERVE_H
#define CYL_OBSERVE_H

#include <stddef.h>
#include <stdint.h>
#include "cyl/status.h"
#include "cyl/segment.h"
#include "cyl/camera.h"
#include "cyl/noise.h"
#include "cyl/confidence.h"
#include "cyl/rangebearing.h"
#include "cyl/landmark.h"
#include "cyl/subpixel.h"

#ifdef __cplusplus
extern "C" {
#endif

/* cyl_observation.flags: the blob's CYL_BLOB_TOUCH_* (0x01..0x08) and CYL_BLOB_MERGED (0x10)
 * bits are copied, plus: */
#define CYL_OBS_CUT         0x020u  /* cut by the border of the sampled region: not a whole landmark */
#define CYL_OBS_NO_SIZE     0x040u  /* class has no configured physical size: confidence 0 */
#define CYL_OBS_NO_RANGE    CYL_RB_NO_RANGE  /* 0x100: at/above the horizon; bearing only */
#define CYL_OBS_INVALID     0x200u  /* undistortion or geometry failed: only u, v, variances valid */
#define CYL_OBS_NONLINEAR   0x400u  /* sigma(range)/range > params.nonlinear_rel_sigma: the
                                       first-order covariance is no longer accurate (near the horizon) */
#define CYL_OBS_PARTIAL     0x800u  /* aspect_rel outside [m, 1/m], m = params.partial_aspect_min:
                                       the box is not a whole landmark's -- narrower (a side hidden
                                       behind something), shorter (top or bottom hidden) or wider
                                       (run into something of its colour): the centroid, bearing
                                       included, is off by a share of the missing or extra part,
                                       far beyond its variance; or, where the range is accurate
                                       (no CYL_OBS_NONLINEAR), |offset_rel| above
                                       params.partial_offset_max or area_rel below
                                       params.partial_area_min: the box is whole but the blob is
                                       not (a lit or shaded side, or patches, left out of the
                                       class), with the same effect */

/* Default of cyl_observe_params.partial_aspect_min: chosen on the synthetic scene's tuning drives
 * (seeds 1-20, and 1-6 at twice and half the sensor noise; docs/uncertainty.md, "Partly hidden
 * landmarks"). A whole landmark's aspect_rel lies within 0.805-1.075 on 98% of the views of
 * seeds 1-20. */
#define CYL_PARTIAL_ASPECT_MIN_DEFAULT 0.8

/* Default of cyl_observe_params.partial_offset_max: on the synthetic scene's tuning drives (seeds
 * 1-20, and 1-6 at twice and half the sensor noise) |offset_rel| of the views a back end uses whole
 * is below 0.0403 on 99% of them (docs/uncertainty.md, "Blobs with a side missing"). */
#define CYL_PARTIAL_OFFSET_MAX_DEFAULT 0.04

/* Default of cyl_observe_params.missing_part_share: 0 (off). 0.5 is what the tuning drives of two
 * rendered scenes choose (the most drives with both joint ANEES inside, 35 of 52 against 29; held
 * out 72 of 92 against 69, the hard scene's landmarks inside on 8 of 10 against 3), but on clean
 * views it doubles the variance (pixel-noise-only NEES 2.07 -> 0.94, seed 101): aspect_rel spreads
 * over 0.805-1.075 where nothing is missing (docs/uncertainty.md, "A part missing from the box"). */
#define CYL_MISSING_PART_SHARE_DEFAULT 0.0

/* Default of cyl_observe_params.partial_area_min: 0 (off). On the same drives area_rel is above
 * 0.775 on 99% of the views at the nominal sensor noise, but at twice the noise a whole landmark's
 * blob breaks into pieces and keeps 0.75 of its area (median): no threshold separates that from a
 * side missing, which offset_rel does. */
#define CYL_PARTIAL_AREA_MIN_DEFAULT 0.0

/* Default of cyl_observe_params.partial_side_max: 0 (off). side_colour_rel is measured whenever the
 * frame is at hand. 0.5 is what 24 tuning drives of two rendered scenes choose (both joint ANEES
 * inside on 15 against 14), but held out it cost the built-in scene's drives 5% of median ATE and
 * one drive against the fixed-covariance oracle for the hard scene's association errors (7 to 0)
 * (docs/uncertainty.md, "The landmark's colour beyond one side of the box"). */
#define CYL_PARTIAL_SIDE_MAX_DEFAULT 0.0

/* Defaults of cyl_observe_params.side_sigma_rel and side_sigma_free: side_colour_rel as a sigma of
 * the view's u bias, side_sigma_rel * max(|side_colour_rel| - side_sigma_free, 0) * w_px.
 * 0.25 is what 24 tuning drives of two rendered scenes choose (built-in seeds 1-10 and 1-4 at twice
 * the sensor noise, hard 1-10: both joint ANEES inside on 16 against 14 off, 15 at 0.5, 14 at 0.1;
 * association errors 6 to 0); the free share 0.1 was set on the same drives' residuals (the
 * built-in scene's views, unbiased, spread over -0.35..0.37; the hard scene's bias starts above
 * 0.2). Held out: docs/uncertainty.md, "The landmark's colour beyond one side of the box". */
#define CYL_SIDE_SIGMA_REL_DEFAULT 0.25
#define CYL_SIDE_SIGMA_FREE_DEFAULT 0.1

/* Calibration parameters in cyl_observation.jac_calib: fx fy cx cy tilt yaw h s. Their prior
 * covariance is cyl_calib_cov(). */
#define CYL_CALIB_COUNT 8

typedef struct cyl_observe_params {
    cyl_noise_estimator estimator;              /* centroid variance estimator (default CYL_NOISE_LOCAL;
                                                   CYL_NOISE_IMAGE with the frame) */
    cyl_geom_model model;                       /* geometric model (default CYL_GEOM_EXACT) */
    uint8_t class_mask;                         /* bit i: observe blobs of class i (default 0xFF) */
    uint32_t min_area;                          /* skip blobs with fewer samples (default 1) */
    double min_var_px2;                         /* floor of each centroid variance, px^2 (default 0) */
    double nonlinear_rel_sigma;                 /* CYL_OBS_NONLINEAR threshold on sigma_r / r
                                                   (default 0.055: beyond it Monte Carlo shows the
                                                   first-order range variance off by > 3%, roughly
                                                   10 (sigma_r/r)^2; <= 0 disables) */
    double partial_aspect_min;                  /* CYL_OBS_PARTIAL when aspect_rel is below this or
                                                   above its inverse (default CYL_PARTIAL_ASPECT_MIN_DEFAULT;
                                                   <= 0 disables) */
    double partial_offset_max;                  /* CYL_OBS_PARTIAL when |offset_rel| is above this
                                                   (default CYL_PARTIAL_OFFSET_MAX_DEFAULT; <= 0
                                                   disables) */
    double partial_area_min;                    /* CYL_OBS_PARTIAL when area_rel is below this
                                                   (default CYL_PARTIAL_AREA_MIN_DEFAULT: off; <= 0
                                                   disables) */
    double partial_side_max;                    /* CYL_OBS_PARTIAL when |side_colour_rel| is above
                                                   this (default CYL_PARTIAL_SIDE_MAX_DEFAULT: off;
                                                   <= 0 disables; needs image; with CYL_CONFIG_SUBPIXEL
                                                   0, CYL_ERR_UNSUPPORTED) */
    cyl_landmark_size size[CYL_MAX_CLASSES];    /* physical size of each class's landmarks, m
                                                   (default 0 = unknown) */
    /* CYL_NOISE_IMAGE and subpixel: the frame and colour table seg was made from, and the image
     * estimator's settings (cyl_noise_blob_image). Both pointers must be set for either. */
    const cyl_image *image;                     /* default NULL */
    const cyl_colortable *table;                /* default NULL */
    cyl_noise_image_params image_noise;         /* default cyl_noise_image_params_default() */
    double silhouette_rel_sigma;                /* the silhouette's geometric bias (cyl/silhouette.h)
                                                   is taken out of the measurement point of every
                                                   uncut blob of a class with a size, with this
                                                   relative uncertainty (default 0.25: a prior, not
                                                   tuned); < 0: not corrected */
    double silhouette_sigma_u_px;               /* and this absolute one, px, per axis: what is not
                                                   geometry (shading, the table's erosion, chroma
                                                   subsampling; default 0.25; chosen on the
                                                   synthetic scene's tuning seeds 1-20 for the
                                                   blob's own edges; 0.05 with sub-pixel edges,
                                                   docs/uncertainty.md) */
    double silhouette_sigma_v_px;               /* likewise v (default 0.25; 0.125 with sub-pixel
                                                   edges) */
    double group_silhouette_sigma_u_px;         /* the same for grouped landmarks
                                                   (cyl_observe_groups), px (default 0.25 with
                                                   either edges: on the multiband scene's tuning
                                                   seeds the single blobs' values left grouped
                                                   observations over-confident, docs/uncertainty.md) */
    double group_silhouette_sigma_v_px;         /* likewise v (default 0.25) */
    int subpixel;                               /* 1: each blob's centroid with its edges placed
                                                   sub-pixel (cyl/subpixel.h: the shaded side's
                                                   bias taken out); needs image and table (default
                                                   0: the blob's centroid, as the table cut it; 1
                                                   with the frame) */
    cyl_subpixel_params subpixel_params;        /* default cyl_subpixel_params_default() */
    double subpixel_rel_sigma;                  /* the sub-pixel edges' shift of a single blob's
                                                   centroid (subpixel_du_px, dv_px) is a
                                                   correction too: this share of it is its
                                                   uncertainty, added to the bias variance
                                                   (bias_var_*) where the silhouette is corrected
                                                   (default 0: none; 0.25, silhouette_rel_sigma's
                                                   prior, trades cautious poses at the nominal
                                                   noise for consistent ones at half the noise and
                                                   in the hard scene: docs/uncertainty.md) */
    double missing_part_share;                  /* a part missing from a single blob's box, or
                                                   extra, as aspect_rel measures it (w_px (1/aspect_rel
                                                   - 1) of its width, h_px (1 - 1/aspect_rel) of its
                                                   height), moves the centroid by up to half of it,
                                                   to a side not known: this share of that shift is
                                                   taken as a bias sigma, px, added to var_*_px2,
                                                   bias_var_*_px2 and the covariances, where the
                                                   silhouette is corrected (default
                                                   CYL_MISSING_PART_SHARE_DEFAULT; 0: none) */
    double side_sigma_rel;                      /* the landmark's colour beyond one side of a single
                                                   blob's box (side_colour_rel, measured with the
                                                   frame) moves its centroid away from that side:
                                                   side_sigma_rel * max(|side_colour_rel| -
                                                   side_sigma_free, 0) * w_px is taken as a sigma of
                                                   the view's u bias, px, added to var_u_px2 and the
                                                   covariances (not to bias_var: it changes from view
                                                   to view) (default CYL_SIDE_SIGMA_REL_DEFAULT; 0:
                                                   none; needs image and CYL_CONFIG_SUBPIXEL, else
                                                   side_colour_rel is 0 and nothing is added) */
    double side_sigma_free;                     /* |side_colour_rel| up to this adds nothing
                                                   (default CYL_SIDE_SIGMA_FREE_DEFAULT, 0..1) */
} cyl_observe_params;

typedef struct cyl_observation {
    uint32_t blob;              /* index of the blob in seg->blobs */
    uint8_t cls;                /* class index */
    uint32_t flags;             /* CYL_BLOB_TOUCH_*, CYL_BLOB_MERGED, CYL_OBS_* bits */
    uint32_t area;              /* samples in the blob */
    double u_px;                /* measurement point column, px: the blob's centroid less the
                                   silhouette's bias (centroid_u_px - bias_u_px) */
    double v_px;                /* measurement point row, px */
    double var_u_px2;           /* variance of u_px, px^2: the centroid's (at least min_var_px2)
                                   plus bias_var_u_px2 */
    double var_v_px2;           /* variance of v_px, px^2 */
    double centroid_u_px;       /* the blob's centroid, column, px (with params.subpixel: with its
                                   edges placed sub-pixel, the blob's own plus subpixel_du_px) */
    double centroid_v_px;       /* the blob's centroid, row, px */
    double subpixel_du_px;      /* the sub-pixel edges' shift of the centroid, u, px (0: none) */
    double subpixel_dv_px;      /* likewise v, px */
    double bias_u_px;           /* silhouette bias taken out, u, px (0: none; cyl/silhouette.h) */
    double bias_v_px;           /* silhouette bias taken out, v, px (< 0: centroid above the centre) */
    double bias_var_u_px2;      /* its variance, px^2 (part of var_u_px2) */
    double bias_var_v_px2;      /* likewise v, px^2 */
    double range_m;             /* range from the robot centre, m (0 if CYL_OBS_NO_RANGE) */
    double bearing_rad;         /* bearing from the robot centre, rad, left positive */
    double cov_rb[2][2];        /* covariance of (range_m, bearing_rad): m^2, m rad; m rad, rad^2 */
    double x_m, y_m;            /* landmark in the robot frame (x forward, y left), m */
    double cov_xy[2][2];        /* covariance of (x_m, y_m), m^2 */
    double depth_m;             /* depth of the point along the optical axis, m */
    double w_px, h_px;          /* blob bounding box, px (samples times step) */
    double w_est_px, h_est_px;  /* expected size of a landmark of the class at depth_m, px */
    double confidence;          /* eq. 7, 0..1 (0 if cut, no range or no size) */
    double confidence_uncut;    /* score of the uncut dimensions, 0..1 (cyl_landmark_confidence) */
    double aspect_rel;          /* (w_px / h_px) / (w_est_px / h_est_px), unitless: the blob's
                                   width-to-height ratio over the whole landmark's at its place in
                                   the image (the depth cancels, so a wrong range does not move
                                   it); about 1 for a whole landmark, < 1 when a side is hidden,
                                   > 1 when the top or bottom is; 0 when unknown (no size,
                                   no range) */
    double area_rel;            /* the blob's area (with its edges moved, when they are: the
                                   sub-pixel edges' area) over the area of the whole landmark's
                                   silhouette at the measured place (cyl_silhouette_bias.area_px2),
                                   unitless: about 1 for a whole landmark, less when parts of it
                                   were not classified; 0 when unknown (no size, no range, cut by
                                   the border, a group of bands) */
    double offset_rel;          /* (u_px - the blob box's middle column) / w_px, unitless: a whole
                                   landmark's silhouette is symmetric about its axis, so its
                                   measurement point lies at the box's middle (within 0.04 of the
                                   width on 99% of the synthetic drives' views used whole); a side missing
                                   moves the centroid by about half the missing share of the width
                                   while the box stays; 0 when unknown (as area_rel) */
    /* The calibration's share, for back ends that estimate the calibration error as a state:
     * it is constant during a run, so per-observation factors with cov_rb are not independent
     * (docs/uncertainty.md, "Constant calibration errors"). */
    double jac_calib[2][CYL_CALIB_COUNT]; /* d(range_m, bearing_rad)/d(fx, fy, cx, cy [px], tilt, yaw
                                   [rad], height, offset [m]) */
    double cov_rb_frame[2][2];  /* cov_rb from the inputs that change frame to frame only (centroid
                                   noise) and the distortion terms: m^2, m rad, rad^2 */
    /* Landmarks of several bands (cyl_observe_groups); a blob's observation (cyl_observe) has
     * model CYL_NO_MODEL, group_flags 0, landmark_id -1 and code_confidence 0. */
    uint16_t model;             /* index of the landmark model, or CYL_NO_MODEL */
    uint32_t group_flags;       /* the group's CYL_GROUP_* bits */
    int32_t landmark_id;        /* identity read from the landmark's code, or -1 (none, or not read
                                   confidently: cyl/landmark.h) */
    double code_confidence;     /* the group's code confidence, 0..1 */
    double z_ref_m;             /* height above the centroid plane of the axis point the range and
                                   bearing refer to (cyl_observe_groups; 0 for a blob's), m */
    double side_colour_rel;     /* share of the pixels in a 3 px strip just left of the blob's box
                                   (its middle 60% of rows) whose chroma is the blob's (pointing
                                   within 25.8 deg of the blob's mean chroma, at least half as
                                   strong), less that share just right of it, -1..1, unitless: the
                                   landmark's colour going on beyond one side, a part of it not
                                   classified there (a lit side paler than the class), which moves
                                   the centroid away from that side; 0 when not measured (no image,
                                   a group, the strips outside the frame, a colourless blob, a
                                   build without CYL_CONFIG_SUBPIXEL) */
} cyl_observation;

#define CYL_NO_MODEL 0xFFFFu    /* cyl_observation.model of an observation made from one blob */

/* The defaults above. */
cyl_observe_params cyl_observe_params_default(void);

/* The defaults for a caller that observes with the frame at hand (it sets image and table per
 * frame, as a frontend does): cyl_observe_params_default() with the image estimator, sub-pixel
 * edges, and the silhouette's absolute sigmas that the sub-pixel edges leave, u 0.05 px and
 * v 0.125 px (chosen on the synthetic scene's tuning seeds 1-20, docs/uncertainty.md). */
cyl_observe_params cyl_observe_params_default_frame(void);

/* Workspace bytes cyl_observe() needs for this segmentation and parameters. */
size_t cyl_observe_work_size(const cyl_segmentation *seg, const cyl_observe_params *p);

/* Observations of the blobs of seg into out[0 .. cap-1]; *n_out receives the count. Returns
 * CYL_OK, CYL_TRUNCATED (more blobs than cap: the first cap are filled), CYL_ERR_ARG,
 * CYL_ERR_CAMERA (cyl_camera_check failed) or CYL_ERR_NOMEM (work too small). */
cyl_status cyl_observe(const cyl_segmentation *seg, const cyl_camera *cam,
                       const cyl_observe_params *p, void *work, size_t work_size,
                       cyl_observation *out, uint32_t cap, uint32_t *n_out);

/* Observations of grouped landmarks (cyl_group_blobs, cyl/landmark.h), one per group of
 * groups[0 .. n_groups-1], made as cyl_observe() makes them from a blob, with these differences:
 *   - the centroid is that of all the group's samples, its variance sum_i (n_i / N)^2 var_i over
 *     the member blobs (n_i samples each, N in all; their edges are independent), each var_i by
 *     the chosen estimator;
 *   - the measurement point is the image of the landmark's axis at height z_ref_m above the
 *     centroid plane (the plane the camera's height_m refers to; the landmark stands on the floor
 *     plane_height_m below it): the middle of the matched bands, weighted by their side areas. The
 *     silhouette bias taken out is that of the matched bands (cyl_silhouette_bias_model) from that
 *     point, and the range and bearing are those of the landmark's axis;
 *   - the confidence compares the group's box with the expected box of the whole landmark (its
 *     widest diameter, its total height); blob is the group's first member, area the samples of
 *     all members; model, group_flags, landmark_id and code_confidence come from the group.
 * p->size and p->class_mask are not used. Returns as cyl_observe(); CYL_ERR_ARG also for a group
 * whose model index or blob indices are out of range, or plane_height_m < 0. */
cyl_status cyl_observe_groups(const cyl_segmentation *seg, const cyl_group *groups, uint32_t n_groups,
                              const cyl_landmark_model *models, uint32_t n_models, double plane_height_m,
                              const cyl_camera *cam, const cyl_observe_params *p, void *work, size_t work_size,
                              cyl_observation *out, uint32_t cap, uint32_t *n_out);

/* Prior covariance of the calibration parameters of cyl_observation.jac_calib (fx fy cx cy tilt
 * yaw h s): the camera's intrinsic covariance block and the mount variances. */
void cyl_calib_cov(const cyl_camera *cam, double cov[CYL_CALIB_COUNT][CYL_CALIB_COUNT]);

/* Error budget (Tables 8, 9) of one observation made with camera cam and model. */
cyl_status cyl_observation_budget(const cyl_observation *obs, const cyl_camera *cam,
                                  cyl_geom_model model, cyl_error_budget *b);

#ifdef __cplusplus
}
#endif
#endif /* CYL_OBSERVE_H */
