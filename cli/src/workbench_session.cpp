#include "workbench_session.hpp"

#include <CLI/CLI.hpp>

#include <cmath>
#include <filesystem>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/workflow/fit_export.hpp"
#include "geoanchor/io/control/control_csv.hpp"
#include "command_input.hpp"
#include "option_parsing.hpp"
#include "version.hpp"

namespace geoanchor::cli {

void add_workbench_options(CLI::App* cmd, WorkbenchOptions& o) {
  cmd->add_option("CONTROL", o.inputs,
                  "Control set (CSV or JSON), or - for standard input; with --view network the network's inputs, as for adjust")
      ->required();
  cmd->add_option("--transform", o.transform,
                  "Transform file: its model, convention and recorded choices (and the points left out) start the fit");
  cmd->add_option("--model", o.model, "Model to fit (overrides the transform file's; default helmert7)");
  cmd->add_option("--convention", o.convention, "position_vector|coordinate_frame (default: the file's, else position_vector)");
  cmd->add_option("--origin", o.origin, "Nominal origin LAT,LON,H of ENU control coordinates");
  cmd->add_option("--ellipsoid", o.ellipsoid, "Ellipsoid of geodetic/ENU control coordinates (default: each frame's own; WGS84 for an unnamed frame)");
  o.network_flags = add_network_options(cmd, o.network);
}

void check_workbench_inputs(WorkbenchOptions& o, bool network_view) {
  if (network_view) {
    const std::pair<bool, const char*> fit_only[] = {
        {!o.transform.empty(), "--transform"}, {o.model.has_value(), "--model"}, {o.origin.has_value(), "--origin"},
        {o.ellipsoid.has_value(), "--ellipsoid"}};
    for (const auto& [given, flag] : fit_only) {
      if (given) {
        throw Error(ErrorKind::usage, "E_OPTION",
                    std::string(flag) + ": not with --view network (the network view adjusts a survey network; it fits no transform)");
      }
    }
    if (o.convention && !o.network.estimate_helmert) {
      throw Error(ErrorKind::usage, "E_OPTION", "--convention: with --view network only with --estimate-helmert");
    }
    return;
  }
  for (const CLI::Option* flag : o.network_flags) {
    // A fit's data snooping, as in fit: flag (the default) or remove.
    if (flag->get_name() == "--remove-outliers" || flag->get_name() == "--no-snooping") continue;
    if (flag->count() > 0) {
      throw Error(ErrorKind::usage, "E_OPTION",
                  flag->get_name() + ": only with --view network (a survey network's view; a control set's views fit a transform)");
    }
  }
  if (o.inputs.size() != 1) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "CONTROL: expected one control set, got " + std::to_string(o.inputs.size()) +
                    " files (several inputs make a survey network: --view network)");
  }
  o.control = o.inputs.front();
}

namespace {

// The largest distance, over the control marks' source positions, between
// the file's transform and the refit (metres); NaN if either cannot be applied.
double largest_difference_m(const io::TransformFile& file, const io::TransformFile& refit, const geodesy::ControlSet& set) {
  double worst = 0.0;
  for (const auto& p : set.points) {
    try {
      const auto a = file.apply(p.source, p.epoch, false, set.source_name);
      const auto b = refit.apply(p.source, p.epoch, false, set.source_name);
      worst = std::max(worst, (a.m - b.m).norm());
    } catch (const Error&) {
      return std::nan("");
    }
  }
  return worst;
}

}  // namespace

gui::View parse_view(const std::string& text, std::string_view flag) {
  if (const auto view = gui::view_from_string(text)) return *view;
  throw Error(ErrorKind::usage, "E_OPTION",
              std::string(flag) + " " + text + ": expected workbench, plan, histogram, table, parameters, comparison or network");
}

std::pair<int, int> parse_size(const std::string& text, std::string_view flag) {
  const auto x = text.find('x');
  const auto w = x == std::string::npos ? std::nullopt : parse_finite_double(text.substr(0, x));
  const auto h = x == std::string::npos ? std::nullopt : parse_finite_double(text.substr(x + 1));
  // Below the minimum the views' text would not fit (workbench_ui.hpp).
  if (!w || !h || *w != std::floor(*w) || *h != std::floor(*h) || *w < gui::kMinimumWidth_px || *h < gui::kMinimumHeight_px ||
      *w > 8192 || *h > 8192) {
    throw Error(ErrorKind::usage, "E_OPTION",
                std::string(flag) + " " + text + ": expected WIDTHxHEIGHT in pixels, " + std::to_string(gui::kMinimumWidth_px) +
                    " … 8192 wide and " + std::to_string(gui::kMinimumHeight_px) +
                    " … 8192 tall (the smallest at which every view's text fits), e.g. 1600x1000");
  }
  return {static_cast<int>(*w), static_cast<int>(*h)};
}

