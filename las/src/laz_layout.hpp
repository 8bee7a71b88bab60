#pragma once
// The chunk layout a laszip VLR's items describe (which items follow POINT10
// or POINT14, and how many extra bytes): made in one place (laz.cpp) for the
// chunk coders of laz.cpp and the LAZ reader of las_laz.cpp.

#include <cstdint>

#include "geoanchor/las/laz.hpp"
#include "laz_chunk.hpp"

namespace geoanchor::io {

// The layout of `vlr`'s items, for records of `record_length` bytes.
laz::ChunkLayout chunk_layout(const LazVlr& vlr, std::uint16_t record_length);

}  // namespace geoanchor::io
