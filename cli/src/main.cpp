// The geoanchor executable: one subcommand per capability.
// Errors print as `geoanchor: error[CODE]: message` and exit with a code
// per kind: 2 usage, 3 bad input, 4 rejected result, 5 I/O (listed in every
// --help). `help [COMMAND]` and `version` answer as --help and --version.

#include <CLI/CLI.hpp>

#include <functional>
#include <iostream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "adjust_command.hpp"
#include "apply_command.hpp"
#include "audit_command.hpp"
#include "command_input.hpp"
#include "convert_command.hpp"
#include "crs_command.hpp"
#include "diagnose_command.hpp"
#include "fit_command.hpp"
#include "option_parsing.hpp"
#include "snapshot_command.hpp"
#include "transform_command.hpp"
#include "usage_hints.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "huge_pages.hpp"
#include "version.hpp"

namespace {
// Help and the version go to standard output like every result: one that
// cannot be written is an error (exit 5), as for the other commands.
int printed(int cli11_exit, std::string_view what) {
  try {
    geoanchor::io::finish_standard_output(what);
  } catch (const geoanchor::Error& e) {
    std::cerr << "geoanchor: error[" << e.code() << "]: " << e.what() << '\n';
    return geoanchor::exit_code(e.kind());
  }
  return cli11_exit;
}
}  // namespace

