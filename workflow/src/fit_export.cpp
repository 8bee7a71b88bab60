#include "geoanchor/workflow/fit_export.hpp"
#include "geoanchor/workflow/fit_checks.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <future>
#include <limits>
#include <numeric>
#include <ostream>
#include <system_error>
#include <utility>

#include "geoanchor/base/number_text.hpp"

namespace geoanchor::workflow {

namespace {
// A mark left out by the input (use = 0) whose prediction test fails.
bool fails_prediction(const solver::PointResult& p, double alpha_point) {
  return !p.used && !p.outlier && p.point_dof > 0 && p.point_p_value < alpha_point;
}
}  // namespace

using solver::FitModel;

// The printed report: parameters, statistics with verdict, residuals with
// flagged points first.
void write_fit_report(std::ostream& out, const solver::FitResult& r, const geodesy::ControlSet& set,
                      const solver::FitOptions& o) {
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
  if (const auto rec = solution_record(r, set, o)) {
    // Per GNSS solution type: marks, and how many the fit used or left out for it.
    out << "\n  GNSS solutions (" << (rec->policy == geodesy::SolutionPolicy::exclude
                                         ? "float and worse left out; --solution-weighting weighs them"
                                         : "weighted: sigmas × factor; dead_reckoned left out")
        << "):";
    bool first = true;
    for (const auto s : geodesy::kGnssSolutions) {
      const io::SolutionTally& t = rec->classes[geodesy::solution_index(s)];
      if (t.marks == 0) continue;
      out << (first ? " " : ", ") << geodesy::to_string(s) << " " << t.marks << " (used " << t.used;
      if (t.excluded) out << ", left out " << t.excluded;
      if (t.sigma_factor != 1.0 && t.used) out << ", σ × " << format_shortest(t.sigma_factor);
      out << ")";
      first = false;
    }
  }
  out << "\n\nParameters (" << (r.covariance_scaled_by_sigma0 ? "σ scaled by the a-posteriori σ0" : "σ from the a-priori weights, σ0 = 1")
      << ")\n";
  for (const auto& p : r.parameters) {
    const bool angle = p.name.find("arcsec") != std::string::npos, scale = p.name.find("ppm") != std::string::npos;
    const int decimals = angle ? 6 : scale ? 5 : 4;
    char line[160];
    if (p.estimated) {
      std::snprintf(line, sizeof line, "  %-22s %18s  ± %s\n", p.name.c_str(), format_fixed(p.value, decimals).c_str(),
                    format_fixed(p.sigma, decimals).c_str());
    } else {
      std::snprintf(line, sizeof line, "  %-22s %18s  (fixed)\n", p.name.c_str(), format_fixed(p.value, decimals).c_str());
    }
    out << line;
  }
  const auto& g = r.global_test;
  out << "\nStatistics\n  σ0 = " << (r.sigma0 ? format_fixed(*r.sigma0, 3) : "undefined (no redundancy)") << ", dof = " << r.dof
      << "\n";
  if (r.variance_factors) {
    out << "  variance factors (--vce): source " << format_fixed(r.variance_factors->first, 3) << ", target "
        << format_fixed(r.variance_factors->second, 3) << " (σ scale " << format_fixed(std::sqrt(r.variance_factors->first), 3) << ", "
        << format_fixed(std::sqrt(r.variance_factors->second), 3) << ")\n";
  }
  if (g.applicable) {
    out << "  global test (χ², α = " << o.alpha << "): " << format_fixed(g.statistic, 2) << " in [" << format_fixed(g.critical_lower, 2)
        << ", " << format_fixed(g.critical_upper, 2) << "]: "
        << (g.passed ? "PASSED" : g.failed_high() ? "FAILED (high)" : "FAILED (low)") << "\n";
  } else {
    out << "  global test: not applicable (no a-priori sigmas, or no redundancy)\n";
  }
  // Removed marks first, then unused ones, then by decreasing max |w| (an
  // untestable mark's NaN last; equal keys in file order). Large sets show
  // every mark that is not "ok" and the largest |w| of the rest; the
  // transform file's points hold every mark. Only the rows shown are sorted
  // (10⁶ marks: the 50 largest are kept in a heap as the marks go by, not
  // all of them sorted or even held), on keys of 24 bytes, not whole
  // PointResults.
  struct Key {
    int rank;
    double w;
    std::size_t i;
  };
  const auto before = [](const Key& a, const Key& b) {
    return a.rank != b.rank ? a.rank < b.rank : a.w != b.w ? a.w > b.w : a.i < b.i;
  };
  const auto is_ok = [&](const solver::PointResult& p) {
    return p.status(o.alpha_point) == solver::TestStatus::used && !(p.robust_weight < 1.0);
  };
  constexpr std::size_t kAllRowsUpTo = 1000, kOkRowsOfLargeSets = 50;
  const bool large = r.points.size() > kAllRowsUpTo;
  std::vector<Key> shown, ok_keys;  // ok_keys: a heap whose top is the last of them in `before` order
  std::vector<std::size_t> removed;  // the outliers, in file order (one pass over the marks: 10⁶ are 270 MB)
  std::size_t ok_hidden = 0;
  for (std::size_t i = 0; i < r.points.size(); ++i) {
    const auto& p = r.points[i];
    if (p.outlier) removed.push_back(i);
    // Removed first, then flagged, then the rest (the ignored last); by |w| within each.
    const solver::TestStatus st = p.status(o.alpha_point);
    const int group = st == solver::TestStatus::removed ? 0 : st == solver::TestStatus::flagged ? 1 : st == solver::TestStatus::ignored ? 3 : 2;
    const Key k{group, std::isnan(p.w_max) ? -std::numeric_limits<double>::infinity() : p.w_max, i};
    if (!large || !is_ok(p)) {
      shown.push_back(k);
      continue;
    }
    if (ok_keys.size() < kOkRowsOfLargeSets) {
      ok_keys.push_back(k);
      std::push_heap(ok_keys.begin(), ok_keys.end(), before);
      continue;
    }
    ++ok_hidden;
    if (!before(k, ok_keys.front())) continue;  // most marks: one comparison
    std::pop_heap(ok_keys.begin(), ok_keys.end(), before);
    ok_keys.back() = k;
    std::push_heap(ok_keys.begin(), ok_keys.end(), before);
  }
  shown.insert(shown.end(), ok_keys.begin(), ok_keys.end());
  std::sort(shown.begin(), shown.end(), before);
  out << "\nResiduals (target − transformed source, local E/N/U, mm); w-tests critical |w| = " << format_fixed(r.w_critical, 2)
      << "\n  id            dE       dN       dU      wE     wN     wU    MDB mm  status        snooping rank\n";
  for (const Key& k : shown) {
    const auto& p = r.points[k.i];
    char line[200];
    const std::string mdb = std::isfinite(p.mdb_m) ? format_fixed(1e3 * p.mdb_m, 1) : "-";
    const solver::TestStatus st = p.status(o.alpha_point);
    std::string status = solver::to_string(st);
    if (st == solver::TestStatus::used && p.robust_weight < 1.0) status += " (weight " + format_fixed(p.robust_weight, 3) + ")";
    // A mark the input left out is a check of the transform: its failing
    // prediction test is a finding, not something to hide behind "ignored".
    if (st == solver::TestStatus::ignored && fails_prediction(p, o.alpha_point)) status = "ignored, FAILS";
    if (p.snooping_rank > 0 || p.passes_after_rank > 0) {
      status.resize(std::max<std::size_t>(status.size(), 12), ' ');
      status += "  " + (p.snooping_rank > 0 ? std::to_string(p.snooping_rank)
                                           : "- (passes once rank " + std::to_string(p.passes_after_rank) + " is out)");
    }
    const auto w = [](double v) { return std::isfinite(v) ? format_fixed(v, 2) : std::string("-"); };
    std::snprintf(line, sizeof line, "  %-10s %8.1f %8.1f %8.1f  %6s %6s %6s  %8s  %s\n", p.id.c_str(),
                  1e3 * p.residual_enu_m.x(), 1e3 * p.residual_enu_m.y(), 1e3 * p.residual_enu_m.z(), w(p.w_enu.x()).c_str(),
                  w(p.w_enu.y()).c_str(), w(p.w_enu.z()).c_str(), mdb.c_str(), status.c_str());
    out << line;
  }
  if (ok_hidden > 0) {
    out << "  ... and " << ok_hidden << " more marks, all used and passing, with smaller |w| (every mark is in the transform "
        << "file's points)\n";
  }
  for (const std::size_t i : removed) out << "  " << r.points[i].id << ": " << r.points[i].removed_because << "\n";
  out << "  (flagged: fails its point test at alpha_point " << format_shortest(o.alpha_point)
      << ", kept; removed: by --remove-outliers; the snooping rank is the order in which iterative data snooping removes "
         "them, strongest evidence first; marks not used are tested against the final fit: residuals at full size, "
         "prediction w-tests; 'ignored, FAILS': such a mark fails its test, and the transform does not hold there)\n";
  if (!r.warnings.empty()) out << "\n" << r.warnings.size() << " warning(s): see standard error and the transform file\n";
}

namespace {

// The per-point record of `p` in a transform file.
void point_record(const solver::PointResult& p, double alpha_point, const std::vector<std::string>& left_out, io::FitPointRecord& q) {
  q.id = p.id;
  for (int k = 0; k < 3; ++k) {
    q.residual_enu_m[static_cast<std::size_t>(k)] = p.residual_enu_m(k);
    q.w_enu[static_cast<std::size_t>(k)] = p.w_enu(k);
    q.redundancy_enu[static_cast<std::size_t>(k)] = p.redundancy_enu(k);
  }
  // The w-test of largest magnitude among the testable axes (NaN: none is).
  q.w_test = std::numeric_limits<double>::quiet_NaN();
  for (int k = 0; k < 3; ++k) {
    if (std::isfinite(p.w_enu(k)) && !(std::fabs(p.w_enu(k)) <= std::fabs(q.w_test))) q.w_test = p.w_enu(k);
  }
  q.mdb_m = p.mdb_m;
  q.point_test = p.point_statistic;
  q.point_test_dof = p.point_dof;
  q.point_test_p = p.point_p_value;
  q.outlier = p.outlier;
  q.used = p.used;
  q.status = solver::to_string(p.status(alpha_point));
  q.snooping_rank = p.snooping_rank;
  q.note = p.removed_because;
  if (std::find(left_out.begin(), left_out.end(), p.id) != left_out.end()) q.note = kLeftOutInWorkbench;
  if (p.status(alpha_point) == solver::TestStatus::ignored && fails_prediction(p, alpha_point)) {
    q.note = (q.note.empty() ? "" : q.note + "; ") + "not used, and fails its prediction test at alpha_point " +
             format_shortest(alpha_point) + ": the transform does not hold at this mark";
  }
  q.robust_weight = p.robust_weight;
}

}  // namespace

void record_statistics(io::FitRecord& f, std::optional<double> sigma0, int dof, double alpha, double alpha_point,
                       const solver::GlobalTest& global_test) {
  f.sigma0 = sigma0;
  f.dof = dof;
  f.alpha = alpha;
  f.alpha_point = alpha_point;
  f.global_statistic = global_test.statistic;
  f.global_critical_lower = global_test.critical_lower;
  f.global_critical_upper = global_test.critical_upper;
  f.global_passed = global_test.passed;
  f.global_applicable = global_test.applicable;
}

io::TransformFile transform_file_from_fit(const solver::FitResult& r, const geodesy::ControlSet& set,
                                          const solver::FitOptions& o, const std::vector<std::string>& left_out,
                                          const std::string& generator, const io::SurveyMetadata* survey) {
  StreamedTransformFile streamed = streamed_transform_file_from_fit(r, set, o, left_out, generator, survey);
  io::TransformFile& t = streamed.file;
  t.fit->points.resize(streamed.points.count);
  for (std::size_t i = 0; i < streamed.points.count; ++i) streamed.points.record(i, t.fit->points[i]);
  return std::move(t);
}

namespace {

// The extent of the marks set.points[i] for which used(i) holds.
template <class Used>
std::optional<io::ControlExtent> extent_of(const geodesy::ControlSet& set, std::size_t count, const Used& used) {
  std::vector<geodesy::EcefPosition> marks;
  marks.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    if (used(i)) marks.push_back(set.points[i].source);
  }
  if (marks.empty()) return std::nullopt;
  return io::ControlExtent::of(marks);
}

// The extent of the marks `r` used. r.points[i] is set.points[i] (the
// solver keeps the input order; an id may repeat at other epochs, so the
// index, not the id, names the mark).
std::optional<io::ControlExtent> used_marks_extent(const solver::FitResult& r, const geodesy::ControlSet& set) {
  return extent_of(set, std::min(r.points.size(), set.points.size()), [&](std::size_t i) { return r.points[i].used; });
}

StreamedTransformFile streamed_file(const solver::FitResult& r, const geodesy::ControlSet& set, const solver::FitOptions& o,
                                    const std::vector<std::string>& left_out, const std::string& generator,
                                    std::optional<io::ControlExtent> extent, const io::SurveyMetadata* survey) {
  StreamedTransformFile streamed;
  io::TransformFile& t = streamed.file;
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
  // A dynamic frame named without an epoch (every point has its own) is
  // written at the points' mean epoch: a fixed transform holds at one.
  t.source_frame = written_frame(set.source_frame, set, r.model);
  t.target_frame = written_frame(set.target_frame, set, r.model);
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
  record_statistics(f, r.sigma0, r.dof, o.alpha, o.alpha_point, r.global_test);
  f.warnings = r.warnings;
  f.variance_factors = r.variance_factors;
  f.extent = std::move(extent);  // the network's, source frame: the marks the fit used
  f.generator = generator;
  // How roles given in a CRS were read (PROJ's operation and grids): each
  // role's record is a JSON object already.
  auto add_record = [&f](const char* role, const std::string& record) {
    if (record.empty()) return;
    f.control_crs_json += (f.control_crs_json.empty() ? "{\"" : ",\"") + std::string(role) + "\":" + record;
  };
  add_record("source", set.source_input.crs_record_json);
  add_record("target", set.target_input.crs_record_json);
  if (!f.control_crs_json.empty()) f.control_crs_json += "}";
  f.gnss_solutions = solution_record(r, set, o);
  t.fit = std::move(f);
  t.metadata = transform_metadata(r, set, survey);
  streamed.points.count = r.points.size();
  // Each mark's solution type, kept here: the set may be gone when the
  // records are written.
  std::vector<std::optional<geodesy::GnssSolution>> solutions;
  if (set.has_solutions) {
    solutions.reserve(set.points.size());
    for (const auto& p : set.points) solutions.push_back(p.solution);
  }
  streamed.points.record = [&r, left_out, solutions = std::move(solutions)](std::size_t i, io::FitPointRecord& q) {
    point_record(r.points[i], r.alpha_point, left_out, q);
    q.solution = i < solutions.size() ? solutions[i] : std::nullopt;
  };
  return streamed;
}

// The target coordinates' horizontal CRS, as the control set read them.
std::string horizontal_crs_text(const geodesy::ControlInputForm& form, const std::optional<geodesy::Frame>& frame,
                                const std::optional<geodesy::LocalOrigin>& origin) {
  std::string text;
  switch (form.form) {
    case geodesy::CoordinateForm::crs: return form.crs_name;
    case geodesy::CoordinateForm::ecef: text = "geocentric (ECEF)"; break;
    case geodesy::CoordinateForm::geodetic: text = "geographic (latitude, longitude) on " + form.ellipsoid.name(); break;
    case geodesy::CoordinateForm::projected:
      if (form.projection && form.projection->utm) {
        text = "UTM zone " + form.projection->utm->to_string() + " on " + form.ellipsoid.name();
      } else if (form.projection) {
        const auto& tm = form.projection->tm;
        text = "Transverse Mercator (lat0 " + format_shortest(tm.lat0.deg()) + "°, lon0 " + format_shortest(tm.lon0.deg()) +
               "°, k0 " + format_shortest(tm.k0) + ", FE " + format_shortest(tm.false_easting_m) + " m, FN " +
               format_shortest(tm.false_northing_m) + " m) on " + form.ellipsoid.name();
      } else {
        text = "projected";
      }
      break;
    case geodesy::CoordinateForm::enu:
      text = origin ? "local ENU at " + format_shortest(origin->point.lat.deg()) + "°, " +
                          format_shortest(origin->point.lon.deg()) + "°, " + format_shortest(origin->point.h.m) + " m on " +
                          form.ellipsoid.name()
                    : "local ENU";
      break;
  }
  return text + (frame ? " in " + frame->to_string() : "");
}

}  // namespace

