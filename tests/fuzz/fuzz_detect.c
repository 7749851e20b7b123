/* SPDX-License-Identifier: BSD-3-Clause */
/* libFuzzer: frame -> blobs -> observations over random formats, dimensions, strides, regions
 * of interest, steps and merge rules (within the documented limits), with invariants checked:
 * every blob's runs add up to its area and point back to it, counts stay within capacity,
 * observations are finite or flagged. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include "cyl/observe.h"

#define MAX_W 200
#define MAX_H 120

static uint8_t frame[4 * MAX_W * MAX_H + 4096];

static uint32_t take(const uint8_t **p, size_t *n, uint32_t mod)
{
    uint32_t v = 0;
    if (*n >= 2) { v = (uint32_t)((*p)[0] | ((*p)[1] << 8)); *p += 2; *n -= 2; }
    return mod ? v % mod : v;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const cyl_pixfmt fmts[] = { CYL_FMT_YUYV, CYL_FMT_UYVY, CYL_FMT_NV12, CYL_FMT_I420, CYL_FMT_YUV444P };
    static cyl_colortable t;
    static int init;
    static uint8_t mem[1 << 20];
    static cyl_observation obs[64];
    static uint8_t work[1 << 16];
    cyl_segmentation seg;
    cyl_segment_params p = cyl_segment_params_default();
    cyl_observe_params op = cyl_observe_params_default();
    cyl_camera cam;
    cyl_image img;
    uint32_t w, h, max_runs, max_blobs, i, n_obs = 0;
    size_t stride, need, k;
    cyl_pixfmt fmt;
    cyl_status s;

    if (!init) {
        cyl_colortable_init(&t);
        cyl_colortable_add_box(&t, 0, 30, 250, 60, 100, 170, 210);
        cyl_colortable_add_box(&t, 1, 30, 250, 40, 80, 50, 90);
        cyl_colortable_add_box(&t, 2, 0, 255, 0, 255, 0, 40);
        init = 1;
    }
    fmt = fmts[take(&data, &size, 5)];
    w = 1 + take(&data, &size, MAX_W);
    h = 1 + take(&data, &size, MAX_H);
    stride = take(&data, &size, 64);
    if (stride) stride += (fmt == CYL_FMT_YUYV || fmt == CYL_FMT_UYVY) ? 4 * ((w + 1) / 2) : w;
    p.min_run_px = (uint16_t)(1 + take(&data, &size, 5));
    p.x_step = (uint16_t)(1 + take(&data, &size, 3));
    p.y_step = (uint16_t)(1 + take(&data, &size, 3));
    p.roi.x = take(&data, &size, w);
    p.roi.y = take(&data, &size, h);
    p.roi.width = take(&data, &size, w + 1);
    p.roi.height = take(&data, &size, h + 1);
    for (i = 0; i < CYL_MAX_CLASSES; i++) {
        p.cls[i].merge_gap_px = (int32_t)take(&data, &size, 12) - 2;
        p.cls[i].merge_min_density = take(&data, &size, 101) / 100.0;
        p.cls[i].min_area = take(&data, &size, 20);
    }
    max_runs = 1 + take(&data, &size, 4000);
    max_blobs = 1 + take(&data, &size, 500);
    need = cyl_image_buffer_size(fmt, w, h, stride);
    if (need == 0 || need > sizeof frame) return 0;
    for (k = 0; k < need; k++) frame[k] = size ? data[k % size] : (uint8_t)k;
    if (cyl_image_wrap(&img, fmt, w, h, frame, stride) != CYL_OK) abort();
    if (cyl_segment_mem_size(max_runs, max_blobs) > sizeof mem) return 0;
    if (cyl_segmentation_init(&seg, mem, sizeof mem, max_runs, max_blobs) != CYL_OK) abort();
    s = cyl_segment(&t, &img, &p, &seg);
    if (s == CYL_ERR_SIZE) {
        /* only an ROI outside the frame may be refused here */
        if (p.roi.width && p.roi.height && p.roi.x + p.roi.width <= w && p.roi.y + p.roi.height <= h) abort();
        return 0;
    }
    if (s < 0) abort();
    if (seg.n_runs > max_runs || seg.n_blobs > max_blobs) abort();
    for (i = 0; i < seg.n_blobs; i++) {
        const cyl_blob *b = &seg.blobs[i];
        uint32_t r, area = 0, runs = 0;
        for (r = b->first_run; r != CYL_NONE; r = seg.runs[r].next) {
            if (r >= seg.n_runs || seg.runs[r].blob != i || seg.runs[r].cls != b->cls) abort();
            area += seg.runs[r].width;
            if (++runs > seg.n_runs) abort();
        }
        if (area != b->area || runs != b->n_runs) abort();
        if (!(b->cx_px >= b->x0 && b->cx_px <= b->x1 && b->cy_px >= b->y0 && b->cy_px <= b->y1)) abort();
    }
    cyl_camera_init(&cam);
    cam.width = w; cam.height = h;
    cam.fx_px = cam.fy_px = 50.0 + take(&data, &size, 500);
    cam.cx_px = w / 2.0; cam.cy_px = h / 2.0;
    cam.k1 = ((double)take(&data, &size, 200) - 100.0) / 400.0;
    cam.tilt_rad = ((double)take(&data, &size, 200) - 50.0) / 200.0;
    cam.height_m = 0.1 + take(&data, &size, 100) / 100.0;
    cam.tilt_sigma_rad = 0.01; cam.yaw_sigma_rad = 0.01; cam.height_sigma_m = 0.001;
    op.size[0].diameter_m = 0.1; op.size[0].height_m = 0.3;
    op.estimator = (cyl_noise_estimator)take(&data, &size, 4);  /* uniform, column, local, image */
    op.image = &img;
    op.table = &t;
    op.image_noise.band_px = 1 + take(&data, &size, 4);
    op.image_noise.draws = 2 + take(&data, &size, 8);
    op.model = (cyl_geom_model)take(&data, &size, 2);
    if (cyl_observe_work_size(&seg, &op) > sizeof work) return 0;
    s = cyl_observe(&seg, &cam, &op, work, sizeof work, obs, 64, &n_obs);
    if (s < 0) abort();
    if (n_obs > 64) abort();
    for (i = 0; i < n_obs; i++) {
        const cyl_observation *o = &obs[i];
        if (o->flags & (CYL_OBS_INVALID | CYL_OBS_NO_RANGE)) continue;
        if (!isfinite(o->range_m) || o->range_m < 0 || !isfinite(o->cov_rb[0][0]) || o->cov_rb[0][0] < 0 ||
            o->cov_rb[1][1] < 0 || !(o->confidence >= 0 && o->confidence <= 1))
            abort();
    }
    return 0;
}
