#pragma once
// Pre-analysis candidates (AdjustOptions::candidates): each candidate
// measurement (a new direction set's directions together) added alone to
// the design by a low-rank update of the covariance from the factor
// (CovarianceUpdate), never a refactorization, and the candidates ranked by
// the criterion (AdjustOptions::candidate_criterion, else
// candidate_ranking). Cost per candidate: one solve per row (k rows: k
// solves, batched) and the criterion over the stations.
//
// Private to solver.

#include "geoanchor/solver/network_adjustment.hpp"
#include "network_free_datum.hpp"
#include "network_problem.hpp"
#include "sparse/sparse_factor.hpp"

namespace geoanchor::solver {

// The built-in criterion of AdjustOptions::candidate_ranking.
CriterionValue built_in_criterion(const AdjustmentResult& design, const CovarianceUpdate* update, CandidateRanking ranking,
                                  double confidence, geodesy::NetworkSpace space);

// result.candidates and result.design_worst, after station_statistics.
// Throws geoanchor::Error (input) E_CANDIDATE_STATION for a candidate at a
// station the design does not reach, E_COVARIANCE for a candidate's
// covariance that is not positive definite.
void rank_candidates(const NetworkProblem& p, const NormalFactor& f, const InnerConstraints& inner, AdjustmentResult& result);

}  // namespace geoanchor::solver
