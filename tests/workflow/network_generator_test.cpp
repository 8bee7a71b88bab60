// The network generator (workflow/network_generator.hpp) and the network
// writers (io/network/network_output.hpp): what is written reads back to the same
// network in both formats; a generated network adjusted as `geoanchor
// adjust` reads it agrees with the generator's truth within the adjusted
// covariances, and data snooping finds the planted blunders. The expected
// coverage is the normal distribution's (95 % within 1.96 σ), the truth the
// generator's and the normal matrix built here from the measurements, never
// the adjustment's output.

#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <Eigen/LU>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "accuracy.hpp"
#include "temp_folder.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/io/network/network_input.hpp"
#include "geoanchor/io/network/network_output.hpp"
#include "geoanchor/solver/network_adjustment.hpp"
#include "geoanchor/workflow/adjust.hpp"
#include "geoanchor/workflow/network_generator.hpp"

namespace geoanchor::workflow {
namespace {

using testing::TempFolder;
namespace fs = std::filesystem;

// 1.96 σ holds 95 % of a normal variable; over ≈ 3000 components the share
// found has a standard error of 0.4 %, so 93–97 % is five of them.
constexpr double kCoverageSigmas = 1.96;
constexpr double kCoverageLow = 0.93, kCoverageHigh = 0.97;
// σ0 over ≈ 5500 degrees of freedom: its standard error is ≈ 1 %.
constexpr double kSigma0Tolerance = 0.05;
// Data snooping at alpha 0.001 per measurement removes about 0.1 % of
// good measurements; twice that is allowed.
constexpr double kFalseAlarmShare = 0.002;
// Two factorizations of the same matrix agree to rounding.
constexpr double kCovarianceRelative = 1e-9;

void expect_same_network(const geodesy::Network& a, const geodesy::Network& b) {
  ASSERT_EQ(a.stations.size(), b.stations.size());
  ASSERT_EQ(a.measurements.size(), b.measurements.size());
  ASSERT_TRUE(a.frame && b.frame);
  EXPECT_EQ(a.frame->to_string(), b.frame->to_string());
  for (std::size_t i = 0; i < a.stations.size(); ++i) {
    EXPECT_EQ(a.stations[i].id, b.stations[i].id);
    EXPECT_EQ(a.stations[i].position, b.stations[i].position) << a.stations[i].id;  // bit for bit
    EXPECT_EQ(a.stations[i].constraint.text(), b.stations[i].constraint.text()) << a.stations[i].id;
  }
  for (std::size_t k = 0; k < a.measurements.size(); ++k) {
    const auto& x = a.measurements[k];
    const auto& y = b.measurements[k];
    EXPECT_EQ(x.kind, y.kind);
    EXPECT_EQ(x.stations, y.stations);
    EXPECT_EQ(x.value, y.value) << k;
    EXPECT_EQ(x.covariance, y.covariance) << k;
    ASSERT_TRUE(y.frame);
    EXPECT_EQ(x.frame->to_string(), y.frame->to_string());
  }
}

// A network generated and written into `dir` as PREFIX.*.
GeneratedNetwork generated_in(const TempFolder& dir, NetworkGeneratorOptions o, const std::string& prefix) {
  GeneratedNetwork g = generate_network(o);
  const auto paths = write_generated_network(g, dir.path(), prefix, io::Overwrite::refuse);
  EXPECT_EQ(paths.size(), 5u);
  return g;
}

TEST(NetworkGenerator, WrittenFilesReadBackToTheSameNetworkInBothFormats) {
  TempFolder dir;
  NetworkGeneratorOptions o;
  o.stations = 150;
  o.seed = 7;
  const GeneratedNetwork g = generated_in(dir, o, "net");
  expect_same_network(g.network, io::read_network({(dir.path() / "net.stn.xml").string(), (dir.path() / "net.msr.xml").string()}));
  expect_same_network(g.network, io::read_network({(dir.path() / "net.json").string()}));
  // The truth and the blunders as written.
  std::ifstream truth(dir.path() / "net.truth.csv");
  std::string line;
  std::getline(truth, line);
  EXPECT_EQ(line, "station,x_m,y_m,z_m,held");
  std::size_t rows = 0, held = 0;
  while (std::getline(truth, line)) ++rows, held += line.ends_with(",true") ? 1u : 0u;
  EXPECT_EQ(rows, 150u);
  EXPECT_EQ(held, o.held);
  // The same seed, the same network; another seed, another.
  const GeneratedNetwork again = generate_network(o);
  EXPECT_EQ(again.network.measurements[5].value, g.network.measurements[5].value);
  o.seed = 8;
  EXPECT_NE(generate_network(o).network.measurements[5].value, g.network.measurements[5].value);
}

TEST(NetworkGenerator, EachStationHasFourToSixNearestAndHeldStationsSitOnTheTruth) {
  NetworkGeneratorOptions o;
  o.stations = 400;
  const GeneratedNetwork g = generate_network(o);
  std::vector<int> degree(g.network.stations.size(), 0);
  for (const auto& m : g.network.measurements) ++degree[m.stations[0]], ++degree[m.stations[1]];
  for (std::size_t i = 0; i < degree.size(); ++i) EXPECT_GE(degree[i], 4) << g.network.stations[i].id;
  for (std::size_t i = 0; i < g.truth.size(); ++i) {
    const auto& s = g.network.stations[i];
    if (s.constraint.any()) EXPECT_EQ(s.position, g.truth[i]);
    else EXPECT_GT((s.position - g.truth[i]).norm(), 0.0);
  }
  // Each blunder is the planted length.
  for (const auto& b : g.blunders) EXPECT_NEAR(b.offset_m.norm(), o.blunder_m, 1e-12);
}

TEST(NetworkGenerator, AdjustedAsReadItCoversTheTruthAndSnoopingFindsThePlantedBlunders) {
  TempFolder dir;
  NetworkGeneratorOptions o;
  o.stations = 1000;
  o.blunders = 6;
  const GeneratedNetwork g = generated_in(dir, o, "network");
  AdjustRequest request;
  request.inputs = {(dir.path() / "network.stn.xml").string(), (dir.path() / "network.msr.xml").string()};
  request.options.remove_outliers = true;
  const PreparedNetwork prepared = prepare_network(request);
  const solver::AdjustmentResult r = solver::adjust_network(prepared.network, request.options);
  ASSERT_TRUE(r.converged);
  ASSERT_TRUE(r.sigma0);
  EXPECT_NEAR(*r.sigma0, 1.0, kSigma0Tolerance);
  std::set<std::size_t> planted;
  for (const auto& b : g.blunders) planted.insert(b.measurement);
  std::size_t found = 0, false_alarms = 0;
  for (const auto& m : r.measurements) {
    if (!m.outlier) continue;
    if (planted.count(m.index)) ++found;
    else ++false_alarms;
  }
  EXPECT_EQ(found, planted.size());
  EXPECT_LE(static_cast<double>(false_alarms), kFalseAlarmShare * static_cast<double>(r.measurements.size()));
  // Far apart, the blunders go in one snooping step, not one step each.
  EXPECT_LE(r.passes, 3);
  // The errors against the truth, whitened by the adjustment's own
  // normal matrix: with N = Pᵀ L Lᵀ P (built here from the measurements
  // the adjustment kept, in ECEF), z = Lᵀ P e has independent standard
  // normal components when e ~ N(0, N⁻¹). The stations' errors themselves
  // are strongly correlated (three held stations over 1000 km), so the
  // share of them within 1.96 σ varies from one network to the next far
  // more than a count of independent draws would (0.89 to 0.97 over six
  // seeds); the whitened share does not.
  std::vector<Eigen::Index> unknown(r.stations.size(), -1);
  Eigen::Index count = 0;
  for (std::size_t i = 0; i < r.stations.size(); ++i) {
    if (r.stations[i].constraint != "CCC") unknown[i] = count, count += 3;
  }
  std::vector<Eigen::Triplet<double>> entries;
  for (const auto& am : r.measurements) {
    if (!am.used) continue;
    const auto& m = prepared.network.measurements[am.index];
    const Eigen::Matrix3d w = m.covariance.inverse();
    const Eigen::Index ends[2] = {unknown[m.stations[0]], unknown[m.stations[1]]};
    const double sign[2] = {-1.0, 1.0};
    for (int a = 0; a < 2; ++a) {
      for (int b = 0; b < 2; ++b) {
        if (ends[a] < 0 || ends[b] < 0) continue;
        for (int i = 0; i < 3; ++i) {
          for (int j = 0; j < 3; ++j) entries.emplace_back(ends[a] + i, ends[b] + j, sign[a] * sign[b] * w(i, j));
        }
      }
    }
  }
  Eigen::SparseMatrix<double> n(count, count);
  n.setFromTriplets(entries.begin(), entries.end());
  const Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> llt(n);
  ASSERT_EQ(llt.info(), Eigen::Success);
  Eigen::VectorXd e(count);
  for (std::size_t i = 0; i < r.stations.size(); ++i) {
    if (unknown[i] >= 0) e.segment<3>(unknown[i]) = r.stations[i].position - g.truth[i];
  }
  const Eigen::VectorXd z = llt.matrixU() * (llt.permutationP() * e);
  const double inside = static_cast<double>((z.array().abs() <= kCoverageSigmas).count());
  const double coverage = inside / static_cast<double>(count);
  EXPECT_GE(coverage, kCoverageLow);
  EXPECT_LE(coverage, kCoverageHigh);
  // Each station's own covariance is the matching block of N⁻¹: one
  // station's, solved here, against the adjustment's.
  const std::size_t probe = r.stations.size() / 3;
  ASSERT_GE(unknown[probe], 0);
  Eigen::MatrixXd unit = Eigen::MatrixXd::Zero(count, 3);
  unit.block<3, 3>(unknown[probe], 0).setIdentity();
  const Eigen::Matrix3d q = llt.solve(unit).block<3, 3>(unknown[probe], 0);
  EXPECT_LT(testing::max_abs_component(q - r.stations[probe].covariance_m2), kCovarianceRelative * testing::max_abs_component(q));
}

// Issue 17 point 3: the threads share out measurements and sum in one
// order, so one thread and two give the same bits.
void expect_identical(const solver::AdjustmentResult& a, const solver::AdjustmentResult& b) {
  EXPECT_EQ(a.vtpv, b.vtpv);
  EXPECT_EQ(a.passes, b.passes);
  ASSERT_EQ(a.stations.size(), b.stations.size());
  for (std::size_t i = 0; i < a.stations.size(); ++i) {
    EXPECT_EQ(a.stations[i].position, b.stations[i].position) << a.stations[i].id;
    EXPECT_EQ(a.stations[i].covariance_m2, b.stations[i].covariance_m2) << a.stations[i].id;
  }
  ASSERT_EQ(a.measurements.size(), b.measurements.size());
  for (std::size_t k = 0; k < a.measurements.size(); ++k) {
    const auto& x = a.measurements[k];
    const auto& y = b.measurements[k];
    EXPECT_EQ(x.outlier, y.outlier) << k;
    EXPECT_EQ(x.residual, y.residual) << k;
    EXPECT_EQ(x.redundancy, y.redundancy) << k;
    // NaN (no redundancy) compares unequal to itself: compare the bits' meaning.
    for (Eigen::Index c = 0; c < x.w.size(); ++c) {
      EXPECT_TRUE(x.w(c) == y.w(c) || (std::isnan(x.w(c)) && std::isnan(y.w(c)))) << k;
    }
    EXPECT_EQ(x.p_value, y.p_value) << k;
  }
  ASSERT_EQ(a.relative.size(), b.relative.size());
  for (std::size_t k = 0; k < a.relative.size(); ++k) EXPECT_EQ(a.relative[k].sigma_distance_m, b.relative[k].sigma_distance_m);
}

TEST(NetworkGenerator, Issue17_OneThreadAndTwoGiveTheSameBits) {
  NetworkGeneratorOptions o;
  o.stations = 2000;
  o.blunders = 4;
  const GeneratedNetwork g = generate_network(o);
  solver::AdjustOptions one, two;
  one.jobs = 1;
  two.jobs = 2;
  expect_identical(solver::adjust_network(g.network, one), solver::adjust_network(g.network, two));
  // A terrestrial 3-D network with a gross error and a datum defect (GNU
  // Gama's tetrahedron): every other path through the adjustment.
  AdjustRequest request;
  request.inputs = {std::string(GEOANCHOR_FIXTURES_DIR) + "/networks/gama/tst-tetrahedron-1.gkf"};
  const PreparedNetwork prepared = prepare_network(request);
  expect_identical(solver::adjust_network(prepared.network, one), solver::adjust_network(prepared.network, two));
}

// Issue 17 point 5: a snooping pass that removes a few measurements takes
// them out of the last factor and its selected inverse (Woodbury) instead
// of factoring again. Against the same adjustment factored afresh every
// pass: the same measurements removed, and every number within rounding.
TEST(NetworkGenerator, Issue17_SnoopingDowndatesAgreeWithFactoringEveryPass) {
  constexpr double kPosition_m = 1e-9;     // float64 spacing at Earth radius is 9.3e-10 m
  constexpr double kRelative = 1e-9;       // covariances, of each station's largest entry
  constexpr double kStatistic = 1e-9;      // w, redundancy (dimensionless)
  NetworkGeneratorOptions o;
  o.stations = 2000;
  o.blunders = 4;
  o.seed = 6;  // snooping takes 10 measurements, then 1 more: the second pass is a downdate
  const GeneratedNetwork g = generate_network(o);
  solver::AdjustOptions updated, afresh;
  updated.remove_outliers = afresh.remove_outliers = true;
  afresh.snooping_downdates = false;
  const solver::AdjustmentResult a = solver::adjust_network(g.network, updated);
  const solver::AdjustmentResult b = solver::adjust_network(g.network, afresh);
  ASSERT_GE(a.removed_per_pass.size(), 2u);
  EXPECT_GE(a.passes_downdated, 1);
  EXPECT_EQ(b.passes_downdated, 0);
  EXPECT_EQ(a.removed_per_pass, b.removed_per_pass);
  EXPECT_EQ(a.dof, b.dof);
  EXPECT_NEAR(a.vtpv, b.vtpv, kRelative * b.vtpv);
  ASSERT_EQ(a.stations.size(), b.stations.size());
  double position = 0.0, covariance = 0.0;
  for (std::size_t i = 0; i < a.stations.size(); ++i) {
    position = testing::nan_max(position, testing::max_abs_component(a.stations[i].position - b.stations[i].position));
    const double scale = testing::max_abs_component(b.stations[i].covariance_m2);
    if (scale != 0.0) {  // (a held station's is zero; a NaN one is counted and fails)
      covariance = testing::nan_max(covariance, testing::max_abs_component(a.stations[i].covariance_m2 - b.stations[i].covariance_m2) / scale);
    }
  }
  EXPECT_LE(position, kPosition_m);
  EXPECT_LE(covariance, kRelative);
  ASSERT_EQ(a.measurements.size(), b.measurements.size());
  double statistic = 0.0;
  for (std::size_t k = 0; k < a.measurements.size(); ++k) {
    const auto& x = a.measurements[k];
    const auto& y = b.measurements[k];
    ASSERT_EQ(x.outlier, y.outlier) << k;
    for (Eigen::Index c = 0; c < x.w.size(); ++c) {
      if (std::isnan(y.w(c))) {
        EXPECT_TRUE(std::isnan(x.w(c))) << k;
        continue;
      }
      statistic = testing::nan_max(statistic, std::abs(x.w(c) - y.w(c)));
      statistic = testing::nan_max(statistic, std::abs(x.redundancy(c) - y.redundancy(c)));
    }
  }
  EXPECT_LE(statistic, kStatistic);
}

TEST(NetworkGenerator, RefusesWhatItCannotMakeByName) {
  NetworkGeneratorOptions o;
  o.stations = 3;
  EXPECT_THROW(generate_network(o), Error);
  o.stations = 100;
  o.blunders = 50;
  try {
    generate_network(o);
    FAIL() << "50 blunders in 100 stations";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("--blunders 50"), std::string::npos) << e.what();
  }
  o.blunders = 1;
  o.held = 0;
  EXPECT_THROW(generate_network(o), Error);
}

TEST(NetworkWriters, RefuseWhatTheFormatsCannotHoldBeforeWriting) {
  NetworkGeneratorOptions o;
  o.stations = 20;
  o.blunders = 1;
  GeneratedNetwork g = generate_network(o);
  geodesy::NetworkMeasurement d;
  d.kind = geodesy::MeasurementKind::slope_distance;
  d.stations = {0, 1};
  d.value = Eigen::VectorXd::Constant(1, 100.0);
  d.covariance = Eigen::MatrixXd::Constant(1, 1, 1e-6);
  d.source = "survey.csv:4";
  g.network.measurements.push_back(d);
  std::ostringstream out;
  try {
    io::write_dynaml_measurements(g.network, out);
    FAIL() << "a slope distance written";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_NETWORK_WRITE");
    EXPECT_NE(std::string(e.what()).find("survey.csv:4: slope distance"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(out.str().empty());
  g.network.measurements.pop_back();
  g.network.stations[2].constraint.code = {'C', 'C', 'F'};
  EXPECT_THROW(io::write_network_json(g.network, out), Error);
  g.network.stations[2].constraint.code = {'F', 'F', 'F'};
  g.network.frame = geodesy::Frame::parse("ITRF2014@2020.3", "test");
  try {
    io::write_dynaml_stations(g.network, out);
    FAIL() << "an epoch that is no day";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("2020.3"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(out.str().empty());
}

TEST(NetworkGenerator, AnExistingOutputLeavesNoneOfTheOthers) {
  TempFolder dir;
  NetworkGeneratorOptions o;
  o.stations = 50;
  o.blunders = 1;
  const GeneratedNetwork g = generate_network(o);
  std::ofstream(dir.path() / "network.truth.csv") << "mine\n";
  EXPECT_THROW(write_generated_network(g, dir.path(), "network", io::Overwrite::refuse), Error);
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(dir.path())) {
    ++files;
    EXPECT_EQ(e.path().filename(), "network.truth.csv");
  }
  EXPECT_EQ(files, 1u);
}

}  // namespace
}  // namespace geoanchor::workflow
