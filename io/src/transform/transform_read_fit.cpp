// Reading a transform file's fit record, what `geoanchor fit` adds: the
// sigmas and correlation (checked against the model's parameters), the
// statistics, the per-point records, the GNSS solution classes and the
// control extent.

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "transform/transform_common.hpp"

namespace geoanchor::io::detail {
namespace {

using geodesy::Angle;

// Correlations: geoanchor writes them at full precision, so a symmetric
// matrix is symmetric to the last bit and its diagonal is 1 within rounding;
// 1e-9 also accepts a matrix typed in with nine or more digits.
constexpr double kCorrelationTol = 1e-9;
// The smallest eigenvalue of a correlation matrix may be this far below 0:
// rounding a correlation matrix to seven significant digits moves its
// eigenvalues by less than 14 × 5e-8 = 7e-7 (14 parameters at most); a typo
// or a wrong sign moves them by ~1e-2 or more.
constexpr double kCorrelationPsdTol = 1e-6;

// The fit record's sigmas and correlation, checked against the model's
// parameters (point by point: what apply propagates is what the file says).
void parse_sigmas(const json& doc, const TransformFile& t, const ModelParameters& mp, FitRecord& f, std::string_view source) {
  const std::string model(to_string(t.model));
  std::vector<std::string> sigma_keys;  // as the file spells them, in its order
  std::map<std::string, std::string> canonical_of;
  std::vector<std::string> expected;
  for (const auto& e : mp.estimated) expected.push_back(e.key);
  const json* sig = member(doc, "sigmas");
  if (sig) {
    if (!sig->is_object()) fail(source, "sigmas", "expected an object of parameter -> sigma");
    for (const auto& item : sig->items()) {
      // Named copies, not a structured binding: the lambdas below capture
      // them, which clang before 16 refuses for a binding.
      const std::string key = item.key();
      const json& value = item.value();
      const auto e = std::find_if(mp.estimated.begin(), mp.estimated.end(), [&](const Estimated& x) { return x.key == key; });
      if (e == mp.estimated.end()) {
        const auto other = std::find_if(mp.estimated.begin(), mp.estimated.end(),
                                        [&](const Estimated& x) { return !x.other_key.empty() && x.other_key == key; });
        if (other != mp.estimated.end()) {
          fail(source, "sigmas." + key,
               "parameters states this parameter as " + other->key + "; give its sigma in the same unit, as sigmas." + other->key);
        }
        const auto why = mp.no_sigma.find(key);
        fail(source, "sigmas." + key,
             (why != mp.no_sigma.end() ? why->second : "not a parameter of model " + model) +
                 "; sigmas are read for the estimated parameters, in the units of parameters: " + key_list(expected));
      }
      if (!value.is_number() || !(value.get<double>() >= 0.0)) {
        fail(source, "sigmas." + key, "value " + value.dump() + " is not a sigma (a finite number >= 0)");
      }
      f.sigmas.emplace_back(e->canonical, value.get<double>() * e->to_canonical);
      sigma_keys.push_back(key);
      canonical_of[key] = e->canonical;
    }
  }
  const json* corr = member(doc, "correlation");
  const json* names = member(doc, "correlation_parameters");
  if (corr && corr->is_string()) {
    const std::string v = corr->get<std::string>();
    if (v != "none") {
      fail(source, "correlation",
           "value \"" + v + "\" unknown; expected a matrix [[...], ...] with correlation_parameters, or \"none\" "
                            "(the parameters are uncorrelated)");
    }
    if (names) fail(source, "correlation_parameters", "given with \"correlation\": \"none\", which has no matrix to order; remove it");
    if (sigma_keys.empty()) fail(source, "correlation", "\"none\" without sigmas: there is nothing to correlate");
    f.uncorrelated = true;
    return;
  }
  if (corr) {
    if (!sig) fail(source, "correlation", "given without sigmas; a correlation matrix needs the sigmas it scales");
    if (!corr->is_array()) fail(source, "correlation", "value " + corr->dump() + " is neither a matrix [[...], ...] nor \"none\"");
    if (!names) {
      fail(source, "correlation_parameters",
           "missing; the correlation matrix needs the order of its rows and columns, e.g. [\"tx_m\", \"ty_m\", ...]");
    }
    if (!names->is_array()) fail(source, "correlation_parameters", "value " + names->dump() + " is not an array of parameter names");
    std::vector<std::string> order;
    for (std::size_t i = 0; i < names->size(); ++i) {
      const std::string where = "correlation_parameters[" + std::to_string(i) + "]";
      const std::string n = string_at((*names)[i], where, source);
      if (!canonical_of.count(n)) {
        fail(source, where, n + " has no sigma in sigmas; expected the parameters sigmas gives: " + key_list(sigma_keys));
      }
      if (std::find(order.begin(), order.end(), n) != order.end()) fail(source, where, n + " appears twice");
      order.push_back(n);
    }
    for (const auto& k : sigma_keys) {
      if (std::find(order.begin(), order.end(), k) == order.end()) {
        fail(source, "correlation_parameters",
             "misses " + k + ", which sigmas gives; the matrix must cover every parameter with a sigma (or say "
                             "\"correlation\": \"none\" when the parameters are uncorrelated)");
      }
    }
    const std::size_t n = order.size();
    if (corr->size() != n) {
      fail(source, "correlation", "has " + std::to_string(corr->size()) + " rows; expected " + std::to_string(n) +
                                      ", one per correlation_parameters entry");
    }
    Eigen::MatrixXd r(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
    for (std::size_t i = 0; i < n; ++i) {
      const std::string row_at = "correlation[" + std::to_string(i) + "]";
      const json& row = (*corr)[i];
      if (!row.is_array() || row.size() != n) fail(source, row_at, "expected " + std::to_string(n) + " values (a square matrix)");
      for (std::size_t j = 0; j < n; ++j) {
        const std::string at = row_at + "[" + std::to_string(j) + "]";
        const double v = number_at(row[j], at, source);
        if (!(std::fabs(v) <= 1.0 + kCorrelationTol)) fail(source, at, "value " + format_shortest(v) + " is not a correlation in [-1, 1]");
        if (i == j && !(std::fabs(v - 1.0) <= kCorrelationTol)) {
          fail(source, at, "value " + format_shortest(v) + " on the diagonal; the correlation of " + order[i] + " with itself is 1");
        }
        r(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = v;
      }
    }
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = 0; j < i; ++j) {
        const double a = r(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
        const double b = r(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(i));
        if (!(std::fabs(a - b) <= kCorrelationTol)) {
          fail(source, "correlation[" + std::to_string(i) + "][" + std::to_string(j) + "]",
               "value " + format_shortest(a) + " but correlation[" + std::to_string(j) + "][" + std::to_string(i) +
                   "] is " + format_shortest(b) + " (" + order[i] + " / " + order[j] + "); the matrix must be symmetric");
        }
      }
    }
    if (n > 0) {
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(r, Eigen::EigenvaluesOnly);
      const double smallest = eig.eigenvalues().minCoeff();
      if (eig.info() != Eigen::Success || !(smallest >= -kCorrelationPsdTol)) {
        fail(source, "correlation",
             "not positive semi-definite (smallest eigenvalue " + format_shortest(smallest) + ", below -" +
                 format_shortest(kCorrelationPsdTol) + "): no covariance has these correlations; look for a typo or a "
                                                       "wrong sign");
      }
    }
    for (const auto& k : order) f.correlation_names.push_back(canonical_of.at(k));
    for (std::size_t i = 0; i < n; ++i) {
      std::vector<double> row;
      for (std::size_t j = 0; j < n; ++j) row.push_back(r(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)));
      f.correlation.push_back(row);
    }
    return;
  }
  if (names) fail(source, "correlation_parameters", "given without correlation; expected both, or neither");
  if (!sigma_keys.empty()) {
    fail(source, "correlation",
         "missing; sigmas without a correlation matrix would be propagated as if the parameters were uncorrelated, "
         "which can understate or overstate a tile's uncertainty many times: give correlation and "
         "correlation_parameters, or \"correlation\": \"none\" when the parameters are uncorrelated");
  }
}

void parse_statistics(const json& st, FitRecord& f, std::string_view source) {
  only_keys(st, "statistics", source,
            {"sigma0", "dof", "sigmas_scaled_by_sigma0", "alpha", "alpha_point", "global_test", "warnings", "variance_factors"});
  // null where the fit left a number undefined (no degrees of freedom).
  const auto number_or_null = [&](const json& v, const std::string& path) {
    return v.is_null() ? std::numeric_limits<double>::quiet_NaN() : number_at(v, path, source);
  };
  if (const json* v = member(st, "sigma0")) {
    const double s0 = number_or_null(*v, "statistics.sigma0");
    if (!v->is_null()) f.sigma0 = s0;
    if (!v->is_null() && !(s0 >= 0.0)) {
      fail(source, "statistics.sigma0", "value " + v->dump() + " is not a standard deviation (>= 0)");
    }
  }
  if (const json* v = member(st, "dof")) f.dof = count_at(*v, "statistics.dof", source);
  if (const json* v = member(st, "sigmas_scaled_by_sigma0")) {
    f.sigmas_scaled_by_sigma0 = bool_at(*v, "statistics.sigmas_scaled_by_sigma0", source);
  }
  // The significance levels the fit used (the workbench reopens with them).
  for (const auto& [key, target] : {std::pair<const char*, double*>{"alpha", &f.alpha}, {"alpha_point", &f.alpha_point}}) {
    const json* v = member(st, key);
    if (!v) continue;
    const double a = number_at(*v, std::string("statistics.") + key, source);
    if (!(a > 0.0 && a < 1.0)) {
      fail(source, std::string("statistics.") + key, "value " + v->dump() + " is not a significance level in (0, 1)");
    }
    *target = a;
  }
  if (const json* g = member(st, "global_test")) {
    const std::string at = "statistics.global_test";
    only_keys(*g, at, source, {"statistic", "critical", "critical_lower", "passed", "applicable"});
    if (const json* v = member(*g, "statistic")) f.global_statistic = number_or_null(*v, at + ".statistic");
    if (const json* v = member(*g, "critical")) f.global_critical_upper = number_or_null(*v, at + ".critical");
    if (const json* v = member(*g, "critical_lower")) f.global_critical_lower = number_or_null(*v, at + ".critical_lower");
    if (const json* v = member(*g, "applicable")) f.global_applicable = bool_at(*v, at + ".applicable", source);
    if (const json* v = member(*g, "passed")) {
      if (v->is_null()) {
        // null: the test does not apply.
        if (member(*g, "applicable") && f.global_applicable) {
          fail(source, at + ".passed", "null (the test does not apply) but applicable is true");
        }
        f.global_applicable = false;
        f.global_passed = false;
      } else {
        f.global_passed = bool_at(*v, at + ".passed", source);
      }
    }
  }
  if (const json* w = member(st, "warnings")) {
    if (!w->is_array()) fail(source, "statistics.warnings", "value " + w->dump() + " is not an array of strings");
    for (std::size_t i = 0; i < w->size(); ++i) {
      f.warnings.push_back(string_at((*w)[i], "statistics.warnings[" + std::to_string(i) + "]", source));
    }
  }
  if (const json* vf = member(st, "variance_factors")) {
    const std::string at = "statistics.variance_factors";
    only_keys(*vf, at, source, {"source", "target"});
    const double s = number_field(*vf, "source", at + ".", source), t = number_field(*vf, "target", at + ".", source);
    if (!(s > 0.0)) fail(source, at + ".source", "value " + format_shortest(s) + " is not a variance factor (> 0)");
    if (!(t > 0.0)) fail(source, at + ".target", "value " + format_shortest(t) + " is not a variance factor (> 0)");
    f.variance_factors = std::make_pair(s, t);
  }
}

// Per point: which were used, removed or left out, and why, with the tests.
void parse_points(const json& pts, FitRecord& f, std::string_view source) {
  if (!pts.is_array()) fail(source, "points", "value is not an array of point records");
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const std::string where = "points[" + std::to_string(i) + "]";
    const json& jp = pts[i];
    only_keys(jp, where, source,
              {"id", "residual_enu_m", "w_test", "w_enu", "redundancy_enu", "mdb_m", "point_test", "outlier", "used", "note",
               "robust_weight", "solution", "status", "snooping_rank"});
    FitPointRecord q;
    if (!jp.contains("id")) fail(source, where + ".id", "missing; every point record names its mark");
    q.id = string_at(jp.at("id"), where + ".id", source);
    if (const json* v = member(jp, "residual_enu_m")) q.residual_enu_m = triple_at(*v, where + ".residual_enu_m", source);
    // Untestable (no redundancy on the axis): written null, read as NaN.
    if (const json* v = member(jp, "w_test")) q.w_test = number_or_null_at(*v, where + ".w_test", source);
    if (const json* v = member(jp, "w_enu")) q.w_enu = triple_at(*v, where + ".w_enu", source, true);
    if (const json* v = member(jp, "redundancy_enu")) q.redundancy_enu = triple_at(*v, where + ".redundancy_enu", source);
    if (const json* v = member(jp, "mdb_m")) q.mdb_m = number_or_null_at(*v, where + ".mdb_m", source);
    if (const json* v = member(jp, "point_test")) {
      only_keys(*v, where + ".point_test", source, {"statistic", "dof", "p_value"});
      if (const json* s = member(*v, "statistic")) q.point_test = number_or_null_at(*s, where + ".point_test.statistic", source);
      if (const json* d = member(*v, "dof")) q.point_test_dof = count_at(*d, where + ".point_test.dof", source);
      if (const json* p = member(*v, "p_value")) {
        q.point_test_p = number_at(*p, where + ".point_test.p_value", source);
        if (!(q.point_test_p >= 0.0 && q.point_test_p <= 1.0)) {
          fail(source, where + ".point_test.p_value", "value " + p->dump() + " is not a probability in [0, 1]");
        }
      }
    }
    if (const json* v = member(jp, "outlier")) q.outlier = bool_at(*v, where + ".outlier", source);
    if (const json* v = member(jp, "used")) q.used = bool_at(*v, where + ".used", source);
    if (const json* v = member(jp, "note")) q.note = string_at(*v, where + ".note", source);
    if (const json* v = member(jp, "robust_weight")) {
      q.robust_weight = number_at(*v, where + ".robust_weight", source);
      if (!(q.robust_weight > 0.0 && q.robust_weight <= 1.0)) {
        fail(source, where + ".robust_weight", "value " + v->dump() + " is not a weight in (0, 1]");
      }
    }
    if (const json* v = member(jp, "status")) {
      q.status = string_at(*v, where + ".status", source);
      static const std::array<const char*, 5> kStatuses = {"used", "flagged", "removed", "uncontrolled", "ignored"};
      if (std::find(kStatuses.begin(), kStatuses.end(), q.status) == kStatuses.end()) {
        fail(source, where + ".status", "value " + v->dump() + " is not a status; expected used, flagged, removed, uncontrolled or ignored");
      }
    }
    if (const json* v = member(jp, "snooping_rank")) {
      q.snooping_rank = static_cast<std::size_t>(count_at(*v, where + ".snooping_rank", source));
      if (q.snooping_rank == 0) fail(source, where + ".snooping_rank", "value 0: a rank counts from 1 (leave it out for none)");
    }
    if (const json* v = member(jp, "solution")) {
      if (v->is_string()) q.solution = geodesy::parse_gnss_solution(v->get<std::string>());
      if (!q.solution) {
        fail(source, where + ".solution", "value " + v->dump() + " is not a GNSS solution type; expected one of " +
                                              geodesy::gnss_solution_names());
      }
    }
    f.points.push_back(q);
  }
}

GnssSolutionRecord parse_gnss_solutions(const json& g, std::string_view source) {
  const std::string at = "gnss_solutions";
  only_keys(g, at, source, {"policy", "classes"});
  GnssSolutionRecord r;
  const json* p = member(g, "policy");
  if (!p) fail(source, at + ".policy", "missing; expected exclude or weight");
  const std::string policy = string_at(*p, at + ".policy", source);
  if (policy == "exclude") {
    r.policy = geodesy::SolutionPolicy::exclude;
  } else if (policy == "weight") {
    r.policy = geodesy::SolutionPolicy::weight;
  } else {
    fail(source, at + ".policy", "value \"" + policy + "\" unknown; expected exclude or weight");
  }
  const json* c = member(g, "classes");
  if (!c) fail(source, at + ".classes", "missing; expected one object per GNSS solution type");
  std::vector<std::string> names;
  for (const auto s : geodesy::kGnssSolutions) names.emplace_back(geodesy::to_string(s));
  only_keys(*c, at + ".classes", source, names);
  for (const auto s : geodesy::kGnssSolutions) {
    const std::string name(geodesy::to_string(s));
    const std::string w = at + ".classes." + name;
    const json* e = member(*c, name);
    if (!e) fail(source, w, "missing; every GNSS solution type is listed");
    only_keys(*e, w, source, {"marks", "used", "excluded", "sigma_factor"});
    SolutionTally& t = r.classes[geodesy::solution_index(s)];
    for (const auto& [key, slot] : {std::pair<const char*, std::uint64_t*>{"marks", &t.marks}, {"used", &t.used}, {"excluded", &t.excluded}}) {
      const json* v = member(*e, key);
      if (!v || !v->is_number_unsigned()) fail(source, w + "." + key, "expected a count (an integer >= 0)");
      *slot = v->get<std::uint64_t>();
    }
    t.sigma_factor = number_field(*e, "sigma_factor", w + ".", source);
    if (t.used + t.excluded > t.marks) {
      fail(source, w, "used " + std::to_string(t.used) + " + excluded " + std::to_string(t.excluded) + " > marks " +
                          std::to_string(t.marks));
    }
    const bool used = geodesy::used_under(s, r.policy);
    if (used ? t.excluded != 0 : t.used != 0) {
      fail(source, w, std::string(used ? "excluded" : "used") + " is not 0, but policy " + policy + (used ? " uses " : " leaves out ") +
                          name + " marks");
    }
    const double factor = geodesy::sigma_factor_under(s, r.policy);
    if (t.sigma_factor != factor) {
      fail(source, w + ".sigma_factor", "value " + format_shortest(t.sigma_factor) + " but policy " + policy + " gives " +
                                            name + " marks the factor " + format_shortest(factor));
    }
  }
  return r;
}

ControlExtent parse_extent(const json& e, std::string_view source) {
  const std::string where = "control_extent";
  only_keys(e, where, source, {"centroid", "hull_en_m"});
  if (!e.contains("centroid")) fail(source, where + ".centroid", "missing; expected {\"lat_deg\", \"lon_deg\", \"h_m\"}");
  if (!e.contains("hull_en_m")) fail(source, where + ".hull_en_m", "missing; expected [[e, n], ...] in metres");
  const json& c = e.at("centroid");
  only_keys(c, where + ".centroid", source, {"lat_deg", "lon_deg", "h_m", "ellipsoid"});
  // ControlExtent::of puts the centroid on WGS84; no other is read.
  if (const json* el = member(c, "ellipsoid")) {
    const std::string name = string_at(*el, where + ".centroid.ellipsoid", source);
    if (name != "WGS84") fail(source, where + ".centroid.ellipsoid", "value \"" + name + "\" not read; the extent's centroid is on WGS84");
  }
  ControlExtent x;
  const double lat = number_field(c, "lat_deg", where + ".centroid.", source);
  const double lon = number_field(c, "lon_deg", where + ".centroid.", source);
  if (!(std::fabs(lat) <= 90.0)) fail(source, where + ".centroid.lat_deg", "latitude " + format_shortest(lat) + " not in [-90, 90]");
  if (!(std::fabs(lon) <= 180.0)) fail(source, where + ".centroid.lon_deg", "longitude " + format_shortest(lon) + " not in [-180, 180]");
  // (The centroid of marks spread over a continent lies below the ground:
  // no physical range for it, only finiteness.)
  const double h = number_field(c, "h_m", where + ".centroid.", source);
  x.centroid.point = geodesy::GeodeticPosition{Angle::degrees(lat), Angle::degrees(lon), geodesy::EllipsoidalHeight{h}};
  x.centroid.ellipsoid = geodesy::Ellipsoid::wgs84();
  const json& hull = e.at("hull_en_m");
  if (!hull.is_array()) fail(source, where + ".hull_en_m", "value is not an array of [e, n] in metres");
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const json& v = hull[i];
    const std::string at = where + ".hull_en_m[" + std::to_string(i) + "]";
    if (!v.is_array() || v.size() != 2) fail(source, at, "value " + v.dump() + " is not [e, n] in metres");
    x.hull_en_m.push_back({number_at(v[0], at + "[0]", source), number_at(v[1], at + "[1]", source)});
  }
  if (x.hull_en_m.empty()) fail(source, where + ".hull_en_m", "empty");
  return x;
}

}  // namespace

