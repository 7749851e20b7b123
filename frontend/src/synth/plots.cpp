// SPDX-License-Identifier: BSD-3-Clause
// PNG plots of the experiments, drawn with OpenCV (no Python needed).
#include "cylfe/synth_experiments.hpp"
#include "cylfe/error.hpp"

#include "cylfe/media.hpp"
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace cylfe {
namespace synth {

namespace {

struct Axes {
    cv::Mat img;
    cv::Rect area;
    double x0, x1, y0, y1;
    bool logx = false, logy = false;
    Axes(int w, int h, double x0_, double x1_, double y0_, double y1_, bool lx, bool ly)
        : img(h, w, CV_8UC3, cv::Scalar(255, 255, 255)), area(100, 50, w - 130, h - 120), x0(x0_), x1(x1_), y0(y0_),
          y1(y1_), logx(lx), logy(ly) {}
    double tx(double x) const { return logx ? std::log10(std::max(x, 1e-300)) : x; }
    double ty(double y) const { return logy ? std::log10(std::max(y, 1e-300)) : y; }
    cv::Point px(double x, double y) const
    {
        double fx = (tx(x) - tx(x0)) / (tx(x1) - tx(x0)), fy = (ty(y) - ty(y0)) / (ty(y1) - ty(y0));
        return cv::Point((int)std::lround(area.x + fx * area.width), (int)std::lround(area.y + area.height - fy * area.height));
    }
    void text(const std::string &s, cv::Point p, double scale = 0.45, const cv::Scalar &c = cv::Scalar(0, 0, 0))
    {
        cv::putText(img, s, p, cv::FONT_HERSHEY_SIMPLEX, scale, c, 1, cv::LINE_AA);
    }
    void frame(const std::string &title, const std::string &xl, const std::string &yl,
               const std::vector<double> &xt, const std::vector<double> &yt)
    {
        cv::rectangle(img, area, cv::Scalar(0, 0, 0), 1);
        for (double x : xt) {
            cv::Point p = px(x, y0);
            cv::line(img, p, p + cv::Point(0, 5), cv::Scalar(0, 0, 0), 1);
            char b[32];
            snprintf(b, sizeof b, "%g", x);
            text(b, p + cv::Point(-12, 20), 0.4);
        }
        for (double y : yt) {
            cv::Point p = px(x0, y);
            cv::line(img, p, p - cv::Point(5, 0), cv::Scalar(0, 0, 0), 1);
            char b[32];
            snprintf(b, sizeof b, "%g", y);
            text(b, p + cv::Point(-62, 4), 0.4);
        }
        text(title, cv::Point(area.x, 30), 0.6);
        text(xl, cv::Point(area.x + area.width / 2 - 100, img.rows - 25), 0.5);
        // vertical y label: draw rotated
        cv::Mat lab(30, area.height, CV_8UC3, cv::Scalar(255, 255, 255));
        cv::putText(lab, yl, cv::Point(10, 20), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
        cv::Mat rot;
        cv::rotate(lab, rot, cv::ROTATE_90_COUNTERCLOCKWISE);
        rot.copyTo(img(cv::Rect(5, area.y, rot.cols, rot.rows)));
    }
    void save(const std::string &path)
    {
        if (!media::imwrite(path, img)) throw Error(path + ": cannot write plot");
    }
};

} // namespace

void plot_normalised_hist(const std::string &path, const std::string &title, const std::vector<double> &z)
{
    const double lo = -4, hi = 4, bw = 0.25;
    const int nb = (int)((hi - lo) / bw);
    std::vector<double> cnt(nb, 0);
    size_t outside = 0;
    for (double v : z) {
        int b = (int)std::floor((v - lo) / bw);
        if (b < 0 || b >= nb) { outside++; continue; }
        cnt[b] += 1;
    }
    double ymax = 0.45;
    for (double &c : cnt) { c = z.empty() ? 0 : c / (z.size() * bw); ymax = std::max(ymax, c * 1.1); }
    Axes ax(720, 480, lo, hi, 0, ymax, false, false);
    for (int b = 0; b < nb; b++) {
        cv::Point p0 = ax.px(lo + b * bw, 0), p1 = ax.px(lo + (b + 1) * bw, cnt[b]);
        cv::rectangle(ax.img, cv::Rect(p0.x, p1.y, p1.x - p0.x, p0.y - p1.y), cv::Scalar(200, 160, 120), cv::FILLED);
        cv::rectangle(ax.img, cv::Rect(p0.x, p1.y, p1.x - p0.x, p0.y - p1.y), cv::Scalar(120, 80, 40), 1);
    }
    std::vector<cv::Point> curve;
    for (int i = 0; i <= 400; i++) {
        double x = lo + (hi - lo) * i / 400.0;
        curve.push_back(ax.px(x, std::exp(-0.5 * x * x) / std::sqrt(2 * 3.14159265358979323846)));
    }
    cv::polylines(ax.img, curve, false, cv::Scalar(0, 0, 220), 2, cv::LINE_AA);
    std::vector<double> yt;
    for (int i = 0; i * 0.1 <= ymax + 1e-9; i++) yt.push_back(i * 0.1);
    ax.frame(title, "normalised error  (error / sigma)", "density", {-4, -3, -2, -1, 0, 1, 2, 3, 4}, yt);
    char b[96];
    snprintf(b, sizeof b, "n = %zu (%zu outside +-4)", z.size(), outside);
    ax.text(b, cv::Point(ax.area.x + 10, ax.area.y + 20));
    ax.text("bars: measured", cv::Point(ax.area.x + ax.area.width - 170, ax.area.y + 20), 0.45, cv::Scalar(120, 80, 40));
    ax.text("red: N(0,1)", cv::Point(ax.area.x + ax.area.width - 170, ax.area.y + 40), 0.45, cv::Scalar(0, 0, 220));
    ax.save(path);
}

void plot_variance(const std::string &path, const std::vector<VarianceRow> &rows)
{
    double lo = 1e30, hi = 0;
    for (const VarianceRow &r : rows) {
        for (double v : {r.actual_x, r.actual_y})
            if (v > 0) { lo = std::min(lo, v); hi = std::max(hi, v); }
        for (int e = 0; e < kEstimators; e++)
            for (double v : {r.est_x[e], r.est_y[e]})
                if (v > 0) { lo = std::min(lo, v); hi = std::max(hi, v); }
    }
    if (hi <= 0) { lo = 1e-4; hi = 1; }
    lo = std::pow(10, std::floor(std::log10(lo))); hi = std::pow(10, std::ceil(std::log10(hi)));
    Axes ax(720, 560, lo, hi, lo, hi, true, true);
    // y = x and the factor-2 band
    for (double f : {0.5, 1.0, 2.0}) {
        cv::Point a = ax.px(lo, std::max(lo, lo * f)), b = ax.px(std::min(hi, hi / f), std::min(hi, hi * f));
        if (f < 1) { a = ax.px(lo / f, lo); b = ax.px(hi, hi * f); }
        cv::line(ax.img, a, b, f == 1.0 ? cv::Scalar(0, 0, 0) : cv::Scalar(150, 150, 150), 1, cv::LINE_AA);
    }
    const cv::Scalar col[kEstimators] = {cv::Scalar(0, 140, 255), cv::Scalar(200, 60, 0), cv::Scalar(0, 160, 0),
                                         cv::Scalar(180, 0, 180)};
    for (const VarianceRow &r : rows)
        for (int e = 0; e < kEstimators; e++) {
            if (r.actual_x > 0 && r.est_x[e] > 0) cv::circle(ax.img, ax.px(r.actual_x, r.est_x[e]), 5, col[e], 2, cv::LINE_AA);
            if (r.actual_y > 0 && r.est_y[e] > 0) {
                cv::Point p = ax.px(r.actual_y, r.est_y[e]);
                cv::rectangle(ax.img, cv::Rect(p.x - 4, p.y - 4, 9, 9), col[e], 2, cv::LINE_AA);
            }
        }
    std::vector<double> t;
    for (int i = 0; lo * std::pow(10.0, i) <= hi * 1.0001; i++) t.push_back(lo * std::pow(10.0, i));
    ax.frame("centroid variance: estimators vs measured", "measured variance (px^2)",
             "estimator mean (px^2)", t, t);
    const char *nm[kEstimators] = {"uniform (eq. 4)", "column/row (eq. 5)", "local 3x3 (eq. 6)",
                                   "image (frame noise + table boundary)"};
    for (int e = 0; e < kEstimators; e++) ax.text(nm[e], cv::Point(ax.area.x + 10, ax.area.y + 20 + 20 * e), 0.45, col[e]);
    ax.text("circles: x (horizontal), squares: y (vertical)", cv::Point(ax.area.x + 10, ax.area.y + 100));
    ax.text("lines: y = x/2, x, 2x", cv::Point(ax.area.x + 10, ax.area.y + 120), 0.45, cv::Scalar(100, 100, 100));
    ax.save(path);
}

} // namespace synth
} // namespace cylfe
