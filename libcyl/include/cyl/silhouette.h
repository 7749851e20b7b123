/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- the geometric bias of a landmark's blob centroid, modelled.
 *
 * The range and bearing of cyl_observe() come from the ray through the blob's centroid, taken as
 * the image of the landmark's centre (its axis at the centroid plane). It is not: the silhouette of
 * a vertical cylinder seen from above its top runs from the front of its base to the back of its
 * top, and perspective makes its near parts larger, so the silhouette's centroid lies above (and, off
 * the image centre, beside) the image of the centre -- 1.5 px at 1 m in the synthetic scene, which
 * is several sigmas of the centroid's noise (docs/synthetic.md, "Bias of the blob centroid").
 *
 * cyl_silhouette_bias() computes that offset from the geometry alone: the camera (intrinsics, lens,
 * tilt, yaw, height, offset), the landmark's size and its position. A cylinder is convex, so its
 * silhouette is the convex hull of the images of its top and bottom circles (exactly so in the
 * pinhole's normalised coordinates, where the hull is found); the hull's outline is then taken
 * through the lens model (in pieces of at most 4 px) and the area centroid computed in pixels, so a
 * tall blob low in a barrel-distorted image has its centroid pulled up as in the image.
 * The offset is returned with a variance for what the model does not know: (rel_sigma x offset)^2
 * for the landmark's true size and shape, plus sigma_px^2 for what is not geometry (shading, the
 * colour table's erosion of the silhouette, the chroma subsampling), per axis.
 */
#ifndef CYL_SILHOUETTE_H
#define CYL_SILHOUETTE_H

#include "cyl/status.h"
#include "cyl/camera.h"
#include "cyl/confidence.h"
#include "cyl/landmark.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Points per circle of the hull (top and bottom); 48 keep the offset within 0.03 px of ray casting
 * (tests/unit/test_silhouette.c; 32 did not: 0.07 px); stack ~3.4 KB on x86-64. */
#define CYL_SILHOUETTE_POINTS 48

typedef struct cyl_silhouette_bias {
    double du_px;          /* silhouette centroid minus the image of the centre, u (right), px */
    double dv_px;          /* likewise v (down), px; < 0: the centroid lies above the centre */
    double var_u_px2;      /* variance of du_px: (rel_sigma du_px)^2 + sigma_px^2, px^2 */
    double var_v_px2;      /* variance of dv_px: (rel_sigma dv_px)^2 + sigma_px^2, px^2 */
    double area_px2;       /* the silhouette's area in the image, px^2 */
} cyl_silhouette_bias;

/* The offset for a landmark of this size standing with its centre at robot-frame (x_m, y_m) on
 * the centroid plane (the plane cam->height_m below the optical centre; the cylinder reaches
 * height_m/2 above and below it). rel_sigma >= 0: the offset's relative uncertainty; sigma_px >= 0:
 * its absolute uncertainty, px. Returns CYL_OK, CYL_ERR_ARG (NULL, size <= 0 or non-finite,
 * rel_sigma or sigma_px < 0 or non-finite), the camera's
 * cyl_camera_check() error, or CYL_ERR_NO_RANGE when part of the landmark is not in front of the
 * camera. */
cyl_status cyl_silhouette_bias_at(const cyl_camera *cam, double x_m, double y_m, const cyl_landmark_size *size,
                                  double rel_sigma, double sigma_px, cyl_silhouette_bias *out);

/* The same for a landmark of several bands (cyl/landmark.h): the offset of the area centroid of
 * the visible parts of the bands in band_mask (bit k: band k, counted from the top) from the image
 * of the landmark's axis at the centroid plane. The landmark stands with its base base_z_m above
 * the centroid plane (negative: below; for landmarks on the floor, minus the plane's height above
 * the floor), its radius linear from the base to the top (a cylinder or a cone). The whole is
 * convex, so band k's image is the convex hull of the images of its two circles, less what the
 * rest of the landmark hides of it: seen from above the band's top, the hull of the part above it
 * (its top cap is hidden unless it is the top band); from below its bottom, the part below. The
 * overlap is a convex polygon clipped in normalised coordinates; areas and centroids are taken in
 * pixels through the lens as above. The cylinder of cyl_silhouette_bias_at() is the one-band model
 * with base_z_m = -height_m / 2. Stack: about 10 KB on 32-bit targets. Returns as
 * cyl_silhouette_bias_at(); CYL_ERR_ARG also for a model that fails cyl_landmark_models_check() or
 * a band_mask that is empty or names bands the model does not have. */
cyl_status cyl_silhouette_bias_model(const cyl_camera *cam, double x_m, double y_m,
                                     const cyl_landmark_model *model, double base_z_m, uint32_t band_mask,
                                     double rel_sigma, double sigma_px, cyl_silhouette_bias *out);

#ifdef __cplusplus
}
#endif
#endif
