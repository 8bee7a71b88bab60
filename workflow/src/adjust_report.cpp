// The report of an adjustment: the text `geoanchor adjust` prints and its
// JSON document (schema geoanchor.adjust-report/1).
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "adjust_outputs.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/workflow/adjust.hpp"

namespace geoanchor::workflow {

using namespace adjust_detail;
using geodesy::NetworkSpace;

namespace {

// The adjusted coordinates as the text report lists them: geodetic
// latitude and longitude (degrees, 9 decimals: 0.1 mm), ellipsoidal height
// and ECEF X, Y, Z (metres, 4 decimals), with the shift from the a-priori
// position (mm); a local network's x, y, z.
std::string adjusted_coordinates_text(const geodesy::Network& net, const solver::AdjustmentResult& r) {
  std::ostringstream out;
  const bool ellipsoidal = net.space == NetworkSpace::ellipsoidal;
  if (ellipsoidal) {
    out << "Adjusted coordinates (" << (net.frame ? net.frame->to_string() : std::string("?")) << ", ellipsoid " << net.ellipsoid.name()
        << "; latitude, longitude in degrees, h ellipsoidal, X Y Z ECEF in metres; shift from the a-priori position)\n";
    out << "  id            latitude       longitude          h (m)          X (m)           Y (m)           Z (m)   shift (mm)\n";
  } else {
    out << "Adjusted coordinates (local, axes " << net.axes.name() << "; metres; shift from the a-priori position)\n";
    out << "  id                   x (m)           y (m)           z (m)   shift (mm)\n";
  }
  for (const auto& s : r.stations) {
    if (!s.used) continue;
    const double shift_mm = 1e3 * (s.position - s.a_priori).norm();
    char line[240];
    if (ellipsoidal) {
      const geodesy::GeodeticPosition g =
          geodesy::geodetic_from_ecef(net.ellipsoid, geodesy::EcefPosition(s.position.x(), s.position.y(), s.position.z()));
      std::snprintf(line, sizeof line, "  %-12s %14.9f %15.9f %10.4f %15.4f %15.4f %15.4f %10.1f\n", s.id.c_str(), g.lat.deg(),
                    g.lon.deg(), g.h.m, s.position.x(), s.position.y(), s.position.z(), shift_mm);
    } else {
      std::snprintf(line, sizeof line, "  %-12s %15.4f %15.4f %15.4f %10.1f\n", s.id.c_str(), s.position.x(), s.position.y(),
                    s.position.z(), shift_mm);
    }
    out << line;
  }
  return out.str();
}

// --vce: each group's factor, in the text report (empty without).
std::string variance_components_text(const solver::AdjustmentResult& r) {
  if (r.variance_components.empty()) return "";
  std::ostringstream out;
  out << "Variance components (--vce: each group's a-priori covariances scaled by its factor; " << r.vce_iterations
      << " adjustments)\n";
  out << "  group                                  measurements  redundancy    factor  sigma\n";
  for (const auto& c : r.variance_components) {
    char line[200];
    if (c.estimated) {
      std::snprintf(line, sizeof line, "  %-38s %12zu %11.2f %9.3f  %.3f\n", c.name.c_str(), c.measurements, c.redundancy, c.factor,
                    c.sigma);
    } else {
      std::snprintf(line, sizeof line, "  %-38s %12zu %11.2f   not estimated (factor 1 kept)\n", c.name.c_str(), c.measurements,
                    c.redundancy);
    }
    out << line;
  }
  out << "\n";
  return out.str();
}

// --vce: the JSON report's variance_components.
nlohmann::ordered_json variance_components_document(const solver::AdjustmentResult& r) {
  using nlohmann::ordered_json;
  ordered_json components = ordered_json::array();
  for (const auto& c : r.variance_components) {
    components.push_back({{"group", c.name},
                          {"measurements", c.measurements},
                          {"redundancy", c.redundancy},
                          {"estimated", c.estimated},
                          {"factor", c.factor},
                          {"sigma", c.estimated ? ordered_json(c.sigma) : ordered_json(nullptr)}});
  }
  return {{"iterations", r.vce_iterations}, {"groups", components}};
}

constexpr std::size_t kReportRows = 20;

// A component's name in the reports: "" for one value, "0.x" or a point's
// "ID.x" for a GNSS measurement, an observation set's part by its source.
std::string component_text(const geodesy::Network& net, const geodesy::NetworkMeasurement& m, Eigen::Index k) {
  static constexpr const char* kAxis[] = {"x", "y", "z"};
  if (m.kind == geodesy::MeasurementKind::observation_set) return " [" + m.parts[static_cast<std::size_t>(k)].source + "]";
  if (m.value.size() == 1) return "";
  const std::string whose = m.kind == geodesy::MeasurementKind::gnss_points ? net.stations[m.stations[static_cast<std::size_t>(k / 3)]].id
                                                                            : std::to_string(k / 3);
  return " [" + whose + "." + kAxis[k % 3] + "]";
}

// A measurement's component, for the tables of components.
struct Row {
  const solver::AdjustedMeasurement* am;
  Eigen::Index k;
};

// The MDB of component k in its unit (mm or arc seconds).
std::string mdb_component_text(const geodesy::NetworkMeasurement& m, double mdb, Eigen::Index k) {
  if (!std::isfinite(mdb)) return "-";
  return angular(geodesy::component_kind(m, k)) ? format_fixed(mdb * kRadToArcsec, 2) + "\"" : format_fixed(mdb * 1e3, 1) + " mm";
}

// The measurement components whose blunder of MDB size moves a station
// most (external reliability), largest first.
std::string external_reliability_text(const geodesy::Network& net, const solver::AdjustmentResult& r) {
  std::vector<Row> rows;
  for (const auto& am : r.measurements) {
    for (std::size_t k = 0; k < am.external.size(); ++k) {
      if (std::isfinite(am.external[k].effect_m)) rows.push_back({&am, static_cast<Eigen::Index>(k)});
    }
  }
  if (rows.empty()) return "";
  const auto effect = [](const Row& a) { return a.am->external[static_cast<std::size_t>(a.k)].effect_m; };
  std::stable_sort(rows.begin(), rows.end(), [&](const Row& a, const Row& b) { return effect(a) > effect(b); });
  std::ostringstream out;
  out << "\nExternal reliability: the largest effects on a station of an undetected blunder of MDB size (of " << rows.size()
      << " components)\n";
  for (std::size_t i = 0; i < rows.size() && i < kReportRows; ++i) {
    const auto& am = *rows[i].am;
    const auto& m = net.measurements[am.index];
    const auto& e = am.external[static_cast<std::size_t>(rows[i].k)];
    out << "  " << m.source << "  " << geodesy::to_string(m.kind) << " " << stations_of(net, m) << component_text(net, m, rows[i].k)
        << ": MDB " << mdb_component_text(m, am.mdb(rows[i].k), rows[i].k) << " moves " << r.stations[e.station].id << " by "
        << format_fixed(e.effect_m * 1e3, 1) << " mm (horizontal " << format_fixed(e.horizontal_m * 1e3, 1) << " mm at "
        << r.stations[e.horizontal_station].id << ", vertical " << format_fixed(e.vertical_m * 1e3, 1) << " mm at "
        << r.stations[e.vertical_station].id << ")\n";
  }
  return out.str();
}

// Pre-analysis: the measurement components least controlled by the others.
std::string least_redundant_text(const geodesy::Network& net, const solver::AdjustmentResult& r) {
  std::vector<Row> rows;
  for (const auto& am : r.measurements) {
    if (!am.used) continue;
    for (Eigen::Index k = 0; k < am.redundancy.size(); ++k) rows.push_back({&am, k});
  }
  const auto red = [](const Row& a) { return a.am->redundancy(a.k); };
  std::stable_sort(rows.begin(), rows.end(), [&](const Row& a, const Row& b) { return red(a) < red(b); });
  std::ostringstream out;
  out << "\nLeast redundant measurement components (redundancy number, MDB; of " << rows.size() << ")\n";
  for (std::size_t i = 0; i < rows.size() && i < kReportRows; ++i) {
    const auto& am = *rows[i].am;
    const auto& m = net.measurements[am.index];
    out << "  " << m.source << "  " << geodesy::to_string(m.kind) << " " << stations_of(net, m) << component_text(net, m, rows[i].k)
        << ": r " << format_fixed(am.redundancy(rows[i].k), 3) << ", MDB " << mdb_component_text(m, am.mdb(rows[i].k), rows[i].k)
        << "\n";
  }
  return out.str();
}

// The statistics section of the text report (not in a pre-analysis).
std::string statistics_text(const solver::AdjustmentResult& r, const solver::AdjustOptions& o) {
  std::ostringstream out;
  out << "Statistics\n";
  out << "  vtpv = " << format_fixed(r.vtpv, 3) << ", dof = " << r.dof;
  if (r.variance_factor) out << ", variance factor = " << format_fixed(*r.variance_factor, 4) << ", sigma0 = " << format_fixed(*r.sigma0, 4);
  out << "\n";
  const auto& g = r.global_test;
  if (r.dof > 0) {
    out << "  global test (chi-squared, " << format_shortest(100.0 * (1.0 - o.alpha)) << " %): " << format_fixed(g.statistic, 3)
        << " in [" << format_fixed(g.critical_lower, 3) << ", " << format_fixed(g.critical_upper, 3) << "]: "
        << (g.passed ? "PASSED" : g.failed_high() ? "FAILED (high)" : "FAILED (low)") << "\n";
  }
  out << "  w-tests: critical |w| = " << format_fixed(r.w_critical, 2) << " (alpha " << format_shortest(o.alpha_point) << ")\n\n";
  out << variance_components_text(r);
  return out.str();
}

// --estimate-helmert: the estimated transformation, in the file's units.
std::string helmert_text(const PreparedNetwork& prepared, const solver::AdjustmentResult& r) {
  std::ostringstream out;
  const auto& net = prepared.network;
  if (prepared.helmert && r.helmert) {
    const HelmertInFileUnits u = helmert_in_file_units(prepared, r);
    out << "Helmert of group " << prepared.helmert->name << ": " << prepared.helmert_frame->to_string() << " -> "
        << net.frame->to_string() << ", " << (prepared.helmert->rates ? "helmert14 at reference epoch " + format_fixed(prepared.helmert->reference_epoch, 4) : "helmert7")
        << ", " << (prepared.helmert_position_vector ? "position_vector" : "coordinate_frame")
        << " (sigmas from the a-priori weights)\n";
    for (std::size_t k = 0; k < u.names.size(); ++k) {
      const auto i = static_cast<Eigen::Index>(k);
      char line[160];
      std::snprintf(line, sizeof line, "  %-22s %14.6f  ± %.6f\n", u.names[k].c_str(), u.value(i), std::sqrt(std::max(0.0, u.covariance(i, i))));
      out << line;
    }
    out << "\n";
  }
  return out.str();
}

// --candidates: the ranking.
std::string candidates_text(const PreparedNetwork& prepared, const solver::AdjustmentResult& r, const solver::AdjustOptions& o) {
  std::ostringstream out;
  const auto& net = prepared.network;
  if (!r.candidates.empty()) {
    const bool up = o.candidate_ranking == solver::CandidateRanking::sigma_up && !o.candidate_criterion;
    out << "\nCandidates ranked by the worst station's " << (o.candidate_criterion ? std::string("criterion (custom)")
                                                           : up ? std::string("sigma up")
                                                                : "semi-major axis at " + format_shortest(100.0 * o.confidence) + " %")
        << " with each added alone (design: " << format_fixed(r.design_worst.value * 1e3, 2) << " mm at "
        << r.stations[r.design_worst.station].id << ")\n";
    for (std::size_t k = 0; k < r.candidates.size() && k < kReportRows; ++k) {
      const auto& c = r.candidates[k];
      const auto& first = prepared.candidates[c.measurements.front()];
      std::string stations;
      for (std::size_t mi : c.measurements) stations += (stations.empty() ? "" : " ") + stations_of(net, prepared.candidates[mi]);
      out << "  " << (k + 1) << ". " << first.source << "  " << geodesy::to_string(first.kind)
          << (c.measurements.size() > 1 ? " (" + std::to_string(c.measurements.size()) + " of a new set)" : std::string()) << " "
          << stations << ": worst " << format_fixed(c.worst.value * 1e3, 2) << " mm at " << r.stations[c.worst.station].id
          << " (improves by " << format_fixed(c.improvement * 1e3, 2) << " mm)\n";
    }
    if (r.candidates.size() > kReportRows) out << "  (" << r.candidates.size() << " in all: --candidates-output lists every one)\n";
  }
  return out.str();
}

// --estimate-helmert: the JSON report's helmert.
nlohmann::ordered_json helmert_document(const PreparedNetwork& prepared, const solver::AdjustmentResult& r) {
  using nlohmann::ordered_json;
  const auto& net = prepared.network;
  auto num = [](double v) { return std::isfinite(v) ? ordered_json(v) : ordered_json(nullptr); };
  const HelmertInFileUnits u = helmert_in_file_units(prepared, r);
  ordered_json values, sigmas;
  for (std::size_t k = 0; k < u.names.size(); ++k) {
    const auto i = static_cast<Eigen::Index>(k);
    values[u.names[k]] = num(u.value(i));
    sigmas[u.names[k]] = num(std::sqrt(std::max(0.0, u.covariance(i, i))));
  }
  return {{"group", prepared.helmert->name},
          {"model", prepared.helmert->rates ? "helmert14" : "helmert7"},
          {"convention", prepared.helmert_position_vector ? "position_vector" : "coordinate_frame"},
          {"source_frame", prepared.helmert_frame->to_string()},
          {"target_frame", net.frame->to_string()},
          {"reference_epoch", prepared.helmert->rates ? num(prepared.helmert->reference_epoch) : ordered_json(nullptr)},
          {"measurements", prepared.helmert->measurements.size()},
          {"parameters", values},
          {"sigmas", sigmas}};
}

// The GNSS solution types: the JSON report's gnss_solutions.
nlohmann::ordered_json gnss_solutions_document(const io::GnssSolutionRecord& rec) {
  using nlohmann::ordered_json;
  ordered_json classes = ordered_json::object();
  for (const auto s : geodesy::kGnssSolutions) {
    const io::SolutionTally& c = rec.classes[geodesy::solution_index(s)];
    classes[std::string(geodesy::to_string(s))] = {
        {"measurements", c.marks}, {"used", c.used}, {"excluded", c.excluded}, {"sigma_factor", c.sigma_factor}};
  }
  return {{"policy", std::string(geodesy::to_string(rec.policy))}, {"classes", classes}};
}

// --candidates: the JSON report's candidates.
nlohmann::ordered_json candidates_document(const PreparedNetwork& prepared, const solver::AdjustmentResult& r,
                                           const solver::AdjustOptions& o) {
  using nlohmann::ordered_json;
  auto num = [](double v) { return std::isfinite(v) ? ordered_json(v) : ordered_json(nullptr); };
  ordered_json ranked = ordered_json::array();
  for (const auto& c : r.candidates) {
    ordered_json sources = ordered_json::array();
    for (std::size_t mi : c.measurements) sources.push_back(prepared.candidates[mi].source);
    ranked.push_back({{"sources", sources},
                      {"worst_m", num(c.worst.value)},
                      {"worst_station", r.stations[c.worst.station].id},
                      {"improvement_m", num(c.improvement)}});
  }
  return {{"criterion", candidate_criterion_name(o)},
          {"design_worst_m", num(r.design_worst.value)},
          {"design_worst_station", r.stations[r.design_worst.station].id},
          {"ranked", ranked}};
}

}  // namespace

std::string report_text(const PreparedNetwork& prepared, const solver::AdjustmentResult& r, const solver::AdjustOptions& o) {
  const auto& net = prepared.network;
  std::ostringstream out;
  out << "geoanchor adjust: " << net.source_name << "\n";
  if (r.preanalysis) {
    out << "  PRE-ANALYSIS: the design at the a-priori coordinates and the a-priori errors alone; no measured value is "
           "used: no residuals, no sigma0, no global test, no w-tests\n";
  }
  out << "  network: " << (net.space == NetworkSpace::ellipsoidal ? "on the ellipsoid " + net.ellipsoid.name() + ", frame " +
                                                                         (net.frame ? net.frame->to_string() : std::string("?"))
                                                                   : "local, axes " + net.axes.name())
      << "; " << net.stations.size() << " stations, " << net.measurements.size() << " measurements\n";
  for (const auto& n : prepared.notes) out << "  " << n << "\n";
  out << "  datum: " << r.datum << "\n";
  if (r.preanalysis) {
    out << "  design: " << r.unknowns << " unknowns, " << r.observations << " observations, dof " << r.dof << ", factor "
        << r.factor_nonzeros << " nonzeros (one factorization)\n";
  } else out << "  solve: " << r.iterations << " iterations, last correction " << format_fixed(r.largest_correction_m, 6) << " m; "
      << r.unknowns << " unknowns, " << r.observations << " observations, factor " << r.factor_nonzeros << " nonzeros\n";
  if (!r.removed_per_pass.empty()) {
    std::string steps;
    for (std::size_t k : r.removed_per_pass) steps += (steps.empty() ? "" : ", ") + std::to_string(k);
    out << "  data snooping: " << r.passes << " adjustments, removing " << steps << " measurement(s) in turn";
    if (r.passes_downdated > 0) {
      out << "; " << r.passes_downdated << " of them by taking the removed measurements out of the last factor (a downdate)";
    }
    out << "\n";
  }
  out << "\n";
  if (!r.preanalysis) out << statistics_text(r, o);
  out << helmert_text(prepared, r);
  // A pre-analysis adds the ellipse at --confidence (the prediction a plan is judged by).
  const bool planned = r.preanalysis;
  if (planned) {
    out << "Stations (predicted from the a-priori weights, at the a-priori coordinates; ellipse 1 sigma and at "
        << format_shortest(100.0 * o.confidence) << " %)\n";
  } else {
    out << "Stations (sigmas from the a-priori weights; ellipse 1 sigma)\n";
  }
  const bool ellipsoidal = net.space == NetworkSpace::ellipsoidal;
  out << "  id            " << (ellipsoidal ? "sigma_e  sigma_n  sigma_u" : "sigma_x  sigma_y  sigma_z") << "  (mm)   ellipse a/b (mm) az (deg)  "
      << (planned ? " a/b at confidence (mm)  " : "") << "constraint\n";
  for (const auto& s : r.stations) {
    if (!s.used) continue;
    const Eigen::Matrix3d& c = s.covariance_local_m2;
    char line[200], conf[64] = "";
    if (planned) std::snprintf(conf, sizeof conf, " %8.2f/%-8.2f      ", 1e3 * s.ellipse_confidence.semi_major_m, 1e3 * s.ellipse_confidence.semi_minor_m);
    std::snprintf(line, sizeof line, "  %-12s %8.2f %8.2f %8.2f        %7.2f/%-7.2f %7.2f    %s%s\n", s.id.c_str(),
                  1e3 * std::sqrt(std::max(0.0, c(0, 0))), 1e3 * std::sqrt(std::max(0.0, c(1, 1))),
                  1e3 * std::sqrt(std::max(0.0, c(2, 2))), 1e3 * s.ellipse.semi_major_m, 1e3 * s.ellipse.semi_minor_m,
                  s.ellipse.azimuth_rad * kRadToDeg, conf, s.constraint.c_str());
    out << line;
  }
  if (!r.preanalysis) out << "\n" << adjusted_coordinates_text(net, r);
  // The flagged measurements first, in the order data snooping removes them.
  const auto p_text = [](double p) {
    char b[32];
    std::snprintf(b, sizeof b, "%.3g", p);
    return std::string(b);
  };
  // The largest MDB (an observation set's: of its lengths and of its angles).
  const auto mdb_text = [&](const solver::AdjustedMeasurement& am, const geodesy::NetworkMeasurement& m) {
    double largest[2] = {0.0, 0.0};  // lengths, angles
    bool has[2] = {false, false};
    for (Eigen::Index k = 0; k < am.mdb.size(); ++k) {
      const int a = angular(geodesy::component_kind(m, k)) ? 1 : 0;
      has[a] = true;
      if (!(am.mdb(k) <= largest[a])) largest[a] = am.mdb(k);
    }
    std::string text;
    for (int a = 0; a < 2; ++a) {
      if (!has[a]) continue;
      text += text.empty() ? "" : ", ";
      if (!std::isfinite(largest[a])) text += "-";
      else text += a ? format_fixed(largest[a] * kRadToArcsec, 2) + "\"" : format_fixed(largest[a] * 1e3, 1) + " mm";
    }
    return text;
  };
  // An observation set's observation with the largest |w|.
  const auto worst_part = [&](const solver::AdjustedMeasurement& am, const geodesy::NetworkMeasurement& m) {
    if (m.kind != geodesy::MeasurementKind::observation_set) return std::string();
    Eigen::Index worst = -1;
    for (Eigen::Index k = 0; k < am.w.size(); ++k) {
      if (std::isfinite(am.w(k)) && (worst < 0 || std::fabs(am.w(k)) > std::fabs(am.w(worst)))) worst = k;
    }
    if (worst < 0) return std::string();
    const auto& part = m.parts[static_cast<std::size_t>(worst)];
    return " (largest at " + part.source + " " + geodesy::to_string(part.kind) + " " + stations_of(net, part) + ")";
  };
  const std::vector<std::size_t> failing = solver::failing_measurements(r);
  std::size_t flagged = 0, removed = 0;
  for (const auto& am : r.measurements) {
    const auto st = am.status(r.alpha_point);
    flagged += st == solver::TestStatus::flagged ? 1u : 0u;
    removed += st == solver::TestStatus::removed ? 1u : 0u;
  }
  if (flagged > 0) {
    out << "\nFlagged measurements: " << flagged << " fail their test at alpha " << format_shortest(o.alpha_point)
        << " and are kept (--remove-outliers removes them in the order of their snooping rank, strongest evidence first)\n";
    out << "  rank  measurement\n";
    for (const std::size_t k : failing) {
      const auto& am = r.measurements[k];
      if (am.status(r.alpha_point) != solver::TestStatus::flagged) continue;
      const auto& m = net.measurements[am.index];
      char rank[16];
      std::snprintf(rank, sizeof rank, "%4s", am.snooping_rank > 0 ? std::to_string(am.snooping_rank).c_str() : "-");
      out << "  " << rank << "  " << m.source << "  " << geodesy::to_string(m.kind) << " " << stations_of(net, m) << ": max |w| "
          << format_fixed(am.w_max, 2) << worst_part(am, m) << ", test " << format_fixed(am.statistic, 2) << " (chi-squared, " << am.test_dof
          << " dof), p " << p_text(am.p_value) << ", MDB " << mdb_text(am, m)
          << (am.passes_after_rank > 0 ? "; passes once rank " + std::to_string(am.passes_after_rank) + " is removed" : std::string())
          << "\n";
    }
  }
  // The measurements with the largest |w|.
  std::vector<const solver::AdjustedMeasurement*> by_w;
  for (const auto& am : r.measurements) {
    if (std::isfinite(am.w_max)) by_w.push_back(&am);
  }
  std::stable_sort(by_w.begin(), by_w.end(), [](auto* a, auto* b) { return a->w_max > b->w_max; });
  if (!r.preanalysis) out << "\nMeasurements with the largest |w| (of " << r.measurements.size() << ")\n";
  for (std::size_t k = 0; k < by_w.size() && k < 20; ++k) {
    const auto& am = *by_w[k];
    const auto& m = net.measurements[am.index];
    out << "  " << m.source << "  " << geodesy::to_string(m.kind) << " " << stations_of(net, m) << ": max |w| "
        << format_fixed(am.w_max, 2) << worst_part(am, m) << ", p " << p_text(am.p_value) << ", " << solver::to_string(am.status(r.alpha_point))
        << (am.snooping_rank > 0 ? " (snooping rank " + std::to_string(am.snooping_rank) + ")" : std::string()) << "\n";
  }
  if (removed > 0) {
    out << "\nMeasurements removed (--remove-outliers, or a gross misclosure past the input's tolerance): " << removed << "\n";
    for (const auto& am : r.measurements) {
      if (am.outlier) out << "  " << net.measurements[am.index].source << ": " << am.removed_because << "\n";
    }
  }
  relative_report_text(out, prepared, r, o);
  out << external_reliability_text(net, r);
  if (r.preanalysis) out << least_redundant_text(net, r);
  out << candidates_text(prepared, r, o);
  if (!r.warnings.empty()) {
    out << "\nWarnings\n";
    for (const auto& w : r.warnings) out << "  " << w << "\n";
  }
  return out.str();
}

nlohmann::ordered_json report_document(const PreparedNetwork& prepared, const solver::AdjustmentResult& r,
                                       const solver::AdjustOptions& o, ReportDetail detail) {
  const bool full = detail == ReportDetail::full;
  using nlohmann::ordered_json;
  const auto& net = prepared.network;
  auto num = [](double v) { return std::isfinite(v) ? ordered_json(v) : ordered_json(nullptr); };
  ordered_json j;
  j["schema"] = "geoanchor.adjust-report/1";
  j["preanalysis"] = r.preanalysis;
  j["inputs"] = net.source_name;
  j["space"] = net.space == NetworkSpace::ellipsoidal ? "ellipsoidal" : "local";
  if (net.frame) j["frame"] = net.frame->to_string();
  j["ellipsoid"] = net.ellipsoid.name();
  j["datum"] = r.datum;
  j["datum_defect"] = r.datum_defect;
  if (const auto rec = adjust_solution_record(prepared, r)) j["gnss_solutions"] = gnss_solutions_document(*rec);
  j["notes"] = prepared.notes;
  j["vtpv"] = r.vtpv;
  j["dof"] = r.dof;
  j["variance_factor"] = r.variance_factor ? ordered_json(*r.variance_factor) : ordered_json(nullptr);
  j["sigma0"] = r.sigma0 ? ordered_json(*r.sigma0) : ordered_json(nullptr);
  j["global_test"] = {{"statistic", r.global_test.statistic},
                      {"lower", r.global_test.critical_lower},
                      {"upper", r.global_test.critical_upper},
                      {"passed", r.global_test.passed},
                      {"verdict", r.global_test.verdict()},
                      {"confidence", 1.0 - o.alpha}};
  if (!r.variance_components.empty()) j["variance_components"] = variance_components_document(r);
  if (prepared.helmert && r.helmert) j["helmert"] = helmert_document(prepared, r);
  j["w_critical"] = r.w_critical;
  j["iterations"] = r.iterations;
  j["snooping"] = {{"adjustments", r.passes}, {"removed_per_step", r.removed_per_pass}, {"downdated", r.passes_downdated}};
  j["converged"] = r.converged;
  j["largest_correction_m"] = r.largest_correction_m;
  j["unknowns"] = r.unknowns;
  j["observations"] = r.observations;
  ordered_json stations = ordered_json::array();
  const double sigma_scale = r.sigma0.value_or(1.0);
  for (const auto& s : r.stations) {
    if (!s.used || !full) continue;
    const Eigen::Matrix3d& c = s.covariance_local_m2;
    ordered_json st = {{"id", s.id}, {"position_m", {s.position.x(), s.position.y(), s.position.z()}}};
    if (net.space == NetworkSpace::ellipsoidal) {
      const auto g = geodesy::geodetic_from_ecef(net.ellipsoid, geodesy::EcefPosition(s.position.x(), s.position.y(), s.position.z()));
      st["lat_deg"] = g.lat.deg();
      st["lon_deg"] = g.lon.deg();
      st["h_m"] = g.h.m;
      st["sigma_enu_m"] = {std::sqrt(std::max(0.0, c(0, 0))), std::sqrt(std::max(0.0, c(1, 1))), std::sqrt(std::max(0.0, c(2, 2)))};
      st["sigma_enu_scaled_m"] = {sigma_scale * std::sqrt(std::max(0.0, c(0, 0))), sigma_scale * std::sqrt(std::max(0.0, c(1, 1))),
                                  sigma_scale * std::sqrt(std::max(0.0, c(2, 2)))};
    } else {
      st["sigma_xyz_m"] = {std::sqrt(std::max(0.0, c(0, 0))), std::sqrt(std::max(0.0, c(1, 1))), std::sqrt(std::max(0.0, c(2, 2)))};
      st["sigma_xyz_scaled_m"] = {sigma_scale * std::sqrt(std::max(0.0, c(0, 0))), sigma_scale * std::sqrt(std::max(0.0, c(1, 1))),
                                  sigma_scale * std::sqrt(std::max(0.0, c(2, 2)))};
    }
    ordered_json cov = ordered_json::array();
    for (int a = 0; a < 3; ++a) cov.push_back({s.covariance_m2(a, 0), s.covariance_m2(a, 1), s.covariance_m2(a, 2)});
    st["covariance_m2"] = cov;
    st["ellipse"] = {{"a_m", s.ellipse.semi_major_m}, {"b_m", s.ellipse.semi_minor_m}, {"azimuth_deg", s.ellipse.azimuth_rad * kRadToDeg}};
    st["ellipse_confidence"] = {{"a_m", s.ellipse_confidence.semi_major_m}, {"b_m", s.ellipse_confidence.semi_minor_m},
                                {"confidence", o.confidence}};
    st["constraint"] = s.constraint;
    stations.push_back(st);
  }
  if (full) j["stations"] = std::move(stations);
  ordered_json measurements = ordered_json::array(), flagged = ordered_json::array(), removed = ordered_json::array();
  for (const std::size_t k : solver::failing_measurements(r)) {
    const auto& am = r.measurements[k];
    const auto& m = net.measurements[am.index];
    ordered_json x = {{"source", m.source},
                      {"kind", kind_key(m.kind)},
                      {"stations", stations_of(net, m)},
                      {"snooping_rank", am.snooping_rank > 0 ? ordered_json(am.snooping_rank) : ordered_json(nullptr)},
                      {"passes_after_rank", am.passes_after_rank > 0 ? ordered_json(am.passes_after_rank) : ordered_json(nullptr)},
                      {"w_max", num(am.w_max)},
                      {"test", {{"statistic", num(am.statistic)}, {"dof", am.test_dof}, {"p_value", num(am.p_value)}}}};
    ordered_json mdb = ordered_json::array();
    for (Eigen::Index c = 0; c < am.mdb.size(); ++c) mdb.push_back(num(am.mdb(c)));
    x["mdb"] = mdb;
    if (am.outlier) x["because"] = am.removed_because;
    (am.outlier ? removed : flagged).push_back(std::move(x));
  }
  for (const auto& am : r.measurements) {
    const auto& m = net.measurements[am.index];
    if (am.outlier && am.snooping_rank == 0) removed.push_back({{"source", m.source}, {"kind", kind_key(m.kind)},
                                                               {"stations", stations_of(net, m)}, {"because", am.removed_because}});
    if (!full) continue;
    ordered_json x = {{"source", m.source}, {"kind", kind_key(m.kind)}, {"stations", stations_of(net, m)}};
    if (m.kind == geodesy::MeasurementKind::observation_set) {
      // Its components' observations, each with its own unit.
      ordered_json parts = ordered_json::array();
      for (const auto& part : m.parts) {
        parts.push_back({{"source", part.source}, {"kind", kind_key(part.kind)}, {"stations", stations_of(net, part)},
                         {"unit", angular(part.kind) ? "rad" : "m"}});
      }
      x["parts"] = std::move(parts);
    } else {
      x["unit"] = angular(m.kind) ? "rad" : "m";
    }
    auto vec = [&](const Eigen::VectorXd& v) {
      ordered_json a = ordered_json::array();
      for (Eigen::Index k = 0; k < v.size(); ++k) a.push_back(num(v(k)));
      return a;
    };
    x["observed"] = vec(am.observed);
    x["adjusted"] = vec(am.adjusted);
    x["residual"] = vec(am.residual);
    x["sigma"] = vec(am.sigma);
    x["residual_sigma"] = vec(am.residual_sigma);
    x["redundancy"] = vec(am.redundancy);
    x["w"] = vec(am.w);
    x["mdb"] = vec(am.mdb);
    x["test"] = {{"statistic", num(am.statistic)}, {"dof", am.test_dof}, {"p_value", num(am.p_value)}};
    ordered_json external = ordered_json::array();  // per component: null without an MDB
    for (const auto& e : am.external) {
      if (!std::isfinite(e.effect_m)) {
        external.push_back(nullptr);
        continue;
      }
      ordered_json c = {{"effect_m", e.effect_m},
                        {"station", r.stations[e.station].id},
                        {"horizontal_m", e.horizontal_m},
                        {"horizontal_station", r.stations[e.horizontal_station].id},
                        {"vertical_m", e.vertical_m},
                        {"vertical_station", r.stations[e.vertical_station].id}};
      if (e.helmert.size() > 0) c["helmert"] = vec(e.helmert);
      external.push_back(std::move(c));
    }
    x["external"] = std::move(external);
    x["status"] = solver::to_string(am.status(r.alpha_point));
    x["snooping_rank"] = am.snooping_rank > 0 ? ordered_json(am.snooping_rank) : ordered_json(nullptr);
    if (!m.frame_step.empty()) x["frame_step"] = m.frame_step;
    measurements.push_back(std::move(x));
  }
  if (full) j["measurements"] = std::move(measurements);
  j["flagged"] = std::move(flagged);
  j["removed"] = std::move(removed);
  relative_report_document(j, prepared, r, o, full);
  if (!r.candidates.empty()) j["candidates"] = candidates_document(prepared, r, o);
  j["warnings"] = r.warnings;
  if (!r.refused_because.empty()) j["refused_because"] = r.refused_because;
  return j;
}

}  // namespace geoanchor::workflow
