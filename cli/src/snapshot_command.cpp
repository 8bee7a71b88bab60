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

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/workflow/fit_export.hpp"
#include "geoanchor/gui/offscreen.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/base/hash.hpp"
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

std::string joined(const std::vector<std::string>& ids);

// The network view's notes and warnings: what was done to the inputs, and
// why there is no adjustment.
std::vector<std::string> network_notes(const NetworkSession& s) {
  std::vector<std::string> out;
  for (const auto& n : s.prepared.notes) {
    if (!n.starts_with("warning: ")) out.push_back(n);
  }
  return out;
}

std::vector<std::string> network_warnings(const NetworkSession& s) {
  std::vector<std::string> out;
  for (const auto& n : s.prepared.notes) {
    if (n.starts_with("warning: ")) out.push_back(n.substr(9));
  }
  if (!s.model->result()) {
    out.push_back("no adjustment: " + s.model->error());
    return out;
  }
  const auto& r = *s.model->result();
  for (const auto& w : r.warnings) out.push_back(w);
  if (!r.refused_because.empty() && std::find(out.begin(), out.end(), r.refused_because) == out.end()) out.push_back(r.refused_because);
  const auto& g = r.global_test;
  if (g.applicable && !g.passed) {
    out.push_back("the global test fails " + std::string(g.failed_high() ? "high" : "low") + " (" + format_fixed(g.statistic, 3) +
                  " outside [" + format_fixed(g.critical_lower, 3) + ", " + format_fixed(g.critical_upper, 3) + "])" +
                  (g.failed_high() ? ": `geoanchor adjust` would refuse to write its results" : ""));
  }
  return out;
}

void print_network_notes(const NetworkSession& s) {
  for (const auto& n : network_notes(s)) std::cerr << "geoanchor: note: " << n << '\n';
  for (const auto& w : network_warnings(s)) std::cerr << "geoanchor: warning: " << w << '\n';
}

// What the picture of the network view shows, in one line.
std::string network_figure_line(const gui::NetworkUi& ui, const NetworkSession& s) {
  const gui::NetworkGeometry& g = ui.plan();
  const double w_critical = s.model->w_critical();
  std::string line = std::to_string(s.model->network().stations.size()) + " stations, " +
                     std::to_string(s.model->network().measurements.size()) + " measurements (";
  for (std::size_t c = 0; c < gui::kMeasurementClasses; ++c) {
    line += (c ? ", " : "") + std::to_string(g.measurements_by_class[c]) + " " +
            gui::describe(static_cast<gui::MeasurementClass>(c), w_critical);
  }
  std::size_t lines = 0;
  for (std::size_t n : g.lines_by_class) lines += n;
  line += "), drawn as " + std::to_string(lines) + " lines";
  if (g.ellipses_drawn > 0) {
    line += "; " + std::to_string(g.ellipses_drawn) + " error ellipses at " + format_shortest(100.0 * g.confidence) + " % × " +
            format_shortest(g.ellipse_exaggeration);
  }
  if (!g.schematic) line += "; scale bar " + format_shortest(g.scale_bar_m) + " m";
  line += "; " + std::to_string(g.labelled_measurements.size()) + " outliers and failing measurements labelled";
  if (!g.unlabelled.empty()) line += "; no room for the ids of " + joined(g.unlabelled);
  return line;
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
  cmd->add_option("--view", o.view,
                  "workbench|plan|histogram|table|parameters|comparison (default workbench), or network: a survey network "
                  "adjusted as by adjust");
  cmd->add_option("--size", o.size, "WIDTHxHEIGHT in pixels (default 1600x1000)");
  cmd->add_option("-o,--output", o.output, "PNG to write, or - for standard output")->required();
  cmd->add_flag("--overwrite", o.overwrite, "Replace an existing output");
  cmd->add_flag("--json", o.json, "Print what was written as JSON (schema geoanchor.snapshot/1) on standard output");
  return cmd;
}

CLI::App* add_report_command(CLI::App& app, ReportOptions& o) {
  auto* cmd = app.add_subcommand("report", "Write a fit's text report and a PNG of every workbench view into a folder");
  add_workbench_options(cmd, o.workbench);
  cmd->add_option("--view", o.view, "network: report on a survey network (adjust's text report and the network view)");
  cmd->add_option("--size", o.size, "WIDTHxHEIGHT of the pictures (default 1600x1000)");
  cmd->add_option("-o,--output", o.output, "Folder to write (created; refused if it holds report files, unless --overwrite)")
      ->required();
  cmd->add_flag("--overwrite", o.overwrite, "Replace report files already in the folder");
  cmd->add_flag("--json", o.json, "Print what was written as JSON (schema geoanchor.report/1) on standard output");
  return cmd;
}

