// SPDX-License-Identifier: BSD-3-Clause
// The detector config's landmark models (`landmarks:`, docs/formats.md): parsed into libcyl's
// models, written back by detector_config_yaml, and bad input named by file, line and field; and
// the Detector observing a painted two-band landmark as one observation with its identity.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "config_file.hpp"
#include "cylfe/error.hpp"
#include "cylfe/overlay.hpp"
#include "cylfe/pipeline.hpp"

using namespace cylfe;

namespace {

cyl_colortable table3()
{
    cyl_colortable t;
    cyl_colortable_init(&t);
    cyl_colortable_set_class(&t, 0, "orange", 255, 128, 0);
    cyl_colortable_set_class(&t, 1, "pink", 255, 0, 255);
    cyl_colortable_set_class(&t, 2, "green", 0, 255, 0);
    return t;
}

using cfgtest::write_tmp;

const char *kGood = "landmarks:\n"
                    "  plane_height_m: 0.15\n"
                    "  grouping:\n"
                    "    scale_tol: 0.4\n"
                    "  models:\n"
                    "    - name: cone\n"
                    "      bands: [orange, gap, orange]\n"
                    "      band_heights_m: [0.10, 0.05, 0.15]\n"
                    "      shape: cone\n"
                    "      diameter_m: [0.25, 0.05]\n"
                    "    - name: code3\n"
                    "      bands: [pink, green]\n"
                    "      band_heights_m: [0.15, 0.15]\n"
                    "      diameter_m: 0.1\n"
                    "      id: 3\n";

// the error message of loading text, or "" if it loads
std::string error_of(const std::string &text)
{
    DetectorConfig c;
    return cfgtest::load_error(text, table3(), c);
}

int seg_blob_at(const cyl_segmentation &seg, int x, int y)
{
    for (uint32_t i = 0; i < seg.n_blobs; i++)
        if (x >= seg.blobs[i].x0 && x <= seg.blobs[i].x1 && y >= seg.blobs[i].y0 && y <= seg.blobs[i].y1) return (int)i;
    return -1;
}

} // namespace

TEST(LandmarkConfig, ParsesModels)
{
    const std::string p = write_tmp(kGood);
    cyl_colortable t = table3();
    DetectorConfig c;
    load_detector_config(p, t, c);
    std::remove(p.c_str());
    ASSERT_EQ(c.models.size(), 2u);
    EXPECT_EQ(c.model_names[0], "cone");
    EXPECT_DOUBLE_EQ(c.plane_height_m, 0.15);
    EXPECT_DOUBLE_EQ(c.group.scale_tol, 0.4);
    const cyl_landmark_model &a = c.models[0], &b = c.models[1];
    EXPECT_EQ(a.n_bands, 3);
    EXPECT_EQ(a.band_cls[0], 0);
    EXPECT_EQ(a.band_cls[1], CYL_BAND_GAP);
    EXPECT_EQ(a.band_cls[2], 0);
    EXPECT_DOUBLE_EQ(a.band_height_m[1], 0.05);
    EXPECT_EQ(a.shape, CYL_SHAPE_CONE);
    EXPECT_DOUBLE_EQ(a.diameter_bottom_m, 0.25);
    EXPECT_DOUBLE_EQ(a.diameter_top_m, 0.05);
    EXPECT_EQ(a.id, -1);
    EXPECT_EQ(b.shape, CYL_SHAPE_CYLINDER);
    EXPECT_EQ(b.band_cls[0], 1);
    EXPECT_EQ(b.band_cls[1], 2);
    EXPECT_EQ(b.id, 3);
    EXPECT_EQ(model_classes(c), 0x7u);
    // written back and read again: the same models
    const std::string p2 = write_tmp(detector_config_yaml(c, t, "round trip"));
    DetectorConfig c2;
    load_detector_config(p2, t, c2);
    std::remove(p2.c_str());
    ASSERT_EQ(c2.models.size(), 2u);
    EXPECT_EQ(c2.model_names, c.model_names);
    for (size_t i = 0; i < 2; i++) {
        EXPECT_EQ(c2.models[i].n_bands, c.models[i].n_bands);
        EXPECT_EQ(std::vector<uint8_t>(c2.models[i].band_cls, c2.models[i].band_cls + 4),
                  std::vector<uint8_t>(c.models[i].band_cls, c.models[i].band_cls + 4));
        EXPECT_DOUBLE_EQ(c2.models[i].diameter_bottom_m, c.models[i].diameter_bottom_m);
        EXPECT_DOUBLE_EQ(c2.models[i].diameter_top_m, c.models[i].diameter_top_m);
        EXPECT_EQ(c2.models[i].id, c.models[i].id);
    }
}

