// The diagnosis's signature hypotheses (diagnosis_hypotheses.hpp): each
// mistake's predicted discrepancy (heights orthometric, an epoch off, an
// ENU origin off, coordinates in another datum, rotations in the other
// convention), weighed by the Bayes factor of a linear-Gaussian model.

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

#include "diagnosis_hypotheses.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/frame_catalog.hpp"
#include "geoanchor/geodesy/local_frame.hpp"

namespace geoanchor::solver::diagnosis_detail {

using geodesy::ControlSet;
using geodesy::CoordinateForm;
using geodesy::DecimalYear;
using geodesy::EcefPosition;

namespace {

// A candidate frame is tested only where it differs from the declared one by
// this many times the noise and the stated accuracy of their tie.
constexpr double kDistinguishableFactor = 2.0;
// How far (in prior sigmas) an estimated quantity may lie from its prior.
constexpr double kPlausiblePriorSigmas = 5.0;
// Priors (1σ) of what signature hypotheses estimate.
constexpr double kGeoidPriorM = 0.5;          // EGM96 against the geoid the heights came from
constexpr double kFrameOffsetFloorM = 0.01;   // a catalog path's stated accuracy, at least this
constexpr double kEpochPriorYears = 10.0;     // how far off a declared epoch may be
constexpr double kOriginShiftPriorM = 100.0;  // how far off a nominal ENU origin may be
constexpr double kOriginYawPriorRad = 0.1;    // and its heading (5.7°)
constexpr double kMinDeltaEpochYears = 0.25;  // an epoch error smaller than this is not reported
// The frame used for plate velocities.
constexpr std::string_view kPlateFrame = "ITRF2020";

// The marginal log-likelihood (natural log, up to the constant common to all
// models of the same data) of y = G θ + e, θ ~ N(0, diag(prior²)),
// e_i ~ N(0, σ_i² I), and the posterior mean of θ: exact for this linear-
// Gaussian model (Woodbury and the determinant lemma on the k×k system).
struct Evidence {
  double log_p = 0.0;
  Eigen::VectorXd theta;
};

Evidence linear_gaussian_evidence(const Vectors& y, const std::vector<Eigen::MatrixXd>& g, const Eigen::VectorXd& prior,
                                  const std::vector<double>& sigma) {
  const auto k = prior.size();
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(k, k);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(k);
  double y2 = 0.0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    const Eigen::Vector3d yi = y[i] / sigma[i];
    y2 += yi.squaredNorm();
    if (k > 0) {
      const Eigen::MatrixXd gi = g[i] / sigma[i];
      m += gi.transpose() * gi;
      b += gi.transpose() * yi;
    }
  }
  Evidence out;
  out.theta = Eigen::VectorXd::Zero(k);
  double quad = y2, logdet = 0.0;
  if (k > 0) {
    for (Eigen::Index j = 0; j < k; ++j) {
      m(j, j) += 1.0 / (prior[j] * prior[j]);
      logdet += 2.0 * std::log(prior[j]);
    }
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(m);
    out.theta = ldlt.solve(b);
    quad -= b.dot(out.theta);
    logdet += ldlt.vectorD().array().log().sum();
  }
  out.log_p = -0.5 * (quad + logdet);
  return out;
}

// A signature S with what the hypothesis estimates (G, prior), tested on the
// discrepancy a: the log10 Bayes factor against "no mistake", the estimates
// and what is left. `nuisance`: G only absorbs the signature's own
// uncertainty (an offset within a geoid model's or a frame tie's accuracy);
// then S must also beat that offset alone (log10_bf_over_offset), or a
// loosely tied frame would "explain" any discrepancy of its tie's size.
struct SignatureFit {
  double log10_bf = 0.0;
  double log10_bf_over_offset = 0.0;
  Eigen::VectorXd theta;
  Vectors left;
  // Every estimate within kPlausiblePriorSigmas of its prior: a hypothesis
  // whose offset (or Δt, or origin shift) lands far outside what it allows
  // is not what the data show, however much it lowers the residuals.
  bool plausible = true;
};

SignatureFit signature_fit(const Vectors& a, const Vectors& s, const std::vector<Eigen::MatrixXd>& g,
                           const Eigen::VectorXd& prior, const std::vector<double>& sigma, bool nuisance) {
  Vectors y(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) y[i] = a[i] - s[i];
  const Evidence with = linear_gaussian_evidence(y, g, prior, sigma);
  const Evidence null = linear_gaussian_evidence(a, {}, Eigen::VectorXd(0), sigma);
  SignatureFit out;
  out.log10_bf = (with.log_p - null.log_p) / kLn10;
  out.log10_bf_over_offset = out.log10_bf;
  if (nuisance) out.log10_bf_over_offset = (with.log_p - linear_gaussian_evidence(a, g, prior, sigma).log_p) / kLn10;
  out.theta = with.theta;
  for (Eigen::Index j = 0; j < prior.size(); ++j) {
    out.plausible = out.plausible && std::fabs(out.theta[j]) <= kPlausiblePriorSigmas * prior[j];
  }
  out.left = y;
  if (prior.size() > 0) {
    for (std::size_t i = 0; i < a.size(); ++i) out.left[i] -= g[i] * out.theta;
  }
  return out;
}

HypothesisResult from_signature(Hypothesis name, const Vectors& a, const SignatureFit& f, int parameters, int variants,
                                std::string effect) {
  HypothesisResult h;
  h.name = name;
  h.applicable = true;
  h.rms_before_m = rms(a);
  h.rms_after_m = rms(f.left);
  h.score = f.log10_bf - std::log10(static_cast<double>(std::max(variants, 1)));
  h.estimated_parameters = parameters;
  h.variants_tried = variants;
  h.plausible = f.plausible && f.log10_bf_over_offset >= kDecisiveLog10BayesFactor;
  h.effect = std::move(effect) + ": discrepancy RMS " + fmt(h.rms_before_m, 3) + " m → " + fmt(h.rms_after_m, 3) + " m";
  if (!f.plausible) h.effect += " (only with an estimate far outside what the hypothesis allows)";
  else if (f.log10_bf_over_offset < kDecisiveLog10BayesFactor) h.effect += " (no better than an offset within its stated accuracy)";
  return h;
}

}  // namespace

