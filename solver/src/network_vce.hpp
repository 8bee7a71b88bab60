#pragma once
// Variance components of a network adjustment (adjust --vce): the
// measurements in groups (AdjustOptions::VarianceGroups), each group's
// a-priori covariances scaled by a factor θ_k iterated by Förstner's rule
// θ_k ← θ_k · Ω_k / r_k (Ω_k = Σ vᵢᵀ Σᵢ⁻¹ vᵢ and r_k = Σ redundancy over the
// group's measurements: for disjoint groups the trace form fit --vce uses,
// vᵀP Q_k P v / tr(P Q_k P Q_vv)) until none changes by kVceTolerance; σ(θ_k)
// = θ_k √(2 / r_k). The estimation adjusts without data snooping (nor
// external reliability or the relative precision asked for); the
// result is the adjustment with the caller's options on the scaled
// covariances, with the components.
//
// Private to solver.

#include <functional>

#include "geoanchor/solver/network_adjustment.hpp"

namespace geoanchor::solver {

// `adjust`: one adjustment (adjust_network without variance components).
AdjustmentResult adjust_with_variance_components(const geodesy::Network& network, const AdjustOptions& options,
                                                 const std::function<AdjustmentResult(const geodesy::Network&, const AdjustOptions&)>& adjust);

}  // namespace geoanchor::solver
