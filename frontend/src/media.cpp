// SPDX-License-Identifier: BSD-3-Clause
// Loading libcyl-media.so (cylfe/media.hpp).
#include "cylfe/media.hpp"
#include "cylfe/data_files.hpp"
#include "cylfe/error.hpp"

#include <cstdlib>
#include <dlfcn.h>
#include <mutex>
#include <sys/stat.h>
#include <vector>

namespace cylfe {
namespace media {
namespace {

std::mutex g_mutex;
const Api *g_api = nullptr;
std::string g_path;

std::vector<std::string> candidates()
{
    const char *env = std::getenv("CYL_MEDIA_PLUGIN");
    if (env && *env) return {env};
    const std::string e = executable_dir();
    if (e.empty()) return {};
    return {e + "/libcyl-media.so", e + "/../libcyl-media.so", e + "/../lib/cyl/libcyl-media.so"};
}

} // namespace

const Api &api()
{
    std::lock_guard<std::mutex> lock(g_mutex);
    if (g_api) return *g_api;
    std::string tried;
    for (const std::string &p : candidates()) {
        tried += tried.empty() ? "" : "; ";
        struct stat st;
        if (::stat(p.c_str(), &st) != 0) {
            tried += p + ": not there";
            continue;
        }
        void *h = ::dlopen(p.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!h) {
            const char *why = ::dlerror();
            tried += why ? why : p + ": cannot load";
            continue;
        }
        using Entry = const Api *(*)();
        Entry entry = reinterpret_cast<Entry>(::dlsym(h, "cyl_media_plugin"));
        const Api *a = entry ? entry() : nullptr;
        if (!a || a->abi != kMediaAbi) {
            tried += p + ": not a libcyl-media plugin of interface version " + std::to_string(kMediaAbi);
            ::dlclose(h);
            continue;
        }
        g_api = a;  // kept loaded for the life of the process
        g_path = p;
        return *g_api;
    }
    std::string msg = "image files, video files and windows need the plugin libcyl-media.so (OpenCV's imgcodecs, "
                      "videoio and highgui), which could not be loaded (";
    msg += tried.empty() ? std::string("no place to look: the executable's directory is unknown") : tried;
    msg += "; CYL_MEDIA_PLUGIN names it)";
    throw Error(msg);
}

std::string plugin_path()
{
    std::lock_guard<std::mutex> lock(g_mutex);
    return g_path;
}

} // namespace media
} // namespace cylfe
