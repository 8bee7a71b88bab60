#include "geoanchor/io/tile_apply.hpp"

#include <algorithm>

#include "geoanchor/geodesy/number_text.hpp"
#include "tile_common.hpp"

namespace geoanchor::io {

std::string_view to_string(TileFormat f) {
  switch (f) {
    case TileFormat::las: return "las";
    case TileFormat::csv: return "csv";
    case TileFormat::ply: return "ply";
  }
  return "?";
}

std::optional<TileFormat> tile_format_of(const std::filesystem::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".las") return TileFormat::las;
  if (ext == ".csv" || ext == ".txt") return TileFormat::csv;
  if (ext == ".ply") return TileFormat::ply;
  return std::nullopt;
}

}  // namespace geoanchor::io
