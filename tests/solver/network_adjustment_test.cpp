// The network adjustment against independent references: observations
// computed from a known truth by GeographicLib (geocentric positions, local
// east/north/up at the instrument) are adjusted back to that truth; the
// sparse factor and its selected inversion against a dense solve; Monte
// Carlo coverage of the reported sigmas, the variance factor and the
// detection rate the MDB promises; the datum's defects by name.

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <GeographicLib/Geocentric.hpp>
#include <GeographicLib/Geodesic.hpp>
#include <GeographicLib/LocalCartesian.hpp>

#include <cmath>
#include <numbers>
#include <random>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "network_builder.hpp"
#include "test_support.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/solver/network_adjustment.hpp"

namespace geoanchor::solver {
namespace {


constexpr double kRecoveryTol_m = 1e-6;       // noise-free observations back to the truth (iteration stops at 1e-7 m)
constexpr double kSparseVsDense_m = 1e-9;     // the bound
constexpr double kSparseVsDenseRelative = 1e-9;

AdjustOptions options(bool dense) {
  AdjustOptions o;
  o.dense = dense;
  o.data_snooping = false;
  return o;
}

TEST(NetworkAdjustment, NoiseFreeObservationsOfEveryKindGiveBackTheTruth) {
  std::mt19937 rng(7);
  const Site s = make_site(12, rng);
  Network net = mixed_network(s, nullptr);
  net.stations[0].constraint.code = {'C', 'C', 'C'};
  // Start 5 m away from the truth (the fixed station at it).
  std::normal_distribution<double> z;
  for (std::size_t i = 1; i < net.stations.size(); ++i) net.stations[i].position += 2.0 * Eigen::Vector3d(z(rng), z(rng), z(rng));
  AdjustOptions o = options(false);
  o.convergence_m = 1e-7;
  const AdjustmentResult r = adjust_network(net, o);
  testing::WorstCase worst;
  for (std::size_t i = 0; i < s.ecef.size(); ++i) worst.add((r.stations[i].position - s.ecef[i]).norm(), i);
  EXPECT_WORST_WITHIN(worst, kRecoveryTol_m);
  EXPECT_LT(r.vtpv, 1e-6);
  // Each orientation is the one the directions were made with.
  for (std::size_t k = 0; k < r.orientations_rad.size(); ++k) {
    EXPECT_NEAR(std::remainder(r.orientations_rad[k] - (0.3 + 0.1 * static_cast<double>(k)), 2 * std::numbers::pi), 0.0, 1e-9);
  }
}

// The sparse and the dense solve of one network, station by station and
// measurement by measurement: positions (m), covariances (relative to each
// station's largest entry), redundancy numbers; and Σ r of the measurements.
struct SparseVsDense {
  testing::WorstCase position, covariance, redundancy;
  double redundancy_sum = 0.0;
};
SparseVsDense compare_sparse_dense(const AdjustmentResult& sparse, const AdjustmentResult& dense) {
  SparseVsDense c;
  for (std::size_t i = 0; i < sparse.stations.size(); ++i) {
    c.position.add((sparse.stations[i].position - dense.stations[i].position).norm(), i);
    const double scale = testing::max_abs_component(dense.stations[i].covariance_m2);
    // A fixed station's covariance is zero: skipped; a NaN reference is counted (and fails).
    if (scale != 0.0) c.covariance.add(testing::max_abs_component(sparse.stations[i].covariance_m2 - dense.stations[i].covariance_m2) / scale, i);
  }
  for (std::size_t k = 0; k < sparse.measurements.size(); ++k) {
    c.redundancy.add(testing::max_abs_component(sparse.measurements[k].redundancy - dense.measurements[k].redundancy), k);
    c.redundancy_sum += sparse.measurements[k].redundancy.sum();
  }
  return c;
}

TEST(NetworkAdjustment, SparseAndDenseSolvesAgreeAndRedundancyNumbersSumToTheDegreesOfFreedom) {
  std::mt19937 rng(11);
  const Site s = make_site(16, rng);
  Network net = mixed_network(s, &rng);
  net.stations[0].constraint.code = {'C', 'C', 'C'};
  net.stations[5].constraint.code = {'C', 'C', 'F'};
  net.stations[5].constraint.sigma_m = {0.005, 0.005, 0.0};
  const AdjustmentResult sparse = adjust_network(net, options(false));
  const AdjustmentResult dense = adjust_network(net, options(true));
  ASSERT_EQ(sparse.stations.size(), dense.stations.size());
  const SparseVsDense c = compare_sparse_dense(sparse, dense);
  EXPECT_WORST_WITHIN(c.position, kSparseVsDense_m);
  EXPECT_WORST_WITHIN(c.covariance, kSparseVsDenseRelative);
  EXPECT_WORST_WITHIN(c.redundancy, kSparseVsDenseRelative);
  double sum = c.redundancy_sum;
  // Σ r over the measurements and the held station's two constraints = dof.
  // The constraints' share: r of a pseudo-observation is 1 − σ_x²/σ_c².
  const auto& held = sparse.stations[5];
  const double c_north = held.covariance_local_m2(1, 1), c_east = held.covariance_local_m2(0, 0);
  sum += (1.0 - c_north / (0.005 * 0.005)) + (1.0 - c_east / (0.005 * 0.005));
  EXPECT_NEAR(sum, static_cast<double>(sparse.dof), 1e-8);
  EXPECT_EQ(sparse.dof, dense.dof);
  EXPECT_NEAR(sparse.vtpv, dense.vtpv, 1e-9 * std::max(1.0, dense.vtpv));
}

// Monte Carlo on a GNSS network with known truth: the reported sigmas cover
// the truth at 1.96σ in 93–97 % of the coordinates, the mean variance factor
// is 1 ± 0.05.
TEST(NetworkAdjustment, MonteCarloCoverageAndVarianceFactor) {
  constexpr int kTrials = 300;
  std::mt19937 rng(2024);
  const Site s = make_site(15, rng);
  std::size_t inside = 0, total = 0;
  double factor_sum = 0.0;
  for (int t = 0; t < kTrials; ++t) {
    Network net = network_of(s);
    for (std::size_t i = 0; i + 1 < s.ecef.size(); ++i) add_baseline(net, s, i, i + 1, &rng);
    for (std::size_t i = 0; i + 4 < s.ecef.size(); ++i) add_baseline(net, s, i, i + 4, &rng);
    for (std::size_t i = 0; i + 5 < s.ecef.size(); i += 2) add_baseline(net, s, i, i + 5, &rng);
    net.stations[0].constraint.code = {'C', 'C', 'C'};
    const AdjustmentResult r = adjust_network(net, options(false));
    factor_sum += *r.variance_factor;
    for (std::size_t i = 1; i < s.ecef.size(); ++i) {
      const Eigen::Vector3d e = r.stations[i].position - s.ecef[i];
      for (int k = 0; k < 3; ++k) {
        inside += std::fabs(e(k)) <= 1.96 * std::sqrt(r.stations[i].covariance_m2(k, k)) ? 1u : 0u;
        ++total;
      }
    }
  }
  const double coverage = static_cast<double>(inside) / static_cast<double>(total);
  EXPECT_GE(coverage, 0.93);
  EXPECT_LE(coverage, 0.97);
  EXPECT_NEAR(factor_sum / kTrials, 1.0, 0.05);
}

// The same for terrestrial-only, levelling and mixed networks (issue 14's
// acceptance: coverage of ±1.96σ within 93–97 %, mean variance factor
// 1 ± 0.05): each network's observations drawn from their a-priori
// covariance around a truth computed by GeographicLib (terrestrial, mixed)
// or by hand (levelling, a local 1-D network).
TEST(NetworkAdjustment, MonteCarloCoverageForTerrestrialLevellingAndMixedNetworks) {
  constexpr int kTrials = 200;
  constexpr double kCoverageLow = 0.93, kCoverageHigh = 0.97, kMeanFactorTolerance = 0.05;
  std::mt19937 rng(4242);
  const Site s = make_site(10, rng);
  enum class Kind { terrestrial, levelling, mixed };
  for (const Kind kind : {Kind::terrestrial, Kind::levelling, Kind::mixed}) {
    const char* name = kind == Kind::terrestrial ? "terrestrial" : kind == Kind::levelling ? "levelling" : "mixed";
    SCOPED_TRACE(name);
    std::size_t inside = 0, total = 0;
    double factor_sum = 0.0;
    // Levelling truth: heights of 12 bench marks, lines between neighbours and across.
    std::vector<double> heights;
    for (int i = 0; i < 12; ++i) heights.push_back(400.0 + 7.0 * i + 3.0 * std::sin(i));
    for (int t = 0; t < kTrials; ++t) {
      Network net;
      std::vector<Eigen::Vector3d> truth;
      if (kind == Kind::levelling) {
        net.space = geodesy::NetworkSpace::local;
        net.local_dimensions = 1;
        net.source_name = "levelling";
        for (std::size_t i = 0; i < heights.size(); ++i) {
          NetworkStation st;
          st.id = "BM" + std::to_string(i);
          st.position = Eigen::Vector3d(0, 0, heights[i] + (i == 0 ? 0.0 : 0.3));  // a-priori off by 0.3 m
          if (i == 0) st.constraint.code = {'F', 'F', 'C'};
          net.stations.push_back(st);
          truth.emplace_back(0, 0, heights[i]);
        }
        std::normal_distribution<double> z;
        auto line = [&](std::size_t a, std::size_t b, double km) {
          const double sigma = 0.001 * std::sqrt(km);
          net.measurements.push_back(scalar(MeasurementKind::height_difference, {a, b}, heights[b] - heights[a] + sigma * z(rng), sigma, "dh"));
        };
        for (std::size_t i = 0; i + 1 < heights.size(); ++i) line(i, i + 1, 1.0 + 0.1 * static_cast<double>(i));
        for (std::size_t i = 0; i + 3 < heights.size(); i += 2) line(i, i + 3, 2.5);
      } else {
        net = mixed_network(s, &rng);
        if (kind == Kind::terrestrial) {
          std::vector<NetworkMeasurement> kept;
          for (auto& m : net.measurements) {
            if (m.kind != MeasurementKind::gnss_baselines && m.kind != MeasurementKind::gnss_points) kept.push_back(std::move(m));
          }
          net.measurements = std::move(kept);
          net.stations[5].constraint.code = {'C', 'C', 'C'};
        }
        net.stations[0].constraint.code = {'C', 'C', 'C'};
        truth = s.ecef;
        // The a-priori positions 2 cm off the truth (the fixed ones at it).
        std::normal_distribution<double> z(0.0, 0.02);
        for (std::size_t i = 0; i < net.stations.size(); ++i) {
          if (!net.stations[i].constraint.any()) net.stations[i].position += Eigen::Vector3d(z(rng), z(rng), z(rng));
        }
      }
      const AdjustmentResult r = adjust_network(net, options(false));
      factor_sum += *r.variance_factor;
      for (std::size_t i = 0; i < net.stations.size(); ++i) {
        if (net.stations[i].constraint.any()) continue;
        const Eigen::Vector3d e = r.stations[i].position - truth[i];
        for (int k = kind == Kind::levelling ? 2 : 0; k < 3; ++k) {
          inside += std::fabs(e(k)) <= 1.96 * std::sqrt(r.stations[i].covariance_m2(k, k)) ? 1u : 0u;
          ++total;
        }
      }
    }
    const double coverage = static_cast<double>(inside) / static_cast<double>(total);
    EXPECT_GE(coverage, kCoverageLow);
    EXPECT_LE(coverage, kCoverageHigh);
    EXPECT_NEAR(factor_sum / kTrials, 1.0, kMeanFactorTolerance);
  }
}

// A blunder of the size of a distance's MDB is found by its w-test about as
// often as the MDB's power (0.80) promises.
TEST(NetworkAdjustment, APlantedBlunderOfTheMdbIsFoundAtTheMdbsPower) {
  constexpr int kTrials = 300;
  std::mt19937 rng(99);
  const Site s = make_site(12, rng);
  Network base = mixed_network(s, &rng);
  base.stations[0].constraint.code = {'C', 'C', 'C'};
  const AdjustmentResult clean = adjust_network(base, options(false));
  // A slope distance with fair redundancy.
  std::size_t target = 0;
  for (const auto& am : clean.measurements) {
    if (base.measurements[am.index].kind == MeasurementKind::slope_distance && am.redundancy(0) > 0.3) {
      target = am.index;
      break;
    }
  }
  double mdb = 0.0;
  for (const auto& am : clean.measurements) {
    if (am.index == target) mdb = am.mdb(0);
  }
  ASSERT_GT(mdb, 0.0);
  int found = 0;
  for (int t = 0; t < kTrials; ++t) {
    Network net = mixed_network(s, &rng);
    net.stations[0].constraint.code = {'C', 'C', 'C'};
    net.measurements[target].value(0) += mdb;
    const AdjustmentResult r = adjust_network(net, options(false));
    for (const auto& am : r.measurements) {
      if (am.index == target && std::fabs(am.w(0)) > r.w_critical) ++found;
    }
  }
  const double rate = static_cast<double>(found) / kTrials;
  EXPECT_GE(rate, 0.72);  // 0.80 ± 3.4 standard errors of 300 trials
  EXPECT_LE(rate, 0.88);
}

// A legacy survey of every station in a datum of its own: the truth
// through the inverse of a planted Helmert (position vector, EPSG
// small-angle: x = T + (1 + ds)(I + [r]×) y), observed with 5 mm per axis.
constexpr double kLegacySigma_m = 0.005;
const Eigen::Matrix<double, 7, 1> kPlantedHelmert =
    (Eigen::Matrix<double, 7, 1>() << 1.234, -0.567, 0.89, 0.7 * kArcsec, -0.4 * kArcsec, 1.1 * kArcsec, 2.5e-6).finished();

void add_legacy_cluster(Network& net, const Site& s, std::mt19937* rng) {
  const Eigen::Matrix<double, 7, 1>& h = kPlantedHelmert;
  Eigen::Matrix3d r;
  r << 1.0, -h(5), h(4), h(5), 1.0, -h(3), -h(4), h(3), 1.0;
  NetworkMeasurement m;
  m.kind = MeasurementKind::gnss_points;
  const auto n = static_cast<Eigen::Index>(s.ecef.size());
  m.value.resize(3 * n);
  m.covariance = Eigen::MatrixXd::Identity(3 * n, 3 * n) * kLegacySigma_m * kLegacySigma_m;
  for (Eigen::Index i = 0; i < n; ++i) {
    m.stations.push_back(static_cast<std::size_t>(i));
    m.value.segment<3>(3 * i) = r.inverse() * (s.ecef[static_cast<std::size_t>(i)] - h.head<3>()) / (1.0 + h(6));
  }
  if (rng) m.value += draw(m.covariance, *rng);
  m.group = "legacy";
  m.source = "legacy survey";
  net.measurements.push_back(m);
}

HelmertGroup legacy_group(const Network& net) {
  HelmertGroup g;
  g.name = "legacy";
  g.measurements = {net.measurements.size() - 1};
  return g;
}

TEST(NetworkAdjustment, HelmertGroupSparseAndDenseAgreeAndRedundancyNumbersSumToTheDegreesOfFreedom) {
  std::mt19937 rng(31);
  const Site s = make_site(16, rng);
  Network net = mixed_network(s, &rng);
  net.stations[0].constraint.code = {'C', 'C', 'C'};
  add_legacy_cluster(net, s, &rng);
  AdjustOptions o = options(false);
  o.helmert = legacy_group(net);
  const AdjustmentResult sparse = adjust_network(net, o);
  o.dense = true;
  const AdjustmentResult dense = adjust_network(net, o);
  ASSERT_TRUE(sparse.helmert && dense.helmert);
  SparseVsDense c = compare_sparse_dense(sparse, dense);
  const Eigen::MatrixXd& hc = dense.helmert->covariance;
  for (Eigen::Index i = 0; i < 7; ++i) {
    for (Eigen::Index j = 0; j < 7; ++j) {
      c.covariance.add(std::abs(sparse.helmert->covariance(i, j) - hc(i, j)) / std::sqrt(hc(i, i) * hc(j, j)), 100 + static_cast<std::size_t>(i));
    }
  }
  // The two estimates move the stations alike (the geocentric parameters of
  // a group a few kilometres across are determined only together, to
  // micrometres each, as their σ of metres says).
  auto moved = [](const Eigen::VectorXd& h, const Eigen::Vector3d& y) {
    Eigen::Matrix3d r;
    r << 1.0, -h(5), h(4), h(5), 1.0, -h(3), -h(4), h(3), 1.0;
    return Eigen::Vector3d(h.head<3>() + (1.0 + h(6)) * r * y);
  };
  testing::WorstCase parameters;
  for (std::size_t i = 0; i < s.ecef.size(); ++i) {
    parameters.add((moved(sparse.helmert->parameters, s.ecef[i]) - moved(dense.helmert->parameters, s.ecef[i])).norm(), i);
  }
  EXPECT_WORST_WITHIN(c.position, kSparseVsDense_m);
  EXPECT_WORST_WITHIN(c.covariance, kSparseVsDenseRelative);
  EXPECT_WORST_WITHIN(c.redundancy, kSparseVsDenseRelative);
  // The points are evaluated from geocentric parameters: sums of terms of
  // 6.4e6 m, whose float64 spacing is 9.3e-10 m (RELIABILITY, round trip).
  constexpr double kMovedByBothEstimates_m = 1e-8;
  EXPECT_WORST_WITHIN(parameters, kMovedByBothEstimates_m);
  const double sum = c.redundancy_sum;
  EXPECT_NEAR(sum, static_cast<double>(sparse.dof), 1e-8);
  EXPECT_EQ(sparse.unknowns, dense.unknowns);
}

// Monte Carlo: the planted Helmert within ±1.96σ of its estimate in 93–97 %
// of the parameters (RELIABILITY 2), the mean variance factor 1 ± 0.05.
TEST(NetworkAdjustment, MonteCarloCoverageOfAnEstimatedHelmert) {
  constexpr int kTrials = 200;
  std::mt19937 rng(77);
  const Site s = make_site(12, rng, 1500.0);
  std::size_t inside = 0, total = 0;
  double factor_sum = 0.0;
  for (int t = 0; t < kTrials; ++t) {
    Network net = network_of(s);
    for (std::size_t i = 0; i + 1 < s.ecef.size(); ++i) add_baseline(net, s, i, i + 1, &rng);
    for (std::size_t i = 0; i + 4 < s.ecef.size(); ++i) add_baseline(net, s, i, i + 4, &rng);
    net.stations[0].constraint.code = {'C', 'C', 'C'};
    add_legacy_cluster(net, s, &rng);
    AdjustOptions o = options(false);
    o.helmert = legacy_group(net);
    const AdjustmentResult r = adjust_network(net, o);
    ASSERT_TRUE(r.helmert);
    factor_sum += *r.variance_factor;
    for (Eigen::Index k = 0; k < 7; ++k) {
      inside += std::abs(r.helmert->parameters(k) - kPlantedHelmert(k)) <= 1.96 * std::sqrt(r.helmert->covariance(k, k)) ? 1u : 0u;
      ++total;
    }
  }
  const double coverage = static_cast<double>(inside) / static_cast<double>(total);
  RecordProperty("coverage", std::to_string(coverage));
  RecordProperty("mean_variance_factor", std::to_string(factor_sum / kTrials));
  EXPECT_GE(coverage, 0.93);
  EXPECT_LE(coverage, 0.97);
  EXPECT_NEAR(factor_sum / kTrials, 1.0, 0.05);
}

// Issue 17 point 5 (review), issue 39: in a single loop of 20 baselines
// one blunder makes every leg fail alike: each leg's residual is its share
// of the loop's one misclosure, so the legs' residuals are correlated by ±1
// and the data cannot say which leg is wrong. Removing any leg would leave
// the others with no redundancy (they would "pass" untested). So none is
// removed, even with --remove-outliers: every failing leg stays flagged, and
// a warning says they cannot be told apart. (Taking legs 4 hops apart
// together once split the network: E_NETWORK_DISCONNECTED.)
TEST(NetworkAdjustment, ASingleLoopsBlunderCannotBeLocatedSoNoLegIsRemoved) {
  std::mt19937 rng(20);
  Site s;
  for (int i = 0; i < 20; ++i) {
    const double angle = 2.0 * std::numbers::pi * i / 20.0;
    const double lat = 47.45 + 3000.0 * std::sin(angle) / 111200.0;
    const double lon = 8.54 + 3000.0 * std::cos(angle) / (111200.0 * std::cos(47.45 * std::numbers::pi / 180.0));
    double x = 0, y = 0, z = 0;
    grs80().Forward(lat, lon, 450.0, x, y, z);
    s.ecef.emplace_back(x, y, z);
    s.geodetic.push_back({lat, lon, 450.0});
  }
  Network net = network_of(s);
  net.stations[0].constraint.code = {'C', 'C', 'C'};
  for (std::size_t i = 0; i < 20; ++i) add_baseline(net, s, i, (i + 1) % 20, &rng);
  net.measurements[7].value += Eigen::Vector3d(0.06, -0.05, 0.05);  // 10 cm
  AdjustOptions o;
  o.remove_outliers = true;
  const AdjustmentResult r = adjust_network(net, o);
  ASSERT_TRUE(r.converged);
  std::size_t removed = 0, flagged = 0;
  for (const auto& m : r.measurements) {
    removed += m.outlier ? 1u : 0u;
    flagged += m.status(r.alpha_point) == TestStatus::flagged ? 1u : 0u;
    EXPECT_EQ(m.snooping_rank, 0u) << m.index;
  }
  EXPECT_EQ(removed, 0u);
  EXPECT_GE(flagged, 2u);  // the planted leg and at least one it cannot be told from
  EXPECT_TRUE(r.measurements[7].fails_test(r.alpha_point));
  bool warned = false;
  for (const auto& w : r.warnings) warned = warned || w.find("cannot be told apart") != std::string::npos;
  EXPECT_TRUE(warned);
}

// A direction set whose every direction is set aside (ignored in the input,
// left out in the workbench) has no orientation unknown: the adjustment is
// the one without those directions, with one unknown fewer.
TEST(NetworkAdjustment, ADirectionSetWithNoDirectionLeftHasNoOrientationUnknown) {
  std::mt19937 rng(5);
  const Site s = make_site(12, rng);
  Network net = mixed_network(s, &rng);
  net.stations[0].constraint.code = {'C', 'C', 'C'};
  ASSERT_FALSE(net.direction_sets.empty());
  const AdjustmentResult all = adjust_network(net, options(false));
  int rows = 0;
  for (auto& m : net.measurements) {
    if (m.kind == MeasurementKind::direction && m.set == 0u) {
      m.ignore = true;
      ++rows;
    }
  }
  ASSERT_GT(rows, 0);
  const AdjustmentResult without = adjust_network(net, options(false));
  EXPECT_EQ(without.dof, all.dof - rows + 1);
  EXPECT_EQ(without.unknowns, all.unknowns - 1);
  EXPECT_TRUE(std::isnan(without.orientation_sigmas_rad[0]));
}

// A local network's error ellipse is oriented from +x towards +y (a bearing
// when x is north and y east, as GNU Gama gives it). B is placed by two
// horizontal distances from held stations, A (along +x, σ 1 mm) and C
// (along the diagonal, σ 20 mm): its covariance is the inverse of
// Σ u uᵀ / σ², whose eigenvectors Eigen gives independently of the solver.
TEST(NetworkAdjustment, ALocalNetworksEllipseIsOrientedFromXTowardsY) {
  constexpr double kAzimuthTol_rad = 1e-6;
  constexpr double kAxisTol_m = 1e-9;
  Network net;
  net.space = geodesy::NetworkSpace::local;
  net.local_dimensions = 2;
  net.source_name = "local";
  const auto station = [&](const char* id, double x, double y, bool held) {
    NetworkStation st;
    st.id = id;
    st.position = Eigen::Vector3d(x, y, 0.0);
    if (held) st.constraint.code = {'C', 'C', 'F'};
    net.stations.push_back(st);
  };
  station("A", 0.0, 0.0, true);
  station("C", 0.0, 100.0, true);
  station("B", 100.0, 0.0, false);
  const double sigma_ab = 0.001, sigma_cb = 0.020;
  net.measurements.push_back(scalar(MeasurementKind::horizontal_distance, {0, 2}, 100.0, sigma_ab, "AB"));
  net.measurements.push_back(scalar(MeasurementKind::horizontal_distance, {1, 2}, 100.0 * std::sqrt(2.0), sigma_cb, "CB"));
  const AdjustmentResult r = adjust_network(net, options(false));
  ASSERT_EQ(r.dof, 0);
  const Eigen::Vector2d u1(1.0, 0.0), u2 = Eigen::Vector2d(100.0, -100.0).normalized();
  const Eigen::Matrix2d n = u1 * u1.transpose() / (sigma_ab * sigma_ab) + u2 * u2.transpose() / (sigma_cb * sigma_cb);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(n.inverse());
  const Eigen::Vector2d major = eig.eigenvectors().col(1);  // (x, y) of the larger eigenvalue
  double expected = std::atan2(major.y(), major.x());       // from +x towards +y
  if (expected < 0.0) expected += std::numbers::pi;
  const auto& b = r.stations[2].ellipse;
  EXPECT_NEAR(b.semi_major_m, std::sqrt(eig.eigenvalues()(1)), kAxisTol_m);
  EXPECT_NEAR(b.semi_minor_m, std::sqrt(eig.eigenvalues()(0)), kAxisTol_m);
  EXPECT_NEAR(std::remainder(b.azimuth_rad - expected, std::numbers::pi), 0.0, kAzimuthTol_rad);
}

TEST(NetworkAdjustment, AnUndefinedDatumIsNamedAndAFreeNetworkHeldByInnerConstraints) {
  std::mt19937 rng(5);
  const Site s = make_site(9, rng);
  Network net = network_of(s);
  for (std::size_t i = 0; i + 1 < s.ecef.size(); ++i) add_baseline(net, s, i, i + 1, &rng);
  for (std::size_t i = 0; i + 3 < s.ecef.size(); ++i) add_baseline(net, s, i, i + 3, &rng);
  try {
    (void)adjust_network(net, options(false));
    ADD_FAILURE() << "a network of baselines alone was adjusted without a datum";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_DATUM_DEFECT");
    const std::string what = e.what();
    EXPECT_NE(what.find("translation along X"), std::string::npos) << what;
    EXPECT_EQ(what.find("rotation"), std::string::npos) << what;  // baselines fix the orientation
    EXPECT_EQ(what.find("scale"), std::string::npos) << what;
  }
  AdjustOptions o = options(false);
  o.free = true;
  const AdjustmentResult free = adjust_network(net, o);
  // Inner constraints over all stations: the corrections average to zero.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& st : free.stations) mean += st.position - st.a_priori;
  mean /= static_cast<double>(free.stations.size());
  EXPECT_LT(mean.norm(), 1e-9);
  // The residuals do not depend on the datum: the same as with one station fixed.
  Network held = net;
  held.stations[4].constraint.code = {'C', 'C', 'C'};
  const AdjustmentResult fixed = adjust_network(held, options(false));
  EXPECT_NEAR(free.vtpv, fixed.vtpv, 1e-9 * fixed.vtpv);
  EXPECT_EQ(free.dof, fixed.dof);
  // The inner-constraint covariance has the smallest trace of any datum.
  double trace_free = 0.0, trace_fixed = 0.0;
  for (std::size_t i = 0; i < free.stations.size(); ++i) {
    trace_free += free.stations[i].covariance_m2.trace();
    trace_fixed += fixed.stations[i].covariance_m2.trace();
  }
  EXPECT_LT(trace_free, trace_fixed);
  // The translations' covariance is zero: the covariance of the mean
  // position (over all pairs) vanishes; on the diagonal blocks alone, their
  // sum is (n - 1)/n of the fixed datum's sum over the other stations when
  // the defect is a pure translation.
  const AdjustmentResult dense_free = [&] {
    AdjustOptions d = o;
    d.dense = true;
    return adjust_network(net, d);
  }();
  testing::WorstCase agreement;
  for (std::size_t i = 0; i < free.stations.size(); ++i) {
    const double scale = testing::max_abs_component(dense_free.stations[i].covariance_m2);
    agreement.add(testing::max_abs_component(free.stations[i].covariance_m2 - dense_free.stations[i].covariance_m2) / scale, i);
  }
  EXPECT_WORST_WITHIN(agreement, kSparseVsDenseRelative);
}

TEST(NetworkAdjustment, BadNetworksAreRefusedByName) {
  std::mt19937 rng(3);
  const Site s = make_site(8, rng);
  auto code_of = [](const Network& net, const AdjustOptions& o) {
    try {
      (void)adjust_network(net, o);
    } catch (const Error& e) {
      return std::string(e.code()) + ": " + e.what();
    }
    return std::string("no error");
  };
  // Two parts that no measurement joins.
  Network split = network_of(s);
  add_baseline(split, s, 0, 1, &rng);
  add_baseline(split, s, 2, 3, &rng);
  split.stations[0].constraint.code = {'C', 'C', 'C'};
  split.stations[2].constraint.code = {'C', 'C', 'C'};
  const std::string disconnected = code_of(split, options(false));
  EXPECT_EQ(disconnected.rfind("E_NETWORK_DISCONNECTED", 0), 0u) << disconnected;
  EXPECT_NE(disconnected.find("S2"), std::string::npos) << disconnected;
  // Every measurement ignored or left out: nothing to adjust (the network
  // view can leave every station out).
  Network idle = split;
  for (auto& m : idle.measurements) m.ignore = true;
  const std::string empty = code_of(idle, options(false));
  EXPECT_EQ(empty.rfind("E_NETWORK_EMPTY", 0), 0u) << empty;
  EXPECT_NE(empty.find("no measurement to adjust (2 read"), std::string::npos) << empty;
  idle.measurements.clear();
  EXPECT_EQ(code_of(idle, options(false)).rfind("E_NETWORK_EMPTY", 0), 0u);
  // A covariance that is not positive definite, named with its smallest eigenvalue.
  Network bad = network_of(s);
  add_baseline(bad, s, 0, 1, &rng);
  bad.stations[0].constraint.code = {'C', 'C', 'C'};
  bad.measurements[0].covariance(0, 1) = bad.measurements[0].covariance(1, 0) = 1.0;
  const std::string cov = code_of(bad, options(false));
  EXPECT_EQ(cov.rfind("E_COVARIANCE", 0), 0u) << cov;
  EXPECT_NE(cov.find("baseline 0-1"), std::string::npos) << cov;
  EXPECT_NE(cov.find("smallest eigenvalue -"), std::string::npos) << cov;
  // A station reached by one distance only: its position is not determined
  // (the baselines 0-1 and 0-3 and the fixed station define the datum).
  Network weak = network_of(s);
  add_baseline(weak, s, 0, 1, &rng);
  add_baseline(weak, s, 0, 3, &rng);
  weak.stations[0].constraint.code = {'C', 'C', 'C'};
  const Sighting g = sighting(s, 1, 2, 0.0, 0.0);
  weak.measurements.push_back(scalar(MeasurementKind::slope_distance, {1, 2},
                                     std::sqrt(g.east * g.east + g.north * g.north + g.up * g.up), 0.002, "line 9"));
  const std::string singular = code_of(weak, options(false));
  EXPECT_EQ(singular.rfind("E_NETWORK_SINGULAR", 0), 0u) << singular;
  EXPECT_NE(singular.find("station S2"), std::string::npos) << singular;
}

}  // namespace
}  // namespace geoanchor::solver
