// SPDX-License-Identifier: BSD-3-Clause
// The benchmarks' shared frames and timing helpers (bench_segment, bench_uncertainty):
// distinct deterministic 640x480 YUYV frames with coloured rectangles (upright "cylinders" and
// neutral clutter), sensor noise and speckle, and the colour table that finds their two colours.
#pragma once
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

extern "C" {
#include "cyl/colortable.h"
#include "cyl/segment.h"
#include "synth_frames.h"
}

namespace bench {

constexpr uint32_t kW = 640, kH = 480;
inline const uint8_t kOrange[3] = {150, 80, 190}, kGreen[3] = {140, 60, 70};

// The frame sets of the benchmark:
//   typical  walls and furniture, 3-5 upright coloured "cylinders", sensor noise, 0.2% specks
//            (1-12% of the pixels coloured: what a robot usually sees);
//   dense    about half the frame coloured in 25-120 rectangles of both classes, sensor noise
//            (a worst case for run detection and blob merging);
//   speckle  the typical frame with 5% single-pixel specks of the class colours (a worst case for
//            the background skip).
enum class FrameSet { Typical, Dense, Speckle };

inline const char *set_name(FrameSet s)
{
    return s == FrameSet::Typical ? "typical" : s == FrameSet::Dense ? "dense" : "speckle";
}

inline std::vector<uint8_t> make_frame(uint64_t seed, FrameSet set = FrameSet::Typical, uint32_t W = kW,
                                       uint32_t H = kH, cyl_pixfmt fmt = CYL_FMT_YUYV)
{
    test_rng r;
    test_rng_seed(&r, seed);
    canvas c;
    canvas_alloc(&c, W, H);
    canvas_fill(&c, 110, 128, 128);
    const double sx = W / 640.0, sy = H / 480.0;  // the layout scales with the frame
    for (int i = 0; i < 6; i++) {  // walls and furniture in neutral colours
        canvas_rect(&c, (int32_t)test_rng_int(&r, 0, W), (int32_t)test_rng_int(&r, 0, H),
                    (int32_t)(test_rng_int(&r, 20, 200) * sx), (int32_t)(test_rng_int(&r, 20, 200) * sy),
                    (uint8_t)test_rng_int(&r, 40, 220), (uint8_t)test_rng_int(&r, 110, 145),
                    (uint8_t)test_rng_int(&r, 110, 145));
    }
    if (set == FrameSet::Dense) {
        // rectangles of both classes until about half the frame is coloured
        int n = (int)test_rng_int(&r, 25, 120);
        const double mean_area = 0.8 * W * H / n;  // overlaps leave about half coloured
        for (int i = 0; i < n; i++) {
            const uint8_t *col = (i % 2) ? kGreen : kOrange;
            const double a = mean_area * (0.5 + test_rng_int(&r, 0, 100) / 100.0);
            const double aspect = 0.3 + test_rng_int(&r, 0, 100) / 40.0;
            int w = (int)std::max(2.0, std::sqrt(a * aspect)), h = (int)std::max(2.0, a / w);
            canvas_rect(&c, (int32_t)test_rng_int(&r, 0, W - 1), (int32_t)test_rng_int(&r, 0, H - 1), w, h, col[0],
                        col[1], col[2]);
        }
    } else {
        int n = (int)test_rng_int(&r, 3, 6);
        for (int i = 0; i < n; i++) {  // cylinders seen from the side: upright rectangles
            const uint8_t *col = (i % 2) ? kGreen : kOrange;
            int w = (int)(test_rng_int(&r, 12, 60) * sx);
            canvas_rect(&c, (int32_t)test_rng_int(&r, 0, W - w), (int32_t)(test_rng_int(&r, 100, 300) * sy), w,
                        (int32_t)(w * 3), col[0], col[1], col[2]);
        }
    }
    canvas_noise(&c, &r, 3.0, 3.0);
    const uint8_t speck[2][3] = {{150, 80, 190}, {140, 60, 70}};
    canvas_speckle(&c, &r, set == FrameSet::Speckle ? 0.05 : 0.002, speck, 2);
    std::vector<uint8_t> buf(cyl_image_buffer_size(fmt, W, H, 0));
    cyl_image img;
    canvas_to_format(&c, fmt, 0, 0, buf.data(), buf.size(), &img);
    canvas_free(&c);
    return buf;
}

// Fraction of a frame's pixels that the table classifies (for the report).
inline double coloured_fraction(const cyl_colortable &t, const std::vector<uint8_t> &yuyv)
{
    size_t n = 0;
    for (size_t i = 0; i + 3 < yuyv.size(); i += 4) {
        n += cyl_colortable_mask(&t, yuyv[i], yuyv[i + 1], yuyv[i + 3]) != 0;
        n += cyl_colortable_mask(&t, yuyv[i + 2], yuyv[i + 1], yuyv[i + 3]) != 0;
    }
    return (double)n / (double)(yuyv.size() / 2);
}

inline double median(std::vector<double> v)
{
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

inline double now_us()
{
    return std::chrono::duration<double, std::micro>(
               std::chrono::steady_clock::now().time_since_epoch()).count();
}

// The table both benchmarks use: orange and green as CMVision-style boxes.
inline void make_table(cyl_colortable *table)
{
    cyl_colortable_init(table);
    cyl_colortable_set_class(table, 0, "orange", 255, 128, 0);
    cyl_colortable_set_class(table, 1, "green", 0, 200, 0);
    cyl_colortable_add_box(table, 0, 60, 240, 70, 90, 180, 200);
    cyl_colortable_add_box(table, 1, 60, 240, 50, 70, 60, 80);
    cyl_colortable_refresh(table);   // as loading a table file does: the inner boxes of the run extension
}

// The benchmarks' shared set-up: nframes distinct frames, the table, and segmentation memory.
// The same classes in the 3-D table's form, as learning leaves them (cyl/colorlearn.h): a cell
// belongs to a class when its centre colour does; uv is the cells' projection and y all ones,
// so segmentation uses the 3-D lookup alone (CYL_LOOKUP_YUV).
inline void to_3d_table(const cyl_colortable &box, cyl_colortable *t)
{
    *t = box;
    std::memset(t->uv, 0, sizeof t->uv);
    for (unsigned yc = 0; yc < CYL_YUV_NY; yc++)
        for (unsigned uc = 0; uc < CYL_YUV_NC; uc++)
            for (unsigned vc = 0; vc < CYL_YUV_NC; vc++) {
                const unsigned Y = yc * 8 + 4, U = uc * 4 + 2, V = vc * 4 + 2;
                const cyl_mask m = (cyl_mask)(box.uv[U][V] & box.y[Y]);
                t->yuv[yc][uc][vc] = m;
                for (unsigned du = 0; du < 4; du++)
                    for (unsigned dv = 0; dv < 4; dv++) t->uv[uc * 4 + du][vc * 4 + dv] |= m;
            }
    std::memset(t->y, 0xFF, sizeof t->y);
    cyl_colortable_refresh(t);
}

struct Setup {
    std::vector<std::vector<uint8_t>> frames;
    cyl_colortable table, table3d;
    cyl_segment_params params = cyl_segment_params_default();
    std::vector<uint8_t> mem;
    cyl_segmentation seg{};
    explicit Setup(int nframes, uint32_t max_runs = 40000, uint32_t max_blobs = 4096,
                   FrameSet set = FrameSet::Typical)
    {
        for (int i = 0; i < nframes; i++) frames.push_back(make_frame(1000 + (uint64_t)i, set));
        make_table(&table);
        to_3d_table(table, &table3d);
        mem.resize(cyl_segment_mem_size(max_runs, max_blobs));
        cyl_segmentation_init(&seg, mem.data(), mem.size(), max_runs, max_blobs);
    }
};

} // namespace bench