WorkbenchSession open_workbench(const WorkbenchOptions& o) {
  require_utf8_arguments(o.argv);
  WorkbenchSession s;
  workflow::FitChoices choices;
  choices.options.model = solver::FitModel::helmert7;
  if (!o.transform.empty()) {
    s.transform = io::read_transform_file(o.transform);
    choices = workflow::fit_choices_from_transform(*s.transform);
    s.notes.push_back("model, convention and fit settings from " + o.transform +
                      (s.transform->fit ? "" : " (published parameters, no fit record: the workbench fits that model to the control)"));
  }
  solver::FitOptions& fo = choices.options;
  if (o.network.remove_outliers && o.network.no_snooping) {
    throw Error(ErrorKind::usage, "E_OPTION", "--remove-outliers and --no-snooping: give one (--no-snooping removes none, the default)");
  }
  if (o.network.remove_outliers) fo.remove_outliers = true;
  if (o.network.no_snooping) fo.remove_outliers = false;
  if (o.model) fo.model = parse_model(*o.model, "--model");
  if (o.convention) {
    fo.convention = parse_convention(*o.convention, "--convention");
  } else if (!fo.convention) {
    fo.convention = solver::Convention::position_vector;
    s.notes.push_back("convention: position_vector (no --convention and none in a transform file; switch in the workbench)");
  }
  io::ControlReadOptions ro;
  if (o.ellipsoid) ro.ellipsoid = parse_ellipsoid(*o.ellipsoid, "--ellipsoid");
  if (o.origin) {
    ro.origin = parse_origin(*o.origin, "--origin", ro.ellipsoid.value_or(geodesy::Ellipsoid::wgs84()));
    fo.nominal_origin = ro.origin;
  } else if (fo.nominal_origin) {
    ro.origin = fo.nominal_origin;  // the transform file's nominal origin reads ENU control
  }
  if ((fo.model == solver::FitModel::enu_origin || fo.model == solver::FitModel::site_calibration) && !fo.nominal_origin) {
    throw Error(ErrorKind::usage, "E_ORIGIN_MISSING",
                "--origin: the " + std::string(solver::to_string(fo.model)) +
                    " model needs the origin LAT,LON,H of the ENU (local) source coordinates");
  }
  ControlInput in = read_control_input(o.control, ro, o.hash_control);
  geodesy::ControlSet& set = in.set;
  if (fo.nominal_origin && set.origin) fo.nominal_origin->ellipsoid = set.origin->ellipsoid;
  s.control_name = in.name;
  s.control_sha256 = in.sha256;
  std::string cmd;
  for (const auto& a : o.argv) cmd += (cmd.empty() ? "" : " ") + a;
  s.generator = "geoanchor " GEOANCHOR_VERSION ": " + cmd;
  const std::filesystem::path control_path(in.from_stdin ? std::string("stdin") : o.control);
  s.save_path = (control_path.parent_path() / (control_path.stem().string() + ".transform.json")).string();
  // Small sets fit on this thread; large ones on the worker, awaited here.
  // The points the file says were left out in the workbench are left out again.
  s.model = std::make_unique<gui::WorkbenchModel>(set, fo, gui::WorkbenchModel::kDefaultAsyncFrom, choices.left_out);
  s.model->wait();
  if (s.transform && s.model->fit()) {
    const io::TransformFile refit =
        workflow::transform_file_from_fit(*s.model->fit(), s.model->control(), fo, s.model->left_out(), s.generator);
    const double d = largest_difference_m(*s.transform, refit, s.model->control());
    if (!std::isfinite(d)) {
      s.notes.push_back(o.transform + " could not be compared with the refit at the control marks (a time-dependent "
                        "transform needs each mark's epoch)");
    } else {
      s.notes.push_back(o.transform + " and the refit of " + in.name + " differ by at most " + format_fixed(1e3 * d, 3) +
                        " mm at the control marks" +
                        (d > 1e-4 && s.transform->fit ? " (the control set or the choices changed since the fit)" : ""));
    }
  }
  return s;
}

}  // namespace geoanchor::cli
