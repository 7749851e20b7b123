// SPDX-License-Identifier: BSD-3-Clause
// Uncertainty benchmark: time of noise estimation + camera model (cyl_observe with the
// local estimator: centroid variance, undistortion, range/bearing, covariance, confidence) for
// all blobs of a frame, against the time to segment that frame (cyl_segment). Same synthetic
// frames as bench_segment. Prints a table line and, last, a JSON fragment
// (", \"observe_us\": ..., \"observe_over_segment\": ...") for scripts/bench.sh's BENCH_EXTRA_JSON.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <vector>

extern "C" {
#include "cyl/colortable.h"
#include "cyl/observe.h"
#include "cyl/segment.h"
#include "synth_frames.h"
}

#include "bench_frames.hpp"

using namespace bench;

int main(int argc, char **argv)
{
    int iterations = argc > 1 ? std::atoi(argv[1]) : 400;
    const int nframes = 8;
    static Setup set(nframes);  // static: the table is 66 KB
    const std::vector<std::vector<uint8_t>> &frames = set.frames;
    const cyl_colortable &table = set.table;
    const cyl_segment_params &params = set.params;
    cyl_segmentation &seg = set.seg;

    // the paper's camera (Tables 4, 5; docs/uncertainty.md), centred for 640x480
    cyl_camera cam;
    cyl_camera_init(&cam);
    cam.width = kW; cam.height = kH;
    cam.fx_px = 875.2; cam.fy_px = 872.4; cam.cx_px = 319.5; cam.cy_px = 239.5;
    cam.k1 = -0.1;  // exercise the iterative undistortion
    const double sig[CYL_INTR_COUNT] = {0.4565, 0.4399, 0.3216, 0.2826, 1e-3, 0, 0, 0, 0};
    cyl_camera_set_intrinsic_sigmas(&cam, sig);
    const double deg = 3.14159265358979323846 / 180.0;
    cam.tilt_rad = 1.656 * deg; cam.tilt_sigma_rad = 0.575 * deg; cam.yaw_sigma_rad = 0.443 * deg;
    cam.height_m = 0.326; cam.height_sigma_m = 3.04e-4; cam.offset_m = 0.15; cam.offset_sigma_m = 0.00255;
    cam.flags = 0;
    cyl_observe_params op = cyl_observe_params_default();
    op.size[0].diameter_m = op.size[1].diameter_m = 0.10;
    op.size[0].height_m = op.size[1].height_m = 0.30;
    std::vector<cyl_observation> obs(seg.max_blobs);

    std::vector<double> t_seg, t_obs;
    unsigned long nobs = 0, nblobs = 0;
    double sink = 0;
    for (int i = 0; i < iterations; i++) {
        cyl_image img;
        cyl_image_wrap(&img, CYL_FMT_YUYV, kW, kH, frames[(size_t)i % nframes].data(), 0);
        double t0 = now_us();
        cyl_segment(&table, &img, &params, &seg);
        double t1 = now_us();
        uint32_t n = 0;
        cyl_observe(&seg, &cam, &op, nullptr, 0, obs.data(), (uint32_t)obs.size(), &n);
        double t2 = now_us();
        t_seg.push_back(t1 - t0);
        t_obs.push_back(t2 - t1);
        nobs += n;
        nblobs += seg.n_blobs;
        for (uint32_t k = 0; k < n; k++) sink += obs[k].cov_rb[0][0];
    }
    double ms = median(t_seg), mo = median(t_obs);
    std::printf("uncertainty: cyl_observe (local estimator + camera model) %.1f us/frame for %.1f blobs "
                "(%.2f us/blob) vs cyl_segment %.1f us/frame: %.1f%% (limit 10%%) [sink %g]\n",
                mo, (double)nobs / iterations, mo / std::max(1.0, (double)nobs / iterations), ms,
                100 * mo / ms, sink > 0 ? 1.0 : 0.0);
    std::printf(", \"observe_us\": %.2f, \"observe_blobs_per_frame\": %.2f, \"observe_us_per_blob\": %.3f, "
                "\"observe_over_segment\": %.4f\n",
                mo, (double)nobs / iterations, mo / std::max(1.0, (double)nobs / iterations), mo / ms);
    (void)nblobs;
    return 0;
}