int run_snapshot(const SnapshotOptions& options) {
  SnapshotOptions o = options;
  const bool network = o.view == kNetworkView;
  check_workbench_inputs(o.workbench, network);
  const gui::View view = network ? gui::View::workbench : parse_view(o.view, "--view");
  const auto [w, h] = parse_size(o.size, "--size");
  // -o -: the PNG on standard output, what was written on standard error.
  const bool to_stdout = o.output == "-";
  if (to_stdout && o.json) {
    throw Error(ErrorKind::usage, "E_OPTION", "--json and -o -: both would go to standard output; give -o FILE.png");
  }
  if (!to_stdout && fs::path(o.output).extension() != ".png") {
    throw Error(ErrorKind::usage, "E_OPTION", "-o " + o.output + ": expected a file name ending in .png, or - for standard output");
  }
  if (!to_stdout) {
    for (const auto& in : o.workbench.inputs) {
      if (in != "-") io::refuse_same_file(in, o.output);
    }
  }
  // A FIFO, a device or a folder is refused even with --overwrite.
  if (!to_stdout) io::check_output_path(o.output, io::Overwrite::allow);
  if (!to_stdout && !o.overwrite && fs::exists(fs::symlink_status(o.output))) {
    throw Error(ErrorKind::io, "E_OUTPUT_EXISTS", o.output + ": exists (use --overwrite to replace it)");
  }
  std::optional<WorkbenchSession> s;
  std::optional<NetworkSession> ns;
  if (network) {
    ns = open_network(o.workbench.inputs, o.workbench.network, o.workbench.convention);
    print_network_notes(*ns);
  } else {
    s = open_workbench(o.workbench);
    print_notes(*s);
  }
  gui::OffscreenRenderer renderer(w, h);
  std::optional<gui::WorkbenchUi> ui;
  std::optional<gui::NetworkUi> network_ui;
  if (network) {
    network_ui.emplace(*ns->model);
  } else {
    ui.emplace(*s->model, gui::UiOptions{s->save_path, s->generator});
  }
  std::size_t bytes = 0;
  {
    const std::string where = to_stdout ? "<stdout>" : o.output;
    const std::string png = gui::encode_png(network ? renderer.render(*network_ui) : renderer.render(*ui, view), where);
    bytes = png.size();
    CommandOutput out(o.output, o.overwrite);
    out.stream().write(png.data(), static_cast<std::streamsize>(png.size()));
    out.commit();
  }
  const gui::TableGeometry t = network ? gui::TableGeometry{} : ui->table();
  const bool partial_table = t.drawn && t.total > 0 && t.shown_ids.size() < t.total;
  if (o.json) {
    ordered_json j;
    j["schema"] = "geoanchor.snapshot/1";
    j["control"] = network ? ordered_json(nullptr) : ordered_json(s->control_name);
    if (network) j["inputs"] = input_names(o.workbench.inputs);
    j["output"] = o.output;
    j["bytes"] = bytes;
    j["view"] = network ? std::string(kNetworkView) : std::string(gui::to_string(view));
    j["width_px"] = w;
    j["height_px"] = h;
    j["table"] = t.drawn ? ordered_json{{"first", t.total > 0 && !t.shown_ids.empty() ? t.first + 1 : 0},
                                        {"shown", t.shown_ids.size()},
                                        {"total", t.total}}
                         : ordered_json(nullptr);
    if (network) {
      const gui::NetworkGeometry& g = network_ui->plan();
      ordered_json classes, measurement_classes;
      for (std::size_t c = 0; c < gui::kMeasurementClasses; ++c) {
        const char* name = gui::to_string(static_cast<gui::MeasurementClass>(c));
        classes[name] = g.lines_by_class[c];
        measurement_classes[name] = g.measurements_by_class[c];
      }
      ordered_json labelled = ordered_json::array();
      for (std::size_t m : g.labelled_measurements) labelled.push_back(m + 1);
      j["network"] = {{"stations", ns->model->network().stations.size()},
                      {"measurements", ns->model->network().measurements.size()},
                      {"adjusted", ns->model->result().has_value()},
                      {"measurements_by_class", measurement_classes},
                      {"lines", classes},
                      {"ellipses", g.ellipses_drawn},
                      {"ellipse_exaggeration", g.ellipse_exaggeration},
                      {"confidence", g.confidence},
                      {"labelled_measurements", labelled}};
    }
    j["notes"] = network ? network_notes(*ns) : s->notes;
    j["warnings"] = network ? network_warnings(*ns) : session_warnings(*s);
    print_json(j);
    return 0;
  }
  std::ostream& said = to_stdout ? std::cerr : std::cout;
  said << "wrote " << (to_stdout ? "<stdout>" : o.output) << " (" << w << "x" << h << ", view "
       << (network ? std::string(kNetworkView) : std::string(gui::to_string(view)));
  if (network) said << ": " << network_figure_line(*network_ui, *ns);
  if (partial_table) {
    said << "; the table shows " << (t.shown_ids.empty() ? "no whole row" : "marks " + std::to_string(t.first + 1) + "–" +
                                                             std::to_string(t.first + t.shown_ids.size()))
         << " of " << t.total << ": `geoanchor report` pages them all";
  }
  said << ")\n";
  if (!to_stdout) io::finish_standard_output("the line \"wrote " + o.output + "\"", "; " + o.output + " was written");
  return 0;
}

