// SPDX-License-Identifier: BSD-3-Clause
// The overlay: landmarks, low-confidence observations and rejected blobs drawn differently,
// labels on a dark background that do not overlap, ellipses only where they mean something.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "cylfe/calibration.hpp"
#include "cylfe/overlay.hpp"
#include "cylfe/pipeline.hpp"

extern "C" {
#include "cyl/image.h"
#include "cyl/rangebearing.h"
}

using namespace cylfe;

namespace {

cyl_camera synthetic_camera()
{
    return load_camera_calibration("calib_data/synthetic_camera.yaml").cam;
}

// A grey 640x480 YUYV frame with orange rectangles (class 0 of the table below).
struct Frame {
    std::vector<uint8_t> bytes = std::vector<uint8_t>(640 * 480 * 2);
    cyl_image img{};
    Frame()
    {
        for (size_t i = 0; i < bytes.size(); i += 2) { bytes[i] = 100; bytes[i + 1] = 128; }
        cyl_image_wrap(&img, CYL_FMT_YUYV, 640, 480, bytes.data(), 0);
    }
    void paint(int x0, int y0, int w, int h)
    {
        for (int y = y0; y < y0 + h; y++)
            for (int x = x0; x < x0 + w; x++) {
                uint8_t *p = &bytes[(size_t)(y * 640 + x) * 2];
                p[0] = 150;
                p[1] = (x % 2 == 0) ? 90 : 200;  // U on even pixels, V on odd ones
            }
    }
};

cyl_colortable orange_table()
{
    cyl_colortable t;
    cyl_colortable_init(&t);
    cyl_colortable_set_class(&t, 0, "orange", 255, 128, 0);
    cyl_colortable_add_box(&t, 0, 120, 200, 70, 110, 180, 220);
    return t;
}

cyl_observation obs_at(double x, double y, double var_m2)
{
    cyl_observation o{};
    o.x_m = x;
    o.y_m = y;
    o.range_m = std::hypot(x, y);
    o.cov_xy[0][0] = o.cov_xy[1][1] = var_m2;
    o.confidence = 0.9;
    return o;
}

} // namespace

TEST(Overlay, KindFollowsConfidenceAndRange)
{
    OverlayOptions opt;
    cyl_observation o = obs_at(2, 0, 1e-4);
    EXPECT_EQ(overlay_kind(o, opt), OverlayKind::Landmark);
    o.confidence = 0.49;
    EXPECT_EQ(overlay_kind(o, opt), OverlayKind::LowConfidence);
    o.confidence = 1.0;
    o.flags = CYL_OBS_NO_RANGE;
    EXPECT_EQ(overlay_kind(o, opt), OverlayKind::LowConfidence);
}

TEST(Overlay, EllipseOnlyWhereItMeansSomething)
{
    const cyl_camera cam = synthetic_camera();
    OverlayOptions opt;
    const cv::Size im(640, 480);
    // a landmark 2 m ahead with 1 cm sigma: a small closed polygon around its image
    cyl_observation o = obs_at(2, 0, 1e-4);
    std::vector<cv::Point> p = overlay_ellipse(cam, o, opt, im);
    ASSERT_EQ(p.size(), 48u);
    double u, v;
    ASSERT_EQ(cyl_rb_project(&cam, 2, 0, &u, &v), CYL_OK);
    double far = 0;
    for (const cv::Point &q : p) far = std::max(far, std::hypot(q.x - u, q.y - v));
    EXPECT_GT(far, 0.5);
    EXPECT_LT(far, 40.0);
    // a 36 m "landmark" with a 20 m sigma: no ellipse (half-axis 49 m > 0.5 x 36 m)
    EXPECT_TRUE(overlay_ellipse(cam, obs_at(36, 0, 400), opt, im).empty());
    // just inside and just outside the relative limit: 2.448 sigma vs 0.5 x range
    const double s_in = 0.49 * 4 / std::sqrt(5.991), s_out = 0.51 * 4 / std::sqrt(5.991);
    EXPECT_FALSE(overlay_ellipse(cam, obs_at(4, 0, s_in * s_in), opt, im).empty());
    EXPECT_TRUE(overlay_ellipse(cam, obs_at(4, 0, s_out * s_out), opt, im).empty());
    // behind the camera, without a range, or with a broken covariance: none
    EXPECT_TRUE(overlay_ellipse(cam, obs_at(-2, 0, 1e-4), opt, im).empty());
    o.flags = CYL_OBS_NO_RANGE;
    EXPECT_TRUE(overlay_ellipse(cam, o, opt, im).empty());
    o = obs_at(2, 0, NAN);
    EXPECT_TRUE(overlay_ellipse(cam, o, opt, im).empty());
}

