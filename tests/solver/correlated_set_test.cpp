// Correlated terrestrial observation sets (geodesy::MeasurementKind::
// observation_set): the observations of one set whitened as one block by
// the Cholesky factor of their joint covariance, with residuals, redundancy
// numbers and w-tests per observation and one measurement test per set.
//
// The reference is a dense generalized least-squares solve written here:
// a plane network whose observation equations are the test's own formulas
// (bearing = atan2(Δy, Δx), distance = |Δ|, direction = bearing − the
// set's orientation, angle = bearing to the foresight − to the backsight),
// its design matrix by central differences, x = (AᵀC⁻¹A)⁻¹AᵀC⁻¹l iterated,
// and the statistics from C, A and N⁻¹ as textbooks define them:
// Q_v = C − A N⁻¹ Aᵀ, redundancy numbers diag(Q_v C⁻¹), w_i =
// (C⁻¹v)_i / √(C⁻¹ Q_v C⁻¹)_ii, the set's test its whitened residual's
// vᵀQ⁺v over its directions with redundancy.

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/network.hpp"
#include "geoanchor/solver/network_adjustment.hpp"
#include "accuracy.hpp"

namespace geoanchor::solver {
namespace {

using geodesy::MeasurementKind;
using geodesy::Network;
using geodesy::NetworkMeasurement;

constexpr double kPi = std::numbers::pi;
constexpr double kArcsec = kPi / 648000.0;

// Against the dense reference: both converge to the same minimum (to far
// below this); the reference's design matrix by central differences
// (h = 1 mm: truncation ~1e-12, rounding ~1e-10 relative) moves its
// minimum by < 1e-11 m.
constexpr double kSameAdjustment_m = 1e-9;
constexpr double kSameAngle_rad = 1e-11;        // 1e-9 m over the 500 m sights
constexpr double kSameStatistic = 1e-7;         // redundancy numbers, w, σ ratios: N⁻¹ to ~1e-10 relative
// A set without correlations against its observations as measurements of
// their own: the same equations summed in another order, through a normal
// matrix whose condition (orientations against coordinates) is ~1e6.
constexpr double kSameSums_m = 1e-11;
constexpr double kSameSumsRelative = 1e-9;

// The plane network: A, B, C fixed; P, Q free; x, y in metres, bearings
// from +x towards +y (Gama's axes "ne", angles clockwise).
const std::vector<std::string> kIds = {"A", "B", "C", "P", "Q"};
const std::vector<Eigen::Vector2d> kTruth = {{0, 0}, {1000, 0}, {0, 800}, {400.031, 299.978}, {699.962, 600.044}};
const std::vector<Eigen::Vector2d> kApriori = {{0, 0}, {1000, 0}, {0, 800}, {400, 300}, {700, 600}};
constexpr double kOrientationA = 0.3, kOrientationC = -1.1;  // radians
constexpr std::size_t A = 0, B = 1, C = 2, P = 3, Q = 4;

struct Obs {
  MeasurementKind kind;
  std::vector<std::size_t> at;  // direction, distance: from, to; angle: at, backsight, foresight
  int set;              // direction set: 0 at A, 1 at C; −1 none
  double sigma;         // m or rad
  double noise;         // in sigmas: the "measured" error (fixed, not random)
};

constexpr double kDir = 2.0 * kArcsec, kAngle = 3.0 * kArcsec;
const std::vector<Obs> kObs = {
    // The correlated set at A: three directions and two distances.
    {MeasurementKind::direction, {A, B}, 0, kDir, 0.6},
    {MeasurementKind::direction, {A, P}, 0, kDir, -1.2},
    {MeasurementKind::direction, {A, Q}, 0, kDir, 0.9},
    {MeasurementKind::horizontal_distance, {A, P}, -1, 0.002, 0.3},
    {MeasurementKind::horizontal_distance, {A, Q}, -1, 0.002, -0.7},
    // Measurements of their own.
    {MeasurementKind::horizontal_distance, {B, P}, -1, 0.003, 1.1},
    {MeasurementKind::horizontal_distance, {B, Q}, -1, 0.003, -0.4},
    {MeasurementKind::horizontal_distance, {C, P}, -1, 0.003, 0.8},
    {MeasurementKind::horizontal_distance, {C, Q}, -1, 0.003, -1.5},
    {MeasurementKind::horizontal_distance, {P, Q}, -1, 0.003, 0.2},
    {MeasurementKind::horizontal_angle, {B, A, P}, -1, kAngle, 1.0},
    {MeasurementKind::horizontal_angle, {C, A, Q}, -1, kAngle, -0.9},
    {MeasurementKind::direction, {C, A}, 1, kDir, 0.5},
    {MeasurementKind::direction, {C, P}, 1, kDir, -0.3},
    {MeasurementKind::direction, {C, Q}, 1, kDir, 1.3},
};
constexpr int kSetSize = 5;

// The set's correlations (positive definite: checked where used).
Eigen::MatrixXd set_correlation() {
  Eigen::MatrixXd r(kSetSize, kSetSize);
  r << 1.0, 0.4, 0.2, 0.1, -0.2,  //
      0.4, 1.0, 0.3, -0.1, 0.1,   //
      0.2, 0.3, 1.0, 0.2, 0.0,    //
      0.1, -0.1, 0.2, 1.0, 0.35,  //
      -0.2, 0.1, 0.0, 0.35, 1.0;
  return r;
}

double wrap(double a) {
  a = std::remainder(a, 2.0 * kPi);
  return a <= -kPi ? a + 2.0 * kPi : a;
}

double bearing(const Eigen::Vector2d& from, const Eigen::Vector2d& to) { return std::atan2(to.y() - from.y(), to.x() - from.x()); }

// The observations computed from u = (xP, yP, xQ, yQ, oA, oC).
Eigen::VectorXd model(const Eigen::VectorXd& u) {
  std::vector<Eigen::Vector2d> x = kApriori;
  x[P] = u.segment<2>(0);
  x[Q] = u.segment<2>(2);
  Eigen::VectorXd f(static_cast<Eigen::Index>(kObs.size()));
  for (std::size_t k = 0; k < kObs.size(); ++k) {
    const Obs& o = kObs[k];
    double v = 0.0;
    if (o.kind == MeasurementKind::direction) v = bearing(x[o.at[0]], x[o.at[1]]) - u(4 + o.set);
    if (o.kind == MeasurementKind::horizontal_distance) v = (x[o.at[1]] - x[o.at[0]]).norm();
    if (o.kind == MeasurementKind::horizontal_angle) v = bearing(x[o.at[0]], x[o.at[2]]) - bearing(x[o.at[0]], x[o.at[1]]);
    f(static_cast<Eigen::Index>(k)) = v;
  }
  return f;
}

bool angular(MeasurementKind k) { return k != MeasurementKind::horizontal_distance; }

// The observed values: the truth's plus the fixed errors, angles in [0, 2π).
Eigen::VectorXd observed() {
  Eigen::VectorXd u(6);
  u << kTruth[P], kTruth[Q], kOrientationA, kOrientationC;
  Eigen::VectorXd l = model(u);
  for (std::size_t k = 0; k < kObs.size(); ++k) {
    double& v = l(static_cast<Eigen::Index>(k));
    v += kObs[k].noise * kObs[k].sigma;
    if (angular(kObs[k].kind)) v = std::fmod(v + 4.0 * kPi, 2.0 * kPi);
  }
  return l;
}

// The joint covariance: the set's block D R D, the rest diagonal.
Eigen::MatrixXd covariance(const Eigen::MatrixXd& set_r) {
  const auto n = static_cast<Eigen::Index>(kObs.size());
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < n; ++j) {
      const double r = i == j ? 1.0 : (i < kSetSize && j < kSetSize ? set_r(i, j) : 0.0);
      c(i, j) = r * kObs[static_cast<std::size_t>(i)].sigma * kObs[static_cast<std::size_t>(j)].sigma;
    }
  }
  return c;
}

