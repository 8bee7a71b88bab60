#pragma once
// Least-squares adjustment of a survey network (geodesy/network.hpp):
// GNSS baselines and point clusters with their joint covariances, and
// terrestrial measurements modelled in 3-D on the ellipsoid in the local
// geodetic horizon at the instrument, or in a plane local system
// (docs/commands/adjust.md states the models).
//
// Unknowns: each station's corrections along its local east, north and up
// (ellipsoidal) or x, y, z (local), less the components its constraint
// fixes, and one orientation per direction set. Gauss–Newton: the normal
// matrix AᵀPA, assembled sparse, is factored each iteration by a
// supernodal Cholesky (a fill-reducing ordering and CHOLMOD's symbolic
// analysis, then geoanchor's own numeric factorization on several
// threads, solver/src/sparse/), until the largest coordinate correction is
// below `convergence_m`. The statistics come from the final
// factor: station covariances, covariances between stations that share a
// measurement and every measurement's redundancy from the entries of N⁻¹
// on the factor's pattern (Takahashi's selected inversion), never a dense
// inverse.
//
// The datum: station constraints (fixed, or held with a standard
// deviation), or --free: the defect is found (which of the three
// translations, three rotations and scale no measurement defines) and the
// network is held by inner constraints over the chosen stations (all by
// default): the minimum-norm solution over them, by an S-transformation of
// a minimally constrained one. A defect that is not defined is refused by
// name.
//
// The statistics are fit's (one implementation, solver/src/
// point_statistics.hpp): vᵀPv, dof, σ0 and the two-sided χ² global test;
// per measurement the residual, its standard deviation, redundancy numbers,
// w-tests, MDB and the measurement test; data snooping by the same rule
// (solver/src/snooping.hpp: ranked by evidence, flagged; removed only with
// remove_outliers, within max_outlier_share).

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "geoanchor/geodesy/geoid.hpp"
#include "geoanchor/geodesy/network.hpp"
#include "geoanchor/solver/helmert_fit.hpp"