std::optional<io::GnssSolutionRecord> solution_record(const solver::FitResult& r, const geodesy::ControlSet& set,
                                                      const solver::FitOptions& o) {
  if (!set.has_solutions) return std::nullopt;
  io::GnssSolutionRecord rec;
  rec.policy = o.solutions;
  for (const auto s : geodesy::kGnssSolutions) {
    rec.classes[geodesy::solution_index(s)].sigma_factor = geodesy::sigma_factor_under(s, o.solutions);
  }
  for (std::size_t i = 0; i < set.points.size(); ++i) {
    const geodesy::ControlPoint& p = set.points[i];
    if (!p.solution) continue;
    io::SolutionTally& t = rec.classes[geodesy::solution_index(*p.solution)];
    ++t.marks;
    if (i < r.points.size() && r.points[i].used) ++t.used;
    if (p.use && !geodesy::used_under(*p.solution, o.solutions)) ++t.excluded;
  }
  return rec;
}

io::MapMetadata transform_metadata(const solver::FitResult& r, const geodesy::ControlSet& set,
                                   const io::SurveyMetadata* survey) {
  using T = io::MapMetadataBuilder::Text;
  io::MapMetadataBuilder b("the transform file of the fit of " + set.source_name);
  const std::string derived = "the fit of " + set.source_name;
  if (set.target_frame) {
    b.frame(set.target_frame->name(), derived + " (target frame)");
    if (set.target_frame->epoch()) b.coordinate_epoch(set.target_frame->epoch()->year, derived + " (target frame)");
  }
  // The map's ENU frame: the nominal origin its local coordinates are read at.
  if (r.nominal_origin && (r.model == FitModel::enu_origin || r.model == FitModel::site_calibration)) {
    const auto& o = r.nominal_origin->point;
    b.enu_origin(io::MetadataOrigin{o.lat.deg(), o.lon.deg(), o.h.m}, derived + " (nominal origin, --origin)");
  }
  const geodesy::ControlInputForm& target = set.target_input;
  b.text(T::horizontal_crs, horizontal_crs_text(target, set.target_frame, set.origin), derived + " (target coordinates)");
  if (target.height_type == geodesy::HeightKind::orthometric) {
    b.text(T::vertical_datum, "orthometric heights (" + target.height_column + ") on the geoid " + target.geoid_model,
           derived + " (target heights)");
    b.text(T::geoid_model, target.geoid_model, derived + " (target heights)");
  } else if (target.form != geodesy::CoordinateForm::crs) {
    b.text(T::vertical_datum, "ellipsoid " + target.ellipsoid.name(), derived + " (target heights)");
  }
  if (set.has_solutions) {
    geodesy::SolutionCounts counts;
    for (const auto& p : set.points) {
      if (p.solution) ++counts.count[geodesy::solution_index(*p.solution)];
    }
    b.gnss_solution_counts(counts, "computed from the solution column of " + set.source_name + " (" +
                                       std::to_string(counts.total()) + " marks)");
  }
  b.text(T::coordinate_storage, "float64 (JSON numbers at full precision)", "the transform file's format");
  if (survey) {
    // A survey of the source side (its frame the set's source frame, not
    // the target's): its frame-bound fields are checked against the source
    // and left out of the contract, which describes the target side.
    const bool of_source = survey->frame && set.source_frame && survey->frame->name() == set.source_frame->name() &&
                           !(set.target_frame && set.target_frame->name() == set.source_frame->name());
    if (of_source) {
      io::MapMetadataBuilder source_side("the fit's source frame (" + set.source_name + ")");
      source_side.frame(set.source_frame->name(), derived + " (source frame)");
      if (set.source_frame->epoch()) source_side.coordinate_epoch(set.source_frame->epoch()->year, derived + " (source frame)");
      source_side.survey(*survey, true);
    }
    b.survey(*survey, !of_source);
  }
  return b.metadata();
}

