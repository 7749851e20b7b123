// SPDX-License-Identifier: BSD-3-Clause
#include "cylfe/overlay.hpp"
#include "cylfe/error.hpp"

#include <cmath>
#include <cstdio>

#include <opencv2/imgproc.hpp>

extern "C" {
#include "cyl/rangebearing.h"
}

namespace cylfe {

cv::Mat to_bgr(const cyl_image &img)
{
    int w = (int)img.width, h = (int)img.height;
    cv::Mat out;
    switch (img.format) {
    case CYL_FMT_YUYV:
    case CYL_FMT_UYVY: {
        cv::Mat src(h, w & ~1, CV_8UC2, const_cast<uint8_t *>(img.plane[0]), img.stride[0]);
        cv::cvtColor(src, out, img.format == CYL_FMT_YUYV ? cv::COLOR_YUV2BGR_YUYV : cv::COLOR_YUV2BGR_UYVY);
        return out;
    }
    default: {
        // Planar formats: gather a YUV444 image through libcyl's own pixel access, then convert.
        cv::Mat yuv(h, w, CV_8UC3);
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                uint8_t Y, U, V;
                cyl_image_pixel(&img, (uint32_t)x, (uint32_t)y, &Y, &U, &V);
                yuv.at<cv::Vec3b>(y, x) = cv::Vec3b(Y, U, V);
            }
        cv::cvtColor(yuv, out, cv::COLOR_YUV2BGR);
        return out;
    }
    }
}

OverlayKind overlay_kind(const cyl_observation &o, const OverlayOptions &opt)
{
    if (o.flags & (CYL_OBS_NO_RANGE | CYL_OBS_INVALID)) return OverlayKind::LowConfidence;
    return o.confidence >= opt.min_confidence ? OverlayKind::Landmark : OverlayKind::LowConfidence;
}

std::vector<cv::Point> overlay_ellipse(const cyl_camera &cam, const cyl_observation &o, const OverlayOptions &opt,
                                       cv::Size image)
{
    std::vector<cv::Point> poly;
    if (o.flags & (CYL_OBS_NO_RANGE | CYL_OBS_INVALID) || !(o.range_m > 0)) return poly;
    const double k95 = std::sqrt(5.991);  // chi-square, 2 dof, 95%
    double a = o.cov_xy[0][0], c = o.cov_xy[1][1], bb = o.cov_xy[0][1];
    if (!std::isfinite(a) || !std::isfinite(c) || !std::isfinite(bb)) return poly;
    double tr = 0.5 * (a + c), d = std::sqrt(0.25 * (a - c) * (a - c) + bb * bb);
    double l1 = tr + d, l2 = std::max(tr - d, 0.0), ang = 0.5 * std::atan2(2 * bb, a - c);
    if (k95 * std::sqrt(l1) > opt.max_ellipse_rel_range * o.range_m) return poly;
    for (int k = 0; k < 48; k++) {
        double th = 2 * M_PI * k / 48, ex = k95 * std::sqrt(l1) * std::cos(th), ey = k95 * std::sqrt(l2) * std::sin(th);
        double x = o.x_m + ex * std::cos(ang) - ey * std::sin(ang), y = o.y_m + ex * std::sin(ang) + ey * std::cos(ang);
        double u, v;
        if (cyl_rb_project(&cam, x, y, &u, &v) != CYL_OK || !std::isfinite(u) || !std::isfinite(v) ||
            u < -image.width || u > 2.0 * image.width || v < -image.height || v > 2.0 * image.height)
            return {};
        poly.emplace_back((int)std::lround(u), (int)std::lround(v));
    }
    return poly;
}

bool place_label(std::vector<cv::Rect> &taken, cv::Point want, cv::Size size, cv::Size image, cv::Rect *where)
{
    cv::Rect r(std::max(0, std::min(want.x, image.width - size.width)), std::max(0, want.y), size.width, size.height);
    for (int tries = 0; tries < 8 && r.y + r.height <= image.height; tries++) {
        bool clash = false;
        for (const cv::Rect &t : taken)
            if ((r & t).area() > 0) { clash = true; r.y = t.y + t.height + 1; break; }
        if (!clash) {
            taken.push_back(r);
            if (where) *where = r;
            return true;
        }
    }
    return false;
}

namespace {

void tint_blob(cv::Mat &bgr, const cyl_segmentation &seg, const cyl_blob &b, cv::Vec3b col)
{
    for (uint32_t r = b.first_run; r != CYL_NONE; r = seg.runs[r].next) {
        const cyl_run &run = seg.runs[r];
        for (uint32_t k = 0; k < run.width; k++) {
            int x = run.x + (int)(k * seg.x_step);
            if (x < bgr.cols && run.y < bgr.rows) {
                cv::Vec3b &p = bgr.at<cv::Vec3b>(run.y, x);
                for (int c = 0; c < 3; c++) p[c] = (uint8_t)((p[c] + col[c]) / 2);
            }
        }
    }
}

void label(cv::Mat &bgr, std::vector<cv::Rect> &taken, const char *text, cv::Point want, double scale)
{
    int base = 0;
    cv::Size ts = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &base);
    cv::Size box(ts.width + 4, ts.height + base + 4);
    cv::Rect r;
    if (!place_label(taken, cv::Point(want.x, want.y - box.height), box, bgr.size(), &r)) return;
    cv::Mat roi = bgr(r & cv::Rect(0, 0, bgr.cols, bgr.rows));
    roi = roi * 0.25;  // darken the background to a quarter: readable on any scene
    cv::putText(bgr, text, cv::Point(r.x + 2, r.y + 2 + ts.height), cv::FONT_HERSHEY_SIMPLEX, scale,
                cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
}

} // namespace

