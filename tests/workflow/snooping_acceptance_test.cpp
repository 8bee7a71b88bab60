// Issue 39's acceptance for data snooping, on networks whose blunders are
// known because they were planted: generated GNSS networks of 10³ and 10⁴
// stations with one baseline wrong by 0.1 m, 1 m, 100 m or 1 km, and a
// mixed GNSS and terrestrial network with one zenith angle wrong by 1°.
// With --remove-outliers the planted measurement is removed first and the
// good ones removed stay within the false-alarm rate (the binomial 99 %
// bound of α·n); by default the planted measurement is flagged with
// snooping rank 1 and nothing is removed; the same measurements shuffled
// give the same outputs, byte for byte.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "geoanchor/solver/network_adjustment.hpp"
#include "geoanchor/workflow/adjust.hpp"
#include "geoanchor/workflow/network_generator.hpp"
#include "network_builder.hpp"
#include "test_support.hpp"

namespace geoanchor::workflow {
namespace {

constexpr double kAlphaPoint = 0.001;  // the default of adjust --alpha

// The smallest k with P(Bin(n, p) <= k) >= 0.99: the good measurements a
// test at level p fails by chance, at most, 99 times in 100.
std::size_t binomial_99(std::size_t n, double p) {
  double cumulative = 0.0;
  for (std::size_t k = 0; k <= n; ++k) {
    const double log_pmf = std::lgamma(static_cast<double>(n) + 1.0) - std::lgamma(static_cast<double>(k) + 1.0) -
                           std::lgamma(static_cast<double>(n - k) + 1.0) + static_cast<double>(k) * std::log(p) +
                           static_cast<double>(n - k) * std::log1p(-p);
    cumulative += std::exp(log_pmf);
    if (cumulative >= 0.99) return k;
  }
  return n;
}

solver::AdjustOptions options(bool remove) {
  solver::AdjustOptions o;
  o.alpha_point = kAlphaPoint;
  o.remove_outliers = remove;
  return o;
}

// What the planted measurement became, and what the good ones did.
struct Verdict {
  std::size_t planted_rank = 0;
  solver::TestStatus planted_status = solver::TestStatus::used;
  std::size_t first_removed = static_cast<std::size_t>(-1);  // index into the network's measurements
  std::size_t good_removed = 0, good_flagged = 0, removed = 0;
};

Verdict verdict_of(const solver::AdjustmentResult& r, std::size_t planted) {
  Verdict v;
  for (const auto& am : r.measurements) {
    const auto status = am.status(r.alpha_point);
    if (am.snooping_rank == 1 && am.outlier) v.first_removed = am.index;
    if (am.index == planted) {
      v.planted_rank = am.snooping_rank;
      v.planted_status = status;
      continue;
    }
    v.good_removed += am.outlier ? 1u : 0u;
    v.good_flagged += status == solver::TestStatus::flagged ? 1u : 0u;
  }
  for (const auto& am : r.measurements) v.removed += am.outlier ? 1u : 0u;
  return v;
}

void expect_planted_found(const geodesy::Network& net, std::size_t planted, const std::string& what) {
  SCOPED_TRACE(what);
  const std::size_t n = net.measurements.size();
  const std::size_t bound = binomial_99(n, kAlphaPoint);
  // --remove-outliers: the planted measurement first, the good ones within chance.
  const solver::AdjustmentResult removed = solver::adjust_network(net, options(true));
  const Verdict a = verdict_of(removed, planted);
  EXPECT_EQ(a.first_removed, planted);
  EXPECT_EQ(a.planted_status, solver::TestStatus::removed);
  EXPECT_EQ(a.planted_rank, 1u);
  EXPECT_LE(a.good_removed, bound) << "of " << n << " measurements";
  ::testing::Test::RecordProperty(what + " good removed", std::to_string(a.good_removed) + " (bound " + std::to_string(bound) + ")");
  // The default: flagged with rank 1, nothing removed.
  const solver::AdjustmentResult flagged = solver::adjust_network(net, options(false));
  const Verdict b = verdict_of(flagged, planted);
  EXPECT_EQ(b.planted_status, solver::TestStatus::flagged);
  EXPECT_EQ(b.planted_rank, 1u);
  EXPECT_EQ(b.removed, 0u);
  EXPECT_TRUE(flagged.global_test.failed_high());
  const std::vector<std::size_t> first = solver::failing_measurements(flagged);
  ASSERT_FALSE(first.empty());
  EXPECT_EQ(flagged.measurements[first.front()].index, planted) << "named first";
}

TEST(SnoopingAcceptance, Issue39_OneBlunderOfAnySizeIsRemovedFirstAndFlaggedByDefault) {
  for (const double blunder_m : {0.1, 1.0, 100.0, 1000.0}) {
    NetworkGeneratorOptions o;
    o.stations = 1000;
    o.seed = 39;
    o.blunders = 1;
    o.blunder_m = blunder_m;
    const GeneratedNetwork g = generate_network(o);
    expect_planted_found(g.network, g.blunders.front().measurement, "10^3 stations, " + std::to_string(blunder_m) + " m");
  }
}

TEST(SnoopingAcceptance, Issue39_InTenThousandStationsAGrossBlunderGoesFirstAndContaminatesNothingElse) {
  for (const double blunder_m : {1.0, 1000.0}) {
    NetworkGeneratorOptions o;
    o.stations = 10000;
    o.seed = 3;
    o.blunders = 1;
    o.blunder_m = blunder_m;
    const GeneratedNetwork g = generate_network(o);
    expect_planted_found(g.network, g.blunders.front().measurement, "10^4 stations, " + std::to_string(blunder_m) + " m");
  }
}

// The measurements CSV's rows, sorted (the file lists them in the input's order).
std::string sorted_rows(const std::string& csv) {
  std::istringstream in(csv);
  std::vector<std::string> rows;
  std::string line;
  while (std::getline(in, line)) rows.push_back(line);
  std::sort(rows.begin(), rows.end());
  std::string out;
  for (const auto& r : rows) out += r + "\n";
  return out;
}

// The same network with its measurements in another order: the same
// stations CSV and the same measurements CSV rows, byte for byte, with and
// without --remove-outliers.
void expect_shuffle_invariant(const geodesy::Network& net, std::mt19937& rng, const std::string& what) {
  SCOPED_TRACE(what);
  geodesy::Network shuffled = net;
  std::shuffle(shuffled.measurements.begin(), shuffled.measurements.end(), rng);
  for (const bool remove : {false, true}) {
    SCOPED_TRACE(remove ? "--remove-outliers" : "default");
    const solver::AdjustOptions o = options(remove);
    const solver::AdjustmentResult a = solver::adjust_network(net, o), b = solver::adjust_network(shuffled, o);
    EXPECT_TRUE(stations_csv(net, a, o) == stations_csv(shuffled, b, o));
    EXPECT_TRUE(sorted_rows(measurements_csv(net, a, 1)) == sorted_rows(measurements_csv(shuffled, b, 1)));
  }
}

TEST(SnoopingAcceptance, Issue39_ShuffledMeasurementsGiveTheSameOutputsByteForByte) {
  NetworkGeneratorOptions o;
  o.stations = 1000;
  o.seed = 5;
  o.blunders = 1;
  o.blunder_m = 1.0;
  const GeneratedNetwork g = generate_network(o);
  std::mt19937 rng(11);
  expect_shuffle_invariant(g.network, rng, "generated GNSS network");
}

// A mixed network (GNSS baselines, direction sets, slope and horizontal
// distances, zenith and vertical angles, azimuths, angles, heights, arcs;
// tests/support/network_builder.hpp) with noise, one zenith angle 1° off:
// it goes first, the good ones within chance, flagged by default; shuffled,
// the same outputs (direction sets included).
TEST(SnoopingAcceptance, Issue39_AOneDegreeZenithAngleBlunderInAMixedNetworkGoesFirst) {
  std::mt19937 rng(391);
  const solver::Site s = solver::make_site(36, rng);
  geodesy::Network net = solver::mixed_network(s, &rng);
  net.stations[0].constraint.code = {'C', 'C', 'C'};
  net.frame = geodesy::Frame::parse("ITRF2014@2020.0", "test");
  std::size_t planted = net.measurements.size();
  for (std::size_t k = 0; k < net.measurements.size(); ++k) {
    if (net.measurements[k].kind == geodesy::MeasurementKind::zenith_angle && net.measurements[k].stations[0] == 14) {
      planted = k;
      break;
    }
  }
  ASSERT_LT(planted, net.measurements.size());
  net.measurements[planted].value(0) += std::numbers::pi / 180.0;
  expect_planted_found(net, planted, "mixed network, 1° zenith angle");
  expect_shuffle_invariant(net, rng, "mixed network, 1° zenith angle");
}

}  // namespace
}  // namespace geoanchor::workflow
