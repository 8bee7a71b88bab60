#include "diagnose_command.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <type_traits>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/io/control/control_csv.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "geoanchor/solver/diagnosis.hpp"
#include "command_input.hpp"
#include "option_parsing.hpp"

namespace geoanchor::cli {

CLI::App* add_diagnose_command(CLI::App& app, DiagnoseCommandOptions& o) {
  auto* cmd = app.add_subcommand("diagnose", "Say which classic datum mistake explains a bad fit");
  cmd->add_option("CONTROL", o.control, "Control set (CSV or JSON), or - for standard input")->required();
  cmd->add_option("--transform", o.transform, "Apply this transform file instead of fitting --model");
  cmd->add_flag("--json", o.json, "Write the diagnosis as JSON (schema geoanchor.diagnosis/1) on standard output");
  cmd->add_option("--model", o.model, "Model fitted without --transform (default helmert7)");
  cmd->add_option("--convention", o.convention, "position_vector|coordinate_frame of the fitted model (residuals do not depend on it)");
  cmd->add_option("--origin", o.origin, "Nominal origin LAT,LON,H of ENU control coordinates");
  cmd->add_option("--ellipsoid", o.ellipsoid, "Ellipsoid of geodetic, projected and ENU coordinates (default: each frame's own; WGS84 for an unnamed frame)");
  add_control_grid_options(*cmd, o.grids);
  cmd->add_option("--source-frame", o.source_frame, "Source frame NAME[@EPOCH] (overrides the file's)");
  cmd->add_option("--target-frame", o.target_frame, "Target frame NAME[@EPOCH] (overrides the file's)");
  cmd->add_option("--geoid", o.geoid,
                  "Geoid model of orthometric heights (H_src_m, H_dst_m; JSON H_m) and of the height_type test: EGM96 "
                  "(default for the test), EGM96-NGA, a grid name PROJ finds or a PATH");
  cmd->add_option("--sigma", o.sigma, "Noise per coordinate and frame (m, 1σ) assumed when the set gives none (default 0.01)")
      ->check(finite_positive());
  return cmd;
}

namespace {

// A parameter set with its rotations read in the other convention: the same
// numbers, the other type.
template <class C>
using OtherConvention =
    std::conditional_t<std::is_same_v<C, geodesy::PositionVector>, geodesy::CoordinateFrame, geodesy::PositionVector>;

template <class C>
geodesy::Helmert7<OtherConvention<C>> swapped(const geodesy::Helmert7<C>& h) {
  return {h.t_m, h.rx, h.ry, h.rz, h.ds};
}

template <class C>
geodesy::Helmert14<OtherConvention<C>> swapped(const geodesy::Helmert14<C>& h) {
  geodesy::Helmert14<OtherConvention<C>> o;
  o.at_reference_epoch = swapped(h.at_reference_epoch);
  o.rates = {h.rates.dt_m_per_year, h.rates.drx_per_year, h.rates.dry_per_year, h.rates.drz_per_year, h.rates.dds_per_year};
  o.reference_epoch = h.reference_epoch;
  return o;
}

io::TransformFile with_other_convention(const io::TransformFile& t) {
  io::TransformFile s = t;
  std::visit([&](const auto& h) { s.helmert = swapped(h); }, t.helmert);
  return s;
}

bool has_rotations(const io::TransformFile& t) {
  return t.model == io::TransformModel::helmert6 || t.model == io::TransformModel::helmert7 ||
         t.model == io::TransformModel::helmert14 || t.model == io::TransformModel::molodensky_badekas;
}

void print_text(const solver::Diagnosis& d, const std::string& control) {
  std::cout << "geoanchor diagnose: " << control << " (" << d.points_used << " points in use)\n"
            << "  baseline:    " << d.baseline << ", residual RMS " << format_fixed(d.residual_rms_m, 4) << " m\n"
            << "  noise:       RMS " << format_fixed(d.noise_rms_m, 4) << " m per point (3-D)"
            << (d.sigmas_assumed ? ", from the assumed --sigma (the set gives no sigmas)" : ", from the set's sigmas") << "\n"
            << "  expectation: " << d.expectation << "\n";
  if (d.global_test_passed) std::cout << "  global test: " << (*d.global_test_passed ? "passed" : "FAILED") << "\n";
  std::cout << "\n  rank  hypothesis           score   RMS before     RMS after  explains\n";
  int rank = 1;
  for (const auto& h : d.hypotheses) {
    char line[200];
    if (h.applicable) {
      char score[32];
      std::snprintf(score, sizeof score, std::fabs(h.score) < 1e4 ? "%.2f" : "%.2e", h.score);
      std::snprintf(line, sizeof line, "  %4d  %-16s %9s %10.4f m  %10.4f m  %s\n", rank,
                    std::string(solver::to_string(h.name)).c_str(), score, h.rms_before_m, h.rms_after_m,
                    h.explains ? "YES" : "no");
    } else {
      std::snprintf(line, sizeof line, "  %4d  %-16s         –   not tested\n", rank, std::string(solver::to_string(h.name)).c_str());
    }
    std::cout << line << "        " << h.effect << "\n";
    ++rank;
  }
  std::cout << "\n  (score: log10 Bayes factor against \"no mistake\"; >= 2 is decisive)\n\nverdict: " << d.verdict << "\n";
}

}  // namespace

void run_diagnose(const DiagnoseCommandOptions& o) {
  io::ControlReadOptions ro;
  if (o.ellipsoid) ro.ellipsoid = parse_ellipsoid(*o.ellipsoid, "--ellipsoid");
  if (o.origin) ro.origin = parse_origin(*o.origin, "--origin", ro.ellipsoid.value_or(geodesy::Ellipsoid::wgs84()));
  apply_control_grids(o.grids, ro);

  solver::DiagnoseOptions d;
  d.fit.model = parse_model(o.model, "--model");
  if (o.convention) d.fit.convention = parse_convention(*o.convention, "--convention");
  d.fit.nominal_origin = ro.origin;
  if (o.sigma) d.assumed_sigma_m = *o.sigma;
  if ((d.fit.model == solver::FitModel::enu_origin || d.fit.model == solver::FitModel::site_calibration) && !ro.origin) {
    throw Error(ErrorKind::usage, "E_ORIGIN_MISSING",
                "--origin: the " + std::string(solver::to_string(d.fit.model)) + " model needs the origin LAT,LON,H");
  }

  std::optional<io::TransformFile> tf, swapped;
  if (o.transform) {
    tf = io::read_transform_file(*o.transform);
    if (has_rotations(*tf)) swapped = with_other_convention(*tf);
  }
  const geodesy::GeoidGrid* geoid = o.geoid ? &parse_geoid(*o.geoid, "--geoid") : nullptr;
  ro.src_geoid = ro.dst_geoid = geoid;
  if (o.source_frame) ro.source_frame.replace = geodesy::Frame::parse(*o.source_frame, "--source-frame");
  if (o.target_frame) ro.target_frame.replace = geodesy::Frame::parse(*o.target_frame, "--target-frame");
  if (tf) {
    ro.source_frame.fallback = tf->source_frame;
    ro.target_frame.fallback = tf->target_frame;
  }
  ControlInput in = read_control_input(o.control, ro);
  geodesy::ControlSet& set = in.set;
  // A dynamic frame given here needs its epoch, as in the file, unless every point has one.
  const bool every_point_dated = !set.points.empty() && std::all_of(set.points.begin(), set.points.end(),
                                                                    [](const auto& p) { return p.epoch.has_value(); });
  const std::string other_way = ", or an epoch for every point";
  if (!every_point_dated && o.source_frame) {
    geodesy::require_epoch_if_dynamic(*set.source_frame, "--source-frame", ErrorKind::usage, other_way);
  }
  if (!every_point_dated && o.target_frame) {
    geodesy::require_epoch_if_dynamic(*set.target_frame, "--target-frame", ErrorKind::usage, other_way);
  }
  if (tf) {
    const std::string where = *o.transform;
    solver::GivenTransform g;
    g.apply = [&tf, where](const geodesy::EcefPosition& x, std::optional<geodesy::DecimalYear> t) {
      return tf->apply(x, t, false, where + " (a point without epoch)");
    };
    if (swapped) {
      g.apply_swapped = [&swapped, where](const geodesy::EcefPosition& x, std::optional<geodesy::DecimalYear> t) {
        return swapped->apply(x, t, false, where);
      };
    }
    g.description = *o.transform + " (" + std::string(io::to_string(tf->model)) +
                    (has_rotations(*tf) ? ", " + std::string(tf->convention_name()) : std::string()) + ")";
    d.transform = std::move(g);
  }
  d.geoid = geoid ? geoid : &geodesy::GeoidGrid::egm96();

  const solver::Diagnosis r = solver::diagnose(set, d);
  if (!o.json) {
    print_text(r, in.name);
    io::finish_standard_output("the diagnosis");
    return;
  }
  nlohmann::ordered_json j;
  j["schema"] = "geoanchor.diagnosis/1";
  j["problem_found"] = r.problem_found;
  j["verdict"] = r.verdict;
  j["hypotheses"] = nlohmann::ordered_json::array();
  for (const auto& h : r.hypotheses) {
    nlohmann::ordered_json e;
    e["name"] = std::string(solver::to_string(h.name));
    e["score"] = h.score;
    e["rms_before_m"] = h.rms_before_m;
    e["rms_after_m"] = h.rms_after_m;
    e["effect"] = h.effect;
    e["applicable"] = h.applicable;
    e["explains"] = h.explains;
    j["hypotheses"].push_back(std::move(e));
  }
  j["baseline"] = r.baseline;
  j["expectation"] = r.expectation;
  j["residual_rms_m"] = r.residual_rms_m;
  j["noise_rms_m"] = r.noise_rms_m;
  j["points_used"] = r.points_used;
  std::cout << j.dump(2) << '\n';
  io::finish_standard_output("the diagnosis");
}

}  // namespace geoanchor::cli
