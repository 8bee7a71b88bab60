#pragma once
// What a Crs holds (private to crs): its own PROJ context and object.

#include "geoanchor/crs/crs.hpp"
#include "geoanchor/crs/unit_factors.hpp"
#include "proj_handles.hpp"

namespace geoanchor::io {

struct Crs::Impl {
  detail::PjContext ctx;  // declared first: destroyed after the object
  detail::Pj crs;
  CrsDescription description;
};

}  // namespace geoanchor::io