struct Reference {
  Eigen::VectorXd u, v;      // the estimate; residuals, adjusted − observed
  Eigen::MatrixXd c, qv;     // a-priori covariance; residuals' cofactor
  double vtpv = 0.0;
};

// The dense generalized least-squares solve.
Reference dense_gls(const Eigen::VectorXd& l, const Eigen::MatrixXd& c) {
  Reference ref;
  ref.c = c;
  const Eigen::MatrixXd p = c.inverse();
  Eigen::VectorXd u(6);
  u << kApriori[P], kApriori[Q], 0.0, 0.0;
  u(4) = wrap(bearing(kApriori[A], kApriori[B]) - l(0));
  u(5) = wrap(bearing(kApriori[C], kApriori[A]) - l(12));
  const auto misclosure = [&](const Eigen::VectorXd& at) {
    Eigen::VectorXd r = l - model(at);
    for (std::size_t k = 0; k < kObs.size(); ++k) {
      if (angular(kObs[k].kind)) r(static_cast<Eigen::Index>(k)) = wrap(r(static_cast<Eigen::Index>(k)));
    }
    return r;
  };
  const auto design = [&](const Eigen::VectorXd& at) {
    constexpr double kH = 1e-3;  // m (or rad: the orientations enter linearly)
    Eigen::MatrixXd a(l.size(), u.size());
    for (Eigen::Index j = 0; j < u.size(); ++j) {
      Eigen::VectorXd up = at, down = at;
      up(j) += kH;
      down(j) -= kH;
      Eigen::VectorXd d = model(up) - model(down);
      for (std::size_t k = 0; k < kObs.size(); ++k) {
        if (angular(kObs[k].kind)) d(static_cast<Eigen::Index>(k)) = wrap(d(static_cast<Eigen::Index>(k)));
      }
      a.col(j) = d / (2.0 * kH);
    }
    return a;
  };
  Eigen::MatrixXd a;
  for (int iteration = 0; iteration < 50; ++iteration) {
    a = design(u);
    const Eigen::MatrixXd n = a.transpose() * p * a;
    const Eigen::VectorXd dx = n.ldlt().solve(a.transpose() * p * misclosure(u));
    u += dx;
    if (dx.norm() < 1e-13) break;
  }
  a = design(u);
  ref.u = u;
  ref.v = -misclosure(u);
  ref.qv = c - a * (a.transpose() * p * a).inverse() * a.transpose();
  ref.vtpv = ref.v.dot(p * ref.v);
  return ref;
}

