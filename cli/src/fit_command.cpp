#include "fit_command.hpp"

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <numeric>

#include "geoanchor/geodesy/error.hpp"
#include "geoanchor/geodesy/number_text.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/io/control_csv.hpp"
#include "geoanchor/io/transform_file.hpp"
#include "geoanchor/solver/helmert_fit.hpp"
#include "geoanchor/solver/model_comparison.hpp"
#include "option_parsing.hpp"
#include "version.hpp"

namespace geoanchor::cli {
namespace {

using solver::FitModel;

FitModel parse_model(const std::string& m) {
  if (m == "helmert7") return FitModel::helmert7;
  if (m == "helmert6") return FitModel::helmert6;
  if (m == "translation3") return FitModel::translation3;
  if (m == "helmert14") return FitModel::helmert14;
  if (m == "molodensky-badekas") return FitModel::molodensky_badekas;
  if (m == "enu-origin") return FitModel::enu_origin;
  if (m == "site-calibration") return FitModel::site_calibration;
  throw Error(ErrorKind::usage, "E_OPTION",
              "--model " + m + ": expected translation3, helmert6, helmert7, helmert14, molodensky-badekas, enu-origin "
                               "or site-calibration");
}

std::string fixed(double v, int decimals) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", decimals, v);
  return b;
}

// The printed report: parameters, statistics with verdict, residuals with
// flagged points first.
void print_report(std::ostream& out, const solver::FitResult& r, const geodesy::ControlSet& set,
                  const FitCommandOptions& o) {
  out << "geoanchor fit: model " << solver::to_string(r.model);
  if (r.model != FitModel::translation3 && r.model != FitModel::enu_origin && r.model != FitModel::site_calibration) {
    out << ", " << (r.convention == solver::Convention::position_vector ? "position vector" : "coordinate frame")
        << " convention, " << geodesy::to_string(r.rotation_model) << " rotation matrix";
  }
  out << "\n  control: " << set.source_name << " (" << set.points.size() << " points)";
  if (set.source_frame || set.target_frame) {
    out << "; " << (set.source_frame ? set.source_frame->to_string() : "?") << " -> "
        << (set.target_frame ? set.target_frame->to_string() : "?");
  }
  if (r.reference_epoch) out << "; reference epoch " << geodesy::format_decimal_year(*r.reference_epoch);
  out << "\n\nParameters (" << (r.covariance_scaled_by_sigma0 ? "σ scaled by the a-posteriori σ0" : "σ from the a-priori weights, σ0 = 1")
      << ")\n";
  for (const auto& p : r.parameters) {
    const bool angle = p.name.find("arcsec") != std::string::npos, scale = p.name.find("ppm") != std::string::npos;
    const int decimals = angle ? 6 : scale ? 5 : 4;
    char line[160];
    if (p.estimated) {
      std::snprintf(line, sizeof line, "  %-22s %18s  ± %s\n", p.name.c_str(), fixed(p.value, decimals).c_str(),
                    fixed(p.sigma, decimals).c_str());
    } else {
      std::snprintf(line, sizeof line, "  %-22s %18s  (fixed)\n", p.name.c_str(), fixed(p.value, decimals).c_str());
    }
    out << line;
  }
  const auto& g = r.global_test;
  out << "\nStatistics\n  σ0 = " << fixed(r.sigma0, 3) << ", dof = " << r.dof << "\n";
  if (r.variance_factors) {
    out << "  variance factors (--vce): source " << fixed(r.variance_factors->first, 3) << ", target "
        << fixed(r.variance_factors->second, 3) << " (σ scale " << fixed(std::sqrt(r.variance_factors->first), 3) << ", "
        << fixed(std::sqrt(r.variance_factors->second), 3) << ")\n";
  }
  if (g.applicable) {
    out << "  global test (χ², α = " << o.alpha << "): " << fixed(g.statistic, 2) << " in [" << fixed(g.critical_lower, 2)
        << ", " << fixed(g.critical_upper, 2) << "]: "
        << (g.passed ? "PASSED" : g.statistic > g.critical_upper ? "FAILED (high)" : "FAILED (low)") << "\n";
  } else {
    out << "  global test: not applicable (no a-priori sigmas, or no redundancy)\n";
  }
  std::vector<std::size_t> order(r.points.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const auto rank = [&](const solver::PointResult& p) { return p.outlier ? 0 : !p.used ? 1 : 2; };
    if (rank(r.points[a]) != rank(r.points[b])) return rank(r.points[a]) < rank(r.points[b]);
    return r.points[a].w_max > r.points[b].w_max;
  });
  out << "\nResiduals (target − transformed source, local E/N/U, mm); w-tests critical |w| = " << fixed(r.w_critical, 2)
      << "\n  id            dE       dN       dU      wE     wN     wU    MDB mm  status\n";
  for (std::size_t i : order) {
    const auto& p = r.points[i];
    char line[200];
    const std::string mdb = std::isfinite(p.mdb_m) ? fixed(1e3 * p.mdb_m, 1) : "-";
    const std::string status = p.outlier ? "OUTLIER (removed)" : !p.used ? "not used"
                               : p.robust_weight < 1.0 ? "weight " + fixed(p.robust_weight, 3) : "ok";
    std::snprintf(line, sizeof line, "  %-10s %8.1f %8.1f %8.1f  %6.2f %6.2f %6.2f  %8s  %s\n", p.id.c_str(),
                  1e3 * p.residual_enu_m.x(), 1e3 * p.residual_enu_m.y(), 1e3 * p.residual_enu_m.z(), p.w_enu.x(),
                  p.w_enu.y(), p.w_enu.z(), mdb.c_str(), status.c_str());
    out << line;
  }
  for (const auto& p : r.points) {
    if (p.outlier) out << "  " << p.id << ": " << p.removed_because << "\n";
  }
  out << "  (points not used are tested against the final fit: residuals at full size, prediction w-tests)\n";
  if (!r.warnings.empty()) out << "\n" << r.warnings.size() << " warning(s): see standard error and the transform file\n";
}

