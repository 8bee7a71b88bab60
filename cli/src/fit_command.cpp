#include "fit_command.hpp"

#include <CLI/CLI.hpp>
#include <malloc.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <numeric>
#include <optional>
#include <tuple>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/workflow/fit_checks.hpp"
#include "geoanchor/workflow/fit_export.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/io/control/control_csv.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "geoanchor/solver/helmert_fit.hpp"
#include "geoanchor/solver/model_comparison.hpp"
#include "command_input.hpp"
#include "option_parsing.hpp"
#include "version.hpp"

namespace geoanchor::cli {
using solver::FitModel;

CLI::App* add_fit_command(CLI::App& app, FitCommandOptions& o) {
  auto* cmd = app.add_subcommand("fit", "Fit a datum transform to control points, with statistics");
  cmd->add_option("CONTROL", o.control, "Control set (CSV or JSON), or - for standard input");
  cmd->add_option("--src", o.src, "Instead of CONTROL: the source frame's coordinates (CSV without roles, e.g. adjust's stations), joined by id with --dst");
  cmd->add_option("--dst", o.dst, "Instead of CONTROL: the target frame's coordinates (CSV without roles, e.g. adjust's stations), joined by id with --src");
  cmd->add_flag("--allow-unmatched", o.allow_unmatched, "With --src/--dst: leave out --src marks that --dst lacks (else refused)");
  cmd->add_option("--model", o.model,
                  "translation3|helmert6|helmert7|helmert14|molodensky-badekas|enu-origin|site-calibration");
  cmd->add_flag("--compare", o.compare, "Fit every applicable model on the same points and compare them");
  cmd->add_option("--robust", o.robust, "Robust loss for exploration: huber:K or cauchy:K (K in standard deviations)");
  cmd->add_flag("--vce", o.vce, "Estimate variance factors for the source and target covariances");
  cmd->add_flag("--fix-yaw", o.fix_yaw, "enu-origin: hold the yaw at 0");
  cmd->add_option("--tm", o.tm, "site-calibration: the grid LAT0,LON0,K0,FE,FN (default: TM, k0 = 1, at the targets' centroid)");
  cmd->add_flag("--with-scale", o.with_scale, "enu-origin: estimate a scale difference too");
  cmd->add_option("--pivot", o.pivot, "molodensky-badekas: pivot X,Y,Z in ECEF metres (default: the centroid)");
  cmd->add_option("--convention", o.convention, "position_vector|coordinate_frame (required with rotations)");
  cmd->add_option("--rotation-model", o.rotation_model, "small_angle (EPSG, default) | exact");
  cmd->add_option("--reference-epoch", o.reference_epoch, "helmert14: parameter epoch (default: mean observation epoch)");
  cmd->add_option("--origin", o.origin, "Nominal origin LAT,LON,H of ENU control coordinates");
  cmd->add_option("--ellipsoid", o.ellipsoid, "Ellipsoid of geodetic/ENU/projected control coordinates (default: each frame's own, e.g. GRS80 for ITRF/GDA2020; WGS84 for an unnamed frame)");
  add_control_grid_options(*cmd, o.grids);
  cmd->add_option("--source-frame", o.source_frame, "Source frame NAME[@EPOCH] (overrides the file's)");
  cmd->add_option("--target-frame", o.target_frame, "Target frame NAME[@EPOCH] (overrides the file's)");
  cmd->add_option("--geoid", o.geoid, "Geoid of orthometric heights (H_src_m, H_dst_m; JSON H_m): EGM96, EGM96-NGA, a grid name PROJ finds or a PATH");
  cmd->add_option("--alpha", o.alpha, "Significance of the global test (default 0.05)")->check(finite_range(1e-6, 0.5));
  cmd->add_option("--alpha-point", o.alpha_point, "Significance of point tests and data snooping (default 0.001)")
      ->check(finite_range(1e-9, 0.5));
  cmd->add_flag("--remove-outliers", o.remove_outliers,
                "Remove the marks that fail their point test by iterative data snooping, strongest evidence first, and "
                "fit again (default: flag them and remove none)");
  cmd->add_flag("--no-snooping", o.no_snooping, "Remove no mark (the default; kept for scripts): failing marks are flagged");
  cmd->add_option("--max-outlier-share", o.max_outlier_share,
                  "--remove-outliers: refuse the fit when data snooping would remove more than this share of the marks (default 0.10)")
      ->check(finite_range(0.0, 0.5));
  cmd->add_flag("--scale-by-sigma0", o.scale_by_sigma0, "Scale parameter sigmas by the a-posteriori σ0");
  cmd->add_flag("--accept-failed-global-test", o.accept_failed_global_test,
                "Write the transform even if the global test fails high");
  cmd->add_flag("--solution-weighting", o.solution_weighting,
                "Use marks whose GNSS solution (column 'solution') is float, dgps, sbas or standalone, with their sigmas "
                "multiplied by 10, 25, 75 or 250 (default: left out; dead_reckoned always is)");
  cmd->add_option("--survey-metadata", o.survey_metadata,
                  "Survey metadata (JSON, schema geoanchor.survey/1) for the transform file's metadata contract: ENU "
                  "origin source, GNSS method and base, vertical datum, geoid, RTK-fixed share");
  cmd->add_option("-o,--output", o.output,
                  "Transform file (JSON) to write; - writes it on standard output (the report then goes to standard error)");
  cmd->add_flag("--overwrite", o.overwrite, "Replace an existing output");
  cmd->add_flag("--json", o.json,
                "Print the report as JSON (schema geoanchor.fit-report/1, with --compare geoanchor.fit-comparison/1) "
                "on standard output instead of text");
  return cmd;
}

namespace {

using nlohmann::ordered_json;

std::string verdict_text(const solver::GlobalTest& g) {
  return !g.applicable ? "n/a" : g.passed ? "PASSED" : g.failed_high() ? "FAILED high" : "FAILED low";
}

// "control" of the JSON reports: where the set came from.
ordered_json control_json(const ControlInput& in) {
  ordered_json c;
  c["path"] = in.from_stdin || !in.role_files.empty() ? ordered_json(nullptr) : ordered_json(in.name);
  c["name"] = in.name;
  c["sha256"] = in.sha256;
  c["points"] = in.set.points.size();
  if (!in.role_files.empty()) {
    ordered_json files = ordered_json::array();
    for (const auto& f : in.role_files) files.push_back({{"role", f.role}, {"path", f.path}, {"sha256", f.sha256}});
    c["files"] = files;
    c["notes"] = in.notes;
  }
  return c;
}

void print_json(const ordered_json& j) {
  std::cout << j.dump(2) << '\n';
  io::finish_standard_output("the JSON report (--json)");
}

// The --compare table as JSON (geoanchor.fit-comparison/1, docs/commands/fit.md).
void print_compare_json(const ControlInput& in, const std::vector<solver::ModelComparison>& rows,
                        const std::vector<std::string>& warnings) {
  ordered_json j;
  j["schema"] = "geoanchor.fit-comparison/1";
  j["control"] = control_json(in);
  j["data_snooping"] = false;
  ordered_json models = ordered_json::array();
  for (const auto& c : rows) {
    ordered_json m;
    m["model"] = std::string(solver::to_string(c.model));
    m["parameters"] = c.parameters;
    if (!c.fit) {
      m["refused"] = c.refused;
    } else {
      m["refused"] = nullptr;
      m["dof"] = c.fit->dof;
      m["sigma0"] = c.fit->sigma0 ? ordered_json(*c.fit->sigma0) : ordered_json(nullptr);
      m["global_test"] = c.fit->global_test.verdict();
      m["max_abs_w"] = c.max_w;
      m["aic"] = c.aic;
    }
    m["note"] = c.note.empty() ? ordered_json(nullptr) : ordered_json(c.note);
    models.push_back(std::move(m));
  }
  j["models"] = std::move(models);
  ordered_json lowest = ordered_json::array();
  for (const FitModel m : solver::lowest_aic(rows)) lowest.push_back(std::string(solver::to_string(m)));
  j["lowest_aic"] = std::move(lowest);
  j["warnings"] = warnings;
  print_json(j);
}

// Fits every model the data allow on the same points (no data snooping, so
// that the information criterion compares like with like) and prints them.
int run_compare(const ControlInput& in, const solver::FitOptions& base, bool json, const std::vector<std::string>& warnings) {
  const geodesy::ControlSet& set = in.set;
  const auto rows = solver::compare_models(set, base);
  if (json) {
    print_compare_json(in, rows, warnings);
    return 0;
  }
  std::cout << "geoanchor fit --compare: " << set.source_name << " (" << set.points.size()
            << " points; data snooping off so that every model sees the same points)\n";
  if (!base.convention) std::cout << "  (give --convention to include the models with rotations)\n";
  std::cout << "\n  model                u    dof      σ0   global test        max|w|        AIC\n";
  const solver::ModelComparison* best = nullptr;
  for (const auto& c : rows) {
    char line[200];
    const std::string name(solver::to_string(c.model));
    if (!c.fit) {
      std::snprintf(line, sizeof line, "  %-18s refused: ", name.c_str());
      std::cout << line << c.refused << "\n";
      continue;
    }
    const std::string verdict = verdict_text(c.fit->global_test);
    std::snprintf(line, sizeof line, "  %-18s %3d %6d %8s   %-12s %10.2f %10.1f\n", name.c_str(), c.parameters, c.fit->dof,
                  (c.fit->sigma0 ? format_fixed(*c.fit->sigma0, 3) : std::string("undef")).c_str(), verdict.c_str(), c.max_w, c.aic);
    std::cout << line;
    if (!best || c.aic < best->aic) best = &c;
  }
  for (const auto& c : rows) {
    if (!c.note.empty()) std::cout << "  (" << solver::to_string(c.model) << ": " << c.note << ")\n";
  }
  if (best) {
    // helmert7 and molodensky-badekas (one is the other's reparametrisation)
    // tie: name every model at the lowest AIC.
    std::string lowest;
    for (const FitModel m : solver::lowest_aic(rows)) lowest += (lowest.empty() ? "" : " and ") + std::string(solver::to_string(m));
    std::cout << "\n  lowest AIC: " << lowest
              << " (AIC = Ω + 2u with a-priori sigmas; differences above ~10 are strong evidence)\n";
  }
  return 0;
}

// The options' combinations: one control, one model (or --compare), one
// place for each output.
void check_options(const FitCommandOptions& o) {
  if (o.control.empty() == (o.src.empty() || o.dst.empty()) || (o.src.empty() != o.dst.empty())) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "the control: give CONTROL (one file with both frames' columns) or --src FILE --dst FILE (one frame each, "
                "joined by id)");
  }
  if (o.allow_unmatched && o.src.empty()) throw Error(ErrorKind::usage, "E_OPTION", "--allow-unmatched: only with --src/--dst");
  if (o.model.empty() && !o.compare) {
    throw Error(ErrorKind::usage, "E_OPTION", "--model: required (or --compare to fit every applicable model)");
  }
  if (!o.model.empty() && o.compare) {
    throw Error(ErrorKind::usage, "E_OPTION", "--model and --compare: give one");
  }
  if (o.compare && !o.output.empty()) {
    throw Error(ErrorKind::usage, "E_OPTION", "--compare writes no transform file: drop -o, then fit the chosen model");
  }
  if (o.json && o.output == "-") {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--json and -o -: both would go to standard output; give -o FILE (the JSON report holds the transform too)");
  }
}

