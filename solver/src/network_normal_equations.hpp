#pragma once
// The normal equations of a network adjustment: assembled from every
// measurement's whitened rows and the weighted constraints at the current
// state, in the canonical order, and factored (NormalFactor) or their
// singularity explained.
//
// Private to solver.

#include <Eigen/Core>

#include <cstddef>
#include <optional>
#include <vector>

#include "network_problem.hpp"
#include "sparse/sparse_factor.hpp"

namespace geoanchor::solver {

// The normal equations at the current state: entries of N (upper
// triangle), Aᵀ l, the number of observation rows and vᵀPv of the misclosures.
struct NormalEquations {
  std::vector<SymmetricEntry> entries;
  Eigen::VectorXd b;
  std::size_t rows = 0;
};

// With `matrix` false only b and the rows (the matrix is known not to have
// changed: constant_jacobian()). The measurements are linearized on `jobs`
// threads a block at a time and summed on this one in their order, so the
// entries and b do not depend on the threads.
NormalEquations assemble(const NetworkProblem& p, bool matrix = true, int jobs = 1);

// Whether the normal matrix is the same at every state: every measurement
// in the adjustment is linear in the positions (GNSS baselines and points;
// the unknowns' axes are fixed, StationState::axes), no Helmert is
// estimated with them, and the datum is held by constraints (inner
// constraints move with the positions).
bool constant_jacobian(const NetworkProblem& p);

// The factor of the normal matrix (with `previous`, its analysis reused:
// NormalFactor::factor), or a refusal that names what the matrix leaves
// free (explain_singularity).
NormalFactor factor_or_explain(const NetworkProblem& p, const NormalEquations& n, std::optional<NormalFactor> previous = std::nullopt);

}  // namespace geoanchor::solver
