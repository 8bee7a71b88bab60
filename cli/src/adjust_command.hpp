#pragma once
// `geoanchor adjust`: least-squares adjustment of a survey network. See
// docs/commands/adjust.md.

#include <optional>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace geoanchor::cli {

struct AdjustCommandOptions {
  std::vector<std::string> inputs;
  std::string output;  // stations CSV ("-": standard output)
  std::optional<std::string> measurements, report, sinex;
  std::optional<std::string> sinex_frame;
  std::optional<std::string> estimate_helmert;
  std::optional<std::string> convention;      // of the estimated Helmert's file
  std::optional<std::string> helmert_output;  // default: -o's name less .csv, plus .helmert.json
  bool json = false;
  std::optional<std::string> frame;
  std::vector<std::string> constrain;
  bool free = false;
  std::optional<std::string> inner;  // ID,ID,...
  double confidence = 0.95;
  double alpha = 0.001;
  double max_outlier_share = 0.10;
  bool no_snooping = false;
  std::optional<std::string> geoid;
  double refraction = 0.0;
  double convergence_m = 1e-5;
  int max_iterations = 25;
  bool accept_failed_global_test = false;
  bool overwrite = false;
  std::vector<std::string> argv;
};

CLI::App* add_adjust_command(CLI::App& app, AdjustCommandOptions& options);
// Returns the exit code (0, or 4 when the adjustment is refused after reporting).
int run_adjust(const AdjustCommandOptions& options);

}  // namespace geoanchor::cli
