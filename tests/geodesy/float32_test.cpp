// float32 narrowing written inline (geodesy::round_to_float32, a plain
// static_cast<float>), the way the PLY reader and diagnose narrow, against
// the same narrowing done element by element through a volatile float,
// which no optimiser can merge with its neighbours.
//
// GCC 12.2's basic-block SLP vectorizer compiled two or more such round
// trips stored side by side into a plain copy of the doubles; the build
// turns that pass off for GCC < 13 (cmake/GeoanchorCompilerWorkarounds.cmake).
// Built without the flag, these tests fail.

#include <gtest/gtest.h>

#include <Eigen/Core>

#include <array>
#include <cmath>
#include <cstddef>
#include <iomanip>
#include <random>
#include <span>
#include <vector>

#include "geoanchor/geodesy/float32.hpp"

namespace geoanchor::geodesy {
namespace {

// The reference: one conversion at a time, through memory.
double via_volatile_float(double v) {
  const volatile float f = static_cast<float>(v);
  return f;
}

// ECEF-sized coordinates (float32 spacing 0.25–0.5 m there) and map-local
// ones, read through a volatile so that nothing is known at compile time.
std::vector<std::array<double, 3>> coordinates() {
  std::mt19937_64 rng(32);
  std::uniform_real_distribution<double> ecef(-6.4e6, 6.4e6), local(-3000.0, 3000.0);
  std::vector<std::array<double, 3>> out;
  for (int i = 0; i < 1000; ++i) {
    volatile double a = i % 2 ? ecef(rng) : local(rng), b = i % 2 ? ecef(rng) : local(rng), c = ecef(rng);
    out.push_back({a, b, c});
  }
  return out;
}

// The shapes that were miscompiled or could be: each out of line, so that
// the narrowing is compiled on its own, as it is at its call sites.
[[gnu::noinline]] std::array<double, 3> array_initializer(const std::array<double, 3>& x) {
  return {round_to_float32(x[0]), round_to_float32(x[1]), round_to_float32(x[2])};  // diagnose_cli_test's shape
}
[[gnu::noinline]] Eigen::Vector3d vector_constructor(const std::array<double, 3>& x) {
  return {round_to_float32(x[0]), round_to_float32(x[1]), round_to_float32(x[2])};  // tile_metadata_test's shape
}
[[gnu::noinline]] void ply_reader_loop(std::span<double> x, std::span<double> y, std::span<double> z, std::size_t i,
                                       const std::array<double, 3>& v, const std::array<std::size_t, 3>& size) {
  double* dst[3] = {&x[i], &y[i], &z[i]};  // tile_ply.cpp's shape
  for (std::size_t k = 0; k < 3; ++k) *dst[k] = size[k] == 4 ? round_to_float32(v[k]) : v[k];
}
[[gnu::noinline]] void in_place(std::span<double> v) {
  for (double& d : v) d = round_to_float32(d);
}

// issue 12, tests that can fail, item 5: GCC 12 kept x[0] and x[1] of an
// array initializer at double precision.
TEST(Float32, NarrowingStoredSideBySideRoundsEveryElement) {
  std::size_t changed = 0;
  for (const auto& x : coordinates()) {
    const auto a = array_initializer(x);
    const Eigen::Vector3d v = vector_constructor(x);
    for (std::size_t k = 0; k < 3; ++k) {
      const double expected = via_volatile_float(x[k]);
      changed += expected != x[k];
      ASSERT_EQ(a[k], expected) << std::setprecision(17) << "array element " << k << " of (" << x[0] << ", " << x[1]
                                << ", " << x[2] << "): " << a[k] << " is not its float32 value " << expected;
      ASSERT_EQ(v(static_cast<Eigen::Index>(k)), expected)
          << std::setprecision(17) << "vector element " << k << ": " << v(static_cast<Eigen::Index>(k))
          << " is not its float32 value " << expected;
    }
  }
  EXPECT_GT(changed, 2900u);  // the values do lose digits in float32: the comparison is not vacuous
}

// issue 12, tests that can fail, item 5: the PLY reader's loop and a
// narrowing pass over an array.
TEST(Float32, NarrowingInLoopsRoundsEveryElement) {
  const auto xs = coordinates();
  std::vector<double> x(xs.size()), y(xs.size()), z(xs.size()), flat;
  for (std::size_t i = 0; i < xs.size(); ++i) {
    ply_reader_loop(x, y, z, i, xs[i], {4, 4, 8});  // two float properties and a double one
    flat.insert(flat.end(), xs[i].begin(), xs[i].end());
  }
  in_place(flat);
  for (std::size_t i = 0; i < xs.size(); ++i) {
    ASSERT_EQ(x[i], via_volatile_float(xs[i][0])) << std::setprecision(17) << i << ": " << x[i];
    ASSERT_EQ(y[i], via_volatile_float(xs[i][1])) << std::setprecision(17) << i << ": " << y[i];
    ASSERT_EQ(z[i], xs[i][2]) << i;  // the double property is kept
    for (std::size_t k = 0; k < 3; ++k) {
      ASSERT_EQ(flat[3 * i + k], via_volatile_float(xs[i][k])) << std::setprecision(17) << i << " " << k << ": " << flat[3 * i + k];
    }
  }
}

TEST(Float32, RoundToFloat32IsTheNearestFloat) {
  static_assert(round_to_float32(0.5) == 0.5);
  EXPECT_EQ(round_to_float32(16777217.0), 16777216.0);  // 2^24 + 1: a tie, to even
  EXPECT_EQ(round_to_float32(16777219.0), 16777220.0);  // 2^24 + 3: a tie, to even
  EXPECT_EQ(round_to_float32(4277686.123456), 4277686.0);  // spacing 0.5 m at 2^22
  EXPECT_TRUE(std::isnan(round_to_float32(std::nan(""))));
}

}  // namespace
}  // namespace geoanchor::geodesy