io::TransformFile transform_file_from(const solver::FitResult& r, const geodesy::ControlSet& set,
                                      const FitCommandOptions& o) {
  io::TransformFile t;
  switch (r.model) {
    case FitModel::translation3: t.model = io::TransformModel::translation3; break;
    case FitModel::helmert6: t.model = io::TransformModel::helmert6; break;
    case FitModel::helmert7: t.model = io::TransformModel::helmert7; break;
    case FitModel::helmert14: t.model = io::TransformModel::helmert14; break;
    case FitModel::molodensky_badekas: t.model = io::TransformModel::molodensky_badekas; break;
    case FitModel::enu_origin: t.model = io::TransformModel::enu_origin; break;
    case FitModel::site_calibration: t.model = io::TransformModel::site_calibration; break;
  }
  t.pivot_m = r.pivot_m;
  t.site_calibration = r.site_calibration;
  if (r.model == FitModel::enu_origin) {
    auto value = [&](const char* name) {
      for (const auto& p : r.parameters) {
        if (p.name == name) return p.value;
      }
      return 0.0;
    };
    t.enu_origin = io::EnuOriginCorrection{*r.nominal_origin,
                                           Eigen::Vector3d(value("shift_e_m"), value("shift_n_m"), value("shift_u_m")),
                                           geodesy::Angle::arcseconds(value("yaw_arcsec")),
                                           geodesy::ScaleDifference::ppm(value("ds_ppm"))};
  }
  t.rotation_model = r.rotation_model;
  t.source_frame = set.source_frame;
  t.target_frame = set.target_frame;
  t.reference_epoch = r.reference_epoch;
  const bool pv = r.convention == solver::Convention::position_vector;
  if (r.model == FitModel::helmert14) {
    if (pv) {
      t.helmert = r.helmert;
    } else {
      t.helmert = geodesy::to_coordinate_frame(r.helmert);
    }
  } else {
    geodesy::Helmert7<geodesy::PositionVector> h = r.helmert.at_reference_epoch;
    if (r.pivot_m) {
      // The file holds the pivot form: T_p = T + (1 + ds) R p − p.
      const geodesy::AffineMap m = geodesy::target_from_source(h, r.rotation_model);
      h.t_m = m.translation_m() + m.linear() * *r.pivot_m - *r.pivot_m;
    }
    if (pv) {
      t.helmert = h;
    } else {
      t.helmert = geodesy::to_coordinate_frame(h);
    }
  }
  io::FitRecord f;
  for (const auto& p : r.parameters) {
    if (p.estimated) f.sigmas.emplace_back(p.name, p.sigma);
  }
  f.correlation_names = r.covariance_names;
  for (Eigen::Index i = 0; i < r.correlation.rows(); ++i) {
    std::vector<double> row;
    for (Eigen::Index j = 0; j < r.correlation.cols(); ++j) row.push_back(r.correlation(i, j));
    f.correlation.push_back(row);
  }
  f.sigmas_scaled_by_sigma0 = r.covariance_scaled_by_sigma0;
  f.sigma0 = r.sigma0;
  f.dof = r.dof;
  f.alpha = o.alpha;
  f.alpha_point = o.alpha_point;
  f.global_statistic = r.global_test.statistic;
  f.global_critical_lower = r.global_test.critical_lower;
  f.global_critical_upper = r.global_test.critical_upper;
  f.global_passed = r.global_test.passed;
  f.global_applicable = r.global_test.applicable;
  for (const auto& p : r.points) {
    io::FitPointRecord q;
    q.id = p.id;
    for (int k = 0; k < 3; ++k) {
      q.residual_enu_m[static_cast<std::size_t>(k)] = p.residual_enu_m(k);
      q.w_enu[static_cast<std::size_t>(k)] = p.w_enu(k);
      q.redundancy_enu[static_cast<std::size_t>(k)] = p.redundancy_enu(k);
    }
    Eigen::Index worst = 0;
    p.w_enu.cwiseAbs().maxCoeff(&worst);
    q.w_test = p.w_enu(worst);
    q.mdb_m = p.mdb_m;
    q.point_test = p.point_statistic;
    q.point_test_dof = p.point_dof;
    q.point_test_p = p.point_p_value;
    q.outlier = p.outlier;
    q.used = p.used;
    q.note = p.removed_because;
    q.robust_weight = p.robust_weight;
    f.points.push_back(q);
  }
  f.warnings = r.warnings;
  f.variance_factors = r.variance_factors;
  // The network's extent (source frame): the marks the fit used.
  std::vector<geodesy::EcefPosition> used_marks;
  for (const auto& p : r.points) {
    if (!p.used) continue;
    for (const auto& c : set.points) {
      if (c.id == p.id) {
        used_marks.push_back(c.source);
        break;
      }
    }
  }
  if (!used_marks.empty()) f.extent = io::ControlExtent::of(used_marks);
  std::string cmd;
  for (const auto& a : o.argv) cmd += (cmd.empty() ? "" : " ") + a;
  f.generator = "geoanchor " GEOANCHOR_VERSION ": " + cmd;
  t.fit = f;
  return t;
}

}  // namespace