namespace {

// A report made in memory first, then written file by file (each
// atomically; a failure removes what the run wrote).
struct ReportContents {
  std::ostringstream text;
  std::vector<std::pair<std::string, std::string>> images;  // file name, PNG (encoded at once: a 10⁴-mark report has some 300 table pages)
  ordered_json about;    // --json: what the report is about (control, inputs, transform, view)
  ordered_json outcome;  // --json: fit or adjusted, notes, warnings
  std::string figures;   // "wrote …: report.txt and N" + this
};

// report --view network: adjust's text report and the network view.
void network_report(const ReportOptions& o, int w, int h, ReportContents& out) {
  std::ostringstream& text = out.text;
  auto& images = out.images;
  const NetworkSession ns = open_network(o.workbench.inputs, o.workbench.network, o.workbench.convention);
  print_network_notes(ns);
  std::string cmd;
  for (const auto& a : o.workbench.argv) cmd += (cmd.empty() ? "" : " ") + a;
  text << "geoanchor report\n"
       << "  generator: geoanchor " GEOANCHOR_VERSION ": " << cmd << "\n";
  for (const auto& in : o.workbench.inputs) {
    text << "  input:     " << input_name(in)
         << (in == "-" ? std::string() : " (sha256 " + sha256_file_hex(in) + ")") << "\n";
  }
  for (const auto& warning : network_warnings(ns)) text << "  warning: " << warning << "\n";
  text << "\n";
  if (ns.model->result()) {
    text << workflow::report_text(ns.prepared, *ns.model->result(), ns.options);
  } else {
    text << "No adjustment: " << ns.model->error() << "\n";
  }
  text << "\nFigures (" << w << "x" << h << " px)\n";
  gui::OffscreenRenderer renderer(w, h);
  gui::NetworkUi ui(*ns.model);
  const std::string name = std::string(kNetworkView) + ".png";
  images.emplace_back(name, gui::encode_png(renderer.render(ui), name));
  text << "  " << name << ": " << network_figure_line(ui, ns) << "\n";
  out.about = {{"control", nullptr}, {"inputs", input_names(o.workbench.inputs)}, {"transform", nullptr}, {"view", kNetworkView}};
  out.outcome = {{"table_pages", 0}, {"fit", nullptr}, {"adjusted", ns.model->result().has_value()}, {"notes", network_notes(ns)}, {"warnings", network_warnings(ns)}};
  out.figures = " PNG view (the network)";
}

// A fit's report: the fit's text report, the model comparison and every
// workbench view (the table on as many pages as its marks need).
void fit_report(const ReportOptions& o, int w, int h, ReportContents& out) {
  std::ostringstream& text = out.text;
  auto& images = out.images;
  WorkbenchOptions wo = o.workbench;
  wo.hash_control = true;
  WorkbenchSession s = open_workbench(wo);
  print_notes(s);

  text << "geoanchor report\n"
       << "  generator: " << s.generator << "\n"
       << "  control:   " << s.control_name << " (sha256 " << s.control_sha256 << ")\n"
       << "  transform: " << o.workbench.transform << " (sha256 " << sha256_file_hex(o.workbench.transform) << ")\n";
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
  std::size_t pages = 0;
  for (const auto& i : images) pages += i.first.starts_with("table") ? 1u : 0u;
  out.about = {{"control", s.control_name}, {"transform", o.workbench.transform}, {"view", nullptr}};
  out.outcome = {{"table_pages", pages}, {"fit", s.model->fit().has_value()}, {"notes", s.notes}, {"warnings", session_warnings(s)}};
  out.figures = " PNG views (the table on " + std::to_string(pages) + (pages == 1 ? " page)" : " pages)");
}

}  // namespace

