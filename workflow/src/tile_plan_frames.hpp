#pragma once
// What the tile planner's files share (private to workflow): a frame at an
// epoch, and whether a CRS is 2-D.

#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/units.hpp"
#include "geoanchor/crs/crs.hpp"

namespace geoanchor::workflow::detail {

inline geodesy::Frame with_epoch(const geodesy::Frame& f, geodesy::DecimalYear e) {
  return geodesy::Frame::parse(f.name() + "@" + geodesy::format_decimal_year(e), "frame");
}

inline bool two_d(const io::Crs& c) { return c.description().axes.size() < 3; }

}  // namespace geoanchor::workflow::detail
