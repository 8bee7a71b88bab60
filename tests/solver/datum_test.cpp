// The datum judged against the network's own precision (issue 39 point 3
// and 4): well-posed networks of unusual shape, weight and unit are
// accepted and agree with a dense solve and the truth; the defect of a free
// network is named exactly; inner constraints that do not span it are
// refused by name; an inner-constraint covariance is the pseudo-inverse of
// the normal matrix built here independently (Eigen's complete orthogonal
// decomposition); singular stations are named, never an arbitrary one.

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>

#include "geoanchor/base/error.hpp"
#include "geoanchor/solver/network_adjustment.hpp"
#include "datum_rank.hpp"
#include "network_builder.hpp"
#include "test_support.hpp"

namespace geoanchor::solver {
namespace {

constexpr double kTruth_m = 1e-6;                  // noise-free observations back to the truth (iteration stops at 1e-5 m steps, converging quadratically)
constexpr double kSparseVsDense_m = 1e-8;          // two factorizations of one matrix; weak datums lose digits to their condition (1e10)
constexpr double kSparseVsDenseRelative = 1e-7;    // covariances, of each station's largest entry, likewise
constexpr double kPseudoInverseRelative = 1e-9;    // the issue's bound

AdjustOptions quiet(bool dense = false) {
  AdjustOptions o;
  o.dense = dense;
  return o;
}

std::string error_of(const Network& net, const AdjustOptions& o) {
  try {
    (void)adjust_network(net, o);
  } catch (const Error& e) {
    return std::string(e.code()) + ": " + e.what();
  }
  return "no error";
}

// Every station's position and covariance, sparse against dense.
void expect_sparse_equals_dense(const Network& net, const AdjustOptions& o) {
  AdjustOptions dense = o;
  dense.dense = true;
  const AdjustmentResult a = adjust_network(net, o), b = adjust_network(net, dense);
  testing::WorstCase position, covariance;
  for (std::size_t i = 0; i < a.stations.size(); ++i) {
    position.add(testing::max_abs_component(a.stations[i].position - b.stations[i].position), i);
    const double scale = testing::max_abs_component(b.stations[i].covariance_m2);
    covariance.add(scale != 0.0 ? testing::max_abs_component(a.stations[i].covariance_m2 - b.stations[i].covariance_m2) / scale : 0.0, i);
  }
  EXPECT_WORST_WITHIN(position, kSparseVsDense_m);
  EXPECT_WORST_WITHIN(covariance, kSparseVsDenseRelative);
}

// A plane (2-D local) network of stations D0, D1, … at `xy`, no measurement.
Network plane_of(const std::vector<Eigen::Vector2d>& xy, const std::string& name) {
  Network plane;
  plane.space = geodesy::NetworkSpace::local;
  plane.local_dimensions = 2;
  plane.source_name = name;
  for (std::size_t i = 0; i < xy.size(); ++i) {
    NetworkStation st;
    st.id = "D" + std::to_string(i);
    st.position = Eigen::Vector3d(xy[i].x(), xy[i].y(), 0.0);
    plane.stations.push_back(st);
  }
  return plane;
}

// A straight 3-D traverse: 12 stations 250 m apart on one straight line in
// space (azimuth 60°, rising 1°), slope distances, azimuths and zenith
// angles from each station to the next, computed by GeographicLib; the
// first station fixed. Well posed (each leg fixes the next station), and
// the rotation about the line moves no station: no datum is missing.
TEST(NetworkDatum, Issue39_AStraightTraverseWithOneFixedStationIsAdjusted) {
  Site s;
  const GeographicLib::LocalCartesian start(47.45, 8.54, 450.0, grs80());
  const double az = 60.0 * std::numbers::pi / 180.0, el = 1.0 * std::numbers::pi / 180.0;
  for (int k = 0; k < 12; ++k) {
    const double d = 250.0 * k;
    double lat = 0, lon = 0, h = 0;
    start.Reverse(d * std::sin(az) * std::cos(el), d * std::cos(az) * std::cos(el), d * std::sin(el), lat, lon, h);
    double x = 0, y = 0, z = 0;
    grs80().Forward(lat, lon, h, x, y, z);
    s.ecef.emplace_back(x, y, z);
    s.geodetic.push_back({lat, lon, h});
  }
  Network net = network_of(s);
  net.stations[0].constraint.code = {'C', 'C', 'C'};
  for (std::size_t i = 0; i + 1 < s.ecef.size(); ++i) {
    const Sighting g = sighting(s, i, i + 1, 0.0, 0.0);
    const double horizontal = std::hypot(g.east, g.north);
    net.measurements.push_back(scalar(MeasurementKind::slope_distance, {i, i + 1}, std::hypot(horizontal, g.up), 0.002, "slope"));
    net.measurements.push_back(scalar(MeasurementKind::azimuth, {i, i + 1}, std::atan2(g.east, g.north), 1.0 * kArcsec, "azimuth"));
    net.measurements.push_back(scalar(MeasurementKind::zenith_angle, {i, i + 1}, std::atan2(horizontal, g.up), 1.0 * kArcsec, "zenith"));
  }
  // (Its straight line turns the a-priori coordinates 2 m off, as a survey's would be.)
  for (std::size_t i = 1; i < net.stations.size(); ++i) net.stations[i].position += Eigen::Vector3d(1.2, -0.9, 1.5);
  const AdjustmentResult r = adjust_network(net, quiet());
  EXPECT_EQ(r.dof, 0);
  EXPECT_TRUE(r.datum_defect.empty());
  testing::WorstCase truth;
  for (std::size_t i = 0; i < s.ecef.size(); ++i) truth.add((r.stations[i].position - s.ecef[i]).norm(), i);
  EXPECT_WORST_WITHIN(truth, kTruth_m);
  expect_sparse_equals_dense(net, quiet());
}

// A GNSS network whose every station is held with 10 m (DynAdjust's usual
// "free" hold), and with 100 m: the datum is the holds', weak against the
// baselines' millimetres (10⁻⁹ to 10⁻¹¹ of their information) but well
// posed. The translation's σ is the hold's over √n.
TEST(NetworkDatum, Issue39_ANetworkHeldOnlyByWeightedConstraintsIsAdjusted) {
  std::mt19937 rng(10);
  const Site s = make_site(25, rng);
  for (const double sigma_m : {10.0, 100.0}) {
    SCOPED_TRACE(sigma_m);
    Network net = network_of(s);
    for (std::size_t i = 0; i + 1 < s.ecef.size(); ++i) add_baseline(net, s, i, i + 1, &rng);
    for (std::size_t i = 0; i + 5 < s.ecef.size(); ++i) add_baseline(net, s, i, i + 5, &rng);
    for (auto& st : net.stations) st.constraint = {{'C', 'C', 'C'}, {sigma_m, sigma_m, sigma_m}};
    const AdjustmentResult r = adjust_network(net, quiet());
    EXPECT_TRUE(r.datum_defect.empty());
    // σ of the mean position: the holds' σ/√n (the baselines fix the shape).
    const double expected = sigma_m / std::sqrt(static_cast<double>(s.ecef.size()));
    EXPECT_NEAR(std::sqrt(r.stations[12].covariance_local_m2(0, 0)), expected, 0.01 * expected);
    expect_sparse_equals_dense(net, quiet());
  }
}

// A plane network of horizontal distances and direction sets, two stations
// fixed, written in kilometres, in metres and in millimetres (coordinates
// and linear sigmas scaled alike, angles as they are): each accepted, and
// the same network once the units are converted.
TEST(NetworkDatum, Issue39_APlaneNetworkInKilometresOrMillimetresIsTheSameNetwork) {
  constexpr double kRelative = 1e-9;  // of the network's size, and of each covariance's largest entry
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> jitter(-60.0, 60.0);
  std::normal_distribution<double> z;
  std::vector<Eigen::Vector2d> truth;
  for (int i = 0; i < 16; ++i) truth.emplace_back(400.0 * (i % 4) + jitter(rng), 400.0 * (i / 4) + jitter(rng));
  const auto build = [&](double unit) {  // metres per unit
    Network net;
    net.space = geodesy::NetworkSpace::local;
    net.local_dimensions = 2;
    net.source_name = "plane";
    for (std::size_t i = 0; i < truth.size(); ++i) {
      NetworkStation st;
      st.id = "P" + std::to_string(i);
      st.position = Eigen::Vector3d(truth[i].x() + 0.5, truth[i].y() - 0.4, 0.0) / unit;
      net.stations.push_back(st);
    }
    net.stations[0].constraint.code = {'C', 'C', 'F'};
    net.stations[0].position = Eigen::Vector3d(truth[0].x(), truth[0].y(), 0.0) / unit;
    net.stations[15].constraint.code = {'C', 'C', 'F'};
    net.stations[15].position = Eigen::Vector3d(truth[15].x(), truth[15].y(), 0.0) / unit;
    std::mt19937 noise(99);
    for (std::size_t i = 0; i < truth.size(); ++i) {
      const std::size_t set = net.direction_sets.size();
      net.direction_sets.push_back({i, "set"});
      for (std::size_t j = 0; j < truth.size(); ++j) {
        const Eigen::Vector2d d = truth[j] - truth[i];
        if (i == j || d.norm() > 900.0) continue;
        net.measurements.push_back(scalar(MeasurementKind::horizontal_distance, {i, j}, (d.norm() + 0.002 * z(noise)) / unit, 0.002 / unit, "d"));
        auto m = scalar(MeasurementKind::direction, {i, j}, std::atan2(d.y(), d.x()) - 0.2 + 2.0 * kArcsec * z(noise), 2.0 * kArcsec, "r");
        m.set = set;
        net.measurements.push_back(m);
      }
    }
    return net;
  };
  const AdjustmentResult metres = adjust_network(build(1.0), quiet());
  for (const double unit : {1000.0, 0.001}) {
    SCOPED_TRACE(unit);
    const Network net = build(unit);
    const AdjustmentResult r = adjust_network(net, quiet());
    EXPECT_EQ(r.dof, metres.dof);
    EXPECT_NEAR(r.vtpv, metres.vtpv, kRelative * metres.vtpv);
    testing::WorstCase position, covariance;
    for (std::size_t i = 0; i < r.stations.size(); ++i) {
      position.add((unit * r.stations[i].position - metres.stations[i].position).norm() / 1600.0, i);
      const double scale = testing::max_abs_component(metres.stations[i].covariance_m2);
      if (scale != 0.0) {
        covariance.add(testing::max_abs_component(unit * unit * r.stations[i].covariance_m2 - metres.stations[i].covariance_m2) / scale, i);
      }
    }
    EXPECT_WORST_WITHIN(position, kRelative);
    EXPECT_WORST_WITHIN(covariance, kRelative);
    expect_sparse_equals_dense(net, quiet());
  }
}

// A 3-D network of slope distances alone (every pair within 1.2 km, on the
// ellipsoid, instrument and target on the marks): its defect is the three
// translations and the three rotations, named; with inner constraints over
// all stations the covariance is the pseudo-inverse of the normal matrix
// (built here from the distances' unit vectors in ECEF); over two stations
// the rotation about the line through them is left free, and refused.
TEST(NetworkDatum, Issue39_AFreeDistanceNetworkHasSixUndefinedCombinationsAndThePseudoInverse) {
  std::mt19937 rng(6);
  const Site s = make_site(12, rng);
  Network net = network_of(s);
  const double sigma = 0.002;
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < s.ecef.size(); ++i) {
    for (std::size_t j = i + 1; j < s.ecef.size(); ++j) {
      if ((s.ecef[j] - s.ecef[i]).norm() > 1200.0) continue;
      net.measurements.push_back(scalar(MeasurementKind::slope_distance, {i, j}, (s.ecef[j] - s.ecef[i]).norm(), sigma, "d"));
      pairs.emplace_back(i, j);
    }
  }
  for (auto& st : net.stations) st.position += Eigen::Vector3d(0.3, -0.2, 0.4);  // a-priori off by half a metre
  AdjustOptions o = quiet();
  o.free = true;
  const AdjustmentResult r = adjust_network(net, o);
  ASSERT_EQ(r.datum_defect.size(), 6u) << r.datum;
  // Three translations and three rotations, no scale (the distances give it).
  int translations = 0, rotations = 0;
  for (const auto& name : r.datum_defect) {
    translations += name.find("translation") != std::string::npos ? 1 : 0;
    rotations += name.find("rotation") != std::string::npos ? 1 : 0;
    EXPECT_EQ(name.find("scale"), std::string::npos) << name;
  }
  EXPECT_GE(translations, 1);
  EXPECT_GE(rotations, 1);
  // The pseudo-inverse of N = Σ a aᵀ/σ² (a: −u at i, +u at j, u the unit
  // vector from i to j at the adjusted positions), in ECEF.
  const auto n = static_cast<Eigen::Index>(3 * s.ecef.size());
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(n, n);
  for (const auto& [i, j] : pairs) {
    const Eigen::Vector3d u = (r.stations[j].position - r.stations[i].position).normalized();
    Eigen::VectorXd a = Eigen::VectorXd::Zero(n);
    a.segment<3>(static_cast<Eigen::Index>(3 * i)) = -u;
    a.segment<3>(static_cast<Eigen::Index>(3 * j)) = u;
    normal += a * a.transpose() / (sigma * sigma);
  }
  const Eigen::MatrixXd pinv = Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>(normal).pseudoInverse();
  const double scale = testing::max_abs_component(pinv);
  testing::WorstCase agreement;
  for (std::size_t i = 0; i < s.ecef.size(); ++i) {
    const auto at = static_cast<Eigen::Index>(3 * i);
    agreement.add(testing::max_abs_component(r.stations[i].covariance_m2 - pinv.block<3, 3>(at, at)) / scale, i);
  }
  EXPECT_WORST_WITHIN(agreement, kPseudoInverseRelative);
  // The minimum-norm solution over all stations: the corrections sum to no motion of the six.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& st : r.stations) mean += st.position - st.a_priori;
  EXPECT_LT((mean / static_cast<double>(r.stations.size())).norm(), 1e-9);
  // Over two stations: the rotation about the line through them is free.
  o.inner_constraint_stations = {"S0", "S7"};
  const std::string refused = error_of(net, o);
  EXPECT_EQ(refused.rfind("E_INNER_CONSTRAINTS", 0), 0u) << refused;
  EXPECT_NE(refused.find("S0, S7"), std::string::npos) << refused;
  EXPECT_NE(refused.find("rotation about the line through them"), std::string::npos) << refused;
  EXPECT_NE(refused.find("1 of the 6 combinations"), std::string::npos) << refused;
  // One station holds the translations only.
  o.inner_constraint_stations = {"S3"};
  const std::string one = error_of(net, o);
  EXPECT_EQ(one.rfind("E_INNER_CONSTRAINTS", 0), 0u) << one;
  EXPECT_NE(one.find("3 of the 6 combinations"), std::string::npos) << one;
  EXPECT_NE(one.find("one station holds the translations only"), std::string::npos) << one;
}

// The defect of a plane network of directions alone: two translations,
// the rotation and the scale; of a levelling network: the height.
TEST(NetworkDatum, Issue39_TheDefectOfAFreeDirectionOrLevellingNetworkIsNamedExactly) {
  const std::vector<Eigen::Vector2d> xy = {{0, 0}, {500, 40}, {950, -30}, {60, 480}, {520, 530}, {990, 470}, {30, 1010}, {480, 960}};
  Network plane = plane_of(xy, "directions");
  for (std::size_t i = 0; i < xy.size(); ++i) {
    const std::size_t set = plane.direction_sets.size();
    plane.direction_sets.push_back({i, "set"});
    for (std::size_t j = 0; j < xy.size(); ++j) {
      if (i == j) continue;
      const Eigen::Vector2d d = xy[j] - xy[i];
      auto m = scalar(MeasurementKind::direction, {i, j}, std::atan2(d.y(), d.x()), 3.0 * kArcsec, "r");
      m.set = set;
      plane.measurements.push_back(m);
    }
  }
  AdjustOptions o = quiet();
  o.free = true;
  const AdjustmentResult r = adjust_network(plane, o);
  ASSERT_EQ(r.datum_defect.size(), 4u) << r.datum;
  std::string all;
  for (const auto& name : r.datum_defect) all += name + "; ";
  EXPECT_NE(all.find("translation along x"), std::string::npos) << all;
  EXPECT_NE(all.find("translation along y"), std::string::npos) << all;
  EXPECT_NE(all.find("rotation about the vertical"), std::string::npos) << all;
  EXPECT_NE(all.find("scale"), std::string::npos) << all;
  // Without --free: refused, naming the four.
  const std::string refused = error_of(plane, quiet());
  EXPECT_EQ(refused.rfind("E_DATUM_DEFECT", 0), 0u) << refused;
  EXPECT_NE(refused.find("(4 combinations)"), std::string::npos) << refused;

  Network levelling;
  levelling.space = geodesy::NetworkSpace::local;
  levelling.local_dimensions = 1;
  levelling.source_name = "levelling";
  for (int i = 0; i < 5; ++i) {
    NetworkStation st;
    st.id = "L" + std::to_string(i);
    st.position = Eigen::Vector3d(0.0, 0.0, 400.0 + 3.0 * i);
    levelling.stations.push_back(st);
  }
  for (std::size_t i = 0; i < 5; ++i) {
    levelling.measurements.push_back(scalar(MeasurementKind::height_difference, {i, (i + 1) % 5},
                                                   3.0 * static_cast<double>((i + 1) % 5) - 3.0 * static_cast<double>(i), 0.001, "dh"));
  }
  const AdjustmentResult h = adjust_network(levelling, o);
  ASSERT_EQ(h.datum_defect.size(), 1u) << h.datum;
  EXPECT_NE(h.datum_defect[0].find("translation along z"), std::string::npos) << h.datum_defect[0];
}

// Singular stations are named for what leaves them free, never an
// arbitrary one. S14 and S15 each reach the network by two distances and
// each other by one: every station alone is fixed (three distances each),
// but five distances for six coordinates leave one motion of the two
// together free. S16 reaches it by two distances only: it turns alone
// about the line through its two ends.
TEST(NetworkDatum, Issue39_SingularStationsAreTheOnesThatMove) {
  std::mt19937 rng(12);
  const Site s = make_site(17, rng);
  Network net = network_of(s);
  for (std::size_t i = 0; i + 1 < 14; ++i) add_baseline(net, s, i, i + 1, &rng);
  for (std::size_t i = 0; i + 4 < 14; ++i) add_baseline(net, s, i, i + 4, &rng);
  net.stations[0].constraint.code = {'C', 'C', 'C'};
  const auto distance = [&](std::size_t i, std::size_t j) {
    return scalar(MeasurementKind::slope_distance, {i, j}, (s.ecef[j] - s.ecef[i]).norm(), 0.002, "d" + std::to_string(i) + "-" + std::to_string(j));
  };
  Network pair = net;
  for (const auto& [i, j] : std::vector<std::pair<std::size_t, std::size_t>>{{9, 14}, {13, 14}, {10, 15}, {11, 15}, {14, 15}}) {
    pair.measurements.push_back(distance(i, j));
  }
  const std::string together = error_of(pair, quiet());
  EXPECT_EQ(together.rfind("E_NETWORK_SINGULAR", 0), 0u) << together;
  EXPECT_NE(together.find("S14"), std::string::npos) << together;
  EXPECT_NE(together.find("S15"), std::string::npos) << together;
  for (const char* other : {"S1 ", "S2 ", "S3 ", "S5 ", "S9 ", "S10 ", "S11 ", "S12 ", "S13 "}) {
    EXPECT_EQ(together.find(std::string("station ") + other), std::string::npos) << together;
  }
  Network alone = net;
  alone.measurements.push_back(distance(11, 16));
  alone.measurements.push_back(distance(12, 16));
  const std::string turned = error_of(alone, quiet());
  EXPECT_EQ(turned.rfind("E_NETWORK_SINGULAR", 0), 0u) << turned;
  EXPECT_NE(turned.find("station S16"), std::string::npos) << turned;
  EXPECT_NE(turned.find("2 measurements that reach it"), std::string::npos) << turned;
}

// A datum held at one station is not diluted by the number of stations:
// 900 stations joined by baselines of millimetres, held only by one
// station's constraint of 300 m (its information 10⁻¹¹ of a station's own,
// and 10⁻¹⁴ of the network's in all), or by one code GNSS point of 3 m on
// one station. Each is accepted, and the whole network moves with the
// hold: every station's σ is the hold's. Held at 3 km, double precision
// resolves that σ only to a few per cent (the factorization's rounding
// along the translation grows as √n times a station's): accepted, and a
// warning says so; at 6 km it would be rounding, and it is refused.
TEST(NetworkDatum, Issue39_ADatumHeldAtOneStationIsNotDilutedByTheNetworksSize) {
  constexpr double kSigmaRelative = 0.01;  // a station's σ against the hold's (the baselines add millimetres)
  std::mt19937 rng(44);
  const int side = 30;
  const Site s = make_site(side * side, rng);
  Network base = network_of(s);
  for (std::size_t i = 0; i < s.ecef.size(); ++i) {
    if ((i + 1) % side != 0) add_baseline(base, s, i, i + 1, &rng);
    if (i + side < s.ecef.size()) add_baseline(base, s, i, i + side, &rng);
  }
  const std::size_t held = 17;
  const auto warned = [](const AdjustmentResult& r, const std::string& what) {
    return std::any_of(r.warnings.begin(), r.warnings.end(), [&](const std::string& w) { return w.find(what) != std::string::npos; });
  };
  for (const double hold_m : {300.0, 3000.0}) {
    SCOPED_TRACE(hold_m);
    Network net = base;
    net.stations[held].constraint = {{'C', 'C', 'C'}, {hold_m, hold_m, hold_m}};
    const AdjustmentResult r = adjust_network(net, quiet());
    EXPECT_TRUE(r.datum_defect.empty());
    if (hold_m < 1000.0) {
      for (const std::size_t i : {held, std::size_t{450}, s.ecef.size() - 1}) {
        EXPECT_NEAR(std::sqrt(r.stations[i].covariance_local_m2(0, 0)), hold_m, kSigmaRelative * hold_m) << i;
      }
      EXPECT_FALSE(warned(r, "double precision resolves")) << ::testing::PrintToString(r.warnings);
    } else {
      EXPECT_TRUE(warned(r, "held by the weighted constraints alone")) << ::testing::PrintToString(r.warnings);
      EXPECT_TRUE(warned(r, "double precision resolves"));
    }
  }
  // At 6 km the rounding would be the answer: refused, saying so.
  {
    Network net = base;
    net.stations[held].constraint = {{'C', 'C', 'C'}, {6e3, 6e3, 6e3}};
    const std::string refused = error_of(net, quiet());
    EXPECT_EQ(refused.rfind("E_DATUM_DEFECT", 0), 0u) << refused;
    EXPECT_NE(refused.find("not defined to what double precision resolves"), std::string::npos) << refused;
    EXPECT_NE(refused.find("900 stations"), std::string::npos) << refused;
  }
  Network net = base;
  constexpr double kPoint_m = 3.0;
  NetworkMeasurement point;
  point.kind = MeasurementKind::gnss_points;
  point.stations = {held};
  point.value = s.ecef[held];
  point.covariance = Eigen::Matrix3d::Identity() * kPoint_m * kPoint_m;
  point.source = "code point";
  net.measurements.push_back(point);
  const AdjustmentResult r = adjust_network(net, quiet());
  EXPECT_TRUE(r.datum_defect.empty());
  EXPECT_NEAR(std::sqrt(r.stations[450].covariance_local_m2(2, 2)), kPoint_m, kSigmaRelative * kPoint_m);
}

// Two fixed stations 5 cm apart hold every rotation but the one about the
// line through them: their lever is short against the network's
// kilometres, but a fixed component defines any motion that moves it. A
// network of slope distances then lacks exactly that one rotation (named
// alone); add a third fixed station off their line and it is accepted.
TEST(NetworkDatum, Issue39_FixedStationsCentimetresApartHoldAllButTheirLine) {
  std::mt19937 rng(8);
  Site s = make_site(100, rng);
  // Z: 5 cm east of S44, near the middle.
  const std::size_t twin = 44;
  double x = 0, y = 0, z = 0;
  const GeographicLib::LocalCartesian at(s.geodetic[twin][0], s.geodetic[twin][1], s.geodetic[twin][2], grs80());
  double lat = 0, lon = 0, h = 0;
  at.Reverse(0.05, 0.0, 0.0, lat, lon, h);
  grs80().Forward(lat, lon, h, x, y, z);
  s.ecef.emplace_back(x, y, z);
  s.geodetic.push_back({lat, lon, h});
  Network net = network_of(s);
  const std::size_t zed = s.ecef.size() - 1;
  for (std::size_t i = 0; i < s.ecef.size(); ++i) {
    for (std::size_t j = i + 1; j < s.ecef.size(); ++j) {
      if ((i == twin && j == zed) || (s.ecef[j] - s.ecef[i]).norm() > 900.0) continue;
      net.measurements.push_back(scalar(MeasurementKind::slope_distance, {i, j}, (s.ecef[j] - s.ecef[i]).norm(), 0.002, "d"));
    }
  }
  net.stations[twin].constraint.code = {'C', 'C', 'C'};
  net.stations[zed].constraint.code = {'C', 'C', 'C'};
  const std::string refused = error_of(net, quiet());
  EXPECT_EQ(refused.rfind("E_DATUM_DEFECT", 0), 0u) << refused;
  EXPECT_NE(refused.find("rotation"), std::string::npos) << refused;
  EXPECT_EQ(refused.find("combinations)"), std::string::npos) << "one combination only: " << refused;
  net.stations[0].constraint.code = {'C', 'C', 'C'};
  const AdjustmentResult r = adjust_network(net, quiet());
  EXPECT_TRUE(r.datum_defect.empty());
  testing::WorstCase truth;
  for (std::size_t i = 0; i < s.ecef.size(); ++i) truth.add((r.stations[i].position - s.ecef[i]).norm(), i);
  EXPECT_WORST_WITHIN(truth, kTruth_m);
}

// A plane network of distances held only by one station at 1 cm: the
// translations are held, the rotation about it is not, and the
// refusal says that neither the measurements nor the constraints fix it
// (not that they tell it too weakly: the weighted constraint's share of it
// is rounding).
TEST(NetworkDatum, Issue39_AWeightedHoldDoesNotMakeAnUndefinedRotationToldOf) {
  const std::vector<Eigen::Vector2d> xy = {{0, 0}, {500, 40}, {950, -30}, {60, 480}, {520, 530}, {990, 470}};
  Network plane = plane_of(xy, "distances");
  for (std::size_t i = 0; i < xy.size(); ++i) {
    for (std::size_t j = i + 1; j < xy.size(); ++j) {
      plane.measurements.push_back(scalar(MeasurementKind::horizontal_distance, {i, j}, (xy[j] - xy[i]).norm(), 0.002, "d"));
    }
  }
  plane.stations[2].constraint = {{'C', 'C', 'F'}, {0.01, 0.01, 0.0}};
  const std::string refused = error_of(plane, quiet());
  EXPECT_EQ(refused.rfind("E_DATUM_DEFECT", 0), 0u) << refused;
  // One combination: the rotation about the held station (about the
  // centroid, with the translations that keep D2 in place).
  EXPECT_NE(refused.find("neither the measurements nor the constraints fix the "), std::string::npos) << refused;
  EXPECT_NE(refused.find("rotation about the vertical"), std::string::npos) << refused;
  EXPECT_EQ(refused.find("combinations)"), std::string::npos) << refused;
  EXPECT_EQ(refused.find("double precision"), std::string::npos) << refused;
}

// The R factor of stacked rows keeps what a sum of squares loses: 20 000
// rows whose third column is the sum of the first two (rounded) have a
// smallest singular value at rounding's level, 10⁻¹⁶ of the largest, which
// the eigenvalues of AᵀA cannot show below about 10⁻⁸ (their square root).
// RᵀR is AᵀA.
TEST(NetworkDatum, Issue39_TheRowsRFactorResolvesWhatASumOfSquaresCannot) {
  constexpr double kGramRelative = 1e-13;
  constexpr double kNullRelative = 1e-14;
  std::mt19937 rng(2);
  std::normal_distribution<double> z;
  Eigen::MatrixXd a(20000, 3);
  for (Eigen::Index r = 0; r < a.rows(); ++r) {
    a(r, 0) = z(rng);
    a(r, 1) = z(rng);
    a(r, 2) = a(r, 0) + a(r, 1);
  }
  RowsR rows(3);
  for (Eigen::Index at = 0; at < a.rows(); at += 777) rows.add(a.middleRows(at, std::min<Eigen::Index>(777, a.rows() - at)));
  const Eigen::MatrixXd r = rows.r();
  const Eigen::MatrixXd gram = a.transpose() * a;
  EXPECT_LT(testing::max_abs_component(Eigen::MatrixXd(r.transpose() * r - gram)) / testing::max_abs_component(gram), kGramRelative);
  const Eigen::Vector3d sv = Eigen::JacobiSVD<Eigen::Matrix3d>(Eigen::Matrix3d(r)).singularValues();
  EXPECT_LT(sv.z() / sv.x(), kNullRelative);
}


// Every station held and nothing else estimated: refused by name (an empty
// factor ran out of memory, E_INTERNAL std::bad_alloc, before).
TEST(NetworkDatum, Issue42_ANetworkWithNothingToEstimateIsRefusedByName) {
  std::mt19937 rng(3);
  const Site s = make_site(3, rng);
  Network net = network_of(s);
  for (auto& st : net.stations) st.constraint.code = {'C', 'C', 'C'};
  add_baseline(net, s, 0, 1, nullptr);
  add_baseline(net, s, 1, 2, nullptr);
  try {
    (void)adjust_network(net, AdjustOptions{});
    ADD_FAILURE() << "adjusted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_NETWORK_NOTHING_TO_ESTIMATE") << e.what();
    EXPECT_NE(std::string(e.what()).find("free a station"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace geoanchor::solver
