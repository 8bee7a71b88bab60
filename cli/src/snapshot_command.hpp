#pragma once
// The off-screen workbench commands: `geoanchor snapshot` (one view as a
// PNG) and `geoanchor report` (the text report and a PNG of every view).
// See docs/commands/snapshot.md and docs/commands/report.md. `geoanchor gui`
// starts the window, geoanchor-gui, found beside this executable.

#include <string>

#include "workbench_session.hpp"

namespace CLI {
class App;
}

namespace geoanchor::cli {

struct SnapshotOptions {
  WorkbenchOptions workbench;
  std::string view = "workbench";
  std::string size = "1600x1000";
  std::string output;  // a .png path, or "-" for standard output
  bool overwrite = false;
  bool json = false;   // what was written, as JSON on standard output
};

struct ReportOptions {
  WorkbenchOptions workbench;
  std::string view;  // empty: a fit's report; "network": a survey network's
  std::string size = "1600x1000";
  std::string output;  // a folder
  bool overwrite = false;
  bool json = false;   // what was written, as JSON on standard output
};

CLI::App* add_snapshot_command(CLI::App& app, SnapshotOptions& o);
CLI::App* add_report_command(CLI::App& app, ReportOptions& o);
int run_snapshot(const SnapshotOptions& o);
int run_report(const ReportOptions& o);
// Replaces this process with geoanchor-gui (argv after "gui"); returns only
// on failure, with the exit code.
int exec_gui_window(int argc, char** argv);

}  // namespace geoanchor::cli
