// The test helpers that decide whether an accuracy test can fail: the
// NaN-proof worst case, the PROJ reference's handling of PROJ's own errors,
// and the per-test temporary folder. Each is checked by catching the
// failures it reports (gtest-spi), so that a helper that quietly passes
// cannot hide behind the tests that use it.

#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "proj_reference.hpp"
#include "temp_folder.hpp"
#include "test_support.hpp"

namespace geoanchor::testing {
namespace {

constexpr double kTol_m = 1e-6;  // any tolerance: these tests are about NaN, not about size
const double kNan = std::numeric_limits<double>::quiet_NaN();

// The messages of the failures `f` reports, without failing this test.
template <class F>
std::vector<std::string> failures_of(F f) {
  ::testing::TestPartResultArray caught;
  {
    const ::testing::ScopedFakeTestPartResultReporter catcher(
        ::testing::ScopedFakeTestPartResultReporter::INTERCEPT_ONLY_CURRENT_THREAD, &caught);
    f();
  }
  std::vector<std::string> out;
  for (int i = 0; i < caught.size(); ++i) out.emplace_back(caught.GetTestPartResult(i).message());
  return out;
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// issue 12, tests that can fail, item 1: std::max(w, NaN) is w, so a
// comparison against a build that returns NaN everywhere passed.
TEST(WorstCase, ANanAnywhereMakesTheWorstCaseNanAndTheAssertionFail) {
  EXPECT_EQ(std::max(0.0, kNan), 0.0);  // what the old tests did
  EXPECT_TRUE(std::isnan(nan_max(0.0, kNan)));
  EXPECT_TRUE(std::isnan(nan_max(kNan, 0.0)));
  EXPECT_EQ(nan_max(1.0, 2.0), 2.0);
  EXPECT_TRUE(std::isnan(max_abs_component(Eigen::Vector3d(0.0, kNan, 0.0))));
  EXPECT_EQ(max_abs_component(Eigen::Vector3d(0.5, -3.0, 1.0)), 3.0);

  WorstCase w;
  w.add(1e-9, 0);
  w.add(kNan, 1);
  w.add(2e-9, 2);
  EXPECT_TRUE(std::isnan(w.value()));
  EXPECT_EQ(w.count(), 3u);
  EXPECT_EQ(w.nan_count(), 1u);
  EXPECT_EQ(w.first_nan_at(), 1u);
  EXPECT_FALSE(w.within(1.0));
  const auto f = failures_of([&] { EXPECT_WORST_WITHIN(w, kTol_m); });
  ASSERT_EQ(f.size(), 1u);
  const std::string m = f[0];
  EXPECT_TRUE(contains(m, "worst case w = NaN: 1 of 3 are NaN, the first at #1")) << m;
  EXPECT_TRUE(contains(m, "expected at most kTol_m = 1e-06")) << m;

  // Every value NaN: what a build returning NaN everywhere gives.
  WorstCase all_nan;
  for (std::size_t i = 0; i < 1000; ++i) all_nan.add(kNan, i);
  const auto g = failures_of([&] { EXPECT_WORST_WITHIN(all_nan, kTol_m); });
  ASSERT_EQ(g.size(), 1u);
  EXPECT_TRUE(contains(g[0], "1000 of 1000 are NaN")) << g[0];

  // A plain double from nan_max fails the same way.
  const auto h = failures_of([&] { EXPECT_WORST_WITHIN(nan_max(0.0, kNan), kTol_m); });
  ASSERT_EQ(h.size(), 1u);
  EXPECT_TRUE(contains(h[0], "a NaN in the comparison")) << h[0];
}

// issue 12, tests that can fail, item 1: a loop that never ran proves nothing.
TEST(WorstCase, AComparisonOfNoPointFails) {
  const WorstCase none;
  EXPECT_TRUE(std::isnan(none.value()));
  const auto f = failures_of([&] { EXPECT_WORST_WITHIN(none, kTol_m); });
  ASSERT_EQ(f.size(), 1u);
  EXPECT_TRUE(contains(f[0], "no comparison was made")) << f[0];
}

TEST(WorstCase, KeepsTheLargestAndWhereItWasAndMergesWithoutDroppingNan) {
  WorstCase a;
  a.add(3e-9, 10);
  a.add(7e-9, 11);
  a.add(std::numeric_limits<double>::infinity(), 12);
  EXPECT_EQ(a.value(), std::numeric_limits<double>::infinity());
  WorstCase b;
  b.add(5e-9, 20);
  b.add(9e-9, 21);
  EXPECT_EQ(b.value(), 9e-9);
  EXPECT_EQ(b.largest_at(), 21u);
  EXPECT_TRUE(b.within(9e-9));
  EXPECT_FALSE(b.within(8e-9));
  const auto f = failures_of([&] { EXPECT_WORST_WITHIN(b, 8e-9); });
  ASSERT_EQ(f.size(), 1u);
  EXPECT_TRUE(contains(f[0], "9.000e-09 at #21 of 2")) << f[0];
  WorstCase c;
  c.add(kNan, 30);
  b.add(c);
  EXPECT_TRUE(std::isnan(b.value()));
  EXPECT_EQ(b.count(), 3u);
  EXPECT_EQ(b.first_nan_at(), 30u);
  EXPECT_EQ(b.largest_at(), 21u);
}

// issue 12, tests that can fail, item 2: PROJ's error for a point fails the
// test, naming the pipeline, the point and PROJ's message (it was a silent
// NaN that a careless worst case then dropped).
TEST(ProjReference, AnErrorForAPointFailsTheTestNamingThePipelineThePointAndProjsMessage) {
  static const std::string kUtm = "+proj=utm +zone=32 +ellps=WGS84";
  const ProjPipeline utm(kUtm);
  Eigen::Vector3d got;
  const auto f = failures_of([&] { got = utm.inverse(Eigen::Vector3d(1e30, 0.0, 0.0)); });
  ASSERT_EQ(f.size(), 1u);
  const std::string m = f[0];
  EXPECT_TRUE(contains(m, "PROJ reported an error")) << m;
  EXPECT_TRUE(contains(m, "outside of projection domain")) << m;  // PROJ's own words
  EXPECT_TRUE(contains(m, "inverse of (1e+30, 0, 0, t=0)")) << m;
  EXPECT_TRUE(contains(m, "'" + kUtm + "'")) << m;
  EXPECT_TRUE(got.array().isNaN().all());

  // The explicit form, for tests that probe PROJ's own failures.
  const auto g = failures_of([&] {
    const ProjPipeline::Result r = utm.try_inverse(Eigen::Vector3d(1e30, 0.0, 0.0));
    EXPECT_FALSE(r.ok());
    EXPECT_NE(r.proj_errno, 0);
    EXPECT_TRUE(contains(r.error, "outside of projection domain")) << r.error;
    EXPECT_TRUE(r.xyz.array().isNaN().all());
  });
  EXPECT_EQ(g.size(), 0u);
  const ProjPipeline::Result fine = utm.try_forward(Eigen::Vector3d(proj_radians(9.0), proj_radians(47.0), 0.0));
  EXPECT_TRUE(fine.ok());
  EXPECT_TRUE(fine.xyz.allFinite());
  EXPECT_TRUE(fine.error.empty());
}

// issue 12, tests that can fail, item 6: every test's folder is its own.
TEST(TempFolder, EachIsFreshAndItsOwnAndGoesWithItsContents) {
  std::filesystem::path kept;
  {
    const TempFolder a, b("other_prefix");
    EXPECT_NE(a.path(), b.path());
    EXPECT_TRUE(std::filesystem::is_directory(a.path()));
    EXPECT_TRUE(std::filesystem::is_empty(a.path()));
    EXPECT_TRUE(contains(a.path().filename().string(), "TempFolder_EachIsFreshAndItsOwnAndGoesWithItsContents"))
        << a.path();
    EXPECT_TRUE(std::filesystem::equivalent(a.path().parent_path(), ::testing::TempDir())) << a.path();
    std::ofstream(a / "x.txt") << "x";
    kept = a.path();
  }
  EXPECT_FALSE(std::filesystem::exists(kept));
}

}  // namespace
}  // namespace geoanchor::testing
