#pragma once
// `geoanchor crs CRS [--json]`: what geoanchor understands of a CRS, read
// through PROJ, and the WKT2 it would write. See docs/commands/crs.md.

#include <string>

namespace CLI {
class App;
}

namespace geoanchor::cli {

struct CrsCommandOptions {
  std::string crs;
  bool json = false;
};

CLI::App* add_crs_command(CLI::App& app, CrsCommandOptions& options);

// Prints the description. Throws geoanchor::Error.
void run_crs(const CrsCommandOptions& options);

}  // namespace geoanchor::cli