CLI::App* add_fit_command(CLI::App& app, FitCommandOptions& o) {
  auto* cmd = app.add_subcommand("fit", "Fit a datum transform to control points, with statistics");
  cmd->add_option("CONTROL", o.control, "Control set (CSV or JSON)")->required();
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
  cmd->add_option("--ellipsoid", o.ellipsoid, "Ellipsoid of geodetic/ENU control coordinates (default WGS84)");
  cmd->add_option("--source-frame", o.source_frame, "Source frame NAME[@EPOCH] (overrides the file's)");
  cmd->add_option("--target-frame", o.target_frame, "Target frame NAME[@EPOCH] (overrides the file's)");
  cmd->add_option("--alpha", o.alpha, "Significance of the global test (default 0.05)")->check(CLI::Range(1e-6, 0.5));
  cmd->add_option("--alpha-point", o.alpha_point, "Significance of point tests and data snooping (default 0.001)")
      ->check(CLI::Range(1e-9, 0.5));
  cmd->add_flag("--no-snooping", o.no_snooping, "Report outliers but remove none");
  cmd->add_flag("--scale-by-sigma0", o.scale_by_sigma0, "Scale parameter sigmas by the a-posteriori σ0");
  cmd->add_flag("--accept-failed-global-test", o.accept_failed_global_test,
                "Write the transform even if the global test fails high");
  cmd->add_option("-o,--output", o.output, "Transform file (JSON) to write");
  cmd->add_flag("--overwrite", o.overwrite, "Replace an existing output");
  return cmd;
}

namespace {

// Fits every model the data allow on the same points (no data snooping, so
// that the information criterion compares like with like) and prints them.
int run_compare(const geodesy::ControlSet& set, const solver::FitOptions& base) {
  std::cout << "geoanchor fit --compare: " << set.source_name << " (" << set.points.size()
            << " points; data snooping off so that every model sees the same points)\n";
  if (!base.convention) std::cout << "  (give --convention to include the models with rotations)\n";
  std::cout << "\n  model              u    dof      σ0   global test        max|w|        AIC\n";
  const auto rows = solver::compare_models(set, base);
  const solver::ModelComparison* best = nullptr;
  for (const auto& c : rows) {
    char line[200];
    const std::string name(solver::to_string(c.model));
    if (!c.fit) {
      std::snprintf(line, sizeof line, "  %-16s refused: ", name.c_str());
      std::cout << line << c.refused << "\n";
      continue;
    }
    const auto& g = c.fit->global_test;
    const std::string verdict = !g.applicable ? "n/a" : g.passed ? "PASSED" : g.statistic > g.critical_upper ? "FAILED high" : "FAILED low";
    std::snprintf(line, sizeof line, "  %-16s %3d %6d %8.3f   %-12s %10.2f %10.1f\n", name.c_str(), c.parameters, c.fit->dof,
                  c.fit->sigma0, verdict.c_str(), c.max_w, c.aic);
    std::cout << line;
    if (!best || c.aic < best->aic) best = &c;
  }
  if (best) {
    std::cout << "\n  lowest AIC: " << solver::to_string(best->model)
              << " (AIC = Ω + 2u with a-priori sigmas; differences above ~10 are strong evidence)\n";
  }
  return 0;
}

}  // namespace