StreamedTransformFile streamed_transform_file_from_fit(const solver::FitResult& r, const geodesy::ControlSet& set,
                                                       const solver::FitOptions& o,
                                                       const std::vector<std::string>& left_out,
                                                       const std::string& generator, const io::SurveyMetadata* survey) {
  return streamed_file(r, set, o, left_out, generator, used_marks_extent(r, set), survey);
}

StreamedTransformFile streamed_transform_file_from_fit(const FitForExport& fitted, const geodesy::ControlSet& set,
                                                       const solver::FitOptions& o,
                                                       const std::vector<std::string>& left_out,
                                                       const std::string& generator, const io::SurveyMetadata* survey) {
  return streamed_file(fitted.fit, set, o, left_out, generator, fitted.extent, survey);
}

FitForExport fit_for_export(const geodesy::ControlSet& set, const solver::FitOptions& o) {
  // The set is only read, here and by the solver. Should the solve throw,
  // the future's destructor waits for the extent before the set can go.
  const auto extent_to_be_used = [&set] {
    return extent_of(set, set.points.size(), [&](std::size_t i) { return set.points[i].use; });
  };
  std::future<std::optional<io::ControlExtent>> planned;
  try {
    planned = std::async(std::launch::async, extent_to_be_used);
  } catch (const std::system_error&) {  // no thread to be had: formed after the solve, on this one
    planned = std::async(std::launch::deferred, extent_to_be_used);
  }
  FitForExport fitted{solver::fit_helmert(set, o), std::nullopt};
  std::optional<io::ControlExtent> extent = planned.get();
  const auto& points = fitted.fit.points;
  bool same_marks = points.size() == set.points.size();
  for (std::size_t i = 0; same_marks && i < points.size(); ++i) same_marks = points[i].used == set.points[i].use;
  fitted.extent = same_marks ? std::move(extent) : used_marks_extent(fitted.fit, set);
  return fitted;
}