// The solver's options from the flags (those that need the control set
// are completed once it is read).
solver::FitOptions fit_options(const FitCommandOptions& o) {
  solver::FitOptions fo;
  fo.model = o.compare ? FitModel::helmert7 : parse_model(o.model, "--model");
  if (o.convention) {
    fo.convention = parse_convention(*o.convention, "--convention");
  }
  if (o.rotation_model == "small_angle") {
    fo.rotation_model = geodesy::RotationModel::small_angle;
  } else if (o.rotation_model == "exact") {
    fo.rotation_model = geodesy::RotationModel::exact;
  } else {
    throw Error(ErrorKind::usage, "E_OPTION", "--rotation-model " + o.rotation_model + ": expected small_angle or exact");
  }
  if (o.reference_epoch) {
    if (fo.model != FitModel::helmert14) {
      throw Error(ErrorKind::usage, "E_OPTION", "--reference-epoch: only for --model helmert14");
    }
    fo.reference_epoch = geodesy::parse_decimal_year(*o.reference_epoch, "--reference-epoch");
  }
  if (o.tm && !o.compare && fo.model != FitModel::site_calibration) {
    throw Error(ErrorKind::usage, "E_OPTION", "--tm: only for --model site-calibration");
  }
  if (o.pivot) {
    if (fo.model != FitModel::molodensky_badekas) {
      throw Error(ErrorKind::usage, "E_OPTION", "--pivot: only for --model molodensky-badekas");
    }
    const auto parts = split_numbers(*o.pivot, "--pivot", 3, "X,Y,Z (ECEF metres)");
    fo.pivot_m = Eigen::Vector3d(parts[0], parts[1], parts[2]);
  }
  if (o.robust) {
    const auto colon = o.robust->find(':');
    const std::string kind = o.robust->substr(0, colon);
    const auto k = colon == std::string::npos ? std::nullopt : parse_finite_double(o.robust->substr(colon + 1));
    if ((kind != "huber" && kind != "cauchy") || !k || !(*k > 0.0)) {
      throw Error(ErrorKind::usage, "E_OPTION", "--robust " + *o.robust + ": expected huber:K or cauchy:K with K > 0");
    }
    fo.robust = kind == "huber" ? solver::FitOptions::Robust::huber : solver::FitOptions::Robust::cauchy;
    fo.robust_k = *k;
  }
  fo.vce = o.vce;
  fo.alpha = o.alpha;
  fo.alpha_point = o.alpha_point;
  if (o.remove_outliers && o.no_snooping) {
    throw Error(ErrorKind::usage, "E_OPTION", "--remove-outliers and --no-snooping: give one (--no-snooping removes none, the default)");
  }
  fo.data_snooping = true;
  fo.remove_outliers = o.remove_outliers;
  fo.max_outlier_share = o.max_outlier_share;
  fo.scale_by_sigma0 = o.scale_by_sigma0;
  fo.solutions = o.solution_weighting ? geodesy::SolutionPolicy::weight : geodesy::SolutionPolicy::exclude;
  return fo;
}