TEST(Overlay, LabelsDoNotOverlap)
{
    std::vector<cv::Rect> taken;
    const cv::Size im(640, 480), box(100, 14);
    cv::Rect a, b, c;
    ASSERT_TRUE(place_label(taken, cv::Point(50, 40), box, im, &a));
    ASSERT_TRUE(place_label(taken, cv::Point(80, 45), box, im, &b));
    EXPECT_EQ((a & b).area(), 0);
    EXPECT_EQ(b.y, a.y + a.height + 1);
    // kept inside the frame at the right and top edges
    ASSERT_TRUE(place_label(taken, cv::Point(600, -10), box, im, &c));
    EXPECT_EQ(c.x + c.width, 640);
    EXPECT_EQ(c.y, 0);
    // no room left at the bottom: refused, nothing added
    std::vector<cv::Rect> full{cv::Rect(0, 460, 640, 20)};
    EXPECT_FALSE(place_label(full, cv::Point(10, 462), box, im, nullptr));
    EXPECT_EQ(full.size(), 1u);
}

TEST(Overlay, LandmarksLowConfidenceAndRejectedBlobsDrawnApart)
{
    Frame f;
    f.paint(300, 200, 40, 120); // the landmark
    f.paint(100, 300, 4, 4);    // a speck the detector drops (min_area)
    DetectorConfig cfg;
    cfg.observe.min_area = 50;
    cyl_colortable t = orange_table();
    Detector det(t, synthetic_camera(), cfg);
    std::vector<cyl_observation> obs = det.process(f.img);
    const cyl_segmentation &seg = det.segmentation();
    ASSERT_EQ(seg.n_blobs, 2u);
    ASSERT_EQ(obs.size(), 1u);
    const cyl_blob &big = seg.blobs[obs[0].blob], &speck = seg.blobs[1 - obs[0].blob];
    EXPECT_EQ(big.x0, 300);
    EXPECT_EQ(speck.x0, 100);

    for (double conf : {0.9, 0.1}) {
        obs[0].confidence = conf;
        obs[0].flags &= ~(uint32_t)(CYL_OBS_NO_RANGE | CYL_OBS_INVALID);
        cv::Mat bgr = to_bgr(f.img), before = bgr.clone();
        draw_overlay(bgr, det, obs);
        // the rejected speck: a grey box
        EXPECT_EQ(bgr.at<cv::Vec3b>(speck.y0 + 1, speck.x0), cv::Vec3b(150, 150, 150)) << conf;
        // the observation's box in the class colour (BGR), 2 px for a landmark, 1 px otherwise
        const int ym = (big.y0 + big.y1) / 2;
        EXPECT_EQ(bgr.at<cv::Vec3b>(ym, big.x0), cv::Vec3b(0, 128, 255)) << conf;
        const bool thick = bgr.at<cv::Vec3b>(ym, big.x0 - 1) == cv::Vec3b(0, 128, 255) ||
                           bgr.at<cv::Vec3b>(ym, big.x0 + 1) == cv::Vec3b(0, 128, 255);
        EXPECT_EQ(thick, conf > 0.5) << conf;
        // a landmark's label sits above its box on a darkened background; low confidence: no label
        const cv::Vec3b lab = bgr.at<cv::Vec3b>(big.y0 - 6, big.x0 + 1), orig = before.at<cv::Vec3b>(big.y0 - 6, big.x0 + 1);
        if (conf > 0.5)
            EXPECT_LT(lab[1], orig[1] / 2 + 1) << "label background not darkened";
        else
            EXPECT_EQ(lab, orig) << "a low-confidence observation got a label";
        // the key in the top-left corner, darkened
        EXPECT_LT(bgr.at<cv::Vec3b>(30, 128)[1], before.at<cv::Vec3b>(30, 128)[1] / 2 + 1);
    }
}
