#pragma once
// Shared test helpers: named tolerances live in each test; here are the
// random point generators (with the special cases every geodesy test needs),
// domain matchers and the NaN-proof worst-case assertion.

#include <gmock/gmock.h>

#include <Eigen/Core>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "accuracy.hpp"
#include "geoanchor/geodesy/positions.hpp"

namespace geoanchor::testing {

// Worldwide points: uniform on the sphere, plus the poles, ±180°, the
// equator and the Greenwich meridian, at heights drawn from [h_min, h_max].
// Deterministic for a given seed.
inline std::vector<geodesy::GeodeticPosition> worldwide_points(std::size_t n, double h_min_m, double h_max_m,
                                                               unsigned seed = 20261123) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0), lon(-180.0, 180.0), h(h_min_m, h_max_m);
  std::vector<geodesy::GeodeticPosition> out;
  const double specials[][2] = {{90, 0},    {-90, 0},   {90, 123.4}, {-90, -45}, {0, 180},  {0, -180},
                                {45, 180},  {-45, -180}, {0, 0},      {0, 90},    {0, -90},  {89.999999, 180},
                                {-89.999999, -179.999999}, {1e-12, 1e-12}};
  for (const auto& s : specials) {
    for (double hh : {h_min_m, 0.5 * (h_min_m + h_max_m), h_max_m}) {
      out.push_back({geodesy::Angle::degrees(s[0]), geodesy::Angle::degrees(s[1]), geodesy::EllipsoidalHeight{hh}});
    }
  }
  while (out.size() < n) {
    const double lat = std::asin(u(rng)) * 180.0 / M_PI;
    out.push_back({geodesy::Angle::degrees(lat), geodesy::Angle::degrees(lon(rng)), geodesy::EllipsoidalHeight{h(rng)}});
  }
  return out;
}

// A worst-case figure for RecordProperty, in scientific notation.
inline std::string scientific(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3e", v);
  return buf;
}

// Distance between two 3-vectors, metres.
inline double distance_m(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return (a - b).norm(); }

// Matches an Eigen::Vector3d within `tol_m` (Euclidean) of `expected`.
MATCHER_P2(IsNearVector, expected, tol_m,
           "is within " + ::testing::PrintToString(tol_m) + " m of " + ::testing::PrintToString(expected.transpose())) {
  const double d = (arg - expected).norm();
  *result_listener << "distance " << d << " m";
  return std::isfinite(d) && d <= tol_m;
}

// EXPECT_WORST_WITHIN(worst, tol) / ASSERT_WORST_WITHIN: `worst` (a
// WorstCase, or a double from nan_max) is a number and at most `tol`. Fails
// on a NaN anywhere in the comparison and on a comparison of no point,
// saying which, where the worst was and how many were NaN.
inline std::string short_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}
inline ::testing::AssertionResult WorstWithin(const char* worst_expr, const char* tol_expr, const WorstCase& worst,
                                              double tol) {
  if (worst.within(tol)) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "worst case " << worst_expr << " = " << worst.describe() << "; expected at most "
                                       << tol_expr << " = " << short_number(tol);
}
inline ::testing::AssertionResult WorstWithin(const char* worst_expr, const char* tol_expr, double worst, double tol) {
  if (worst <= tol) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "worst case " << worst_expr << " = " << short_number(worst)
                                       << (std::isnan(worst) ? " (a NaN in the comparison)" : "") << "; expected at most "
                                       << tol_expr << " = " << short_number(tol);
}
#define EXPECT_WORST_WITHIN(worst, tol) EXPECT_PRED_FORMAT2(::geoanchor::testing::WorstWithin, worst, tol)
#define ASSERT_WORST_WITHIN(worst, tol) ASSERT_PRED_FORMAT2(::geoanchor::testing::WorstWithin, worst, tol)

// Difference of two angles in degrees, wrapped to [-180, 180].
inline double angle_difference_deg(double a, double b) {
  double d = std::remainder(a - b, 360.0);
  return d;
}

}  // namespace geoanchor::testing
