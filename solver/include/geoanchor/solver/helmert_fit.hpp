#pragma once
// Least-squares fits of Helmert transforms to control points, with the
// statistics geodesists use to judge them.
//
// Model, per point i observed at epoch t_i (all ECEF, metres):
//   target_i = T(t_i) + (1 + ds(t_i)) · R(r(t_i)) · source_i + e_i
// with p(t) = p + ṗ·(t − t_ref) for helmert14 and p(t) = p otherwise.
// Errors are allowed in both frames: each point is weighted by the inverse
// of C_target + J C_source Jᵀ, with J = (1 + ds) R the linear part of the
// transform at the point's epoch: the solve runs first with J = I, then with
// J from the estimate until J changes by less than 1e-12 (two or three
// passes; it matters for large rotations of anisotropic covariances).
//
// The solve runs in Ceres on centroid-referenced parameters (well
// conditioned even for a 2 km network, where geocentric translations and
// rotations correlate above 0.9999); the geocentric parameters and their
// covariance follow exactly from those. Ceres sees the problem reduced to
// its sufficient statistics (12 residuals, 33 with epochs), which has the
// same minimiser and the same JᵀJ as the one with 3n residuals: fitting 10⁶
// points takes about a second. The parameter covariance is ceres::Covariance
// (DENSE_SVD) of that problem.
//
// Every model shares one implementation of the statistics (σ0 and the χ²
// global test, w-tests, redundancy numbers, MDB, point tests, data snooping
// and its limit, the geometry check): solver/src/point_statistics.hpp.

#include <Eigen/Core>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "geoanchor/geodesy/control_point.hpp"
#include "geoanchor/geodesy/gnss_solution.hpp"
#include "geoanchor/geodesy/helmert.hpp"
#include "geoanchor/geodesy/positions.hpp"
#include "geoanchor/geodesy/site_calibration.hpp"

