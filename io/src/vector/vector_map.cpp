// What a vector map says of its own coordinates (vector_map.hpp).

#include "geoanchor/io/vector/vector_map.hpp"

#include "vector/vector_map_internal.hpp"

namespace geoanchor::io {

VectorMapStatement read_vector_map_statement(const std::filesystem::path& map, TileFormat format) {
  switch (format) {
    case TileFormat::geojson: return detail::geojson_statement(map);
    case TileFormat::xodr: return detail::xodr_statement(map);
    default: return {};
  }
}

}  // namespace geoanchor::io
