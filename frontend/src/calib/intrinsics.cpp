// SPDX-License-Identifier: BSD-3-Clause
// cylfe::calib -- chessboard detection and the intrinsic calibration (calib.hpp).
#include "cylfe/calib.hpp"
#include "solver.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>

#include <ceres/ceres.h>
#include <ceres/rotation.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>  // cv::IMREAD_* only

#include "cylfe/media.hpp"
#include <opencv2/imgproc.hpp>

#include "cylfe/error.hpp"

namespace cylfe {
namespace calib {

std::vector<cv::Point3f> board_points(const Board &b)
{
    std::vector<cv::Point3f> p;
    p.reserve((size_t)b.rows * b.cols);
    for (int r = 0; r < b.rows; r++)
        for (int c = 0; c < b.cols; c++) p.emplace_back(float(c * b.square), float(r * b.square), 0.f);
    return p;
}

bool find_corners(const cv::Mat &gray, const Board &b, const DetectOptions &o, std::vector<cv::Point2f> &corners)
{
    int flags = cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE;
    if (o.fast_check) flags |= cv::CALIB_CB_FAST_CHECK;
    corners.clear();
    if (!cv::findChessboardCorners(gray, cv::Size(b.cols, b.rows), corners, flags)) return false;
    // the refinement window must not reach the neighbouring corners: at most half the smallest
    // spacing between adjacent corners (small or foreshortened boards, e.g. lying on the floor)
    double dmin = 1e30;
    for (int r = 0; r < b.rows; r++)
        for (int c = 0; c < b.cols; c++) {
            const cv::Point2f &p = corners[(size_t)r * b.cols + c];
            if (c + 1 < b.cols) dmin = std::min(dmin, (double)cv::norm(p - corners[(size_t)r * b.cols + c + 1]));
            if (r + 1 < b.rows) dmin = std::min(dmin, (double)cv::norm(p - corners[(size_t)(r + 1) * b.cols + c]));
        }
    int half = o.subpix_half_window;
    if (o.adaptive_window) half = std::max(2, std::min(half, (int)std::floor(0.5 * std::min(dmin, 1e6))));
    cv::cornerSubPix(gray, corners, cv::Size(half, half), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, o.subpix_max_iter, o.subpix_eps));
    return corners.size() == (size_t)b.rows * (size_t)b.cols;
}

std::vector<View> detect_views(const std::vector<std::string> &paths, const Board &b, const DetectOptions &o,
                               cv::Size &image_size, const std::function<void(const std::string &)> &warn,
                               const std::function<void(size_t, size_t)> &progress, double min_area_frac)
{
    std::vector<View> views;
    image_size = cv::Size();
    for (size_t i = 0; i < paths.size(); i++) {
        if (progress) progress(i, paths.size());
        const std::string &p = paths[i];
        cv::Mat gray;
        try {
            gray = cylfe::media::imread(p, cv::IMREAD_GRAYSCALE);
        } catch (const cv::Exception &e) {
            throw Error(p + ": unreadable image: " + e.what());
        }
        if (gray.empty()) throw Error(p + ": unreadable image (missing file or not an image OpenCV can decode)");
        if (image_size.area() == 0)
            image_size = gray.size();
        else if (gray.size() != image_size)
            throw Error(p + ": image size " + std::to_string(gray.cols) + "x" + std::to_string(gray.rows) +
                        " differs from the first image's " + std::to_string(image_size.width) + "x" +
                        std::to_string(image_size.height));
        View v;
        v.name = p;
        if (!find_corners(gray, b, o, v.corners)) {
            if (warn) warn(p + ": chessboard (" + std::to_string(b.cols) + "x" + std::to_string(b.rows) +
                           " inner corners) not found; image skipped");
            continue;
        }
        std::vector<cv::Point2f> hull;
        cv::convexHull(v.corners, hull);
        double area = cv::contourArea(hull);
        if (!(area >= min_area_frac * image_size.area())) {
            if (warn) warn(p + ": degenerate view (the board covers " + std::to_string(100.0 * area / image_size.area()) +
                           "% of the image); image skipped");
            continue;
        }
        views.push_back(std::move(v));
    }
    if (progress) progress(paths.size(), paths.size());
    return views;
}

namespace {

// The libcyl camera for a parameter vector (fy from fx when the aspect is fixed).
inline void make_camera(const double *in, double fy_from_fx, cyl_camera &cam)
{
    cam.fx_px = in[0];
    cam.fy_px = fy_from_fx > 0 ? in[0] * fy_from_fx : in[1];
    cam.cx_px = in[2];
    cam.cy_px = in[3];
    cam.k1 = in[4];
    cam.k2 = in[5];
    cam.p1 = in[6];
    cam.p2 = in[7];
    cam.k3 = in[8];
}

// One corner's reprojection residual (px): board point -> camera frame (angle-axis + t) ->
// normalised pinhole point -> libcyl's lens model (cyl_camera_project). Differentiated
// numerically (central differences) so that the lens model stays in one place, the C core.
struct Reproj {
    double X, Y, Z, u, v, fy_from_fx;
    bool operator()(const double *in, const double *pose, double *res) const
    {
        double p[3] = {X, Y, Z}, q[3];
        ceres::AngleAxisRotatePoint(pose, p, q);
        q[0] += pose[3];
        q[1] += pose[4];
        q[2] += pose[5];
        if (!(q[2] > 1e-12)) return false;
        cyl_camera cam;
        make_camera(in, fy_from_fx, cam);
        double pu, pv;
        cyl_camera_project(&cam, q[0] / q[2], q[1] / q[2], &pu, &pv);
        res[0] = pu - u;
        res[1] = pv - v;
        return std::isfinite(res[0]) && std::isfinite(res[1]);
    }
};

double view_sse(const double *in, double fy_from_fx, const double *pose, const std::vector<cv::Point3f> &obj,
                const std::vector<cv::Point2f> &img)
{
    double s = 0;
    for (size_t j = 0; j < obj.size(); j++) {
        Reproj r{obj[j].x, obj[j].y, obj[j].z, img[j].x, img[j].y, fy_from_fx};
        double e[2];
        if (!r(in, pose, e)) return INFINITY;
        s += e[0] * e[0] + e[1] * e[1];
    }
    return s;
}

} // namespace

cyl_camera IntrinsicResult::camera() const
{
    cyl_camera cam;
    cyl_camera_init(&cam);
    cam.width = (uint32_t)image_size.width;
    cam.height = (uint32_t)image_size.height;
    make_camera(intr, 0, cam);
    for (int i = 0; i < CYL_INTR_COUNT; i++)
        for (int j = 0; j < CYL_INTR_COUNT; j++) cam.intr_cov[i][j] = cov[i][j];
    cam.flags &= ~CYL_CAM_INTR_COV_UNKNOWN;
    return cam;
}

IntrinsicResult calibrate_intrinsics(const std::vector<std::vector<cv::Point3f>> &obj,
                                     const std::vector<std::vector<cv::Point2f>> &img, cv::Size image_size,
                                     const IntrinsicOptions &opt, const std::vector<std::string> &names)
{
    const size_t nv = obj.size();
    if (nv != img.size()) throw Error("calibrate_intrinsics: object and image point lists differ in length");
    if (nv < 3) throw Error("intrinsic calibration needs at least 3 usable views, got " + std::to_string(nv));
    if (image_size.width < 2 || image_size.height < 2) throw Error("intrinsic calibration: bad image size");
    int npts = 0;
    for (size_t i = 0; i < nv; i++) {
        if (obj[i].size() != img[i].size() || obj[i].size() < 4)
            throw Error("intrinsic calibration: view " + std::to_string(i) + " has too few or mismatched points");
        npts += (int)obj[i].size();
    }

    // ---- closed-form start: focal length from the views' homographies (Zhang), principal
    // point at the image centre, no distortion; each view's pose by PnP.
    cv::Mat K0 = cv::initCameraMatrix2D(obj, img, image_size, 0.0);
    double fy_from_fx = 0.0;
    if (opt.fix_aspect) {
        fy_from_fx = opt.aspect > 0 ? opt.aspect : K0.at<double>(1, 1) / K0.at<double>(0, 0);
        K0.at<double>(1, 1) = K0.at<double>(0, 0) * fy_from_fx;
    }
    double in[CYL_INTR_COUNT] = {K0.at<double>(0, 0), K0.at<double>(1, 1), K0.at<double>(0, 2), K0.at<double>(1, 2),
                                 0, 0, 0, 0, 0};
    if (!(in[0] > 0) || !(in[1] > 0) || !std::isfinite(in[0]) || !std::isfinite(in[1]))
        throw Error("intrinsic calibration: no closed-form start (degenerate views: are all boards parallel to the image?)");
    std::vector<std::array<double, 6>> poses(nv);
    for (size_t i = 0; i < nv; i++) {
        cv::Mat rv, tv;
        if (!cv::solvePnP(obj[i], img[i], K0, cv::noArray(), rv, tv, false, cv::SOLVEPNP_ITERATIVE))
            throw Error("intrinsic calibration: no pose for view " + (i < names.size() ? names[i] : std::to_string(i)));
        for (int k = 0; k < 3; k++) {
            poses[i][k] = rv.at<double>(k);
            poses[i][3 + k] = tv.at<double>(k);
        }
    }

    // ---- Ceres refinement
    ceres::Problem::Options po;
    po.manifold_ownership = ceres::TAKE_OWNERSHIP;
    ceres::Problem problem(po);
    for (size_t i = 0; i < nv; i++)
        for (size_t j = 0; j < obj[i].size(); j++) {
            auto *cf = new ceres::NumericDiffCostFunction<Reproj, ceres::CENTRAL, 2, CYL_INTR_COUNT, 6>(
                new Reproj{obj[i][j].x, obj[i][j].y, obj[i][j].z, img[i][j].x, img[i][j].y, fy_from_fx});
            problem.AddResidualBlock(cf, nullptr, in, poses[i].data());
        }
    std::vector<int> fixed;
    if (opt.fix_aspect) fixed.push_back(CYL_INTR_FY);
    if (opt.zero_tangent) {
        fixed.push_back(CYL_INTR_P1);
        fixed.push_back(CYL_INTR_P2);
    }
    if (opt.fix_k3) fixed.push_back(CYL_INTR_K3);
    if (!fixed.empty()) problem.SetManifold(in, new ceres::SubsetManifold(CYL_INTR_COUNT, fixed));
    const int n_free_intr = CYL_INTR_COUNT - (int)fixed.size();
    const int p = n_free_intr + 6 * (int)nv;
    if (2 * npts <= p) throw Error("intrinsic calibration: too few corners for the parameters");

    const ceres::Solver::Options so = calib_detail::tight_solver_options(ceres::DENSE_SCHUR, opt.max_iterations);
    ceres::Solver::Summary sum;
    ceres::Solve(so, &problem, &sum);
    if (!sum.IsSolutionUsable() || !std::isfinite(sum.final_cost))
        throw Error("intrinsic calibration: the optimisation failed: " + sum.message);

    IntrinsicResult r;
    r.image_size = image_size;
    r.iterations = (int)sum.iterations.size();
    r.n_points = npts;
    r.n_params = p;
    r.names = names;
    r.sse = 2.0 * sum.final_cost;
    r.rms = std::sqrt(r.sse / npts);
    r.sigma2 = r.sse / (2.0 * npts - p);
    for (int k = 0; k < CYL_INTR_COUNT; k++) r.intr[k] = in[k];
    if (opt.fix_aspect) r.intr[CYL_INTR_FY] = in[0] * fy_from_fx;

    // ---- covariance of the intrinsics (poses marginalised): (J^T J)^-1 * sigma^2
    ceres::Covariance::Options co;
    co.algorithm_type = ceres::DENSE_SVD;
    co.null_space_rank = 0;
    co.min_reciprocal_condition_number = 1e-14;
    co.num_threads = 1;
    ceres::Covariance covariance(co);
    std::vector<std::pair<const double *, const double *>> blocks{{in, in}};
    if (!covariance.Compute(blocks, &problem))
        throw Error("intrinsic calibration: degenerate view set, the intrinsics are not observable (covariance rank "
                    "deficient): add views with the board tilted in different directions");
    double c9[CYL_INTR_COUNT * CYL_INTR_COUNT];
    covariance.GetCovarianceBlock(in, in, c9);
    // with a fixed aspect, fy = a fx: its row and column follow fx's
    for (int i = 0; i < CYL_INTR_COUNT; i++)
        for (int j = 0; j < CYL_INTR_COUNT; j++) {
            double a = c9[i * CYL_INTR_COUNT + j];
            if (opt.fix_aspect) {
                int ii = i == CYL_INTR_FY ? CYL_INTR_FX : i, jj = j == CYL_INTR_FY ? CYL_INTR_FX : j;
                a = c9[ii * CYL_INTR_COUNT + jj] * (i == CYL_INTR_FY ? fy_from_fx : 1.0) *
                    (j == CYL_INTR_FY ? fy_from_fx : 1.0);
            }
            r.cov[i][j] = a * r.sigma2;
        }
    for (int k = 0; k < CYL_INTR_COUNT; k++) {
        r.sigma[k] = std::sqrt(std::max(0.0, r.cov[k][k]));
        if (!std::isfinite(r.sigma[k]))
            throw Error("intrinsic calibration: degenerate view set (non-finite covariance)");
    }

    // ---- per view
    for (size_t i = 0; i < nv; i++) {
        cv::Vec3d rv(poses[i][0], poses[i][1], poses[i][2]), tv(poses[i][3], poses[i][4], poses[i][5]);
        r.rvecs.push_back(rv);
        r.tvecs.push_back(tv);
        double s = view_sse(in, fy_from_fx, poses[i].data(), obj[i], img[i]);
        r.view_rms.push_back(std::sqrt(s / obj[i].size()));
        if (r.view_rms.back() > opt.outlier_factor * r.rms) r.outliers.push_back((int)i);
    }
    return r;
}

} // namespace calib
} // namespace cylfe
