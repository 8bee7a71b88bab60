// Relative precision between pairs of stations (adjust --relative) against
// a reference built in the test: the joint covariance of the two stations
// from AdjustOptions::joint_covariance (one solve of the factor per
// coordinate, or the dense inverse with AdjustOptions::dense: never the
// selected inverse or the elimination-tree paths the code under test
// uses), rotated into the first station's local horizon by GeographicLib,
// its horizontal ellipse by Eigen's eigen-decomposition. The pairs of
// radius:R against a brute-force search over every pair.

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <GeographicLib/Geocentric.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "network_builder.hpp"
#include "test_support.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/solver/network_adjustment.hpp"

namespace geoanchor::solver {
namespace {

constexpr double kAgreementRelative = 1e-9;  // the bound: relative to the pair's 1σ semi-major axis
// √χ²₂(0.95) = √(−2 ln 0.05) and the normal quantile at 0.975 (tables:
// Abramowitz & Stegun 26.2.23 gives z(0.975) = 1.959963985).
constexpr double kEllipse95 = 2.4477468306808166;
constexpr double kInterval95 = 1.959963984540054;

// East/north/up rows at an ECEF position, from GeographicLib.
Eigen::Matrix3d enu_from_ecef(const Eigen::Vector3d& x) {
  double lat = 0, lon = 0, h = 0;
  std::vector<double> m(9);
  grs80().Reverse(x.x(), x.y(), x.z(), lat, lon, h, m);
  Eigen::Matrix3d local_to_geocentric;
  local_to_geocentric << m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8];
  return local_to_geocentric.transpose();
}

// The reference for one pair from the joint covariance of the stations.
struct Reference {
  double a = 0, b = 0, up = 0, sigma_distance = 0, horizontal_distance = 0;
};
Reference reference(const AdjustmentResult& joint, std::size_t s1, std::size_t s2) {
  const auto at = [&](std::size_t s) {
    const auto it = std::find(joint.covariance_stations.begin(), joint.covariance_stations.end(), s);
    return static_cast<Eigen::Index>(3 * (it - joint.covariance_stations.begin()));
  };
  const Eigen::MatrixXd& c = joint.station_covariance_m2;
  const Eigen::Index i = at(s1), j = at(s2);
  const Eigen::Matrix3d diff = c.block<3, 3>(i, i) + c.block<3, 3>(j, j) - c.block<3, 3>(i, j) - c.block<3, 3>(j, i);
  const Eigen::Vector3d x1 = joint.stations[s1].position, x2 = joint.stations[s2].position;
  const Eigen::Matrix3d r = enu_from_ecef(x1);
  const Eigen::Matrix3d local = r * diff * r.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(local.topLeftCorner<2, 2>());
  Reference ref;
  // Rounding's negative zero clamped; a NaN stays NaN (std::max would drop it).
  const auto root = [](double v) { return std::sqrt(v < 0.0 ? 0.0 : v); };
  ref.a = root(eig.eigenvalues()(1));
  ref.b = root(eig.eigenvalues()(0));
  ref.up = std::sqrt(local(2, 2));
  const Eigen::Vector3d u = (x2 - x1).normalized();
  ref.sigma_distance = std::sqrt(u.dot(diff * u));
  ref.horizontal_distance = (r * (x2 - x1)).head<2>().norm();
  return ref;
}

// Every pair of `r.relative` against the reference, relative to the
// pair's 1σ semi-major axis; and the confidence scales.
testing::WorstCase compare(const AdjustmentResult& r, const AdjustmentResult& joint) {
  testing::WorstCase worst;
  for (std::size_t k = 0; k < r.relative.size(); ++k) {
    const RelativePrecision& rp = r.relative[k];
    const Reference ref = reference(joint, rp.from, rp.to);
    const double scale = ref.a;
    worst.add(std::abs(rp.ellipse.semi_major_m - ref.a) / scale, k);
    worst.add(std::abs(rp.ellipse.semi_minor_m - ref.b) / scale, k);
    worst.add(std::abs(rp.sigma_up_m - ref.up) / scale, k);
    worst.add(std::abs(rp.sigma_distance_m - ref.sigma_distance) / scale, k);
    worst.add(std::abs(rp.ellipse_confidence.semi_major_m - kEllipse95 * ref.a) / scale, k);
    worst.add(std::abs(rp.up_confidence_m - kInterval95 * ref.up) / scale, k);
  }
  return worst;
}

// A GNSS network on a grid: baselines to the east and north neighbours
// (with noise), station 0 held unless `free`.
Network grid_network(int n, std::uint32_t seed, bool free, Site* site) {
  std::mt19937 rng(seed);
  *site = make_site(n, rng);
  Network net = network_of(*site);
  const auto side = static_cast<std::size_t>(std::ceil(std::sqrt(n)));
  for (std::size_t i = 0; i < site->ecef.size(); ++i) {
    if ((i + 1) % side != 0 && i + 1 < site->ecef.size()) add_baseline(net, *site, i, i + 1, &rng);
    if (i + side < site->ecef.size()) add_baseline(net, *site, i, i + side, &rng);
  }
  if (!free) net.stations[0].constraint.code = {'C', 'C', 'C'};
  return net;
}

AdjustOptions relative_options(RelativePairs pairs, double radius_m = 0.0) {
  AdjustOptions o;
  o.data_snooping = false;
  o.relative.pairs = pairs;
  o.relative.radius_m = radius_m;
  return o;
}

// connected and all on a mixed network (baselines, distances, directions,
// angles, heights), against the dense inverse.
TEST(RelativePrecision, ConnectedAndAllPairsOfAMixedNetworkEqualTheDenseInverse) {
  std::mt19937 rng(11);
  const Site s = make_site(25, rng);
  Network net = mixed_network(s, &rng);
  net.stations[0].constraint.code = {'C', 'C', 'C'};
  AdjustOptions dense = relative_options(RelativePairs::connected);
  dense.dense = true;
  dense.joint_covariance = true;
  const AdjustmentResult joint = adjust_network(net, dense);
  for (const RelativePairs pairs : {RelativePairs::connected, RelativePairs::all}) {
    const AdjustmentResult r = adjust_network(net, relative_options(pairs));
    if (pairs == RelativePairs::all) {
      EXPECT_EQ(r.relative.size(), 25u * 24u / 2u);
    }
    EXPECT_GT(r.relative.size(), 0u);
    EXPECT_WORST_WITHIN(compare(r, joint), kAgreementRelative);
  }
}

// radius:R on a held network of 2000 stations (the size) and a
// free one (S-transformed) of 700 (the reference, a dense 3n × 3n joint
// covariance, costs O(n³): 40 s of CPU at 2000), against the joint
// covariance by solves; the pairs against a brute-force search.
void check_radius(bool free) {
  const int kStations = free ? 700 : 2000;
  constexpr double kRadius_m = 1000.0;  // 2.5 grid spacings: most pairs share no baseline
  Site s;
  const Network net = grid_network(kStations, free ? 5 : 3, free, &s);
  AdjustOptions o = relative_options(RelativePairs::radius, kRadius_m);
  o.free = free;
  o.joint_covariance = true;
  const AdjustmentResult r = adjust_network(net, o);
  // The pairs: every pair within the radius in the first station's horizon, by brute force.
  std::set<std::pair<std::size_t, std::size_t>> expected, got;
  for (std::size_t a = 0; a < r.stations.size(); ++a) {
    const Eigen::Matrix3d enu = enu_from_ecef(r.stations[a].position);
    for (std::size_t b = a + 1; b < r.stations.size(); ++b) {
      if ((enu * (r.stations[b].position - r.stations[a].position)).head<2>().norm() <= kRadius_m) expected.insert({a, b});
    }
  }
  for (const auto& rp : r.relative) got.insert({rp.from, rp.to});
  EXPECT_EQ(got, expected);
  EXPECT_GT(got.size(), 5u * static_cast<std::size_t>(kStations));  // about 20 neighbours a station
  EXPECT_WORST_WITHIN(compare(r, r), kAgreementRelative);
}

TEST(RelativePrecision, RadiusPairsOf2000StationsEqualTheJointCovariance) { check_radius(false); }
TEST(RelativePrecision, RadiusPairsOfAFreeNetworkOf700StationsEqualTheJointCovariance) { check_radius(true); }

TEST(RelativePrecision, ListedPairsAreTakenEachOnceAndAllPastItsLimitIsRefusedWithTheCount) {
  Site s;
  const Network net = grid_network(36, 9, false, &s);
  AdjustOptions o = relative_options(RelativePairs::listed);
  o.relative.listed = {{5, 30}, {30, 5}, {0, 35}};
  o.joint_covariance = true;
  const AdjustmentResult r = adjust_network(net, o);
  ASSERT_EQ(r.relative.size(), 2u);
  EXPECT_EQ(r.relative[0].from, 0u);
  EXPECT_EQ(r.relative[0].to, 35u);
  EXPECT_EQ(r.relative[1].from, 5u);
  EXPECT_EQ(r.relative[1].to, 30u);
  EXPECT_WORST_WITHIN(compare(r, r), kAgreementRelative);
  // all: 1500 stations make 1 124 250 pairs, past kMaxAllRelativePairs.
  const Network big = grid_network(1500, 9, false, &s);
  try {
    (void)adjust_network(big, relative_options(RelativePairs::all));
    ADD_FAILURE() << "all pairs of 1500 stations were computed";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_OPTION");
    EXPECT_NE(std::string(e.what()).find("1124250 pairs"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("radius:"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace geoanchor::solver
