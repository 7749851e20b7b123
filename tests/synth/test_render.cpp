// SPDX-License-Identifier: BSD-3-Clause
// The synthetic camera: determinism, geometry against analytic projection, lens model against
// OpenCV, YUYV chroma subsampling, odometry noise statistics, the Source event order, scene files
// and the raw log round trip.
#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>

#include <cmath>
#include <cstdio>

#include "cylfe/error.hpp"
#include "cylfe/rawlog.hpp"
#include "cylfe/synth.hpp"
#include "cylfe/synth_experiments.hpp"

using namespace cylfe;
using namespace cylfe::synth;

namespace {

Scene quiet_scene()
{
    Scene s = empty_scene();
    s.imaging.noise_y = 0;
    s.imaging.noise_c = 0;
    s.imaging.exposure_jitter = 0;
    s.imaging.illum_amplitude = 0;
    return s;
}

Cylinder orange_at(double x, double y)
{
    Scene d = default_scene();
    Cylinder c = d.cylinders[0];
    c.x_m = x;
    c.y_m = y;
    return c;
}

} // namespace

TEST(SynthRender, DeterministicForASeed)
{
    Scene s = default_scene();
    SyntheticSource a(s, 3, 42), b(s, 3, 42), c(s, 3, 43);
    SourceEvent ea, eb, ec;
    int frames = 0;
    while (a.next(ea)) {
        ASSERT_TRUE(b.next(eb));
        ASSERT_TRUE(c.next(ec));
        ASSERT_EQ((int)ea.kind, (int)eb.kind);
        if (ea.kind == RecordType::Frame) {
            ASSERT_EQ(ea.header.size, eb.header.size);
            EXPECT_EQ(0, memcmp(ea.data, eb.data, ea.header.size)) << "same seed, frame " << ea.header.seq;
            EXPECT_NE(0, memcmp(ea.data, ec.data, ea.header.size)) << "other seed, frame " << ea.header.seq;
            frames++;
        }
        if (ea.kind == RecordType::Odometry) {
            EXPECT_EQ(ea.odometry.dx_m, eb.odometry.dx_m);
            EXPECT_EQ(ea.odometry.dtheta_rad, eb.odometry.dtheta_rad);
        }
    }
    EXPECT_EQ(frames, 3);
}

// The source generates its drive step by step (constant memory, `make soak`); it must give
// exactly the steps make_drive gives all at once.
TEST(SynthRender, SourceDriveEqualsMakeDrive)
{
    Scene s = default_scene();
    s.camera.width = 64;  // small frames: this test is about the drive, not the pixels
    s.camera.height = 48;
    const uint32_t n = 40;
    std::vector<DriveStep> d = make_drive(s, n, 9);
    SyntheticSource src(s, n, 9);
    SourceEvent ev;
    size_t k_odo = 0, k_pose = 0, k_frame = 0;
    while (src.next(ev)) {
        if (ev.kind == RecordType::Frame) {
            ASSERT_LT(k_frame, d.size());
            EXPECT_EQ(ev.header.seq, d[k_frame].seq);
            EXPECT_EQ(ev.header.t_ns, d[k_frame].t_ns);
            k_frame++;
        } else if (ev.kind == RecordType::Odometry) {
            ASSERT_LT(k_odo, d.size());
            EXPECT_EQ(ev.odometry.dx_m, d[k_odo].odo.dx_m) << "step " << k_odo;
            EXPECT_EQ(ev.odometry.dy_m, d[k_odo].odo.dy_m) << "step " << k_odo;
            EXPECT_EQ(ev.odometry.dtheta_rad, d[k_odo].odo.dtheta_rad) << "step " << k_odo;
            for (int i = 0; i < 6; i++) EXPECT_EQ(ev.odometry.cov[i], d[k_odo].odo.cov[i]);
            k_odo++;
        } else if (ev.kind == RecordType::TruthPose) {
            ASSERT_LT(k_pose, d.size());
            EXPECT_EQ(ev.truth_pose.x_m, d[k_pose].truth.x);
            EXPECT_EQ(ev.truth_pose.theta_rad, d[k_pose].truth.theta);
            k_pose++;
        }
    }
    EXPECT_EQ(k_frame, n);
    EXPECT_EQ(k_odo, n);
    EXPECT_EQ(k_pose, n);
    // odometry noise is really drawn (not all-zero errors)
    EXPECT_NE(d[5].odo.dx_m, d[5].true_dx);
}

