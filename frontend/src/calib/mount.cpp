// SPDX-License-Identifier: BSD-3-Clause
// cylfe::calib -- the robot mount's extrinsics from a chessboard lying on the floor (calib.hpp).
#include "cylfe/calib.hpp"
#include "solver.hpp"

#include <array>
#include <cmath>

#include <ceres/ceres.h>
#include <ceres/rotation.h>
#include <opencv2/calib3d.hpp>

#include "cylfe/error.hpp"

namespace cylfe {
namespace calib {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Pixel residual of one board point for a pose, through libcyl's lens model.
struct PoseReproj {
    const cyl_camera *cam;
    double X, Y, u, v;
    const double *w;  // residual weights (1/sigma_u, 1/sigma_v)
    bool operator()(const double *pose, double *res) const
    {
        double p[3] = {X, Y, 0}, q[3];
        ceres::AngleAxisRotatePoint(pose, p, q);
        q[0] += pose[3];
        q[1] += pose[4];
        q[2] += pose[5];
        if (!(q[2] > 1e-12)) return false;
        double pu, pv;
        cyl_camera_project(cam, q[0] / q[2], q[1] / q[2], &pu, &pv);
        res[0] = (pu - u) * w[0];
        res[1] = (pv - v) * w[1];
        return true;
    }
};

// (height_floor, tilt, yaw, roll, offset, lateral) from a board pose (board -> camera).
// flip = +1 or -1: the detected board x axis is the placement's axis or its opposite.
std::array<double, 6> mount_from_pose(const double *pose, const Board &b, const BoardPlacement &pl, int flip)
{
    double R[9];
    ceres::AngleAxisToRotationMatrix(pose, R);  // column-major: R[c * 3 + r]
    auto Rm = [&](int r, int c) { return R[c * 3 + r]; };
    // camera centre in the board frame: -R^T t
    double Cb[3];
    for (int k = 0; k < 3; k++) Cb[k] = -(Rm(0, k) * pose[3] + Rm(1, k) * pose[4] + Rm(2, k) * pose[5]);
    const double sgn = Cb[2] >= 0 ? 1.0 : -1.0;  // the board normal pointing at the camera is "up"
    const double gc[3] = {0.5 * (b.cols - 1) * b.square, 0.5 * (b.rows - 1) * b.square, 0};
    // floor frame F (board frame re-oriented): xF = flip ex, zF = sgn ez, yF = zF x xF = flip sgn ey
    const double phi = pl.axis_deg * kPi / 180.0, cp = std::cos(phi), sp = std::sin(phi);
    auto to_robot_dir = [&](const double d[3], double out[3]) {
        double a = flip * d[0], bb = flip * sgn * d[1], c = sgn * d[2];
        out[0] = cp * a - sp * bb;
        out[1] = sp * a + cp * bb;
        out[2] = c;
    };
    double rel[3] = {Cb[0] - gc[0], Cb[1] - gc[1], Cb[2] - gc[2]}, Cr[3];
    to_robot_dir(rel, Cr);
    Cr[0] += pl.centre_x_m;
    Cr[1] += pl.centre_y_m;
    // camera axes in the board frame are the rows of R
    double xc[3] = {Rm(0, 0), Rm(0, 1), Rm(0, 2)}, yc[3] = {Rm(1, 0), Rm(1, 1), Rm(1, 2)},
           zc[3] = {Rm(2, 0), Rm(2, 1), Rm(2, 2)};
    double r[3], d[3], f[3];
    to_robot_dir(xc, r);
    to_robot_dir(yc, d);
    to_robot_dir(zc, f);
    std::array<double, 6> m;
    m[0] = Cr[2];
    m[1] = std::atan2(-f[2], std::hypot(f[0], f[1]));
    m[2] = std::atan2(f[1], f[0]);
    m[3] = std::atan2(-r[2], -d[2]);
    m[4] = Cr[0];
    m[5] = Cr[1];
    return m;
}

} // namespace

MountEstimate estimate_mount(const cyl_camera &cam, const Board &b, const BoardPlacement &pl,
                             const std::vector<cv::Point2f> &corners, const std::string &name)
{
    std::vector<cv::Point3f> obj = board_points(b);
    if (corners.size() != obj.size())
        throw Error(name + ": expected " + std::to_string(obj.size()) + " corners, got " + std::to_string(corners.size()));
    // start: PnP on libcyl-undistorted normalised points
    std::vector<cv::Point2f> norm(corners.size());
    for (size_t i = 0; i < corners.size(); i++) {
        double x, y;
        if (cyl_camera_undistort(&cam, corners[i].x, corners[i].y, &x, &y) != CYL_OK)
            throw Error(name + ": corner " + std::to_string(i) + " cannot be undistorted with this camera");
        norm[i] = cv::Point2f((float)x, (float)y);
    }
    cv::Mat rv, tv;
    if (!cv::solvePnP(obj, norm, cv::Mat::eye(3, 3, CV_64F), cv::noArray(), rv, tv, false, cv::SOLVEPNP_ITERATIVE))
        throw Error(name + ": no board pose (degenerate view)");
    double pose[6];
    for (int k = 0; k < 3; k++) {
        pose[k] = rv.at<double>(k);
        pose[3 + k] = tv.at<double>(k);
    }
    // Two fits: unweighted, then weighted by the corner noise estimated separately along u and v
    // (a board lying on the floor is foreshortened vertically: its corners are located less
    // precisely in v than in u, and a pooled variance would understate tilt and overstate yaw).
    double w[2] = {1.0, 1.0};
    const int n = (int)obj.size();
    double su2 = 0, sv2 = 0;
    auto fit = [&](ceres::Problem &problem) {
        for (size_t i = 0; i < obj.size(); i++)
            problem.AddResidualBlock(new ceres::NumericDiffCostFunction<PoseReproj, ceres::CENTRAL, 2, 6>(
                                         new PoseReproj{&cam, obj[i].x, obj[i].y, corners[i].x, corners[i].y, w}),
                                     nullptr, pose);
        const ceres::Solver::Options so = calib_detail::tight_solver_options(ceres::DENSE_QR, 100);
        ceres::Solver::Summary sum;
        ceres::Solve(so, &problem, &sum);
        if (!sum.IsSolutionUsable()) throw Error(name + ": board pose fit failed: " + sum.message);
        su2 = sv2 = 0;
        const double w0[2] = {1.0, 1.0};
        for (size_t i = 0; i < obj.size(); i++) {
            double r[2] = {0, 0};
            PoseReproj{&cam, obj[i].x, obj[i].y, corners[i].x, corners[i].y, w0}(pose, r);
            su2 += r[0] * r[0];
            sv2 += r[1] * r[1];
        }
    };
    ceres::Problem p1;
    fit(p1);
    // 6 parameters: 3 degrees of freedom charged to each axis
    double var_u = std::max(su2 / (n - 3), 1e-8), var_v = std::max(sv2 / (n - 3), 1e-8);
    w[0] = 1 / std::sqrt(var_u);
    w[1] = 1 / std::sqrt(var_v);
    ceres::Problem problem;
    fit(problem);
    MountEstimate e;
    e.name = name;
    e.n_points = n;
    e.rms_px = std::sqrt((su2 + sv2) / n);
    const double sigma2 = 1.0;  // the residuals are already divided by their sigmas
    ceres::Covariance::Options co;
    co.algorithm_type = ceres::DENSE_SVD;
    ceres::Covariance cov(co);
    std::vector<std::pair<const double *, const double *>> blk{{pose, pose}};
    if (!cov.Compute(blk, &problem)) throw Error(name + ": degenerate view (board pose not observable)");
    double C[36];
    cov.GetCovarianceBlock(pose, pose, C);

    int flip = 1;
    std::array<double, 6> m = mount_from_pose(pose, b, pl, 1);
    if (std::fabs(m[2]) > kPi / 2) {
        flip = -1;
        m = mount_from_pose(pose, b, pl, -1);
    }
    // Jacobian of the mount values w.r.t. the pose (central differences)
    double J[6][6];
    for (int k = 0; k < 6; k++) {
        double h = k < 3 ? 1e-7 : 1e-7 * std::max(1.0, std::fabs(pose[k]));
        double pp[6], pm[6];
        for (int i = 0; i < 6; i++) pp[i] = pm[i] = pose[i];
        pp[k] += h;
        pm[k] -= h;
        auto a = mount_from_pose(pp, b, pl, flip), c = mount_from_pose(pm, b, pl, flip);
        for (int i = 0; i < 6; i++) {
            double dd = a[i] - c[i];
            if (i >= 1 && i <= 3) dd = std::remainder(dd, 2 * kPi);
            J[i][k] = dd / (2 * h);
        }
    }
    for (int i = 0; i < 6; i++)
        for (int j = 0; j < 6; j++) {
            double s = 0;
            for (int k = 0; k < 6; k++)
                for (int l = 0; l < 6; l++) s += J[i][k] * C[k * 6 + l] * J[j][l];
            e.cov[i][j] = s * sigma2;
        }
    e.height_floor_m = m[0];
    e.tilt_rad = m[1];
    e.yaw_rad = m[2];
    e.roll_rad = m[3];
    e.offset_m = m[4];
    e.lateral_m = m[5];
    for (int i = 0; i < 6; i++) e.sigma[i] = std::sqrt(std::max(0.0, e.cov[i][i]));
    return e;
}

MountSummary summarise_mount(const std::vector<MountEstimate> &es)
{
    MountSummary s;
    s.n = (int)es.size();
    if (es.empty()) return s;
    auto val = [](const MountEstimate &e, int i) {
        const double v[6] = {e.height_floor_m, e.tilt_rad, e.yaw_rad, e.roll_rad, e.offset_m, e.lateral_m};
        return v[i];
    };
    for (int i = 0; i < 6; i++) {
        double m = 0, w = 0;
        for (const auto &e : es) {
            m += val(e, i);
            w += e.sigma[i] * e.sigma[i];
        }
        m /= s.n;
        double v = 0;
        for (const auto &e : es) v += (val(e, i) - m) * (val(e, i) - m);
        s.mean[i] = m;
        s.spread[i] = s.n > 1 ? std::sqrt(v / (s.n - 1)) : 0.0;
        s.within[i] = std::sqrt(w / s.n);
    }
    return s;
}

} // namespace calib
} // namespace cylfe