int main(int argc, char** argv) {
  using geoanchor::Error;
  using geoanchor::ErrorKind;
  // (adjust alone: the restart costs a start of the program, some 60 ms,
  // and adjust is the command that touches gigabytes of fresh memory.)
  if (argc > 1 && std::string_view(argv[1]) == "adjust") geoanchor::cli::restart_with_huge_pages(argv);
  geoanchor::io::install_signal_cleanup();
  std::vector<std::string> words(argv, argv + argc);
  try {
    geoanchor::cli::require_utf8_arguments(words);
  } catch (const Error& e) {
    std::cerr << "geoanchor: error[" << e.code() << "]: " << e.what() << '\n';
    return geoanchor::exit_code(e.kind());
  }

  // `geoanchor version`, `geoanchor help` and `geoanchor help COMMAND`, as
  // git, gdal and proj users type them: the same as --version, --help and
  // `geoanchor COMMAND --help`.
  const bool help_topic = words.size() == 3 && words[1] == "help";
  if (words.size() == 2 && words[1] == "version") {
    words[1] = "--version";
  } else if (words.size() == 2 && words[1] == "help") {
    words[1] = "--help";
  } else if (help_topic) {
    words = {words[0], words[2], "--help"};
  }
  std::vector<char*> args;
  for (auto& w : words) args.push_back(w.data());
  args.push_back(nullptr);
  argc = static_cast<int>(words.size());
  argv = args.data();

  // The window is its own executable (libGL and libOSMesa cannot share one).
  if (argc > 1 && std::string_view(argv[1]) == "gui") return geoanchor::cli::exec_gui_window(argc, argv);

  CLI::App app{"geoanchor " GEOANCHOR_VERSION ": anchor local maps to the Earth", "geoanchor"};
  app.set_version_flag("--version", "geoanchor " GEOANCHOR_VERSION);
  app.footer(geoanchor::cli::kExitCodeHelp);  // inherited by every subcommand added below
  app.require_subcommand(1);
  geoanchor::cli::ConvertOptions convert;
  convert.argv.assign(argv, argv + argc);
  auto* convert_cmd = geoanchor::cli::add_convert_command(app, convert);
  geoanchor::cli::FitCommandOptions fit;
  fit.argv.assign(argv, argv + argc);
  auto* fit_cmd = geoanchor::cli::add_fit_command(app, fit);
  geoanchor::cli::AdjustCommandOptions adjust;
  adjust.argv.assign(argv, argv + argc);
  auto* adjust_cmd = geoanchor::cli::add_adjust_command(app, adjust);
  geoanchor::cli::ApplyOptions apply;
  apply.argv.assign(argv, argv + argc);
  auto* apply_cmd = geoanchor::cli::add_apply_command(app, apply);
  geoanchor::cli::TransformOptions transform;
  transform.argv.assign(argv, argv + argc);
  auto* transform_cmd = geoanchor::cli::add_transform_command(app, transform);
  geoanchor::cli::CrsCommandOptions crs;
  auto* crs_cmd = geoanchor::cli::add_crs_command(app, crs);
  geoanchor::cli::DiagnoseCommandOptions diagnose;
  auto* diagnose_cmd = geoanchor::cli::add_diagnose_command(app, diagnose);
  geoanchor::cli::SnapshotOptions snapshot;
  snapshot.workbench.argv.assign(argv, argv + argc);
  auto* snapshot_cmd = geoanchor::cli::add_snapshot_command(app, snapshot);
  geoanchor::cli::ReportOptions report;
  report.workbench.argv.assign(argv, argv + argc);
  auto* report_cmd = geoanchor::cli::add_report_command(app, report);
  geoanchor::cli::AuditCommandOptions audit;
  auto* audit_cmd = geoanchor::cli::add_audit_command(app, audit);
  geoanchor::cli::LocateCommandOptions locate;
  auto* locate_cmd = geoanchor::cli::add_locate_command(app, locate);
  // Listed for --help; `geoanchor gui ...` is handed to geoanchor-gui above.
  app.add_subcommand("gui", "Open the residual workbench window (geoanchor-gui; same options as snapshot, no -o)");
  // Listed for --help; rewritten to --help and --version above.
  app.add_subcommand("help", "Print this help, or a command's: geoanchor help fit (= geoanchor fit --help)");
  app.add_subcommand("version", "Print geoanchor's version (= geoanchor --version)");
  if (help_topic && std::string_view(argv[1]) != "gui") {
    bool known = false;
    std::string names;
    for (const CLI::App* sub : std::as_const(app).get_subcommands(std::function<bool(const CLI::App*)>())) {
      known = known || sub->get_name() == argv[1];
      names += (names.empty() ? "" : ", ") + sub->get_name();
    }
    if (!known) {
      std::vector<std::string> all;
      for (const CLI::App* sub : std::as_const(app).get_subcommands(std::function<bool(const CLI::App*)>())) {
        all.push_back(sub->get_name());
      }
      const std::string near = geoanchor::cli::nearest_name(argv[1], all);
      std::cerr << "geoanchor: error[E_USAGE]: help " << argv[1] << ": no such command"
                << (near.empty() ? "" : "; did you mean '" + near + "'?") << "; expected one of " << names
                << "\n(run 'geoanchor --help')\n";
      return geoanchor::exit_code(ErrorKind::usage);
    }
  }

  if (const std::string wrong = geoanchor::cli::single_dash_long_option(app, std::vector<std::string>(argv + 1, argv + argc));
      !wrong.empty()) {
    std::cerr << "geoanchor: error[E_USAGE]: " << wrong << "\n(run 'geoanchor --help')\n";
    return geoanchor::exit_code(ErrorKind::usage);
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return printed(app.exit(e), "the help");
  } catch (const CLI::CallForAllHelp& e) {
    return printed(app.exit(e), "the help");
  } catch (const CLI::CallForVersion& e) {
    return printed(app.exit(e), "the version");
  } catch (const CLI::ParseError& e) {
    const std::vector<std::string> words_after(argv + 1, argv + argc);
    std::cerr << "geoanchor: error[E_USAGE]: " << geoanchor::cli::usage_hint(app, words_after, e.what()) << "\n(run '"
              << geoanchor::cli::help_command(app) << "')\n";
    return geoanchor::exit_code(ErrorKind::usage);
  }

  try {
    if (convert_cmd->parsed()) geoanchor::cli::run_convert(convert);
    if (fit_cmd->parsed()) return geoanchor::cli::run_fit(fit);
    if (apply_cmd->parsed()) return geoanchor::cli::run_apply(apply);
    if (adjust_cmd->parsed()) return geoanchor::cli::run_adjust(adjust);
    if (transform_cmd->parsed()) geoanchor::cli::run_transform(transform);
    if (crs_cmd->parsed()) geoanchor::cli::run_crs(crs);
    if (diagnose_cmd->parsed()) geoanchor::cli::run_diagnose(diagnose);
    if (snapshot_cmd->parsed()) return geoanchor::cli::run_snapshot(snapshot);
    if (report_cmd->parsed()) return geoanchor::cli::run_report(report);
    if (audit_cmd->parsed()) return geoanchor::cli::run_audit(audit);
    if (locate_cmd->parsed()) geoanchor::cli::run_locate(locate);
  } catch (const Error& e) {
    std::cerr << "geoanchor: error[" << e.code() << "]: " << e.what() << '\n';
    return geoanchor::exit_code(e.kind());
  } catch (const std::exception& e) {
    std::cerr << "geoanchor: error[E_INTERNAL]: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
