/* SPDX-License-Identifier: BSD-3-Clause */
/* Compile-time options (cyl/config.h): the library reports the configuration the headers were
 * compiled with, what is compiled out answers CYL_ERR_UNSUPPORTED (a pixel format: CYL_ERR_FORMAT)
 * and what is compiled in works. `make test` runs this test against the default library and
 * against one built with CYL_CONFIG_FIRMWARE_MINIMAL (this file compiled with the same flag). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <cmocka.h>

#include "cyl/colorlearn.h"
#include "cyl/colortable.h"
#include "cyl/config.h"
#include "cyl/landmark.h"
#include "cyl/noise.h"
#include "cyl/observe.h"
#include "cyl/segment.h"
#include "cyl/silhouette.h"
#include "cyl/subpixel.h"
#include "synth_frames.h"
#include "unc_paper.h"

#define W 768
#define H 576

static void test_reported_configuration_matches_the_headers(void **state)
{
    const uint32_t want = (CYL_CONFIG_IMAGE_ESTIMATOR ? CYL_FEATURE_IMAGE_ESTIMATOR : 0u) |
                          (CYL_CONFIG_SUBPIXEL ? CYL_FEATURE_SUBPIXEL : 0u) |
                          (CYL_CONFIG_MODELS ? CYL_FEATURE_MODELS : 0u) | (CYL_CONFIG_LEARN ? CYL_FEATURE_LEARN : 0u);
    (void)state;
    print_message("  features 0x%x, formats 0x%x\n", cyl_config_features(), cyl_config_formats());
    assert_int_equal(cyl_config_features(), want);
    assert_int_equal(cyl_config_formats(), (uint32_t)CYL_CONFIG_FORMATS);
    assert_string_equal(cyl_status_str(CYL_ERR_UNSUPPORTED), "feature compiled out of this build (cyl/config.h)");
}

static void test_formats_wrap_only_when_compiled_in(void **state)
{
    static uint8_t buf[64 * 48 * 3];
    int f;
    (void)state;
    for (f = CYL_FMT_YUYV; f <= CYL_FMT_YUV444P; f++) {
        cyl_image img;
        const int on = (CYL_CONFIG_FORMATS & CYL_FORMAT_BIT(f)) != 0;
        assert_int_equal(cyl_image_wrap(&img, (cyl_pixfmt)f, 64, 48, buf, 0), on ? CYL_OK : CYL_ERR_FORMAT);
    }
    assert_true(cyl_config_formats() & CYL_FORMAT_BIT(CYL_FMT_YUYV));   /* every configuration has YUYV */
}

/* One orange rectangle on grey, YUYV, segmented and observed: what every configuration does. */
typedef struct scene {
    canvas cv;
    uint8_t *buf;
    void *mem;
    cyl_image img;
    cyl_colortable t;
    cyl_segmentation seg;
    cyl_camera cam;
} scene;

static void scene_make(scene *s)
{
    size_t cap, msz;
    uint32_t maxr;
    memset(s, 0, sizeof *s);
    assert_true(canvas_alloc(&s->cv, W, H));
    canvas_fill(&s->cv, 128, 128, 128);
    canvas_rect(&s->cv, 380, 400, 20, 40, 150, 90, 200);   /* x 380..399, y 400..439 */
    cap = canvas_format_size(&s->cv, CYL_FMT_YUYV, 0);
    s->buf = malloc(cap);
    assert_true(canvas_to_format(&s->cv, CYL_FMT_YUYV, 0, 0, s->buf, cap, &s->img));
    cyl_colortable_init(&s->t);
    assert_int_equal(cyl_colortable_add_box(&s->t, 0, 0, 255, 60, 109, 160, 230), CYL_OK);
    maxr = cyl_segment_max_runs(W, H, NULL);
    msz = cyl_segment_mem_size(maxr, 16);
    s->mem = malloc(msz);
    assert_int_equal(cyl_segmentation_init(&s->seg, s->mem, msz, maxr, 16), CYL_OK);
    assert_int_equal(cyl_segment(&s->t, &s->img, NULL, &s->seg), CYL_OK);
    unc_paper_camera(&s->cam);
}

static void scene_free(scene *s)
{
    free(s->buf);
    free(s->mem);
    canvas_free(&s->cv);
}

static void test_segment_and_observe_in_every_configuration(void **state)
{
    scene s;
    cyl_observe_params p = cyl_observe_params_default();
    cyl_observation obs[4];
    uint32_t n = 0;
    (void)state;
    scene_make(&s);
    assert_int_equal(s.seg.n_blobs, 1);
    assert_int_equal(s.seg.blobs[0].area, 20 * 40);
    assert_int_equal(cyl_observe(&s.seg, &s.cam, &p, NULL, 0, obs, 4, &n), CYL_OK);
    assert_int_equal(n, 1);
    /* the rectangle's centroid, by hand: (380 + 399) / 2, (400 + 439) / 2 */
    assert_true(fabs(obs[0].centroid_u_px - 389.5) < 1e-12);
    assert_true(fabs(obs[0].centroid_v_px - 419.5) < 1e-12);
    assert_true(obs[0].range_m > 0.0 && isfinite(obs[0].range_m));
    assert_true(obs[0].cov_rb[0][0] > 0.0);
    scene_free(&s);
}