// Refuse an existing output before any work. With -o - the transform
// file goes to standard output and the report to standard error.
std::unique_ptr<CommandOutput> open_output(const FitCommandOptions& o) {
  std::unique_ptr<CommandOutput> out;
  if (!o.output.empty()) {
    for (const auto* input : {&o.control, &o.src, &o.dst}) {
      if (!input->empty() && *input != "-" && o.output != "-") io::refuse_same_file(*input, o.output);
    }
    out = std::make_unique<CommandOutput>(o.output, o.overwrite);
  }
  return out;
}

// How the control set is read (ellipsoid, origin, grids, geoid, frames),
// and the local models' origin and grid in the solver's options.
io::ControlReadOptions control_read_options(const FitCommandOptions& o, solver::FitOptions& fo) {
  io::ControlReadOptions ro;
  if (o.ellipsoid) ro.ellipsoid = parse_ellipsoid(*o.ellipsoid, "--ellipsoid");
  // The origin's and the site grid's ellipsoid are their frame's, known once the set is read.
  if (o.origin) ro.origin = parse_origin(*o.origin, "--origin", ro.ellipsoid.value_or(geodesy::Ellipsoid::wgs84()));
  apply_control_grids(o.grids, ro);
  if (o.compare) {
    fo.nominal_origin = ro.origin;
  } else if (fo.model == FitModel::enu_origin || fo.model == FitModel::site_calibration) {
    if (!ro.origin) {
      throw Error(ErrorKind::usage, "E_ORIGIN_MISSING",
                  "--origin: the " + std::string(solver::to_string(fo.model)) +
                      " model needs the origin LAT,LON,H of the ENU (local) source coordinates");
    }
    fo.nominal_origin = ro.origin;
    if (o.tm) {
      if (fo.model != FitModel::site_calibration) throw Error(ErrorKind::usage, "E_OPTION", "--tm: only for --model site-calibration");
      fo.site_grid = geodesy::ProjectionDef{ro.ellipsoid.value_or(geodesy::Ellipsoid::wgs84()), parse_tm(*o.tm, "--tm"),
                                            std::nullopt};
    }
    fo.enu_yaw = !o.fix_yaw;
    fo.enu_scale = o.with_scale;
  } else if (o.fix_yaw || o.with_scale) {
    throw Error(ErrorKind::usage, "E_OPTION", "--fix-yaw/--with-scale: only for --model enu-origin");
  }
  const geodesy::GeoidGrid* geoid = o.geoid ? &parse_geoid(*o.geoid, "--geoid") : nullptr;
  ro.src_geoid = ro.dst_geoid = geoid;
  if (o.source_frame) ro.source_frame.replace = geodesy::Frame::parse(*o.source_frame, "--source-frame");
  if (o.target_frame) ro.target_frame.replace = geodesy::Frame::parse(*o.target_frame, "--target-frame");
  return ro;
}

