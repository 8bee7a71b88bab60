// Adjusted values as the observations are given (issue 43 point 6): an
// adjusted direction, horizontal angle or azimuth in [0, 2π) and a
// longitude in (−π, π], whatever a direction set's orientation makes of
// the computed value (a direction adjusted to 407.667° was the symptom);
// each equals observed + residual on the circle.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "geoanchor/solver/network_adjustment.hpp"
#include "network_builder.hpp"
#include "network_model.hpp"

namespace geoanchor::solver {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kOnTheCircle_rad = 1e-12;
constexpr double kRounding_rad = 1e-13;  // a few ulps of 2π

bool circular(MeasurementKind k) {
  return k == MeasurementKind::direction || k == MeasurementKind::horizontal_angle || k == MeasurementKind::azimuth;
}

TEST(AdjustedValues, Issue43_AnglesOnTheCircleStayInTheirRange) {
  std::mt19937 rng(407);
  const Site s = make_site(9, rng);
  Network net = mixed_network(s, &rng);
  net.stations[0].constraint.code = {'C', 'C', 'C'};
  std::size_t circulars = 0;
  for (auto& m : net.measurements) {
    if (!circular(m.kind)) continue;
    m.value(0) -= kTwoPi * std::floor(m.value(0) / kTwoPi);  // as readers give them: [0, 2π)
    ++circulars;
  }
  // Orientations far from the directions' zero: the computed values lie
  // anywhere on the real line.
  AdjustOptions o;
  o.data_snooping = false;
  const AdjustmentResult r = adjust_network(net, o);
  ASSERT_TRUE(r.converged);
  std::size_t checked = 0;
  for (const auto& am : r.measurements) {
    const auto& m = net.measurements[am.index];
    if (!circular(m.kind)) continue;
    const double a = am.adjusted(0);
    EXPECT_GE(a, 0.0) << m.source;
    EXPECT_LT(a, kTwoPi) << m.source;
    EXPECT_LE(std::fabs(std::remainder(a - (m.value(0) + am.residual(0)), kTwoPi)), kOnTheCircle_rad) << m.source;
    ++checked;
  }
  EXPECT_EQ(checked, circulars);
  EXPECT_GT(checked, 20u);
}

TEST(AdjustedValues, Issue43_TheWrapItself) {
  geodesy::NetworkMeasurement d = scalar(MeasurementKind::direction, {0, 1}, 0.0000001, 1e-5, "d");
  EXPECT_NEAR(adjusted_value(d, Eigen::VectorXd::Constant(1, -0.0000003))(0), kTwoPi - 0.0000002, kRounding_rad);
  d.value(0) = kTwoPi - 1e-7;
  EXPECT_NEAR(adjusted_value(d, Eigen::VectorXd::Constant(1, 3e-7))(0), 2e-7, kRounding_rad);
  geodesy::NetworkMeasurement lon = scalar(MeasurementKind::geodetic_longitude, {0}, std::numbers::pi - 1e-8, 1e-5, "lon");
  EXPECT_NEAR(adjusted_value(lon, Eigen::VectorXd::Constant(1, 3e-8))(0), -std::numbers::pi + 2e-8, kRounding_rad);
  geodesy::NetworkMeasurement z = scalar(MeasurementKind::zenith_angle, {0, 1}, 1.5, 1e-5, "z");
  EXPECT_EQ(adjusted_value(z, Eigen::VectorXd::Constant(1, 0.25))(0), 1.75);
}

}  // namespace
}  // namespace geoanchor::solver
