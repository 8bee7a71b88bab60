#include "fit_common.hpp"

#include <cstdio>

#include "geoanchor/geodesy/error.hpp"

namespace geoanchor::solver {

void reject(const std::string& code, const std::string& message) { throw Error(ErrorKind::rejected, code, message); }

std::string fmt(double v, int precision) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*g", precision, v);
  return b;
}

Eigen::MatrixXd symmetric(const Eigen::MatrixXd& c) { return 0.5 * (c + c.transpose()); }

std::vector<std::size_t> init_points(FitResult& result, const geodesy::ControlSet& control) {
  std::vector<std::size_t> active;
  result.points.resize(control.points.size());
  for (std::size_t i = 0; i < control.points.size(); ++i) {
    result.points[i].id = control.points[i].id;
    result.points[i].line = control.points[i].line;
    result.points[i].used = control.points[i].use;
    if (control.points[i].use) {
      active.push_back(i);
    } else {
      result.points[i].removed_because = "use = 0 in the control set";
    }
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
  if (summary.termination_type != ceres::CONVERGENCE) {
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
