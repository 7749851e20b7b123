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

void draw_overlay(cv::Mat &bgr, const Detector &det, const std::vector<cyl_observation> &obs)
{
    const cyl_segmentation &seg = det.segmentation();
    const cyl_colortable &t = det.table();
    // Classified pixels of every blob, tinted with the class's display colour.
    for (uint32_t i = 0; i < seg.n_blobs; i++) {
        const cyl_blob &b = seg.blobs[i];
        cv::Vec3b col(t.rgb[b.cls][2], t.rgb[b.cls][1], t.rgb[b.cls][0]);
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
        cv::rectangle(bgr, cv::Point(b.x0, b.y0), cv::Point(b.x1, b.y1), cv::Scalar(col[0], col[1], col[2]), 1);
    }
    // Observations: text and the 95% ellipse of the landmark's (x, y), projected into the image.
    const double k95 = std::sqrt(5.991);  // chi-square, 2 dof, 95%
    for (const cyl_observation &o : obs) {
        const cyl_blob &b = seg.blobs[o.blob];
        char text[96];
        if (o.flags & CYL_OBS_NO_RANGE)
            std::snprintf(text, sizeof text, "%s no range %.1fdeg", t.name[o.cls], o.bearing_rad * 180 / M_PI);
        else
            std::snprintf(text, sizeof text, "%s %.2fm %.1fdeg c%.2f", t.name[o.cls], o.range_m,
                          o.bearing_rad * 180 / M_PI, o.confidence);
        cv::putText(bgr, text, cv::Point(b.x0, b.y0 > 12 ? b.y0 - 4 : b.y1 + 12), cv::FONT_HERSHEY_SIMPLEX, 0.4,
                    cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
        cv::circle(bgr, cv::Point2d(o.u_px, o.v_px), 2, cv::Scalar(255, 255, 255), -1);
        if (o.flags & (CYL_OBS_NO_RANGE | CYL_OBS_INVALID)) continue;
        double a = o.cov_xy[0][0], c = o.cov_xy[1][1], bb = o.cov_xy[0][1];
        double tr = 0.5 * (a + c), d = std::sqrt(0.25 * (a - c) * (a - c) + bb * bb);
        double l1 = tr + d, l2 = std::max(tr - d, 0.0), ang = 0.5 * std::atan2(2 * bb, a - c);
        std::vector<cv::Point> poly;
        for (int k = 0; k <= 48; k++) {
            double th = 2 * M_PI * k / 48, ex = k95 * std::sqrt(l1) * std::cos(th), ey = k95 * std::sqrt(l2) * std::sin(th);
            double x = o.x_m + ex * std::cos(ang) - ey * std::sin(ang), y = o.y_m + ex * std::sin(ang) + ey * std::cos(ang);
            double u, v;
            if (cyl_rb_project(&det.camera(), x, y, &u, &v) == CYL_OK) poly.emplace_back((int)std::lround(u), (int)std::lround(v));
        }
        if (poly.size() > 2) cv::polylines(bgr, poly, true, cv::Scalar(0, 255, 255), 1, cv::LINE_AA);
    }
}

} // namespace cylfe
