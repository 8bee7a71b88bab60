#include "snapshot_command.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <algorithm>
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
#include "command_input.hpp"
#include "option_parsing.hpp"
#include "version.hpp"

namespace geoanchor::cli {
namespace fs = std::filesystem;

namespace {

using nlohmann::ordered_json;

// The notes and warnings print_notes() shows, for --json.
std::vector<std::string> session_warnings(const WorkbenchSession& s) {
  if (!s.model->fit()) return {"no fit: " + s.model->error()};
  return gui::shown_warnings(*s.model->fit());
}

void print_json(const ordered_json& j) {
  std::cout << j.dump(2) << '\n';
  io::finish_standard_output("the JSON report (--json)");
}

void print_notes(const WorkbenchSession& s) {
  for (const auto& n : s.notes) std::cerr << "geoanchor: note: " << n << '\n';
  if (!s.model->fit()) {
    std::cerr << "geoanchor: warning: no fit: " << s.model->error() << " (the pictures show why)\n";
    return;
  }
  for (const auto& w : gui::shown_warnings(*s.model->fit())) std::cerr << "geoanchor: warning: " << w << '\n';
}

// The report's table pages: table.png, table-2.png, …
std::string table_page_name(std::size_t page) { return page == 1 ? "table.png" : "table-" + std::to_string(page) + ".png"; }

// Whether `name` is a table page other than the first (table-N.png, N ≥ 2).
bool is_later_table_page(const std::string& name) {
  if (!name.starts_with("table-") || !name.ends_with(".png") || name.size() <= 10) return false;
  const std::string n = name.substr(6, name.size() - 10);
  return std::all_of(n.begin(), n.end(), [](char c) { return c >= '0' && c <= '9'; }) && n.front() != '0';
}

std::string joined(const std::vector<std::string>& ids) {
  std::string out;
  for (const auto& id : ids) out += (out.empty() ? "" : ", ") + id;
  return out;
}

}  // namespace

CLI::App* add_snapshot_command(CLI::App& app, SnapshotOptions& o) {
  auto* cmd = app.add_subcommand("snapshot", "Render a workbench view to a PNG, off-screen (no display, no GPU)");
  add_workbench_options(cmd, o.workbench);
  cmd->add_option("--view", o.view, "workbench|plan|histogram|table|parameters|comparison (default workbench)");
  cmd->add_option("--size", o.size, "WIDTHxHEIGHT in pixels (default 1600x1000)");
  cmd->add_option("-o,--output", o.output, "PNG to write, or - for standard output")->required();
  cmd->add_flag("--overwrite", o.overwrite, "Replace an existing output");
  cmd->add_flag("--json", o.json, "Print what was written as JSON (schema geoanchor.snapshot/1) on standard output");
  return cmd;
}

CLI::App* add_report_command(CLI::App& app, ReportOptions& o) {
  auto* cmd = app.add_subcommand("report", "Write a fit's text report and a PNG of every workbench view into a folder");
  add_workbench_options(cmd, o.workbench);
  cmd->add_option("--size", o.size, "WIDTHxHEIGHT of the pictures (default 1600x1000)");
  cmd->add_option("-o,--output", o.output, "Folder to write (created; refused if it holds report files, unless --overwrite)")
      ->required();
  cmd->add_flag("--overwrite", o.overwrite, "Replace report files already in the folder");
  cmd->add_flag("--json", o.json, "Print what was written as JSON (schema geoanchor.report/1) on standard output");
  return cmd;
}

int run_snapshot(const SnapshotOptions& o) {
  const gui::View view = parse_view(o.view, "--view");
  const auto [w, h] = parse_size(o.size, "--size");
  // -o -: the PNG on standard output, what was written on standard error.
  const bool to_stdout = o.output == "-";
  if (to_stdout && o.json) {
    throw Error(ErrorKind::usage, "E_OPTION", "--json and -o -: both would go to standard output; give -o FILE.png");
  }
  if (!to_stdout && fs::path(o.output).extension() != ".png") {
    throw Error(ErrorKind::usage, "E_OPTION", "-o " + o.output + ": expected a file name ending in .png, or - for standard output");
  }
  if (!to_stdout && o.workbench.control != "-") io::refuse_same_file(o.workbench.control, o.output);
  // A FIFO, a device or a folder is refused even with --overwrite.
  if (!to_stdout) io::check_output_path(o.output, io::Overwrite::allow);
  if (!to_stdout && !o.overwrite && fs::exists(fs::symlink_status(o.output))) {
    throw Error(ErrorKind::io, "E_OUTPUT_EXISTS", o.output + ": exists (use --overwrite to replace it)");
  }
  WorkbenchSession s = open_workbench(o.workbench);
  print_notes(s);
  gui::OffscreenRenderer renderer(w, h);
  gui::WorkbenchUi ui(*s.model, {s.save_path, s.generator});
  std::size_t bytes = 0;
  {
    const std::string png = gui::encode_png(renderer.render(ui, view), to_stdout ? "<stdout>" : o.output);
    bytes = png.size();
    CommandOutput out(o.output, o.overwrite);
    out.stream().write(png.data(), static_cast<std::streamsize>(png.size()));
    out.commit();
  }
  const gui::TableGeometry& t = ui.table();
  const bool partial_table = t.drawn && t.total > 0 && t.shown_ids.size() < t.total;
  if (o.json) {
    ordered_json j;
    j["schema"] = "geoanchor.snapshot/1";
    j["control"] = s.control_name;
    j["output"] = o.output;
    j["bytes"] = bytes;
    j["view"] = std::string(gui::to_string(view));
    j["width_px"] = w;
    j["height_px"] = h;
    j["table"] = t.drawn ? ordered_json{{"first", t.total > 0 && !t.shown_ids.empty() ? t.first + 1 : 0},
                                        {"shown", t.shown_ids.size()},
                                        {"total", t.total}}
                         : ordered_json(nullptr);
    j["notes"] = s.notes;
    j["warnings"] = session_warnings(s);
    print_json(j);
    return 0;
  }
  std::ostream& said = to_stdout ? std::cerr : std::cout;
  said << "wrote " << (to_stdout ? "<stdout>" : o.output) << " (" << w << "x" << h << ", view " << gui::to_string(view);
  if (partial_table) {
    said << "; the table shows " << (t.shown_ids.empty() ? "no whole row" : "marks " + std::to_string(t.first + 1) + "–" +
                                                             std::to_string(t.first + t.shown_ids.size()))
         << " of " << t.total << ": `geoanchor report` pages them all";
  }
  said << ")\n";
  if (!to_stdout) io::finish_standard_output("the line \"wrote " + o.output + "\"", "; " + o.output + " was written");
  return 0;
}

int run_report(const ReportOptions& o) {
  if (o.output == "-") {
    throw Error(ErrorKind::usage, "E_OPTION",
                "-o -: report writes a folder (report.txt and a PNG per view), which standard output cannot hold; give "
                "a folder (snapshot -o - writes one view's PNG on standard output)");
  }
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
  // The table's later pages (table-2.png, …) are report files too.
  std::vector<fs::path> earlier_pages;
  if (fs::is_directory(dir)) {
    for (const auto& e : fs::directory_iterator(dir)) {
      if (is_later_table_page(e.path().filename().string())) earlier_pages.push_back(e.path());
    }
    std::sort(earlier_pages.begin(), earlier_pages.end());
  }
  for (const auto& n : names) {
    io::check_output_path(dir / n, io::Overwrite::allow);  // a FIFO, a device or a folder is refused even with --overwrite
    if (!o.overwrite && fs::exists(fs::symlink_status(dir / n))) {
      throw Error(ErrorKind::io, "E_OUTPUT_EXISTS", (dir / n).string() + ": exists (use --overwrite to replace the report)");
    }
  }
  if (!o.overwrite && !earlier_pages.empty()) {
    throw Error(ErrorKind::io, "E_OUTPUT_EXISTS", earlier_pages.front().string() + ": exists (use --overwrite to replace the report)");
  }
  WorkbenchOptions wo = o.workbench;
  wo.hash_control = true;
  WorkbenchSession s = open_workbench(wo);
  print_notes(s);

  // Everything is made in memory first, then written file by file
  // (each atomically); a failure removes what this run wrote.
  std::ostringstream text;
  text << "geoanchor report\n"
       << "  generator: " << s.generator << "\n"
       << "  control:   " << s.control_name << " (sha256 " << s.control_sha256 << ")\n"
       << "  transform: " << o.workbench.transform << " (sha256 " << io::sha256_file_hex(o.workbench.transform) << ")\n";
  for (const auto& n : s.notes) text << "  note: " << n << "\n";
  text << "\n";
  if (s.model->fit()) {
    workflow::write_fit_report(text, *s.model->fit(), s.model->control(), s.model->options());
    // Without advice to fit the model this report is about.
    const std::vector<std::string> warnings = gui::shown_warnings(*s.model->fit());
    if (!warnings.empty()) text << "\nWarnings\n";
    for (const auto& warning : warnings) text << "  " << warning << "\n";
  } else {
    text << "No fit: " << s.model->error() << "\n";
  }
  text << "\nModel comparison (same points, data snooping off; ▶ the model fitted)\n"
       << "    model                u    dof      σ0   global test   max|w|        AIC\n";
  for (const auto& c : s.model->comparison()) {
    char line[200];
    const std::string name(solver::to_string(c.model));
    const char* mark = c.model == s.model->options().model ? "  ▶ " : "    ";
    if (!c.fit) {
      text << mark << name << ": refused: " << c.refused << "\n";
      continue;
    }
    const auto& g = c.fit->global_test;
    std::snprintf(line, sizeof line, "%s%-18s %3d %6d %8s   %-11s %8.2f %10.1f\n", mark, name.c_str(), c.parameters, c.fit->dof,
                  (c.fit->sigma0 ? format_fixed(*c.fit->sigma0, 3) : std::string("undef")).c_str(), !g.applicable ? "n/a" : g.passed ? "PASSED" : "FAILED", c.max_w, c.aic);
    text << line;
  }
  for (const auto& c : s.model->comparison()) {
    if (!c.note.empty()) text << "  (" << solver::to_string(c.model) << ": " << c.note << ")\n";
  }
  {
    std::string lowest;
    for (const auto m : solver::lowest_aic(s.model->comparison())) lowest += (lowest.empty() ? "" : " and ") + std::string(solver::to_string(m));
    if (!lowest.empty()) text << "  lowest AIC: " << lowest << "\n";
  }
  text << "\nFigures (" << w << "x" << h << " px)\n";
  gui::OffscreenRenderer renderer(w, h);
  gui::WorkbenchUi ui(*s.model, {s.save_path, s.generator});
  // PNG-encoded at once: a 10⁴-mark report has some 300 table pages.
  std::vector<std::pair<std::string, std::string>> images;
  for (gui::View v : gui::kAllViews) {
    if (v == gui::View::table) {
      // As many pages as the marks need: each holds the rows wholly in view.
      std::size_t start = 0;
      for (std::size_t page = 1;; ++page) {
        ui.set_table_start(start);
        images.emplace_back(table_page_name(page), gui::encode_png(renderer.render(ui, v), table_page_name(page)));
        const gui::TableGeometry& t = ui.table();
        if (t.total == 0) {
          text << "  " << images.back().first << ": no marks\n";
          break;
        }
        if (t.shown_ids.empty() || t.first != start) {
          throw Error(ErrorKind::usage, "E_OPTION",
                      "--size " + o.size + ": the table has no room for a whole row; expected a larger size");
        }
        text << "  " << images.back().first << ": marks " << t.first + 1 << "–" << t.first + t.shown_ids.size() << " of " << t.total
             << " (sorted by " << t.sorted_by << "): " << joined(t.shown_ids) << "\n";
        start = t.first + t.shown_ids.size();
        if (start >= t.total) break;
      }
      ui.set_table_start(0);
      continue;
    }
    const std::string name = std::string(gui::to_string(v)) + ".png";
    images.emplace_back(name, gui::encode_png(renderer.render(ui, v), name));
    text << "  " << images.back().first;
    if (v == gui::View::workbench && ui.table().drawn && ui.table().total > 0) {
      const gui::TableGeometry& t = ui.table();
      text << ": its table panel shows " << (t.shown_ids.size() == t.total ? "all " + std::to_string(t.total) + " marks"
                                                                            : "marks " + std::to_string(t.first + 1) + "–" +
                                                                                  std::to_string(t.first + t.shown_ids.size()) + " of " +
                                                                                  std::to_string(t.total))
           << " (every mark is on the table pages)";
    }
    if (v == gui::View::plan && ui.plan().drawn) {
      const gui::PlanGeometry& g = ui.plan();
      text << ": residual arrows × " << g.arrow_exaggeration << ", scale bar " << g.scale_bar_m
           << " m, vertical residual colour ±" << g.du_limit_mm << " mm";
      if (g.ellipses_drawn > 0) {
        text << "; " << g.ellipses_drawn << " residual ellipses (" << 100.0 * gui::kEllipseProbability << " %, "
             << format_fixed(g.ellipse_k, 4) << " σ of the a-posteriori residual covariance) at the arrows' factor";
      }
      const std::size_t marks = s.model->control().points.size();
      if (marks > gui::kDensePlanMarks) {
        text << "; a dense plan (more than " << gui::kDensePlanMarks << " marks): no ellipses, only the outliers' ids ("
             << g.labels.size() << " labelled)";
      } else {
        text << "; " << g.labels.size() << " of " << marks << " marks labelled with their id";
      }
      if (!g.unlabelled.empty()) text << " (no room for " << joined(g.unlabelled) << ": named or counted under the plan)";
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
    for (const auto& [name, png] : images) {
      io::AtomicOutputFile out(dir / name, o.overwrite ? io::Overwrite::allow : io::Overwrite::refuse);
      out.stream().write(png.data(), static_cast<std::streamsize>(png.size()));
      out.commit();
      written.push_back(dir / name);
    }
  } catch (...) {
    for (const auto& p : written) fs::remove(p, ec);
    if (created) fs::remove(dir, ec);
    throw;
  }
  // An earlier report's table pages beyond this one's would be read as this one's.
  for (const auto& p : earlier_pages) {
    if (std::none_of(images.begin(), images.end(), [&](const auto& i) { return dir / i.first == p; })) fs::remove(p, ec);
  }
  std::size_t pages = 0;
  for (const auto& i : images) pages += i.first.starts_with("table") ? 1u : 0u;
  if (o.json) {
    ordered_json j;
    j["schema"] = "geoanchor.report/1";
    j["control"] = s.control_name;
    j["transform"] = o.workbench.transform;
    j["folder"] = o.output;
    ordered_json files = ordered_json::array();
    files.push_back({{"name", "report.txt"}, {"bytes", text.str().size()}});
    for (const auto& [name, png] : images) files.push_back({{"name", name}, {"bytes", png.size()}});
    j["files"] = std::move(files);
    j["table_pages"] = pages;
    j["fit"] = s.model->fit().has_value();
    j["notes"] = s.notes;
    j["warnings"] = session_warnings(s);
    print_json(j);
    return 0;
  }
  std::cout << "wrote " << o.output << (o.output.ends_with('/') ? "" : "/") << ": report.txt and " << images.size()
            << " PNG views (the table on " << pages
            << (pages == 1 ? " page" : " pages") << ")\n";
  io::finish_standard_output("the line \"wrote " + o.output + "\"", "; the report was written");
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