static void test_features_answer_or_refuse(void **state)
{
    scene s;
    cyl_observe_params p = cyl_observe_params_default();
    cyl_observation obs[4];
    cyl_centroid_noise cn;
    cyl_subpixel_params spp = cyl_subpixel_params_default();
    cyl_subpixel_result sr;
    cyl_noise_image_params nip = cyl_noise_image_params_default();
    uint32_t n = 0;
    cyl_status want;
    (void)state;
    scene_make(&s);
    /* the image estimator */
    want = CYL_CONFIG_IMAGE_ESTIMATOR ? CYL_OK : CYL_ERR_UNSUPPORTED;
    assert_int_equal(cyl_noise_blob_image(&s.seg, &s.seg.blobs[0], &s.img, &s.t, &nip, &cn), want);
    p.estimator = CYL_NOISE_IMAGE;
    p.image = &s.img;
    p.table = &s.t;
    assert_int_equal(cyl_observe(&s.seg, &s.cam, &p, NULL, 0, obs, 4, &n), want);
    if (want == CYL_OK) assert_true(obs[0].var_u_px2 >= 0.0 && isfinite(obs[0].var_u_px2));
    /* sub-pixel edges: a sharp rectangle's edges stay where they are */
    want = CYL_CONFIG_SUBPIXEL ? CYL_OK : CYL_ERR_UNSUPPORTED;
    assert_int_equal(cyl_subpixel_centroid(&s.seg, &s.seg.blobs[0], &s.img, &s.t, &spp, &sr), want);
    if (want == CYL_OK) {
        assert_true(fabs(sr.cx_px - 389.5) < 1e-9);
        assert_true(fabs(sr.cy_px - 419.5) < 1e-9);
    }
    p = cyl_observe_params_default();
    p.subpixel = 1;
    p.image = &s.img;
    p.table = &s.t;
    assert_int_equal(cyl_observe(&s.seg, &s.cam, &p, NULL, 0, obs, 4, &n), want);
    /* side_colour_rel and its flag come with the sub-pixel edges (both read the image around the
     * blob's edges): compiled out, the measure stays 0 and asking for the flag is refused */
    p = cyl_observe_params_default();
    p.image = &s.img;
    assert_int_equal(cyl_observe(&s.seg, &s.cam, &p, NULL, 0, obs, 4, &n), CYL_OK);
    if (!CYL_CONFIG_SUBPIXEL) assert_true(obs[0].side_colour_rel == 0.0);
    p.partial_side_max = 0.5;
    assert_int_equal(cyl_observe(&s.seg, &s.cam, &p, NULL, 0, obs, 4, &n), want);
    /* landmark models */
    {
        cyl_landmark_model m;
        cyl_silhouette_bias sb;
        cyl_group g[4];
        cyl_group_params gp = cyl_group_params_default();
        const size_t gsz = cyl_group_work_size(16, &gp);
        void *gwork = malloc(gsz + 1u);
        uint32_t ng = 0;
        memset(&m, 0, sizeof m);
        m.n_bands = 1;
        m.band_cls[0] = 0;
        m.band_height_m[0] = 0.3;
        m.shape = CYL_SHAPE_CYLINDER;
        m.diameter_bottom_m = 0.1;
        m.id = -1;
        want = CYL_CONFIG_MODELS ? CYL_OK : CYL_ERR_UNSUPPORTED;
        assert_int_equal(cyl_landmark_models_check(&m, 1), want);
        assert_int_equal(cyl_silhouette_bias_model(&s.cam, 2.0, 0.0, &m, 0.0, 1u, 0.25, 0.0, &sb), want);
        assert_int_equal(cyl_group_blobs(&s.seg, &m, 1, &gp, gwork, gsz, g, 4, &ng), want);
        if (want == CYL_OK) assert_int_equal(ng, 1);
        assert_int_equal(cyl_observe_groups(&s.seg, g, want == CYL_OK ? ng : 0, &m, 1, 0.0, &s.cam, &p, NULL, 0,
                                            obs, 4, &n), want);
        free(gwork);
    }
    /* colour learning */
    {
        cyl_colorhist *h = malloc(sizeof *h);
        assert_non_null(h);
        cyl_colorhist_clear(h);
        want = CYL_CONFIG_LEARN ? CYL_OK : CYL_ERR_UNSUPPORTED;
        assert_int_equal(cyl_colorhist_add(h, &s.img, NULL, NULL, 0, 0), want);
        free(h);
    }
    scene_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reported_configuration_matches_the_headers),
        cmocka_unit_test(test_formats_wrap_only_when_compiled_in),
        cmocka_unit_test(test_segment_and_observe_in_every_configuration),
        cmocka_unit_test(test_features_answer_or_refuse),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
