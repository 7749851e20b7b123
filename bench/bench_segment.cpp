// SPDX-License-Identifier: BSD-3-Clause
// Segmentation benchmark: libcyl (classify + RLE + blobs) against the floor (a
// memcpy of the frame) and the OpenCV pipeline a user would write instead
// (cvtColor YUYV->BGR, inRange per class, connectedComponentsWithStats per
// class), on the same distinct deterministic 640x480 YUYV frames. Prints tables and, last, a JSON
// line. Not a test.
//
//   bench_segment [--iterations N] [--frames F]       timing (medians)
//   bench_segment --real LIST TABLE [--iterations N]  real images (one path a line), converted to
//                                                     YUYV, with a learned table: libcyl vs memcpy
//   bench_segment --callgrind K [--3d] [--set S] [--scalar]
//                                                     only libcyl, K frames (for valgrind);
//                                                     --3d: with the learned-form (3-D) table;
//                                                     --set typical|dense|speckle (bench_frames.hpp);
//                                                     --scalar: the scalar reference path
// libcyl is timed on its vector path (cyl_segment_vector_path()) and on the scalar reference path,
// and the two are checked bit-identical on every frame of every set (simd_bit_identical).
// First the libcyl variants and OpenCV, interleaved, each finding the frame cached (ratios to the
// vector path); then the typical frames and the dense and speckle worst cases against a memcpy of
// the same frames, all three sets measured the same way (each operation finds its frame in L3, not
// L2); then large frames (2048x1536 and 3840x2160, YUYV and NV12: frames/s on one core and two).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include <fstream>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

extern "C" {
#include "cyl/colortable.h"
#include "cyl/segment.h"
#include "synth_frames.h"
}

#include "bench_frames.hpp"

using namespace bench;

namespace {

// BGR image -> YUYV (BT.601 as OpenCV's COLOR_BGR2YUV, each pair's chroma averaged), even width.
std::vector<uint8_t> bgr_to_yuyv(const cv::Mat &bgr, uint32_t *w, uint32_t *h)
{
    cv::Mat yuv;
    cv::cvtColor(bgr, yuv, cv::COLOR_BGR2YUV);
    *w = (uint32_t)(yuv.cols & ~1);
    *h = (uint32_t)yuv.rows;
    std::vector<uint8_t> out((size_t)*w * *h * 2);
    for (uint32_t y = 0; y < *h; y++)
        for (uint32_t x = 0; x < *w; x += 2) {
            const cv::Vec3b a = yuv.at<cv::Vec3b>((int)y, (int)x), b = yuv.at<cv::Vec3b>((int)y, (int)x + 1);
            uint8_t *d = &out[((size_t)y * *w + x) * 2];
            d[0] = a[0];
            d[1] = (uint8_t)((a[1] + b[1] + 1) / 2);
            d[2] = b[0];
            d[3] = (uint8_t)((a[2] + b[2] + 1) / 2);
        }
    return out;
}

// --real LIST TABLE: each image's cyl_segment against a memcpy of the same frame; medians of the
// per-image ratios. Last line JSON.
int bench_real(const std::string &list, const std::string &table_path, int iterations)
{
    std::ifstream lf(list);
    if (!lf) { std::fprintf(stderr, "bench_segment: %s: cannot open\n", list.c_str()); return 1; }
    std::ifstream tf(table_path, std::ios::binary);
    std::vector<uint8_t> tb((std::istreambuf_iterator<char>(tf)), std::istreambuf_iterator<char>());
    static cyl_colortable table;
    if (tb.empty() || cyl_colortable_load(&table, tb.data(), tb.size()) != CYL_OK) {
        std::fprintf(stderr, "bench_segment: %s: not a colour table\n", table_path.c_str());
        return 1;
    }
    std::vector<double> ratios, scalar_ratios, mpx;
    double coloured = 0;
    std::string path;
    while (std::getline(lf, path)) {
        if (path.empty() || path[0] == '#') continue;
        cv::Mat bgr = cv::imread(path, cv::IMREAD_COLOR);
        if (bgr.empty()) { std::fprintf(stderr, "bench_segment: %s: cannot read\n", path.c_str()); return 1; }
        uint32_t w, h;
        std::vector<uint8_t> f = bgr_to_yuyv(bgr, &w, &h), dst(f.size());
        cyl_segment_params params = cyl_segment_params_default();
        const uint32_t max_runs = cyl_segment_max_runs(w, h, &params), max_blobs = 65535;
        std::vector<uint8_t> mem(cyl_segment_mem_size(max_runs, max_blobs));
        cyl_segmentation seg{};
        cyl_segmentation_init(&seg, mem.data(), mem.size(), max_runs, max_blobs);
        cyl_image img;
        cyl_image_wrap(&img, CYL_FMT_YUYV, w, h, f.data(), 0);
        cyl_segment_params scalar_params = params;
        scalar_params.scalar_only = 1;
        std::vector<double> tc, tm, ts;
        for (int i = 0; i < iterations; i++) {
            // the two paths take turns at going first (the first finds the tables less cached)
            const cyl_segment_params &first = i % 2 ? scalar_params : params, &second = i % 2 ? params : scalar_params;
            double t0 = now_us();
            std::memcpy(dst.data(), f.data(), f.size());
            double t1 = now_us();
            cyl_segment(&table, &img, &first, &seg);
            double t2 = now_us();
            cyl_segment(&table, &img, &second, &seg);
            double t3 = now_us();
            tm.push_back(t1 - t0);
            (i % 2 ? ts : tc).push_back(t2 - t1);
            (i % 2 ? tc : ts).push_back(t3 - t2);
        }
        ratios.push_back(median(tc) / median(tm));
        scalar_ratios.push_back(median(ts) / median(tm));
        mpx.push_back(1e-6 * w * h / (median(tc) * 1e-6));
        coloured += coloured_fraction(table, f);
    }
    if (ratios.empty()) { std::fprintf(stderr, "bench_segment: %s: no images\n", list.c_str()); return 1; }
    std::printf("real images (%s): %zu images, libcyl %.2fx memcpy (median of the per-image ratios; %.2f-%.2f; "
                "scalar path %.2fx), %.0f Mpx/s, %.1f%% of pixels coloured\n", list.c_str(), ratios.size(), median(ratios),
                *std::min_element(ratios.begin(), ratios.end()), *std::max_element(ratios.begin(), ratios.end()),
                median(scalar_ratios), median(mpx), 100 * coloured / (double)ratios.size());
    std::printf("{\"real_images\": %zu, \"real_libcyl_over_memcpy\": %.3f, \"real_scalar_libcyl_over_memcpy\": %.3f, "
                "\"real_mpx_per_s\": %.1f}\n", ratios.size(), median(ratios), median(scalar_ratios), median(mpx));
    return 0;
}

} // namespace