NetworkMeasurement measurement_of(std::size_t k, const Eigen::VectorXd& l, const Eigen::MatrixXd& c) {
  NetworkMeasurement m;
  m.kind = kObs[k].kind;
  m.stations = kObs[k].at;
  m.value = Eigen::VectorXd::Constant(1, l(static_cast<Eigen::Index>(k)));
  m.covariance = Eigen::MatrixXd::Constant(1, 1, c(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(k)));
  if (kObs[k].set >= 0) m.set = static_cast<std::size_t>(kObs[k].set);
  m.source = "obs " + std::to_string(k);
  return m;
}

// The network: the first five observations one observation set (when
// `as_set`) or measurements of their own, the rest measurements of their own.
Network network(const Eigen::VectorXd& l, const Eigen::MatrixXd& c, bool as_set = true) {
  Network net;
  net.space = geodesy::NetworkSpace::local;
  net.local_dimensions = 2;
  net.source_name = "plane test network";
  for (std::size_t s = 0; s < kIds.size(); ++s) {
    geodesy::NetworkStation st;
    st.id = kIds[s];
    st.position = Eigen::Vector3d(kApriori[s].x(), kApriori[s].y(), 0.0);
    if (s < 3) st.constraint.code = {'C', 'C', 'C'};
    st.source = "station " + kIds[s];
    net.stations.push_back(st);
  }
  net.direction_sets = {{A, "set at A"}, {C, "set at C"}};
  std::vector<NetworkMeasurement> parts;
  for (std::size_t k = 0; k < kObs.size(); ++k) {
    if (as_set && k < kSetSize) parts.push_back(measurement_of(k, l, c));
    else net.measurements.push_back(measurement_of(k, l, c));
  }
  if (as_set) {
    net.measurements.insert(net.measurements.begin(),
                            geodesy::make_observation_set(std::move(parts), c.topLeftCorner(kSetSize, kSetSize), "the set at A"));
  }
  return net;
}

