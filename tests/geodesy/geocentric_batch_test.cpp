// The array ECEF -> geodetic (two Bowring steps, vectorised) against
// GeographicLib's Geocentric::Reverse, used directly as the reference.

#include <GeographicLib/Geocentric.hpp>
#include <gtest/gtest.h>

#include <cmath>

#include "geoanchor/geodesy/geocentric_batch.hpp"
#include "test_support.hpp"

namespace geoanchor::geodesy {
namespace {

constexpr double kBatchVsGeographicLib_m = 10e-9;  // issue acceptance: 10 nm in position

// Position error of (lat, lon, h) as an answer for ECEF `x`: the distance
// between GeographicLib's (exact, closed-form) forward of it and `x`.
double position_error_m(const GeographicLib::Geocentric& g, double lat, double lon, double h, double x, double y, double z) {
  double fx = 0, fy = 0, fz = 0;
  g.Forward(lat, lon, h, fx, fy, fz);
  return std::hypot(fx - x, fy - y, fz - z);
}

// issue 12, tests that can fail, item 1: the worst case keeps a NaN (a batch
// that wrote NaN everywhere passed with std::max).
TEST(GeocentricBatch, AgreesWithGeographicLibToTenNanometresFromMinus150To1100Km) {
  for (const auto& e : {Ellipsoid::wgs84(), Ellipsoid::grs80()}) {
    const GeographicLib::Geocentric g(e.a_m(), e.f());
    const auto pts = testing::worldwide_points(300000, -150000.0, 1100000.0);
    std::vector<double> x, y, z;
    for (const auto& p : pts) {
      double a = 0, b = 0, c = 0;
      g.Forward(p.lat.deg(), p.lon.deg(), p.h.m, a, b, c);
      x.push_back(a), y.push_back(b), z.push_back(c);
    }
    const auto x0 = x, y0 = y, z0 = z;
    geodetic_from_ecef_batch(e, x, y, z);
    testing::WorstCase worst, worst_vs_reverse;
    for (std::size_t i = 0; i < x.size(); ++i) {
      worst.add(position_error_m(g, x[i], y[i], z[i], x0[i], y0[i], z0[i]), i);
      double lat = 0, lon = 0, h = 0;
      g.Reverse(x0[i], y0[i], z0[i], lat, lon, h);
      // The two answers as positions (longitude is arbitrary on the axis).
      double ax = 0, ay = 0, az = 0, bx = 0, by = 0, bz = 0;
      g.Forward(lat, lon, h, ax, ay, az);
      g.Forward(x[i], y[i], z[i], bx, by, bz);
      worst_vs_reverse.add(std::hypot(ax - bx, ay - by, az - bz), i);
    }
    EXPECT_WORST_WITHIN(worst, kBatchVsGeographicLib_m) << e.name();
    EXPECT_WORST_WITHIN(worst_vs_reverse, kBatchVsGeographicLib_m) << e.name();
    ::testing::Test::RecordProperty("worst_position_error_m_" + e.name(), testing::scientific(worst.value()));
  }
}

TEST(GeocentricBatch, PointsOutsideTheKernelsRangeGoThroughGeographicLibAndNanStaysNan) {
  const Ellipsoid e = Ellipsoid::wgs84();
  const GeographicLib::Geocentric g(e.a_m(), e.f());
  std::vector<double> x = {0.0, 4.2e7, 1000.0, std::nan(""), 6378137.0, 0.0};
  std::vector<double> y = {0.0, 0.0, 2000.0, 0.0, std::numeric_limits<double>::infinity(), 0.0};
  std::vector<double> z = {0.0, 1.0e6, -500.0, 0.0, 0.0, e.b_m() + 1000.0};
  const auto x0 = x, y0 = y, z0 = z;
  geodetic_from_ecef_batch(e, x, y, z);
  for (std::size_t i : {0u, 1u, 2u}) {
    double lat = 0, lon = 0, h = 0;
    g.Reverse(x0[i], y0[i], z0[i], lat, lon, h);
    EXPECT_EQ(x[i], lat) << i;
    EXPECT_EQ(y[i], lon) << i;
    EXPECT_EQ(z[i], h) << i;
  }
  for (std::size_t i : {3u, 4u}) EXPECT_TRUE(std::isnan(x[i]) && std::isnan(y[i]) && std::isnan(z[i])) << i;
  // On the polar axis, inside the kernel's range: the pole, 1 km up.
  EXPECT_EQ(x[5], 90.0);
  EXPECT_NEAR(z[5], 1000.0, kBatchVsGeographicLib_m);
}

}  // namespace
}  // namespace geoanchor::geodesy
