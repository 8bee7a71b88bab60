// The diagnosis of a control set (diagnosis.hpp): the baseline residuals,
// every hypothesis (diagnosis_hypotheses.hpp) judged, ranked and the
// verdict.

#include "geoanchor/solver/diagnosis.hpp"

#include <boost/math/distributions/chi_squared.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

#include "diagnosis_engine.hpp"
#include "diagnosis_hypotheses.hpp"
#include "geoanchor/base/error.hpp"

namespace geoanchor::solver {

using geodesy::ControlSet;

namespace {

// A hypothesis leaves "noise" when what is left is within this many noise RMS
// (3-D), or within this fraction of the discrepancy it was tested on.
constexpr double kExplainedNoiseFactor = 2.0;
constexpr double kExplainedFraction = 0.1;
// What a non-explaining hypothesis may score at most (just below decisive).
constexpr double kCapBelowDecisive = 1.99;

}  // namespace

std::string_view to_string(Hypothesis h) {
  switch (h) {
    case Hypothesis::convention_swap: return "convention_swap";
    case Hypothesis::lat_lon_swap: return "lat_lon_swap";
    case Hypothesis::degrees_radians: return "degrees_radians";
    case Hypothesis::height_type: return "height_type";
    case Hypothesis::datum_mix: return "datum_mix";
    case Hypothesis::epoch: return "epoch";
    case Hypothesis::web_mercator: return "web_mercator";
    case Hypothesis::utm_zone: return "utm_zone";
    case Hypothesis::float32_ecef: return "float32_ecef";
    case Hypothesis::enu_origin: return "enu_origin";
  }
  return "?";
}

Diagnosis diagnose(const ControlSet& set, const DiagnoseOptions& options) {
  using namespace diagnosis_detail;  // the engine and the hypotheses
  const Engine e(set, options);
  if (e.used.empty()) throw Error(ErrorKind::rejected, "E_NO_POINTS", set.source_name + ": no control point is in use");
  Diagnosis d;
  d.points_used = static_cast<int>(e.used.size());
  d.noise_rms_m = e.noise_rms;
  d.sigmas_assumed = !set.has_a_priori_sigmas;

  Vectors base;
  if (options.transform) {
    // Not through residuals(), which turns a failure into "cannot evaluate":
    // here a point without the epoch a time-dependent transform needs is the
    // user's error, and says so.
    for (std::size_t i : e.used) {
      const auto& p = set.points[i];
      base.push_back(p.target.m - options.transform->apply(p.source, epoch_of(set, p)).m);
    }
    if (!std::all_of(base.begin(), base.end(), [](const Eigen::Vector3d& r) { return r.allFinite(); })) {
      throw Error(ErrorKind::input, "E_TRANSFORM", set.source_name + ": the transform gives non-finite positions");
    }
    d.baseline = "applied " + options.transform->description;
  } else {
    const FitResult fit = fit_helmert(set, e.fit_options());  // throws `rejected` for an ill-posed set
    for (std::size_t i : e.used) base.push_back(set.points[i].target.m - apply_fit(fit, set.points[i].source, set.points[i].epoch).m);
    d.baseline = "fitted " + std::string(to_string(fit.model)) + " (no data snooping)";
    if (fit.global_test.applicable && set.has_a_priori_sigmas) d.global_test_passed = fit.global_test.passed;
  }
  if (options.transform && set.has_a_priori_sigmas) {
    const boost::math::chi_squared chi(3.0 * static_cast<double>(e.used.size()));
    d.global_test_passed = chi2(base, e.sigma) <= boost::math::quantile(chi, 1.0 - options.fit.alpha);
  }
  d.residual_rms_m = rms(base);
  const Expectation x = expectation(e);
  d.expectation = x.description;
  if (x.discrepancy) d.departure_rms_m = rms(*x.discrepancy);

  const double rb = d.residual_rms_m;
  d.hypotheses.push_back(options.transform && options.transform->apply_swapped ? convention_swap_correction(e, base)
                                                                                : convention_swap_signature(e, x, rb));
  d.hypotheses.push_back(lat_lon_swap(e, base));
  d.hypotheses.push_back(degrees_radians(e, base));
  d.hypotheses.push_back(height_type(e, x, rb));
  d.hypotheses.push_back(datum_mix(e, x, rb));
  d.hypotheses.push_back(epoch_hypothesis(e, x, rb));
  d.hypotheses.push_back(web_mercator(e, base));
  d.hypotheses.push_back(utm_zone(e, base));
  d.hypotheses.push_back(float32_ecef(e, base));
  d.hypotheses.push_back(enu_origin(e, x, rb));

  for (auto& h : d.hypotheses) {
    if (!std::isfinite(h.score)) h.score = h.score > 0 ? std::numeric_limits<double>::max() : -1e300;
    const bool at_noise = h.rms_after_m <= kExplainedNoiseFactor * e.noise_rms ||
                          h.rms_after_m <= kExplainedFraction * h.rms_before_m;
    h.explains = h.applicable && h.plausible && h.score >= kDecisiveLog10BayesFactor && at_noise;
    if (!h.explains) h.score = std::min(h.score, kCapBelowDecisive);
    if (!h.applicable) h.score = 0.0;
  }
  // Explanations first, the one that estimates least first among them (a
  // predicted effect that matches is stronger evidence than a fitted one that
  // matches as well), then by score; scores are then made non-increasing down
  // the ranking, so that none exceeds that of a simpler explanation above it.
  std::stable_sort(d.hypotheses.begin(), d.hypotheses.end(), [](const HypothesisResult& a, const HypothesisResult& b) {
    if (a.explains != b.explains) return a.explains;
    if (a.explains && a.estimated_parameters != b.estimated_parameters) {
      return a.estimated_parameters < b.estimated_parameters;
    }
    return a.score > b.score;
  });
  for (std::size_t i = 1; i < d.hypotheses.size(); ++i) {
    d.hypotheses[i].score = std::min(d.hypotheses[i].score, d.hypotheses[i - 1].score);
  }

  const auto& best = d.hypotheses.front();
  d.problem_found = best.explains;
  if (d.problem_found) {
    d.verdict = "Most likely " + std::string(to_string(best.name)) + ": " + best.effect + ".";
  } else {
    std::string departure;
    if (d.departure_rms_m && *d.departure_rms_m > kExplainedNoiseFactor * e.noise_rms && !options.transform) {
      departure = set.source_frame && set.target_frame
                      ? "; the points depart from the expected transformation by " + fmt(*d.departure_rms_m, 3) +
                            " m RMS in a way none of them predicts"
                      : "; the two coordinate sets differ by " + fmt(*d.departure_rms_m, 3) +
                            " m RMS (declare their frames to test for datum and epoch mistakes)";
    }
    d.verdict = "No classic mistake explains the data: residual RMS " + fmt(rb, 3) + " m against a noise level of " +
                fmt(e.noise_rms, 3) + " m" + departure +
                (d.global_test_passed && !*d.global_test_passed
                     ? ", and the residuals fail the global test (look for outliers or a wrong model)."
                     : ".");
  }
  return d;
}

}  // namespace geoanchor::solver