HypothesisResult height_type(const Engine& e, const Expectation& x, double rms_base) {
  if (!e.options.geoid) return not_applicable(Hypothesis::height_type, rms_base, "no geoid model loaded");
  if (!x.discrepancy) return not_applicable(Hypothesis::height_type, rms_base, "expectation " + x.description);
  const auto& a = *x.discrepancy;
  std::vector<Eigen::MatrixXd> g;
  Vectors up_n;
  double mean_n = 0.0;
  for (std::size_t i : e.used) {
    const auto& p = e.set.points[i];
    const auto [n, up] = geodesy::geoid_along_up(*e.options.geoid, e.target_geocentric, p.target);
    if (!std::isfinite(n)) return not_applicable(Hypothesis::height_type, rms_base, "a point lies outside the geoid grid");
    up_n.push_back(up * n);
    g.push_back(up);
    mean_n += n / static_cast<double>(e.used.size());
  }
  Eigen::VectorXd prior(1);
  prior << kGeoidPriorM;
  std::optional<SignatureFit> best;
  bool best_source = true;
  for (bool source : {true, false}) {
    // Orthometric source heights put E(s) too low by N (A = +N up); target
    // heights too low by N give A = −N up.
    Vectors s;
    for (const auto& v : up_n) s.push_back(source ? v : Eigen::Vector3d(-v));
    auto f = signature_fit(a, s, g, prior, e.sigma, true);
    if (!best || f.log10_bf > best->log10_bf) {
      best = std::move(f);
      best_source = source;
    }
  }
  double mean_up = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) mean_up += a[k].dot(g[k].col(0)) / static_cast<double>(a.size());
  return from_signature(Hypothesis::height_type, a, *best, 0, 2,
                        role_name(best_source) + " heights look orthometric, not ellipsoidal: vertical offset " +
                            fmt(mean_up, 3) + " m where " + e.options.geoid->model_name() + " gives N = " +
                            fmt(mean_n, 3) + " m");
}

namespace {

bool itrf_like(const std::optional<geodesy::Frame>& f) {
  if (!f) return false;
  return f->datum() == "ITRF" || f->datum() == "WGS84" || f->datum() == "IGS" || f->datum() == "IGb";
}

}  // namespace

