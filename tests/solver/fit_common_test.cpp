// When a fit's solve counts as converged (solver/src/fit_common, private to
// solver): Ceres stopping with FAILURE at the optimum, where its steps move
// the cost only by its rounding, is; any other FAILURE is not.

#include <gtest/gtest.h>

#include "fit_common.hpp"

namespace geoanchor::solver {
namespace {

ceres::IterationSummary step(double cost, double change, double norm, bool successful) {
  ceres::IterationSummary it;
  it.cost = cost;
  it.cost_change = change;
  it.step_norm = norm;
  it.step_is_successful = successful;
  it.step_is_valid = norm > 0.0;
  return it;
}

// The enu-origin fit's solve as Ceres 2.1 reported it under another
// rounding of Eigen's kernels: started at the optimum, every step of about
// 1e-13 raised the cost of 48.2 by some 3e-10 and was rejected, the trust
// region shrank to nothing, and Ceres gave up after five null steps.
ceres::Solver::Summary stalled() {
  ceres::Solver::Summary s;
  s.termination_type = ceres::FAILURE;
  s.message = "Number of consecutive invalid steps more than Solver::Options::max_num_consecutive_invalid_steps: 5";
  s.iterations.push_back(step(48.229559250544625, 0.0, 0.0, true));
  for (int k = 0; k < 4; ++k) s.iterations.push_back(step(48.229559250823016, -2.78e-10, 1.09e-13, false));
  s.iterations.push_back(step(48.22955925079615, -2.52e-10, 2.6e-14, false));
  for (int k = 0; k < 7; ++k) s.iterations.push_back(step(48.229559250544625, 0.0, 0.0, false));
  return s;
}

TEST(SolveTightly, AFailureAtTheOptimumIsConvergenceAndNoOtherIs) {
  EXPECT_TRUE(stopped_at_optimum(stalled()));
  // A rejected step that would have moved the parameters by a micrometre:
  // not at the optimum.
  ceres::Solver::Summary far = stalled();
  far.iterations[3].step_norm = 1e-6;
  EXPECT_FALSE(stopped_at_optimum(far));
  // A cost change beyond rounding.
  ceres::Solver::Summary worse = stalled();
  worse.iterations[2].cost_change = -1e-3;
  EXPECT_FALSE(stopped_at_optimum(worse));
  // Out of iterations is no convergence, whatever the steps.
  ceres::Solver::Summary out = stalled();
  out.termination_type = ceres::NO_CONVERGENCE;
  EXPECT_FALSE(stopped_at_optimum(out));
  // Nothing tried after the last accepted step.
  ceres::Solver::Summary none = stalled();
  none.iterations.resize(1);
  EXPECT_FALSE(stopped_at_optimum(none));
}

}  // namespace
}  // namespace geoanchor::solver
