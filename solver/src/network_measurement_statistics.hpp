#pragma once
// A network adjustment's results per measurement (AdjustedMeasurement):
// adjusted values, residuals and their standard deviations, redundancy,
// w-tests, MDB and the measurement test, from the factor's selected
// inverse; then vᵀPv, the variance factor, σ0 and the global test.
//
// Private to solver.

#include <cstddef>
#include <string>
#include <vector>

#include "geoanchor/solver/network_adjustment.hpp"
#include "network_problem.hpp"
#include "sparse/sparse_factor.hpp"

namespace geoanchor::solver {

// What the measurement statistics read besides the problem and its factor:
// per measurement why it is out of the adjustment (empty: it is not, or
// ignored) and its data-snooping rank (0: none); the tests' λ0
// (PointTestLevels).
struct MeasurementRecord {
  const std::vector<std::string>& outlier_why;
  const std::vector<std::size_t>& rank_of;
  double lambda0 = 0.0;
};

// result.measurements (every measurement its input does not ignore),
// result.vtpv, variance_factor, sigma0 and global_test; result.dof is
// set. On `jobs` threads: each measurement's results are its own, so they
// do not depend on the threads. A measurement left out is tested by
// solves with the factor (CHOLMOD's solve is not shared between threads):
// after the others, on this thread.
void measurement_statistics(const NetworkProblem& p, const NormalFactor& f, const MeasurementRecord& record,
                            AdjustmentResult& result, int jobs);

}  // namespace geoanchor::solver