void draw_overlay(cv::Mat &bgr, const Detector &det, const std::vector<cyl_observation> &obs, const OverlayOptions &opt)
{
    const cyl_segmentation &seg = det.segmentation();
    const cyl_colortable &t = det.table();
    std::vector<int> obs_of_blob(seg.n_blobs, -1);
    // the detector's own observations carry their blobs (several for a grouped landmark)
    const bool own = &obs == &det.last_observations() && det.members().size() == obs.size();
    for (size_t i = 0; i < obs.size(); i++) {
        if (obs[i].blob < seg.n_blobs) obs_of_blob[obs[i].blob] = (int)i;
        if (own)
            for (uint32_t m : det.members()[i])
                if (m < seg.n_blobs) obs_of_blob[m] = (int)i;
    }
    const cv::Scalar grey(150, 150, 150);
    // Rejected blobs first, so that landmarks are drawn over them.
    for (uint32_t i = 0; i < seg.n_blobs; i++) {
        if (obs_of_blob[i] >= 0) continue;
        const cyl_blob &b = seg.blobs[i];
        tint_blob(bgr, seg, b, cv::Vec3b(150, 150, 150));
        cv::rectangle(bgr, cv::Point(b.x0, b.y0), cv::Point(b.x1, b.y1), grey, 1);
    }
    std::vector<cv::Rect> taken;
    if (opt.key) {
        // the key: three sample boxes and their names, in the top-left corner
        const char *names[3] = {"landmark", "low confidence", "rejected blob"};
        int y = 4;
        for (int k = 0; k < 3; k++) {
            cv::Rect r(0, y - 2, 130, 16);
            taken.push_back(r);
            cv::Mat roi = bgr(r & cv::Rect(0, 0, bgr.cols, bgr.rows));
            roi = roi * 0.25;
            cv::rectangle(bgr, cv::Rect(4, y + 1, 14, 10), k == 2 ? grey : cv::Scalar(0, 200, 255), k == 0 ? 2 : 1);
            cv::putText(bgr, names[k], cv::Point(24, y + 10), cv::FONT_HERSHEY_SIMPLEX, 0.35, cv::Scalar(255, 255, 255),
                        1, cv::LINE_AA);
            y += 16;
        }
    }
    // Low-confidence observations, then landmarks (on top, with labels and ellipses).
    for (int pass = 0; pass < 2; pass++)
        for (size_t i = 0; i < obs.size(); i++) {
            const cyl_observation &o = obs[i];
            if (o.blob >= seg.n_blobs) continue;
            const OverlayKind kind = overlay_kind(o, opt);
            if ((pass == 0) != (kind == OverlayKind::LowConfidence)) continue;
            const cyl_blob &b = seg.blobs[o.blob];
            cv::Vec3b col(t.rgb[o.cls][2], t.rgb[o.cls][1], t.rgb[o.cls][0]);
            const cv::Scalar colour(col[0], col[1], col[2]);
            // a grouped landmark: every band's blob in its own class colour, the union box
            cv::Point p0(b.x0, b.y0), p1(b.x1, b.y1);
            if (own && o.model != CYL_NO_MODEL) {
                for (uint32_t m : det.members()[i]) {
                    if (m >= seg.n_blobs) continue;
                    const uint8_t c = seg.blobs[m].cls;
                    tint_blob(bgr, seg, seg.blobs[m], cv::Vec3b(t.rgb[c][2], t.rgb[c][1], t.rgb[c][0]));
                }
                const std::array<uint16_t, 4> &bx = det.boxes()[i];
                p0 = cv::Point(bx[0], bx[1]);
                p1 = cv::Point(bx[2], bx[3]);
            } else {
                tint_blob(bgr, seg, b, col);
            }
            if (kind == OverlayKind::LowConfidence) {
                cv::rectangle(bgr, p0, p1, colour, 1);
                continue;
            }
            cv::rectangle(bgr, p0, p1, colour, 2);
            cv::circle(bgr, cv::Point((int)std::lround(o.u_px), (int)std::lround(o.v_px)), 2, cv::Scalar(255, 255, 255), -1);
            char text[128];
            std::string name = t.name[o.cls];
            const std::vector<std::string> &models = det.config().model_names;
            if (o.model != CYL_NO_MODEL) name = o.model < models.size() ? models[o.model] : std::to_string(o.model);
            if (o.landmark_id >= 0) name += " #" + std::to_string(o.landmark_id);
            std::snprintf(text, sizeof text, "%s %.2fm %.1fdeg c%.2f", name.c_str(), o.range_m,
                          o.bearing_rad * 180 / M_PI, o.confidence);
            label(bgr, taken, text, cv::Point(p0.x, p0.y - 1), 0.4);
            std::vector<cv::Point> poly = overlay_ellipse(det.camera(), o, opt, bgr.size());
            if (poly.size() > 2) cv::polylines(bgr, poly, true, cv::Scalar(0, 255, 255), 1, cv::LINE_AA);
        }
}

} // namespace cylfe
