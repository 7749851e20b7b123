// SPDX-License-Identifier: BSD-3-Clause
#include "cylfe/output_file.hpp"
#include "cylfe/error.hpp"

#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sys/stat.h>

namespace cylfe {

namespace {

std::string errtext(int e) { return std::strerror(e); }

const char *kind(mode_t m)
{
    if (S_ISCHR(m)) return "a character device";
    if (S_ISBLK(m)) return "a block device";
    if (S_ISFIFO(m)) return "a FIFO";
    if (S_ISSOCK(m)) return "a socket";
    if (S_ISDIR(m)) return "a directory";
    return "not a regular file";
}

} // namespace

OutputPlan plan_output(const std::string &path, const std::string &suffix)
{
    OutputPlan p;
    p.path = path;
    p.target = path;
    struct stat ls;
    if (path.empty()) throw Error("output path is empty");
    if (::lstat(path.c_str(), &ls) != 0) {
        if (errno != ENOENT) throw Error(path + ": cannot examine output path: " + errtext(errno));
        p.write_to = path + suffix;  // a new file
        p.staged = true;
        return p;
    }
    if (S_ISLNK(ls.st_mode)) {
        struct stat ts;
        if (::stat(path.c_str(), &ts) != 0)
            throw Error(path + ": symbolic link to a missing or unreachable file (" + errtext(errno) +
                        "); refused as an output");
        if (S_ISDIR(ts.st_mode)) throw Error(path + ": is a link to a directory, not an output file");
        if (!S_ISREG(ts.st_mode)) {  // e.g. /dev/stdout -> a pipe or a terminal: write through
            p.write_to = path;
            return p;
        }
        char buf[PATH_MAX];
        if (!::realpath(path.c_str(), buf)) throw Error(path + ": cannot resolve symbolic link: " + errtext(errno));
        p.target = buf;
        p.write_to = p.target + suffix;
        p.staged = true;
        return p;
    }
    if (S_ISDIR(ls.st_mode)) throw Error(path + ": is a directory, not an output file");
    if (!S_ISREG(ls.st_mode)) {  // device node, FIFO, socket: written in place, never replaced
        p.write_to = path;
        return p;
    }
    p.write_to = path + suffix;
    p.staged = true;
    return p;
}

void finish_output(const OutputPlan &p)
{
    if (!p.staged) return;
    struct stat ls;
    if (::lstat(p.target.c_str(), &ls) == 0 && !S_ISREG(ls.st_mode))
        throw Error(p.target + ": became " + kind(ls.st_mode) + " while writing; the output is left in " +
                    p.write_to);
    if (std::rename(p.write_to.c_str(), p.target.c_str()) != 0)
        throw Error(p.write_to + ": cannot rename to " + p.target + ": " + errtext(errno));
}

} // namespace cylfe
