#include "geoanchor/io/tile/tile_apply.hpp"

#include <algorithm>

#include "geoanchor/base/number_text.hpp"
#include "geoanchor/crs/unit_factors.hpp"
#include "tile/tile_common.hpp"

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
    case TileFormat::laz: return "laz";
    case TileFormat::csv: return "csv";
    case TileFormat::ply: return "ply";
    case TileFormat::geojson: return "geojson";
    case TileFormat::osm: return "osm";
    case TileFormat::xodr: return "xodr";
  }
  return "?";
}

namespace {
std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}
constexpr std::string_view kCopcSuffix = ".copc.laz";
}  // namespace

std::optional<TileFormat> tile_format_of(const std::filesystem::path& p) {
  const std::string ext = lower(p.extension().string());
  if (ext == ".las") return TileFormat::las;
  if (ext == ".laz") return TileFormat::laz;
  if (ext == ".csv" || ext == ".txt") return TileFormat::csv;
  if (ext == ".ply") return TileFormat::ply;
  if (ext == ".geojson") return TileFormat::geojson;
  if (ext == ".osm") return TileFormat::osm;
  if (ext == ".xodr") return TileFormat::xodr;
  return std::nullopt;
}

bool is_copc_name(const std::filesystem::path& p) {
  const std::string name = lower(p.filename().string());
  return name.size() > kCopcSuffix.size() && name.ends_with(kCopcSuffix);
}

std::string tile_output_name(const std::filesystem::path& input, TileFormat out) {
  const std::string name = input.filename().string();
  const auto in = tile_format_of(input);
  if (in == out && !is_copc_name(input)) return name;
  const std::size_t cut =
      is_copc_name(input) ? name.size() - kCopcSuffix.size() : name.size() - input.extension().string().size();
  return name.substr(0, cut) + "." + std::string(to_string(out));
}

}  // namespace geoanchor::io