namespace geoanchor::solver {

// molodensky_badekas: the seven parameters of helmert7 about a pivot p
// (default: the centroid of the used source points),
//   target = p + T + (1 + ds) · R · (source − p),
// where T is nearly uncorrelated with the rotations for a local network.
// enu_origin: map points in ENU at a nominal origin against surveyed
// positions: the corrected origin (a shift in the nominal E, N, U), a yaw
// and optionally a scale,
//   target = O' + R'ᵀ · (1 + ds) · Rz(yaw) · enu_map,
// with O' = O + Rᵀ · shift the corrected origin (R, R' the ENU rotations at
// O and O') and Rz(yaw) turning the map counter-clockwise seen from above.
// site_calibration: local site coordinates (e, n, u; read as ENU at the
// nominal origin) onto a Transverse Mercator grid at the site (k0 = 1 at the
// targets' mean latitude and longitude, unless site_grid is given) by a
// horizontal 4-parameter similarity, and onto ellipsoidal heights by an
// inclined plane (shift and two tilts): geodesy::SiteCalibration.
enum class FitModel { translation3, helmert6, helmert7, helmert14, molodensky_badekas, enu_origin, site_calibration };
std::string_view to_string(FitModel m);
enum class Convention { position_vector, coordinate_frame };

// Variance-component estimation (fit --vce, adjust --vce): the factors are
// iterated until none changes by more than this share, at most this often.
inline constexpr double kVceTolerance = 1e-5;
inline constexpr int kMaxVceIterations = 50;

struct FitOptions {
  FitModel model = FitModel::helmert7;
  // Required for models with rotations; never defaulted.
  std::optional<Convention> convention;
  geodesy::RotationModel rotation_model = geodesy::RotationModel::small_angle;
  // helmert14: defaults to the mean observation epoch of the used points.
  std::optional<geodesy::DecimalYear> reference_epoch;
  // molodensky_badekas: the pivot in ECEF metres (default the centroid).
  std::optional<Eigen::Vector3d> pivot_m;
  // enu_origin: the nominal origin of the map's ENU coordinates (required),
  // whether yaw and scale are estimated (else held at 0).
  std::optional<geodesy::LocalOrigin> nominal_origin;
  bool enu_yaw = true;
  bool enu_scale = false;
  // site_calibration: the grid (default: TM with k0 = 1 at the targets' centroid).
  std::optional<geodesy::ProjectionDef> site_grid;
  double alpha = 0.05;          // global test
  double alpha_point = 0.001;   // w-tests and data snooping
  double power = 0.80;          // for the minimal detectable bias
  // Data snooping (solver/src/snooping.hpp): the marks that fail their
  // point test are ranked in the order iterative snooping would remove them
  // (PointResult::snooping_rank; off: no ranks, for the fits inside
  // diagnose and --compare). They are flagged and kept unless
  // remove_outliers (fit --remove-outliers) removes them in that order.
  bool data_snooping = true;
  bool remove_outliers = false;
  // Data snooping removes at most this share of the marks (at least one);
  // when a mark still fails past it the fit is refused (refused_because):
  // so many failures mean the data or the model is wrong, not blunders.
  double max_outlier_share = 0.10;
  // Ceres' iteration limit; a solve that has not converged within it is
  // refused (E_FIT_NO_CONVERGENCE), never reported as a result.
  int max_solver_iterations = 200;
  // Robust loss for exploration (iteratively reweighted least squares on
  // each point's standardized residual e: Huber w = min(1, K/e), Cauchy
  // w = 1/(1 + (e/K)²)). Statistics are then approximate; no snooping.
  enum class Robust { none, huber, cauchy };
  Robust robust = Robust::none;
  double robust_k = 1.5;
  // Variance-component estimation for the source and target groups: their
  // covariances are rescaled by estimated factors until consistent.
  bool vce = false;  // kVceTolerance, kMaxVceIterations
  // Scale the parameter covariance by σ0² (a posteriori) instead of using
  // the a-priori σ0 = 1. Forced when the control set has no a-priori sigmas.
  bool scale_by_sigma0 = false;
  // Marks with a GNSS solution type (geodesy::ControlPoint::solution):
  // exclude (default) leaves float and worse out of the fit, tested against
  // it as use = 0 marks are; weight uses float, dgps, sbas and standalone
  // with their sigmas multiplied by geodesy::solution_sigma_factor
  // (dead_reckoned stays out). Marks without a type are used as given.
  geodesy::SolutionPolicy solutions = geodesy::SolutionPolicy::exclude;
};

struct Parameter {
  std::string name;  // tx_m, rx_arcsec, ds_ppm, dtx_m_per_year, ...
  double value = 0.0;
  double sigma = 0.0;
  bool estimated = true;  // false for parameters the model holds fixed at 0
};

struct GlobalTest {
  double statistic = 0.0;       // Σ vᵀPv = σ0²·dof
  double critical_lower = 0.0;  // χ²(dof) at α/2
  double critical_upper = 0.0;  // χ²(dof) at 1 − α/2
  bool passed = false;          // statistic within [lower, upper]
  bool applicable = true;       // false without a-priori sigmas
  // Above the upper bound: the measurements disagree more than their
  // sigmas allow (what fit and adjust refuse to write unless accepted).
  bool failed_high() const { return applicable && !passed && statistic > critical_upper; }
  // "passed", "failed high", "failed low" or "not applicable" (the reports' JSON).
  const char* verdict() const { return !applicable ? "not applicable" : passed ? "passed" : failed_high() ? "failed high" : "failed low"; }
};

// What became of a mark (fit) or a measurement (adjust) in the tests: the
// status column of their tables. used: in the fit and passes its test;
// flagged: fails it and is kept (the default); removed: by data snooping
// (--remove-outliers) or by the input's tolerance; uncontrolled: no
// direction of its residual has redundancy enough to be tested
// (kMinRedundancy), so it is adjusted and never tested; ignored: left out
// by the input (use = 0, Ignore, a GNSS solution type left out).
enum class TestStatus { used, flagged, removed, uncontrolled, ignored };
const char* to_string(TestStatus s);

struct PointResult {
  std::string id;
  std::size_t line = 0;
  bool used = true;     // entered the final fit
  bool outlier = false; // removed by data snooping
  std::string removed_because;
  // Its place in the order iterative data snooping removes the failing
  // marks (1: first); 0 for a mark snooping would not remove.
  std::size_t snooping_rank = 0;
  // Flagged, but passes once the marks data snooping removes before it are
  // out: the rank after whose removal it passes (0: not so).
  std::size_t passes_after_rank = 0;
  Eigen::Vector3d residual_enu_m = Eigen::Vector3d::Zero();  // target − transformed source, local E, N, U
  Eigen::Vector3d w_enu = Eigen::Vector3d::Zero();           // w-test per local axis (NaN: untestable, no redundancy)
  Eigen::Vector3d redundancy_enu = Eigen::Vector3d::Zero();  // redundancy numbers per local axis
  double w_max = 0.0;
  double mdb_m = 0.0;  // largest minimal detectable bias over the three axes (inf: an axis without redundancy)
  // The point test: r̄ᵀ Q⁺ r̄ of the whitened residual over its controlled
  // directions, χ²(point_dof) under H0; it fails below alpha_point.
  double point_statistic = 0.0;
  int point_dof = 0;
  double point_p_value = 1.0;
  double point_log_p = 0.0;  // ln point_p_value, without underflow (the evidence snooping ranks by)
  double robust_weight = 1.0;  // with a robust loss: the final IRLS weight
  // The residual's covariance in local E, N, U (m²; for site-calibration:
  // grid E, grid N, up): C − A Σθ Aᵀ in the fit, C + A Σθ Aᵀ for a point
  // tested against it (its prediction), scaled like the parameter sigmas.
  Eigen::Matrix3d residual_cov_enu_m2 = Eigen::Matrix3d::Zero();
  TestStatus status(double alpha_point) const {
    return outlier ? TestStatus::removed
           : !used ? TestStatus::ignored
           : point_dof == 0 ? TestStatus::uncontrolled
           : point_p_value < alpha_point ? TestStatus::flagged
                                         : TestStatus::used;
  }
};

struct FitResult {
  FitModel model = FitModel::helmert7;
  Convention convention = Convention::position_vector;
  geodesy::RotationModel rotation_model = geodesy::RotationModel::small_angle;
  std::optional<geodesy::DecimalYear> reference_epoch;
  // The fitted transform as a geocentric Helmert, in position-vector form
  // (convert for reporting). For molodensky_badekas this is its geocentric
  // equivalent; `parameters` hold the pivot form.
  geodesy::Helmert14<geodesy::PositionVector> helmert;
  std::optional<Eigen::Vector3d> pivot_m;  // molodensky_badekas
  // enu_origin: the nominal and the corrected origin, and the whole
  // correction as an ECEF map (ECEF of the map read at the nominal origin ->
  // true ECEF).
  std::optional<geodesy::LocalOrigin> nominal_origin;
  std::optional<geodesy::LocalOrigin> corrected_origin;
  std::optional<geodesy::AffineMap> ecef_map;
  // site_calibration: the fitted calibration (residuals are in grid E, grid N
  // and up).
  std::optional<geodesy::SiteCalibration> site_calibration;
  // Parameters in the reported convention, units in their names, and the
  // covariance between the estimated ones (same order, same units).
  std::vector<Parameter> parameters;
  Eigen::MatrixXd covariance;
  Eigen::MatrixXd correlation;
  std::vector<std::string> covariance_names;
  bool covariance_scaled_by_sigma0 = false;
  std::optional<double> sigma0;  // a posteriori; undefined (nullopt) without redundancy
  int dof = 0;
  GlobalTest global_test;
  double w_critical = 0.0;  // |w| above this fails its w-test at alpha_point
  double alpha_point = 0.001;  // the options' (PointResult::status)
  std::vector<PointResult> points;  // in input order
  std::vector<std::string> warnings;
  // --vce: the estimated variance factors of the source and target
  // covariances (1 = the stated sigmas were right), and the iterations used.
  std::optional<std::pair<double, double>> variance_factors;
  int robust_iterations = 0;
  int ceres_iterations = 0;
  std::string ceres_report;  // one line
  // Set when the fit must not be written whatever the caller accepts (data
  // snooping reached its limit): why, naming the test that failed.
  std::string refused_because;
};

// The marks that fail their point test (flagged, or removed by data
// snooping), in the order data snooping removes them (snooping_rank), then
// the rest by evidence: what a refusal or report names first.
std::vector<std::size_t> failing_marks(const FitResult& r);

// Throws geoanchor::Error: `rejected` for ill-posed problems (too few
// points, coincident points, collinear or nearly collinear points — any
// combination of parameters the geometry leaves undetermined, named from
// the parameter covariance — one epoch for helmert14, Ceres failure,
// covariance not computable), `usage` for a missing convention.
FitResult fit_helmert(const geodesy::ControlSet& control, const FitOptions& options);

// The target position of `source` under the fitted transform at `epoch`
// (required for helmert14).
geodesy::EcefPosition apply_fit(const FitResult& fit, const geodesy::EcefPosition& source,
                                std::optional<geodesy::DecimalYear> epoch);

}  // namespace geoanchor::solver
