// SPDX-License-Identifier: BSD-3-Clause
// --version for every tool: "<tool> <version> (libcyl <library version>)". The version is written
// once, in libcyl/include/cyl/version.h.
#pragma once

#include <cstdio>
#include <cstring>

#include "cyl/version.h"

namespace cylfe {

// Prints the version and returns true if argv holds --version (before any "--").
inline bool print_version_if_asked(int argc, char **argv, const char *tool)
{
    for (int i = 1; i < argc; i++) {
        if (std::strcmp(argv[i], "--") == 0) break;
        if (std::strcmp(argv[i], "--version") == 0) {
            std::printf("%s %s (libcyl %s)\n", tool, CYL_VERSION_STRING, cyl_version());
            return true;
        }
    }
    return false;
}

} // namespace cylfe
