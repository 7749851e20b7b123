// SPDX-License-Identifier: BSD-3-Clause
// End-to-end replay benchmark: a recorded 640x480 YUYV log through `cyl detect`
// (read, segment, observe, write the JSON Lines log), as a separate process, timed from outside;
// peak memory (ru_maxrss) for a 1,000- and a 10,000-frame log must be the same.
//
// The logs cycle 32 distinct frames rendered by the synthetic camera along its drive, with
// odometry records, so they look like a real recording; writing 10,000 frames takes ~6 GB
// of disk in build/ for the duration of the run.
//
//   bench_replay CYL_BINARY TABLE [--frames-small N] [--frames-large N] [--keep]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

#include "cylfe/calibration.hpp"
#include "cylfe/error.hpp"
#include "cylfe/rawlog.hpp"
#include "cylfe/synth.hpp"

using namespace cylfe;

namespace {

struct RunResult { double seconds; long maxrss_kb; int status; };

RunResult run(const std::vector<std::string> &argv)
{
    auto t0 = std::chrono::steady_clock::now();
    pid_t pid = fork();
    if (pid == 0) {
        std::vector<char *> a;
        for (const auto &s : argv) a.push_back(const_cast<char *>(s.c_str()));
        a.push_back(nullptr);
        execv(a[0], a.data());
        _exit(127);
    }
    int status = 0;
    struct rusage ru;
    wait4(pid, &status, 0, &ru);
    double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return {s, ru.ru_maxrss, status};
}

void write_log(const std::string &path, const std::vector<std::vector<uint8_t>> &frames, const StreamInfo &info,
               uint32_t n)
{
    RawLogWriter w(path, info);
    Odometry o;
    o.dx_m = 0.02;
    o.cov[0] = o.cov[3] = 1e-6;
    o.cov[5] = 1e-6;
    for (uint32_t i = 0; i < n; i++) {
        int64_t t = (int64_t)i * 66666667LL;
        const auto &f = frames[i % frames.size()];
        w.frame(i, t, f.data(), f.size());
        w.odometry(i, t, o);
    }
    w.close();
}

} // namespace

int main(int argc, char **argv)
{
    if (argc < 3 || std::string(argv[1]) == "--help") {
        std::printf("usage: bench_replay CYL_BINARY TABLE [--frames-small N] [--frames-large N] [--keep]\n");
        return argc < 3 ? 2 : 0;
    }
    std::string cyl = argv[1], table = argv[2];
    uint32_t small = 1000, large = 10000;
    bool keep = false;
    for (int i = 3; i < argc; i++) {
        std::string a = argv[i];
        if (a == "--frames-small" && i + 1 < argc) small = (uint32_t)std::atoi(argv[++i]);
        else if (a == "--frames-large" && i + 1 < argc) large = (uint32_t)std::atoi(argv[++i]);
        else if (a == "--keep") keep = true;
        else { std::fprintf(stderr, "bench_replay: unknown argument %s\n", a.c_str()); return 2; }
    }
    try {
        synth::Scene scene = synth::default_scene();
        synth::SyntheticSource src(scene, 32 * 8, 11);
        std::vector<std::vector<uint8_t>> frames;
        SourceEvent ev;
        uint32_t k = 0;
        while (frames.size() < 32 && src.next(ev))
            if (ev.kind == RecordType::Frame && (k++ % 8) == 0) frames.emplace_back(ev.data, ev.data + ev.header.size);
        StreamInfo info = src.info();
        info.flags &= ~StreamInfo::kHasTruth;
        std::string dir = "build/bench", calib = dir + "/synthetic_camera.yaml";
        if (system(("mkdir -p " + dir).c_str()) != 0) throw Error("cannot create " + dir);
        save_camera_calibration(calib, synth::to_cyl_camera(scene));  // the scene's nominal camera
        std::printf("rendered %zu distinct frames %ux%u %s\n", frames.size(), info.width, info.height,
                    fourcc_str(info.fourcc).c_str());
        struct Row { uint32_t n; RunResult r; };
        std::vector<Row> rows;
        for (uint32_t n : {small, large}) {
            std::string log = dir + "/replay_" + std::to_string(n) + ".cylraw", out = dir + "/replay_" + std::to_string(n) + ".jsonl";
            write_log(log, frames, info, n);
            RunResult r = run({cyl, "detect", log, "--table", table, "--calib", calib, "--out", out, "--quiet"});
            if (r.status != 0) throw Error("cyl detect failed on " + log + " (status " + std::to_string(r.status) + ")");
            rows.push_back({n, r});
            if (!keep) { std::remove(log.c_str()); std::remove(out.c_str()); }
        }
        std::printf("%-10s %10s %12s %14s\n", "frames", "seconds", "frames/s", "peak RSS KiB");
        for (const Row &r : rows)
            std::printf("%-10u %10.2f %12.0f %14ld\n", r.n, r.r.seconds, r.n / r.r.seconds, r.r.maxrss_kb);
        double fps = rows[1].n / rows[1].r.seconds;
        double growth = (double)rows[1].r.maxrss_kb / (double)rows[0].r.maxrss_kb;
        std::printf("{\"replay_fps\": %.1f, \"replay_fps_small\": %.1f, \"rss_small_kib\": %ld, \"rss_large_kib\": %ld, "
                    "\"rss_growth\": %.3f}\n",
                    fps, rows[0].n / rows[0].r.seconds, rows[0].r.maxrss_kb, rows[1].r.maxrss_kb, growth);
    } catch (const std::exception &e) {
        std::fprintf(stderr, "bench_replay: %s\n", e.what());
        return 1;
    }
    return 0;
}
