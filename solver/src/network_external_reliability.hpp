#pragma once
// External reliability of a network adjustment (AdjustedMeasurement::
// external): per measurement component, the effect on the unknowns of an
// undetected blunder of its MDB, ∇x = N⁻¹ Aᵢᵀ Pᵢ ∇lᵢ (∇lᵢ = MDB along that
// component), S-transformed to the minimum-norm datum of a free network;
// its largest effect on any station (3-D, horizontal, vertical) and on the
// Helmert parameters. JAG3D's "influence on point position" (EP): its
// factor Qxx Aᵀ P per observation times the bias (applied-geodesy/jag3d,
// NetworkAdjustment.java, setInfluenceOnPointPosition).
//
// Cost: one solve with the factor per component (batched, several
// right-hand sides per CHOLMOD call), each O(nnz(L)), and a pass over the
// unknowns: O(components · nnz(L)) in all, a few factorizations' worth at
// 10⁴ stations (bench/adjust_bench.cpp).
//
// Private to solver.

#include "geoanchor/solver/network_adjustment.hpp"
#include "network_free_datum.hpp"
#include "network_problem.hpp"
#include "sparse/sparse_factor.hpp"

namespace geoanchor::solver {

// Above this many measurement components the external reliability is left
// out, said in a warning: its solves cost 0.7 ms per component at 10³
// stations (8 571 components: 6.2 s against 0.12 s for the rest of a
// pre-analysis) and 4 ms at 10⁴ (85 269: 6 minutes against 3 s), growing
// with nnz(L).
inline constexpr std::size_t kExternalReliabilityMaxComponents = 10000;

// Fills result.measurements[*].external (those in the adjustment whose MDB
// is finite; the rest keep NaN), after measurement_statistics.
void external_reliability(const NetworkProblem& p, const NormalFactor& f, const InnerConstraints& inner, AdjustmentResult& result);

}  // namespace geoanchor::solver
