// SPDX-License-Identifier: BSD-3-Clause
// The detector config's blob rules beyond the gates (docs/formats.md): weak_alone_min_area_px per
// class, and the waist cut (split_waist per class, split_axes): read, written back by
// detector_config_yaml, a value out of range named by file, line and field; and the Detector
// turning two painted cones, the far one standing on the near one's tip, into two observations
// with the cut and one without.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "config_file.hpp"
#include "cylfe/pipeline.hpp"

using namespace cylfe;

namespace {

cyl_colortable table2()
{
    cyl_colortable t;
    cyl_colortable_init(&t);
    cyl_colortable_set_class(&t, 0, "orange", 255, 128, 0);
    cyl_colortable_set_class(&t, 1, "green", 0, 255, 0);
    EXPECT_EQ(cyl_colortable_add_box(&t, 0, 0, 255, 50, 100, 150, 200), CYL_OK);   // U low, V high
    EXPECT_EQ(cyl_colortable_add_box(&t, 1, 0, 255, 50, 100, 50, 100), CYL_OK);    // U, V low
    return t;
}

// Load text as a detector config; the error message with the path replaced by FILE, or "".
std::string load(const std::string &text, DetectorConfig &c)
{
    return cfgtest::load_error(text, table2(), c);
}

} // namespace

TEST(BlobRulesConfig, ReadWrittenBackAndChecked)
{
    DetectorConfig c;
    EXPECT_EQ(c.split.waist_ratio[0], 0.0);   // off unless a config sets it
    ASSERT_EQ(load("classes:\n  orange:\n    split_waist: 0.45\n", c), "");
    EXPECT_DOUBLE_EQ(c.split.waist_ratio[0], 0.45);
    EXPECT_EQ(c.split.waist_ratio[1], 0.0);
    const cyl_colortable t = table2();
    const std::string y = detector_config_yaml(c, t, "test");
    EXPECT_NE(y.find("  orange:\n    split_waist: 0.45\n"), std::string::npos) << y;
    DetectorConfig back;
    ASSERT_EQ(load(y, back), "");
    EXPECT_DOUBLE_EQ(back.split.waist_ratio[0], 0.45);
    DetectorConfig bad;
    const std::string range = load("classes:\n  green:\n    split_waist: 1.5\n", bad);
    EXPECT_EQ(range.rfind("FILE:3: classes.green.split_waist", 0), 0u) << range;
    EXPECT_EQ(load("classes:\n  green:\n    split_wiast: 0.5\n", bad).rfind("FILE:3: classes.green: unknown key 'split_wiast'", 0),
              0u);
    // the axes: rows by default (not written), both or columns read and written back, others refused
    EXPECT_EQ(c.split.axes, (unsigned)CYL_SPLIT_ROWS);
    EXPECT_EQ(y.find("split_axes"), std::string::npos) << y;
    DetectorConfig both;
    ASSERT_EQ(load("split_axes: both\nclasses:\n  orange:\n    split_waist: 0.5\n", both), "");
    EXPECT_EQ(both.split.axes, (unsigned)(CYL_SPLIT_ROWS | CYL_SPLIT_COLUMNS));
    EXPECT_NE(detector_config_yaml(both, t, "").find("split_axes: both\n"), std::string::npos);
    DetectorConfig cols;
    ASSERT_EQ(load("split_axes: columns\n", cols), "");
    EXPECT_EQ(cols.split.axes, (unsigned)CYL_SPLIT_COLUMNS);
    EXPECT_EQ(load("roi: [0, 0, 10, 10]\nsplit_axes: diagonal\n", bad),
              "FILE:2: split_axes: 'diagonal' is not rows, columns or both");
}

TEST(BlobRulesConfig, DetectorCutsStackedCones)
{
    const uint32_t W = 320, H = 240;
    std::vector<uint8_t> buf(3 * W * H, 128);
    // far cone: rows 60..89, 6 -> 30 px wide; near cone: rows 90..169, 8 -> 64 px wide, on x = 160
    auto taper = [&](int ytop, int rows, int w_top, int w_bottom) {
        for (int j = 0; j < rows; j++) {
            const int w = w_top + (int)std::lround((double)(w_bottom - w_top) * j / (rows - 1));
            for (int x = 160 - w / 2; x < 160 - w / 2 + w; x++) {
                buf[W * H + (size_t)(ytop + j) * W + x] = 75;
                buf[2 * W * H + (size_t)(ytop + j) * W + x] = 175;
            }
        }
    };
    taper(60, 30, 6, 30);
    taper(90, 80, 8, 64);
    cyl_image img;
    ASSERT_EQ(cyl_image_wrap(&img, CYL_FMT_YUV444P, W, H, buf.data(), W), CYL_OK);
    cyl_camera cam;
    cyl_camera_init(&cam);
    cam.width = W; cam.height = H;
    cam.fx_px = cam.fy_px = 300; cam.cx_px = 160; cam.cy_px = 120;
    const cyl_colortable t = table2();
    for (const double ratio : {0.0, 0.5}) {
        DetectorConfig c;
        c.split.waist_ratio[0] = ratio;
        Detector det(t, cam, c);
        const std::vector<cyl_observation> &obs = det.process(img);
        if (ratio == 0.0) {
            ASSERT_EQ(obs.size(), 1u);
            EXPECT_EQ(det.boxes()[0], (std::array<uint16_t, 4>{128, 60, 191, 169}));
            continue;
        }
        // the near cone's tip row (8 px against 30 above and 64 below, a share of 0.27) is the cut
        ASSERT_EQ(obs.size(), 2u);
        ASSERT_EQ(det.boxes().size(), 2u);
        EXPECT_EQ(det.boxes()[0], (std::array<uint16_t, 4>{128, 90, 191, 169}));   // the near cone
        EXPECT_EQ(det.boxes()[1], (std::array<uint16_t, 4>{145, 60, 174, 89}));    // the far one
        EXPECT_TRUE(det.segmentation().blobs[0].flags & CYL_BLOB_SPLIT);
        EXPECT_GT(obs[0].centroid_v_px, 90.0);
        EXPECT_LT(obs[1].centroid_v_px, 90.0);
    }
}

TEST(BlobRulesConfig, WeakAloneReadWrittenBackAndChecked)
{
    DetectorConfig c;
    EXPECT_EQ(c.segment.cls[1].weak_alone_min_area, 0u);   // off unless a config sets it
    ASSERT_EQ(load("classes:\n  green:\n    weak_alone_min_area_px: 1500\n", c), "");
    EXPECT_EQ(c.segment.cls[1].weak_alone_min_area, 1500u);
    EXPECT_EQ(c.segment.cls[0].weak_alone_min_area, 0u);
    const cyl_colortable t = table2();
    const std::string y = detector_config_yaml(c, t, "test");
    EXPECT_NE(y.find("  green:\n    weak_alone_min_area_px: 1500\n"), std::string::npos) << y;
    DetectorConfig bad;
    EXPECT_EQ(load("classes:\n  green:\n    weak_alone_min_area_px: 2.5\n", bad).rfind("FILE:3: classes.green.weak_alone_min_area_px", 0), 0u);
}