namespace geoanchor::solver {

inline constexpr std::size_t kMaxJointCovarianceStations = 5000;

// Combined datum estimation (adjust --estimate-helmert): a group of GNSS
// measurements is in a datum of its own, related to the network's frame by
// a Helmert transformation whose parameters are unknowns of the same
// adjustment. The model, position-vector convention, small-angle EPSG
// rotation matrix R = I + [r]×:
//   X_network = T(t) + (1 + s(t)) R(t) X_group,   p(t) = p0 + (t − t0) ṗ
// so a member's computed values are the stations' positions taken back
// into the group's datum (X_group = R⁻¹ (X_network − T) / (1 + s); for
// baselines the translation cancels). t is each member's epoch, t0 the
// reference epoch (rates only).
struct HelmertGroup {
  std::vector<std::size_t> measurements;  // GNSS baselines and point clusters (indices into Network::measurements)
  bool rates = false;                     // 14 parameters: the 7 at reference_epoch and their rates per year
  double reference_epoch = 0.0;           // decimal year (rates)
  std::vector<double> epochs;             // rates: each member's epoch (decimal year), as `measurements`
  std::string name;                       // for messages
};

// The pairs of stations whose relative precision is computed
// (adjust --relative; RelativePrecision): those a measurement joins, every
// pair, every pair within a horizontal distance, or a listed set.
enum class RelativePairs { connected, all, radius, listed };

// RelativePairs::all is refused above this many pairs (E_OPTION): a
// network of about 1400 stations; past it --relative radius:R.
inline constexpr std::size_t kMaxAllRelativePairs = 1'000'000;

struct RelativeOptions {
  RelativePairs pairs = RelativePairs::connected;
  // radius: every pair whose horizontal distance (in the first station's
  // local horizon; a local network's x, y) is at most this (metres).
  double radius_m = 0.0;
  // listed: pairs of indices into Network::stations, each once (from < to
  // is not required; a station with itself is refused by the reader).
  std::vector<std::pair<std::size_t, std::size_t>> listed;
};

struct AdjustmentResult;

// Pre-analysis candidates (AdjustOptions::candidates): a candidate added
// to the design changes the covariance by a low-rank term, from the
// factor (no refactorization): with B its whitened rows over the unknowns
// (a new direction set's orientation projected out), U = S N⁻¹ Bᵀ (S the
// free network's S-transformation, else I) and M = I + B U,
//   Q'(s1, s2) = Q(s1, s2) − U(s1) M⁻¹ U(s2)ᵀ
// for the 3 × 3 blocks of stations s1, s2 along their local axes (east,
// north, up; a local network's x, y, z; zero rows for held components).
struct CovarianceUpdate {
  std::vector<Eigen::MatrixXd> station;  // per station: U's 3 × k rows (empty: the station has no unknown)
  Eigen::MatrixXd m_inverse;             // k × k
  // Q'(s, s) from the design's block q (the station's covariance_local_m2).
  Eigen::Matrix3d updated(std::size_t s, const Eigen::Matrix3d& q) const {
    if (station[s].size() == 0) return q;
    return q - station[s] * m_inverse * station[s].transpose();
  }
};

// A ranking criterion: the design's worst value (larger is worse) and
// where (a station, or for a pair criterion the first of the pair), from
// the pre-analysis result and, for a candidate, the update its
// measurement makes (nullptr: the design as it is). The hook for ranking
// against an accuracy standard's worst pair: such a criterion reads the
// pairs' covariances from the result and subtracts the update's terms.
struct CriterionValue {
  double value = 0.0;
  std::size_t station = 0;
  std::size_t other = 0;  // a pair criterion's second station (else = station)
};
using CandidateCriterion = std::function<CriterionValue(const AdjustmentResult& design, const CovarianceUpdate* update)>;

// The built-in criteria: the largest horizontal semi-major axis at
// AdjustOptions::confidence (2-D), or the largest σ of the up (z) component.
enum class CandidateRanking { semi_major, sigma_up };

struct AdjustOptions {
  double alpha = 0.05;          // the global test
  double alpha_point = 0.001;   // w-tests, measurement tests and data snooping
  double power = 0.80;          // for the minimal detectable bias
  double confidence = 0.95;     // the error ellipses' second size
  // Data snooping (solver/src/snooping.hpp): the measurements that fail
  // their test are ranked in the order iterative snooping would remove
  // them (AdjustedMeasurement::snooping_rank; off: no ranks). They are
  // flagged and kept unless remove_outliers (adjust --remove-outliers)
  // removes them in that order, adjusting again until none fails.
  bool data_snooping = true;
  bool remove_outliers = false;
  // --remove-outliers removes at most this share of the measurements;
  // past it the adjustment is refused (refused_because).
  double max_outlier_share = 0.10;
  double convergence_m = 1e-5;  // the iteration ends when no coordinate moves more (metres)
  int max_iterations = 25;
  double refraction_k = 0.0;    // zenith angles: coefficient of refraction (0.13 is typical by day)
  // Free network: the datum by inner constraints over these stations (all
  // when empty) instead of station constraints.
  bool free = false;
  std::vector<std::string> inner_constraint_stations;
  // Orthometric heights and levelled height differences (ellipsoidal
  // networks) need the geoid; refused without one.
  const geodesy::GeoidGrid* geoid = nullptr;
  // The tests' reference: a dense normal-equation solve and full inverse.
  bool dense = false;
  // Also the joint covariance of all stations in the adjustment
  // (AdjustmentResult::station_covariance_m2): one solve per coordinate,
  // for SINEX output; refused above kMaxJointCovarianceStations.
  bool joint_covariance = false;
  // Threads for the assembly, the selected inversion and the
  // per-measurement statistics (0: the machine's cores). The results do not
  // depend on it: every sum is taken in the same order.
  int jobs = 0;
  // Data snooping takes the few measurements a pass removes out of the
  // last factor and its selected inverse (Sherman–Morrison–Woodbury) when
  // that costs less than factoring again; false: every pass factors and
  // inverts afresh (the tests' reference).
  bool snooping_downdates = true;
  // The memory the factor and its selected inverse may take (bytes; 0: what
  // the machine has available). Checked after CHOLMOD's analysis, before
  // the numbers: E_MEMORY (rejected) names what is needed.
  std::uint64_t memory_budget_bytes = 0;
  // A Helmert transformation estimated with the stations (above).
  std::optional<HelmertGroup> helmert;
  // The pairs whose relative precision is computed (AdjustmentResult::relative).
  RelativeOptions relative;
  // Variance components (adjust --vce): the measurements in groups (by
  // kind, by their `group`, or by their error model), each group's
  // covariances scaled by a factor estimated from its residuals until no
  // factor changes by kVceTolerance (helmert_fit.hpp; Förstner's iteration, as fit --vce:
  // θ_k ← θ_k · vᵀP Q_k P v / tr(P Q_k P Q_vv), for disjoint groups
  // θ_k · Ω_k / r_k); the estimation adjusts without data snooping, the
  // final adjustment with these options on the scaled covariances.
  enum class VarianceGroups { none, kind, group, model };
  VarianceGroups variance_components = VarianceGroups::none;
  // Pre-analysis (adjust --preanalysis): the design at the a-priori
  // coordinates, factored once, no iteration; the measured values are not
  // read (each is replaced by its value computed at the a-priori
  // coordinates, so the misclosures are zero). Results: station
  // covariances and ellipses, redundancy numbers, MDB and external
  // reliability; no residuals, w-tests, σ0 or global test (NaN there, and
  // AdjustmentResult::preanalysis set). Every station needs a-priori
  // coordinates (E_PREANALYSIS_POSITION names one that has none).
  bool preanalysis = false;
  // External reliability (AdjustedMeasurement::external): per measurement
  // component, the effect on the unknowns of an undetected blunder of MDB
  // size, ∇x = N⁻¹ Aᵢᵀ Pᵢ ∇lᵢ. One solve with the factor per component
  // (batched): O(components · nnz(L)) (docs/commands/adjust.md).
  bool external_reliability = true;
  // Pre-analysis: candidate measurements (stations of the network; values
  // not read), each ranked by how much it improves the worst station when
  // added alone to the design (AdjustmentResult::candidates). The
  // directions of a direction set that no design measurement has are one
  // candidate together (their orientation is a new unknown).
  std::vector<geodesy::NetworkMeasurement> candidates;
  CandidateRanking candidate_ranking = CandidateRanking::semi_major;
  CandidateCriterion candidate_criterion;  // set: used instead of candidate_ranking
};

// The effect on the coordinates of an undetected blunder of one
// component's MDB (JAG3D's "influence on point position", EP): the
// largest over the stations, its length in 3-D and, separately, its
// horizontal and vertical parts (in the local east, north, up; a local
// network: x, y and z), each with its station. NaN (and station 0) where
// the component has no MDB (no redundancy).
struct ExternalReliability {
  double effect_m = std::numeric_limits<double>::quiet_NaN();
  std::size_t station = 0;  // index into AdjustmentResult::stations
  double horizontal_m = std::numeric_limits<double>::quiet_NaN();
  std::size_t horizontal_station = 0;
  double vertical_m = std::numeric_limits<double>::quiet_NaN();
  std::size_t vertical_station = 0;
  // With --estimate-helmert: the effect on each Helmert parameter
  // (EstimatedHelmert's order and units, SI); empty without.
  Eigen::VectorXd helmert;
};

// A group with less redundancy than this keeps its factor of 1 (reported
// as not estimable): its estimate would rest on a fraction of one residual.
inline constexpr double kMinVceRedundancy = 2.0;

// One variance component: a group of measurements and the factor its
// a-priori covariances were scaled by.
struct VarianceComponent {
  std::string name;             // "GNSS", "distances", a group or an error model's name
  std::size_t measurements = 0; // in the adjustment
  double redundancy = 0.0;      // r_k, the sum of its redundancy numbers
  double factor = 1.0;          // the estimated variance factor (1: the a-priori weights were right)
  double sigma = 0.0;           // its standard deviation, factor · √(2 / r_k)
  bool estimated = false;       // false: redundancy below kMinVceRedundancy, factor 1 kept
};

// The factor that takes a 1σ horizontal error ellipse to the ellipse that
// holds `confidence` (0 < p < 1) of a 2-D normal error: √χ²₂(p) =
// √(−2 ln(1 − p)) (2.4477 at 95 %); and a 1σ standard deviation of one
// component to the half-width of its two-sided interval at `confidence`:
// the normal quantile at (1 + p) / 2 (1.9600 at 95 %).
double ellipse_confidence_scale(double confidence);
double interval_confidence_scale(double confidence);

// The estimated Helmert of AdjustOptions::helmert: p0 then the rates, in
// SI (tx, ty, tz m; rx, ry, rz rad; ds unitless; the rates per year), and
// their covariance from the a-priori weights (σ0 = 1).
struct EstimatedHelmert {
  Eigen::VectorXd parameters;
  Eigen::MatrixXd covariance;
};

struct ErrorEllipse {
  double semi_major_m = 0.0;
  double semi_minor_m = 0.0;
  double azimuth_rad = 0.0;  // of the semi-major axis, clockwise from north (local: from +x towards +y)
};

struct AdjustedStation {
  std::string id;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // ECEF (ellipsoidal) or local x, y, z
  Eigen::Vector3d a_priori = Eigen::Vector3d::Zero();
  // Covariance (σ0 = 1, from the a-priori weights) in ECEF or local x, y, z,
  // and in local east, north, up (ellipsoidal; local: x, y, z again).
  Eigen::Matrix3d covariance_m2 = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d covariance_local_m2 = Eigen::Matrix3d::Zero();
  ErrorEllipse ellipse;             // 1σ, horizontal
  ErrorEllipse ellipse_confidence;  // at AdjustOptions::confidence (2-D χ² scale)
  std::string constraint;           // "CCF"
  bool used = true;                 // false: no measurement reaches it (left out)
};

// A measurement after the adjustment; vectors have one entry per component
// (3 per baseline or point, 1 for a terrestrial measurement), in SI.
struct AdjustedMeasurement {
  std::size_t index = 0;  // into Network::measurements
  bool used = true;       // in the final adjustment
  bool outlier = false;   // removed: by data snooping (--remove-outliers) or the input's tolerance for misclosures
  std::string removed_because;
  // Its place in the order iterative data snooping removes the failing
  // measurements (1: first); 0 for one snooping would not remove.
  std::size_t snooping_rank = 0;
  // Flagged, but passes once the measurements data snooping removes before
  // it are out: the rank after whose removal it passes (0: not so).
  std::size_t passes_after_rank = 0;
  Eigen::VectorXd observed, adjusted;
  Eigen::VectorXd residual;        // adjusted − observed
  Eigen::VectorXd sigma;           // a priori
  Eigen::VectorXd residual_sigma;  // of the residual (σ0 = 1)
  Eigen::VectorXd redundancy;      // 0 … 1 per component
  Eigen::VectorXd w;               // w-test per component (NaN: no redundancy)
  Eigen::VectorXd mdb;             // minimal detectable bias per component (inf: none)
  double w_max = 0.0;
  double statistic = 0.0;  // the measurement test: χ²(dof) under H0, over its controlled directions
  int test_dof = 0;        // 0: uncontrolled (no direction with redundancy ≥ kMinRedundancy)
  double p_value = 1.0;
  double log_p = 0.0;      // ln p_value without underflow: the evidence data snooping ranks by
  // Per component (AdjustOptions::external_reliability; empty without).
  std::vector<ExternalReliability> external;
  // In the adjustment, controlled, and its measurement test's p-value below
  // alpha_point: what the reports flag and data snooping removes.
  bool fails_test(double alpha_point) const { return used && test_dof > 0 && p_value < alpha_point; }
  TestStatus status(double alpha_point) const {
    return outlier ? TestStatus::removed
           : !used ? TestStatus::ignored
           : test_dof == 0 ? TestStatus::uncontrolled
           : p_value < alpha_point ? TestStatus::flagged
                                   : TestStatus::used;
  }
};

// The precision of the difference `to` − `from` of two adjusted stations,
// in the local horizon of `from` (east, north, up; a local network's x, y,
// z), from their joint cofactor (S-transformed for a free network; σ0 = 1).
// A candidate measurement of a pre-analysis (AdjustOptions::candidates).
struct RankedCandidate {
  std::vector<std::size_t> measurements;  // indices into AdjustOptions::candidates (a direction set: its directions)
  CriterionValue worst;                   // the criterion with it added
  double improvement = 0.0;               // the design's worst value less `worst.value`
};

struct RelativePrecision {
  std::size_t from = 0, to = 0;  // indices into AdjustmentResult::stations
  double distance_m = 0.0;        // spatial (3-D)
  double horizontal_distance_m = 0.0;  // in the horizon of `from`
  double sigma_distance_m = 0.0;  // of the (3-D) distance between them
  ErrorEllipse ellipse;           // of their horizontal difference, 1σ
  ErrorEllipse ellipse_confidence;  // at AdjustOptions::confidence (2-D χ² scale, as the stations')
  double sigma_up_m = 0.0;          // of the difference in up (local: z)
  double up_confidence_m = 0.0;     // half-width at AdjustOptions::confidence (1-D, two-sided)
  Eigen::Matrix3d covariance_local_m2 = Eigen::Matrix3d::Zero();  // of the difference, in the horizon of `from`
};

// Wall seconds of the adjustment's parts, summed over every pass (for the
// benchmarks and docs/scale.md; never part of a report, which must not
// change from run to run).
struct AdjustmentTimings {
  double assemble = 0.0;        // linearization and the normal matrix's entries
  double factor = 0.0;          // ordering and CHOLMOD's symbolic analysis (first pass), numeric factorizations
  double solve = 0.0;           // Gauss–Newton solves
  double select_inverse = 0.0;  // N⁻¹ on the factor's pattern
  double downdate = 0.0;        // data snooping: measurements taken out of the factor and N⁻¹
  double measurements = 0.0;    // per measurement: residuals, redundancy, tests
  double datum = 0.0;           // the datum's undefined and weak combinations (first pass)
  double snooping = 0.0;        // data snooping's order: the failing measurements' cofactors and the sequence
  double stations = 0.0;        // covariances, ellipses, relative precision
  double external = 0.0;        // external reliability: a solve per measurement component
};

struct AdjustmentResult {
  std::vector<AdjustedStation> stations;          // in the network's order
  // In the network's order; those its input ignores are left out (the
  // measurements CSV lists them, status "ignored").
  std::vector<AdjustedMeasurement> measurements;
  std::vector<double> orientations_rad, orientation_sigmas_rad;  // per direction set
  std::vector<RelativePrecision> relative;  // the pairs of AdjustOptions::relative, ordered by (from, to)
  double vtpv = 0.0;                // vᵀ Σ⁻¹ v, Σ the a-priori covariance
  int dof = 0;
  std::optional<double> variance_factor;  // vtpv / dof
  std::optional<double> sigma0;
  GlobalTest global_test;
  double w_critical = 0.0;
  double alpha_point = 0.001;  // the options' (AdjustedMeasurement::status)
  int iterations = 0;  // Gauss–Newton iterations over every pass
  // Adjustments in all: 1, plus one per data-snooping step (--remove-outliers:
  // a step removes every measurement of snooping's order, snooping.hpp, and
  // the next tests all again).
  int passes = 0;
  // Measurements data snooping removed after each pass but the last, and
  // the passes that took them out of the last factor (a downdate,
  // AdjustOptions::snooping_downdates) instead of factoring again.
  std::vector<std::size_t> removed_per_pass;
  int passes_downdated = 0;
  bool converged = false;
  double largest_correction_m = 0.0;  // of the last iteration
  std::string datum;                  // how the datum is defined, in words
  // The combinations of translations, rotations and scale that the
  // measurements and constraints leave undefined, by name (a free network's
  // defect, or what the input's datum stations hold); empty when none.
  std::vector<std::string> datum_defect;
  bool datum_by_minimum_norm = false;  // part of it held by inner constraints (free network, Gama's constrained points)
  std::vector<std::string> warnings;
  std::string refused_because;        // set when data snooping reached its limit
  std::size_t unknowns = 0, observations = 0;
  // With AdjustOptions::joint_covariance: the stations in the adjustment
  // (indices into `stations`) and their joint covariance, 3 rows each, in
  // ECEF (ellipsoidal) or local x, y, z, from the a-priori weights.
  std::vector<std::size_t> covariance_stations;
  Eigen::MatrixXd station_covariance_m2;
  std::int64_t factor_nonzeros = 0;
  AdjustmentTimings seconds;
  std::optional<EstimatedHelmert> helmert;
  // With AdjustOptions::variance_components: each group's estimate, and
  // the estimation's iterations (adjustments).
  std::vector<VarianceComponent> variance_components;
  int vce_iterations = 0;
  // AdjustOptions::preanalysis: no residuals (NaN), no σ0 or global test.
  bool preanalysis = false;
  // AdjustOptions::candidates ranked, best first (the lowest worst value
  // after it is added; ties in the input's order), and the design's own
  // worst value.
  std::vector<RankedCandidate> candidates;
  CriterionValue design_worst;
};

// The measurements that fail their test (flagged, or removed by data
// snooping), as positions in r.measurements: in the order data snooping
// removes them (snooping_rank), then the rest by evidence (ln p, then the
// statistic): what a refusal or a report names first.
std::vector<std::size_t> failing_measurements(const AdjustmentResult& r);

// Throws geoanchor::Error (input) naming the station or measurement: an
// undefined datum (E_DATUM_DEFECT, naming what is undefined: judged
// against the network's own precision, docs/commands/adjust.md "The
// datum"), a disconnected network (E_NETWORK_DISCONNECTED, naming the
// components), stations the measurements do not determine
// (E_NETWORK_SINGULAR, naming them and the direction left free), a
// covariance that is
// not positive definite (E_COVARIANCE, with its smallest eigenvalue), a
// height without a geoid (E_GEOID_MISSING); (usage) inner-constraint
// stations that do not hold the defect (E_INNER_CONSTRAINTS, naming the
// combinations left free); (rejected) no convergence (E_NOT_CONVERGED,
// with the largest correction and its station).
AdjustmentResult adjust_network(const geodesy::Network& network, const AdjustOptions& options);

}  // namespace geoanchor::solver
