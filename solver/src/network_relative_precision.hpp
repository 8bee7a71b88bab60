#pragma once
// Relative precision between pairs of adjusted stations (adjust
// --relative): which pairs (AdjustOptions::relative: those a measurement
// joins, all, all within a horizontal radius, or a listed set) and, per
// pair, the covariance of their difference in the first station's local
// horizon, its horizontal ellipse (1σ and at the confidence), the up σ and
// the σ of the distance. The cross cofactor of a pair that shares no
// measurement (off the factor's pattern) comes from forward solves along
// the elimination tree (DatumCofactors::with_each), never a dense inverse.
//
// Private to solver.

#include <cstddef>
#include <utility>
#include <vector>

#include "geoanchor/solver/network_adjustment.hpp"
#include "network_free_datum.hpp"
#include "network_problem.hpp"

namespace geoanchor::solver {

// The pairs of p.o.relative among the stations in the adjustment, each
// once as (lower, higher) index, sorted. radius: candidates from a grid
// of cells of the radius's size over the stations' horizontal positions
// (each station against its own and the neighbouring cells: O(n) for
// evenly spread stations), then the horizontal distance in the first
// station's horizon. Throws geoanchor::Error (usage, E_OPTION): `all`
// past kMaxAllRelativePairs, naming the count.
std::vector<std::pair<std::size_t, std::size_t>> relative_pairs(const NetworkProblem& p);

// result.relative for relative_pairs(p), on `jobs` threads.
void relative_precision(const NetworkProblem& p, const DatumCofactors& cofactors, AdjustmentResult& result, int jobs);

}  // namespace geoanchor::solver
