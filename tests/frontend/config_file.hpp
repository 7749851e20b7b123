// SPDX-License-Identifier: BSD-3-Clause
// Detector config files for the frontend tests: text written to a temporary file, and the error
// loading it gives (the path shown as FILE), or "" when it loads.
#pragma once

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "cylfe/error.hpp"
#include "cylfe/pipeline.hpp"

namespace cfgtest {

inline std::string write_tmp(const std::string &text)
{
    char name[] = "/tmp/cyl_cfgtest_XXXXXX";
    const int fd = mkstemp(name);
    EXPECT_GE(fd, 0);
    FILE *f = fdopen(fd, "w");
    std::fputs(text.c_str(), f);
    std::fclose(f);
    return name;
}

inline std::string load_error(const std::string &text, const cyl_colortable &t, cylfe::DetectorConfig &c)
{
    const std::string p = write_tmp(text);
    std::string msg;
    try {
        cylfe::load_detector_config(p, t, c);
    } catch (const cylfe::Error &e) {
        msg = e.what();
        if (msg.compare(0, p.size(), p) == 0) msg = "FILE" + msg.substr(p.size());
    }
    std::remove(p.c_str());
    return msg;
}

} // namespace cfgtest
