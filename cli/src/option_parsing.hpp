#pragma once
// What the subcommands share on the command line itself: the value parsers
// (geoanchor/workflow/value_text.hpp, also used by the window) and the
// CLI11 registration of options several subcommands take.

#include "geoanchor/workflow/value_text.hpp"

namespace CLI {
class App;
}

namespace geoanchor::cli {

using workflow::apply_control_grids;
using workflow::ControlGridOptions;
using workflow::parse_convention;
using workflow::parse_ellipsoid;
using workflow::parse_geoid;
using workflow::parse_model;
using workflow::parse_origin;
using workflow::parse_tm;
using workflow::parse_zone;
using workflow::split_numbers;

// --src-zone, --src-tm, --dst-zone, --dst-tm: the grids of a control set's
// easting/northing columns.
void add_control_grid_options(CLI::App& cmd, ControlGridOptions& o);

}  // namespace geoanchor::cli
