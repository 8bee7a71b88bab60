#pragma once
// `geoanchor adjust`: least-squares adjustment of a survey network. See
// docs/commands/adjust.md.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "network_options.hpp"

namespace CLI {
class App;
}

namespace geoanchor::cli {

struct AdjustCommandOptions {
  std::vector<std::string> inputs;
  std::string output;  // stations CSV ("-": standard output)
  std::optional<std::string> measurements, report, sinex;
  // --relative connected|all|radius:R_M|pairs:FILE, --standard NAME|FILE, --relative-output CSV.
  std::string relative = "connected";
  std::optional<std::string> standard, relative_output;
  std::optional<std::string> convention;      // of the estimated Helmert's file
  std::optional<std::string> helmert_output;  // default: -o's name less .csv, plus .helmert.json
  bool json = false;
  NetworkOptions network;
  bool accept_failed_global_test = false;
  bool preanalysis = false;  // --preanalysis
  bool no_external_reliability = false;  // --no-external-reliability
  std::optional<std::string> candidates, candidates_output, rank_by;  // --preanalysis --candidates FILE
  bool overwrite = false;
  int jobs = 0;  // threads; 0: the machine's cores
  std::optional<double> max_memory_gb;
  std::vector<std::string> argv;
  // --generate N: write a generated network instead of adjusting one.
  std::optional<std::size_t> generate;
  std::optional<std::string> out_dir;
  std::optional<std::uint64_t> seed;
  std::optional<std::size_t> held, blunders;
  std::optional<std::string> center;
  std::optional<double> side_km, blunder_m;
};

CLI::App* add_adjust_command(CLI::App& app, AdjustCommandOptions& options);
// Returns the exit code (0, or 4 when the adjustment is refused after reporting).
int run_adjust(const AdjustCommandOptions& options);

}  // namespace geoanchor::cli
