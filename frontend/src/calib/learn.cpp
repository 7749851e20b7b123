// SPDX-License-Identifier: BSD-3-Clause
// cylfe::learn -- colour classes from labelled images, and scoring (learn.hpp).
#include "cylfe/learn.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <dirent.h>
#include <fstream>
#include <memory>
#include <sstream>
#include <sys/stat.h>

#include "cylfe/error.hpp"

#include "cylfe/media.hpp"
#include <opencv2/imgproc.hpp>

namespace cylfe {
namespace learn {

namespace {

bool is_file(const std::string &p)
{
    struct stat st;
    return ::stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

bool is_dir(const std::string &p)
{
    struct stat st;
    return ::stat(p.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

std::string lower(std::string s)
{
    for (char &c : s) c = (char)std::tolower((unsigned char)c);
    return s;
}

std::string ext_of(const std::string &p)
{
    size_t slash = p.find_last_of('/'), dot = p.find_last_of('.');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
    return lower(p.substr(dot + 1));
}

bool is_image_ext(const std::string &e) { return e == "jpg" || e == "jpeg" || e == "png" || e == "bmp"; }

std::string num(double v, int prec = 4)
{
    char b[64];
    std::snprintf(b, sizeof b, "%.*g", prec, v);
    return b;
}

std::string json_str(const std::string &s)
{
    std::string o = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') { o += '\\'; o += c; }
        else if ((unsigned char)c < 0x20) { char b[8]; std::snprintf(b, sizeof b, "\\u%04x", c); o += b; }
        else o += c;
    }
    return o + "\"";
}

// Integer pixel range [lo, hi) covered by the continuous interval [a, b) (pixel centres inside).
void px_range(double a, double b, int n, int *lo, int *hi)
{
    *lo = std::max(0, (int)std::ceil(a - 0.5));
    *hi = std::min(n, (int)std::ceil(b - 0.5));
}

} // namespace

std::vector<Box> read_yolo(const std::string &path, int width, int height)
{
    std::ifstream f(path);
    if (!f) throw Error(path + ": cannot open label file: " + std::strerror(errno));
    std::vector<Box> out;
    std::string line;
    int ln = 0;
    while (std::getline(f, line)) {
        ln++;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.find_first_not_of(" \t") == std::string::npos) continue;
        std::istringstream is(line);
        std::string tok[6];
        int n = 0;
        while (n < 6 && is >> tok[n]) n++;
        const std::string where = path + ":" + std::to_string(ln) + ": ";
        if (n != 5) throw Error(where + "expected 5 fields '<class> <cx> <cy> <w> <h>', got " + std::to_string(n));
        double v[5];
        for (int k = 0; k < 5; k++) {
            char *end = nullptr;
            v[k] = std::strtod(tok[k].c_str(), &end);
            if (*end || !std::isfinite(v[k]))
                throw Error(where + "field " + std::to_string(k + 1) + " is not a number: '" + tok[k] + "'");
        }
        if (v[0] < 0 || v[0] != std::floor(v[0])) throw Error(where + "class id must be a whole number >= 0");
        const double tol = 1e-3;
        if (v[3] <= 0 || v[4] <= 0) throw Error(where + "box width and height must be > 0");
        if (v[1] - v[3] / 2 < -tol || v[1] + v[3] / 2 > 1 + tol || v[2] - v[4] / 2 < -tol || v[2] + v[4] / 2 > 1 + tol)
            throw Error(where + "box reaches outside the image (normalised coordinates must lie in [0, 1])");
        Box b;
        b.label = (int)v[0];
        b.x0 = std::max(0.0, (v[1] - v[3] / 2) * width);
        b.x1 = std::min((double)width, (v[1] + v[3] / 2) * width);
        b.y0 = std::max(0.0, (v[2] - v[4] / 2) * height);
        b.y1 = std::min((double)height, (v[2] + v[4] / 2) * height);
        out.push_back(b);
    }
    return out;
}

void write_yolo(const std::string &path, const std::vector<Box> &boxes, int width, int height)
{
    std::string s;
    char b[160];
    for (const Box &x : boxes) {
        std::snprintf(b, sizeof b, "%d %.6f %.6f %.6f %.6f\n", x.label, (x.x0 + x.x1) / 2 / width,
                      (x.y0 + x.y1) / 2 / height, x.width() / width, x.height() / height);
        s += b;
    }
    write_file_atomic(path, s);
}

std::string find_label_file(const std::string &image)
{
    size_t slash = image.find_last_of('/');
    std::string dir = slash == std::string::npos ? "." : image.substr(0, slash);
    std::string base = slash == std::string::npos ? image : image.substr(slash + 1);
    size_t dot = base.find_last_of('.');
    std::string stem = dot == std::string::npos ? base : base.substr(0, dot);
    size_t ds = dir.find_last_of('/');
    std::string last = ds == std::string::npos ? dir : dir.substr(ds + 1);
    if (last == "images") {
        std::string parent = ds == std::string::npos ? "." : dir.substr(0, ds);
        std::string p = parent + "/labels/" + stem + ".txt";
        if (is_file(p)) return p;
    }
    std::string p = dir + "/" + stem + ".txt";
    return is_file(p) ? p : "";
}

std::vector<std::string> expand_images(const std::vector<std::string> &args)
{
    std::vector<std::string> out;
    for (const std::string &a : args) {
        if (is_dir(a)) {
            std::vector<std::string> files;
            std::unique_ptr<DIR, int (*)(DIR *)> d(::opendir(a.c_str()), ::closedir);
            if (!d) throw Error(a + ": cannot read directory: " + std::strerror(errno));
            while (struct dirent *e = ::readdir(d.get())) {
                std::string n = e->d_name;
                if (n[0] != '.' && is_image_ext(ext_of(n))) files.push_back(std::string(a).append("/").append(n));
            }
            std::sort(files.begin(), files.end());
            if (files.empty()) throw Error(a + ": no image files (jpg, jpeg, png, bmp) in this directory");
            out.insert(out.end(), files.begin(), files.end());
        } else if (ext_of(a) == "list") {
            std::ifstream f(a);
            if (!f) throw Error(a + ": cannot open image list: " + std::strerror(errno));
            size_t slash = a.find_last_of('/');
            std::string dir = slash == std::string::npos ? "." : a.substr(0, slash);
            std::string line;
            while (std::getline(f, line)) {
                if (!line.empty() && line.back() == '\r') line.pop_back();
                if (line.empty() || line[0] == '#') continue;
                out.push_back(line[0] == '/' ? line : std::string(dir).append("/").append(line));
            }
        } else {
            out.push_back(a);
        }
    }
    return out;
}

namespace {

LabelledFrame load_labelled(const std::string &path, bool need_labels)
{
    LabelledFrame l;
    l.frame = calib::load_frame(path);
    std::string lf = find_label_file(path);
    if (lf.empty()) {
        if (need_labels)
            throw Error(path + ": no label file (looked for ../labels/STEM.txt and STEM.txt beside the image)");
        return l;
    }
    l.boxes = read_yolo(lf, (int)l.frame.img.width, (int)l.frame.img.height);
    return l;
}

// Fill mask (w x h) with value inside box b, inset by a fraction of its size per side.
void paint(std::vector<uint8_t> &mask, int w, int h, const Box &b, double inset, uint8_t value)
{
    const double dx = b.width() * inset, dy = b.height() * inset;
    int x0, x1, y0, y1;
    px_range(b.x0 + dx, b.x1 - dx, w, &x0, &x1);
    px_range(b.y0 + dy, b.y1 - dy, h, &y0, &y1);
    for (int y = y0; y < y1; y++) std::memset(&mask[(size_t)y * w + x0], value, (size_t)std::max(0, x1 - x0));
}

// Count the pixels of img whose mask byte equals value (mask null: all) into h, once per
// exposure gain, colour temperature and added white light of the options (photometric augmentation).
void count_augmented(cyl_colorhist *h, const cyl_image &img, const uint8_t *mask, size_t stride, uint8_t value,
                     const LearnOptions &o, const std::string &what)
{
    for (double g : o.gains)
        for (double t : o.colour_temperatures)
            for (double wl : o.white_lifts) {
                const double rgb[3] = {g * (1.0 + t), g, g / (1.0 + t)};
                check(cyl_colorhist_add_light(h, &img, nullptr, mask, stride, value, rgb, wl), what);
            }
}

} // namespace

namespace {

// The learning itself; frame(i) gives training frame i of n with its boxes.
LearnResult learn_core(cyl_colortable &t, size_t n_images, const std::function<LabelledFrame(size_t)> &frame,
                       const std::vector<ClassSpec> &classes, const LearnOptions &o,
                       const std::function<void(size_t, size_t)> &progress)
{
    if (classes.empty()) throw Error("no class to learn");
    if (classes.size() > CYL_MAX_CLASSES) throw Error("at most 8 classes");
    if (n_images == 0) throw Error("no training images");
    if (o.gains.empty()) throw Error("no exposure gain to learn at");
    if (o.colour_temperatures.empty()) throw Error("no colour temperature to learn at");
    for (double t : o.colour_temperatures)
        if (!(t > -0.5 && t <= 1.0)) throw Error("colour temperature shift " + num(t) + " outside (-0.5, 1]");
    if (o.white_lifts.empty()) throw Error("no white light to learn at");
    for (double wl : o.white_lifts)
        if (!(wl >= -255 && wl <= 255)) throw Error("white light " + num(wl) + " outside -255..255 levels");
    const uint64_t passes = (uint64_t)(o.gains.size() * o.colour_temperatures.size() * o.white_lifts.size());
    const size_t nc = classes.size();
    std::vector<std::unique_ptr<cyl_colorhist>> pos(nc);
    for (auto &p : pos) { p.reset(new cyl_colorhist); cyl_colorhist_clear(p.get()); }
    std::vector<std::unique_ptr<cyl_colorhist>> sur(nc);
    for (auto &p : sur) { p.reset(new cyl_colorhist); cyl_colorhist_clear(p.get()); }
    std::unique_ptr<cyl_colorhist> neg(new cyl_colorhist);
    cyl_colorhist_clear(neg.get());
    LearnResult res;
    res.classes.resize(nc);
    // Table indices: given, existing by name, or the next free.
    std::vector<unsigned> idx(nc);
    for (size_t i = 0; i < nc; i++) {
        const ClassSpec &c = classes[i];
        if (c.name.empty() || c.name.size() >= CYL_CLASS_NAME_LEN)
            throw Error("class name '" + c.name + "' must be 1.." + std::to_string(CYL_CLASS_NAME_LEN - 1) + " bytes");
        int found = cyl_colortable_find_class(&t, c.name.c_str());
        int index = c.index >= 0 ? c.index : found;
        if (index < 0)
            for (int k = 0; k < CYL_MAX_CLASSES; k++) {
                bool used = t.name[k][0] != '\0';
                for (size_t j = 0; j < i; j++) used = used || idx[j] == (unsigned)k;
                if (!used) { index = k; break; }
            }
        if (index < 0) throw Error("the table has no free class index for '" + c.name + "'");
        if (t.name[index][0] && c.name != t.name[index])
            throw Error("index " + std::to_string(index) + " is taken by class '" + t.name[index] + "'");
        idx[i] = (unsigned)index;
        res.classes[i].name = c.name;
        res.classes[i].index = (unsigned)index;
    }
    const size_t total = n_images + o.negative_images.size();
    size_t done = 0;
    for (size_t fi = 0; fi < n_images; fi++) {
        const LabelledFrame l = frame(fi);
        const std::string &path = l.frame.label;
        const int w = (int)l.frame.img.width, h = (int)l.frame.img.height;
        // mask: 0 background, 1 + i class i, 255 ignored (another learned class's box, or an
        // unlearned label's box when those are not background)
        std::vector<uint8_t> mask((size_t)w * h, 0);
        for (const Box &b : l.boxes) {
            bool learned = false;
            for (size_t i = 0; i < nc; i++) learned = learned || classes[i].label == b.label;
            if (learned || !o.other_boxes_negative) paint(mask, w, h, b, 0.0, 255);
        }
        for (size_t i = 0; i < nc; i++) {
            std::vector<uint8_t> m((size_t)w * h, 0);
            for (const Box &b : l.boxes)
                if (b.label == classes[i].label) {
                    paint(m, w, h, b, o.inset, 1);
                    ClassReport &c = res.classes[i];
                    c.boxes++;
                    const bool edge = b.x0 < 1 || b.y0 < 1 || b.x1 > w - 1 || b.y1 > h - 1;
                    if (!edge && b.height() > 0) {
                        const double a = b.width() / b.height();
                        c.aspect_min = c.aspect_min > 0 ? std::min(c.aspect_min, a) : a;
                        c.aspect_max = std::max(c.aspect_max, a);
                    }
                }
            const uint64_t before = pos[i]->total;
            count_augmented(pos[i].get(), l.frame.img, m.data(), (size_t)w, 1, o, path + ": class histogram");
            res.classes[i].positive_px += (pos[i]->total - before) / passes;
            if (o.surround > 0) {
                // the ring: background pixels (mask 0) within the grown boxes of the class
                std::fill(m.begin(), m.end(), 0);
                for (const Box &b : l.boxes)
                    if (b.label == classes[i].label) {
                        Box g = b;
                        const double dx = std::max(2.0, o.surround * b.width()), dy = std::max(2.0, o.surround * b.height());
                        g.x0 -= dx; g.x1 += dx; g.y0 -= dy; g.y1 += dy;
                        paint(m, w, h, g, 0.0, 1);
                    }
                for (size_t k = 0; k < m.size(); k++)
                    if (mask[k] != 0) m[k] = 0;
                count_augmented(sur[i].get(), l.frame.img, m.data(), (size_t)w, 1, o, path + ": surround histogram");
            }
        }
        count_augmented(neg.get(), l.frame.img, mask.data(), (size_t)w, 0, o, path + ": background histogram");
        if (progress) progress(++done, total);
    }
    for (const std::string &path : o.negative_images) {
        calib::Frame f = calib::load_frame(path);
        count_augmented(neg.get(), f.img, nullptr, 0, 0, o, path + ": background histogram");
        if (progress) progress(++done, total);
    }
    for (size_t i = 0; i < nc; i++)
        if (pos[i]->total == 0)
            throw Error("class '" + classes[i].name + "' (label " + std::to_string(classes[i].label) +
                        "): no labelled pixel in the " + std::to_string(n_images) + " training images");
    res.negative_px = neg->total / passes;
    res.images = n_images;

    static const uint8_t pal[CYL_MAX_CLASSES][3] = {{255, 120, 0}, {0, 200, 60}, {0, 90, 255}, {255, 220, 0},
                                                    {220, 0, 220}, {0, 220, 220}, {255, 255, 255}, {140, 70, 20}};
    for (size_t i = 0; i < nc; i++)
        if (t.name[idx[i]][0] == '\0')
            check(cyl_colortable_set_class(&t, idx[i], classes[i].name.c_str(), pal[idx[i]][0], pal[idx[i]][1],
                                           pal[idx[i]][2]), "class name");
    // weak classes: NAME~ (existing, or the next free index)
    std::vector<cyl_learn_class> lc(nc);
    for (size_t i = 0; i < nc; i++) {
        lc[i].cls = idx[i];
        lc[i].positive = pos[i].get();
        lc[i].surround = o.surround > 0 ? sur[i].get() : nullptr;
        lc[i].weak_cls = CYL_CLASS_NONE;
        if (!o.weak) continue;
        std::string wn = classes[i].name.substr(0, CYL_CLASS_NAME_LEN - 2) + "~";
        int w = cyl_colortable_find_class(&t, wn.c_str());
        if (w < 0)
            for (int n = 0; n < CYL_MAX_CLASSES; n++) {
                const int k = o.weak_from_top ? CYL_MAX_CLASSES - 1 - n : n;
                bool used = t.name[k][0] != '\0';
                for (size_t j = 0; j < nc; j++) used = used || idx[j] == (unsigned)k || lc[j].weak_cls == (unsigned)k;
                if (!used) { w = k; break; }
            }
        if (w < 0) throw Error("the table has no free class index for the weak class '" + wn + "' (use --no-weak)");
        const uint8_t *c = t.rgb[idx[i]];
        check(cyl_colortable_set_class(&t, (unsigned)w, wn.c_str(), (uint8_t)(c[0] / 2), (uint8_t)(c[1] / 2),
                                       (uint8_t)(c[2] / 2)), "weak class name");
        lc[i].weak_cls = (unsigned)w;
        res.classes[i].weak_index = (unsigned)w;
    }
    std::vector<float> work(cyl_learn_workspace_size((unsigned)nc) / sizeof(float) + 1);
    std::vector<cyl_learn_report> rep(nc);
    cyl_status s = cyl_colortable_learn(&t, lc.data(), (unsigned)nc, neg.get(), &o.params, work.data(),
                                        work.size() * sizeof(float), rep.data());
    if (s == CYL_ERR_EMPTY)
        throw Error("learning claimed no colour for a class at the false-positive rate " + num(o.params.max_bg_fraction) +
                    ": its colours are as common in the background, or around its boxes, as in them (raise --fpr, lower "
                    "--surround-weight, or label more)");
    check(s, "learning the colour classes");
    for (size_t i = 0; i < nc; i++) res.classes[i].r = rep[i];

    // Per training frame: the share each class covers; warnings.
    for (size_t fi = 0; fi < n_images; fi++) {
        const LabelledFrame lf = frame(fi);
        const calib::Frame &f = lf.frame;
        const std::string &path = f.label;
        const int w = (int)f.img.width, h = (int)f.img.height;
        std::vector<uint8_t> cls((size_t)w * h);
        check(cyl_classify(&t, &f.img, nullptr, 1, 1, cls.data(), (size_t)w), path + ": classify");
        for (size_t i = 0; i < nc; i++) {
            size_t n = (size_t)std::count(cls.begin(), cls.end(), (uint8_t)idx[i]);
            double share = (double)n / cls.size();
            if (share > res.classes[i].worst_frame_share) {
                res.classes[i].worst_frame_share = share;
                res.classes[i].worst_frame = path;
            }
        }
    }
    for (size_t i = 0; i < nc; i++) {
        ClassReport &c = res.classes[i];
        if (c.r.grey_fraction > 0.0)
            c.warnings.push_back(num(100 * c.r.grey_fraction, 3) + "% of its colour cells are near grey (chroma within 8 " +
                                 "of neutral): it may fire on white, grey or black surfaces");
        if (c.worst_frame_share > o.flood_fraction)
            c.warnings.push_back("covers " + num(100 * c.worst_frame_share, 3) + "% of training frame " + c.worst_frame);
        if (c.r.recall < 0.15)
            c.warnings.push_back("keeps only " + num(100 * c.r.recall, 3) +
                                 "% of its labelled pixels: its colours are common in the background too");
        for (size_t j = 0; j < nc; j++)
            if (c.r.lost_to[idx[j]] > 0.01)
                c.warnings.push_back(num(100 * c.r.lost_to[idx[j]], 3) + "% of its pixels went to '" + classes[j].name +
                                     "' where both classes claimed the colour (the likelier class keeps it)");
    }
    return res;
}

} // namespace

LearnResult learn_from_labels(cyl_colortable &t, const std::vector<std::string> &images,
                              const std::vector<ClassSpec> &classes, const LearnOptions &o,
                              const std::function<void(size_t, size_t)> &progress)
{
    return learn_core(t, images.size(), [&](size_t i) { return load_labelled(images[i], true); }, classes, o, progress);
}

LearnResult learn_from_frames(cyl_colortable &t, const std::vector<LabelledFrame> &frames,
                              const std::vector<ClassSpec> &classes, const LearnOptions &o)
{
    return learn_core(t, frames.size(), [&](size_t i) { return frames[i]; }, classes, o, nullptr);
}

std::string report_text(const LearnResult &r, const cyl_colortable &t)
{
    (void)t;
    std::string s = "learned from " + std::to_string(r.images) + " images, " + std::to_string(r.negative_px) +
                    " background px\n";
    char b[512];
    std::snprintf(b, sizeof b, "%-16s %5s %6s %10s %9s %10s %9s %7s %9s   %s\n", "class", "index", "boxes", "pixels",
                  "recall", "bg claimed", "ratio thr", "cells", "max frame", "weak class: +recall +bg claimed thr");
    s += b;
    for (const ClassReport &c : r.classes) {
        std::snprintf(b, sizeof b, "%-16s %5u %6llu %10llu %8.1f%% %9.3f%% %9.3g %7u %8.2f%%", c.name.c_str(), c.index,
                      (unsigned long long)c.boxes, (unsigned long long)c.positive_px, 100 * c.r.recall,
                      100 * c.r.bg_fraction, c.r.lr_threshold, c.r.cells, 100 * c.worst_frame_share);
        s += b;
        if (c.weak_index != CYL_CLASS_NONE) {
            std::snprintf(b, sizeof b, "   %u: +%.1f%% +%.3f%% %.3g", c.weak_index, 100 * c.r.weak_recall,
                          100 * c.r.weak_bg_fraction, c.r.weak_lr_threshold);
            s += b;
        }
        s += "\n";
    }
    for (const ClassReport &c : r.classes) {
        const ClassReport::WeakAlone &w = c.weak_alone;
        if (!w.evaluated) continue;
        std::snprintf(b, sizeof b,
                      "%s: weak blobs alone (from %u px) %s: on its training images they find %llu -> %llu boxes, "
                      "false blobs %.2f -> %.2f per image\n",
                      c.name.c_str(), w.tried_area_px, w.area_px ? "on" : "off", (unsigned long long)w.found_off,
                      (unsigned long long)w.found_on, w.fp_off, w.fp_on);
        s += b;
    }
    for (const ClassReport &c : r.classes)
        for (const std::string &w : c.warnings) s += "warning: " + c.name + ": " + w + "\n";
    return s;
}

void choose_weak_alone(const cyl_colortable &t, const std::vector<std::string> &images,
                       const std::vector<ClassSpec> &classes, uint32_t area_px, double max_fp_per_image,
                       DetectorConfig &cfg, LearnResult &r)
{
    ScoreOptions so;
    so.detector = cfg;
    for (const ClassReport &c : r.classes) so.detector.segment.cls[c.index].weak_alone_min_area = 0;
    const ScoreResult off = score(t, images, classes, so);
    for (const ClassReport &c : r.classes) so.detector.segment.cls[c.index].weak_alone_min_area = area_px;
    const ScoreResult on = score(t, images, classes, so);
    const double n = off.images ? (double)off.images : 1.0;
    for (ClassReport &c : r.classes) {
        for (size_t k = 0; k < classes.size(); k++) {
            if (classes[k].name != c.name) continue;
            ClassReport::WeakAlone &w = c.weak_alone;
            w.evaluated = true;
            w.tried_area_px = area_px;
            w.found_off = off.classes[k].found_iou;
            w.found_on = on.classes[k].found_iou;
            w.fp_off = (double)off.classes[k].false_blobs / n;
            w.fp_on = (double)on.classes[k].false_blobs / n;
            w.area_px = (area_px > 0 && w.found_on > w.found_off && w.fp_on <= max_fp_per_image) ? area_px : 0;
            cfg.segment.cls[c.index].weak_alone_min_area = w.area_px;
        }
    }
}

std::string report_json(const LearnResult &r, const cyl_colortable &t)
{
    std::string s = "{\"images\": " + std::to_string(r.images) + ", \"background_px\": " + std::to_string(r.negative_px) +
                    ", \"classes\": [";
    for (size_t i = 0; i < r.classes.size(); i++) {
        const ClassReport &c = r.classes[i];
        if (i) s += ", ";
        s += "{\"name\": " + json_str(c.name) + ", \"index\": " + std::to_string(c.index) +
             ", \"boxes\": " + std::to_string(c.boxes) + ", \"positive_px\": " + std::to_string(c.positive_px) +
             ", \"recall\": " + num(c.r.recall, 6) + ", \"recall_before_overlaps\": " + num(c.r.recall_alone, 6) +
             ", \"background_claimed\": " + num(c.r.bg_fraction, 6) + ", \"ratio_threshold\": " + num(c.r.lr_threshold, 6) +
             ", \"cells\": " + std::to_string(c.r.cells) + ", \"grey_cell_fraction\": " + num(c.r.grey_fraction, 6) +
             ", \"weak_index\": " + (c.weak_index == CYL_CLASS_NONE ? std::string("null") : std::to_string(c.weak_index)) +
             ", \"weak_recall\": " + num(c.r.weak_recall, 6) + ", \"weak_background_claimed\": " +
             num(c.r.weak_bg_fraction, 6) + ", \"weak_ratio_threshold\": " + num(c.r.weak_lr_threshold, 6) + ", \"weak_cells\": " +
             std::to_string(c.r.weak_cells) +
             ", \"max_frame_share\": " + num(c.worst_frame_share, 6) + ", \"box_aspect_range\": [" + num(c.aspect_min, 6) +
             ", " + num(c.aspect_max, 6) + "], \"weak_alone\": ";
        const ClassReport::WeakAlone &w = c.weak_alone;
        if (w.evaluated)
            s += "{\"min_area_px\": " + std::to_string(w.area_px) + ", \"tried_area_px\": " + std::to_string(w.tried_area_px) +
                 ", \"train_boxes_found_off\": " + std::to_string(w.found_off) + ", \"train_boxes_found_on\": " +
                 std::to_string(w.found_on) + ", \"train_fp_per_image_off\": " + num(w.fp_off, 6) +
                 ", \"train_fp_per_image_on\": " + num(w.fp_on, 6) + "}";
        else
            s += "null";
        s += ", \"lost_to\": {";
        bool first = true;
        for (unsigned j = 0; j < CYL_MAX_CLASSES; j++)
            if (c.r.lost_to[j] > 0) {
                s += std::string(first ? "" : ", ") + json_str(t.name[j]) + ": " + num(c.r.lost_to[j], 6);
                first = false;
            }
        s += "}, \"warnings\": [";
        for (size_t k = 0; k < c.warnings.size(); k++) s += (k ? ", " : "") + json_str(c.warnings[k]);
        s += "]}";
    }
    return s + "]}";
}

// ---- scoring --------------------------------------------------------------------------------------

ScoreResult score(const cyl_colortable &t, const std::vector<std::string> &images,
                  const std::vector<ClassSpec> &classes, const ScoreOptions &o,
                  const std::function<void(size_t, size_t)> &progress)
{
    ScoreResult res;
    std::vector<unsigned> idx;
    for (const ClassSpec &c : classes) {
        int k = cyl_colortable_find_class(&t, c.name.c_str());
        if (k < 0) throw Error("the table has no class '" + c.name + "'");
        idx.push_back((unsigned)k);
        ClassScore cs;
        cs.name = c.name;
        cs.label = c.label;
        res.classes.push_back(cs);
    }
    std::vector<double> us;
    double mpx_total = 0;
    std::vector<uint8_t> mem;
    cyl_segmentation seg{};
    std::vector<uint8_t> split_work;
    uint32_t cap_w = 0, cap_h = 0;
    size_t done = 0;
    // one row per labelled box (with the blob matched to it, if any); false blobs too, with matched_iou
    // "false_blob" and their own box in x0..y1 and in the blob columns
    std::string csv = "image,class,x0_px,y0_px,x1_px,y1_px,best_iou,matched_iou,centroid_inside,class_px_share,"
                      "blob_x0_px,blob_y0_px,blob_x1_px,blob_y1_px,blob_area_px,blob_flags\n";
    // a blob's columns: box as x0, y0, x1 + 1, y1 + 1 (the label boxes' convention), area, CYL_BLOB_* flags
    auto blob_cols = [](const cyl_blob *K) {
        if (!K) return std::string(",,,,,");
        char b[128];
        std::snprintf(b, sizeof b, "%d,%d,%d,%d,%u,%u", K->x0, K->y0, K->x1 + 1, K->y1 + 1, K->area, (unsigned)K->flags);
        return std::string(b);
    };
    std::unique_ptr<Detector> det;
    if (o.camera) det.reset(new Detector(t, *o.camera, o.detector));
    std::vector<char> observed;   // per blob of the detector's segmentation: an observation kept it
    for (const std::string &path : images) {
        LabelledFrame l = load_labelled(path, false);
        const cyl_image &img = l.frame.img;
        if (img.width != cap_w || img.height != cap_h) {
            uint32_t mr = cyl_segment_max_runs(img.width, img.height, &o.detector.segment), mb = mr;
            mem.assign(cyl_segment_mem_size(mr, mb), 0);
            check(cyl_segmentation_init(&seg, mem.data(), mem.size(), mr, mb), "segmentation memory");
            cap_w = img.width;
            cap_h = img.height;
        }
        auto t0 = std::chrono::steady_clock::now();
        check(cyl_segment(&t, &img, &o.detector.segment, &seg), path + ": segmentation");
        auto t1 = std::chrono::steady_clock::now();
        us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
        check(split_blobs(o.detector, seg, split_work), path + ": splitting blobs");
        const double frame_px = (double)img.width * img.height;
        mpx_total += frame_px / 1e6;
        if (det) {
            if (img.width != o.camera->width || img.height != o.camera->height)
                throw Error(path + ": the image is " + std::to_string(img.width) + "x" + std::to_string(img.height) +
                            " px but the camera's frames are " + std::to_string(o.camera->width) + "x" +
                            std::to_string(o.camera->height));
            const std::vector<cyl_observation> &obs = det->process(img);
            observed.assign(det->segmentation().n_blobs, 0);
            for (const cyl_observation &ob : obs) observed[ob.blob] = 1;
        }
        const cyl_segmentation &sg = det ? det->segmentation() : seg;
        cv::Mat vis;
        if (!o.overlay_dir.empty()) {
            vis = calib::classified_overlay(t, l.frame, 0.5);
            for (const Box &b : l.boxes)
                cv::rectangle(vis, cv::Rect2d(b.x0, b.y0, b.width(), b.height()), cv::Scalar(255, 255, 255), 1);
        }
        for (size_t ci = 0; ci < classes.size(); ci++) {
            ClassScore &cs = res.classes[ci];
            const unsigned k = idx[ci];
            std::vector<const cyl_blob *> blobs;
            uint64_t class_px = 0;
            for (uint32_t b = sg.class_first[k]; b < sg.class_first[k] + sg.class_count[k]; b++) {
                class_px += sg.blobs[b].area;
                if (det ? !observed[b] : !blob_passes(o.detector, sg.blobs[b], img.width, img.height)) continue;
                blobs.push_back(&sg.blobs[b]);
            }
            if ((double)class_px > o.flood_fraction * frame_px) cs.flooded_frames++;
            std::vector<const Box *> boxes;
            for (const Box &b : l.boxes)
                if (b.label == cs.label) boxes.push_back(&b);
            // a blob's box (its last column and row included) against a label box; its centroid in one
            auto iou = [](const Box &B, const cyl_blob &K) {
                const double kx0 = K.x0, kx1 = K.x1 + 1.0, ky0 = K.y0, ky1 = K.y1 + 1.0;
                const double ix = std::min(B.x1, kx1) - std::max(B.x0, kx0), iy = std::min(B.y1, ky1) - std::max(B.y0, ky0);
                if (ix <= 0 || iy <= 0) return 0.0;
                return ix * iy / (B.width() * B.height() + (kx1 - kx0) * (ky1 - ky0) - ix * iy);
            };
            auto centroid_in = [](const Box &B, const cyl_blob &K) {
                return K.cx_px + 0.5 >= B.x0 && K.cx_px + 0.5 < B.x1 && K.cy_px + 0.5 >= B.y0 && K.cy_px + 0.5 < B.y1;
            };
            // IoU matching, greedy by IoU, one blob per box
            struct Pair { double iou; size_t b, k; };
            std::vector<Pair> pairs;
            for (size_t bi = 0; bi < boxes.size(); bi++)
                for (size_t kb = 0; kb < blobs.size(); kb++) {
                    const double v = iou(*boxes[bi], *blobs[kb]);
                    if (v > 0 && v >= o.iou) pairs.push_back({v, bi, kb});
                }
            std::sort(pairs.begin(), pairs.end(), [](const Pair &a, const Pair &b) { return a.iou > b.iou; });
            std::vector<char> box_used(boxes.size(), 0), blob_used(blobs.size(), 0);
            std::vector<const cyl_blob *> box_blob(boxes.size(), nullptr);
            for (const Pair &p : pairs) {
                if (box_used[p.b] || blob_used[p.k]) continue;
                box_used[p.b] = blob_used[p.k] = 1;
                box_blob[p.b] = blobs[p.k];
            }
            for (size_t bi = 0; bi < boxes.size(); bi++) {
                const Box &B = *boxes[bi];
                const bool large = B.width() >= o.min_box_px;
                bool centroid = false;
                for (const cyl_blob *K : blobs) centroid = centroid || centroid_in(B, *K);
                if (!o.boxes_csv.empty()) {
                    double best = 0;
                    for (const cyl_blob *K : blobs) best = std::max(best, iou(B, *K));
                    uint64_t inside_px = 0, all_px = 0;
                    int x0, x1, y0, y1;
                    px_range(B.x0, B.x1, (int)img.width, &x0, &x1);
                    px_range(B.y0, B.y1, (int)img.height, &y0, &y1);
                    for (int y = y0; y < y1; y++)
                        for (int x = x0; x < x1; x++) {
                            uint8_t Y, U, V;
                            cyl_image_pixel(&img, (uint32_t)x, (uint32_t)y, &Y, &U, &V);
                            inside_px += cyl_mask_class(cyl_colortable_mask(&t, Y, U, V)) == k;
                            all_px++;
                        }
                    char b[512];
                    std::snprintf(b, sizeof b, "%s,%s,%.1f,%.1f,%.1f,%.1f,%.3f,%d,%d,%.3f,", path.c_str(), cs.name.c_str(),
                                  B.x0, B.y0, B.x1, B.y1, best, (int)box_used[bi], (int)centroid,
                                  all_px ? (double)inside_px / (double)all_px : 0.0);
                    csv += b + blob_cols(box_blob[bi]) + "\n";
                }
                cs.boxes++;
                cs.boxes_large += large;
                cs.found_iou += box_used[bi];
                cs.found_iou_large += large && box_used[bi];
                cs.found_centroid += centroid;
                cs.found_centroid_large += large && centroid;
            }
            for (const cyl_blob *K : blobs) {
                if (K->area < o.fp_min_area) continue;
                bool inside = false;
                for (const Box *B : boxes) inside = inside || centroid_in(*B, *K);
                cs.false_blobs += !inside;
                if (!inside && !o.boxes_csv.empty()) {
                    char b[512];
                    std::snprintf(b, sizeof b, "%s,%s,%d,%d,%d,%d,,false_blob,,,", path.c_str(), cs.name.c_str(),
                                  K->x0, K->y0, K->x1 + 1, K->y1 + 1);
                    csv += b + blob_cols(K) + "\n";
                }
                if (!vis.empty()) {
                    const uint8_t *rgb = t.rgb[k];
                    cv::Scalar col = inside ? cv::Scalar(rgb[2], rgb[1], rgb[0]) : cv::Scalar(0, 0, 255);
                    cv::rectangle(vis, cv::Rect(K->x0, K->y0, K->x1 - K->x0 + 1, K->y1 - K->y0 + 1), col, 1);
                }
            }
        }
        if (!vis.empty()) {
            size_t slash = path.find_last_of('/'), dot = path.find_last_of('.');
            std::string stem = path.substr(slash == std::string::npos ? 0 : slash + 1);
            if (dot != std::string::npos && dot > (slash == std::string::npos ? 0 : slash)) stem.resize(stem.find_last_of('.'));
            const std::string out = o.overlay_dir + "/" + stem + ".png";
            if (!cylfe::media::imwrite(out, vis)) throw Error(out + ": cannot write overlay image");
        }
        res.images++;
        if (progress) progress(++done, images.size());
    }
    if (!o.boxes_csv.empty()) write_file_atomic(o.boxes_csv, csv);
    if (!us.empty()) {
        std::vector<double> s = us;
        std::nth_element(s.begin(), s.begin() + (long)s.size() / 2, s.end());
        res.median_us = s[s.size() / 2];
        res.median_us_per_mpx = res.median_us / (mpx_total / (double)images.size());
    }
    return res;
}

} // namespace learn
} // namespace cylfe
