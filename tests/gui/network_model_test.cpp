// The network view's model driven without a window (issue 14 point 10):
// leaving a station or a measurement out re-adjusts, and the degrees of
// freedom change by what the left-out measurements and unknowns count; the
// plan, the lines and the worker-thread path agree with a direct adjustment.
// The network is the bundled airport network (fixtures/airport_network),
// whose layout the generator states (make_airport_network.py).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <tuple>
#include <vector>

#include "geoanchor/gui/network_model.hpp"
#include "geoanchor/workflow/adjust.hpp"
#include "test_support.hpp"

namespace geoanchor::gui {
namespace {

using geodesy::MeasurementKind;

geodesy::Network airport_network() {
  workflow::AdjustRequest request;
  request.inputs = {std::string(GEOANCHOR_FIXTURES_DIR) + "/airport_network/lszh_network.json"};
  return workflow::prepare_network(request).network;
}

solver::AdjustOptions no_snooping() {
  solver::AdjustOptions o;
  o.data_snooping = false;
  return o;
}

std::size_t rows_of(const geodesy::NetworkMeasurement& m) { return static_cast<std::size_t>(m.value.size()); }

// A local 3-D network of one station P at (10, 20, 5) m measured twice as a
// GNSS point with covariance `cov`, the second value `shift_x_m` further
// along x; axes x, y as given.
geodesy::Network point_measured_twice(char x, char y, const Eigen::Matrix3d& cov, double shift_x_m = 0.0) {
  geodesy::Network net;
  net.space = geodesy::NetworkSpace::local;
  net.local_dimensions = 3;
  net.axes.x = x;
  net.axes.y = y;
  geodesy::NetworkStation p;
  p.id = "P";
  p.position = Eigen::Vector3d(10.0, 20.0, 5.0);
  net.stations.push_back(p);
  for (int k = 0; k < 2; ++k) {
    geodesy::NetworkMeasurement m;
    m.kind = MeasurementKind::gnss_points;
    m.stations = {0};
    m.value = Eigen::Vector3d(10.0 + (k == 0 ? 0.0 : shift_x_m), 20.0, 5.0);
    m.covariance = cov;
    m.source = "test";
    net.measurements.push_back(m);
  }
  return net;
}

TEST(NetworkModel, LinesAndPlanAreTheNetworksAndTheAdjustmentsOwn) {
  const geodesy::Network net = airport_network();
  NetworkModel model(net, no_snooping());
  ASSERT_TRUE(model.result()) << model.error();
  const solver::AdjustmentResult direct = solver::adjust_network(net, no_snooping());
  EXPECT_EQ(model.result()->dof, direct.dof);
  EXPECT_DOUBLE_EQ(model.result()->vtpv, direct.vtpv);
  // The generator's layout: 16 baselines, 24 slope distances, 24 zenith
  // angles and 24 directions are lines; the reference stations' cluster is none.
  const auto lines = model.lines();
  EXPECT_EQ(lines.size(), 16u + 24u + 24u + 24u);
  for (const auto& l : lines) {
    EXPECT_TRUE(l.used);
    EXPECT_TRUE(std::isfinite(l.w_max));
  }
  // The plan: P02 − P01 as the generator placed them (ENU at the aerodrome
  // reference point: 246 m east, 19 m south); the plan's east and north are
  // at the network's centroid a few kilometres away, whose tangent plane
  // turns the 250 m difference by less than 0.1 m.
  constexpr double kTangentPlanesM = 0.1;
  const auto stations = model.stations();
  const auto at = [&](const std::string& id) {
    return std::find_if(stations.begin(), stations.end(), [&](const auto& r) { return r.id == id; })->plan_m;
  };
  const Eigen::Vector2d d = at("P02") - at("P01");
  EXPECT_WORST_WITHIN((d - Eigen::Vector2d(246.0, -19.0)).norm(), kTangentPlanesM);
  for (const auto& s : stations) {
    EXPECT_TRUE(s.used) << s.id;
    EXPECT_GT(s.ellipse.semi_major_m, 0.0) << s.id;
  }
}

TEST(NetworkModel, LeavingOutReadjustsWithTheDegreesOfFreedomItCounts) {
  const geodesy::Network net = airport_network();
  NetworkModel model(net, no_snooping());
  ASSERT_TRUE(model.result()) << model.error();
  const int dof0 = model.result()->dof;
  // One slope distance: one row less.
  std::size_t distance = 0;
  while (net.measurements[distance].kind != MeasurementKind::slope_distance) ++distance;
  const unsigned before = model.generation();
  model.set_measurement_left_out(distance, true);
  ASSERT_TRUE(model.result()) << model.error();
  EXPECT_GT(model.generation(), before);
  EXPECT_EQ(model.result()->dof, dof0 - 1);
  EXPECT_EQ(model.measurements_left_out(), std::vector<std::size_t>{distance});
  model.set_measurement_left_out(distance, false);
  EXPECT_EQ(model.result()->dof, dof0);

  // T1, the traverse's centre: every measurement naming it goes (its rows),
  // and so do its three coordinates and its direction set's orientation.
  const auto t1 = *net.find("T1");
  std::size_t rows = 0;
  for (const auto& m : net.measurements) {
    if (std::find(m.stations.begin(), m.stations.end(), t1) != m.stations.end()) rows += rows_of(m);
  }
  model.set_station_left_out("T1", true);
  ASSERT_TRUE(model.result()) << model.error();
  EXPECT_EQ(model.result()->dof, dof0 - static_cast<int>(rows) + 3 + 1);
  const auto stations = model.stations();
  const auto t1_row = std::find_if(stations.begin(), stations.end(), [](const auto& r) { return r.id == "T1"; });
  EXPECT_TRUE(t1_row->left_out);
  EXPECT_FALSE(t1_row->used);
  for (const auto& l : model.lines()) {
    if (l.from == t1 || l.to == t1) {
      EXPECT_TRUE(l.left_out && !l.used);
    }
  }

  // REFA: the point cluster of both reference stations goes with it, and
  // with it the network's only datum: refused, saying so.
  model.set_station_left_out("REFA", true);
  EXPECT_FALSE(model.result());
  EXPECT_NE(model.error().find("E_DATUM_DEFECT"), std::string::npos) << model.error();
  model.set_station_left_out("REFA", false);
  model.set_station_left_out("T1", false);
  ASSERT_TRUE(model.result()) << model.error();
  EXPECT_EQ(model.result()->dof, dof0);
}

TEST(NetworkModel, TheWorkerThreadGivesTheSameAdjustment) {
  const geodesy::Network net = airport_network();
  NetworkModel direct(net, no_snooping(), 1'000'000);
  NetworkModel worker(net, no_snooping(), 0);  // every network on the worker
  worker.set_station_left_out("P05", true);
  worker.set_station_left_out("P05", false);  // changes while one runs: the last choice wins
  worker.wait();
  ASSERT_TRUE(worker.result()) << worker.error();
  EXPECT_FALSE(worker.busy());
  EXPECT_EQ(worker.result()->dof, direct.result()->dof);
  EXPECT_DOUBLE_EQ(worker.result()->vtpv, direct.result()->vtpv);
}

// A local network's x, y go onto the plan by its axis convention: with x
// north and y east (GNU Gama's default), a station 100 m along +x is 100 m
// north; with x east and y south, 100 m along +y is 100 m south.
TEST(NetworkModel, ALocalNetworksAxesTurnItsPlanToEastAndNorth) {
  constexpr double kExact_m = 1e-12;
  const auto plan_of = [](char x, char y) {
    geodesy::Network net;
    net.space = geodesy::NetworkSpace::local;
    net.local_dimensions = 2;
    net.axes.x = x;
    net.axes.y = y;
    for (const auto& [id, px, py] : {std::tuple{"A", 0.0, 0.0}, std::tuple{"B", 100.0, 0.0}, std::tuple{"C", 0.0, 100.0}}) {
      geodesy::NetworkStation st;
      st.id = id;
      st.position = Eigen::Vector3d(px, py, 0.0);
      net.stations.push_back(st);
    }
    NetworkModel model(net, solver::AdjustOptions{});  // nothing to adjust: the a-priori plan
    EXPECT_FALSE(model.result());
    EXPECT_TRUE(model.error().starts_with("E_NETWORK_EMPTY: ")) << model.error();
    const auto rows = model.stations();
    return std::pair{Eigen::Vector2d(rows[1].plan_m - rows[0].plan_m), Eigen::Vector2d(rows[2].plan_m - rows[0].plan_m)};
  };
  const auto [ne_b, ne_c] = plan_of('n', 'e');
  EXPECT_LE((ne_b - Eigen::Vector2d(0.0, 100.0)).norm(), kExact_m);
  EXPECT_LE((ne_c - Eigen::Vector2d(100.0, 0.0)).norm(), kExact_m);
  const auto [es_b, es_c] = plan_of('e', 's');
  EXPECT_LE((es_b - Eigen::Vector2d(100.0, 0.0)).norm(), kExact_m);
  EXPECT_LE((es_c - Eigen::Vector2d(0.0, -100.0)).norm(), kExact_m);
}

// The solver gives a local ellipse's azimuth from +x towards +y; the plan
// is east, north, so the model turns the major axis with the positions. A
// point measured twice with a covariance whose major axis (σ 20 mm, minor
// 1 mm) points 30° from +x towards +y: on the plan, clockwise from north,
// that axis is at 30° for axes ne (x north, y east), 60° for en, 120° for
// es (x east, y south: 0.866 E − 0.5 N), 150° for nw (0.866 N − 0.5 E) and
// 30° for sw (−0.866 N − 0.5 E, an axis taken modulo 180°).
TEST(NetworkModel, ALocalNetworksEllipsesTurnWithItsAxes) {
  constexpr double kAzimuth_rad = 1e-9;
  constexpr double kPi = 3.14159265358979323846;
  constexpr double kDeg = kPi / 180.0;
  const auto ellipse_of = [&](char x, char y) {
    const double t = 30.0 * kDeg;
    Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
    r.topLeftCorner<2, 2>() << std::cos(t), -std::sin(t), std::sin(t), std::cos(t);
    NetworkModel model(point_measured_twice(x, y, r * Eigen::Vector3d(4e-4, 1e-6, 1e-6).asDiagonal() * r.transpose()), no_snooping());
    EXPECT_TRUE(model.result()) << model.error();
    return model.stations().at(0).ellipse;
  };
  // Azimuths of an axis are taken modulo 180°.
  const auto axis_gap = [&](double a, double b) {
    const double d = std::fmod(std::abs(a - b), kPi);
    return std::min(d, kPi - d);
  };
  const auto ne = ellipse_of('n', 'e');
  EXPECT_NEAR(ne.semi_major_m, 0.02 / std::sqrt(2.0), 1e-9);
  for (const auto& [x, y, expected_deg] : {std::tuple{'n', 'e', 30.0}, std::tuple{'e', 'n', 60.0}, std::tuple{'e', 's', 120.0},
                                            std::tuple{'n', 'w', 150.0}, std::tuple{'s', 'w', 30.0}}) {
    const auto e = ellipse_of(x, y);
    EXPECT_LE(axis_gap(e.azimuth_rad, expected_deg * kDeg), kAzimuth_rad) << x << y << ": " << e.azimuth_rad / kDeg << "°";
  }
}

// The class a measurement is shown in follows the solver's measurement test
// (the one data snooping uses), not its largest |w| alone. P is measured
// twice, σ 1 mm per component: with the two differing by d along x, each
// residual is d/2 with σ_v = σ/√2, so w_x = d/(σ√2) and the measurement's
// χ²(3) statistic is w_x². At α = 0.001: w_c = 3.2905, χ²₃ critical 16.266
// (tables). w_x = 3.5: |w| above w_c but the test passes (12.25): elevated.
// w_x = 4.5: the test fails (20.25): failing, kept with snooping off.
TEST(NetworkModel, AMeasurementsClassFollowsItsMeasurementTest) {
  constexpr double kSigma_m = 1e-3;
  const auto rows_for = [&](double w_x) {
    NetworkModel model(point_measured_twice('n', 'e', Eigen::Matrix3d::Identity() * kSigma_m * kSigma_m, w_x * kSigma_m * std::sqrt(2.0)),
                       no_snooping());
    EXPECT_TRUE(model.result()) << model.error();
    return model.measurement_rows();
  };
  const auto elevated = rows_for(3.5);
  ASSERT_EQ(elevated.size(), 2u);
  for (const auto& r : elevated) {
    EXPECT_NEAR(r.w_max, 3.5, 1e-6);
    EXPECT_FALSE(r.has_line);
    EXPECT_EQ(r.shown_as, MeasurementClass::elevated);
  }
  for (const auto& r : rows_for(4.5)) EXPECT_EQ(r.shown_as, MeasurementClass::failing);
  for (const auto& r : rows_for(1.0)) EXPECT_EQ(r.shown_as, MeasurementClass::small);
  // Orange starts at 2, or at w_c when a larger α makes it smaller.
  EXPECT_EQ(elevated_w(3.2905), 2.0);
  EXPECT_EQ(elevated_w(1.96), 1.96);
  EXPECT_NE(describe(MeasurementClass::small, 1.96).find("1.96"), std::string::npos);
}

}  // namespace
}  // namespace geoanchor::gui