// Golden values: the drive of seed 9 (default scene), printed with %.17g by the first
// implementation (all steps generated up front, commit 1e4df48). Streaming must not have changed the sequence: `make demo`
// and the committed fixtures depend on it.
TEST(SynthRender, DriveGoldenValues)
{
    std::vector<DriveStep> d = make_drive(default_scene(), 6, 9);
    EXPECT_DOUBLE_EQ(d[1].odo.dx_m, 0.019824666187517492);
    EXPECT_DOUBLE_EQ(d[5].odo.dy_m, -0.00018557369266475137);
    EXPECT_DOUBLE_EQ(d[5].odo.dtheta_rad, -0.0036995226961980374);
    EXPECT_DOUBLE_EQ(d[5].truth.x, 0.83973334242962261);
}

TEST(SynthRender, SourceEventOrderAndInfo)
{
    Scene s = default_scene();
    SyntheticSource src(s, 4, 1);
    EXPECT_EQ(src.info().fourcc, fourcc('Y', 'U', 'Y', 'V'));
    EXPECT_TRUE(src.info().flags & StreamInfo::kHasTruth);
    EXPECT_EQ(src.info().frame_bytes, 640u * 480u * 2u);
    size_t n_lm = 0;
    for (const Cylinder &c : s.cylinders) n_lm += c.landmark;
    EXPECT_GE(n_lm, 12u);
    SourceEvent ev;
    for (size_t i = 0; i < n_lm; i++) {
        ASSERT_TRUE(src.next(ev));
        ASSERT_EQ((int)ev.kind, (int)RecordType::TruthLandmark);
        EXPECT_LT(ev.truth_landmark.cls, 2u);
    }
    const RecordType order[3] = {RecordType::Frame, RecordType::Odometry, RecordType::TruthPose};
    for (uint64_t k = 0; k < 4; k++)
        for (int j = 0; j < 3; j++) {
            ASSERT_TRUE(src.next(ev));
            EXPECT_EQ((int)ev.kind, (int)order[j]);
            EXPECT_EQ(ev.header.seq, k);
            if (ev.kind == RecordType::Frame) {
                EXPECT_EQ(ev.image.format, CYL_FMT_YUYV);
                EXPECT_EQ(ev.image.width, 640u);
            }
        }
    EXPECT_FALSE(src.next(ev));
    EXPECT_DOUBLE_EQ(src.progress(), 1.0);
}

TEST(SynthRender, OwnUndistortionAgreesWithOpenCV)
{
    CameraModel c;
    c.k1 = -0.25; c.k2 = 0.09; c.p1 = 0.001; c.p2 = -0.0015; c.k3 = -0.01;
    cv::Mat K = (cv::Mat_<double>(3, 3) << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
    cv::Mat D = (cv::Mat_<double>(1, 5) << c.k1, c.k2, c.p1, c.p2, c.k3);
    std::vector<cv::Point2d> src, dst;
    for (int v = 0; v < 480; v += 40)
        for (int u = 0; u < 640; u += 40) src.push_back(cv::Point2d(u, v));
    cv::undistortPoints(src, dst, K, D, cv::noArray(), cv::noArray(),
                        cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 200, 1e-15));
    double worst = 0;
    for (size_t i = 0; i < src.size(); i++) {
        double x, y;
        ASSERT_TRUE(undistort(c, (src[i].x - c.cx) / c.fx, (src[i].y - c.cy) / c.fy, &x, &y));
        worst = std::max(worst, std::hypot(x - dst[i].x, y - dst[i].y));
        double xd, yd;
        distort(c, x, y, &xd, &yd);
        EXPECT_NEAR(c.cx + c.fx * xd, src[i].x, 1e-8);
    }
    EXPECT_LT(worst, 1e-7);
}

