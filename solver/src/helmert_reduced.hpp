#pragma once
// The Helmert fit's least squares: the normal equations reduced to
// sufficient statistics, solved by Ceres in scaled units, with the
// parameters' covariance (ceres::Covariance).
//
// Private to solver.

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

#include "geoanchor/solver/helmert_fit.hpp"
#include "helmert_model.hpp"

namespace geoanchor::solver {

// θ' as solved, with its covariance (σ0 = 1) and the solver's account.
struct HelmertSolution {
  std::array<double, kMaxParams> theta{};  // centred, solver units
  Eigen::MatrixXd cov_centred;             // over `estimated` indices, a-priori σ0 = 1
  Eigen::MatrixXd cov_scaled;              // the same in the scaled units (every column metres at the RMS radius)
  std::vector<int> estimated;              // indices into θ
  int iterations = 0;
  std::string report;
};

// Parameters are solved in scaled units so that every Jacobian column has
// the size of a displacement in metres: rotations and scale times the
// network's RMS radius L, rates times the RMS epoch spread D as well.
// ceres::Covariance does no column scaling of its own, and unscaled
// radians-per-year columns would make a sound 14-parameter problem look
// rank-deficient.
struct ParameterScales {
  double l = 1.0, d = 1.0;
  std::array<double, kMaxParams> param{};
};

ParameterScales parameter_scale(const std::vector<MarkObservation>& obs);

// θ' and its covariance for the marks' observations (with `td`, helmert14:
// the epochs and velocities too), the model's parameters estimated.
HelmertSolution solve_helmert(const std::vector<MarkObservation>& obs, const std::vector<MarkVelocity>& velocities,
                              const FitOptions& o, bool td);

}  // namespace geoanchor::solver
