#pragma once
// The statistics every estimator reports, in one implementation (Baarda's
// B-method as geodesists apply it): σ0 and the two-sided χ² global test,
// w-tests per local axis, redundancy numbers, minimal detectable biases,
// the multi-dimensional point test, data snooping with its limit, the
// geometry check from the parameter covariance, and the warnings that go
// with them. helmert_fit.cpp, enu_origin_fit.cpp and site_calibration_fit.cpp
// all call these; nothing here knows a model.

#include <Eigen/Core>

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "geoanchor/solver/helmert_fit.hpp"

namespace geoanchor::solver {

struct PointTestInput {
  Eigen::Vector3d v_m;    // residual (target − model), metres, in the axes of `w`'s input
  Eigen::Matrix3d w;      // whitening: Wᵀ W = C⁻¹
  Eigen::Matrix3d q;      // cofactor of the whitened residual: I − A N⁻¹ Aᵀ in the fit, I + A N⁻¹ Aᵀ outside
  Eigen::Matrix3d enu;    // rows: local east, north, up in the residual's axes
  bool in_fit = true;
};

// The tests of one observation of k components (a mark's three
// coordinates, a GNSS baseline, a distance): `v` its residual, `w` the
// whitening (Wᵀ W = C⁻¹), `q` the cofactor of the whitened residual
// (I − A N⁻¹ Aᵀ in the adjustment, I + A N⁻¹ Aᵀ for one tested against
// it), `axes` the directions in the observation's space along which
// blunders are tested (rows, unit length: the local E, N, U of a mark, the
// identity for a measurement's own components).
// How much leverage (Σ over removed points of 1 − mean redundancy) one
// snooping pass may remove at once; see snoop().
inline constexpr double kSnoopLeverageBudget = 0.01;

struct ObservationTest {
  Eigen::VectorXd w;           // per axis (NaN: no redundancy along it)
  Eigen::VectorXd redundancy;  // per axis: the diagonal of Q_v P there (0 outside the adjustment, or without redundancy)
  Eigen::VectorXd mdb;         // per axis, in the observation's units (inf: undetectable; NaN outside)
  double w_max = 0.0;
  double statistic = 0.0;      // vᵀ Q⁺ v of the whitened residual: χ²(dof) under H0
  int dof = 0;
  double p_value = 1.0;
};
ObservationTest test_observation(const Eigen::VectorXd& v, const Eigen::MatrixXd& w, const Eigen::MatrixXd& q,
                                 const Eigen::MatrixXd& axes, bool in_fit, double sigma_scale, double lambda0);

// The two-sided χ² global test of Ω = Σ vᵀPv with `dof` degrees of
// freedom at `alpha`; applicable with a-priori sigmas and redundancy.
GlobalTest global_test(double omega, int dof, double alpha, bool applicable);

// Which failing items (worst first: ascending p-value) one pass of data
// snooping removes: the first, then more while their leverages (1 − mean
// redundancy) add up to at most kSnoopLeverageBudget and `may_take(count)`
// allows `count` of them. Returns indices into `failing`.
struct SnoopCandidate {
  double p_value = 1.0;
  double leverage = 0.0;
};
std::vector<std::size_t> snoop_selection(const std::vector<SnoopCandidate>& failing,
                                         const std::function<bool(std::size_t)>& may_take);

// Fills residual_enu_m, w_enu, w_max, redundancy_enu, mdb_m and the point
// test of `pr`. `sigma_scale` is σ̂0 when σ0 is estimated (τ-tests), else 1;
// `lambda0` the non-centrality for the MDB. An axis along which the point
// has no redundancy cannot be tested: its w is NaN (writers show "-" or
// null), its redundancy 0 and the MDB infinite.
void test_point(const PointTestInput& in, double sigma_scale, double lambda0, PointResult& pr);

// The critical |w| and the MDB's non-centrality at the options' alpha_point
// and power.
struct PointTestLevels {
  double w_critical = 0.0;
  double lambda0 = 0.0;
};
PointTestLevels point_test_levels(const FitOptions& o);

// σ0 (undefined, std::nullopt, when dof = 0), dof and the two-sided χ²
// global test of Ω = Σ vᵀPv into `r`.
void fill_global_test(FitResult& r, double omega, int dof, double alpha, bool a_priori_sigmas);

// σ̂0 when the options scale by it (and it is defined), else 1.
double sigma_scale(const FitResult& r, const FitOptions& o);

// The correlation matrix of a covariance matrix.
Eigen::MatrixXd correlation_of(const Eigen::MatrixXd& cov);

// One step of data snooping after the points in `active` were tested in
// the fit: the point with the smallest point-test p-value below
// alpha_point is removed from `active` (marked in `r`) and `removed` is
// returned, so that the caller refits; in large networks further failing
// points go in the same step while their leverage is small (see
// kSnoopLeverageBudget). A failing point is never kept
// silently: when too few points would remain (fewer than `min_points`, or no
// redundancy), or when removing it would take data snooping past the
// options' max_outlier_share of the marks, it stays in the fit, a warning
// names it, and past the share `r.refused_because` says the data or the
// model is wrong and which test failed.
enum class SnoopStep { none, removed, stopped };
SnoopStep snoop(FitResult& r, std::vector<std::size_t>& active, const FitOptions& o, int u, int min_points);

// The largest number of marks data snooping may remove from `n` marks.
std::size_t max_snooped(std::size_t n, const FitOptions& o);

// The geometry check: `scaled_cov` is the parameter covariance in units
// where every parameter moves the points by metres at the network's RMS
// radius (translations in m, rotations and scale times that radius, rates
// times the epoch spread too); `translations` are the rows of the static
// translations in it. D = sqrt(λmax / mean translation variance) compares the
// worst-determined combination of parameters with the translation, which
// any n marks determine to σ/√n: about 1–1.5 for marks spread around their
// centroid, the aspect ratio for an elongated network, and without bound as
// a combination becomes unobservable (marks on a line: the rotation about
// it). Returns D and the unit eigenvector of λmax (in the covariance's order).
struct GeometryDilution {
  double dilution = 0.0;
  Eigen::VectorXd direction;
};
GeometryDilution geometry_dilution(const Eigen::MatrixXd& scaled_cov, const std::vector<int>& translations);

// Above this dilution a fit is refused (E_FIT_WEAK_GEOMETRY: a network
// 1000 times longer than wide is a line); above the warning level (a
// corridor ten times longer than wide) the weak combination is named.
inline constexpr double kRefuseDilution = 1000.0;
inline constexpr double kWarnDilution = 10.0;

// The common closing warnings: low redundancy, the global test's verdict,
// and, when data snooping removed marks, how many fail by chance alone at
// alpha_point and how much that lowers σ0 (so that a global test failing low
// after snooping a large set is read for what it is).
void add_statistics_warnings(FitResult& r, const FitOptions& o);

}  // namespace geoanchor::solver
