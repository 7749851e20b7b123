/* SPDX-License-Identifier: BSD-3-Clause */
#include "cyl/version.h"

const char *cyl_version(void) { return CYL_VERSION_STRING; }
