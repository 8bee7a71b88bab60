#include "point_statistics.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <limits>

#include "statistics.hpp"

namespace geoanchor::solver {

void test_point(const PointTestInput& in, double sigma_scale, double lambda0, PointResult& pr) {
  const Eigen::Vector3d vw = in.w * in.v_m;
  pr.residual_enu_m = in.enu * in.v_m;

  // The point test over the redundant directions of Q (all three unless the
  // point alone determines some parameter).
  double stat = 0.0;
  int rank = 0;
  const Eigen::LLT<Eigen::Matrix3d> llt(in.q);
  if (llt.info() == Eigen::Success && llt.matrixLLT().diagonal().minCoeff() > 1e-5) {
    stat = vw.dot(llt.solve(vw));
    rank = 3;
  } else {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> qe(in.q);
    for (int e = 0; e < 3; ++e) {
      if (qe.eigenvalues()(e) > 1e-9) {
        const double proj = qe.eigenvectors().col(e).dot(vw);
        stat += proj * proj / qe.eigenvalues()(e);
        ++rank;
      }
    }
  }
  pr.point_statistic = stat / (sigma_scale * sigma_scale);
  pr.point_dof = rank;
  pr.point_p_value = rank > 0 ? chi_squared_upper_tail(rank, pr.point_statistic) : 1.0;

  // w-tests (Baarda) for a blunder along each local axis.
  pr.w_max = 0.0;
  pr.mdb_m = in.in_fit ? 0.0 : std::numeric_limits<double>::quiet_NaN();  // outside the fit: no detectability
  for (int axis = 0; axis < 3; ++axis) {
    const Eigen::Vector3d b = in.w * in.enu.row(axis).transpose();  // blunder direction, whitened
    const double q = b.dot(in.q * b);
    if (!(q > 1e-12 * b.squaredNorm())) {  // no redundancy along this axis: the blunder is invisible
      pr.w_enu(axis) = 0.0;
      pr.redundancy_enu(axis) = 0.0;
      pr.mdb_m = std::numeric_limits<double>::infinity();
      continue;
    }
    const double w = b.dot(vw) / std::sqrt(q) / sigma_scale;  // τ-test when σ0 is estimated
    pr.w_enu(axis) = w;
    pr.w_max = std::max(pr.w_max, std::fabs(w));
    if (in.in_fit) {
      pr.redundancy_enu(axis) = q / b.squaredNorm();
      pr.mdb_m = std::max(pr.mdb_m, std::sqrt(lambda0) * sigma_scale / std::sqrt(q));
    } else {
      pr.redundancy_enu(axis) = 0.0;
    }
  }
}

void fill_global_test(FitResult& r, double omega, int dof, double alpha, bool a_priori_sigmas) {
  r.dof = dof;
  r.sigma0 = dof > 0 ? std::sqrt(omega / dof) : 0.0;
  auto& g = r.global_test;
  g.statistic = omega;
  g.applicable = a_priori_sigmas && dof > 0;
  if (dof > 0) {
    g.critical_lower = chi_squared_quantile(dof, alpha / 2.0);
    g.critical_upper = chi_squared_quantile(dof, 1.0 - alpha / 2.0);
    g.passed = omega >= g.critical_lower && omega <= g.critical_upper;
  }
}

Eigen::MatrixXd correlation_of(const Eigen::MatrixXd& cov) {
  Eigen::MatrixXd c = cov;
  for (Eigen::Index a = 0; a < cov.rows(); ++a) {
    for (Eigen::Index b = 0; b < cov.cols(); ++b) c(a, b) = cov(a, b) / std::sqrt(cov(a, a) * cov(b, b));
  }
  return c;
}

std::optional<std::size_t> snoop(FitResult& r, const std::vector<std::size_t>& active, const FitOptions& o, int u) {
  const int n = static_cast<int>(active.size());
  if (!o.data_snooping || r.dof <= 0 || 3 * (n - 1) - u <= 0) return std::nullopt;
  double worst_p = 1.0;
  std::optional<std::size_t> worst;
  for (std::size_t k = 0; k < active.size(); ++k) {
    const auto& p = r.points[active[k]];
    if (p.point_dof > 0 && p.point_p_value < worst_p) {
      worst_p = p.point_p_value;
      worst = k;
    }
  }
  if (!worst || worst_p >= o.alpha_point) return std::nullopt;
  PointResult& pr = r.points[active[*worst]];
  char why[200];
  std::snprintf(why, sizeof why, "data snooping: point test %.4g (χ²(%d), p = %.2g < %.3g); max |w| %.3g", pr.point_statistic,
                pr.point_dof, pr.point_p_value, o.alpha_point, pr.w_max);
  pr.outlier = true;
  pr.used = false;
  pr.removed_because = why;
  return worst;
}

}  // namespace geoanchor::solver