FitChoices fit_choices_from_transform(const io::TransformFile& t) {
  FitChoices c;
  solver::FitOptions& o = c.options;
  switch (t.model) {
    case io::TransformModel::translation3: o.model = FitModel::translation3; break;
    case io::TransformModel::helmert6: o.model = FitModel::helmert6; break;
    case io::TransformModel::helmert7: o.model = FitModel::helmert7; break;
    case io::TransformModel::helmert14: o.model = FitModel::helmert14; break;
    case io::TransformModel::molodensky_badekas: o.model = FitModel::molodensky_badekas; break;
    case io::TransformModel::enu_origin: o.model = FitModel::enu_origin; break;
    case io::TransformModel::site_calibration: o.model = FitModel::site_calibration; break;
  }
  const std::string_view convention = t.convention_name();
  if (convention == "position_vector") {
    o.convention = solver::Convention::position_vector;
  } else if (convention == "coordinate_frame") {
    o.convention = solver::Convention::coordinate_frame;
  }
  o.rotation_model = t.rotation_model;
  o.reference_epoch = t.reference_epoch;
  o.pivot_m = t.pivot_m;
  if (t.enu_origin) {
    o.nominal_origin = t.enu_origin->nominal;
    // Held parameters are exactly 0 and have no σ in the fit record.
    o.enu_yaw = t.enu_origin->yaw.rad() != 0.0;
    o.enu_scale = t.enu_origin->ds.ppm() != 0.0;
    if (t.fit) {
      const auto has_sigma = [&](std::string_view name) {
        return std::any_of(t.fit->sigmas.begin(), t.fit->sigmas.end(), [&](const auto& s) { return s.first == name; });
      };
      o.enu_yaw = has_sigma("yaw_arcsec");
      o.enu_scale = has_sigma("ds_ppm");
    }
  }
  if (t.site_calibration) {
    o.nominal_origin = t.site_calibration->local_origin();
    o.site_grid = t.site_calibration->grid();
  }
  if (t.fit) {
    o.alpha = t.fit->alpha;
    o.alpha_point = t.fit->alpha_point;
    o.scale_by_sigma0 = t.fit->sigmas_scaled_by_sigma0;
    for (const auto& p : t.fit->points) {
      if (p.note == kLeftOutInWorkbench) c.left_out.push_back(p.id);
      // A mark data snooping removed: the fit was made with --remove-outliers.
      if (p.outlier) o.remove_outliers = true;
    }
  }
  return c;
}

}  // namespace geoanchor::workflow
