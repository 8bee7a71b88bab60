#pragma once
// How audit writes lengths and lists of names into its evidence (private to
// workflow's audit).

#include <cstddef>
#include <string>
#include <vector>

#include "geoanchor/base/number_text.hpp"
#include "map_files.hpp"

namespace geoanchor::workflow::audit_detail {

inline constexpr std::size_t kListed = 20;  // artifacts named in one line of evidence at most

inline std::string fixed(double v, int decimals) { return format_fixed(v, decimals); }
inline std::string cm(double m) { return fixed(m * 100.0, 1) + " cm"; }
inline std::string mm(double m) { return fixed(m * 1000.0, 2) + " mm"; }

inline std::string join(const std::vector<std::string>& v) { return detail::name_list(v, kListed); }

}  // namespace geoanchor::workflow::audit_detail
