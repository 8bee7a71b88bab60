#pragma once
// What `geoanchor adjust` and the workbench's network view (`snapshot`,
// `report` and `gui` with --view network) share: the network's inputs read
// into one network with the datum and statistics options of
// docs/commands/adjust.md, ready to adjust.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "geoanchor/gui/network_model.hpp"
#include "geoanchor/workflow/adjust.hpp"

namespace CLI {
class App;
class Option;
}  // namespace CLI

namespace geoanchor::cli {

struct NetworkOptions {
  std::optional<std::string> frame;
  std::optional<std::string> sinex_frame;
  std::vector<std::string> constrain;
  bool free = false;
  std::optional<std::string> inner;  // ID,ID,...
  double confidence = 0.95;
  double alpha = 0.001;
  double max_outlier_share = 0.10;
  bool no_snooping = false;      // the default (flag, remove none): kept for scripts
  bool remove_outliers = false;  // iterative data snooping removes the failing measurements
  bool solution_weighting = false;  // GNSS measurements of float and worse weighted instead of left out
  std::optional<std::string> geoid;
  std::optional<double> refraction;  // --refraction (else the inputs' own, else 0)
  double convergence_m = 1e-5;
  int max_iterations = 25;
  std::optional<std::string> estimate_helmert;
  std::optional<std::string> vce;  // kind|group|model
};

// --frame, --sinex-frame, --constrain, --free, --inner-constraints,
// --confidence, --alpha, --max-outlier-share, --remove-outliers,
// --no-snooping, --geoid,
// --refraction, --convergence, --max-iterations, --estimate-helmert, --vce. Returns
// the options added (to tell which were given).
std::vector<CLI::Option*> add_network_options(CLI::App* cmd, NetworkOptions& o);

// The request `adjust` would make of these inputs and options (the helmert
// convention as given; `--sinex` output asks for the joint covariance).
// Throws geoanchor::Error (usage) for options that contradict each other.
workflow::AdjustRequest network_request(const std::vector<std::string>& inputs, const NetworkOptions& o,
                                        const std::optional<std::string>& helmert_convention);

// The network read and prepared, and the model the network view draws
// (adjusted at once; awaited for large networks).
struct NetworkSession {
  workflow::PreparedNetwork prepared;
  solver::AdjustOptions options;
  std::unique_ptr<gui::NetworkModel> model;
};
NetworkSession open_network(const std::vector<std::string>& inputs, const NetworkOptions& o,
                            const std::optional<std::string>& helmert_convention);

}  // namespace geoanchor::cli