// What `geoanchor fit` adds: read back whole (the workbench reopens a fit
// with it; apply propagates the sigmas and checks the extent).
std::optional<FitRecord> parse_fit_record(const json& doc, const TransformFile& t, const ModelParameters& mp,
                                          std::string_view source) {
  bool any = false;
  for (const char* key : {"sigmas", "correlation", "correlation_parameters", "statistics", "points", "control_extent",
                          "control_crs", "gnss_solutions"}) {
    any = any || doc.contains(key);
  }
  if (!any) return std::nullopt;
  FitRecord f;
  f.sigma0.reset();  // not known unless statistics states it
  if (const json* g = member(doc, "generator")) f.generator = string_at(*g, "generator", source);
  parse_sigmas(doc, t, mp, f, source);
  if (const json* st = member(doc, "statistics")) parse_statistics(*st, f, source);
  if (const json* pts = member(doc, "points")) parse_points(*pts, f, source);
  if (const json* e = member(doc, "control_extent")) f.extent = parse_extent(*e, source);
  if (const json* g = member(doc, "gnss_solutions")) f.gnss_solutions = parse_gnss_solutions(*g, source);
  if (const json* c = member(doc, "control_crs")) {
    // A record of how the control was read, kept as it is: only its shape is checked.
    if (!c->is_object()) fail(source, "control_crs", "value is not a JSON object");
    for (const auto& [role, record] : c->items()) {
      if (role != "source" && role != "target") fail(source, "control_crs." + role, "unknown key; expected source or target");
      if (!record.is_object()) fail(source, "control_crs." + role, "value is not a JSON object");
    }
    f.control_crs_json = c->dump();
  }
  return f;
}

}  // namespace geoanchor::io::detail