TEST(LandmarkConfig, BadInputNamesLineAndField)
{
    const std::string head = "landmarks:\n  plane_height_m: 0.15\n  models:\n    - name: a\n";
    EXPECT_EQ(error_of(head + "      bands: [orange, pinkk]\n      band_heights_m: [0.1, 0.1]\n      diameter_m: 0.1\n"),
              "FILE:5: landmarks.models[0].bands: 'pinkk' is not a class of the table (did you mean 'pink'?)");
    EXPECT_EQ(error_of(head + "      bands: [gap, orange]\n      band_heights_m: [0.1, 0.1]\n      diameter_m: 0.1\n"),
              "FILE:5: landmarks.models[0].bands: the first and the last band must be classes, not gap");
    EXPECT_EQ(error_of(head + "      bands: [orange]\n      band_heights_m: [0.1, 0.1]\n      diameter_m: 0.1\n"),
              "FILE:6: landmarks.models[0].band_heights_m: expected a list of 1 numbers");
    EXPECT_EQ(error_of(head + "      bands: [orange]\n      band_heights_m: [0.1]\n      diameter_m: 0.1\n      colour: red\n"),
              "FILE:8: landmarks.models[0]: unknown key 'colour'");
    EXPECT_EQ(error_of(head + "      bands: [orange]\n      band_heights_m: [0.1]\n      diameter_m: [0.1, 0.2]\n"),
              "FILE:7: landmarks.models[0].diameter_m: a cylinder has one diameter (a cone: [base, top])");
    EXPECT_EQ(error_of(head + "      bands: [orange]\n      band_heights_m: [0.1]\n      diameter_m: 0.1\n      shape: pyramid\n"),
              "FILE:8: landmarks.models[0].shape: 'pyramid' is not cylinder or cone");
    EXPECT_EQ(error_of(head + "      bands: [orange]\n      band_heights_m: [0.1]\n      diameter_m: 0.1\n"
                              "    - name: b\n      bands: [orange]\n      band_heights_m: [0.2]\n      diameter_m: 0.1\n"),
              "FILE:9: landmarks.models[1].bands: the same bands as model 'a' (the code would not tell them apart)");
    EXPECT_EQ(error_of(head + "      bands: [orange]\n      band_heights_m: [0.1]\n      diameter_m: 0.1\n      id: 4\n"
                              "    - name: b\n      bands: [pink]\n      band_heights_m: [0.2]\n      diameter_m: 0.1\n"
                              "      id: 4\n"),
              "FILE:13: landmarks.models[1].id: 4 is the id of another model");
    EXPECT_EQ(error_of("landmarks:\n  models:\n    - name: a\n"),
              "FILE:2: landmarks: plane_height_m is required (the height above the floor of the plane the camera's "
              "mount_height_m is counted from, m)");
    EXPECT_EQ(error_of("landmarks:\n  plane_height_m: 0.15\n  models: []\n"),
              "FILE:3: landmarks.models: expected a list of models");
}

