// SPDX-License-Identifier: BSD-3-Clause
// Robot trajectory, odometry with a documented noise model, and the SyntheticSource.
#include "cylfe/synth.hpp"
#include "cylfe/error.hpp"
#include "random.hpp"

#include <algorithm>
#include <cmath>

namespace cylfe {
namespace synth {

namespace {
constexpr double kPi = 3.14159265358979323846;

using detail::wrap;

void curve(const TrajectoryParams &p, double ph, double *x, double *y, double *dx, double *dy)
{
    if (p.type == "ellipse") {
        *x = p.centre_x_m + p.a_m * std::cos(ph);
        *y = p.centre_y_m + p.b_m * std::sin(ph);
        *dx = -p.a_m * std::sin(ph);
        *dy = p.b_m * std::cos(ph);
    } else {  // figure8: x = a sin p, y = b sin p cos p
        *x = p.centre_x_m + p.a_m * std::sin(ph);
        *y = p.centre_y_m + 0.5 * p.b_m * std::sin(2 * ph);
        *dx = p.a_m * std::cos(ph);
        *dy = p.b_m * std::cos(2 * ph);
    }
}

// Arc-length table of one period of the curve.
struct ArcTable {
    std::vector<double> s;  // cumulative length at phase k * 2 pi / N
    double length = 0;
    static constexpr int N = 20000;
    explicit ArcTable(const TrajectoryParams &p)
    {
        s.resize(N + 1);
        s[0] = 0;
        for (int k = 0; k < N; k++) {
            double ph = 2 * kPi * (k + 0.5) / N, x, y, dx, dy;
            curve(p, ph, &x, &y, &dx, &dy);
            s[k + 1] = s[k] + std::hypot(dx, dy) * 2 * kPi / N;
        }
        length = s[N];
    }
    double phase(double dist) const
    {
        double d = std::fmod(dist, length);
        if (d < 0) d += length;
        size_t k = std::upper_bound(s.begin(), s.end(), d) - s.begin();
        if (k == 0) k = 1;
        if (k > (size_t)N) k = N;
        double f = (d - s[k - 1]) / std::max(1e-15, s[k] - s[k - 1]);
        return 2 * kPi * (k - 1 + f) / N;
    }
};

using detail::splitmix;

using Gauss = detail::NormalStream;  // standard normal from a seeded stream

} // namespace

Pose2 trajectory_pose(const TrajectoryParams &p, double dist)
{
    static thread_local std::unique_ptr<ArcTable> tab;
    static thread_local TrajectoryParams tab_p;
    if (!tab || tab_p.type != p.type || tab_p.a_m != p.a_m || tab_p.b_m != p.b_m) {
        tab.reset(new ArcTable(p));
        tab_p = p;
    }
    double d0 = 0;
    {   // arc length at the start phase
        double ph0 = std::fmod(p.phase0, 2 * kPi);
        if (ph0 < 0) ph0 += 2 * kPi;
        double k = ph0 / (2 * kPi) * ArcTable::N;
        size_t i = (size_t)k;
        d0 = tab->s[i] + (k - i) * (tab->s[std::min(i + 1, (size_t)ArcTable::N)] - tab->s[i]);
    }
    double ph = tab->phase(d0 + dist), x, y, dx, dy;
    curve(p, ph, &x, &y, &dx, &dy);
    return Pose2{x, y, std::atan2(dy, dx)};
}

void pose_between(const Pose2 &a, const Pose2 &b, double *dx, double *dy, double *dth)
{
    double c = std::cos(a.theta), s = std::sin(a.theta);
    double ex = b.x - a.x, ey = b.y - a.y;
    *dx = c * ex + s * ey;
    *dy = -s * ex + c * ey;
    *dth = wrap(b.theta - a.theta);
}

void odometry_covariance(const OdometryNoise &n, double dx, double dy, double dth, double cov[6])
{
    double d = std::hypot(dx, dy);
    double sl = n.k_long * d + n.min_xy, sa = n.k_lat * d + n.min_xy;
    double st = n.k_rot * std::fabs(dth) + n.k_rot_d * d + n.min_theta;
    double phi = d > 1e-12 ? std::atan2(dy, dx) : 0.0, c = std::cos(phi), s = std::sin(phi);
    // R diag(sl^2, sa^2) R^T
    cov[0] = c * c * sl * sl + s * s * sa * sa;  // xx
    cov[1] = c * s * (sl * sl - sa * sa);        // xy
    cov[2] = 0;                                  // xt
    cov[3] = s * s * sl * sl + c * c * sa * sa;  // yy
    cov[4] = 0;                                  // yt
    cov[5] = st * st;                            // tt
}

DriveGenerator::DriveGenerator(const Scene &s, uint64_t seed)
    : tp_(s.trajectory), noise_(s.odometry), rng_(mix_seed(seed, 0x0D0Du, 1))
{
    if (tp_.fps <= 0 || tp_.speed_mps < 0) throw Error("synthetic scene: trajectory fps must be > 0 and speed >= 0");
}

DriveStep DriveGenerator::next()
{
    DriveStep st;
    const uint64_t k = k_++;
    st.seq = k;
    double t = (double)k / tp_.fps;
    st.t_ns = (int64_t)std::llround(t * 1e9);
    st.truth = trajectory_pose(tp_, tp_.speed_mps * t);
    if (k == 0) {
        odometry_covariance(noise_, 0, 0, 0, st.odo.cov);
    } else {
        Gauss g(rng_);
        pose_between(prev_, st.truth, &st.true_dx, &st.true_dy, &st.true_dtheta);
        odometry_covariance(noise_, st.true_dx, st.true_dy, st.true_dtheta, st.odo.cov);
        double d = std::hypot(st.true_dx, st.true_dy);
        double phi = d > 1e-12 ? std::atan2(st.true_dy, st.true_dx) : 0.0;
        double sl = noise_.k_long * d + noise_.min_xy, sa = noise_.k_lat * d + noise_.min_xy;
        double sth = std::sqrt(st.odo.cov[5]);
        double el = sl * g(), ea = sa * g(), et = sth * g();
        rng_ = g.st;
        st.odo.dx_m = st.true_dx + std::cos(phi) * el - std::sin(phi) * ea;
        st.odo.dy_m = st.true_dy + std::sin(phi) * el + std::cos(phi) * ea;
        st.odo.dtheta_rad = st.true_dtheta + et;
    }
    prev_ = st.truth;
    return st;
}

std::vector<DriveStep> make_drive(const Scene &s, uint32_t frames, uint64_t seed)
{
    DriveGenerator gen(s, seed);
    std::vector<DriveStep> out;
    out.reserve(frames);
    for (uint32_t k = 0; k < frames; k++) out.push_back(gen.next());
    return out;
}

// ---- SyntheticSource ----------------------------------------------------------------------

SyntheticSource::SyntheticSource(const Scene &s, uint32_t frames, uint64_t seed)
    : scene_(s), renderer_(s), seed_(seed), drive_(s, seed), frames_(frames)
{
    for (const Cylinder &c : scene_.cylinders) {
        if (!c.landmark) continue;
        TruthLandmark l;
        l.id = c.id;
        l.cls = c.cls < 0 ? 0xFFFFFFFFu : (uint32_t)c.cls;
        l.x_m = c.x_m; l.y_m = c.y_m; l.diameter_m = c.diameter_m; l.height_m = c.height_m;
        landmarks_.push_back(l);
    }
    info_.fourcc = fourcc('Y', 'U', 'Y', 'V');
    info_.width = scene_.camera.width;
    info_.height = scene_.camera.height;
    info_.stride = scene_.camera.width * 2;
    info_.frame_bytes = info_.stride * info_.height;
    info_.flags = StreamInfo::kHasTruth | StreamInfo::kMonotonic;
    info_.source = "synthetic seed " + std::to_string(seed);
    if (info_.source.size() > 23) info_.source.resize(23);
}

double SyntheticSource::progress() const
{
    return frames_ == 0 ? 1.0 : (double)step_ / (double)frames_;
}

bool SyntheticSource::next(SourceEvent &ev)
{
    ev = SourceEvent{};
    if (lm_next_ < landmarks_.size()) {
        ev.kind = RecordType::TruthLandmark;
        ev.header.type = ev.kind;
        ev.header.seq = 0;
        ev.header.t_ns = 0;
        ev.header.size = 8 + 4 * 8;
        ev.truth_landmark = landmarks_[lm_next_++];
        return true;
    }
    if (step_ >= frames_) return false;
    if (phase_ == 0) cur_ = drive_.next();  // step_ == cur_.seq from here to the truth pose
    const DriveStep &st = cur_;
    ev.header.seq = st.seq;
    ev.header.t_ns = st.t_ns;
    if (phase_ == 0) {
        double gain = renderer_.frame_gain(seed_, st.seq, st.t_ns * 1e-9);
        renderer_.render_clean(st.truth, gain, clean_, st.t_ns * 1e-9);
        renderer_.finish_yuyv(clean_, mix_seed(seed_, st.seq, 0x5EED), frame_);
        ev.kind = RecordType::Frame;
        ev.header.type = ev.kind;
        ev.header.size = (uint32_t)frame_.size();
        ev.data = frame_.data();
        check(cyl_image_wrap(&ev.image, CYL_FMT_YUYV, info_.width, info_.height, frame_.data(), info_.stride),
              "synthetic frame");
        phase_ = 1;
    } else if (phase_ == 1) {
        ev.kind = RecordType::Odometry;
        ev.header.type = ev.kind;
        ev.header.size = 9 * 8;
        ev.odometry = st.odo;
        phase_ = 2;
    } else {
        ev.kind = RecordType::TruthPose;
        ev.header.type = ev.kind;
        ev.header.size = 3 * 8;
        ev.truth_pose.x_m = st.truth.x;
        ev.truth_pose.y_m = st.truth.y;
        ev.truth_pose.theta_rad = st.truth.theta;
        phase_ = 0;
        step_++;
    }
    return true;
}

} // namespace synth
} // namespace cylfe