// The centre of a rendered cylinder's blob against the analytic projection of its centre, over the
// field of view, with strong distortion so that ignoring the lens would fail by pixels.
TEST(SynthRender, BlobCentroidMatchesProjection)
{
    Scene s = quiet_scene();
    s.camera.k1 = -0.22;
    s.camera.k2 = 0.08;
    Scene d = default_scene();
    s.classes = d.classes;
    s.cylinders.push_back(d.cylinders[0]);  // for the colour table's prototype
    cyl_colortable t;
    train_colortable(s, &t, 3);
    Renderer ren(s);
    Detect det(t, s);
    const Pose2 robot{0, 0, 0};
    CameraPose cp = camera_pose(s.camera, robot);
    std::vector<uint8_t> f;
    const double pos[][2] = {{1.2, 0.0}, {2.0, 0.55}, {2.0, -0.6}, {3.0, 1.0}, {1.5, -0.6}, {3.5, -1.2}};
    double max_lens_effect = 0;
    for (auto &p : pos) {
        Cylinder c = orange_at(p[0], p[1]);
        ren.mutable_scene().cylinders.assign(1, c);
        ren.render_yuyv(robot, 1.0, 1, f);
        det.segment(f.data());
        const cyl_segmentation &seg = det.seg();
        ASSERT_EQ(seg.class_count[0], 1u) << "at " << p[0] << "," << p[1];
        const cyl_blob &b = seg.blobs[seg.class_first[0]];
        double pc[3] = {c.x_m, c.y_m, c.height_m / 2}, u, v;
        ASSERT_TRUE(project_point(s.camera, cp, pc, &u, &v));
        EXPECT_NEAR(b.cx_px, u, 0.5) << "at " << p[0] << "," << p[1];
        EXPECT_NEAR(b.cy_px, v, 1.5) << "at " << p[0] << "," << p[1];
        // the same point without the lens model
        CameraModel pin = s.camera;
        pin.k1 = pin.k2 = 0;
        double u0, v0;
        project_point(pin, cp, pc, &u0, &v0);
        max_lens_effect = std::max(max_lens_effect, std::hypot(u - u0, v - v0));
        // the blob's size: a cylinder of diameter D at distance r spans about fx D / r columns
        double r = std::hypot(c.x_m - cp.c[0], c.y_m - cp.c[1]);
        EXPECT_NEAR(b.x1 - b.x0 + 1, s.camera.fx * c.diameter_m / r, 0.25 * s.camera.fx * c.diameter_m / r + 2);
    }
    EXPECT_GT(max_lens_effect, 5.0) << "the test positions must exercise the lens model";
}

TEST(SynthRender, YuyvChromaSubsampling)
{
    Scene s = quiet_scene();
    s.cylinders.push_back(orange_at(1.5, 0.02));
    Renderer ren(s);
    CleanFrame cf;
    ren.render_clean(Pose2{0, 0, 0}, 1.0, cf);
    std::vector<uint8_t> f;
    ren.finish_yuyv(cf, 5, f);
    ASSERT_EQ(f.size(), 640u * 480u * 2u);
    cyl_image img;
    ASSERT_EQ(cyl_image_wrap(&img, CYL_FMT_YUYV, 640, 480, f.data(), 0), CYL_OK);
    auto q = [](double x) { return (int)std::min(255.0, std::max(0.0, std::floor(x + 0.5))); };
    int chroma_edges = 0;
    for (uint32_t y = 0; y < 480; y += 7)
        for (uint32_t x = 0; x < 640; x += 2) {
            size_t i = (size_t)y * 640 + x;
            uint8_t Y0, U0, V0, Y1, U1, V1;
            ASSERT_EQ(cyl_image_pixel(&img, x, y, &Y0, &U0, &V0), CYL_OK);
            ASSERT_EQ(cyl_image_pixel(&img, x + 1, y, &Y1, &U1, &V1), CYL_OK);
            // luma per pixel, one chroma pair shared by two pixels = the mean of the two
            EXPECT_NEAR(Y0, q(cf.y[i]), 1);
            EXPECT_NEAR(Y1, q(cf.y[i + 1]), 1);
            EXPECT_EQ(U0, U1);
            EXPECT_EQ(V0, V1);
            EXPECT_NEAR(U0, q(0.5 * (cf.u[i] + cf.u[i + 1])), 1);
            EXPECT_NEAR(V0, q(0.5 * (cf.v[i] + cf.v[i + 1])), 1);
            EXPECT_EQ(f[2 * i], Y0);
            EXPECT_EQ(f[2 * i + 1], U0);
            EXPECT_EQ(f[2 * i + 2], Y1);
            EXPECT_EQ(f[2 * i + 3], V0);
            if (std::fabs(cf.u[i] - cf.u[i + 1]) > 4) chroma_edges++;
        }
    EXPECT_GT(chroma_edges, 5) << "the frame must contain chroma edges inside pixel pairs";
}