// A two-band coded landmark painted into a YUV 4:4:4 frame (pink over green, each 20 x 20 px,
// touching) with one lone green square elsewhere: the detector gives one observation of the
// model with its identity and the union box, and the lone square as that model with a band missing.
TEST(LandmarkConfig, DetectorObservesTheGroup)
{
    const std::string p = write_tmp("landmarks:\n  plane_height_m: 0.15\n  models:\n    - name: code3\n"
                                    "      bands: [pink, green]\n      band_heights_m: [0.1, 0.1]\n"
                                    "      diameter_m: 0.1\n      id: 3\n");
    cyl_colortable t = table3();
    ASSERT_EQ(cyl_colortable_add_box(&t, 1, 0, 255, 150, 200, 150, 200), CYL_OK);   // pink: U, V high
    ASSERT_EQ(cyl_colortable_add_box(&t, 2, 0, 255, 50, 100, 50, 100), CYL_OK);     // green: U, V low
    DetectorConfig c;
    load_detector_config(p, t, c);
    std::remove(p.c_str());
    const uint32_t W = 320, H = 240;
    std::vector<uint8_t> buf(3 * W * H, 128);
    auto paint = [&](int x0, int y0, int w, int h, uint8_t u, uint8_t v) {
        for (int y = y0; y < y0 + h; y++)
            for (int x = x0; x < x0 + w; x++) {
                buf[W * H + (size_t)y * W + x] = u;
                buf[2 * W * H + (size_t)y * W + x] = v;
            }
    };
    paint(150, 150, 20, 20, 175, 175);
    paint(150, 170, 20, 20, 75, 75);
    paint(40, 40, 20, 20, 75, 75);
    cyl_image img;
    ASSERT_EQ(cyl_image_wrap(&img, CYL_FMT_YUV444P, W, H, buf.data(), W), CYL_OK);
    cyl_camera cam;
    cyl_camera_init(&cam);
    cam.width = W; cam.height = H;
    cam.fx_px = cam.fy_px = 300; cam.cx_px = 160; cam.cy_px = 60;
    cam.tilt_rad = 0.2; cam.height_m = 0.3; cam.offset_m = 0;
    Detector det(t, cam, c);
    const std::vector<cyl_observation> &obs = det.process(img);
    ASSERT_EQ(obs.size(), 2u);
    EXPECT_EQ(obs[0].model, 0);
    EXPECT_EQ(obs[0].landmark_id, 3);
    EXPECT_EQ(obs[0].group_flags, 0u);
    EXPECT_DOUBLE_EQ(obs[0].code_confidence, 1.0);
    EXPECT_EQ(obs[0].area, 800u);
    EXPECT_DOUBLE_EQ(obs[0].centroid_u_px, 159.5);
    EXPECT_DOUBLE_EQ(obs[0].centroid_v_px, 169.5);
    ASSERT_EQ(det.boxes().size(), 2u);
    EXPECT_EQ(det.boxes()[0], (std::array<uint16_t, 4>{150, 150, 169, 189}));
    EXPECT_EQ(obs[1].model, 0);
    EXPECT_EQ(obs[1].landmark_id, -1);
    EXPECT_EQ(obs[1].group_flags, (uint32_t)CYL_GROUP_MISSING_BAND);
    EXPECT_DOUBLE_EQ(obs[1].code_confidence, 0.5);
    EXPECT_EQ(det.boxes()[1], (std::array<uint16_t, 4>{40, 40, 59, 59}));
    ASSERT_EQ(det.members().size(), 2u);
    EXPECT_EQ(det.members()[0][0], (uint32_t)seg_blob_at(det.segmentation(), 155, 155));
    EXPECT_EQ(det.members()[0][1], (uint32_t)seg_blob_at(det.segmentation(), 155, 175));
    // the overlay: the green band tinted green (not grey, as a rejected blob would be), the union
    // box in the landmark's colour (its first band's, pink) at the top-left corner of the pink band
    cv::Mat bgr = to_bgr(img);
    OverlayOptions opt;
    opt.min_confidence = 0.0;
    opt.key = false;
    draw_overlay(bgr, det, obs, opt);
    const cv::Vec3b g = bgr.at<cv::Vec3b>(180, 160), corner = bgr.at<cv::Vec3b>(150, 150);
    EXPECT_GT(g[1], g[0] + 40);
    EXPECT_GT(g[1], g[2] + 40);
    EXPECT_EQ(corner, cv::Vec3b(255, 0, 255));
}
