// SPDX-License-Identifier: BSD-3-Clause
// cylfe::synth -- a synthetic camera with ground truth (docs/synthetic.md).
//
// A flat floor inside a room of walls; vertical cylinders or truncated cones, in one colour or in
// horizontal bands of colour (the landmarks), boxes, thin poles and floor patches (clutter in
// landmark colours, neutral occluders); a robot with a camera mounted on it, driving a
// trajectory with noisy odometry. Frames are rendered by casting rays
// through sub-pixel samples of every pixel (supersampling = anti-aliased edges) through this
// file's own lens model and mounting -- independent of libcyl's camera code -- then optical
// blur, exposure, per-pixel sensor noise in YUV, 4:2:2 chroma subsampling into YUYV bytes.
//
// Frames (world): x, y on the floor, z up; the floor is z = 0. Robot pose (x, y, theta), theta
// counter-clockwise from +x. Camera: optical centre offset_m ahead of the robot centre,
// height_floor_m above the floor, turned left by yaw_rad and pitched down by tilt_rad
// (paper-model.md). Pixel (u, v): centres at integers, u right, v down; normalised distorted
// x_d = (u - cx)/fx, Brown-Conrady k1 k2 p1 p2 k3 (OpenCV order) from undistorted (x, y).
//
// Determinism: every random quantity derives from the seed given to the call (splitmix64 /
// xoshiro256**); the same scene, seed and frame index give bit-identical frames.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "cylfe/rawlog.hpp"
#include "cylfe/source.hpp"

extern "C" {
#include "cyl/camera.h"
}

