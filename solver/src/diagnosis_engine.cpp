// What the diagnosis's hypotheses work on (diagnosis_engine.hpp).

#include "diagnosis_engine.hpp"

#include <algorithm>
#include <cmath>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/frame_catalog.hpp"
#include "geoanchor/base/number_text.hpp"

namespace geoanchor::solver::diagnosis_detail {

using geodesy::ControlPoint;
using geodesy::ControlSet;
using geodesy::DecimalYear;

namespace {

// The smallest noise a point is given (m, 1σ): keeps χ² finite for a set
// whose sigmas are zero in one frame and tiny in the other.
constexpr double kNoiseFloorM = 1e-4;

}  // namespace

std::string fmt(double v, int decimals) { return format_fixed(v, decimals); }

std::string role_name(bool source) { return source ? "source" : "target"; }

double rms(const Vectors& v) {
  if (v.empty()) return 0.0;
  double s = 0.0;
  for (const auto& x : v) s += x.squaredNorm();
  return std::sqrt(s / static_cast<double>(v.size()));
}

double chi2(const Vectors& r, const std::vector<double>& sigma) {
  double s = 0.0;
  for (std::size_t i = 0; i < r.size(); ++i) s += r[i].squaredNorm() / (sigma[i] * sigma[i]);
  return s;
}

std::optional<DecimalYear> epoch_of(const ControlSet& set, const ControlPoint& p) {
  if (p.epoch) return p.epoch;
  if (set.target_frame && set.target_frame->epoch()) return set.target_frame->epoch();
  if (set.source_frame && set.source_frame->epoch()) return set.source_frame->epoch();
  return std::nullopt;
}

Engine::Engine(const ControlSet& s, const DiagnoseOptions& o)
    : set(s), options(o), source_geocentric(s.source_input.ellipsoid), target_geocentric(s.target_input.ellipsoid) {
  for (std::size_t i = 0; i < set.points.size(); ++i) {
    if (set.points[i].use) used.push_back(i);
  }
  double total = 0.0;
  for (std::size_t i : used) {
    const auto& p = set.points[i];
    double s2 = set.has_a_priori_sigmas ? (p.source_cov_m2.trace() + p.target_cov_m2.trace()) / 3.0
                                        : 2.0 * options.assumed_sigma_m * options.assumed_sigma_m;
    s2 = std::max(s2, kNoiseFloorM * kNoiseFloorM);
    sigma.push_back(std::sqrt(s2));
    total += 3.0 * s2;
  }
  noise_rms = used.empty() ? 0.0 : std::sqrt(total / static_cast<double>(used.size()));
}

FitOptions Engine::fit_options() const {
  FitOptions f = options.fit;
  f.data_snooping = false;
  f.robust = FitOptions::Robust::none;
  if (!f.convention) f.convention = Convention::position_vector;  // residuals do not depend on it
  return f;
}

std::optional<Vectors> Engine::residuals(const ControlSet& s, const PointMap* map) const {
  Vectors out;
  out.reserve(used.size());
  try {
    if (map) {
      for (std::size_t i : used) {
        const auto& p = s.points[i];
        out.push_back(p.target.m - (*map)(p.source, epoch_of(s, p)).m);
      }
    } else {
      const FitResult fit = fit_helmert(s, fit_options());
      for (std::size_t i : used) {
        const auto& p = s.points[i];
        out.push_back(p.target.m - apply_fit(fit, p.source, p.epoch).m);
      }
    }
  } catch (const Error&) {
    return std::nullopt;
  }
  for (const auto& r : out) {
    if (!r.allFinite()) return std::nullopt;
  }
  return out;
}

std::optional<Vectors> Engine::baseline_residuals(const ControlSet& s) const {
  return residuals(s, options.transform ? &options.transform->apply : nullptr);
}

Expectation expectation(const Engine& e) {
  Expectation x;
  const auto& set = e.set;
  auto identity = [&](std::string why) {
    Vectors d;
    for (std::size_t i : e.used) d.push_back(set.points[i].target.m - set.points[i].source.m);
    x.discrepancy = std::move(d);
    x.description = std::move(why);
    x.map = geodesy::AffineMap::identity();
  };
  if (e.options.transform) {
    x.discrepancy = e.baseline_residuals(set);
    x.description = "the given transform " + e.options.transform->description;
    return x;
  }
  if (!set.source_frame || !set.target_frame) {
    identity("the identity (frames not declared: the two coordinate sets are expected to agree)");
    return x;
  }
  const auto& fs = *set.source_frame;
  const auto& ft = *set.target_frame;
  if (fs.epoch() && ft.epoch() && *fs.epoch() != *ft.epoch()) {
    x.description = "unavailable: the declared epochs differ (" + fs.to_string() + ", " + ft.to_string() +
                    "); the signature tests need the two sets at one epoch";
    return x;
  }
  x.epoch = fs.epoch() ? fs.epoch() : ft.epoch();
  if (fs.name() == ft.name()) {
    identity("the identity (both sets in " + fs.to_string() + ")");
    return x;
  }
  try {
    const auto path = geodesy::find_frame_path(fs.name(), ft.name(), "declared frames");
    Vectors d;
    for (std::size_t i : e.used) {
      const auto& p = set.points[i];
      const auto t = x.epoch ? x.epoch : p.epoch;
      if (!t && path.time_dependent()) {
        x.description = "unavailable: " + fs.name() + " → " + ft.name() + " is time-dependent and point " + p.id +
                        " has no epoch";
        return x;
      }
      d.push_back(p.target.m - path.apply(p.source, t.value_or(DecimalYear{2000.0})).m);
    }
    x.discrepancy = std::move(d);
    if (x.epoch || !path.time_dependent()) x.map = path.at(x.epoch.value_or(DecimalYear{2000.0}));
    x.description = "the catalog path " + fs.to_string() + " → " + ft.to_string() + " (±" + fmt(path.accuracy_m(), 3) + " m)";
  } catch (const Error& err) {
    x.description = std::string("unavailable: ") + err.what();
  }
  return x;
}

HypothesisResult not_applicable(Hypothesis name, double rms_base, std::string why) {
  HypothesisResult h;
  h.name = name;
  h.rms_before_m = h.rms_after_m = rms_base;
  h.effect = std::move(why);
  return h;
}

}  // namespace geoanchor::solver::diagnosis_detail
