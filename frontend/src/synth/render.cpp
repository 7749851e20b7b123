// SPDX-License-Identifier: BSD-3-Clause
// Ray-casting renderer of the synthetic scene (docs/synthetic.md). Own lens and mounting code:
// nothing here calls libcyl's camera model.
#include "cylfe/synth.hpp"
#include "cylfe/error.hpp"
#include "corners.hpp"
#include "random.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace cylfe {
namespace synth {

namespace {

constexpr double kPi = 3.14159265358979323846;

using detail::splitmix;

struct Xoshiro {
    uint64_t s[4]{};
    explicit Xoshiro(uint64_t seed) { for (auto &v : s) v = splitmix(seed); }
    static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
    uint64_t next()
    {
        uint64_t r = rotl(s[1] * 5, 7) * 9, t = s[1] << 17;
        s[2] ^= s[0]; s[3] ^= s[1]; s[1] ^= s[2]; s[0] ^= s[3];
        s[2] ^= t; s[3] = rotl(s[3], 45);
        return r;
    }
};

// Inverse standard normal CDF (Acklam's rational approximation refined by one Halley step).
double inv_norm(double p)
{
    static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02,
                               1.383577518672690e+02, -3.066479806614716e+01, 2.506628277459239e+00};
    static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                               6.680131188771972e+01, -1.328068155288572e+01};
    static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                               -2.549732539343734e+00, 4.374664141464968e+00, 2.938163982698783e+00};
    static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                               3.754408661907416e+00};
    double q, r, x;
    if (p < 0.02425) {
        q = std::sqrt(-2 * std::log(p));
        x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
            ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
    } else if (p > 1 - 0.02425) {
        q = std::sqrt(-2 * std::log(1 - p));
        x = -(((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
            ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
    } else {
        q = p - 0.5;
        r = q * q;
        x = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
            (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
    }
    double e = 0.5 * std::erfc(-x / std::sqrt(2.0)) - p;
    double u = e * std::sqrt(2 * kPi) * std::exp(x * x / 2);
    return x - u / (1 + x * u / 2);
}

// 65536 equiprobable normal quantiles: indexing with 16 random bits samples N(0,1) (exactly in
// distribution up to the table's resolution; variance 1 to 2e-4).
const std::vector<float> &normal_table()
{
    static const std::vector<float> t = [] {
        std::vector<float> v(65536);
        for (int i = 0; i < 65536; i++) v[i] = (float)inv_norm((i + 0.5) / 65536.0);
        return v;
    }();
    return t;
}

inline double dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

struct Hit {
    double t = std::numeric_limits<double>::infinity();
    double n[3] = {0, 0, 1};
    Yuv col;
};

void gaussian_kernel(double sigma, std::vector<float> &k)
{
    k.clear();
    if (sigma <= 0.05) { k.push_back(1.f); return; }
    int r = (int)std::ceil(3.0 * sigma);
    double s = 0;
    for (int i = -r; i <= r; i++) { double w = std::exp(-0.5 * i * i / (sigma * sigma)); k.push_back((float)w); s += w; }
    for (auto &w : k) w = (float)(w / s);
}

// Separable convolution with clamped borders; horizontal kernel kh, vertical kv.
// tmp: scratch, reused across calls (no per-frame allocation of a plane)
void blur_plane(std::vector<float> &p, uint32_t w, uint32_t h, const std::vector<float> &kh,
                const std::vector<float> &kv, std::vector<float> &tmp)
{
    tmp.resize(p.size());
    int rh = (int)kh.size() / 2, rv = (int)kv.size() / 2;
    if (rh > 0) {
        std::vector<float> pad(w + 2 * rh);
        for (uint32_t y = 0; y < h; y++) {
            const float *src = &p[(size_t)y * w];
            for (int i = 0; i < rh; i++) { pad[i] = src[0]; pad[w + rh + i] = src[w - 1]; }
            std::copy(src, src + w, pad.begin() + rh);
            float *dst = &tmp[(size_t)y * w];
            std::fill(dst, dst + w, 0.f);
            for (int k = 0; k <= 2 * rh; k++) {
                const float wk = kh[k];
                const float *s = &pad[k];
                for (uint32_t x = 0; x < w; x++) dst[x] += wk * s[x];
            }
        }
    } else {
        tmp = p;
    }
    if (rv > 0) {
        for (int y = 0; y < (int)h; y++) {
            float *dst = &p[(size_t)y * w];
            std::fill(dst, dst + w, 0.f);
            for (int k = -rv; k <= rv; k++) {
                int yy = std::min(std::max(y + k, 0), (int)h - 1);
                const float *src = &tmp[(size_t)yy * w];
                float wk = kv[k + rv];
                for (uint32_t x = 0; x < w; x++) dst[x] += wk * src[x];
            }
        }
    } else {
        p = tmp;
    }
}

} // namespace

uint64_t mix_seed(uint64_t seed, uint64_t a, uint64_t b)
{
    uint64_t x = seed ^ 0x5851F42D4C957F2Dull;
    uint64_t r = splitmix(x);
    x = r ^ (a * 0x9E3779B97F4A7C15ull);
    r = splitmix(x);
    x = r ^ (b * 0xD1B54A32D192ED03ull);
    return splitmix(x);
}

void distort(const CameraModel &c, double x, double y, double *xd, double *yd)
{
    double r2 = x * x + y * y;
    double rad = 1 + r2 * (c.k1 + r2 * (c.k2 + r2 * c.k3));
    *xd = x * rad + 2 * c.p1 * x * y + c.p2 * (r2 + 2 * x * x);
    *yd = y * rad + c.p1 * (r2 + 2 * y * y) + 2 * c.p2 * x * y;
}

bool undistort(const CameraModel &c, double xd, double yd, double *xo, double *yo)
{
    double x = xd, y = yd;
    for (int it = 0; it < 40; it++) {
        double r2 = x * x + y * y;
        double rad = 1 + r2 * (c.k1 + r2 * (c.k2 + r2 * c.k3));
        double drad = c.k1 + r2 * (2 * c.k2 + 3 * c.k3 * r2);  // d rad / d r2
        double fx = x * rad + 2 * c.p1 * x * y + c.p2 * (r2 + 2 * x * x) - xd;
        double fy = y * rad + c.p1 * (r2 + 2 * y * y) + 2 * c.p2 * x * y - yd;
        double a = rad + 2 * x * x * drad + 2 * c.p1 * y + 6 * c.p2 * x;
        double b = 2 * x * y * drad + 2 * c.p1 * x + 2 * c.p2 * y;
        double cc = b;  // the Jacobian is symmetric
        double d = rad + 2 * y * y * drad + 6 * c.p1 * y + 2 * c.p2 * x;
        double det = a * d - b * cc;
        if (std::fabs(det) < 1e-12) return false;
        double sx = (d * fx - b * fy) / det, sy = (-cc * fx + a * fy) / det;
        x -= sx;
        y -= sy;
        if (std::fabs(sx) + std::fabs(sy) < 1e-15) break;
    }
    double xr, yr;
    distort(c, x, y, &xr, &yr);
    *xo = x;
    *yo = y;
    return std::fabs(xr - xd) + std::fabs(yr - yd) < 1e-12;
}

CameraPose camera_pose(const CameraModel &cam, const Pose2 &rb)
{
    CameraPose p;
    p.c[0] = rb.x + cam.offset_m * std::cos(rb.theta);
    p.c[1] = rb.y + cam.offset_m * std::sin(rb.theta);
    p.c[2] = cam.height_floor_m;
    double psi = rb.theta + cam.yaw_rad, t = cam.tilt_rad;
    p.f[0] = std::cos(t) * std::cos(psi);
    p.f[1] = std::cos(t) * std::sin(psi);
    p.f[2] = -std::sin(t);
    p.r[0] = std::sin(psi);
    p.r[1] = -std::cos(psi);
    p.r[2] = 0;
    // down = forward x right
    p.d[0] = p.f[1] * p.r[2] - p.f[2] * p.r[1];
    p.d[1] = p.f[2] * p.r[0] - p.f[0] * p.r[2];
    p.d[2] = p.f[0] * p.r[1] - p.f[1] * p.r[0];
    return p;
}

bool project_point(const CameraModel &cam, const CameraPose &cp, const double p[3], double *u, double *v)
{
    double q[3] = {p[0] - cp.c[0], p[1] - cp.c[1], p[2] - cp.c[2]};
    double zc = dot3(q, cp.f);
    if (zc <= 1e-6) return false;
    double x = dot3(q, cp.r) / zc, y = dot3(q, cp.d) / zc, xd, yd;
    distort(cam, x, y, &xd, &yd);
    *u = cam.cx + cam.fx * xd;
    *v = cam.cy + cam.fy * yd;
    return true;
}

Renderer::Renderer(const Scene &s) : scene_(s) { build_raymap(); }

void Renderer::set_camera(const CameraModel &c)
{
    scene_.camera = c;
    if (c.width != ray_cam_.width || c.height != ray_cam_.height || c.fx != ray_cam_.fx ||
        c.fy != ray_cam_.fy || c.cx != ray_cam_.cx || c.cy != ray_cam_.cy || c.k1 != ray_cam_.k1 ||
        c.k2 != ray_cam_.k2 || c.p1 != ray_cam_.p1 || c.p2 != ray_cam_.p2 || c.k3 != ray_cam_.k3 ||
        ray_n_ != scene_.imaging.samples)
        build_raymap();
}

void Renderer::build_raymap()
{
    const CameraModel &c = scene_.camera;
    uint32_t n = scene_.imaging.samples;
    if (n < 1 || n > 4) throw Error("synthetic scene: imaging.samples must be 1..4");
    if (c.width < 2 || c.height < 1 || c.width % 2 || c.fx <= 0 || c.fy <= 0)
        throw Error("synthetic scene: bad camera size or focal length");
    // The forward model must be one-to-one over the field of view (and beyond, for the screen
    // boxes of partly visible objects): the radial map must increase up to r = 2.
    for (int i = 1; i <= 200; i++) {
        double r = 2.0 * i / 200, r2 = r * r;
        double dr = 1 + 3 * c.k1 * r2 + 5 * c.k2 * r2 * r2 + 7 * c.k3 * r2 * r2 * r2;
        if (dr <= 0.05) throw Error("synthetic scene: lens distortion folds within r = 2 (not supported)");
    }
    ray_.assign((size_t)c.width * c.height * n * n * 2, 0.f);
    size_t k = 0;
    for (uint32_t py = 0; py < c.height; py++)
        for (uint32_t px = 0; px < c.width; px++)
            for (uint32_t sy = 0; sy < n; sy++)
                for (uint32_t sx = 0; sx < n; sx++) {
                    double u = px + (sx + 0.5) / n - 0.5, v = py + (sy + 0.5) / n - 0.5;
                    double x, y;
                    if (!undistort(c, (u - c.cx) / c.fx, (v - c.cy) / c.fy, &x, &y))
                        throw Error("synthetic scene: undistortion failed at a pixel");
                    ray_[k++] = (float)x;
                    ray_[k++] = (float)y;
                }
    ray_w_ = c.width;
    ray_h_ = c.height;
    ray_n_ = n;
    ray_cam_ = c;
}

double Renderer::frame_gain(uint64_t seed, uint64_t k, double t_s) const
{
    const Imaging &im = scene_.imaging;
    Xoshiro r(mix_seed(seed, k, 0x6A1Bu));
    double z = normal_table()[r.next() >> 48];
    double g = im.exposure * (1 + im.illum_amplitude * std::sin(2 * kPi * t_s / im.illum_period_s));
    return g * (1 + im.exposure_jitter * z);
}

namespace {

// Screen bounding box of a set of world points; false when some point is behind (or nearly at)
// the camera plane -- then the box is the whole image.
struct SBox { int x0, y0, x1, y1; };

SBox screen_box(const CameraModel &cam, const CameraPose &cp, const std::vector<std::array<double, 3>> &pts)
{
    double u0 = 1e30, v0 = 1e30, u1 = -1e30, v1 = -1e30;
    int behind = 0;
    for (auto &p : pts) {
        double q[3] = {p[0] - cp.c[0], p[1] - cp.c[1], p[2] - cp.c[2]};
        if (dot3(q, cp.f) < 0.05) behind++;
    }
    if (behind == (int)pts.size()) return SBox{0, 0, -1, -1};  // wholly behind the camera
    if (behind) return SBox{0, 0, (int)cam.width - 1, (int)cam.height - 1};  // straddles: whole image
    for (auto &p : pts) {
        double u, v;
        project_point(cam, cp, p.data(), &u, &v);
        u0 = std::min(u0, u); u1 = std::max(u1, u); v0 = std::min(v0, v); v1 = std::max(v1, v);
    }
    // Points just in front of the camera plane project far outside the image (or to NaN beyond
    // the lens model's fold): clamp before converting to int (UBSan found the overflow).
    auto lim = [](double x) { return std::max(-1e6, std::min(1e6, x)); };
    SBox b;
    b.x0 = (int)std::floor(lim(u0)) - 3; b.x1 = (int)std::ceil(lim(u1)) + 3;
    b.y0 = (int)std::floor(lim(v0)) - 3; b.y1 = (int)std::ceil(lim(v1)) + 3;
    b.x0 = std::max(b.x0, 0); b.y0 = std::max(b.y0, 0);
    b.x1 = std::min(b.x1, (int)cam.width - 1); b.y1 = std::min(b.y1, (int)cam.height - 1);
    return b;
}

// A truncated cone rather than a cylinder (Cylinder::diameter_top_m)?
inline bool is_cone(const Cylinder &c) { return c.diameter_top_m >= 0 && c.diameter_top_m != c.diameter_m; }

// The surface colour of a landmark hit at height z above the floor (side) or on its top cap:
// bands are listed top to bottom; a z on a boundary belongs to the upper band, and the bottom band
// takes whatever is left (heights that sum to height_m only up to rounding).
const Yuv &surface_colour(const Cylinder &c, double z, bool cap)
{
    if (c.bands.empty()) return c.colour;
    if (cap) return c.bands.front().colour;
    double top = c.height_m;
    for (size_t i = 0; i + 1 < c.bands.size(); i++) {
        double bottom = top - c.bands[i].height_m;
        if (z >= bottom) return c.bands[i].colour;
        top = bottom;
    }
    return c.bands.back().colour;
}

} // namespace

void Renderer::render_clean(const Pose2 &robot, double gain, CleanFrame &out, double t_s) const
{
    const Scene &s = scene_;
    const CameraModel &cam = s.camera;
    const Imaging &im = s.imaging;
    const uint32_t W = cam.width, H = cam.height, n = ray_n_, nn = n * n;
    CameraPose cp = camera_pose(cam, robot);
    const double L[3] = {std::cos(im.light_el_rad) * std::cos(im.light_az_rad),
                         std::cos(im.light_el_rad) * std::sin(im.light_az_rad), std::sin(im.light_el_rad)};

    // Objects: cylinders then boxes, with screen boxes.
    struct Obj { int kind; size_t idx; SBox b; };
    std::vector<Obj> objs;
    std::vector<std::array<double, 3>> pts;
    for (size_t i = 0; i < s.cylinders.size(); i++) {
        const Cylinder &c = s.cylinders[i];
        pts.clear();
        double R = std::max(c.diameter_m, c.diameter_top_m) / 2;  // a cone: its larger end
        for (int k = 0; k < 16; k++) {
            double a = 2 * kPi * k / 16, x = c.x_m + R * 1.09 * std::cos(a), y = c.y_m + R * 1.09 * std::sin(a);
            pts.push_back({x, y, 0.0});
            pts.push_back({x, y, c.height_m});
        }
        SBox b = screen_box(cam, cp, pts);
        if (b.x0 <= b.x1 && b.y0 <= b.y1) objs.push_back({0, i, b});
    }
    for (size_t i = 0; i < s.boxes.size(); i++) {
        const Box &bx = s.boxes[i];
        pts.clear();
        detail::append_rect_corners(bx.x_m, bx.y_m, bx.yaw_rad, bx.size_x_m, bx.size_y_m, {0.0, bx.size_z_m}, pts);
        SBox b = screen_box(cam, cp, pts);
        if (b.x0 <= b.x1 && b.y0 <= b.y1) objs.push_back({1, i, b});
    }

    std::vector<double> box_c(s.boxes.size()), box_s(s.boxes.size()), pat_c(s.patches.size()), pat_s(s.patches.size());
    for (size_t i = 0; i < s.boxes.size(); i++) { box_c[i] = std::cos(s.boxes[i].yaw_rad); box_s[i] = std::sin(s.boxes[i].yaw_rad); }
    for (size_t i = 0; i < s.patches.size(); i++) { pat_c[i] = std::cos(s.patches[i].yaw_rad); pat_s[i] = std::sin(s.patches[i].yaw_rad); }

    out.width = W;
    out.height = H;
    out.y.assign((size_t)W * H, 0.f);
    out.u.assign((size_t)W * H, 0.f);
    out.v.assign((size_t)W * H, 0.f);
    if (out.want_labels) out.label.assign((size_t)W * H, -1);
    const double wb_u = im.wb_drift * std::sin(2 * kPi * t_s / im.wb_period_s);
    const double wb_v = -0.7 * im.wb_drift * std::sin(2 * kPi * t_s / im.wb_period_s + 0.5);

    const Room &room = s.room;
    const double floor_shade = im.ambient + im.diffuse * std::max(0.0, L[2]);
    std::vector<const Obj *> row_objs, px_objs;
    for (uint32_t py = 0; py < H; py++) {
        row_objs.clear();
        for (auto &o : objs)
            if ((int)py >= o.b.y0 && (int)py <= o.b.y1) row_objs.push_back(&o);
        for (uint32_t px = 0; px < W; px++) {
            px_objs.clear();
            for (auto *o : row_objs)
                if ((int)px >= o->b.x0 && (int)px <= o->b.x1) px_objs.push_back(o);
            const float *rays = &ray_[(((size_t)py * W + px) * nn) * 2];
            double acc_y = 0, acc_u = 0, acc_v = 0;
            int32_t lab = -1;
            uint32_t lab_n = 0;
            for (uint32_t k = 0; k < nn; k++) {
                double xn = rays[2 * k], yn = rays[2 * k + 1];
                double D[3] = {xn * cp.r[0] + yn * cp.d[0] + cp.f[0], xn * cp.r[1] + yn * cp.d[1] + cp.f[1],
                               xn * cp.r[2] + yn * cp.d[2] + cp.f[2]};
                Hit h;
                // Background: floor, walls, ceiling.
                int bg = 0;  // 0 floor, 1 wall x, 2 wall y, 3 ceiling
                if (D[2] < 0) { h.t = -cp.c[2] / D[2]; bg = 0; }
                else if (D[2] > 0) { h.t = (room.wall_height_m - cp.c[2]) / D[2]; bg = 3; }
                if (D[0] > 1e-12) { double t = (room.x_max - cp.c[0]) / D[0]; if (t < h.t) { h.t = t; bg = 1; } }
                else if (D[0] < -1e-12) { double t = (room.x_min - cp.c[0]) / D[0]; if (t < h.t) { h.t = t; bg = 1; } }
                if (D[1] > 1e-12) { double t = (room.y_max - cp.c[1]) / D[1]; if (t < h.t) { h.t = t; bg = 2; } }
                else if (D[1] < -1e-12) { double t = (room.y_min - cp.c[1]) / D[1]; if (t < h.t) { h.t = t; bg = 2; } }
                int hit_obj = -1;  // -1 background
                const Obj *ho = nullptr;
                double hit_z = 0;      // a landmark's hit: height above the floor,
                bool hit_cap = false;  // on its top cap (for the colour band)
                for (auto *o : px_objs) {
                    if (o->kind == 0 && is_cone(s.cylinders[o->idx])) {
                        // Truncated cone: x^2 + y^2 = R(z)^2, R(z) = R0 + k z, k = (R1 - R0) / H, on the
                        // ray z = cz + t Dz: R = A0 + A1 t. A quadratic in t; a root counts when it lies
                        // in 0 <= z <= H on the nappe with R(z) >= 0; the nearest such root (or the cap)
                        // is the hit.
                        const Cylinder &c = s.cylinders[o->idx];
                        const double R0 = c.diameter_m / 2, R1 = c.diameter_top_m / 2, Hc = c.height_m;
                        const double kc = (R1 - R0) / Hc;
                        double pxr = cp.c[0] - c.x_m, pyr = cp.c[1] - c.y_m;
                        double A0 = R0 + kc * cp.c[2], A1 = kc * D[2];
                        double a = D[0] * D[0] + D[1] * D[1] - A1 * A1;
                        double b = 2 * (pxr * D[0] + pyr * D[1] - A0 * A1);
                        double cc = pxr * pxr + pyr * pyr - A0 * A0;
                        double ts[2];
                        int nt = 0;
                        if (std::fabs(a) > 1e-12 * (D[0] * D[0] + D[1] * D[1] + D[2] * D[2])) {
                            double disc = b * b - 4 * a * cc;
                            if (disc >= 0) {
                                // the numerically stable pair of roots
                                double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
                                if (q != 0) { ts[nt++] = q / a; ts[nt++] = cc / q; }
                            }
                        } else if (b != 0) {
                            ts[nt++] = -cc / b;  // the ray parallel to a generator: one root
                        }
                        for (int j = 0; j < nt; j++) {
                            double t = ts[j];
                            if (!(t > 0 && t < h.t)) continue;
                            double z = cp.c[2] + t * D[2];
                            if (z < 0 || z > Hc || A0 + A1 * t < 0) continue;
                            double qx = pxr + t * D[0], qy = pyr + t * D[1], rr = std::hypot(qx, qy);
                            h.t = t;
                            // outward normal: the gradient of sqrt(x^2 + y^2) - R(z)
                            double inv = 1.0 / std::sqrt(1 + kc * kc);
                            if (rr > 0) { h.n[0] = qx / rr * inv; h.n[1] = qy / rr * inv; h.n[2] = -kc * inv; }
                            else { h.n[0] = 0; h.n[1] = 0; h.n[2] = 1; }  // the apex
                            hit_z = z; hit_cap = false;
                            hit_obj = 0; ho = o;
                        }
                        if (R1 > 0 && D[2] != 0) {
                            double t = (Hc - cp.c[2]) / D[2];
                            if (t > 0 && t < h.t) {
                                double qx = pxr + t * D[0], qy = pyr + t * D[1];
                                if (qx * qx + qy * qy <= R1 * R1) {
                                    h.t = t; h.n[0] = 0; h.n[1] = 0; h.n[2] = D[2] < 0 ? 1 : -1;
                                    hit_z = Hc; hit_cap = true;
                                    hit_obj = 0; ho = o;
                                }
                            }
                        }
                    } else if (o->kind == 0) {
                        const Cylinder &c = s.cylinders[o->idx];
                        double R = c.diameter_m / 2;
                        double pxr = cp.c[0] - c.x_m, pyr = cp.c[1] - c.y_m;
                        double a = D[0] * D[0] + D[1] * D[1];
                        double b = 2 * (pxr * D[0] + pyr * D[1]);
                        double cc = pxr * pxr + pyr * pyr - R * R;
                        double disc = b * b - 4 * a * cc;
                        if (disc >= 0 && a > 0) {
                            double t1 = (-b - std::sqrt(disc)) / (2 * a);
                            double z = cp.c[2] + t1 * D[2];
                            if (t1 > 0 && t1 < h.t && z >= 0 && z <= c.height_m) {
                                h.t = t1;
                                h.n[0] = (pxr + t1 * D[0]) / R; h.n[1] = (pyr + t1 * D[1]) / R; h.n[2] = 0;
                                hit_z = z; hit_cap = false;
                                hit_obj = 0; ho = o;
                            }
                        }
                        if (D[2] != 0) {
                            double t = (c.height_m - cp.c[2]) / D[2];
                            if (t > 0 && t < h.t) {
                                double qx = pxr + t * D[0], qy = pyr + t * D[1];
                                if (qx * qx + qy * qy <= R * R) {
                                    h.t = t; h.n[0] = 0; h.n[1] = 0; h.n[2] = D[2] < 0 ? 1 : -1;
                                    hit_z = c.height_m; hit_cap = true;
                                    hit_obj = 0; ho = o;
                                }
                            }
                        }
                    } else {
                        const Box &bx = s.boxes[o->idx];
                        double ca = box_c[o->idx], sa = box_s[o->idx];
                        double ox = cp.c[0] - bx.x_m, oy = cp.c[1] - bx.y_m;
                        double O[3] = {ca * ox + sa * oy, -sa * ox + ca * oy, cp.c[2]};
                        double Dl[3] = {ca * D[0] + sa * D[1], -sa * D[0] + ca * D[1], D[2]};
                        double lo[3] = {-bx.size_x_m / 2, -bx.size_y_m / 2, 0};
                        double hi[3] = {bx.size_x_m / 2, bx.size_y_m / 2, bx.size_z_m};
                        double tn = -1e30, tf = 1e30;
                        int axis = 0; double sgn = 1;
                        bool miss = false;
                        for (int ax = 0; ax < 3 && !miss; ax++) {
                            if (std::fabs(Dl[ax]) < 1e-15) {
                                if (O[ax] < lo[ax] || O[ax] > hi[ax]) miss = true;
                                continue;
                            }
                            double t0 = (lo[ax] - O[ax]) / Dl[ax], t1 = (hi[ax] - O[ax]) / Dl[ax];
                            double sg = -1;
                            if (t0 > t1) { std::swap(t0, t1); sg = 1; }
                            if (t0 > tn) { tn = t0; axis = ax; sgn = sg; }
                            tf = std::min(tf, t1);
                        }
                        if (!miss && tn <= tf && tn > 0 && tn < h.t) {
                            h.t = tn;
                            double nl[3] = {0, 0, 0};
                            nl[axis] = sgn;
                            h.n[0] = ca * nl[0] - sa * nl[1]; h.n[1] = sa * nl[0] + ca * nl[1]; h.n[2] = nl[2];
                            hit_obj = 1; ho = o;
                        }
                    }
                }
                double shade;
                Yuv col;
                if (hit_obj == 0) {
                    col = surface_colour(s.cylinders[ho->idx], hit_z, hit_cap);
                    shade = im.ambient + im.diffuse * std::max(0.0, dot3(h.n, L));
                    if (out.want_labels && s.cylinders[ho->idx].landmark) {
                        if (lab == (int32_t)ho->idx) lab_n++;
                        else if (lab_n == 0) { lab = (int32_t)ho->idx; lab_n = 1; }
                    }
                } else if (hit_obj == 1) {
                    col = s.boxes[ho->idx].colour;
                    shade = im.ambient + im.diffuse * std::max(0.0, dot3(h.n, L));
                } else if (bg == 0) {
                    double X = cp.c[0] + h.t * D[0], Y = cp.c[1] + h.t * D[1];
                    col = room.floor;
                    int tile = ((int)std::floor(X / 0.3) + (int)std::floor(Y / 0.3)) & 1;
                    col.y += tile ? room.floor_texture : -room.floor_texture;
                    double shadow = 0.0;
                    for (size_t pi = 0; pi < s.patches.size(); pi++) {
                        const FloorPatch &fp = s.patches[pi];
                        double ca = pat_c[pi], sa = pat_s[pi];
                        double lx = ca * (X - fp.x_m) + sa * (Y - fp.y_m), ly = -sa * (X - fp.x_m) + ca * (Y - fp.y_m);
                        if (std::fabs(lx) <= fp.size_x_m / 2 && std::fabs(ly) <= fp.size_y_m / 2) {
                            if (fp.shadow > 0) shadow = std::max(shadow, fp.shadow);
                            else col = fp.colour;
                        }
                    }
                    shade = floor_shade * (1.0 - shadow);
                } else if (bg == 3) {
                    col = room.ceiling;
                    shade = im.ambient + im.diffuse * 0.3;
                } else {
                    col = room.wall;
                    double nrm[3] = {bg == 1 ? (D[0] > 0 ? -1.0 : 1.0) : 0.0, bg == 2 ? (D[1] > 0 ? -1.0 : 1.0) : 0.0, 0};
                    shade = im.ambient + im.diffuse * (0.35 + 0.65 * std::max(0.0, dot3(nrm, L)));
                }
                if (im.illum_gradient_per_m != 0.0)
                    shade *= std::max(0.2, 1.0 + im.illum_gradient_per_m * (cp.c[0] + h.t * D[0]));
                double g = shade * gain;
                acc_y += col.y * g;
                acc_u += (col.u - 128.0) * g;
                acc_v += (col.v - 128.0) * g;
            }
            size_t o = (size_t)py * W + px;
            out.y[o] = (float)(acc_y / nn);
            out.u[o] = (float)(128.0 + acc_u / nn + wb_u);
            out.v[o] = (float)(128.0 + acc_v / nn + wb_v);
            if (out.want_labels && 2 * lab_n >= nn) out.label[o] = lab;
        }
    }
    // Optical blur (all planes) and the chroma bandwidth limit (horizontal, chroma only).
    std::vector<float> k_opt, k_chr;
    gaussian_kernel(im.blur_sigma_px, k_opt);
    gaussian_kernel(std::sqrt(im.blur_sigma_px * im.blur_sigma_px + im.chroma_blur_px * im.chroma_blur_px), k_chr);
    blur_plane(out.y, W, H, k_opt, k_opt, out.scratch);
    blur_plane(out.u, W, H, k_chr, k_opt, out.scratch);
    blur_plane(out.v, W, H, k_chr, k_opt, out.scratch);
}

void Renderer::finish_yuyv(const CleanFrame &cf, uint64_t noise_seed, std::vector<uint8_t> &out) const
{
    const Imaging &im = scene_.imaging;
    const uint32_t W = cf.width, H = cf.height;
    out.resize((size_t)W * H * 2);
    const std::vector<float> &T = normal_table();
    Xoshiro r(mix_seed(noise_seed, 0xF4A3u, 0));
    const float sy = (float)im.noise_y, sc = (float)im.noise_c;
    auto q = [](float x) -> uint8_t {
        float v = std::floor(x + 0.5f);
        return (uint8_t)(v < 0 ? 0 : v > 255 ? 255 : v);
    };
    for (uint32_t y = 0; y < H; y++) {
        const float *Y = &cf.y[(size_t)y * W], *U = &cf.u[(size_t)y * W], *V = &cf.v[(size_t)y * W];
        uint8_t *o = &out[(size_t)y * W * 2];
        for (uint32_t x = 0; x < W; x += 2) {
            uint64_t a = r.next(), b = r.next();
            float y0 = Y[x] + sy * T[a & 0xFFFF], y1 = Y[x + 1] + sy * T[(a >> 16) & 0xFFFF];
            float u0 = U[x] + sc * T[(a >> 32) & 0xFFFF], u1 = U[x + 1] + sc * T[a >> 48];
            float v0 = V[x] + sc * T[b & 0xFFFF], v1 = V[x + 1] + sc * T[(b >> 16) & 0xFFFF];
            o[2 * x + 0] = q(y0);
            o[2 * x + 1] = q(0.5f * (u0 + u1));
            o[2 * x + 2] = q(y1);
            o[2 * x + 3] = q(0.5f * (v0 + v1));
        }
    }
}

void Renderer::render_yuyv(const Pose2 &robot, double gain, uint64_t noise_seed, std::vector<uint8_t> &yuyv) const
{
    CleanFrame cf;
    render_clean(robot, gain, cf);
    finish_yuyv(cf, noise_seed, yuyv);
}

} // namespace synth
} // namespace cylfe