const AdjustedStation& station(const AdjustmentResult& r, const std::string& id) {
  for (const auto& s : r.stations) {
    if (s.id == id) return s;
  }
  throw std::runtime_error("no station " + id);
}

AdjustOptions tight() {
  AdjustOptions o;
  o.convergence_m = 1e-10;  // iterate to the minimum: the comparisons are far tighter than the default 10 µm
  return o;
}

TEST(CorrelatedSet, TheSetsWhiteningAgreesWithADenseGeneralizedLeastSquaresSolve) {
  const Eigen::MatrixXd c = covariance(set_correlation());
  ASSERT_EQ(Eigen::LLT<Eigen::MatrixXd>(c).info(), Eigen::Success);
  const Eigen::VectorXd l = observed();
  const Reference ref = dense_gls(l, c);
  const Network net = network(l, c);
  ASSERT_EQ(net.measurements.size(), kObs.size() - kSetSize + 1);
  const AdjustmentResult r = adjust_network(net, tight());
  ASSERT_TRUE(r.converged);
  EXPECT_EQ(r.observations, kObs.size());
  EXPECT_EQ(r.unknowns, 6u);
  EXPECT_EQ(r.dof, 9);
  EXPECT_NEAR(r.vtpv, ref.vtpv, ref.vtpv * 1e-9);
  EXPECT_LE((station(r, "P").position.head<2>() - ref.u.segment<2>(0)).norm(), kSameAdjustment_m);
  EXPECT_LE((station(r, "Q").position.head<2>() - ref.u.segment<2>(2)).norm(), kSameAdjustment_m);
  ASSERT_EQ(r.orientations_rad.size(), 2u);
  EXPECT_LE(std::fabs(wrap(r.orientations_rad[0] - ref.u(4))), kSameAngle_rad);
  EXPECT_LE(std::fabs(wrap(r.orientations_rad[1] - ref.u(5))), kSameAngle_rad);

  // Per observation: residual, its σ, redundancy number and w-test.
  const Eigen::MatrixXd p = c.inverse();
  const Eigen::MatrixXd r_matrix = ref.qv * p;
  const Eigen::VectorXd pv = p * ref.v;
  const Eigen::MatrixXd pqp = p * ref.qv * p;
  double redundancy_sum = 0.0;
  for (const auto& am : r.measurements) {
    const auto& m = net.measurements[am.index];
    const std::size_t first = m.kind == MeasurementKind::observation_set ? 0 : std::stoul(m.source.substr(4));
    for (Eigen::Index k = 0; k < m.value.size(); ++k) {
      const Eigen::Index i = static_cast<Eigen::Index>(first) + k;
      const double unit = angular(kObs[static_cast<std::size_t>(i)].kind) ? kSameAngle_rad : kSameAdjustment_m;
      SCOPED_TRACE("observation " + std::to_string(i));
      EXPECT_NEAR(am.residual(k), ref.v(i), unit);
      EXPECT_NEAR(am.residual_sigma(k) / std::sqrt(c(i, i)), std::sqrt(ref.qv(i, i) / c(i, i)), kSameStatistic);
      EXPECT_NEAR(am.redundancy(k), r_matrix(i, i), kSameStatistic);
      EXPECT_NEAR(am.w(k), pv(i) / std::sqrt(pqp(i, i)), kSameStatistic);
      redundancy_sum += am.redundancy(k);
    }
    if (m.kind != MeasurementKind::observation_set) continue;
    // The set's test: its whitened residual against its cofactor block
    // over the directions with redundancy (eigenvalues ≥ 0.001,
    // docs/commands/adjust.md). The set holds every direction of A's set:
    // a common turn of them is A's orientation, with no redundancy, so
    // four of its five directions are tested.
    const Eigen::MatrixXd w = Eigen::MatrixXd(c.topLeftCorner(kSetSize, kSetSize).llt().matrixL()).inverse();
    const Eigen::VectorXd vw = w * ref.v.head(kSetSize);
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(w * ref.qv.topLeftCorner(kSetSize, kSetSize) * w.transpose());
    double statistic = 0.0;
    int tested = 0;
    for (Eigen::Index k = 0; k < kSetSize; ++k) {
      if (eig.eigenvalues()(k) < 1e-3) continue;
      statistic += std::pow(eig.eigenvectors().col(k).dot(vw), 2) / eig.eigenvalues()(k);
      ++tested;
    }
    EXPECT_EQ(tested, kSetSize - 1);
    EXPECT_LT(eig.eigenvalues()(0), 1e-12);  // the common turn: none
    EXPECT_EQ(am.test_dof, tested);
    EXPECT_NEAR(am.statistic, statistic, statistic * kSameStatistic);
  }
  EXPECT_NEAR(redundancy_sum, r.dof, 1e-9);  // Σ redundancy numbers = dof
}

