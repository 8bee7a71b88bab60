// Pre-analysis (AdjustOptions::preanalysis), external reliability and the
// ranking of candidate measurements, against independent references:
// Monte Carlo adjustments of networks whose measured values are the
// truth plus noise drawn from the a-priori covariances (the predicted
// ellipses and σ_up must cover the scatter), the adjustment of the same
// design (covariances, redundancy, MDB), a dense N⁻¹ Aᵀ P ∇l built in the
// test from GeographicLib's local axes, and brute force: the design with
// each candidate added, adjusted (dense) afresh.

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include <cmath>
#include <random>

#include "accuracy.hpp"
#include "network_builder.hpp"
#include "test_support.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/solver/network_adjustment.hpp"

namespace geoanchor::solver {
namespace {

constexpr double kSameDesignRelative = 1e-12;       // the brief's bound: pre-analysis against an adjustment of the same design
constexpr double kSameDesignMixedRelative = 1e-10;  // terrestrial: the adjustment's rounding moves (below)
constexpr double kDenseRelative = 1e-9;        // external reliability and candidates against dense references
constexpr double kChi2_2d_95 = 5.991464547107979;  // χ²₂(0.95)
constexpr double kNormal_975 = 1.959963984540054;  // the two-sided 95 % normal quantile
constexpr double kCoverageLow = 0.93, kCoverageHigh = 0.97;  // the acceptance band
constexpr int kRuns = 500;

AdjustOptions options() {
  AdjustOptions o;
  o.data_snooping = false;
  return o;
}

AdjustOptions preanalysis() {
  AdjustOptions o = options();
  o.preanalysis = true;
  return o;
}

Network small_mixed(int stations, std::uint32_t seed, std::mt19937* noise = nullptr) {
  std::mt19937 rng(seed);
  const Site s = make_site(stations, rng);
  Network net = mixed_network(s, noise);
  net.stations[0].constraint.code = {'C', 'C', 'C'};
  return net;
}

// The pre-analysis of `net` against its adjustment, both at the same
// coordinates: covariances (relative to each station's largest entry),
// redundancy numbers and MDB (relative).
void expect_same_as_adjustment(Network net, double tolerance) {
  // The a-priori coordinates at the adjustment's solution (terrestrial
  // values are GeographicLib's, which the model reproduces to 1e-7 m):
  // adjusting again moves no station beyond rounding.
  AdjustOptions o = options();
  o.convergence_m = 1e-8;
  const AdjustmentResult first = adjust_network(net, o);
  for (std::size_t i = 0; i < net.stations.size(); ++i) net.stations[i].position = first.stations[i].position;
  const AdjustmentResult planned = adjust_network(net, preanalysis());
  const AdjustmentResult adjusted = adjust_network(net, o);
  ASSERT_TRUE(planned.preanalysis);
  EXPECT_EQ(planned.iterations, 0);
  EXPECT_FALSE(planned.sigma0.has_value());
  EXPECT_FALSE(planned.global_test.applicable);
  testing::WorstCase covariance, redundancy, mdb;
  for (std::size_t i = 0; i < net.stations.size(); ++i) {
    const double scale = testing::max_abs_component(adjusted.stations[i].covariance_m2);
    if (scale == 0.0) continue;  // the fixed station
    covariance.add(testing::max_abs_component(planned.stations[i].covariance_m2 - adjusted.stations[i].covariance_m2) / scale, i);
  }
  ASSERT_EQ(planned.measurements.size(), adjusted.measurements.size());
  for (std::size_t k = 0; k < planned.measurements.size(); ++k) {
    redundancy.add(testing::max_abs_component(planned.measurements[k].redundancy - adjusted.measurements[k].redundancy), k);
    const auto& a = adjusted.measurements[k].mdb;
    mdb.add(testing::max_abs_component(planned.measurements[k].mdb - a) / testing::max_abs_component(a), k);
    // No residual, no w-test: nothing measured is used.
    EXPECT_TRUE(planned.measurements[k].residual.array().isNaN().all());
    EXPECT_TRUE(planned.measurements[k].w.array().isNaN().all());
  }
  EXPECT_WORST_WITHIN(covariance, tolerance);
  EXPECT_WORST_WITHIN(redundancy, tolerance);
  EXPECT_WORST_WITHIN(mdb, tolerance);
}

// GNSS baselines: the design does not depend on where the stations are
// (the unknowns' axes are the a-priori ones), so the same design exactly.
TEST(Preanalysis, AGnssDesignEqualsItsAdjustment) {
  std::mt19937 rng(5);
  const Site s = make_site(15, rng);
  Network net = network_of(s);
  for (std::size_t i = 0; i + 1 < s.ecef.size(); ++i) add_baseline(net, s, i, i + 1, nullptr);
  for (std::size_t i = 0; i + 4 < s.ecef.size(); ++i) add_baseline(net, s, i, i + 4, nullptr);
  net.stations[0].constraint.code = {'C', 'C', 'C'};
  expect_same_as_adjustment(net, kSameDesignRelative);
}

// Every kind of measurement: the second adjustment moves the stations by
// rounding (1e-9 m in ECEF), which changes a 400 m sight's design by
// ~3e-12 of itself.
TEST(Preanalysis, AMixedDesignEqualsItsAdjustment) { expect_same_as_adjustment(small_mixed(12, 5), kSameDesignMixedRelative); }

TEST(Preanalysis, MeasuredValuesAreNotRead) {
  const Network net = small_mixed(9, 6);
  Network planned = net;
  for (auto& m : planned.measurements) {
    m.value.setZero();  // what a reader gives for "value": null
    m.value_known = false;
  }
  const AdjustmentResult with = adjust_network(net, preanalysis());
  const AdjustmentResult without = adjust_network(planned, preanalysis());
  testing::WorstCase covariance;
  for (std::size_t i = 0; i < net.stations.size(); ++i) {
    covariance.add(testing::max_abs_component(with.stations[i].covariance_m2 - without.stations[i].covariance_m2), i);
  }
  EXPECT_WORST_WITHIN(covariance, 0.0);
  // An adjustment refuses a measurement with no value, by name.
  try {
    (void)adjust_network(planned, options());
    FAIL() << "an adjustment took a measurement with no value";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_VALUE_MISSING");
    EXPECT_NE(std::string(e.what()).find(planned.measurements[0].source), std::string::npos) << e.what();
  }
}

TEST(Preanalysis, RefusesAStationWithoutAPrioriCoordinatesByName) {
  Network net = small_mixed(6, 7);
  net.stations[3].position_known = false;
  try {
    (void)adjust_network(net, preanalysis());
    FAIL() << "a pre-analysis took a station with no a-priori coordinates";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_PREANALYSIS_POSITION");
    EXPECT_NE(std::string(e.what()).find("S3"), std::string::npos) << e.what();
  }
}

// Adjustments of the network with noise drawn from the a-priori
// covariances: the predicted 95 % ellipses and 1-D σ_up intervals of the
// pre-analysis cover the adjusted positions' scatter about the truth.
TEST(Preanalysis, PredictedEllipsesAndSigmaUpCoverTheMonteCarloScatter) {
  std::mt19937 site_rng(11);
  const Site s = make_site(30, site_rng);
  Network design = mixed_network(s, nullptr);
  design.stations[0].constraint.code = {'C', 'C', 'C'};
  const AdjustmentResult planned = adjust_network(design, preanalysis());
  std::mt19937 rng(20261208);
  std::size_t inside_2d = 0, inside_up = 0, samples = 0;
  AdjustOptions o = options();
  o.external_reliability = false;  // not needed for the positions
  for (int run = 0; run < kRuns; ++run) {
    Network net = mixed_network(s, &rng);
    net.stations[0].constraint.code = {'C', 'C', 'C'};
    const AdjustmentResult r = adjust_network(net, o);
    for (std::size_t i = 1; i < s.ecef.size(); ++i) {
      const Eigen::Vector3d enu = local_to_ecef(s, i).transpose() * (r.stations[i].position - s.ecef[i]);
      const Eigen::Matrix3d q = local_to_ecef(s, i).transpose() * planned.stations[i].covariance_m2 * local_to_ecef(s, i);
      const Eigen::Vector2d en = enu.head<2>();
      const double d2 = en.dot(q.topLeftCorner<2, 2>().ldlt().solve(en));
      inside_2d += d2 <= kChi2_2d_95 ? 1u : 0u;
      inside_up += std::abs(enu(2)) <= kNormal_975 * std::sqrt(q(2, 2)) ? 1u : 0u;
      ++samples;
    }
  }
  const double c2 = static_cast<double>(inside_2d) / static_cast<double>(samples);
  const double cu = static_cast<double>(inside_up) / static_cast<double>(samples);
  RecordProperty("coverage_2d_95", std::to_string(c2));
  RecordProperty("coverage_up_95", std::to_string(cu));
  EXPECT_GE(c2, kCoverageLow);
  EXPECT_LE(c2, kCoverageHigh);
  EXPECT_GE(cu, kCoverageLow);
  EXPECT_LE(cu, kCoverageHigh);
  // The stations CSV's 95 % semi-major axis is the same ellipse: its
  // scale √χ²₂(0.95) of the 1σ one.
  EXPECT_NEAR(planned.stations[5].ellipse_confidence.semi_major_m / planned.stations[5].ellipse.semi_major_m, std::sqrt(kChi2_2d_95),
              1e-12);
}

// A GNSS network (the design is the local axes, known from GeographicLib):
// ∇x = N⁻¹ Aᵀ P ∇l, dense, for each component's MDB, against the effect the
// adjustment and the pre-analysis report.
void expect_external_reliability_dense(bool planned_mode) {
  std::mt19937 rng(21);
  const Site s = make_site(10, rng);
  Network net = network_of(s);
  for (std::size_t i = 0; i + 1 < s.ecef.size(); ++i) add_baseline(net, s, i, i + 1, nullptr);
  for (std::size_t i = 0; i + 3 < s.ecef.size(); ++i) add_baseline(net, s, i, i + 3, nullptr);
  add_baseline(net, s, 2, 9, nullptr);
  net.stations[0].constraint.code = {'C', 'C', 'C'};
  const AdjustmentResult r = adjust_network(net, planned_mode ? preanalysis() : options());
  // Unknowns: east, north, up of stations 1 … n−1.
  const auto n = static_cast<Eigen::Index>(3 * (s.ecef.size() - 1));
  const auto rows = static_cast<Eigen::Index>(3 * net.measurements.size());
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(rows, n), p = Eigen::MatrixXd::Zero(rows, rows);
  for (std::size_t k = 0; k < net.measurements.size(); ++k) {
    const auto& m = net.measurements[k];
    const auto row = static_cast<Eigen::Index>(3 * k);
    if (m.stations[1] > 0) a.block(row, static_cast<Eigen::Index>(3 * (m.stations[1] - 1)), 3, 3) += local_to_ecef(s, m.stations[1]);
    if (m.stations[0] > 0) a.block(row, static_cast<Eigen::Index>(3 * (m.stations[0] - 1)), 3, 3) -= local_to_ecef(s, m.stations[0]);
    p.block(row, row, 3, 3) = m.covariance.inverse();
  }
  const Eigen::MatrixXd normal = a.transpose() * p * a;
  const Eigen::LLT<Eigen::MatrixXd> llt(normal);
  testing::WorstCase effect, horizontal, vertical;
  std::size_t compared = 0;
  for (std::size_t k = 0; k < r.measurements.size(); ++k) {
    const auto& am = r.measurements[k];
    ASSERT_EQ(am.external.size(), 3u);
    for (Eigen::Index c = 0; c < 3; ++c) {
      Eigen::VectorXd bias = Eigen::VectorXd::Zero(rows);
      bias(static_cast<Eigen::Index>(3 * am.index) + c) = am.mdb(c);
      const Eigen::VectorXd dx = llt.solve(a.transpose() * p * bias);
      double worst = 0, worst_h = 0, worst_v = 0;
      std::size_t at = 0;
      for (std::size_t st = 1; st < s.ecef.size(); ++st) {
        const Eigen::Vector3d d = dx.segment<3>(static_cast<Eigen::Index>(3 * (st - 1)));
        if (d.norm() > worst) worst = d.norm(), at = st;
        worst_h = testing::nan_max(worst_h, std::hypot(d(0), d(1)));
        worst_v = testing::nan_max(worst_v, std::abs(d(2)));
      }
      const auto& e = am.external[static_cast<std::size_t>(c)];
      effect.add(std::abs(e.effect_m - worst) / worst, k);
      horizontal.add(std::abs(e.horizontal_m - worst_h) / worst, k);
      vertical.add(std::abs(e.vertical_m - worst_v) / worst, k);
      EXPECT_EQ(e.station, at) << am.index << " component " << c;
      ++compared;
    }
  }
  EXPECT_EQ(compared, 3 * net.measurements.size());
  EXPECT_WORST_WITHIN(effect, kDenseRelative);
  EXPECT_WORST_WITHIN(horizontal, kDenseRelative);
  EXPECT_WORST_WITHIN(vertical, kDenseRelative);
}

TEST(ExternalReliability, AdjustmentEqualsADenseComputation) { expect_external_reliability_dense(false); }
TEST(ExternalReliability, PreanalysisEqualsADenseComputation) { expect_external_reliability_dense(true); }

// The candidates ranked by the low-rank update against brute force: the
// design with each candidate added, its pre-analysis factored afresh
// (dense), the worst 95 % semi-major axis read from its stations.
TEST(PreanalysisCandidates, RankingEqualsBruteForce) {
  std::mt19937 rng(31);
  const Site s = make_site(9, rng);
  Network design = network_of(s);
  for (std::size_t i = 0; i + 1 < s.ecef.size(); ++i) add_baseline(design, s, i, i + 1, nullptr);
  add_baseline(design, s, 0, 4, nullptr);
  // A direction set in the design (its orientation an unknown).
  design.direction_sets.push_back({2, "set at 2"});
  for (std::size_t j : {1u, 3u, 5u}) {
    auto m = scalar(MeasurementKind::direction, {2, j}, 0.0, 1.0 * kArcsec, "design direction 2-" + std::to_string(j));
    m.set = 0;
    design.measurements.push_back(m);
  }
  design.stations[0].constraint.code = {'C', 'C', 'C'};
  // Candidates: baselines, distances, a direction of the design's set, and
  // a new set of three directions (one candidate).
  std::vector<NetworkMeasurement> candidates;
  std::vector<std::vector<std::size_t>> expected_groups;
  {
    Network tmp = design;
    add_baseline(tmp, s, 8, 0, nullptr);
    add_baseline(tmp, s, 3, 7, nullptr);
    candidates.push_back(tmp.measurements[tmp.measurements.size() - 2]);
    candidates.push_back(tmp.measurements.back());
  }
  candidates.push_back(scalar(MeasurementKind::slope_distance, {8, 5}, 0.0, 0.002, "candidate distance 8-5"));
  candidates.push_back(scalar(MeasurementKind::horizontal_distance, {6, 1}, 0.0, 0.001, "candidate distance 6-1"));
  auto old_set = scalar(MeasurementKind::direction, {2, 8}, 0.0, 1.0 * kArcsec, "candidate direction 2-8");
  old_set.set = 0;
  candidates.push_back(old_set);
  design.direction_sets.push_back({7, "new set at 7"});
  for (std::size_t j : {8u, 4u, 6u}) {
    auto m = scalar(MeasurementKind::direction, {7, j}, 0.0, 1.0 * kArcsec, "candidate direction 7-" + std::to_string(j));
    m.set = 1;
    candidates.push_back(m);
  }
  AdjustOptions o = preanalysis();
  o.candidates = candidates;
  const AdjustmentResult r = adjust_network(design, o);
  ASSERT_EQ(r.candidates.size(), 6u);  // the new set's three directions are one candidate
  // Brute force.
  const double scale = std::sqrt(kChi2_2d_95);
  auto worst_of = [&](const AdjustmentResult& x) {
    double worst = 0.0;
    for (const auto& st : x.stations) worst = testing::nan_max(worst, st.ellipse.semi_major_m * scale);
    return worst;
  };
  AdjustOptions dense = preanalysis();
  dense.dense = true;
  EXPECT_NEAR(r.design_worst.value, worst_of(adjust_network(design, dense)), kDenseRelative * r.design_worst.value);
  testing::WorstCase value;
  std::vector<double> brute;
  for (const auto& c : r.candidates) {
    Network with = design;
    for (std::size_t mi : c.measurements) with.measurements.push_back(candidates[mi]);
    const double expected = worst_of(adjust_network(with, dense));
    brute.push_back(expected);
    value.add(std::abs(c.worst.value - expected) / expected);
  }
  EXPECT_WORST_WITHIN(value, kDenseRelative);
  // Ranked: the brute-force values ascend in the reported order.
  for (std::size_t k = 1; k < brute.size(); ++k) EXPECT_LE(brute[k - 1], brute[k] * (1 + kDenseRelative)) << k;
  // Each improves on the design (or leaves it).
  for (const auto& c : r.candidates) EXPECT_GE(c.improvement, -kDenseRelative * r.design_worst.value);
}

TEST(PreanalysisCandidates, ACandidateAtAStationOutsideTheDesignIsRefusedByName) {
  Network net = small_mixed(6, 8);
  NetworkStation extra;
  extra.id = "FAR";
  extra.position = net.stations[1].position + Eigen::Vector3d(100, 0, 0);
  extra.source = "station FAR";
  net.stations.push_back(extra);
  AdjustOptions o = preanalysis();
  o.candidates.push_back(scalar(MeasurementKind::slope_distance, {1, net.stations.size() - 1}, 0.0, 0.002, "candidate to FAR"));
  try {
    (void)adjust_network(net, o);
    FAIL() << "a candidate at a station outside the design was taken";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_CANDIDATE_STATION");
    EXPECT_NE(std::string(e.what()).find("FAR"), std::string::npos) << e.what();
  }
  // Candidates without a pre-analysis: refused.
  AdjustOptions not_planned = options();
  not_planned.candidates = o.candidates;
  try {
    (void)adjust_network(small_mixed(6, 8), not_planned);
    FAIL() << "candidates were taken without a pre-analysis";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_OPTION");
  }
}

}  // namespace
}  // namespace geoanchor::solver
