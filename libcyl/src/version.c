/* SPDX-License-Identifier: BSD-3-Clause */
#include "cyl/config.h"
#include "cyl/version.h"

const char *cyl_version(void) { return CYL_VERSION_STRING; }

uint32_t cyl_config_features(void)
{
    uint32_t f = 0u;
#if CYL_CONFIG_IMAGE_ESTIMATOR
    f |= CYL_FEATURE_IMAGE_ESTIMATOR;
#endif
#if CYL_CONFIG_SUBPIXEL
    f |= CYL_FEATURE_SUBPIXEL;
#endif
#if CYL_CONFIG_MODELS
    f |= CYL_FEATURE_MODELS;
#endif
#if CYL_CONFIG_LEARN
    f |= CYL_FEATURE_LEARN;
#endif
    return f;
}

uint32_t cyl_config_formats(void) { return (uint32_t)CYL_CONFIG_FORMATS; }