TEST(SynthRender, SensorNoiseLevel)
{
    Scene s = quiet_scene();
    s.imaging.noise_y = 3.0;
    s.imaging.noise_c = 4.0;
    s.imaging.blur_sigma_px = 0;
    s.imaging.chroma_blur_px = 0;
    s.room.floor_texture = 0;
    Renderer ren(s);
    CleanFrame cf;
    ren.render_clean(Pose2{0, 0, 0}, 1.0, cf);
    std::vector<uint8_t> a, b;
    ren.finish_yuyv(cf, 1, a);
    ren.finish_yuyv(cf, 2, b);
    // difference of two frames on the floor (bottom half): var = 2 sigma^2 (+ quantisation)
    double sy = 0, su = 0;
    size_t ny = 0, nu = 0;
    for (size_t i = 640 * 2 * 300; i < a.size(); i += 2) {
        double d = (double)a[i] - b[i];
        if (i % 4 == 0) { sy += d * d; ny++; }
        double dc = (double)a[i + 1] - b[i + 1];
        su += dc * dc; nu++;
    }
    EXPECT_NEAR(std::sqrt(sy / ny / 2), 3.0, 0.15);
    EXPECT_NEAR(std::sqrt(su / nu / 2), 4.0 / std::sqrt(2.0), 0.15);  // chroma averaged over 2 px
}

TEST(SynthDrive, OdometryNoiseStatistics)
{
    Scene s = default_scene();
    std::vector<DriveStep> d = make_drive(s, 20000, 11);
    double nees = 0, m[3] = {0, 0, 0};
    double dist = 0;
    for (size_t k = 1; k < d.size(); k++) {
        const DriveStep &st = d[k];
        double e[3] = {st.odo.dx_m - st.true_dx, st.odo.dy_m - st.true_dy, st.odo.dtheta_rad - st.true_dtheta};
        const double *c = st.odo.cov;  // xx xy xt yy yt tt
        EXPECT_EQ(c[2], 0.0);
        EXPECT_EQ(c[4], 0.0);
        double det = c[0] * c[3] - c[1] * c[1];
        ASSERT_GT(det, 0);
        double q = (c[3] * e[0] * e[0] - 2 * c[1] * e[0] * e[1] + c[0] * e[1] * e[1]) / det + e[2] * e[2] / c[5];
        nees += q;
        m[0] += e[0] / std::sqrt(c[0]);
        m[1] += e[1] / std::sqrt(c[3]);
        m[2] += e[2] / std::sqrt(c[5]);
        dist += std::hypot(st.true_dx, st.true_dy);
        // the sigma grows with the distance travelled
        double dd = std::hypot(st.true_dx, st.true_dy);
        EXPECT_NEAR(std::sqrt(c[0] + c[3]), std::hypot(s.odometry.k_long * dd + s.odometry.min_xy,
                                                        s.odometry.k_lat * dd + s.odometry.min_xy), 1e-12);
    }
    double n = d.size() - 1;
    EXPECT_NEAR(nees / n, 3.0, 0.12);  // chi-square(3) mean; sd of the mean 0.017
    for (double v : m) EXPECT_NEAR(v / n, 0.0, 0.04);
    // the truth follows the trajectory at the configured speed
    EXPECT_NEAR(dist, s.trajectory.speed_mps * n / s.trajectory.fps, 0.01 * dist);
    EXPECT_EQ(d[0].odo.dx_m, 0.0);
}