// The set as read, checked before the solve (the local models' ellipsoids
// taken from it, epochs of dynamic frames, swapped axes, far marks, epochs
// spread over years). Returns what the report says about orthometric input.
std::vector<std::string> check_control_set(const FitCommandOptions& o, const io::ControlReadOptions& ro, geodesy::ControlSet& set,
                                           solver::FitOptions& fo) {
  const geodesy::GeoidGrid* geoid = ro.src_geoid;
  if (fo.nominal_origin && set.origin) fo.nominal_origin->ellipsoid = set.origin->ellipsoid;
  if (fo.site_grid) fo.site_grid->ellipsoid = set.target_input.ellipsoid;
  // A dynamic frame given on the command line needs its epoch as one in the
  // file does (the reader refuses those), unless every point has one.
  const bool every_point_dated = !set.points.empty() && std::all_of(set.points.begin(), set.points.end(),
                                                                    [](const auto& p) { return p.epoch.has_value(); });
  for (const auto& [flag, given] : {std::pair{"--source-frame", &ro.source_frame.replace},
                                    std::pair{"--target-frame", &ro.target_frame.replace}}) {
    if (*given && !every_point_dated) {
      geodesy::require_epoch_if_dynamic(**given, flag, ErrorKind::usage, ", or an epoch for every point");
    }
  }
  std::vector<std::string> heights;  // what the report says about orthometric input
  for (const auto* form : {&set.source_input, &set.target_input}) {
    if (form->height_type != geodesy::HeightKind::orthometric) continue;
    heights.push_back(form->height_column + " orthometric, read as h = H + N on " + form->geoid_model);
  }
  if (geoid && heights.empty()) {
    std::cerr << "geoanchor: warning: --geoid " << *o.geoid << " unused: the control set gives ellipsoidal heights (h)\n";
  }
  if (const auto swap = workflow::likely_lat_lon_swap(set)) throw Error(ErrorKind::input, "E_AXIS_SWAP", *swap);
  if (const auto far = workflow::far_apart_mark(set)) throw Error(ErrorKind::input, "E_MARK_FAR_APART", *far);
  (void)workflow::fixed_fit_epoch(set, fo.model);  // refuses epochs spread over years before the solve
  return heights;
}

