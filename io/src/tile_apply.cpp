#include "geoanchor/io/tile_apply.hpp"

#include <algorithm>

#include "geoanchor/geodesy/number_text.hpp"
#include "crs_impl.hpp"
#include "tile_common.hpp"

namespace geoanchor::io {

TileCrsAxes tile_crs_axes(const Crs& crs) {
  const auto& d = crs.description();
  TileCrsAxes a;
  a.geocentric = d.type == "geocentric";
  const auto& axes = d.visualization_axes.empty() ? d.axes : d.visualization_axes;
  a.angular = !axes.empty() && axes[0].unit_type == "angular";
  if (!axes.empty()) a.horizontal_unit = a.angular ? axes[0].unit_to_si / detail::kRadiansPerDegree : axes[0].unit_to_si;
  a.has_height = axes.size() >= 3;
  if (a.has_height) a.vertical_m = axes[2].unit_to_si;
  return a;
}

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
