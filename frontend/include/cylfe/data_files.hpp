// SPDX-License-Identifier: BSD-3-Clause
// Finding the data files the tools ship with (the synthetic scene's colour table, the paper's
// camera), so that a tool works from any directory, in the build tree and installed alike.
//
// A name is looked up, first hit wins, in
//   1. $CYL_DATA_DIR, when that variable is set (and then only there: a wrong setting is an
//      error, not a silent fallback);
//   2. <directory of the executable>/../share/cyl    (installed: PREFIX/bin/cyl, PREFIX/share/cyl);
//   3. <directory of the executable>/../calib_data and ../../calib_data  (the build tree:
//      build/cyl and build/san/cyl next to the repository's calib_data/).
#pragma once
#include <string>
#include <vector>

namespace cylfe {

// The folder of the running executable (from /proc/self/exe; "" when unknown). Data files and the
// media plugin (cylfe/media.hpp) are found relative to it.
std::string executable_dir();

// The directories searched for data files, in order (what `cyl --help` and errors print).
std::vector<std::string> data_dirs();

// The path of the data file `name`; throws Error naming every place searched when none has it.
std::string data_file(const std::string &name);

} // namespace cylfe
