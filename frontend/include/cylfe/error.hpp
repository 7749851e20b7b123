// SPDX-License-Identifier: BSD-3-Clause
// cylfe: the C++ frontend on libcyl. Errors are exceptions carrying a message that names the
// file, line, field or device at fault; the tools turn them into a message and an exit code.
#pragma once
#include <stdexcept>
#include <string>

extern "C" {
#include "cyl/status.h"
}

namespace cylfe {

// Exit codes of the command-line tools.
enum ExitCode : int {
    kExitOk = 0,
    kExitFailure = 1,      // the run failed (bad input data, device error, ...)
    kExitUsage = 2,        // bad command line
    kExitInterrupted = 130 // stopped by SIGINT/SIGTERM after a clean shutdown
};

class Error : public std::runtime_error {
public:
    explicit Error(const std::string &what) : std::runtime_error(what) {}
};

// Throw an Error "<context>: <libcyl status text>" unless s is CYL_OK or CYL_TRUNCATED.
inline void check(cyl_status s, const std::string &context)
{
    if (s < 0) throw Error(context + ": " + cyl_status_str(s));
}

} // namespace cylfe
