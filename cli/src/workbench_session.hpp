#pragma once
// What the workbench commands (`gui`, `snapshot`, `report`) share: their
// common options and the opening of a control set, with a transform file's
// recorded fit choices, into a WorkbenchModel.

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "geoanchor/gui/workbench_model.hpp"
#include "geoanchor/gui/workbench_ui.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "network_options.hpp"

namespace CLI {
class App;
}

namespace geoanchor::cli {

struct WorkbenchOptions {
  // CONTROL: one control set; with --view network, the network's inputs
  // (as `adjust` takes them). check_workbench_inputs() sets `control`.
  std::vector<std::string> inputs;
  std::string control;    // a path, or "-" for standard input
  std::string transform;  // empty: none
  std::optional<std::string> model, convention, origin;
  std::optional<std::string> ellipsoid;  // default: each frame's (io::ControlReadOptions::ellipsoid)
  std::vector<std::string> argv;
  bool hash_control = false;  // fill WorkbenchSession::control_sha256 (report)
  // --view network: adjust's datum and statistics options.
  NetworkOptions network;
  std::vector<CLI::Option*> network_flags;
};

// CONTROL, --transform, --model, --convention, --origin, --ellipsoid, and
// for the network view adjust's --frame, --constrain, … (network_options.hpp).
void add_workbench_options(CLI::App* cmd, WorkbenchOptions& o);

// The view named on the command line, "network" among them.
inline constexpr const char* kNetworkView = "network";

// Checks that the inputs and flags belong to the view asked for (a fit's
// views: one control set and the fit's options; the network view: the
// network's inputs and adjust's options, --convention only with
// --estimate-helmert) and sets `control`. Throws geoanchor::Error (usage)
// naming the flag.
void check_workbench_inputs(WorkbenchOptions& o, bool network_view);

struct WorkbenchSession {
  std::optional<io::TransformFile> transform;
  std::unique_ptr<gui::WorkbenchModel> model;
  // Notes for the report and standard error: where the choices came from,
  // and how far the transform file's parameters are from the refit.
  std::vector<std::string> notes;
  std::string save_path;  // proposed by Save transform…
  std::string generator;
  std::string control_name;    // "<stdin>" or the path
  std::string control_sha256;  // with WorkbenchOptions::hash_control
};

// "--view NAME" and "--size WIDTHxHEIGHT" (pixels, gui::kMinimumWidth_px ×
// gui::kMinimumHeight_px … 8192 × 8192), shared
// by the window and the off-screen commands. Throw geoanchor::Error (usage).
gui::View parse_view(const std::string& text, std::string_view flag);
std::pair<int, int> parse_size(const std::string& text, std::string_view flag);

// Choices: --model/--convention, else the transform file's, else helmert7 in
// the position-vector convention (the workbench shows it and lets the user
// switch). The fit runs at once (waits for large sets). Throws
// geoanchor::Error naming the file or flag, and for a command line that is
// not UTF-8 (it is recorded as the generator of a saved transform).
WorkbenchSession open_workbench(const WorkbenchOptions& o);

}  // namespace geoanchor::cli
