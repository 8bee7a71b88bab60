#pragma once
// `geoanchor transform`: coordinates (and velocities) from one reference
// frame and epoch to another through the frame catalog. See
// docs/commands/transform.md.

#include <optional>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace geoanchor::cli {

struct TransformOptions {
  std::string input = "-";
  std::string output;  // empty or "-": standard output
  std::string from, to;
  std::optional<std::string> plate;
  std::string plate_model = "ITRF2020";
  std::optional<std::string> ellipsoid;  // default: each frame's own (issue 13 point 5)
  std::optional<int> precision;
  std::optional<std::string> geoid;  // for H_m columns (read and written on the same model)
  bool assume_zero_velocity = false;  // a plate-fixed frame's epoch change without velocities (issue 40 point 1)
  bool overwrite = false;
  bool json = false;  // print the provenance sidecar on standard output
  std::vector<std::string> argv;
};

CLI::App* add_transform_command(CLI::App& app, TransformOptions& o);
void run_transform(const TransformOptions& o);

}  // namespace geoanchor::cli