TEST(SynthScene, FileRoundTripAndErrors)
{
    Scene s = default_scene();
    s.camera.tilt_rad = 0.2;
    const char *path = "/tmp/cyl_synth_scene_test.yaml";
    save_scene(path, s);
    Scene r = load_scene(path);
    ASSERT_EQ(r.cylinders.size(), s.cylinders.size());
    ASSERT_EQ(r.boxes.size(), s.boxes.size());
    ASSERT_EQ(r.patches.size(), s.patches.size());
    EXPECT_NEAR(r.camera.tilt_rad, 0.2, 1e-9);
    EXPECT_NEAR(r.cylinders[3].x_m, s.cylinders[3].x_m, 1e-12);
    EXPECT_EQ(r.cylinders[3].cls, s.cylinders[3].cls);
    EXPECT_EQ(r.cylinders.back().landmark, false);
    EXPECT_EQ(r.boxes[2].cls, -1);
    // the same frames from the loaded scene
    std::vector<uint8_t> fa, fb;
    Renderer(s).render_yuyv(Pose2{0.5, 0.2, 0.3}, 1.0, 9, fa);
    Renderer(r).render_yuyv(Pose2{0.5, 0.2, 0.3}, 1.0, 9, fb);
    size_t diff = 0;
    for (size_t i = 0; i < fa.size(); i++) diff += fa[i] != fb[i];
    EXPECT_LT(diff, fa.size() / 1000) << "scene file must reproduce the scene (up to text rounding)";
    FILE *f = fopen(path, "w");
    fputs("%YAML:1.0\n---\nclasses: [red]\ncylinders:\n  - { class: blue, x_m: 1.0, y_m: 0 }\n", f);
    fclose(f);
    try {
        load_scene(path);
        FAIL() << "unknown class accepted";
    } catch (const Error &e) {
        EXPECT_NE(std::string(e.what()).find("blue"), std::string::npos);
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
    }
    remove(path);
}

TEST(SynthRawLog, RoundTrip)
{
    Scene s = default_scene();
    s.imaging.samples = 1;
    const char *path = "/tmp/cyl_synth_test.cylraw";
    std::vector<std::vector<uint8_t>> frames;
    std::vector<Odometry> odo;
    {
        SyntheticSource src(s, 3, 5);
        RawLogWriter w(path, src.info());
        SourceEvent ev;
        while (src.next(ev)) {
            if (ev.kind == RecordType::Frame) {
                w.frame(ev.header.seq, ev.header.t_ns, ev.data, ev.header.size);
                frames.emplace_back(ev.data, ev.data + ev.header.size);
            } else if (ev.kind == RecordType::Odometry) {
                w.odometry(ev.header.seq, ev.header.t_ns, ev.odometry);
                odo.push_back(ev.odometry);
            } else if (ev.kind == RecordType::TruthPose) {
                w.truth_pose(ev.header.seq, ev.header.t_ns, ev.truth_pose);
            } else {
                w.truth_landmark(ev.header.t_ns, ev.truth_landmark);
            }
        }
        w.close();
    }
    RawLogReader r(path);
    EXPECT_TRUE(r.info().flags & StreamInfo::kHasTruth);
    RecordHeader h;
    std::vector<uint8_t> p;
    size_t nf = 0, no = 0, nl = 0;
    while (r.next(h, p)) {
        if (h.type == RecordType::Frame) { ASSERT_LT(nf, frames.size()); EXPECT_TRUE(p == frames[nf]); nf++; }
        if (h.type == RecordType::Odometry) { Odometry o = RawLogReader::parse_odometry(p); EXPECT_EQ(o.dx_m, odo[no].dx_m); EXPECT_EQ(o.cov[5], odo[no].cov[5]); no++; }
        if (h.type == RecordType::TruthLandmark) nl++;
    }
    EXPECT_EQ(nf, 3u);
    EXPECT_EQ(no, 3u);
    EXPECT_GE(nl, 12u);
    remove(path);
}

TEST(SynthScene, CalibrationErrorDrawnFromTheSigmas)
{
    Scene s = default_scene();
    const int n = 4000;
    double st = 0, st2 = 0, sf2 = 0;
    for (int i = 0; i < n; i++) {
        CameraModel e = perturb_camera(s.camera, s.sigmas, (uint64_t)i);
        double dt = (e.tilt_rad - s.camera.tilt_rad) / s.sigmas.tilt_rad;
        st += dt;
        st2 += dt * dt;
        double df = (e.fx - s.camera.fx) / s.sigmas.fx;
        sf2 += df * df;
        EXPECT_EQ(e.width, s.camera.width);
    }
    EXPECT_NEAR(st / n, 0.0, 0.06);
    EXPECT_NEAR(std::sqrt(st2 / n), 1.0, 0.04);
    EXPECT_NEAR(std::sqrt(sf2 / n), 1.0, 0.04);
    CameraModel a = perturb_camera(s.camera, s.sigmas, 5), b = perturb_camera(s.camera, s.sigmas, 5);
    EXPECT_EQ(a.tilt_rad, b.tilt_rad);
}