namespace cylfe {
namespace synth {

// A surface colour as the YUV (BT.601, 8-bit range) it has under unit illumination and unit
// exposure. Shading multiplies Y and the chroma offsets (U - 128, V - 128) by the same factor.
struct Yuv {
    double y = 128, u = 128, v = 128;
};

// One horizontal colour band of a landmark (Cylinder::bands).
struct Band {
    double height_m = 0.1;         // > 0
    int32_t cls = -1;              // colour class index, -1 = a colour no class stands for (a cone's
                                   // white stripe)
    Yuv colour;
};

struct Cylinder {                  // vertical, standing on the floor, closed top
    uint32_t id = 0;               // landmark id (TruthLandmark id), unique
    int32_t cls = -1;              // colour class index (names in Scene::classes), -1 = none; with
                                   // bands: the class the truth reports (multiband_scene: the top band's)
    bool landmark = true;          // false: clutter (a thin pole, ...)
    double x_m = 0, y_m = 0;       // axis position, world
    double diameter_m = 0.1, height_m = 0.3;  // diameter_m: at the floor (the base of a cone)
    Yuv colour;                    // the colour when `bands` is empty
    // Colour bands, TOP TO BOTTOM, heights summing to height_m (load_scene checks: 1e-9). Empty:
    // one colour (`colour`). A side point at height z (from the floor) takes the colour of the band
    // containing z; the top cap the top band's. Labels (CleanFrame::label) cover all bands.
    std::vector<Band> bands;
    // Shape: < 0 (default) or == diameter_m: a cylinder. Otherwise a truncated cone, the radius
    // linear in z from diameter_m / 2 at the floor to diameter_top_m / 2 at height_m (0: a full
    // cone with its apex at the top), closed by a flat top cap when diameter_top_m > 0.
    double diameter_top_m = -1;
};

struct Box {                       // box standing on the floor, rotated by yaw about z
    int32_t cls = -1;              // colour class of clutter, -1 = neutral occluder
    double x_m = 0, y_m = 0, yaw_rad = 0;
    double size_x_m = 0.3, size_y_m = 0.3, size_z_m = 0.3;
    Yuv colour;
};

struct FloorPatch {                // flat coloured rectangle lying on the floor (a mat, paper)
    int32_t cls = -1;
    double x_m = 0, y_m = 0, yaw_rad = 0, size_x_m = 0.5, size_y_m = 0.5;
    Yuv colour;
    double shadow = 0.0;           // > 0: not a coloured patch but a cast shadow, darkening the floor
                                   // under it by this fraction (0..1) and keeping its colour
};

struct CameraModel {
    uint32_t width = 640, height = 480;
    double fx = 570, fy = 568, cx = 322.4, cy = 236.9;
    double k1 = -0.12, k2 = 0.05, p1 = 0.0008, p2 = -0.0006, k3 = 0.0;
    double tilt_rad = 0.20944;     // 12 deg down
    double yaw_rad = 0.0;          // left positive
    double height_floor_m = 0.476; // optical centre above the floor
    double offset_m = 0.10;        // optical centre ahead of the robot centre (s)
};

// Calibration uncertainty the estimator is told about (and, in the experiments, the spread from
// which calibration errors are drawn). Defaults: the paper's Tables 4 and 5.
struct CameraSigmas {
    double fx = 0.4565, fy = 0.4399, cx = 0.3216, cy = 0.2826;
    double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;
    double tilt_rad = 0.575 * 3.14159265358979323846 / 180.0;
    double yaw_rad = 0.443 * 3.14159265358979323846 / 180.0;
    double height_m = 3.04e-4;
    double offset_m = 0.00255;     // the paper's 95% +-5 mm
};

struct Imaging {
    uint32_t samples = 2;          // n: n x n sub-pixel samples per pixel (1..4)
    double blur_sigma_px = 1.0;    // optical blur (Gaussian), luma and chroma
    double chroma_blur_px = 2.0;   // extra horizontal low-pass of chroma (analog/encoder bandwidth)
    double noise_y = 2.5;          // sensor noise, Y levels (std), per pixel
    double noise_c = 3.5;          // sensor noise, U and V levels (std), per pixel before 4:2:2
    double exposure = 1.0;         // global gain
    double exposure_jitter = 0.03; // frame-to-frame relative gain noise (auto-exposure hunting)
    double illum_amplitude = 0.12; // slow illumination change: gain * (1 + a sin(2 pi t / T))
    double illum_period_s = 40.0;
    double ambient = 0.70;         // shading = ambient + diffuse * max(0, n . l)
    double diffuse = 0.40;
    double light_az_rad = 0.7, light_el_rad = 0.9;  // direction towards the (distant) light
    double illum_gradient_per_m = 0.0;  // illumination across the room: shading * (1 + g * x_world)
    double wb_drift = 0.0;         // white-balance drift over the drive: U += A sin(2 pi t / T),
    double wb_period_s = 60.0;     // V -= 0.7 A sin(2 pi t / T + 0.5), in U/V levels (A = wb_drift)
};

struct Room {
    double x_min = -4.5, x_max = 4.5, y_min = -3.5, y_max = 3.5;  // walls, m
    double wall_height_m = 2.5;
    Yuv floor{118, 126, 131};      // grey linoleum
    Yuv wall{178, 124, 131};       // off-white
    Yuv ceiling{200, 128, 128};
    double floor_texture = 6.0;    // Y amplitude of a faint 0.3 m tile pattern
};

struct TrajectoryParams {
    std::string type = "figure8";  // "figure8" (x = a sin p, y = b sin p cos p) or "ellipse"
    double centre_x_m = 0, centre_y_m = 0;
    double a_m = 2.6, b_m = 3.0;   // figure8: x half-extent a, lobes +-b/2; ellipse: semi-axes
    double speed_mps = 0.30;
    double fps = 15.0;
    double phase0 = 0.3;           // start parameter
};

// Odometry increment noise: for a true increment of translation d (m) and rotation a (rad),
// independent zero-mean Gaussian errors, in the frame of the translation direction,
//   longitudinal  std = k_long * d + min_xy
//   lateral       std = k_lat * d + min_xy
//   rotation      std = k_rot * |a| + k_rot_d * d + min_theta
// rotated into the previous pose's frame; that covariance is what the ODOMETRY record carries.
struct OdometryNoise {
    double k_long = 0.02;          // m per m
    double k_lat = 0.01;           // m per m
    double k_rot = 0.03;           // rad per rad
    double k_rot_d = 0.008;        // rad per m
    double min_xy = 1e-4;          // m
    double min_theta = 1e-4;       // rad
};

struct Scene {
    std::string name = "default";
    std::vector<std::string> classes{"orange", "green"};  // colour class names, index = cls
    Room room;
    std::vector<Cylinder> cylinders;
    std::vector<Box> boxes;
    std::vector<FloorPatch> patches;
    CameraModel camera;
    CameraSigmas sigmas;
    Imaging imaging;
    TrajectoryParams trajectory;
    OdometryNoise odometry;
    double landmark_diameter_m = 0.10;  // the landmarks' (common) size: confidence, libcyl h
    double landmark_height_m = 0.30;
};

// The built-in default scene: a 9 m x 7 m room, 14 landmarks (7 orange, 7 green) around and
// inside a figure-eight drive, clutter in both colours (flat box, floor mat, thin poles, a tall
// box) and two neutral occluders.
Scene default_scene();
// A static, empty room with no landmarks (experiments add their own objects).
Scene empty_scene();
// The default scene made hard for colour learning: a wooden floor and an olive wall in hues near
// the landmarks', dull orange, dull green, red and yellow clutter, an illumination gradient across
// the room, cast shadows on the floor, and exposure and white-balance drift over the drive.
Scene hard_scene();
// The default room and drive with landmarks of several colours: 6 striped traffic cones
// (orange / white / orange) and 8 colour-coded cylinders (three bands of green, blue, pink), classes
// {"orange", "green", "blue", "pink"}, one neutral occluder and one flat orange box.
Scene multiband_scene();
// Read / write a scene file (YAML or JSON through cv::FileStorage; docs/synthetic.md). Missing
// fields keep the defaults of an empty scene. Throws cylfe::Error naming the file and field.
Scene load_scene(const std::string &path);
void save_scene(const std::string &path, const Scene &s);
// "default", "empty", "hard", "multiband" -> the built-in scenes, otherwise load_scene(path).
Scene scene_by_name(const std::string &name_or_path);

// A camera whose intrinsics and mount differ from c by an error drawn once from the sigmas
// (seeded): render with it and estimate with c to simulate a calibration that is off by a
// realistic amount (constant over the run, as real calibration errors are).
CameraModel perturb_camera(const CameraModel &c, const CameraSigmas &sg, uint64_t seed);

struct Pose2 {
    double x = 0, y = 0, theta = 0;
};

// The libcyl camera description of a scene camera (its nominal values and sigmas), with
// h = height of the optical centre above the landmarks' centroid plane.
cyl_camera to_cyl_camera(const Scene &s);
cyl_camera to_cyl_camera(const CameraModel &c, const CameraSigmas &sg, double landmark_height_m);

// Camera pose in the world: optical centre c and camera axes (right, down, forward).
struct CameraPose {
    double c[3];
    double r[3], d[3], f[3];
};
CameraPose camera_pose(const CameraModel &cam, const Pose2 &robot);
// Forward projection of a world point with this file's own model; false if behind the camera.
bool project_point(const CameraModel &cam, const CameraPose &cp, const double p[3], double *u,
                   double *v);
// Brown-Conrady forward model and its inverse (Newton; |residual| < 1e-12), own code.
void distort(const CameraModel &cam, double x, double y, double *xd, double *yd);
bool undistort(const CameraModel &cam, double xd, double yd, double *x, double *y);

// A frame's clean (noise-free, float) YUV planes at full resolution.
struct CleanFrame {
    uint32_t width = 0, height = 0;
    std::vector<float> y, u, v;
    std::vector<float> scratch;  // the blur's workspace: reusing a CleanFrame reuses all its memory
    bool want_labels = false;    // fill `label`:
    std::vector<int32_t> label;  // per pixel, the index in Scene::cylinders of the landmark that at
                                 // least half of the pixel's samples hit, else -1
};

class Renderer {
public:
    explicit Renderer(const Scene &s);
    const Scene &scene() const { return scene_; }
    Scene &mutable_scene() { return scene_; }  // objects may be edited between frames
    // Change the camera; the ray map is rebuilt when intrinsics or image size changed.
    void set_camera(const CameraModel &c);
    // Ray casting with supersampling, shading and optical blur (no noise).
    // t_s: the frame's time, for the white-balance drift (Imaging::wb_drift).
    void render_clean(const Pose2 &robot, double gain, CleanFrame &out, double t_s = 0.0) const;
    // Sensor noise (seeded), 4:2:2 chroma subsampling, quantisation into YUYV bytes
    // (width * 2 bytes per line).
    void finish_yuyv(const CleanFrame &clean, uint64_t noise_seed, std::vector<uint8_t> &yuyv) const;
    // Both.
    void render_yuyv(const Pose2 &robot, double gain, uint64_t noise_seed,
                     std::vector<uint8_t> &yuyv) const;
    // Exposure gain of frame index k at time t (illumination change and jitter, seeded).
    double frame_gain(uint64_t seed, uint64_t k, double t_s) const;

private:
    void build_raymap();
    Scene scene_;
    std::vector<float> ray_;   // per sample (x_n, y_n), undistorted; width*height*n*n*2
    uint32_t ray_w_ = 0, ray_h_ = 0, ray_n_ = 0;
    CameraModel ray_cam_;
};

// One step of a drive: true pose, the odometry increment since the previous step (noisy, with
// its covariance) and the timestamp.
struct DriveStep {
    uint64_t seq = 0;
    int64_t t_ns = 0;
    Pose2 truth;
    Odometry odo;        // first step: zero increment with the floor covariance
    double true_dx = 0, true_dy = 0, true_dtheta = 0;  // the exact increment (for tests)
};
Pose2 trajectory_pose(const TrajectoryParams &p, double dist_m);
// Increment b relative to a, in a's frame.
void pose_between(const Pose2 &a, const Pose2 &b, double *dx, double *dy, double *dth);
// Covariance (upper triangle xx xy xt yy yt tt) of the odometry error for a true increment.
void odometry_covariance(const OdometryNoise &n, double dx, double dy, double dth, double cov[6]);
// The drive, generated one step at a time in constant memory (steps 0, 1, 2, ...; the same
// sequence as make_drive for the same scene and seed).
class DriveGenerator {
public:
    DriveGenerator(const Scene &s, uint64_t seed);  // throws Error on a bad trajectory
    DriveStep next();
    uint64_t steps_done() const { return k_; }

private:
    TrajectoryParams tp_;
    OdometryNoise noise_;
    uint64_t rng_;       // state of the odometry-noise stream
    Pose2 prev_{};
    uint64_t k_ = 0;
};
// The first `frames` steps of the drive (tests and experiments that want them all at once).
std::vector<DriveStep> make_drive(const Scene &s, uint32_t frames, uint64_t seed);

// The synthetic scene as a cylfe::Source: TruthLandmark events (one per landmark) first, then
// per step Frame, Odometry, TruthPose. StreamInfo: YUYV, flags kHasTruth | kMonotonic.
class SyntheticSource : public Source {
public:
    SyntheticSource(const Scene &s, uint32_t frames, uint64_t seed);
    const StreamInfo &info() const override { return info_; }
    bool next(SourceEvent &ev) override;
    double progress() const override;
    const Renderer &renderer() const { return renderer_; }
    // Per-pixel landmark labels of the frame just emitted (CleanFrame::label); off by default.
    void set_labels(bool on) { clean_.want_labels = on; }
    const std::vector<int32_t> &labels() const { return clean_.label; }

private:
    Scene scene_;
    Renderer renderer_;
    uint64_t seed_;
    DriveGenerator drive_;   // constant memory however many frames (make soak)
    uint64_t frames_;
    DriveStep cur_;          // the step being emitted (frame, odometry, truth pose)
    std::vector<TruthLandmark> landmarks_;
    StreamInfo info_;
    size_t lm_next_ = 0, step_ = 0;
    int phase_ = 0;  // 0 frame, 1 odometry, 2 truth pose
    CleanFrame clean_;             // reused frame to frame (constant memory)
    std::vector<uint8_t> frame_;
};

// splitmix64 mixing of (seed, a, b) into a new seed.
uint64_t mix_seed(uint64_t seed, uint64_t a, uint64_t b = 0);

} // namespace synth
} // namespace cylfe