TEST(CorrelatedSet, ASetWithoutCorrelationsIsItsObservationsAdjustedOneByOne) {
  const Eigen::MatrixXd c = covariance(Eigen::MatrixXd::Identity(kSetSize, kSetSize));
  const Eigen::VectorXd l = observed();
  const Network set = network(l, c, true), apart = network(l, c, false);
  const AdjustmentResult rs = adjust_network(set, tight()), ra = adjust_network(apart, tight());
  EXPECT_EQ(rs.dof, ra.dof);
  EXPECT_NEAR(rs.vtpv, ra.vtpv, ra.vtpv * kSameSumsRelative);
  for (const char* id : {"P", "Q"}) {
    EXPECT_LE((station(rs, id).position - station(ra, id).position).norm(), kSameSums_m) << id;
    const Eigen::Matrix3d& cs = station(rs, id).covariance_m2;
    EXPECT_LE(testing::max_abs_component(cs - station(ra, id).covariance_m2), testing::max_abs_component(cs) * kSameSumsRelative) << id;
  }
  // The set's observations have the residuals, redundancy numbers and
  // w-tests they have as measurements of their own (the measurements in
  // the network's order: the set first, or its five observations first).
  const AdjustedMeasurement& s = rs.measurements.front();
  ASSERT_EQ(s.residual.size(), kSetSize);
  for (Eigen::Index k = 0; k < kSetSize; ++k) {
    const AdjustedMeasurement& one = ra.measurements[static_cast<std::size_t>(k)];
    EXPECT_NEAR(s.residual(k), one.residual(0), kSameSums_m) << k;
    EXPECT_NEAR(s.redundancy(k), one.redundancy(0), kSameSumsRelative) << k;
    EXPECT_NEAR(s.w(k), one.w(0), kSameSumsRelative) << k;
    EXPECT_NEAR(s.mdb(k), one.mdb(0), one.mdb(0) * kSameSumsRelative) << k;
  }
}

TEST(CorrelatedSet, TheDenseReferencePathAgrees) {
  const Eigen::MatrixXd c = covariance(set_correlation());
  const Network net = network(observed(), c);
  AdjustOptions dense = tight();
  dense.dense = true;
  const AdjustmentResult rs = adjust_network(net, tight()), rd = adjust_network(net, dense);
  for (const char* id : {"P", "Q"}) EXPECT_LE((station(rs, id).position - station(rd, id).position).norm(), kSameAdjustment_m) << id;
  const AdjustedMeasurement& a = rs.measurements.front();
  const AdjustedMeasurement& b = rd.measurements.front();
  for (Eigen::Index k = 0; k < kSetSize; ++k) {
    EXPECT_NEAR(a.redundancy(k), b.redundancy(k), kSameStatistic) << k;
    EXPECT_NEAR(a.w(k), b.w(k), kSameStatistic) << k;
  }
  EXPECT_NEAR(a.statistic, b.statistic, a.statistic * kSameStatistic);
}