// The transform file, unless the fit was refused: streamed to `out`, or
// with --json formed whole (and returned, for the report; else empty).
std::string write_transform(const FitCommandOptions& o, CommandOutput* out, bool refused, workflow::FitForExport& fitted,
                            geodesy::ControlSet& set, const solver::FitOptions& fo, const io::SurveyMetadata* survey_ptr) {
  const solver::FitResult& r = fitted.fit;
  std::string cmd;
  for (const auto& a : o.argv) cmd += (cmd.empty() ? "" : " ") + a;
  const std::string generator = "geoanchor " GEOANCHOR_VERSION ": " + cmd;
  // --json embeds the file's content; otherwise the file is streamed (10⁶
  // marks' records are never held whole).
  std::string transform_text;
  // The metadata contract first: a survey file that contradicts the fit
  // refuses it before anything is written.
  const io::MapMetadata contract = workflow::transform_metadata(r, set, survey_ptr);
  (void)contract;
  if (o.json) transform_text = io::to_json_text(workflow::transform_file_from_fit(r, set, fo, {}, generator, survey_ptr));
  if (out && !refused) {
    if (o.json) {
      out->stream() << transform_text;
    } else {
      const workflow::StreamedTransformFile file =
          workflow::streamed_transform_file_from_fit(fitted, set, fo, {}, generator, survey_ptr);
      // The marks are not read again: they and the solver's freed memory
      // go back to the system before the file is written (10⁶ marks:
      // 550 MB), where the file's cache pages can reuse them (on this
      // platform a fresh page costs as much as the bytes written into it)
      // and the exit has less to free.
      std::vector<geodesy::ControlPoint>().swap(set.points);
      (void)malloc_trim(0);
      io::write_json(out->stream(), file.file, file.points);
    }
    out->commit();
    for (const auto& t : io::take_removed_stale_temporaries()) {
      std::cerr << "geoanchor: warning: " << io::stale_temporary_warning(t) << '\n';
    }
    if (!o.json && !out->to_stdout()) {
      std::cout << "\nwrote " << o.output << "\n";
      io::finish_standard_output("the line \"wrote " + o.output + "\"", "; " + o.output + " was written");
    }
  }
  return transform_text;
}

