#pragma once
// What a Crs holds (private to io): its own PROJ context and object.

#include "geoanchor/io/crs.hpp"
#include "proj_handles.hpp"

namespace geoanchor::io {

struct Crs::Impl {
  detail::PjContext ctx;  // declared first: destroyed after the object
  detail::Pj crs;
  CrsDescription description;
};

}  // namespace geoanchor::io
