#include "snapshot_command.hpp"

#include <CLI/CLI.hpp>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "geoanchor/geodesy/error.hpp"
#include "geoanchor/geodesy/number_text.hpp"
#include "geoanchor/workflow/fit_export.hpp"
#include "geoanchor/gui/offscreen.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/io/hash.hpp"
#include "option_parsing.hpp"
#include "version.hpp"

namespace geoanchor::cli {
namespace fs = std::filesystem;

namespace {

void print_notes(const WorkbenchSession& s) {
  for (const auto& n : s.notes) std::cerr << "geoanchor: note: " << n << '\n';
  if (!s.model->fit()) {
    std::cerr << "geoanchor: warning: no fit: " << s.model->error() << " (the pictures show why)\n";
    return;
  }
  for (const auto& w : s.model->fit()->warnings) std::cerr << "geoanchor: warning: " << w << '\n';
}

}  // namespace

CLI::App* add_snapshot_command(CLI::App& app, SnapshotOptions& o) {
  auto* cmd = app.add_subcommand("snapshot", "Render a workbench view to a PNG, off-screen (no display, no GPU)");
  add_workbench_options(cmd, o.workbench);
  cmd->add_option("--view", o.view, "workbench|plan|histogram|table|parameters|comparison (default workbench)");
  cmd->add_option("--size", o.size, "WIDTHxHEIGHT in pixels (default 1600x1000)");
  cmd->add_option("-o,--output", o.output, "PNG to write")->required();
  cmd->add_flag("--overwrite", o.overwrite, "Replace an existing output");
  return cmd;
}

CLI::App* add_report_command(CLI::App& app, ReportOptions& o) {
  auto* cmd = app.add_subcommand("report", "Write a fit's text report and a PNG of every workbench view into a folder");
  add_workbench_options(cmd, o.workbench);
  cmd->add_option("--size", o.size, "WIDTHxHEIGHT of the pictures (default 1600x1000)");
  cmd->add_option("-o,--output", o.output, "Folder to write (created; refused if it holds report files, unless --overwrite)")
      ->required();
  cmd->add_flag("--overwrite", o.overwrite, "Replace report files already in the folder");
  return cmd;
}

int run_snapshot(const SnapshotOptions& o) {
  const gui::View view = parse_view(o.view, "--view");
  const auto [w, h] = parse_size(o.size, "--size");
  if (fs::path(o.output).extension() != ".png") {
    throw Error(ErrorKind::usage, "E_OPTION", "-o " + o.output + ": expected a file name ending in .png");
  }
  io::refuse_same_file(o.workbench.control, o.output);
  if (!o.overwrite && fs::exists(o.output)) {
    throw Error(ErrorKind::io, "E_OUTPUT_EXISTS", o.output + ": exists (use --overwrite to replace it)");
  }
  WorkbenchSession s = open_workbench(o.workbench);
  print_notes(s);
  gui::OffscreenRenderer renderer(w, h);
  gui::WorkbenchUi ui(*s.model, {s.save_path, s.generator});
  gui::write_png(renderer.render(ui, view), o.output, o.overwrite);
  std::cout << "wrote " << o.output << " (" << w << "x" << h << ", view " << gui::to_string(view) << ")\n";
  return 0;
}

int run_report(const ReportOptions& o) {
  const auto [w, h] = parse_size(o.size, "--size");
  if (o.workbench.transform.empty()) {
    throw Error(ErrorKind::usage, "E_OPTION", "--transform: required (the transform file the report is about)");
  }
  const fs::path dir(o.output);
  std::vector<std::string> names{"report.txt"};
  for (gui::View v : gui::kAllViews) names.push_back(std::string(gui::to_string(v)) + ".png");
  if (fs::exists(dir) && !fs::is_directory(dir)) {
    throw Error(ErrorKind::io, "E_OUTPUT_EXISTS", o.output + ": exists and is not a folder");
  }
  for (const auto& n : names) {
    if (!o.overwrite && fs::exists(dir / n)) {
      throw Error(ErrorKind::io, "E_OUTPUT_EXISTS", (dir / n).string() + ": exists (use --overwrite to replace the report)");
    }
  }
  WorkbenchSession s = open_workbench(o.workbench);
  print_notes(s);

  // Everything is made in memory first, then written file by file
  // (each atomically); a failure removes what this run wrote.
  std::ostringstream text;
  text << "geoanchor report\n"
       << "  generator: " << s.generator << "\n"
       << "  control:   " << o.workbench.control << " (sha256 " << io::sha256_file_hex(o.workbench.control) << ")\n"
       << "  transform: " << o.workbench.transform << " (sha256 " << io::sha256_file_hex(o.workbench.transform) << ")\n";
  for (const auto& n : s.notes) text << "  note: " << n << "\n";
  text << "\n";
  if (s.model->fit()) {
    workflow::write_fit_report(text, *s.model->fit(), s.model->control(), s.model->options());
    if (!s.model->fit()->warnings.empty()) text << "\nWarnings\n";
    for (const auto& warning : s.model->fit()->warnings) text << "  " << warning << "\n";
  } else {
    text << "No fit: " << s.model->error() << "\n";
  }
  text << "\nModel comparison (same points, data snooping off)\n  model              u    dof      σ0   global test   max|w|        AIC\n";
  for (const auto& c : s.model->comparison()) {
    char line[200];
    const std::string name(solver::to_string(c.model));
    if (!c.fit) {
      text << "  " << name << ": refused: " << c.refused << "\n";
      continue;
    }
    const auto& g = c.fit->global_test;
    std::snprintf(line, sizeof line, "  %-16s %3d %6d %8s   %-11s %8.2f %10.1f\n", name.c_str(), c.parameters, c.fit->dof,
                  (c.fit->sigma0 ? format_fixed(*c.fit->sigma0, 3) : std::string("undef")).c_str(), !g.applicable ? "n/a" : g.passed ? "PASSED" : "FAILED", c.max_w, c.aic);
    text << line;
  }
  text << "\nFigures (" << w << "x" << h << " px)\n";
  gui::OffscreenRenderer renderer(w, h);
  gui::WorkbenchUi ui(*s.model, {s.save_path, s.generator});
  std::vector<std::pair<std::string, gui::RgbImage>> images;
  for (gui::View v : gui::kAllViews) {
    images.emplace_back(std::string(gui::to_string(v)) + ".png", renderer.render(ui, v));
    text << "  " << images.back().first;
    if (v == gui::View::plan && ui.plan().drawn) {
      text << ": residual arrows × " << ui.plan().arrow_exaggeration << ", scale bar " << ui.plan().scale_bar_m
           << " m, vertical residual colour ±" << ui.plan().du_limit_mm << " mm";
    }
    text << "\n";
  }

  const bool created = !fs::exists(dir);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw Error(ErrorKind::io, "E_WRITE", o.output + ": cannot create folder: " + ec.message());
  std::vector<fs::path> written;
  try {
    {
      io::AtomicOutputFile out(dir / "report.txt", o.overwrite ? io::Overwrite::allow : io::Overwrite::refuse);
      out.stream() << text.str();
      out.commit();
      written.push_back(dir / "report.txt");
    }
    for (const auto& [name, image] : images) {
      gui::write_png(image, dir / name, o.overwrite);
      written.push_back(dir / name);
    }
  } catch (...) {
    for (const auto& p : written) fs::remove(p, ec);
    if (created) fs::remove(dir, ec);
    throw;
  }
  std::cout << "wrote " << o.output << "/: report.txt and " << images.size() << " PNG views\n";
  return 0;
}

int exec_gui_window(int argc, char** argv) {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  const fs::path window = (ec ? fs::path(argv[0]).parent_path() : self.parent_path()) / "geoanchor-gui";
  if (!fs::exists(window)) {
    std::cerr << "geoanchor: error[E_GUI_MISSING]: " << window.string()
              << ": not found (the window is built with -DGEOANCHOR_BUILD_GUI=ON; `geoanchor snapshot` renders without it)\n";
    return exit_code(ErrorKind::usage);
  }
  std::vector<char*> args;
  std::string name = window.string();
  args.push_back(name.data());
  for (int i = 2; i < argc; ++i) args.push_back(argv[i]);
  args.push_back(nullptr);
  execv(name.c_str(), args.data());
  std::cerr << "geoanchor: error[E_GUI_START]: " << name << ": cannot start: " << std::strerror(errno) << "\n";
  return exit_code(ErrorKind::io);
}

}  // namespace geoanchor::cli
