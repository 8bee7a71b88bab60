#include "point_statistics.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
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

}  // namespace geoanchor::solver
