// SPDX-License-Identifier: BSD-3-Clause
// cyl-train: colour-table training (paper section 3.3) from image files or raw-log frames, on the
// command line or interactively in a window. Writes libcyl's CYLT table. docs/calibration.md.
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>
#include <unistd.h>

#include <opencv2/highgui.hpp>  // window flags and events only: windows are in the media plugin
#include <opencv2/imgproc.hpp>

#include "cylfe/version.hpp"
#include "cylfe/calib.hpp"
#include "cylfe/error.hpp"
#include "cylfe/learn.hpp"
#include "cylfe/media.hpp"
#include "cylfe/progress.hpp"

using namespace cylfe;
using namespace cylfe::calib;

namespace {

const char *kUsage =
    "usage: cyl-train learn -o TABLE.cylt --class NAME=LABEL... [options] IMAGE|DIR|LIST...\n"
    "       cyl-train -o TABLE.cylt [--base IN.cylt] [params] STEP...\n"
    "       cyl-train --gui IMAGE|LOG.cylraw [--frame N] -o TABLE.cylt [--base IN.cylt] [--class NAME]...\n"
    "       cyl-train --help | --version\n"
    "\n"
    "learn (the recommended way, docs/colour-learning.md): learns each class from the labelled\n"
    "boxes of several images (YOLO label files: DIR/labels/STEM.txt for DIR/images/STEM.jpg, or\n"
    "STEM.txt beside the image) against the background (every pixel outside the learned classes'\n"
    "boxes): a likelihood ratio over a 3-D YUV table, thresholded at a background false-positive\n"
    "rate (cyl/colorlearn.h). Prints a report per class. Options:\n"
    "  --class NAME=LABEL[@INDEX]  learn class NAME from the boxes with label id LABEL (repeatable;\n"
    "                      INDEX: its table index, lower wins where box classes overlap)\n"
    "  --fpr F             share of background pixels a class may claim (default 0.0005)\n"
    "  --smooth S          smoothing of the colour histograms, cells (default 1.5)\n"
    "  --min-ratio R       never claim a colour less than R times likelier in the class (default 4)\n"
    "  --weak-fpr F        share of background the class and its weak class NAME~ may claim together\n"
    "                      (default 0.01, raised to --fpr if that is larger); weak pixels count only\n"
    "                      where they touch the class's own\n"
    "  --min-share S       each class keeps at least S of its boxes' pixels, the threshold lowered\n"
    "                      below the rate's if need be (default 0: the rate alone)\n"
    "  --unseen W          weight of a uniform colour density in the background model: how likely a\n"
    "                      colour never seen in training is background (default 0.02)\n"
    "  --min-weak-ratio R  never give the weak class a colour less than R times likelier in the class\n"
    "                      (default 1.5)\n"
    "  --no-weak           no weak class\n"
    "  --gains G1,G2,...   count every training pixel as it would look at each of these exposure gains\n"
    "                      (the light or exposure changing; default 0.8,1,1.25)\n"
    "  --colour-temps T1,T2,...  ... and at each of these light colours: red gain 1+T, blue gain\n"
    "                      1/(1+T) (T > 0 warmer, < 0 cooler; -0.45..1; default 0: as taken)\n"
    "  --white-lifts W1,W2,...  ... and with a white light of W levels added to every channel (a\n"
    "                      highlight: brighter and paler; -255..255; default 0,16)\n"
    "  --inset F           trim F of each box's size off every side before counting (default 0)\n"
    "  --surround F        each class's surround: the background within F of a box's width/height\n"
    "                      (at least 2 px) around its boxes (default 0.25; 0: none)\n"
    "  --surround-weight W take out of a class the colours whose share in its boxes is at most W\n"
    "                      times their share in its surround (default 0.5; 0: off)\n"
    "  --negatives PATH    extra background-only images (file, directory or .list; repeatable)\n"
    "  --all-boxes-ignored boxes of labels not learned are left out of the background (default:\n"
    "                      they are background: a yellow shirt teaches the ball class what not to be)\n"
    "  --report FILE.json  also write the report as JSON\n"
    "  --config-out FILE.yaml  write a detector config (cyl detect --config, cyl-score --config) with\n"
    "                      each class's blob shape gate from its boxes: aspect_range = the boxes'\n"
    "                      width/height range widened by --aspect-margin (default 2) each way,\n"
    "                      min_fill (default 0.3) and merge_gap_px (default 3)\n"
    "  --aspect-margin M, --min-fill F, --merge-gap N   (for --config-out)\n"
    "  --split-waist R     (for --config-out) cut a blob where its rows narrow to below R of its\n"
    "                      widest rows above and below (two landmarks touching, one above the\n"
    "                      other; default 0.5; 0: off)\n"
    "  --split-axes A      (for --config-out) cut between rows (default), columns (side by side)\n"
    "                      or both\n"
    "  --weak-alone-area N|auto  (for --config-out) a blob of weak pixels alone (no pixel of the\n"
    "                      class itself: a landmark in shade) counts when it has at least N px\n"
    "                      (0: never). auto (default): per class, 700 px when on the training\n"
    "                      images it finds more of the class's boxes than without and adds no more\n"
    "                      than 1 false blob per image, else 0 (the report says which and why)\n"
    "  --size NAME=D,H     (for --config-out, repeatable) the class's landmark diameter and height,\n"
    "                      m: the config gets size_m and the expected-size gate at the measured range\n"
    "  --size-gate F       that gate's factor for classes given a size (default 2; 0: off)\n"
    "  --base IN.cylt      start from this table; -q quiet; -o required\n"
    "\n"
    "rectangles (the paper's method, cyl_colortable_train: a UV histogram of the region, thresholded,\n"
    "its bounding rectangle grown by a margin, and a Y window from the brightness quantiles) and\n"
    "writes the table (CYLT format, libcyl/include/cyl/colortable.h) via a temporary file + rename.\n"
    "Train on what the detector sees: for a V4L2 YUYV camera, record a raw log (cyl record) and\n"
    "train on its frames (--image LOG.cylraw --frame N); image files are converted as the `cyl`\n"
    "file source does (cv::cvtColor BGR -> YUV I420, BT.601).\n"
    "\n"
    "steps (processed in order):\n"
    "  --class NAME        select class NAME (existing in --base, or the next free index)\n"
    "  --index I           with --class: put a new class at index I (0..7; lower wins overlaps)\n"
    "  --color R,G,B       display colour of the current class (overlays)\n"
    "  --replace           clear the current class's colours before training it\n"
    "  --image PATH        current image file or raw log\n"
    "  --frame N           frame N (0-based) of the current raw log (default 0)\n"
    "  --rect X,Y,W,H      train the current class on this rectangle of the current image\n"
    "params (before the steps they apply to):\n"
    "  --min-bin-count N   a UV bin needs >= N region pixels (default 2)\n"
    "  --min-bin-fraction F  ... and >= F of the region's pixels (default 0.002)\n"
    "  --uv-margin N       grow the UV rectangle by N bins per side (default 3)\n"
    "  --y-margin N        widen the Y window by N levels (default 16)\n"
    "  --y-quantiles LO,HI Y window from these quantiles (default 0.01,0.99)\n"
    "other:\n"
    "  -o, --out FILE      output table (required)\n"
    "  --base FILE         start from this table (default: empty)\n"
    "  -q, --quiet\n"
    "\n"
    "interactive (--gui): drag a rectangle with the left button to train the current class on it;\n"
    "the classified pixels are shown in the classes' display colours. Keys:\n"
    "  0-7 select class   n next class   r rename the current class (type, Enter)\n"
    "  u undo             c clear the current class   o overlay on/off   l learn mode on/off\n"
    "  s save to -o       p write the window image to --snapshot FILE   q / Esc quit\n"
    "  --snapshot FILE     where p writes the window image (default: TABLE.png)\n"
    "  --learn             start in learn mode (key l): each box dragged is a labelled example and\n"
    "                      the classes are learned as by `cyl-train learn` from all of them at once,\n"
    "                      the report shown live; s also saves the boxes as YOLO labels, which\n"
    "                      `cyl-train learn` reads (and --learn loads them again)\n"
    "  --save-labels FILE  where s writes the labels (default: the image's STEM.txt beside it)\n"
    "  --scale S           display scale (default 1)\n"
    "\n"
    "exit codes: 0 ok, 1 failed (unreadable image or table, bad rectangle, nothing to train), 2 bad\n"
    "command line. No partial table is ever written.\n";

struct Usage : std::runtime_error {
    using std::runtime_error::runtime_error;
};

std::vector<double> parse_list(const std::string &opt, const std::string &v, size_t n)
{
    std::vector<double> out;
    size_t pos = 0;
    while (pos <= v.size()) {
        size_t c = v.find(',', pos);
        std::string part = v.substr(pos, c == std::string::npos ? std::string::npos : c - pos);
        char *end = nullptr;
        double d = std::strtod(part.c_str(), &end);
        if (part.empty() || *end || !std::isfinite(d)) {
            std::string m = opt;
            m += ": not a number: '";
            m += part;
            m += "'";
            throw Usage(m);
        }
        out.push_back(d);
        if (c == std::string::npos) break;
        pos = c + 1;
    }
    if (out.size() != n) throw Usage(opt + ": expected " + std::to_string(n) + " comma-separated values");
    return out;
}

double parse_num(const std::string &opt, const std::string &v, double lo, double hi, bool integer)
{
    double d = parse_list(opt, v, 1)[0];
    if (d < lo || d > hi || (integer && d != std::floor(d)))
        throw Usage(opt + ": expected " + std::string(integer ? "an integer" : "a number") + " in [" +
                    std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return d;
}

const uint8_t kPalette[CYL_MAX_CLASSES][3] = {{255, 120, 0}, {0, 200, 60}, {0, 90, 255}, {255, 220, 0},
                                              {220, 0, 220}, {0, 220, 220}, {255, 255, 255}, {140, 70, 20}};

// Select (or create) a class by name; index < 0: the next free slot.
unsigned select_class(cyl_colortable &t, const std::string &name, int index)
{
    if (name.empty() || name.size() >= CYL_CLASS_NAME_LEN)
        throw Usage("--class: name must be 1.." + std::to_string(CYL_CLASS_NAME_LEN - 1) + " bytes");
    int found = cyl_colortable_find_class(&t, name.c_str());
    if (found >= 0) {
        if (index >= 0 && index != found)
            throw Error("class '" + name + "' already exists at index " + std::to_string(found));
        return (unsigned)found;
    }
    if (index < 0) {
        for (int i = 0; i < CYL_MAX_CLASSES; i++)
            if (t.name[i][0] == '\0') { index = i; break; }
        if (index < 0) throw Error("the table already has " + std::to_string(CYL_MAX_CLASSES) + " classes");
    } else if (t.name[index][0] != '\0')
        throw Error("index " + std::to_string(index) + " is taken by class '" + t.name[index] + "'");
    const uint8_t *c = kPalette[index];
    check(cyl_colortable_set_class(&t, (unsigned)index, name.c_str(), c[0], c[1], c[2]), "--class");
    return (unsigned)index;
}

struct Opts {
    std::string out, base, gui, snapshot, save_labels;
    long gui_frame = 0;
    double scale = 1.0;
    bool quiet = false, gui_learn = false;
    std::vector<std::string> gui_classes;
};

// ---- interactive ------------------------------------------------------------------------------

constexpr int kBarHeight = 54;  // px of status bar below the image

struct Gui {
    cyl_colortable table, base;                // base: the table before learn mode's classes
    std::vector<cyl_colortable> undo;
    std::vector<std::vector<learn::Box>> undo_boxes;
    std::vector<learn::Box> boxes;             // learn mode: the labelled boxes so far
    bool learn = false;
    std::string labels_path;
    Frame frame;
    unsigned cls = 0;
    bool dragging = false, overlay = true, naming = false, dirty = true;
    cv::Point p0, p1;
    std::string status, name_buf;
    cyl_train_params params;
    double scale = 1.0;
};

// Learn mode: learn every class that has boxes from this frame's boxes (the rest of the frame
// is background), into the table as it was when learn mode began; the report goes to the status
// line and stdout.
void relearn(Gui &g)
{
    std::vector<learn::ClassSpec> classes;
    for (unsigned k = 0; k < CYL_MAX_CLASSES; k++) {
        bool has = false;
        for (const learn::Box &b : g.boxes) has = has || b.label == (int)k;
        if (!has) continue;
        learn::ClassSpec c;
        c.name = g.base.name[k][0] ? std::string(g.base.name[k]) : g.table.name[k][0] ? std::string(g.table.name[k])
                                                                                    : "class" + std::to_string(k);
        c.label = (int)k;
        c.index = (int)k;
        classes.push_back(c);
    }
    if (classes.empty()) { g.table = g.base; g.status = "no boxes"; return; }
    learn::LearnOptions lo;
    lo.weak_from_top = true;
    std::vector<learn::LabelledFrame> frames(1);
    frames[0].frame = g.frame;
    frames[0].boxes = g.boxes;
    cyl_colortable t = g.base;
    for (const learn::ClassSpec &c : classes)
        if (!t.name[c.index][0]) {
            const uint8_t *col = kPalette[c.index];
            cyl_colortable_set_class(&t, (unsigned)c.index, c.name.c_str(), col[0], col[1], col[2]);
        }
    try {
        learn::LearnResult r = learn::learn_from_frames(t, frames, classes, lo);
        g.table = t;
        std::fputs(learn::report_text(r, t).c_str(), stdout);
        std::fflush(stdout);
        for (const learn::ClassReport &c : r.classes)
            if (c.index == g.cls) {
                char b[200];
                std::snprintf(b, sizeof b, "learned %s from %llu box(es): recall %.0f%% (+%.0f%% weak), background %.3f%%, "
                              "covers %.1f%% of the frame%s", c.name.c_str(), (unsigned long long)c.boxes,
                              100 * c.r.recall, 100 * c.r.weak_recall, 100 * c.r.bg_fraction, 100 * c.worst_frame_share,
                              c.warnings.empty() ? "" : " (warnings on stdout)");
                g.status = b;
            }
    } catch (const Error &e) {
        g.status = e.what();
    }
}

void on_mouse(int ev, int x, int y, int, void *ud)
{
    Gui &g = *static_cast<Gui *>(ud);
    cv::Point p((int)std::lround(x / g.scale), (int)std::lround(y / g.scale));
    p.x = std::max(0, std::min((int)g.frame.img.width - 1, p.x));
    p.y = std::max(0, std::min((int)g.frame.img.height - 1, p.y));
    if (ev == cv::EVENT_LBUTTONDOWN) {
        g.dragging = true;
        g.p0 = g.p1 = p;
        g.dirty = true;
    } else if (ev == cv::EVENT_MOUSEMOVE && g.dragging) {
        g.p1 = p;
        g.dirty = true;
    } else if (ev == cv::EVENT_LBUTTONUP && g.dragging) {
        g.dragging = false;
        g.p1 = p;
        cv::Rect r(cv::Point(std::min(g.p0.x, g.p1.x), std::min(g.p0.y, g.p1.y)),
                   cv::Point(std::max(g.p0.x, g.p1.x) + 1, std::max(g.p0.y, g.p1.y) + 1));
        if (r.width < 3 || r.height < 3) {
            g.status = "rectangle too small";
        } else if (g.learn) {
            learn::Box b;
            b.label = (int)g.cls;
            b.x0 = r.x; b.y0 = r.y; b.x1 = r.x + r.width; b.y1 = r.y + r.height;
            g.undo.push_back(g.table);
            g.undo_boxes.push_back(g.boxes);
            g.boxes.push_back(b);
            relearn(g);
        } else {
            if (g.table.name[g.cls][0] == '\0') {
                std::string n = "class" + std::to_string(g.cls);
                const uint8_t *c = kPalette[g.cls];
                cyl_colortable_set_class(&g.table, g.cls, n.c_str(), c[0], c[1], c[2]);
            }
            g.undo.push_back(g.table);
            try {
                uint8_t box[6];
                train_rect(g.table, g.cls, g.frame, r, g.params, box);
                char b[200];
                std::snprintf(b, sizeof b, "trained %s on %d,%d,%d,%d: U %d-%d V %d-%d Y %d-%d, covers %.0f%%",
                              g.table.name[g.cls], r.x, r.y, r.width, r.height, box[0], box[1], box[2], box[3], box[4],
                              box[5], 100 * class_coverage(g.table, g.cls, g.frame, r));
                g.status = b;
                std::printf("%s\n", b);
                std::fflush(stdout);
            } catch (const Error &e) {
                g.undo.pop_back();
                g.status = e.what();
            }
        }
        g.dirty = true;
    }
}

cv::Mat render(const Gui &g)
{
    cv::Mat img = g.overlay ? classified_overlay(g.table, g.frame) : classified_overlay(cyl_colortable{}, g.frame, 0);
    if (g.scale != 1.0) cv::resize(img, img, cv::Size(), g.scale, g.scale, cv::INTER_NEAREST);
    if (g.learn)
        for (const learn::Box &b : g.boxes) {
            const uint8_t *c = g.table.rgb[b.label];
            cv::rectangle(img, cv::Rect2d(b.x0 * g.scale, b.y0 * g.scale, b.width() * g.scale, b.height() * g.scale),
                          cv::Scalar(c[2], c[1], c[0]), 1);
        }
    if (g.dragging)
        cv::rectangle(img, cv::Point(g.p0) * g.scale, cv::Point(g.p1) * g.scale, cv::Scalar(255, 255, 255), 1);
    // status bar: the class, the keys, the last message
    cv::Mat bar(kBarHeight, img.cols, CV_8UC3, cv::Scalar(40, 40, 40));
    std::string line1 = "class " + std::to_string(g.cls) + ": " +
                        (g.naming ? g.name_buf + "_  (type the name, Enter)" : std::string(g.table.name[g.cls]));
    std::string line2 = std::string(g.learn ? "LEARN drag: box" : "drag: train") + "  0-7/n: class  r: rename  u: undo (" +
                        std::to_string(g.undo.size()) + ")  c: clear  l: learn mode  o: overlay  s: save  p: snapshot  q: quit";
    const uint8_t *c = g.table.rgb[g.cls];
    cv::rectangle(bar, cv::Rect(4, 4, 12, 12), cv::Scalar(c[2], c[1], c[0]), cv::FILLED);
    cv::putText(bar, line1, cv::Point(22, 15), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(230, 230, 230), 1);
    cv::putText(bar, line2, cv::Point(4, 32), cv::FONT_HERSHEY_SIMPLEX, 0.3, cv::Scalar(200, 200, 200), 1);
    cv::putText(bar, g.status, cv::Point(4, 48), cv::FONT_HERSHEY_SIMPLEX, 0.35, cv::Scalar(160, 220, 255), 1);
    cv::Mat out;
    cv::vconcat(img, bar, out);
    return out;
}

int run_gui(Opts &o, cyl_colortable &t, const cyl_train_params &params)
{
    const char *disp = std::getenv("DISPLAY");
    if (!disp || !*disp) throw Error("--gui needs an X display (DISPLAY is not set); use the command-line steps instead");
    Gui g;
    g.table = t;
    g.params = params;
    g.scale = o.scale;
    g.frame = load_frame(o.gui, o.gui_frame);
    if (!o.gui_classes.empty()) g.cls = (unsigned)cyl_colortable_find_class(&g.table, o.gui_classes.front().c_str());
    std::string snapshot = o.snapshot.empty() ? o.out + ".png" : o.snapshot;
    const std::string win = "cyl-train";
    cylfe::media::named_window(win, cv::WINDOW_AUTOSIZE | cv::WINDOW_GUI_NORMAL);  // Qt: no toolbar or status bar
    cylfe::media::set_mouse_callback(win, on_mouse, &g);
    g.status = "drag a rectangle over a landmark";
    g.base = g.table;
    g.labels_path = o.save_labels;
    if (g.labels_path.empty()) {   // STEM.txt beside the image: where cyl-train learn looks for it
        size_t dot = o.gui.find_last_of('.'), slash = o.gui.find_last_of('/');
        g.labels_path = (dot != std::string::npos && (slash == std::string::npos || dot > slash) ? o.gui.substr(0, dot) : o.gui) + ".txt";
    }
    if (o.gui_learn) {
        g.learn = true;
        if (access(g.labels_path.c_str(), R_OK) == 0) {
            g.boxes = learn::read_yolo(g.labels_path, (int)g.frame.img.width, (int)g.frame.img.height);
            relearn(g);
            g.status = "loaded " + std::to_string(g.boxes.size()) + " box(es) from " + g.labels_path + "; " + g.status;
        } else {
            g.status = "learn mode: drag a box around each landmark";
        }
    }
    std::printf("cyl-train: window open (%s)\n", g.frame.label.c_str());
    std::fflush(stdout);
    for (;;) {
        if (g.dirty) {
            cylfe::media::imshow(win, render(g));
            g.dirty = false;
        }
        int k = cylfe::media::wait_key(20);
        if (k < 0) {
            if (cylfe::media::window_property(win, cv::WND_PROP_AUTOSIZE) < 0) break;  // window closed
            continue;
        }
        k &= 0xff;
        g.dirty = true;
        if (g.naming) {
            if (k == 13 || k == 10) {
                g.naming = false;
                if (!g.name_buf.empty()) {
                    int other = cyl_colortable_find_class(&g.table, g.name_buf.c_str());
                    if (other >= 0 && other != (int)g.cls)
                        g.status = "name '" + g.name_buf + "' is taken by class " + std::to_string(other);
                    else {
                        g.undo.push_back(g.table);
                        uint8_t c[3] = {g.table.rgb[g.cls][0], g.table.rgb[g.cls][1], g.table.rgb[g.cls][2]};
                        if (g.table.name[g.cls][0] == '\0') std::memcpy(c, kPalette[g.cls], 3);
                        cyl_colortable_set_class(&g.table, g.cls, g.name_buf.c_str(), c[0], c[1], c[2]);
                        g.status = "class " + std::to_string(g.cls) + " named " + g.name_buf;
                    }
                }
            } else if (k == 27) {
                g.naming = false;
            } else if (k == 8 || k == 127) {
                if (!g.name_buf.empty()) g.name_buf.pop_back();
            } else if (k > 32 && k < 127 && g.name_buf.size() + 1 < CYL_CLASS_NAME_LEN) {
                g.name_buf += (char)k;
            }
            continue;
        }
        if (k == 'q' || k == 27) break;
        if (k >= '0' && k < '0' + CYL_MAX_CLASSES) g.cls = (unsigned)(k - '0');
        else if (k == 'n') g.cls = (g.cls + 1) % CYL_MAX_CLASSES;
        else if (k == 'r') { g.naming = true; g.name_buf.clear(); }
        else if (k == 'o') g.overlay = !g.overlay;
        else if (k == 'l') {
            g.learn = !g.learn;
            if (g.learn) { g.base = g.table; g.boxes.clear(); g.undo_boxes.clear(); g.undo.clear(); }
            g.status = g.learn ? "learn mode: drag a box around each landmark (the rest is background)" : "rectangle mode";
        } else if (k == 'u') {
            if (g.undo.empty()) g.status = "nothing to undo";
            else {
                g.table = g.undo.back();
                g.undo.pop_back();
                if (g.learn && !g.undo_boxes.empty()) { g.boxes = g.undo_boxes.back(); g.undo_boxes.pop_back(); }
                g.status = "undone";
            }
        } else if (k == 'c') {
            g.undo.push_back(g.table);
            if (g.learn) {
                g.undo_boxes.push_back(g.boxes);
                std::vector<learn::Box> keep;
                for (const learn::Box &b : g.boxes)
                    if (b.label != (int)g.cls) keep.push_back(b);
                g.boxes = keep;
                relearn(g);
            } else {
                cyl_colortable_clear_class(&g.table, g.cls);
            }
            g.status = "cleared class " + std::to_string(g.cls);
        } else if (k == 's') {
            try {
                save_table(o.out, g.table);
                g.status = "saved " + o.out;
                std::printf("cyl-train: saved %s\n", o.out.c_str());
                if (g.learn && !g.boxes.empty()) {
                    learn::write_yolo(g.labels_path, g.boxes, (int)g.frame.img.width, (int)g.frame.img.height);
                    g.status += " and " + g.labels_path;
                    std::printf("cyl-train: saved %s\n", g.labels_path.c_str());
                }
            } catch (const Error &e) {
                g.status = e.what();
            }
        } else if (k == 'p') {
            try {
                std::vector<uint8_t> buf;
                cylfe::media::imencode_png(render(g), buf);
                write_file_atomic(snapshot, std::string(buf.begin(), buf.end()));
                g.status = "wrote " + snapshot;
                std::printf("cyl-train: wrote %s\n", snapshot.c_str());
            } catch (const std::exception &e) {
                g.status = e.what();
            }
        }
        std::fflush(stdout);
    }
    cylfe::media::destroy_all_windows();
    return kExitOk;
}

} // namespace

// ---- learn: classes from labelled images ------------------------------------------------------

int learn_main(int argc, char **argv)
{
    std::string out, base, report, config_out;
    double aspect_margin = 2.0, min_fill = 0.3, size_gate = 2.0, split_waist = 0.5;
    unsigned split_axes = cyl_split_params_default().axes;
    long weak_alone = -1;   // -1: auto (chosen per class on the training images)
    bool weak_fpr_given = false;
    std::vector<std::pair<std::string, cyl_landmark_size>> sizes;
    long merge_gap = 3;
    std::vector<learn::ClassSpec> classes;
    std::vector<std::string> inputs, negatives;
    learn::LearnOptions lo;
    bool quiet = false;
    try {
        for (int i = 2; i < argc; i++) {
            std::string s = argv[i];
            auto next = [&]() -> std::string {
                if (i + 1 >= argc) throw Usage(s + ": missing value");
                return argv[++i];
            };
            if (s == "-h" || s == "--help") { std::fputs(kUsage, stdout); return kExitOk; }
            else if (s == "-o" || s == "--out") out = next();
            else if (s == "--base") base = next();
            else if (s == "--report") report = next();
            else if (s == "--config-out") config_out = next();
            else if (s == "--aspect-margin") aspect_margin = parse_num(s, next(), 1, 100, false);
            else if (s == "--min-fill") min_fill = parse_num(s, next(), 0, 1, false);
            else if (s == "--split-waist") split_waist = parse_num(s, next(), 0, 1, false);
            else if (s == "--weak-alone-area") {
                const std::string v = next();
                if (v == "auto") weak_alone = -1;
                else if (v.empty() || v.find_first_not_of("0123456789") != std::string::npos)
                    throw Usage("--weak-alone-area: expected a whole number of px or auto, got '" + v + "'");
                else weak_alone = (long)parse_num(s, v, 0, 1e9, true);
            }
            else if (s == "--split-axes") {
                const std::string v = next();
                split_axes = split_axes_from_name(v);
                if (!split_axes) throw Usage("--split-axes: '" + v + "' is not rows, columns or both");
            }
            else if (s == "--size-gate") {
                size_gate = parse_num(s, next(), 0, 100, false);
                if (size_gate > 0 && size_gate < 1) throw Usage("--size-gate: 0 (off) or >= 1");
            }
            else if (s == "--size") {
                std::string v = next(), name;
                cyl_landmark_size size{};
                if (!parse_size_option(v, name, size)) throw Usage("--size: expected NAME=D,H in m, got '" + v + "'");
                sizes.push_back({name, size});
            }
            else if (s == "--merge-gap") merge_gap = (long)parse_num(s, next(), -1, 1000, true);
            else if (s == "-q" || s == "--quiet") quiet = true;
            else if (s == "--fpr") lo.params.max_bg_fraction = parse_num(s, next(), 0, 1, false);
            else if (s == "--smooth") lo.params.smooth_sigma_cells = parse_num(s, next(), 0, 2, false);
            else if (s == "--min-ratio") lo.params.min_likelihood_ratio = parse_num(s, next(), 0, 1e9, false);
            else if (s == "--inset") lo.inset = parse_num(s, next(), 0, 0.45, false);
            else if (s == "--surround") lo.surround = parse_num(s, next(), 0, 10, false);
            else if (s == "--surround-weight") lo.params.surround_weight = parse_num(s, next(), 0, 4, false);
            else if (s == "--negatives") negatives.push_back(next());
            else if (s == "--all-boxes-ignored") lo.other_boxes_negative = false;
            else if (s == "--no-weak") lo.weak = false;
            else if (s == "--gains" || s == "--colour-temps" || s == "--white-lifts") {
                const bool gains = s == "--gains", lifts = s == "--white-lifts";
                std::vector<double> &list = gains ? lo.gains : lifts ? lo.white_lifts : lo.colour_temperatures;
                std::string v = next();
                list.clear();
                size_t pos = 0;
                while (pos <= v.size()) {
                    size_t c = v.find(',', pos);
                    list.push_back(parse_num(s, v.substr(pos, c == std::string::npos ? std::string::npos : c - pos),
                                             gains ? 0.1 : lifts ? -255 : -0.45, gains ? 10 : lifts ? 255 : 1, false));
                    if (c == std::string::npos) break;
                    pos = c + 1;
                }
            }
            else if (s == "--weak-fpr") {
                lo.params.weak_bg_fraction = parse_num(s, next(), 0, 1, false);
                weak_fpr_given = true;
            }
            else if (s == "--min-share") lo.params.min_class_share = parse_num(s, next(), 0, 1, false);
            else if (s == "--unseen") lo.params.bg_uniform_weight = parse_num(s, next(), 0, 1, false);
            else if (s == "--min-weak-ratio") lo.params.min_weak_ratio = parse_num(s, next(), 0, 1e9, false);
            else if (s == "--class") {
                std::string v = next();
                size_t eq = v.find('=');
                if (eq == std::string::npos || eq == 0) throw Usage("--class: expected NAME=LABEL[@INDEX], got '" + v + "'");
                learn::ClassSpec c;
                c.name = v.substr(0, eq);
                std::string rest = v.substr(eq + 1);
                size_t at = rest.find('@');
                c.label = (int)parse_num("--class " + c.name + " label", rest.substr(0, at), 0, 1e6, true);
                if (at != std::string::npos)
                    c.index = (int)parse_num("--class " + c.name + " index", rest.substr(at + 1), 0, CYL_MAX_CLASSES - 1, true);
                if (c.name.size() >= CYL_CLASS_NAME_LEN)
                    throw Usage("--class: name must be 1.." + std::to_string(CYL_CLASS_NAME_LEN - 1) + " bytes");
                for (const auto &o : classes)
                    if (o.name == c.name) throw Usage("--class " + c.name + " given twice");
                classes.push_back(c);
            } else if (!s.empty() && s[0] == '-') throw Usage("unknown argument '" + s + "'");
            else inputs.push_back(s);
        }
        if (out.empty()) throw Usage("-o TABLE.cylt is required");
        if (!sizes.empty() && config_out.empty()) throw Usage("--size is for the detector config: give --config-out");
        // the class and its weak class together claim at least what the class alone does
        if (lo.params.weak_bg_fraction < lo.params.max_bg_fraction) {
            if (weak_fpr_given) throw Usage("--weak-fpr must be at least --fpr");
            lo.params.weak_bg_fraction = lo.params.max_bg_fraction;
        }
        if (classes.empty()) throw Usage("give at least one --class NAME=LABEL");
        if (inputs.empty()) throw Usage("give the training images (files, directories or .list files)");
    } catch (const Usage &e) {
        std::fprintf(stderr, "cyl-train: %s\n(cyl-train --help for usage)\n", e.what());
        return kExitUsage;
    }
    try {
        cyl_colortable t;
        cyl_colortable_init(&t);
        if (!base.empty()) load_table(base, t);
        std::vector<std::string> images = learn::expand_images(inputs);
        lo.negative_images = learn::expand_images(negatives);
        cylfe::Progress bar(!quiet, "learning", "images");
        const auto t0 = std::chrono::steady_clock::now();
        learn::LearnResult r = learn::learn_from_labels(t, images, classes, lo, [&](size_t k, size_t n) {
            double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            bar.update((double)k / (double)n, k, s > 0 ? (double)k / s : 0.0);
        });
        bar.done();
        save_table(out, t);
        if (!config_out.empty()) {
            DetectorConfig cfg;
            cfg.split.axes = split_axes;
            for (const learn::ClassReport &c : r.classes) {
                cfg.segment.cls[c.index].merge_gap_px = (int32_t)merge_gap;
                cfg.gate[c.index].min_fill = min_fill;
                cfg.split.waist_ratio[c.index] = split_waist;
                cfg.segment.cls[c.index].weak_alone_min_area = weak_alone > 0 ? (uint32_t)weak_alone : 0;
                if (c.aspect_max > 0) {
                    cfg.gate[c.index].aspect_min = c.aspect_min / aspect_margin;
                    cfg.gate[c.index].aspect_max = c.aspect_max * aspect_margin;
                }
            }
            for (const auto &sz : sizes) {
                int k = cyl_colortable_find_class(&t, sz.first.c_str());
                if (k < 0) throw Error("--size: the table has no class '" + sz.first + "'");
                cfg.observe.size[k] = sz.second;
                cfg.gate[k].size_gate = size_gate;
            }
            if (weak_alone < 0)
                learn::choose_weak_alone(t, images, classes, learn::kWeakAloneAreaPx, learn::kWeakAloneMaxFalsePerImage,
                                         cfg, r);
            write_file_atomic(config_out, detector_config_yaml(cfg, t, "cyl detector config written by cyl-train learn "
                                                                       "(blob shape gates from the labelled boxes)"));
        }
        if (!report.empty()) write_file_atomic(report, learn::report_json(r, t) + "\n");
        if (!quiet) {
            std::fputs(learn::report_text(r, t).c_str(), stdout);
        std::fflush(stdout);
            std::printf("wrote %s\n", out.c_str());
        }
        return kExitOk;
    } catch (const std::exception &e) {
        std::fprintf(stderr, "cyl-train: error: %s\n", e.what());
        return kExitFailure;
    }
}

int main(int argc, char **argv)
{
    if (cylfe::print_version_if_asked(argc, argv, "cyl-train")) return 0;
    if (argc >= 2 && std::string(argv[1]) == "learn") return learn_main(argc, argv);
    Opts o;
    std::vector<std::pair<std::string, std::string>> steps;  // (option, value) in order
    try {
        if (argc < 2) throw Usage("no arguments");
        for (int i = 1; i < argc; i++) {
            std::string s = argv[i];
            auto next = [&]() -> std::string {
                if (i + 1 >= argc) throw Usage(s + ": missing value");
                return argv[++i];
            };
            if (s == "-h" || s == "--help") {
                std::fputs(kUsage, stdout);
                return kExitOk;
            } else if (s == "-o" || s == "--out") o.out = next();
            else if (s == "--base") o.base = next();
            else if (s == "--gui") o.gui = next();
            else if (s == "--snapshot") o.snapshot = next();
            else if (s == "--save-labels") o.save_labels = next();
            else if (s == "--learn") o.gui_learn = true;
            else if (s == "--scale") o.scale = parse_num(s, next(), 0.25, 4, false);
            else if (s == "-q" || s == "--quiet") o.quiet = true;
            else if (s == "--replace") steps.emplace_back(s, "");
            else if (s == "--class" || s == "--index" || s == "--color" || s == "--colour" || s == "--image" ||
                     s == "--frame" || s == "--rect" || s == "--min-bin-count" || s == "--min-bin-fraction" ||
                     s == "--uv-margin" || s == "--y-margin" || s == "--y-quantiles")
                steps.emplace_back(s == "--colour" ? "--color" : s, next());
            else throw Usage("unknown argument '" + s + "'");
        }
        if (o.out.empty()) throw Usage("-o TABLE.cylt is required");
        if (o.gui.empty()) {
            bool any_rect = false;
            for (auto &st : steps) any_rect = any_rect || st.first == "--rect";
            if (!any_rect) throw Usage("nothing to train: give --class NAME --image FILE --rect X,Y,W,H (or --gui)");
        }
        // validate numbers early (bad command line -> exit 2)
        for (auto &st : steps) {
            if (st.first == "--index") parse_num(st.first, st.second, 0, CYL_MAX_CLASSES - 1, true);
            else if (st.first == "--color") parse_list(st.first, st.second, 3);
            else if (st.first == "--frame") parse_num(st.first, st.second, 0, 1e12, true);
            else if (st.first == "--rect") parse_list(st.first, st.second, 4);
            else if (st.first == "--min-bin-count") parse_num(st.first, st.second, 1, 1e9, true);
            else if (st.first == "--min-bin-fraction") parse_num(st.first, st.second, 0, 1, false);
            else if (st.first == "--uv-margin" || st.first == "--y-margin") parse_num(st.first, st.second, 0, 255, true);
            else if (st.first == "--y-quantiles") parse_list(st.first, st.second, 2);
            else if (st.first == "--class" && (st.second.empty() || st.second.size() >= CYL_CLASS_NAME_LEN))
                throw Usage("--class: name must be 1.." + std::to_string(CYL_CLASS_NAME_LEN - 1) + " bytes");
        }
    } catch (const Usage &e) {
        std::fprintf(stderr, "cyl-train: %s\n(cyl-train --help for usage)\n", e.what());
        return kExitUsage;
    }
    try {
        cyl_colortable t;
        cyl_colortable_init(&t);
        if (!o.base.empty()) load_table(o.base, t);
        cyl_train_params params = cyl_train_params_default();
        int cls = -1;
        std::string pending_class;
        std::string image;
        long frame_index = 0;
        Frame frame;
        bool frame_loaded = false;
        int trained = 0;
        auto need_class = [&](const std::string &what) {
            if (cls < 0) throw Error(what + " before any --class");
        };
        for (size_t i = 0; i < steps.size(); i++) {
            const std::string &k = steps[i].first, &v = steps[i].second;
            if (k == "--class") {
                int index = -1;
                if (i + 1 < steps.size() && steps[i + 1].first == "--index")
                    index = (int)parse_num("--index", steps[++i].second, 0, CYL_MAX_CLASSES - 1, true);
                cls = (int)select_class(t, v, index);
                if (!o.gui.empty()) o.gui_classes.push_back(v);
            } else if (k == "--index") {
                throw Error("--index must follow --class");
            } else if (k == "--color") {
                need_class("--color");
                auto c = parse_list(k, v, 3);
                for (double x : c)
                    if (x < 0 || x > 255) throw Error("--color: components 0..255");
                const std::string nm = t.name[cls];  // set_class overwrites the name it is given
                check(cyl_colortable_set_class(&t, (unsigned)cls, nm.c_str(), (uint8_t)c[0], (uint8_t)c[1], (uint8_t)c[2]),
                      "--color");
            } else if (k == "--replace") {
                need_class("--replace");
                cyl_colortable_clear_class(&t, (unsigned)cls);
            } else if (k == "--image") {
                image = v;
                frame_index = 0;
                frame_loaded = false;
            } else if (k == "--frame") {
                frame_index = (long)parse_num(k, v, 0, 1e12, true);
                frame_loaded = false;
            } else if (k == "--rect") {
                need_class("--rect");
                if (image.empty()) throw Error("--rect before any --image");
                if (!frame_loaded) {
                    frame = load_frame(image, frame_index);
                    frame_loaded = true;
                }
                auto r = parse_list(k, v, 4);
                cv::Rect rect((int)r[0], (int)r[1], (int)r[2], (int)r[3]);
                uint8_t box[6];
                train_rect(t, (unsigned)cls, frame, rect, params, box);
                trained++;
                if (!o.quiet)
                    std::printf("%-10s %s rect %s: U %3d-%3d V %3d-%3d Y %3d-%3d, classifies %.1f%% of the rectangle\n",
                                t.name[cls], frame.label.c_str(), v.c_str(), box[0], box[1], box[2], box[3], box[4],
                                box[5], 100 * class_coverage(t, (unsigned)cls, frame, rect));
            } else if (k == "--min-bin-count") params.min_bin_count = (uint32_t)parse_num(k, v, 1, 1e9, true);
            else if (k == "--min-bin-fraction") params.min_bin_fraction = parse_num(k, v, 0, 1, false);
            else if (k == "--uv-margin") params.uv_margin = (uint8_t)parse_num(k, v, 0, 255, true);
            else if (k == "--y-margin") params.y_margin = (uint8_t)parse_num(k, v, 0, 255, true);
            else if (k == "--y-quantiles") {
                auto q = parse_list(k, v, 2);
                if (!(q[0] >= 0 && q[0] < q[1] && q[1] <= 1)) throw Error("--y-quantiles: 0 <= LO < HI <= 1");
                params.y_lo_fraction = q[0];
                params.y_hi_fraction = q[1];
            }
        }
        if (!o.gui.empty()) return run_gui(o, t, params);
        save_table(o.out, t);
        if (!o.quiet) {
            std::printf("wrote %s (%d region(s)); classes:", o.out.c_str(), trained);
            for (int i = 0; i < CYL_MAX_CLASSES; i++)
                if (t.name[i][0]) std::printf(" %d=%s", i, t.name[i]);
            std::printf("\n");
        }
        return kExitOk;
    } catch (const Usage &e) {
        std::fprintf(stderr, "cyl-train: %s\n(cyl-train --help for usage)\n", e.what());
        return kExitUsage;
    } catch (const std::exception &e) {
        std::fprintf(stderr, "cyl-train: error: %s\n", e.what());
        return kExitFailure;
    }
}
