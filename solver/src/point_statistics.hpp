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

// Below this redundancy a direction of a measurement's residual is not
// tested: the eigenvalues of the whitened residual cofactor Q (the
// redundancy numbers of the measurement's independent directions, 0 … 1 in
// the adjustment) are compared with it, and so is each axis's redundancy
// bᵀQb/bᵀb. Along such a direction a blunder shows in the residual at less
// than a thousandth of its size (its MDB is over 30 times the measurement's
// own σ·√λ0), and what the residual holds there is rounding: Q = I − A N⁻¹ Aᵀ
// is formed in double precision, so a redundancy of 1e-10 gives w-tests of
// a few units from rounding alone. A measurement with no direction above it
// is "uncontrolled": it is adjusted, never tested, never removed.
inline constexpr double kMinRedundancy = 1e-3;

// The test of one measurement (or mark) of k components over the
// directions of its residual that are controlled (the eigenvectors of Q
// with eigenvalue ≥ kMinRedundancy): statistic vᵀ Q⁺ v (over those
// directions; v whitened, divided by σ0² for τ-tests), χ²(dof) under H0,
// dof the number of those directions (0: uncontrolled, p = 1). log_p is
// ln p computed without underflow: the evidence data snooping ranks by.
struct MeasurementTest {
  double statistic = 0.0;
  int dof = 0;
  double p_value = 1.0;
  double log_p = 0.0;
};
MeasurementTest measurement_test(const Eigen::VectorXd& vw, const Eigen::MatrixXd& q, double sigma_scale);

// The tests of one observation of k components (a mark's three
// coordinates, a GNSS baseline, a distance): `v` its residual, `w` the
// whitening (Wᵀ W = C⁻¹), `q` the cofactor of the whitened residual
// (I − A N⁻¹ Aᵀ in the adjustment, I + A N⁻¹ Aᵀ for one tested against
// it), `axes` the directions in the observation's space along which
// blunders are tested (rows, unit length: the local E, N, U of a mark, the
// identity for a measurement's own components). The measurement test is
// measurement_test(); an axis whose redundancy is below kMinRedundancy has
// no w-test (NaN) and an infinite MDB.
// K: the observation's components (Eigen::Dynamic for any; 3 for a mark,
// on the stack: a million marks' tests allocate nothing).
template <int K>
struct ObservationTestOf {
  Eigen::Matrix<double, K, 1> w;           // per axis (NaN: uncontrolled along it)
  Eigen::Matrix<double, K, 1> redundancy;  // per axis: the diagonal of Q_v P there (0 outside the adjustment)
  Eigen::Matrix<double, K, 1> mdb;         // per axis, in the observation's units (inf: undetectable; NaN outside)
  double w_max = 0.0;
  double statistic = 0.0;      // vᵀ Q⁺ v of the whitened residual: χ²(dof) under H0
  int dof = 0;
  double p_value = 1.0;
  double log_p = 0.0;
};
using ObservationTest = ObservationTestOf<Eigen::Dynamic>;
ObservationTest test_observation(const Eigen::VectorXd& v, const Eigen::MatrixXd& w, const Eigen::MatrixXd& q,
                                 const Eigen::MatrixXd& axes, bool in_fit, double sigma_scale, double lambda0);
ObservationTestOf<3> test_observation(const Eigen::Vector3d& v, const Eigen::Matrix3d& w, const Eigen::Matrix3d& q,
                                      const Eigen::Matrix3d& axes, bool in_fit, double sigma_scale, double lambda0);

// The two-sided χ² global test of Ω = Σ vᵀPv with `dof` degrees of
// freedom at `alpha`; applicable with a-priori sigmas and redundancy.
GlobalTest global_test(double omega, int dof, double alpha, bool applicable);

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

// The correlation matrix of a covariance matrix, each entry by
// correlation_coefficient.
Eigen::MatrixXd correlation_of(const Eigen::MatrixXd& cov);
// cov / √(var_a var_b) within [−1, 1] (rounding of a nearly dependent pair
// can put it a few parts in 10⁶ outside); 0 when either variance is 0 (a
// fixed component) or a value is not finite.
double correlation_coefficient(double covariance, double variance_a, double variance_b);

// What data snooping needs of a fit as it stands: for each mark that
// fails its point test (its place in `active`), its whitened design rows
// over the estimated parameters (3 × u) and whitened residual; and the
// parameters' cofactor N⁻¹ (u × u, σ0 = 1). Only the failing marks are
// kept (10⁶ marks: a few thousand rows, not 10⁶).
struct FitLinearization {
  Eigen::MatrixXd n_inv;
  std::vector<std::size_t> position;   // in `active`
  std::vector<Eigen::MatrixXd> a;      // 3 × u each
  std::vector<Eigen::Vector3d> vw;
  void add(std::size_t at, const Eigen::MatrixXd& rows, const Eigen::Vector3d& whitened) {
    position.push_back(at);
    a.push_back(rows);
    vw.push_back(whitened);
  }
};

// Data snooping after the marks in `active` were tested in the fit
// (solver/src/snooping.hpp): the order in which iterative snooping removes
// the failing marks, each removal the strongest evidence after the ones
// before it, is each mark's snooping_rank (ranks continue those of earlier
// passes). With o.remove_outliers the ranked marks are removed from
// `active` (marked in `r`) and `removed` is returned, so that the caller
// refits and tests again; otherwise nothing is removed (none). A failing
// mark is never removed silently: when too few marks would remain (fewer
// than `min_points`, or no redundancy) it stays, a warning names it
// (stopped); past the options' max_outlier_share of the marks
// `r.refused_because` says the data or the model is wrong and which test
// failed.
enum class SnoopStep { none, removed, stopped };
SnoopStep snoop(FitResult& r, std::vector<std::size_t>& active, const FitOptions& o, int u, int min_points,
                const FitLinearization& lin);

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