HypothesisResult epoch_hypothesis(const Engine& e, const Expectation& x, double rms_base) {
  if (!x.discrepancy) return not_applicable(Hypothesis::epoch, rms_base, "expectation " + x.description);
  const auto dated = [](const std::optional<geodesy::Frame>& f) { return f && f->epoch() && itrf_like(f); };
  if (!dated(e.set.source_frame) && !dated(e.set.target_frame)) {
    return not_applicable(Hypothesis::epoch, rms_base,
                          "needs a declared epoch to be wrong: an ITRF or WGS 84 frame with @EPOCH (plate-fixed frames "
                          "barely move with the epoch)");
  }
  const auto& a = *x.discrepancy;
  Eigen::VectorXd prior(1);
  prior << kEpochPriorYears;
  struct Candidate {
    std::string what;
    std::vector<Eigen::MatrixXd> g;
  };
  std::vector<Candidate> candidates;
  bool velocities = !e.used.empty();
  for (std::size_t i : e.used) velocities = velocities && e.set.points[i].velocities != nullptr;
  if (velocities) {
    Candidate c{"the points' own velocities", {}};
    for (std::size_t i : e.used) c.g.push_back(Eigen::MatrixXd(e.set.points[i].velocities->target_m_per_year));
    candidates.push_back(std::move(c));
  } else {
    for (const auto& pm : geodesy::plate_motion_models()) {
      if (pm.frame != kPlateFrame) continue;
      Candidate c{"the " + pm.plate + " plate's motion (" + pm.frame + "-PMM)", {}};
      for (std::size_t i : e.used) c.g.push_back(Eigen::MatrixXd(pm.velocity_m_per_year(e.set.points[i].target)));
      candidates.push_back(std::move(c));
    }
  }
  std::optional<SignatureFit> best;
  std::size_t best_c = 0;
  const Vectors zero(a.size(), Eigen::Vector3d::Zero());
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    auto f = signature_fit(a, zero, candidates[c].g, prior, e.sigma, false);
    if (!best || f.log10_bf > best->log10_bf) {
      best = std::move(f);
      best_c = c;
    }
  }
  if (!best) return not_applicable(Hypothesis::epoch, rms_base, "no plate motion model is loaded");
  const Candidate& chosen = candidates[best_c];
  const double dt = best->theta[0];
  double speed = 0.0;
  for (const auto& g : chosen.g) speed += g.norm() / static_cast<double>(chosen.g.size());
  auto h = from_signature(Hypothesis::epoch, a, *best, 1, static_cast<int>(candidates.size()),
                          "a shift of " + fmt(speed * std::fabs(dt), 3) + " m along " + chosen.what + " (" +
                              fmt(speed * 1000.0, 1) + " mm/yr): the target coordinates are " + fmt(dt, 2) +
                              " yr later than declared (or the source's earlier)");
  if (std::fabs(dt) < kMinDeltaEpochYears) h.score = std::min(h.score, 0.0);
  return h;
}

HypothesisResult enu_origin(const Engine& e, const Expectation& x, double rms_base) {
  const bool src = e.set.source_input.form == CoordinateForm::enu, dst = e.set.target_input.form == CoordinateForm::enu;
  if (!src && !dst) return not_applicable(Hypothesis::enu_origin, rms_base, "no frame has ENU map coordinates");
  if (!x.discrepancy) return not_applicable(Hypothesis::enu_origin, rms_base, "expectation " + x.description);
  if (!e.set.origin) return not_applicable(Hypothesis::enu_origin, rms_base, "the set records no nominal origin");
  const auto& a = *x.discrepancy;
  const geodesy::LocalTangentPlane plane(*e.set.origin);
  const Eigen::Matrix3d r = plane.enu_from_ecef_rotation();
  const Eigen::Vector3d up = r.row(2).transpose();
  const EcefPosition o = plane.ecef_from_enu(geodesy::EnuPosition{Eigen::Vector3d::Zero(), *e.set.origin});
  std::vector<Eigen::MatrixXd> g;
  for (std::size_t i : e.used) {
    const auto& p = e.set.points[i];
    Eigen::MatrixXd gi(3, 4);
    gi.leftCols(3).setIdentity();
    gi.col(3) = up.cross((src ? p.source : p.target).m - o.m);
    g.push_back(gi);
  }
  Eigen::VectorXd prior(4);
  prior << kOriginShiftPriorM, kOriginShiftPriorM, kOriginShiftPriorM, kOriginYawPriorRad;
  const auto f = signature_fit(a, Vectors(a.size(), Eigen::Vector3d::Zero()), g, prior, e.sigma, false);
  // The map's points must move by this to land on the targets (source map),
  // or the other way round (target map).
  const double sign = src ? 1.0 : -1.0;
  const Eigen::Vector3d shift_enu = sign * (r * f.theta.head<3>());
  const double yaw_deg = sign * f.theta[3] * 180.0 / std::numbers::pi;
  return from_signature(Hypothesis::enu_origin, a, f, 4, 1,
                        std::string(src ? "source" : "target") + " ENU origin is off: the map moves by E " +
                            fmt(shift_enu[0], 3) + " m, N " + fmt(shift_enu[1], 3) + " m, U " + fmt(shift_enu[2], 3) +
                            " m and turns " + fmt(yaw_deg, 4) + "° (counter-clockwise) about its origin");
}