// The report as JSON (geoanchor.fit-report/1, docs/commands/fit.md):
// what happened, and the transform file's content, written or not.
void print_report_json(const FitCommandOptions& o, const ControlInput& in, const solver::FitResult& r, bool has_output,
                       const std::optional<workflow::FitRefusal>& refusal, const std::string& transform_text) {
  ordered_json j;
  j["schema"] = "geoanchor.fit-report/1";
  j["control"] = control_json(in);
  j["status"] = refusal ? "refused" : has_output ? "written" : "not written";
  j["output"] = has_output && !refusal ? ordered_json(o.output) : ordered_json(nullptr);
  j["refusal"] = refusal ? ordered_json{{"code", refusal->code}, {"message", refusal->message}} : ordered_json(nullptr);
  j["global_test"] = r.global_test.verdict();
  // The marks failing their point test: flagged (kept) and removed (by
  // --remove-outliers), in the order data snooping removes them.
  ordered_json flagged = ordered_json::array(), removed = ordered_json::array();
  for (const std::size_t i : solver::failing_marks(r)) {
    const solver::PointResult& p = r.points[i];
    ordered_json m;
    m["id"] = p.id;
    m["snooping_rank"] = p.snooping_rank > 0 ? ordered_json(p.snooping_rank) : ordered_json(nullptr);
    m["passes_after_rank"] = p.passes_after_rank > 0 ? ordered_json(p.passes_after_rank) : ordered_json(nullptr);
    m["w_max"] = std::isfinite(p.w_max) ? ordered_json(p.w_max) : ordered_json(nullptr);
    m["mdb_m"] = std::isfinite(p.mdb_m) ? ordered_json(p.mdb_m) : ordered_json(nullptr);
    m["point_test"] = {{"statistic", p.point_statistic}, {"dof", p.point_dof}, {"p_value", p.point_p_value}};
    if (p.outlier) m["because"] = p.removed_because;
    (p.outlier ? removed : flagged).push_back(std::move(m));
  }
  j["flagged"] = std::move(flagged);
  j["removed"] = std::move(removed);
  j["warnings"] = r.warnings;
  j["transform"] = ordered_json::parse(transform_text);
  print_json(j);
}

}  // namespace

