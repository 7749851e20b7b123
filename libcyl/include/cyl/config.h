/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- compile-time options, for firmware that needs a smaller library (as nanopb's pb.h).
 *
 * Each option is a macro defined when libcyl is compiled, e.g.
 *   make -C libcyl CFLAGS='-Os -DCYL_CONFIG_IMAGE_ESTIMATOR=0 -DCYL_CONFIG_SUBPIXEL=0'
 * Defaults (nothing defined): everything is in. Options change no struct, no enum and no function
 * signature, so code compiled against the headers links with any configuration; a function whose
 * feature is compiled out returns CYL_ERR_UNSUPPORTED (or, for a pixel format, cyl_image_wrap
 * returns CYL_ERR_FORMAT), and cyl_config_features() / cyl_config_formats() tell at run time what
 * the linked library has. `make cross` measures a firmware built with all options off
 * (CYL_CONFIG_FIRMWARE_MINIMAL below) beside the default one.
 *
 *   CYL_CONFIG_IMAGE_ESTIMATOR  1: the image centroid-variance estimator, cyl_noise_blob_image()
 *                                  (CYL_NOISE_IMAGE). 0: the paper's estimators only.
 *   CYL_CONFIG_SUBPIXEL         1: sub-pixel edges, cyl_subpixel_centroid() (params.subpixel).
 *   CYL_CONFIG_MODELS           1: landmark models of several bands: cyl_landmark_models_check(),
 *                                  cyl_group_blobs(), cyl_observe_groups(),
 *                                  cyl_silhouette_bias_model(). 0: single-colour landmarks only.
 *   CYL_CONFIG_LEARN            1: colour learning from examples (cyl/colorlearn.h). Tables made on
 *                                  a host load on any configuration.
 *   CYL_CONFIG_FORMATS          the pixel formats segmented, classified and wrapped: a mask of
 *                                  CYL_FORMAT_BIT(CYL_FMT_...); default all five.
 */
#ifndef CYL_CONFIG_H
#define CYL_CONFIG_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define CYL_FORMAT_BIT(fmt) (1u << (unsigned)(fmt))

/* All options off: what a firmware that segments YUYV and observes single-colour landmarks with
 * the paper's estimators needs (define CYL_CONFIG_FIRMWARE_MINIMAL to get it). */
#ifdef CYL_CONFIG_FIRMWARE_MINIMAL
#ifndef CYL_CONFIG_IMAGE_ESTIMATOR
#define CYL_CONFIG_IMAGE_ESTIMATOR 0
#endif
#ifndef CYL_CONFIG_SUBPIXEL
#define CYL_CONFIG_SUBPIXEL 0
#endif
#ifndef CYL_CONFIG_MODELS
#define CYL_CONFIG_MODELS 0
#endif
#ifndef CYL_CONFIG_LEARN
#define CYL_CONFIG_LEARN 0
#endif
#ifndef CYL_CONFIG_FORMATS
#define CYL_CONFIG_FORMATS CYL_FORMAT_BIT(1) /* CYL_FMT_YUYV */
#endif
#endif

#ifndef CYL_CONFIG_IMAGE_ESTIMATOR
#define CYL_CONFIG_IMAGE_ESTIMATOR 1
#endif
#ifndef CYL_CONFIG_SUBPIXEL
#define CYL_CONFIG_SUBPIXEL 1
#endif
#ifndef CYL_CONFIG_MODELS
#define CYL_CONFIG_MODELS 1
#endif
#ifndef CYL_CONFIG_LEARN
#define CYL_CONFIG_LEARN 1
#endif
#ifndef CYL_CONFIG_FORMATS
#define CYL_CONFIG_FORMATS 0x3Eu /* CYL_FMT_YUYV .. CYL_FMT_YUV444P (1..5) */
#endif

/* Bits of cyl_config_features(). */
#define CYL_FEATURE_IMAGE_ESTIMATOR 0x1u
#define CYL_FEATURE_SUBPIXEL 0x2u
#define CYL_FEATURE_MODELS 0x4u
#define CYL_FEATURE_LEARN 0x8u

/* The features the linked library was compiled with (CYL_FEATURE_* bits). */
uint32_t cyl_config_features(void);
/* The pixel formats the linked library was compiled with (CYL_FORMAT_BIT(CYL_FMT_*) bits). */
uint32_t cyl_config_formats(void);

#ifdef __cplusplus
}
#endif
#endif
