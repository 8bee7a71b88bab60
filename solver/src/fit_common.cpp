#include "fit_common.hpp"

#include <cmath>

#include <cstdio>

#include "geoanchor/base/error.hpp"

namespace geoanchor::solver {

void reject(const std::string& code, const std::string& message) { throw Error(ErrorKind::rejected, code, message); }

std::string fmt(double v, int precision) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*g", precision, v);
  return b;
}

Eigen::MatrixXd symmetric(const Eigen::MatrixXd& c) { return 0.5 * (c + c.transpose()); }

std::vector<std::size_t> init_points(FitResult& result, const geodesy::ControlSet& control, const FitOptions& options) {
  std::vector<std::size_t> active;
  result.alpha_point = options.alpha_point;
  result.points.resize(control.points.size());
  for (std::size_t i = 0; i < control.points.size(); ++i) {
    const geodesy::ControlPoint& p = control.points[i];
    PointResult& r = result.points[i];
    r.id = p.id;
    r.line = p.line;
    r.used = p.use;
    if (!p.use) {
      r.removed_because = "use = 0 in the control set";
    } else if (p.solution && !geodesy::used_under(*p.solution, options.solutions)) {
      r.used = false;
      r.removed_because =
          "GNSS solution " + std::string(geodesy::to_string(*p.solution)) +
          (options.solutions == geodesy::SolutionPolicy::exclude
               ? ": float and worse are left out (--solution-weighting weighs float, dgps, sbas and standalone)"
               : ": a dead-reckoned position is left out even with --solution-weighting (no factor bounds its drift)");
    }
    if (r.used) active.push_back(i);
  }
  return active;
}

void note_missing_sigmas(FitResult& result, FitOptions& options, const geodesy::ControlSet& control) {
  if (control.has_a_priori_sigmas) return;
  options.scale_by_sigma0 = true;
  result.warnings.push_back("no a-priori sigmas in " + control.source_name +
                            ": equal weights; parameter sigmas are scaled by the a-posteriori σ0 and the global test is "
                            "not applicable");
}

void quiet_ceres_logging() {
  // Ceres reports through glog on standard error (rank deficiency, line
  // search failures); geoanchor checks every outcome itself and says what
  // went wrong, so those lines would only come first and confuse. Fatal
  // messages (a violated Ceres invariant) still print.
  static const bool once = [] {
    FLAGS_minloglevel = google::GLOG_FATAL;
    return true;
  }();
  (void)once;
}

// Whether Ceres stopped with FAILURE at the optimum: these tolerances are
// below the rounding of the cost, so there the trust region's steps only
// move the cost by its rounding; Ceres rejects them, shrinks the region,
// calls the null steps invalid and, after a few, gives up where it stands
// (seen for the enu-origin fit when Eigen's kernels round otherwise: a
// start already at the optimum, every step of 1e-13 raising a cost of 48
// by 3e-10). True when every step after the last accepted one moved the
// parameters by less than kNullStep and the cost by no more than its
// rounding.
bool stopped_at_optimum(const ceres::Solver::Summary& s) {
  constexpr double kNullStep = 1e-12;         // parameters (metres, or scaled to them)
  constexpr double kCostRounding = 1e-10;     // relative: the cost's evaluation at ECEF magnitudes
  if (s.termination_type != ceres::FAILURE || s.iterations.empty()) return false;
  std::size_t last = 0;
  for (std::size_t k = 0; k < s.iterations.size(); ++k) {
    if (s.iterations[k].step_is_successful) last = k;
  }
  if (last + 1 >= s.iterations.size()) return false;
  const double cost = s.iterations[last].cost;
  for (std::size_t k = last + 1; k < s.iterations.size(); ++k) {
    const auto& it = s.iterations[k];
    if (it.step_is_successful || !(it.step_norm <= kNullStep) || !(std::abs(it.cost_change) <= kCostRounding * cost)) return false;
  }
  return true;
}

ceres::Solver::Summary solve_tightly(ceres::Problem& problem, ceres::LinearSolverType solver, int max_iterations) {
  quiet_ceres_logging();
  ceres::Solver::Options so;
  so.linear_solver_type = solver;
  so.max_num_iterations = max_iterations;
  so.function_tolerance = 1e-16;
  so.gradient_tolerance = 1e-20;
  so.parameter_tolerance = 1e-15;
  so.num_threads = 1;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  if (summary.termination_type != ceres::CONVERGENCE && !stopped_at_optimum(summary)) {
    reject("E_FIT_NO_CONVERGENCE", "the least-squares solve did not converge (Ceres: " +
                                       std::string(ceres::TerminationTypeToString(summary.termination_type)) + " after " +
                                       std::to_string(summary.iterations.size()) + " iterations: " + summary.message +
                                       "); no transform was written");
  }
  return summary;
}

Eigen::MatrixXd covariance_or_reject(ceres::Problem& problem, const std::vector<const double*>& blocks, int u) {
  quiet_ceres_logging();
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::DENSE_SVD;
  co.null_space_rank = 0;
  ceres::Covariance covariance(co);
  if (!covariance.Compute(blocks, &problem)) {
    reject("E_FIT_COVARIANCE", "the parameter covariance cannot be computed: the normal matrix is rank-deficient (a "
                               "parameter is not observable from these points); no transform was written");
  }
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> c(u, u);
  if (!covariance.GetCovarianceMatrix(blocks, c.data())) {
    reject("E_FIT_COVARIANCE", "the parameter covariance could not be read back from Ceres");
  }
  return c;
}

}  // namespace geoanchor::solver