int main(int argc, char **argv)
{
    int iterations = 1500, nframes = 16, callgrind = 0, use3d = 0, scalar = 0;
    FrameSet cg_set = FrameSet::Typical;
    std::string real_list, real_table;
    for (int i = 1; i < argc; i++) {
        std::string a = argv[i];
        if (a == "--help" || a == "-h") {
            std::printf("usage: bench_segment [--iterations N] [--frames F] [--callgrind K [--3d] [--set S] [--scalar]]\n"
                        "       bench_segment --real LIST TABLE [--iterations N]\n");
            return 0;
        } else if (a == "--iterations" && i + 1 < argc) iterations = std::atoi(argv[++i]);
        else if (a == "--frames" && i + 1 < argc) nframes = std::atoi(argv[++i]);
        else if (a == "--callgrind" && i + 1 < argc) callgrind = std::atoi(argv[++i]);
        else if (a == "--3d") use3d = 1;
        else if (a == "--scalar") scalar = 1;
        else if (a == "--real" && i + 2 < argc) { real_list = argv[++i]; real_table = argv[++i]; }
        else if (a == "--set" && i + 1 < argc) {
            std::string v = argv[++i];
            if (v == "dense") cg_set = FrameSet::Dense;
            else if (v == "speckle") cg_set = FrameSet::Speckle;
            else if (v != "typical") { std::fprintf(stderr, "bench_segment: --set typical|dense|speckle\n"); return 2; }
        }
        else { std::fprintf(stderr, "bench_segment: unknown argument '%s' (see --help)\n", a.c_str()); return 2; }
    }
    if (iterations < 1 || nframes < 1) { std::fprintf(stderr, "bench_segment: counts must be >= 1\n"); return 2; }
    if (!real_list.empty()) return bench_real(real_list, real_table, std::min(iterations, 60));

    static Setup set(nframes, 40000, 4096, callgrind > 0 ? cg_set : FrameSet::Typical);  // static: 193 KiB tables
    const std::vector<std::vector<uint8_t>> &frames = set.frames;
    const cyl_colortable &table = use3d ? set.table3d : set.table;
    const cyl_segment_params &params = set.params;
    cyl_segmentation &seg = set.seg;
    cyl_segment_params scalar_params = params;
    scalar_params.scalar_only = 1;

    if (callgrind > 0) {
        unsigned long blobs = 0;
        for (int i = 0; i < callgrind; i++) {
            cyl_image img;
            cyl_image_wrap(&img, CYL_FMT_YUYV, kW, kH, frames[i % nframes].data(), 0);
            cyl_segment(&table, &img, scalar ? &scalar_params : &params, &seg);
            blobs += seg.n_blobs;
        }
        std::printf("frames %d pixels_per_frame %u blobs %lu\n", callgrind, kW * kH, blobs);
        return 0;
    }

    cv::setNumThreads(1);  // one core, like libcyl
    std::vector<uint8_t> dst(kW * kH * 2);
    cv::Mat bgr, mask, labels, stats, centroids;
    const cv::Scalar lo[2] = {cv::Scalar(0, 90, 200), cv::Scalar(60, 150, 0)};
    const cv::Scalar hi[2] = {cv::Scalar(120, 190, 255), cv::Scalar(170, 255, 120)};
    std::vector<double> t_cyl, t_cv, t_3d, t_scalar, t_cls;
    std::vector<uint8_t> class_map(kW * kH);
    unsigned long sink = 0, cv_blobs = 0, cyl_blobs = 0;
    for (int i = 0; i < iterations; i++) {
        const std::vector<uint8_t> &f = frames[i % nframes];
        std::memcpy(dst.data(), f.data(), f.size());   // untimed: every path below finds the frame cached
        sink += dst[(size_t)i % dst.size()];
        cyl_image img;
        cyl_image_wrap(&img, CYL_FMT_YUYV, kW, kH, f.data(), 0);
        double t2 = now_us();
        cyl_segment(&table, &img, &params, &seg);
        double t3 = now_us();
        cyl_blobs += seg.n_blobs;
        double t6 = now_us();
        cyl_segment(&set.table3d, &img, &params, &seg);
        double t7 = now_us();
        cyl_segment(&table, &img, &scalar_params, &seg);
        double t8 = now_us();
        t_scalar.push_back(t8 - t7);
        cyl_classify(&table, &img, nullptr, 1, 1, class_map.data(), kW);   // the overlay's class map
        t_cls.push_back(now_us() - t8);
        t_cyl.push_back(t3 - t2);
        t_3d.push_back(t7 - t6);
        if (i % 3 == 0) {  // OpenCV is slow: a third of the iterations still gives hundreds of samples
            cv::Mat yuyv((int)kH, (int)kW, CV_8UC2, const_cast<uint8_t *>(f.data()));
            double t4 = now_us();
            cv::cvtColor(yuyv, bgr, cv::COLOR_YUV2BGR_YUYV);
            for (int k = 0; k < 2; k++) {
                cv::inRange(bgr, lo[k], hi[k], mask);
                cv_blobs += (unsigned long)cv::connectedComponentsWithStats(mask, labels, stats, centroids, 4, CV_32S);
            }
            double t5 = now_us();
            t_cv.push_back(t5 - t4);
        }
    }
    double m_cyl = median(t_cyl), m_cv = median(t_cv), m_3d = median(t_3d),
           m_scalar = median(t_scalar), m_cls = median(t_cls);
    // the vector path against the scalar reference, bit for bit, on every frame of every set
    const uint32_t cmp_runs = cyl_segment_max_runs(kW, kH, &params), cmp_blobs = 65535;
    std::vector<uint8_t> cmp_mem(cyl_segment_mem_size(cmp_runs, cmp_blobs));
    cyl_segmentation cmp{};
    cyl_segmentation_init(&cmp, cmp_mem.data(), cmp_mem.size(), cmp_runs, cmp_blobs);
    int identical = 1, compared = 0;
    auto same = [&](const cyl_colortable &tb, const cyl_image &img, cyl_segmentation &s) {
        cyl_segment(&tb, &img, &params, &s);
        cyl_segment(&tb, &img, &scalar_params, &cmp);
        compared++;
        return s.n_runs == cmp.n_runs && s.n_blobs == cmp.n_blobs &&
               std::memcmp(s.runs, cmp.runs, sizeof(cyl_run) * s.n_runs) == 0 &&
               std::memcmp(s.blobs, cmp.blobs, sizeof(cyl_blob) * s.n_blobs) == 0;
    };
    for (const auto &f : frames) {
        cyl_image img;
        cyl_image_wrap(&img, CYL_FMT_YUYV, kW, kH, f.data(), 0);
        identical &= same(table, img, seg) && same(set.table3d, img, seg);
    }
    std::printf("640x480 YUYV, %d distinct frames, %d iterations (OpenCV %zu), one thread\n", nframes,
                iterations, t_cv.size());
    // ratios here are to the vector path's time in this loop (the memcpy comparison follows)
    std::printf("%-52s %12s %10s\n", "pipeline", "median us", "x libcyl");
    std::printf("%-52s %12.1f %10s\n", (std::string("libcyl classify+RLE+blobs, ") + cyl_segment_vector_path() + " path").c_str(),
                m_cyl, "1.00x");
    std::printf("%-52s %12.1f %9.2fx\n", "libcyl, scalar reference path", m_scalar, m_scalar / m_cyl);
    std::printf("%-52s %12.1f %9.2fx\n", "cyl_classify: the class map an overlay draws", m_cls, m_cls / m_cyl);
    std::printf("%-52s %12.1f %9.2fx\n", "libcyl, same classes as a learned 3-D table", m_3d, m_3d / m_cyl);
    std::printf("%-52s %12.1f %9.2fx\n", "OpenCV cvtColor+2 inRange+2 connectedComponents", m_cv, m_cv / m_cyl);
    std::printf("libcyl blobs/frame %.2f; libcyl is %.1fx faster than OpenCV (sink %lu)\n",
                (double)cyl_blobs / iterations, m_cv / m_cyl, sink % 7);

    // Each set against a memcpy of the same frames, all three sets measured the same way. The
    // frames (16 distinct, 9.8 MB, more than a core's L2) are taken in turn, so every operation
    // finds its frame where it was left 15 frames earlier (L3, not L2), as a camera's frame arrives
    // uncached; the memcpy writes one destination buffer, as a pipeline that copies each frame into
    // its own buffer does. Blocks of one memcpy pass, one vector-path pass and one scalar-path pass
    // over the frames alternate, so the machine's load drifts touch all three alike; medians.
    // (Until this loop the typical set's memcpy was timed in the loop above, where OpenCV and
    // cyl_classify evict the memcpy's destination between frames: 47 us instead of 24 us, which
    // made the typical ratio read about half of what it is here.)
    // The floors of the typical set, measured the same way: reading each frame once (an OR over its
    // bytes), and the segmentation's walk through the background alone (a table with no class: no
    // pixel starts a run). What the runs add is the rest of the typical set's time.
    static cyl_colortable no_class;   // static: 193 KiB
    cyl_colortable_init(&no_class);
    cyl_colortable_refresh(&no_class);
    unsigned long walk_runs = 0;      // must stay 0: the walk alone
    auto read_frame = [](const std::vector<uint8_t> &f) {
        uint64_t a = 0, b = 0, c = 0, d = 0;
        for (size_t i = 0; i + 32 <= f.size(); i += 32) {
            uint64_t w[4];
            std::memcpy(w, f.data() + i, 32);
            a |= w[0]; b |= w[1]; c |= w[2]; d |= w[3];
        }
        return a | b | c | d;
    };
    std::vector<double> t_read, t_walk;
    double worst = 0, set_ratio[3] = {0, 0, 0}, set_frac[3] = {0, 0, 0}, scalar_ratio[3] = {0, 0, 0},
           set_mem[3] = {0, 0, 0}, set_cyl[3] = {0, 0, 0}, set_blobs[3] = {0, 0, 0};
    const int passes = std::max(3, iterations / (3 * nframes));
    for (int k = 0; k < 3; k++) {
        const FrameSet fs = (FrameSet)k;
        std::vector<std::vector<uint8_t>> fr;
        for (int i = 0; i < nframes; i++) fr.push_back(k == 0 ? frames[(size_t)i] : make_frame(2000 + (uint64_t)i, fs));
        for (const auto &f : fr) {
            cyl_image img;
            cyl_image_wrap(&img, CYL_FMT_YUYV, kW, kH, f.data(), 0);
            if (k > 0) identical &= same(table, img, seg) && same(set.table3d, img, seg);
            set_frac[k] += coloured_fraction(table, f) / (double)fr.size();
        }
        std::vector<double> tc, tm, ts;
        unsigned long blobs = 0;
        for (int pass = 0; pass < passes; pass++) {
            for (const auto &f : fr) {
                double t0 = now_us();
                std::memcpy(dst.data(), f.data(), f.size());
                tm.push_back(now_us() - t0);
                sink += dst[(size_t)pass % dst.size()];
            }
            if (k == 0) {
                for (const auto &f : fr) {
                    double t0 = now_us();
                    sink += read_frame(f);
                    t_read.push_back(now_us() - t0);
                }
                for (const auto &f : fr) {
                    cyl_image img;
                    cyl_image_wrap(&img, CYL_FMT_YUYV, kW, kH, f.data(), 0);
                    double t0 = now_us();
                    cyl_segment(&no_class, &img, &params, &seg);
                    t_walk.push_back(now_us() - t0);
                    walk_runs += seg.n_runs;
                }
            }
            for (int path = 0; path < 2; path++)
                for (const auto &f : fr) {
                    cyl_image img;
                    cyl_image_wrap(&img, CYL_FMT_YUYV, kW, kH, f.data(), 0);
                    double t0 = now_us();
                    cyl_segment(&table, &img, path ? &scalar_params : &params, &seg);
                    (path ? ts : tc).push_back(now_us() - t0);
                    if (!path) blobs += seg.n_blobs;
                }
        }
        set_mem[k] = median(tm);
        set_cyl[k] = median(tc);
        set_ratio[k] = set_cyl[k] / set_mem[k];
        scalar_ratio[k] = median(ts) / set_mem[k];
        set_blobs[k] = (double)blobs / (double)tc.size();
        if (k > 0) worst = std::max(worst, set_ratio[k]);
    }
    std::printf("\nagainst a memcpy of the same frames (each found in L3, not L2; %d passes over %d frames)\n", passes, nframes);
    std::printf("%-10s %9s %11s %10s %10s %8s %13s\n", "set", "coloured", "blobs/frame", "memcpy us", "libcyl us",
                "ratio", "scalar ratio");
    for (int k = 0; k < 3; k++)
        std::printf("%-10s %8.0f%% %11.1f %10.1f %10.1f %7.2fx %12.2fx\n", set_name((FrameSet)k), 100 * set_frac[k],
                    set_blobs[k], set_mem[k], set_cyl[k], set_ratio[k], scalar_ratio[k]);
    const double read_ratio = median(t_read) / set_mem[0], walk_ratio = median(t_walk) / set_mem[0];
    if (walk_runs) {
        std::fprintf(stderr, "bench_segment: the table of no class found %lu runs\n", walk_runs);
        return 1;
    }
    std::printf("typical set: reading each frame once %.2fx memcpy; the segmentation's background walk alone (no class) "
                "%.2fx; the runs add %.2fx\n", read_ratio, walk_ratio, set_ratio[0] - walk_ratio);
    std::printf("\n");

    // Large frames: frames/s of cyl_segment on one core, and of two bands on two threads
    // (cyl_segment_band on each, then cyl_segment_join), checked identical to cyl_segment.
    struct Large { uint32_t w, h; cyl_pixfmt fmt; const char *name; double fps, fps2; };
    Large large[] = {{2048, 1536, CYL_FMT_YUYV, "2048x1536 YUYV", 0, 0}, {2048, 1536, CYL_FMT_NV12, "2048x1536 NV12", 0, 0},
                     {3840, 2160, CYL_FMT_YUYV, "3840x2160 YUYV", 0, 0}, {3840, 2160, CYL_FMT_NV12, "3840x2160 NV12", 0, 0}};
    for (Large &L : large) {
        const uint32_t max_runs = cyl_segment_max_runs(L.w, L.h, &params) / 8, max_blobs = 16384;
        std::vector<uint8_t> mem(cyl_segment_mem_size(max_runs, max_blobs));
        cyl_segmentation big{};
        cyl_segmentation_init(&big, mem.data(), mem.size(), max_runs, max_blobs);
        std::vector<std::vector<uint8_t>> fr;
        for (int i = 0; i < 3; i++) fr.push_back(make_frame(3000 + (uint64_t)i, FrameSet::Typical, L.w, L.h, L.fmt));
        std::vector<double> t;
        for (int i = 0; i < std::max(9, iterations / 50); i++) {
            cyl_image img;
            cyl_image_wrap(&img, L.fmt, L.w, L.h, fr[i % 3].data(), 0);
            double t0 = now_us();
            cyl_segment(&table, &img, &params, &big);
            t.push_back(now_us() - t0);
        }
        for (const auto &f : fr) {
            cyl_image img;
            cyl_image_wrap(&img, L.fmt, L.w, L.h, f.data(), 0);
            const uint32_t n0 = (cyl_segment(&table, &img, &params, &big), big.n_runs);
            std::vector<cyl_run> r0(big.runs, big.runs + n0);
            cyl_segment(&table, &img, &scalar_params, &big);
            identical &= big.n_runs == n0 && std::memcmp(r0.data(), big.runs, sizeof(cyl_run) * n0) == 0;
            compared++;
        }
        L.fps = 1e6 / median(t);
        // two bands on two threads
        std::vector<cyl_run> band[2];
        band[0].resize(max_runs);
        band[1].resize(max_runs);
        std::vector<double> t2;
        for (int i = 0; i < std::max(9, iterations / 50); i++) {
            cyl_image img;
            cyl_image_wrap(&img, L.fmt, L.w, L.h, fr[i % 3].data(), 0);
            const uint32_t rows = cyl_segment_rows(&img, &params), mid = rows / 2;
            uint32_t n[2] = {0, 0};
            double t0 = now_us();
            std::thread worker([&] { cyl_segment_band(&table, &img, &params, mid, rows, band[1].data(), max_runs, &n[1]); });
            cyl_segment_band(&table, &img, &params, 0, mid, band[0].data(), max_runs, &n[0]);
            worker.join();
            const cyl_run *br[2] = {band[0].data(), band[1].data()};
            cyl_segment_join(&table, &img, &params, br, n, 2, &big);
            t2.push_back(now_us() - t0);
            if (i < 3) {  // the joined result is cyl_segment's
                std::vector<cyl_run> rj(big.runs, big.runs + big.n_runs);
                std::vector<cyl_blob> bj(big.blobs, big.blobs + big.n_blobs);
                cyl_segment(&table, &img, &params, &big);
                identical &= big.n_runs == rj.size() && big.n_blobs == bj.size() &&
                             std::memcmp(rj.data(), big.runs, sizeof(cyl_run) * rj.size()) == 0 &&
                             std::memcmp(bj.data(), big.blobs, sizeof(cyl_blob) * bj.size()) == 0;
                compared++;
            }
        }
        L.fps2 = 1e6 / median(t2);
        std::printf("%-52s %12.1f   %.0f frames/s on one core; two bands on two threads %.0f frames/s (%.2fx)\n",
                    (std::string("libcyl on ") + L.name).c_str(), median(t), L.fps, L.fps2, L.fps2 / L.fps);
    }
    std::printf("{\"libcyl_us\": %.2f, \"memcpy_us\": %.2f, \"opencv_us\": %.2f, \"libcyl_over_memcpy\": %.3f, "
                "\"opencv_over_libcyl\": %.2f, \"libcyl_3d_us\": %.2f, \"table3d_over_box\": %.3f, "
                "\"typical_coloured_frac\": %.3f, \"dense_libcyl_over_memcpy\": %.3f, \"dense_coloured_frac\": %.3f, "
                "\"speckle_libcyl_over_memcpy\": %.3f, \"worst_libcyl_over_memcpy\": %.3f, "
                "\"fps_2048x1536_yuyv\": %.1f, \"fps_2048x1536_nv12\": %.1f, \"fps_3840x2160_yuyv\": %.1f, "
                "\"fps_3840x2160_nv12\": %.1f, \"fps_2048x1536_yuyv_2cores\": %.1f, \"fps_2048x1536_nv12_2cores\": %.1f, "
                "\"fps_3840x2160_yuyv_2cores\": %.1f, \"fps_3840x2160_nv12_2cores\": %.1f, \"vector_path\": \"%s\", \"scalar_libcyl_over_memcpy\": %.3f, "
                "\"scalar_worst_libcyl_over_memcpy\": %.3f, \"simd_bit_identical\": %s, \"simd_frames_compared\": %d, \"classify_us\": %.2f, "
                "\"classify_over_segment\": %.3f, \"typical_read_over_memcpy\": %.3f, \"typical_background_over_memcpy\": %.3f}\n",
                set_cyl[0], set_mem[0], m_cv, set_ratio[0], m_cv / m_cyl, m_3d, m_3d / m_cyl, set_frac[0], set_ratio[1], set_frac[1],
                set_ratio[2], worst, large[0].fps, large[1].fps, large[2].fps, large[3].fps, large[0].fps2, large[1].fps2, large[2].fps2,
                large[3].fps2, cyl_segment_vector_path(),
                scalar_ratio[0], std::max(scalar_ratio[1], scalar_ratio[2]), identical ? "true" : "false", compared, m_cls,
                m_cls / m_cyl, read_ratio, walk_ratio);
    return 0;
}
