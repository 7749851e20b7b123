// SPDX-License-Identifier: BSD-3-Clause
// Progress on stderr for the long-running tools: a bar redrawn with '\r' on a terminal, and a plain
// line per 10% otherwise (a log file or a pipe never gets carriage returns).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <unistd.h>

namespace cylfe {

class Progress {
public:
    // what: the activity ("rendering"); unit: what is counted ("frames"). Disabled: prints nothing.
    Progress(bool enabled, std::string what, std::string unit)
        : on_(enabled), tty_(isatty(2) != 0), what_(std::move(what)), unit_(std::move(unit)) {}
    // frac in [0,1] (negative: unknown, nothing printed); count: items so far; rate: items per second
    void update(double frac, uint64_t count, double rate)
    {
        if (!on_ || frac < 0) return;
        int pct = (int)std::lround(frac * 100.0);
        if (tty_) {
            int n = pct / 4;
            std::fprintf(stderr, "\r%s [%-25s] %3d%% %llu %s %.0f/s", what_.c_str(), std::string((size_t)n, '#').c_str(),
                         pct, (unsigned long long)count, unit_.c_str(), rate);
        } else if (pct / 10 > last_ / 10) {
            std::fprintf(stderr, "%s: %d%% (%llu %s, %.0f/s)\n", what_.c_str(), pct, (unsigned long long)count,
                         unit_.c_str(), rate);
        }
        last_ = pct;
    }
    // ends the bar's line (on a terminal); call before printing anything else
    void done()
    {
        if (on_ && tty_ && last_ >= 0) std::fputc('\n', stderr);
        last_ = -1;
    }

private:
    bool on_, tty_;
    std::string what_, unit_;
    int last_ = -1;
};

} // namespace cylfe
