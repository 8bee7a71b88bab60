#pragma once
// What every fit shares: the point list, the Ceres solve with its checks,
// the covariance or a refusal, and message helpers.

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <string>
#include <vector>

#include "geoanchor/solver/helmert_fit.hpp"

namespace geoanchor::solver {

[[noreturn]] void reject(const std::string& code, const std::string& message);
std::string fmt(double v, int precision = 3);

// (C + Cᵀ) / 2: a propagated covariance J Σ Jᵀ is symmetric only up to
// rounding; the reported one is exactly.
Eigen::MatrixXd symmetric(const Eigen::MatrixXd& c);

// Fills result.points from the control set; returns the indices in use:
// the marks with use = 1 whose GNSS solution type options.solutions uses.
std::vector<std::size_t> init_points(FitResult& result, const geodesy::ControlSet& control, const FitOptions& options);

// Without a-priori sigmas: weights are equal, σ0 scales the sigmas, and the
// result says so.
void note_missing_sigmas(FitResult& result, FitOptions& options, const geodesy::ControlSet& control);

// Silences Ceres' own glog lines (below fatal), once per process.
void quiet_ceres_logging();

// Solves with tolerances at float64 noise (Ceres' defaults stop measurably
// short of the optimum); refuses anything but CONVERGENCE.
ceres::Solver::Summary solve_tightly(ceres::Problem& problem, ceres::LinearSolverType solver, int max_iterations);
// Whether a FAILURE of solve_tightly's is Ceres stalling at the optimum
// (its steps there move the cost only by its rounding), which
// solve_tightly takes as converged.
bool stopped_at_optimum(const ceres::Solver::Summary& summary);

// (JᵀJ)⁻¹ over `blocks` (u parameters in all) by ceres::Covariance
// (DENSE_SVD); refuses a rank-deficient problem.
Eigen::MatrixXd covariance_or_reject(ceres::Problem& problem, const std::vector<const double*>& blocks, int u);

}  // namespace geoanchor::solver
