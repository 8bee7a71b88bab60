#pragma once
// A geoid grid by PROJ's name or by path (`--geoid NAME|PATH`), evaluated
// by PROJ's vgridshift: any grid format PROJ reads (GTX, GeoTIFF), found
// where PROJ finds grids (its data directories, no network), with PROJ's
// own bilinear interpolation.

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "geoanchor/geodesy/geoid.hpp"

namespace geoanchor::io {

// Throws geoanchor::Error (input, E_GEOID_MISSING) naming `flag`, the text
// and PROJ's search paths when no such file exists; (input, E_GEOID) when
// PROJ cannot read it as a vertical grid.
geodesy::GeoidGrid proj_geoid_grid(std::string_view name_or_path, std::string_view flag);

// The file `--geoid NAME|PATH` names: the path as given, else a grid of that
// name where PROJ looks; nullopt when there is none.
std::optional<std::filesystem::path> find_geoid_file(std::string_view name_or_path);

// What an output records of the geoid it used (JSON text): the model, the
// grid file and its SHA-256, and how it is interpolated.
std::string geoid_record_json(const geodesy::GeoidGrid& grid);

}  // namespace geoanchor::io
