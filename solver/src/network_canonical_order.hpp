#pragma once
// The canonical order of a network's measurements and direction sets: by
// what each is, never by where it is in the input, so that every sum over
// them runs in one order and the same network in a shuffled file gives the
// same bits; and the key data snooping breaks exact ties with.
//
// Private to solver.

#include <cstddef>
#include <string>
#include <vector>

#include "geoanchor/geodesy/network.hpp"

namespace geoanchor::solver {

// Direction sets by what they are: their station's name, then their
// directions in the order of their content, compared one by one (then the
// fewer first). Equal sets are interchangeable.
std::vector<std::size_t> canonical_set_order(const geodesy::Network& net);

// Each set's place in canonical_set_order (its canonical rank).
std::vector<std::size_t> set_ranks(const std::vector<std::size_t>& set_order);

// The canonical rank + 1 of measurement m's direction set (an observation
// set's: its first direction's) in `ranks` (set_ranks); 0 for none.
std::size_t direction_set_rank(const geodesy::NetworkMeasurement& m, const std::vector<std::size_t>& ranks);

// The measurements by what they are (compare_content), a direction's set
// by its canonical rank after that.
std::vector<std::size_t> canonical_order(const geodesy::Network& net, const std::vector<std::size_t>& set_order);

// The text data snooping breaks exact ties with: what the measurement is
// (kind, stations, values, heights and covariance as exact hexadecimal, an
// observation set's parts' kinds and heights,
// frame, group, a direction's set by its canonical rank `set_rank` (0 for
// none), solution type, variance scales, ignored), not where it is.
std::string measurement_key(const geodesy::Network& net, const geodesy::NetworkMeasurement& m, std::size_t set_rank);

}  // namespace geoanchor::solver