// The same network with its measurements and direction sets in another
// order gives the same bits (network_canonical_order.cpp).
TEST(CorrelatedSet, TheSameNetworkShuffledGivesTheSameBits) {
  const Eigen::MatrixXd c = covariance(set_correlation());
  const Network net = network(observed(), c);
  const AdjustmentResult r = adjust_network(net, {});
  std::mt19937 rng(7);
  for (int shuffle = 0; shuffle < 4; ++shuffle) {
    Network other = net;
    std::shuffle(other.measurements.begin(), other.measurements.end(), rng);
    // The direction sets numbered the other way round.
    std::swap(other.direction_sets[0], other.direction_sets[1]);
    for (auto& m : other.measurements) {
      const auto renumber = [](NetworkMeasurement& x) {
        if (x.set) x.set = 1 - *x.set;
      };
      renumber(m);
      for (auto& part : m.parts) renumber(part);
    }
    const AdjustmentResult s = adjust_network(other, {});
    EXPECT_EQ(s.vtpv, r.vtpv) << shuffle;
    for (const char* id : {"P", "Q"}) {
      EXPECT_EQ(station(s, id).position, station(r, id).position) << id;
      EXPECT_EQ(station(s, id).covariance_m2, station(r, id).covariance_m2) << id;
    }
    for (const auto& am : s.measurements) {
      if (other.measurements[am.index].kind != MeasurementKind::observation_set) continue;
      EXPECT_EQ(am.w, r.measurements.front().w);
      EXPECT_EQ(am.statistic, r.measurements.front().statistic);
    }
  }
}

// A blunder in one observation of a set: the set fails its test, its w is
// largest at that observation, and data snooping removes the whole set.
TEST(CorrelatedSet, ABlunderFlagsItsSetAndSnoopingRemovesTheSet) {
  const Eigen::MatrixXd c = covariance(set_correlation());
  Eigen::VectorXd l = observed();
  l(1) += 40.0 * kArcsec;  // the direction A→P, 20σ
  const Network net = network(l, c);
  const AdjustmentResult flagged = adjust_network(net, {});
  const AdjustedMeasurement& set = flagged.measurements.front();
  ASSERT_EQ(net.measurements[set.index].kind, MeasurementKind::observation_set);
  EXPECT_EQ(set.status(flagged.alpha_point), TestStatus::flagged);
  EXPECT_EQ(set.snooping_rank, 1u);
  Eigen::Index worst = 0;
  set.w.cwiseAbs().maxCoeff(&worst);
  EXPECT_EQ(worst, 1);
  AdjustOptions remove;
  remove.remove_outliers = true;
  const AdjustmentResult removed = adjust_network(net, remove);
  EXPECT_EQ(removed.measurements.front().status(removed.alpha_point), TestStatus::removed);
  EXPECT_EQ(removed.dof, 5);  // 10 observations left; P, Q and the set at C's orientation
  for (std::size_t k = 1; k < removed.measurements.size(); ++k) EXPECT_TRUE(removed.measurements[k].used) << k;
}

TEST(CorrelatedSet, AMalformedSetOrACovarianceNotPositiveDefiniteIsRefused) {
  const Eigen::VectorXd l = observed();
  Eigen::MatrixXd r = set_correlation();
  r(0, 1) = r(1, 0) = 1.2;  // a correlation past 1
  const Network bad = network(l, covariance(r));
  try {
    adjust_network(bad, {});
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_COVARIANCE");
    EXPECT_NE(std::string(e.what()).find("the set at A: observation set: the covariance is not positive definite"), std::string::npos)
        << e.what();
  }
  // Parts that do not give the set its stations.
  Network mixed = network(l, covariance(set_correlation()));
  mixed.measurements.front().parts[2].stations = {A, C};
  try {
    adjust_network(mixed, {});
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_NETWORK_KIND");
    EXPECT_NE(std::string(e.what()).find("the set at A: observation set: its parts must be"), std::string::npos) << e.what();
  }
  // A part that is no single terrestrial value is no set at all.
  std::vector<NetworkMeasurement> parts = {measurement_of(0, l, covariance(set_correlation()))};
  parts[0].kind = MeasurementKind::gnss_points;
  EXPECT_THROW(geodesy::make_observation_set(parts, Eigen::MatrixXd::Identity(1, 1), "x"), std::invalid_argument);
  EXPECT_THROW(geodesy::make_observation_set({measurement_of(0, l, covariance(set_correlation()))}, Eigen::MatrixXd::Identity(2, 2), "x"),
               std::invalid_argument);
}

}  // namespace
}  // namespace geoanchor::solver