int run_fit(const FitCommandOptions& o) {
  // A fit's memory is a few large arrays (10⁶ marks: the set, the solver's
  // observations and the per-point results, 0.9 GB at the peak), most of
  // them built once; glibc would map each large one afresh and unmap it
  // when freed, so that every phase pays the kernel to zero new pages again
  // (when the peak was 1.3 GB: 450 000 page faults, a third of the
  // command's CPU). Here they come from the heap and freed memory is kept
  // for the next phase (then 30 % fewer page faults, about 0.4 s less), and
  // given back before the file is written (write_transform). The process
  // ends with the command, so nothing is held for longer.
  (void)mallopt(M_MMAP_MAX, 0);
  (void)mallopt(M_TRIM_THRESHOLD, std::numeric_limits<int>::max());
  check_options(o);
  solver::FitOptions fo = fit_options(o);
  // Read before any work: a bad survey file fails before the fit.
  std::optional<io::SurveyMetadata> survey;
  if (o.survey_metadata) survey = io::read_survey_metadata(*o.survey_metadata);
  const io::SurveyMetadata* survey_ptr = survey ? &*survey : nullptr;
  const std::unique_ptr<CommandOutput> out = open_output(o);
  std::ostream& report = out && out->to_stdout() ? std::cerr : std::cout;

  const io::ControlReadOptions ro = control_read_options(o, fo);
  const geodesy::GeoidGrid* geoid = ro.src_geoid;
  ControlInput in = o.control.empty() ? read_control_pair_input(o.src, o.dst, ro, o.allow_unmatched, o.json) : read_control_input(o.control, ro, o.json);
  geodesy::ControlSet& set = in.set;
  const std::vector<std::string> heights = check_control_set(o, ro, set, fo);
  std::vector<std::string> set_warnings = workflow::control_set_warnings(set);
  // What the join of --src and --dst left out: printed and recorded with the fit.
  set_warnings.insert(set_warnings.end(), in.notes.begin(), in.notes.end());
  if (o.compare) {
    for (const auto& w : set_warnings) std::cerr << "geoanchor: warning: " << w << '\n';
    const int code = run_compare(in, fo, o.json, set_warnings);
    io::finish_standard_output("the comparison");
    return code;
  }

  // Only a streamed transform file takes the extent formed during the
  // solve (--json forms the file whole, after it).
  const bool streamed_output = out && !o.json;
  workflow::FitForExport fitted = streamed_output ? workflow::fit_for_export(set, fo)
                                                  : workflow::FitForExport{solver::fit_helmert(set, fo), std::nullopt};
  solver::FitResult& r = fitted.fit;  // warnings are added below; the marks used stay as they are
  r.warnings.insert(r.warnings.begin(), set_warnings.begin(), set_warnings.end());
  if (const auto w = workflow::orthometric_height_warning(r, set, geoid ? *geoid : geodesy::GeoidGrid::egm96())) {
    r.warnings.push_back(*w);
  }
  if (!o.json) {
    for (const auto& h : heights) report << "heights: " << h << "\n";
    workflow::write_fit_report(report, r, set, fo);
  }
  for (const auto& w : r.warnings) std::cerr << "geoanchor: warning: " << w << '\n';

  const auto refusal = workflow::fit_refusal(r, in.name, o.accept_failed_global_test);
  if (refusal) std::cerr << "geoanchor: error[" << refusal->code << "]: " << refusal->message << '\n';
  // A report nobody could read: the transform it describes is not written.
  if (!o.json) {
    io::finish_standard_output("the fit report", out && !refusal && !out->to_stdout() ? "; " + o.output + " was not written"
                                                                                      : std::string());
  }
  const std::string transform_text = write_transform(o, out.get(), refusal.has_value(), fitted, set, fo, survey_ptr);
  if (o.json) print_report_json(o, in, r, out != nullptr, refusal, transform_text);
  return refusal ? exit_code(ErrorKind::rejected) : 0;
}

}  // namespace geoanchor::cli