int run_fit(const FitCommandOptions& o) {
  if (o.model.empty() && !o.compare) {
    throw Error(ErrorKind::usage, "E_OPTION", "--model: required (or --compare to fit every applicable model)");
  }
  if (!o.model.empty() && o.compare) {
    throw Error(ErrorKind::usage, "E_OPTION", "--model and --compare: give one");
  }
  if (o.compare && !o.output.empty()) {
    throw Error(ErrorKind::usage, "E_OPTION", "--compare writes no transform file: drop -o, then fit the chosen model");
  }
  solver::FitOptions fo;
  fo.model = o.compare ? FitModel::helmert7 : parse_model(o.model);
  if (o.convention) {
    if (*o.convention == "position_vector") {
      fo.convention = solver::Convention::position_vector;
    } else if (*o.convention == "coordinate_frame") {
      fo.convention = solver::Convention::coordinate_frame;
    } else {
      throw Error(ErrorKind::usage, "E_OPTION", "--convention " + *o.convention + ": expected position_vector or coordinate_frame");
    }
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
  fo.data_snooping = !o.no_snooping;
  fo.scale_by_sigma0 = o.scale_by_sigma0;

  // Refuse an existing output before any work.
  std::unique_ptr<io::AtomicOutputFile> out;
  if (!o.output.empty()) {
    io::refuse_same_file(o.control, o.output);
    out = std::make_unique<io::AtomicOutputFile>(o.output, o.overwrite ? io::Overwrite::allow : io::Overwrite::refuse);
  }

  io::ControlReadOptions ro;
  ro.ellipsoid = parse_ellipsoid(o.ellipsoid, "--ellipsoid");
  if (o.origin) ro.origin = parse_origin(*o.origin, "--origin", ro.ellipsoid);
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
      fo.site_grid = geodesy::ProjectionDef{ro.ellipsoid, parse_tm(*o.tm, "--tm"), std::nullopt};
    }
    fo.enu_yaw = !o.fix_yaw;
    fo.enu_scale = o.with_scale;
  } else if (o.fix_yaw || o.with_scale) {
    throw Error(ErrorKind::usage, "E_OPTION", "--fix-yaw/--with-scale: only for --model enu-origin");
  }
  geodesy::ControlSet set = io::read_control_set(o.control, ro);
  if (o.source_frame) set.source_frame = geodesy::Frame::parse(*o.source_frame, "--source-frame");
  if (o.target_frame) set.target_frame = geodesy::Frame::parse(*o.target_frame, "--target-frame");
  std::vector<std::string> frame_warnings;
  for (const auto* f : {&set.source_frame, &set.target_frame}) {
    if (*f && (*f)->datum() == "WGS84" && (*f)->realization().empty()) {
      frame_warnings.push_back("frame " + (*f)->to_string() +
                               " is the WGS 84 ensemble: its realizations differ by up to about 2 m; name one, e.g. "
                               "WGS84(G2139)");
    }
  }
  if (o.compare) {
    for (const auto& w : frame_warnings) std::cerr << "geoanchor: warning: " << w << '\n';
    return run_compare(set, fo);
  }

  solver::FitResult r = solver::fit_helmert(set, fo);
  r.warnings.insert(r.warnings.begin(), frame_warnings.begin(), frame_warnings.end());
  print_report(std::cout, r, set, o);
  for (const auto& w : r.warnings) std::cerr << "geoanchor: warning: " << w << '\n';

  const auto& g = r.global_test;
  if (g.applicable && g.statistic > g.critical_upper && !o.accept_failed_global_test) {
    std::cerr << "geoanchor: error[E_FIT_GLOBAL_TEST]: " << o.control << ": global test failed high (" << fixed(g.statistic, 2)
              << " > " << fixed(g.critical_upper, 2) << ", σ0 = " << fixed(r.sigma0, 3)
              << "): the residuals do not fit the stated sigmas; no transform was written. hint: look for blunders "
                 "(residual table), wrong sigmas, or a wrong model; --accept-failed-global-test writes it anyway\n";
    return exit_code(ErrorKind::rejected);
  }
  if (out) {
    out->stream() << io::to_json_text(transform_file_from(r, set, o));
    out->commit();
    std::cout << "\nwrote " << o.output << "\n";
  }
  return 0;
}

}  // namespace geoanchor::cli
