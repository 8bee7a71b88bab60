// The Helmert fit (helmert_fit.hpp): the entry points and the weighted
// fit's passes (helmert_weighted_fit.hpp), robust reweighting and the GNSS
// solution types' weights around them.

#include "geoanchor/solver/helmert_fit.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "enu_origin_fit.hpp"
#include "fit_common.hpp"
#include "geoanchor/base/error.hpp"
#include "helmert_weighted_fit.hpp"
#include "point_statistics.hpp"

namespace geoanchor::solver {

using geodesy::ControlSet;
using geodesy::DecimalYear;

std::string_view to_string(FitModel m) {
  switch (m) {
    case FitModel::translation3: return "translation3";
    case FitModel::helmert6: return "helmert6";
    case FitModel::helmert7: return "helmert7";
    case FitModel::helmert14: return "helmert14";
    case FitModel::molodensky_badekas: return "molodensky-badekas";
    case FitModel::enu_origin: return "enu-origin";
    case FitModel::site_calibration: return "site-calibration";
  }
  return "?";
}

geodesy::EcefPosition apply_fit(const FitResult& fit, const geodesy::EcefPosition& source,
                                std::optional<DecimalYear> epoch) {
  if (fit.ecef_map) return geodesy::EcefPosition(fit.ecef_map->apply(source.m));
  if (fit.site_calibration) return fit.site_calibration->target_from_source(source);
  const DecimalYear t = fit.model == FitModel::helmert14 ? epoch.value() : fit.helmert.reference_epoch;
  return geodesy::apply(geodesy::evaluate_at(fit.helmert, t), fit.rotation_model, source);
}

namespace {

// The fit of `control` as its covariances stand (the GNSS solution types'
// sigma factors already applied by fit_helmert).
FitResult fit_weighted(const ControlSet& control, const FitOptions& options);

// Iteratively reweighted least squares for a robust loss.
FitResult fit_robust(const ControlSet& control, const FitOptions& options) {
  constexpr int kMaxIterations = 50;
  constexpr double kWeightTolerance = 1e-6;
  FitOptions o = options;
  o.robust = FitOptions::Robust::none;
  o.data_snooping = false;
  std::vector<double> weight(control.points.size(), 1.0);
  FitResult r;
  for (int it = 1; it <= kMaxIterations; ++it) {
    ControlSet weighted = control;
    for (std::size_t i = 0; i < weighted.points.size(); ++i) {
      weighted.points[i].source_cov_m2 /= weight[i];
      weighted.points[i].target_cov_m2 /= weight[i];
    }
    if (!control.has_a_priori_sigmas) weighted.has_a_priori_sigmas = false;
    r = fit_weighted(weighted, o);
    double change = 0.0;
    for (std::size_t i = 0; i < r.points.size(); ++i) {
      const auto& p = r.points[i];
      if (!p.used || p.point_dof == 0) continue;
      // The point test T was computed with covariance C / w, so T = w · vᵀC⁻¹v:
      // the standardized residual under the stated covariance is sqrt(T / (dof · w)).
      const double e = std::sqrt(p.point_statistic / (p.point_dof * weight[i]));
      const double k = options.robust_k;
      const double w = options.robust == FitOptions::Robust::huber ? (e <= k ? 1.0 : k / e) : 1.0 / (1.0 + (e / k) * (e / k));
      change = std::max(change, std::fabs(w - weight[i]));
      weight[i] = std::max(w, 1e-6);
    }
    r.robust_iterations = it;
    if (change < kWeightTolerance) break;
  }
  for (std::size_t i = 0; i < r.points.size(); ++i) r.points[i].robust_weight = weight[i];
  r.warnings.push_back(std::string(options.robust == FitOptions::Robust::huber ? "Huber" : "Cauchy") + " robust loss (k = " +
                       fmt(options.robust_k) + ", " + std::to_string(r.robust_iterations) +
                       " reweighting passes): for exploration; sigmas and tests assume the final weights were known");
  return r;
}

FitResult fit_weighted(const ControlSet& control, const FitOptions& options) {
  if (options.robust != FitOptions::Robust::none) return fit_robust(control, options);
  if (options.model == FitModel::enu_origin || options.model == FitModel::site_calibration) {
    if (options.vce) {
      throw Error(ErrorKind::usage, "E_OPTION", "--vce: not available for the " + std::string(to_string(options.model)) +
                                                    " model yet");
    }
    return options.model == FitModel::enu_origin ? fit_enu_origin(control, options) : fit_site_calibration(control, options);
  }
  WeightedFit fit(control, options);
  while (true) {
    FitPass current;
    fit.check_marks(current);
    fit.observe(current);
    fit.solve_weighted(current);
    current.geometry_warning = fit.weak_geometry(current);
    const GeocentricEstimate estimate = fit.geocentric_estimate(current);
    fit.set_helmert(estimate.g);
    fit.residuals(current);
    fit.test_marks(current);
    // --- variance components (--vce) -----------------------------------------
    if (fit.o.vce && current.dof > 0 && fit.next_variance_components(current)) continue;
    // --- data snooping ------------------------------------------------------
    if (snoop(fit.result, fit.active, fit.o, current.u, min_points(fit.o.model), current.lin) == SnoopStep::removed) continue;
    fit.test_marks_outside(current);
    return fit.report(current, estimate);
  }
}

}  // namespace

FitResult fit_helmert(const ControlSet& control, const FitOptions& options) {
  // GNSS solution types weighted on request: float and worse enter with
  // their covariances scaled by the class's factor squared (geodesy::
  // solution_sigma_factor); excluded classes are left out by init_points.
  bool scaled = false;
  if (options.solutions == geodesy::SolutionPolicy::weight && control.has_solutions) {
    for (const auto& p : control.points) {
      scaled = scaled || (p.solution && geodesy::sigma_factor_under(*p.solution, options.solutions) != 1.0);
    }
  }
  if (!scaled) return fit_weighted(control, options);
  if (!control.has_a_priori_sigmas) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--solution-weighting: " + control.source_name +
                    " gives no a-priori sigmas, which the GNSS solution types' factors would scale; give sigma_src_m/"
                    "sigma_dst_m (or covariances), or leave float and worse out (the default)");
  }
  ControlSet weighted = control;
  for (auto& p : weighted.points) {
    if (!p.solution) continue;
    const double f = geodesy::sigma_factor_under(*p.solution, options.solutions);
    p.source_cov_m2 *= f * f;
    p.target_cov_m2 *= f * f;
  }
  return fit_weighted(weighted, options);
}


}  // namespace geoanchor::solver