int run_report(const ReportOptions& options) {
  ReportOptions o = options;
  if (!o.view.empty() && o.view != kNetworkView) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--view " + o.view + ": expected network (without --view, report writes every view of a fit)");
  }
  const bool network = o.view == kNetworkView;
  check_workbench_inputs(o.workbench, network);
  if (o.output == "-") {
    throw Error(ErrorKind::usage, "E_OPTION",
                "-o -: report writes a folder (report.txt and a PNG per view), which standard output cannot hold; give "
                "a folder (snapshot -o - writes one view's PNG on standard output)");
  }
  const auto [w, h] = parse_size(o.size, "--size");
  if (!network && o.workbench.transform.empty()) {
    throw Error(ErrorKind::usage, "E_OPTION", "--transform: required (the transform file the report is about)");
  }
  const fs::path dir(o.output);
  // Every name a report of either kind writes: an earlier report's files
  // that this one does not replace would be read as this one's.
  std::vector<std::string> names{"report.txt"};
  if (network) {
    names.push_back(std::string(kNetworkView) + ".png");
  } else {
    for (gui::View v : gui::kAllViews) names.push_back(std::string(gui::to_string(v)) + ".png");
  }
  if (fs::exists(dir) && !fs::is_directory(dir)) {
    throw Error(ErrorKind::io, "E_OUTPUT_EXISTS", o.output + ": exists and is not a folder");
  }
  std::vector<fs::path> earlier_files;  // report files of an earlier report that this one may not write
  if (fs::is_directory(dir)) {
    std::vector<std::string> any_report{std::string(kNetworkView) + ".png"};
    for (gui::View v : gui::kAllViews) any_report.push_back(std::string(gui::to_string(v)) + ".png");
    for (const auto& e : fs::directory_iterator(dir)) {
      const std::string name = e.path().filename().string();
      const bool ours = std::find(names.begin(), names.end(), name) != names.end();
      const bool other = std::find(any_report.begin(), any_report.end(), name) != any_report.end() || is_later_table_page(name);
      if (!ours && other) earlier_files.push_back(e.path());
    }
    std::sort(earlier_files.begin(), earlier_files.end());
  }
  for (const auto& n : names) {
    io::check_output_path(dir / n, io::Overwrite::allow);  // a FIFO, a device or a folder is refused even with --overwrite
    if (!o.overwrite && fs::exists(fs::symlink_status(dir / n))) {
      throw Error(ErrorKind::io, "E_OUTPUT_EXISTS", (dir / n).string() + ": exists (use --overwrite to replace the report)");
    }
  }
  if (!o.overwrite && !earlier_files.empty()) {
    throw Error(ErrorKind::io, "E_OUTPUT_EXISTS", earlier_files.front().string() + ": exists (use --overwrite to replace the report)");
  }

  ReportContents c;
  if (network) {
    network_report(o, w, h, c);
  } else {
    fit_report(o, w, h, c);
  }
  const auto& images = c.images;
  const std::string text = c.text.str();

  const bool created = !fs::exists(dir);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw Error(ErrorKind::io, "E_WRITE", o.output + ": cannot create folder: " + ec.message());
  std::vector<fs::path> written;
  try {
    {
      io::AtomicOutputFile out(dir / "report.txt", o.overwrite ? io::Overwrite::allow : io::Overwrite::refuse);
      out.stream() << text;
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
  // An earlier report's files beyond this one's would be read as this one's.
  for (const auto& p : earlier_files) {
    if (std::none_of(images.begin(), images.end(), [&](const auto& i) { return dir / i.first == p; })) fs::remove(p, ec);
  }
  if (o.json) {
    ordered_json j;
    j["schema"] = "geoanchor.report/1";
    for (const auto& [k, v] : c.about.items()) j[k] = v;
    j["folder"] = o.output;
    ordered_json files = ordered_json::array();
    files.push_back({{"name", "report.txt"}, {"bytes", text.size()}});
    for (const auto& [name, png] : images) files.push_back({{"name", name}, {"bytes", png.size()}});
    j["files"] = std::move(files);
    for (const auto& [k, v] : c.outcome.items()) j[k] = v;
    print_json(j);
    return 0;
  }
  std::cout << "wrote " << o.output << (o.output.ends_with('/') ? "" : "/") << ": report.txt and " << images.size() << c.figures << "\n";
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
