// SPDX-License-Identifier: BSD-3-Clause
// cylfe::calib -- colour-table training helpers (calib.hpp).
#include "cylfe/calib.hpp"

#include <opencv2/imgproc.hpp>

#include "cylfe/error.hpp"
#include "cylfe/overlay.hpp"

namespace cylfe {
namespace calib {

namespace {
std::string rect_str(const cv::Rect &r)
{
    return std::to_string(r.x) + "," + std::to_string(r.y) + "," + std::to_string(r.width) + "," +
           std::to_string(r.height);
}

cyl_roi to_roi(const Frame &f, const cv::Rect &r)
{
    if (r.width < 1 || r.height < 1 || r.x < 0 || r.y < 0 || r.x + r.width > (int)f.img.width ||
        r.y + r.height > (int)f.img.height)
        throw Error(f.label + ": rectangle " + rect_str(r) + " (x,y,w,h) is empty or not inside the " +
                    std::to_string(f.img.width) + "x" + std::to_string(f.img.height) + " image");
    cyl_roi roi;
    roi.x = (uint32_t)r.x;
    roi.y = (uint32_t)r.y;
    roi.width = (uint32_t)r.width;
    roi.height = (uint32_t)r.height;
    return roi;
}
} // namespace

void train_rect(cyl_colortable &t, unsigned cls, const Frame &frame, const cv::Rect &rect,
                const cyl_train_params &params, uint8_t box[6])
{
    cyl_roi roi = to_roi(frame, rect);
    std::vector<uint32_t> work((cyl_train_workspace_size() + 3) / 4);
    cyl_status s = cyl_colortable_train(&t, cls, &frame.img, &roi, &params, work.data(), work.size() * 4, box);
    if (s == CYL_ERR_EMPTY)
        throw Error(frame.label + ": rectangle " + rect_str(rect) +
                    ": no colour is common enough to train on (region too small or too varied; lower "
                    "--min-bin-count / --min-bin-fraction)");
    check(s, frame.label + ": training on rectangle " + rect_str(rect));
}

double class_coverage(const cyl_colortable &t, unsigned cls, const Frame &frame, const cv::Rect &rect)
{
    cyl_roi roi = to_roi(frame, rect);
    std::vector<uint8_t> out((size_t)rect.width * rect.height);
    check(cyl_classify(&t, &frame.img, &roi, 1, 1, out.data(), (size_t)rect.width), frame.label + ": classify");
    size_t n = 0;
    for (uint8_t c : out) n += c == cls;
    return (double)n / out.size();
}

cv::Mat classified_overlay(const cyl_colortable &t, const Frame &frame, double alpha)
{
    cv::Mat bgr = to_bgr(frame.img).clone();
    const int w = (int)frame.img.width, h = (int)frame.img.height;
    std::vector<uint8_t> cls((size_t)w * h);
    check(cyl_classify(&t, &frame.img, nullptr, 1, 1, cls.data(), (size_t)w), frame.label + ": classify");
    for (int y = 0; y < h; y++) {
        cv::Vec3b *row = bgr.ptr<cv::Vec3b>(y);
        for (int x = 0; x < w; x++) {
            unsigned c = cls[(size_t)y * w + x];
            if (c >= CYL_MAX_CLASSES) continue;
            const uint8_t *rgb = t.rgb[c];
            for (int k = 0; k < 3; k++)
                row[x][k] = cv::saturate_cast<uint8_t>((1 - alpha) * row[x][k] + alpha * rgb[2 - k]);
        }
    }
    return bgr;
}

} // namespace calib
} // namespace cylfe
