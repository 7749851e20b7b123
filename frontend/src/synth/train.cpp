// SPDX-License-Identifier: BSD-3-Clause
// Colour table for a synthetic scene: trained by libcyl's cyl_colortable_train on rendered
// frames of the scene's landmark colours (paper section 3.3: operator regions over several
// images and illuminations; here the region is the inner part of a landmark's projection).
#include "cylfe/synth_experiments.hpp"
#include "cylfe/error.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace cylfe {
namespace synth {

namespace {
constexpr double kPi = 3.14159265358979323846;
const uint8_t kDisplay[][3] = {{255, 128, 0}, {0, 200, 60}, {40, 80, 255}, {255, 230, 0},
                               {200, 0, 200}, {0, 220, 220}, {255, 255, 255}, {128, 128, 128}};
} // namespace

void train_colortable(const Scene &scene, cyl_colortable *t, uint64_t seed, std::string *log,
                      const cyl_train_params *params)
{
    cyl_colortable_init(t);
    for (size_t c = 0; c < scene.classes.size() && c < CYL_MAX_CLASSES; c++)
        check(cyl_colortable_set_class(t, (unsigned)c, scene.classes[c].c_str(), kDisplay[c][0], kDisplay[c][1],
                                       kDisplay[c][2]),
              "colour table class");
    // One colour per class: the first one-colour landmark of the class, else the first band of it.
    Scene s = empty_scene();
    s.camera = scene.camera;
    s.imaging = scene.imaging;
    s.room = scene.room;
    std::vector<uint8_t> work(cyl_train_workspace_size()), frame;
    std::vector<uint32_t> work32((work.size() + 3) / 4);
    cyl_train_params tp = cyl_train_params_default();
    // A stricter histogram threshold and a 1-bin margin than libcyl's defaults (0.002, 3): the
    // chroma noise tails otherwise push the table's boundary towards the background colour and
    // every blob grows by a noisy pixel or two on each side (docs/synthetic.md).
    tp.min_bin_fraction = 0.02;
    tp.uv_margin = 1;
    if (params) tp = *params;
    for (size_t c = 0; c < scene.classes.size() && c < CYL_MAX_CLASSES; c++) {
        const Cylinder *proto = nullptr;
        Cylinder from_band;
        for (const Cylinder &cy : scene.cylinders)
            if (cy.cls == (int32_t)c && cy.landmark && cy.bands.empty()) { proto = &cy; break; }
        // No one-colour landmark of the class: a band of that class (a striped or coded landmark)
        // stands for it, as a plain cylinder of the band's colour and the landmark's size.
        for (size_t i = 0; !proto && i < scene.cylinders.size(); i++) {
            const Cylinder &cy = scene.cylinders[i];
            if (!cy.landmark) continue;
            for (const Band &b : cy.bands)
                if (b.cls == (int32_t)c) {
                    from_band = cy;
                    from_band.cls = b.cls;
                    from_band.colour = b.colour;
                    from_band.bands.clear();
                    from_band.diameter_top_m = -1;
                    proto = &from_band;
                    break;
                }
        }
        if (!proto) continue;
        // Training views: the landmark seen from 8 directions around it (so that lit and shaded
        // sides are both in view), at three ranges, off-centre, under five exposures.
        const double ranges[] = {1.2, 2.2, 3.2};
        const double gains[] = {0.8, 0.92, 1.0, 1.1, 1.22};
        int n = 0;
        Renderer ren(s);
        for (int az = 0; az < 8; az++)
            for (double r : ranges)
                for (double g : gains) {
                    Cylinder cy = *proto;
                    cy.x_m = 0;
                    cy.y_m = 0;
                    ren.mutable_scene().cylinders.assign(1, cy);
                    double phi = 2 * kPi * az / 8 + 0.3 * r, bearing = 0.25 * std::sin(1.7 * az + r);
                    // robot placed so that the landmark is at range r and the given bearing
                    double heading = phi + kPi + bearing;
                    Pose2 rb{r * std::cos(phi) - s.camera.offset_m * std::cos(heading),
                             r * std::sin(phi) - s.camera.offset_m * std::sin(heading), heading};
                    ren.render_yuyv(rb, g, mix_seed(seed, c, n++), frame);
                    CameraPose cp = camera_pose(s.camera, rb);
                    double pc[3] = {cy.x_m, cy.y_m, cy.height_m / 2}, u, v;
                    if (!project_point(s.camera, cp, pc, &u, &v)) continue;
                    double wpx = s.camera.fx * cy.diameter_m / r, hpx = s.camera.fy * cy.height_m / r;
                    // the operator's region: the inner half of the width, 60% of the height (clear of the
                    // blurred edges, as an operator would draw it)
                    cyl_roi roi;
                    roi.width = (uint32_t)std::max(2.0, 0.5 * wpx - 2);
                    roi.height = (uint32_t)std::max(2.0, 0.6 * hpx);
                    roi.x = (uint32_t)std::max(0.0, u - roi.width / 2.0);
                    roi.y = (uint32_t)std::max(0.0, v - roi.height / 2.0);
                    if (roi.x + roi.width > s.camera.width || roi.y + roi.height > s.camera.height) continue;
                    cyl_image img;
                    check(cyl_image_wrap(&img, CYL_FMT_YUYV, s.camera.width, s.camera.height, frame.data(), 0),
                          "training frame");
                    uint8_t box[6];
                    cyl_status st = cyl_colortable_train(t, (unsigned)c, &img, &roi, &tp, work32.data(),
                                                         work32.size() * 4, box);
                    if (st < 0 && st != CYL_ERR_EMPTY) check(st, "cyl_colortable_train");
                    if (log && st == CYL_OK) {
                        char buf[160];
                        snprintf(buf, sizeof buf, "%s az=%d r=%.1f g=%.2f: U %d-%d V %d-%d Y %d-%d\n",
                                 scene.classes[c].c_str(), az, r, g, box[0], box[1], box[2], box[3], box[4], box[5]);
                        *log += buf;
                    }
                }
    }
    (void)kPi;
}

} // namespace synth
} // namespace cylfe
