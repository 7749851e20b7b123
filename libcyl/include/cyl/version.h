/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- the library's version, at compile time (these macros) and at run time (cyl_version()).
 * A program can check that the headers it was compiled with match the library it links:
 *   if (strcmp(cyl_version(), CYL_VERSION_STRING) != 0) ...
 * The one place the version is written: libcyl's Makefile, the tools' --version, libcyl.pc and the
 * Python package read it from here. */
#ifndef CYL_VERSION_H
#define CYL_VERSION_H

#ifdef __cplusplus
extern "C" {
#endif

#define CYL_VERSION_MAJOR 0
#define CYL_VERSION_MINOR 9
#define CYL_VERSION_PATCH 0
#define CYL_VERSION_STRING "0.9.0"
/* MAJOR * 10000 + MINOR * 100 + PATCH, for #if comparisons */
#define CYL_VERSION_NUMBER (CYL_VERSION_MAJOR * 10000 + CYL_VERSION_MINOR * 100 + CYL_VERSION_PATCH)

/* The version of the library linked (its CYL_VERSION_STRING when it was built). */
const char *cyl_version(void);

#ifdef __cplusplus
}
#endif
#endif
