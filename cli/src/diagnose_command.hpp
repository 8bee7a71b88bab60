#pragma once
// `geoanchor diagnose`: which classic datum mistake explains a bad fit. See
// docs/commands/diagnose.md.

#include <optional>
#include <string>
#include <vector>

#include "option_parsing.hpp"

namespace CLI {
class App;
}

namespace geoanchor::cli {

struct DiagnoseCommandOptions {
  std::string control;
  std::optional<std::string> transform;
  bool json = false;
  std::string model = "helmert7";
  std::optional<std::string> convention;
  std::optional<std::string> origin;
  std::optional<std::string> ellipsoid;  // default: each frame's (io::ControlReadOptions::ellipsoid)
  ControlGridOptions grids;  // easting/northing columns
  std::optional<std::string> source_frame, target_frame;
  std::optional<std::string> geoid;  // EGM96 | EGM96-NGA: reads H columns, and the height_type hypothesis uses it
  std::optional<double> sigma;
};

CLI::App* add_diagnose_command(CLI::App& app, DiagnoseCommandOptions& options);
void run_diagnose(const DiagnoseCommandOptions& options);

}  // namespace geoanchor::cli
