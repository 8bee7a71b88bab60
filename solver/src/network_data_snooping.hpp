#pragma once
// Data snooping in a network adjustment (snooping.hpp): the measurements
// that fail their test, ranked in the order iterative snooping removes
// them with the cofactors of network_snooping.hpp; flagged and kept, or
// with remove_outliers taken out for the next pass, up to
// max_outlier_share (past it the adjustment is refused or the failures
// named).
//
// Private to solver.

#include <cstddef>
#include <string>
#include <vector>

#include "geoanchor/solver/network_adjustment.hpp"
#include "network_problem.hpp"
#include "sparse/sparse_factor.hpp"

namespace geoanchor::solver {

// What data snooping carries from one pass of the adjustment to the next.
struct SnoopingRecord {
  std::size_t countable = 0;  // the measurements in the adjustment before data snooping removed any
  std::size_t removed = 0;    // removed by data snooping so far
  // Per measurement: why it is out of the adjustment (a gross misclosure,
  // data snooping), empty when it is not; and its rank in data snooping's
  // order (AdjustedMeasurement::snooping_rank, 0: none).
  std::vector<std::string> outlier_why;
  std::vector<std::size_t> rank_of;
  std::vector<std::size_t> removed_last_pass;  // what the last pass removed
};

// Data snooping (snooping.hpp): the failing measurements in the order
// iterative snooping removes them, each the strongest evidence once the
// ones before it are out. Flagged and kept; with remove_outliers they
// go, and the network is adjusted and tested again (ranks continue):
// then true, p.active without them and `record` updated.
bool snoop_network(NetworkProblem& p, const NormalFactor& f, SnoopingRecord& record, AdjustmentResult& result, int jobs);

}  // namespace geoanchor::solver