HypothesisResult datum_mix(const Engine& e, const Expectation& x, double rms_base) {
  if (!x.discrepancy) return not_applicable(Hypothesis::datum_mix, rms_base, "expectation " + x.description);
  const auto& fs = e.set.source_frame;
  const auto& ft = e.set.target_frame;
  if (!fs || !ft) {
    return not_applicable(Hypothesis::datum_mix, rms_base,
                          "needs the declared frames (source_frame, target_frame) to know what to compare");
  }
  const auto& a = *x.discrepancy;
  const auto t_of = [&](std::size_t i) {
    const auto t = x.epoch ? x.epoch : e.set.points[i].epoch;
    return t.value_or(DecimalYear{2000.0});
  };
  // The used points' sources carried from frame `from` to frame `to` by the catalog.
  auto positions_in = [&](std::string_view from, std::string_view to) -> std::optional<Vectors> {
    try {
      const auto path = geodesy::find_frame_path(from, to, "datum_mix");
      if (path.time_dependent() && !x.epoch) {
        for (std::size_t i : e.used) {
          if (!e.set.points[i].epoch) return std::nullopt;
        }
      }
      Vectors out;
      for (std::size_t i : e.used) {
        const auto& p = e.set.points[i];
        out.push_back(path.apply(p.source, t_of(i)).m);
      }
      return out;
    } catch (const Error&) {
      return std::nullopt;
    }
  };
  const auto declared = positions_in(fs->name(), ft->name());
  if (!declared) return not_applicable(Hypothesis::datum_mix, rms_base, "the declared frames are not in the catalog");
  struct Candidate {
    std::string what;
    Vectors s;
    double accuracy_m;
  };
  std::vector<Candidate> candidates;
  for (const auto& name : geodesy::catalog_frame_names()) {
    for (bool source : {true, false}) {
      if (name == (source ? fs->name() : ft->name())) continue;
      // Target actually in `name`: t = P(fs→name)(s). Source actually in
      // `name`: t = P(name→ft)(s).
      const auto actual = source ? positions_in(name, ft->name()) : positions_in(fs->name(), name);
      if (!actual) continue;
      Vectors s;
      for (std::size_t k = 0; k < a.size(); ++k) s.push_back((*actual)[k] - (*declared)[k]);
      double acc = kFrameOffsetFloorM;
      try {
        acc = std::max(acc, (source ? geodesy::find_frame_path(name, fs->name(), "") : geodesy::find_frame_path(ft->name(), name, ""))
                                .accuracy_m());
      } catch (const Error&) {
      }
      // Indistinguishable from the declared frame here: within the noise or
      // within the stated accuracy of the two frames' tie.
      if (rms(s) < kDistinguishableFactor * std::max(e.noise_rms, acc)) continue;
      candidates.push_back({role_name(source) + " coordinates look like " + name + ", not " +
                                (source ? fs->name() : ft->name()),
                            std::move(s), acc});
    }
  }
  if (candidates.empty()) return not_applicable(Hypothesis::datum_mix, rms_base, "no catalog frame differs measurably here");
  std::optional<SignatureFit> best;
  std::size_t best_c = 0;
  std::vector<Eigen::MatrixXd> g(a.size(), Eigen::MatrixXd(Eigen::Matrix3d::Identity()));
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    const Eigen::VectorXd prior = Eigen::VectorXd::Constant(3, candidates[c].accuracy_m);
    auto f = signature_fit(a, candidates[c].s, g, prior, e.sigma, true);
    if (!best || f.log10_bf > best->log10_bf) {
      best = std::move(f);
      best_c = c;
    }
  }
  return from_signature(Hypothesis::datum_mix, a, *best, 0, static_cast<int>(candidates.size()),
                        candidates[best_c].what + " (a " + fmt(rms(candidates[best_c].s), 3) + " m difference here)");
}

HypothesisResult convention_swap_signature(const Engine& e, const Expectation& x, double rms_base) {
  if (e.options.transform) {
    return not_applicable(Hypothesis::convention_swap, rms_base, "the given transform has no rotations");
  }
  if (!x.discrepancy || !x.map) {
    return not_applicable(Hypothesis::convention_swap, rms_base,
                          "a fitted transform takes the signs of its rotations from the data; give --transform (or "
                          "declare frames the catalog connects) to test a published set");
  }
  const Eigen::Matrix3d l = x.map->linear();
  Vectors s;
  for (std::size_t i : e.used) s.push_back((l.transpose() - l) * e.set.points[i].source.m);
  if (rms(s) < 1e-4) {
    return not_applicable(Hypothesis::convention_swap, rms_base, "the expected transformation has no rotations");
  }
  const auto f = signature_fit(*x.discrepancy, s, {}, Eigen::VectorXd(0), e.sigma, false);
  return from_signature(Hypothesis::convention_swap, *x.discrepancy, f, 0, 1,
                        "the target was computed with the catalog's rotations in the other convention");
}

}  // namespace geoanchor::solver::diagnosis_detail
