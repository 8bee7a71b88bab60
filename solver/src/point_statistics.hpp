#pragma once
// The tests of one control point's residual, shared by every model.

#include <Eigen/Core>

#include <functional>
#include <optional>
#include <vector>

#include "geoanchor/solver/helmert_fit.hpp"

namespace geoanchor::solver {

namespace detail {
// ∂target/∂θ (3 × u, θ the estimated parameters in any units) and Σθ in the
// same units, as a function of the source point and its epoch.
struct Propagation {
  std::function<Eigen::MatrixXd(const geodesy::EcefPosition&, std::optional<geodesy::DecimalYear>)> jacobian;
  Eigen::MatrixXd covariance;
};
}  // namespace detail

struct PointTestInput {
  Eigen::Vector3d v_m;    // residual (target − model), ECEF metres
  Eigen::Matrix3d w;      // whitening: Wᵀ W = C⁻¹
  Eigen::Matrix3d q;      // cofactor of the whitened residual: I − A N⁻¹ Aᵀ in the fit, I + A N⁻¹ Aᵀ outside
  Eigen::Matrix3d enu;    // rows: local east, north, up in ECEF
  bool in_fit = true;
};

// Fills residual_enu_m, w_enu, w_max, redundancy_enu, mdb_m and the point
// test of `pr`. `sigma_scale` is σ̂0 when σ0 is estimated (τ-tests), else 1;
// `lambda0` the non-centrality for the MDB.
void test_point(const PointTestInput& in, double sigma_scale, double lambda0, PointResult& pr);

// σ0, dof and the two-sided χ² global test of Ω = Σ vᵀPv into `r`.
void fill_global_test(FitResult& r, double omega, int dof, double alpha, bool a_priori_sigmas);

// The correlation matrix of a covariance matrix.
Eigen::MatrixXd correlation_of(const Eigen::MatrixXd& cov);

// If data snooping removes a point now, marks it in `r` and returns its index
// in `active` (the point with the smallest point-test p-value below
// alpha_point, while the fit keeps redundancy); std::nullopt otherwise.
std::optional<std::size_t> snoop(FitResult& r, const std::vector<std::size_t>& active, const FitOptions& o, int u);

}  // namespace geoanchor::solver
