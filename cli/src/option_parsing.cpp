#include "option_parsing.hpp"

#include <CLI/CLI.hpp>

namespace geoanchor::cli {

void add_control_grid_options(CLI::App& cmd, ControlGridOptions& o) {
  cmd.add_option("--src-zone", o.src_zone, "UTM zone of easting_src_m/northing_src_m (e.g. 32N)");
  cmd.add_option("--src-tm", o.src_tm, "Transverse Mercator LAT0,LON0,K0,FE,FN of easting_src_m/northing_src_m");
  cmd.add_option("--dst-zone", o.dst_zone, "UTM zone of easting_dst_m/northing_dst_m");
  cmd.add_option("--dst-tm", o.dst_tm, "Transverse Mercator of easting_dst_m/northing_dst_m");
}

}  // namespace geoanchor::cli
