// SPDX-License-Identifier: BSD-3-Clause
// Internal to frontend/src/calib/: the Ceres settings every calibration fit uses (tight
// tolerances, single thread, silent), so that the fits converge to the same precision.
#pragma once
#include <ceres/ceres.h>

namespace cylfe {
namespace calib_detail {

inline ceres::Solver::Options tight_solver_options(ceres::LinearSolverType linear_solver, int max_iterations)
{
    ceres::Solver::Options so;
    so.linear_solver_type = linear_solver;
    so.max_num_iterations = max_iterations;
    so.function_tolerance = 1e-15;
    so.gradient_tolerance = 1e-14;
    so.parameter_tolerance = 1e-14;
    so.num_threads = 1;
    so.logging_type = ceres::SILENT;
    return so;
}

} // namespace calib_detail
} // namespace cylfe
