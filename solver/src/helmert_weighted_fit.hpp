#pragma once
// The weighted Helmert fit (fit_helmert for the Helmert models, without a
// robust loss), pass after pass: a pass per variance-component iteration
// (--vce) and per data-snooping removal, each over the marks still in use.
// WeightedFit holds what the passes share; FitPass what one pass finds.
//
// Private to solver.

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "geoanchor/geodesy/control_point.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/solver/helmert_fit.hpp"
#include "helmert_model.hpp"
#include "helmert_reduced.hpp"
#include "point_statistics.hpp"

namespace geoanchor::solver {

inline constexpr double kArcsecPerRad = 180.0 / M_PI * 3600.0;

// (ĀᵀĀ)⁻¹ over the estimated parameters, and a point's whitened design rows
// over them (at most 14 columns: on the stack).
using NormalMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxParams, kMaxParams>;
using PointJacobian = Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, kMaxParams>;

// What one pass finds, step by step.
struct FitPass {
  int n = 0;                                                      // marks in use
  Eigen::Vector3d cx = Eigen::Vector3d::Zero(), cy = Eigen::Vector3d::Zero();  // their source and target centroids
  std::vector<MarkObservation> obs;
  std::vector<MarkVelocity> velocities;
  HelmertSolution sol;
  int u = 0;    // parameters estimated
  int dof = 0;  // 3 n − u plus the velocity observations
  std::string geometry_warning;
  // Residuals (target − transformed source) and their whitened values, per
  // mark in use; the global test's σ̂0 scale of the tests.
  std::vector<Eigen::Vector3d> v, vw;
  double tau = 1.0;
  NormalMatrix n_inv;
  RotationWithDerivatives final_rotation;
  std::vector<Eigen::Matrix3d> qvs;  // whitened Q_vv per point, kept for --vce
  FitLinearization lin;              // the failing marks, for data snooping
};

// The geocentric parameters from a pass's θ' (solver units) and their
// covariance; as reported (Molodensky-Badekas: the translation at the pivot).
struct GeocentricEstimate {
  std::array<double, kMaxParams> g{};
  std::array<double, kMaxParams> reported{};
  Eigen::MatrixXd cov;
  bool mb = false;
};

struct WeightedFit {
  // Refuses a model with rotations and no convention; the result's points
  // and the marks in use (init_points), the test levels.
  WeightedFit(const geodesy::ControlSet& control, const FitOptions& options);

  const geodesy::ControlSet& control;
  const FitOptions& options;  // as given
  FitOptions o;               // as the fit uses them (missing sigmas noted, helmert14's reference epoch)
  bool td = false;            // helmert14: epochs and rates
  FitResult result;
  std::vector<std::size_t> active;  // the marks in the fit
  PointTestLevels levels;
  // Variance factors of the source and target covariances (--vce).
  double f_src = 1.0, f_dst = 1.0;
  int vce_iterations = 0;
  // Each mark's local east, north, up (rows, in ECEF) at its target
  // position: the axes of its residuals and w-tests, the same in every pass.
  std::vector<Eigen::Matrix3d> axes;
  std::vector<bool> have_axes;
  geodesy::GeocentricConverter geocentric;

  const Eigen::Matrix3d& local_axes(std::size_t i);
  // Weights from C_target + J C_source Jᵀ, J = (1 + ds(t)) R(r(t)) of the
  // current estimate (the identity before the first solve).
  Eigen::Matrix3d whitening(const geodesy::ControlPoint& p, const Eigen::Matrix3d& j) const;
  // J at θ for an epoch offset dt.
  Eigen::Matrix3d linear_part(const std::array<double, kMaxParams>& th, double dt) const;
  // The whitened design rows of a point over the estimated parameters.
  PointJacobian design(const FitPass& current, const MarkObservation& ob) const;

  // The steps of a pass, in order.
  void check_marks(FitPass& current);
  void observe(FitPass& current) const;
  void solve_weighted(FitPass& current) const;
  std::string weak_geometry(const FitPass& current) const;
  GeocentricEstimate geocentric_estimate(const FitPass& current);
  void set_helmert(const std::array<double, kMaxParams>& g);
  void residuals(FitPass& current);
  void test_marks(FitPass& current);
  bool next_variance_components(const FitPass& current);
  void test_marks_outside(const FitPass& current);
  FitResult report(const FitPass& current, GeocentricEstimate estimate);

  // Parts of the steps.
  void check_epochs(const FitPass& current);
  void check_spread(const FitPass& current) const;
  void report_parameters(const FitPass& current, const GeocentricEstimate& estimate);
  void warn_translation_correlation(const FitPass& current, const GeocentricEstimate& estimate);
  void warn_implausible_magnitudes();
};

}  // namespace geoanchor::solver
