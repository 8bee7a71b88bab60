// Issue 16 point 3: fits leave marks of float and worse GNSS solutions out
// by default, and weigh them on request. The reference is the same fit of
// the same marks without solution types, with those marks set to use = 0
// (or their covariances scaled by hand): what the policy must amount to.

#include <gtest/gtest.h>

#include <cmath>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/control/control_csv.hpp"
#include "geoanchor/solver/helmert_fit.hpp"

namespace geoanchor::solver {
namespace {

using geodesy::GnssSolution;

// Two fits of the same marks in the same order run the same arithmetic:
// their parameters agree to rounding.
constexpr double kSameFitTol = 1e-12;  // relative, of each parameter and sigma

geodesy::ControlSet gnss_set() {
  return io::read_control_csv(std::filesystem::path(GEOANCHOR_FIXTURES_DIR) / "airport_control_gnss.csv", {});
}

FitOptions options() {
  FitOptions o;
  o.model = FitModel::molodensky_badekas;
  o.convention = Convention::position_vector;
  return o;
}

void expect_same_parameters(const FitResult& a, const FitResult& b) {
  ASSERT_EQ(a.parameters.size(), b.parameters.size());
  for (std::size_t k = 0; k < a.parameters.size(); ++k) {
    const auto& p = a.parameters[k];
    const auto& q = b.parameters[k];
    EXPECT_EQ(p.name, q.name);
    EXPECT_NEAR(p.value, q.value, kSameFitTol * std::max(1.0, std::fabs(q.value))) << p.name;
    EXPECT_NEAR(p.sigma, q.sigma, kSameFitTol * std::max(1.0, std::fabs(q.sigma))) << p.name;
  }
  EXPECT_EQ(a.dof, b.dof);
}

TEST(SolutionFit, Issue16_FloatAndWorseAreLeftOutAsIfTheirUseWere0) {
  const geodesy::ControlSet set = gnss_set();
  ASSERT_TRUE(set.has_solutions);
  ASSERT_EQ(set.points.size(), 36u);
  const FitResult fit = fit_helmert(set, options());
  // The reference: no solution types, P32-P36 (float, float, dgps, sbas,
  // standalone, per the fixture's comment) not used.
  geodesy::ControlSet plain = set;
  plain.has_solutions = false;
  for (auto& p : plain.points) {
    p.solution.reset();
    if (p.id >= "P32") p.use = false;
  }
  const FitResult reference = fit_helmert(plain, options());
  expect_same_parameters(fit, reference);
  std::size_t left_out = 0;
  for (const auto& p : fit.points) {
    if (p.id >= "P32") {
      EXPECT_FALSE(p.used) << p.id;
      EXPECT_NE(p.removed_because.find("GNSS solution"), std::string::npos) << p.removed_because;
      ++left_out;
    }
  }
  EXPECT_EQ(left_out, 5u);
  EXPECT_EQ(fit.points[31].removed_because,
            "GNSS solution float: float and worse are left out (--solution-weighting weighs float, dgps, sbas and "
            "standalone)");
}

TEST(SolutionFit, Issue16_WeightingScalesTheSigmasByTheClassFactor) {
  const geodesy::ControlSet set = gnss_set();
  FitOptions o = options();
  o.solutions = geodesy::SolutionPolicy::weight;
  const FitResult fit = fit_helmert(set, o);
  // By hand: float ×10, dgps ×25, sbas ×75, standalone ×250 on both sigmas
  // (covariances × factor²).
  geodesy::ControlSet scaled = set;
  scaled.has_solutions = false;
  for (auto& p : scaled.points) {
    const double f = p.id == "P32" || p.id == "P33" ? 10.0 : p.id == "P34" ? 25.0 : p.id == "P35" ? 75.0 : p.id == "P36" ? 250.0 : 1.0;
    p.source_cov_m2 *= f * f;
    p.target_cov_m2 *= f * f;
    p.solution.reset();
  }
  expect_same_parameters(fit, fit_helmert(scaled, options()));
  for (const auto& p : fit.points) EXPECT_TRUE(p.used || p.outlier) << p.id;
  // Weighting needs sigmas to scale.
  geodesy::ControlSet no_sigmas = set;
  no_sigmas.has_a_priori_sigmas = false;
  try {
    (void)fit_helmert(no_sigmas, o);
    ADD_FAILURE() << "fitted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_OPTION");
    EXPECT_NE(std::string(e.what()).find("gives no a-priori sigmas"), std::string::npos) << e.what();
  }
}

TEST(SolutionFit, Issue16_ASetOfFixedMarksFitsAsWithoutTheColumn) {
  geodesy::ControlSet set = gnss_set();
  geodesy::ControlSet plain = set;
  plain.has_solutions = false;
  for (std::size_t i = 0; i < set.points.size(); ++i) {
    set.points[i].solution = GnssSolution::fixed;
    plain.points[i].solution.reset();
  }
  expect_same_parameters(fit_helmert(set, options()), fit_helmert(plain, options()));
  // dead_reckoned is left out even with weighting.
  set.points[0].solution = GnssSolution::dead_reckoned;
  FitOptions o = options();
  o.solutions = geodesy::SolutionPolicy::weight;
  const FitResult weighted = fit_helmert(set, o);
  EXPECT_FALSE(weighted.points[0].used);
  EXPECT_NE(weighted.points[0].removed_because.find("dead-reckoned"), std::string::npos);
}

}  // namespace
}  // namespace geoanchor::solver
