// SPDX-License-Identifier: BSD-3-Clause
// Where an output file is written so that only a regular file is ever replaced.
//
// A tool's output (an observation log, a raw frame log, a colour table, a calibration file) is
// written to "<target><suffix>" and renamed over the target at the end, so that a good file is
// never replaced by a partial one. That rename is only ever done over a regular file (or where no
// file is yet):
//   - a character or block device, a FIFO or a socket (`--out /dev/null`, a named pipe) is written
//     directly and left what it is;
//   - a symbolic link is written through: the link stays, and its target is treated by the same
//     rules (a regular target is replaced by rename in its own directory, a device is written
//     directly); a link to nothing is refused;
//   - a directory is refused.
#pragma once
#include <string>

namespace cylfe {

struct OutputPlan {
    std::string path;      // the path the user named
    std::string target;    // the file that ends up holding the output (a symlink's target)
    std::string write_to;  // where the bytes go: target + suffix when staged, else the path itself
    bool staged = false;   // true: write_to is renamed over target by finish_output()
};

// Decide how to write `path`. Throws Error naming the path for a directory, a dangling symlink
// or a path that cannot be examined.
OutputPlan plan_output(const std::string &path, const std::string &suffix = ".part");

// Rename a staged output over its target (nothing to do for a direct one). Checks again that the
// target is still a regular file or absent; throws Error naming the file otherwise.
void finish_output(const OutputPlan &plan);

} // namespace cylfe
