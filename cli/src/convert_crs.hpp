#pragma once
// `geoanchor convert --crs SRC --to-crs DST`: the coordinates through PROJ's
// operation for the pair, the columns named by each CRS's axes.

#include "convert_command.hpp"

namespace geoanchor::cli {

// Throws geoanchor::Error.
void run_convert_crs(const ConvertOptions& o);

}  // namespace geoanchor::cli
