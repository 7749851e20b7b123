// SPDX-License-Identifier: BSD-3-Clause
#include "cylfe/data_files.hpp"
#include "cylfe/error.hpp"

#include <cstdlib>
#include <sys/stat.h>
#include <unistd.h>

namespace cylfe {
std::string executable_dir()
{
    char buf[4096];
    ssize_t n = ::readlink("/proc/self/exe", buf, sizeof buf - 1);
    if (n <= 0) return "";
    std::string p(buf, (size_t)n);
    size_t slash = p.find_last_of('/');
    return slash == std::string::npos ? "" : p.substr(0, slash);
}

namespace {

bool is_file(const std::string &p)
{
    struct stat st;
    return ::stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

} // namespace

std::vector<std::string> data_dirs()
{
    const char *env = std::getenv("CYL_DATA_DIR");
    if (env && *env) return {env};
    std::vector<std::string> dirs;
    const std::string e = executable_dir();
    if (!e.empty()) {
        dirs.push_back(e + "/../share/cyl");
        dirs.push_back(e + "/../calib_data");
        dirs.push_back(e + "/../../calib_data");
    }
    return dirs;
}

std::string data_file(const std::string &name)
{
    const std::vector<std::string> dirs = data_dirs();
    std::string tried;
    for (const std::string &d : dirs) {
        std::string p = d;
        p += '/';
        p += name;
        if (is_file(p)) return p;
        tried += tried.empty() ? "" : ", ";
        tried += p;
    }
    const char *env = std::getenv("CYL_DATA_DIR");
    std::string msg = name;
    msg += ": data file not found (looked at ";
    msg += tried.empty() ? std::string("no place: the executable's directory is unknown") : tried;
    msg += env && *env ? "; CYL_DATA_DIR is set, so only there)" : "; set CYL_DATA_DIR to the directory that holds it)";
    throw Error(msg);
}

} // namespace cylfe
