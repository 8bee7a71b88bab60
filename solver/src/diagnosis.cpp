#include "geoanchor/solver/diagnosis.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include <boost/math/distributions/chi_squared.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/quantization.hpp"
#include "geoanchor/geodesy/frame_catalog.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/geodesy/projection.hpp"

namespace geoanchor::solver {
namespace {

using geodesy::ControlPoint;
using geodesy::ControlSet;
using geodesy::CoordinateForm;
using geodesy::DecimalYear;
using geodesy::EcefPosition;
using Vectors = std::vector<Eigen::Vector3d>;

constexpr double kLn10 = 2.302585092994046;
// The smallest noise a point is given (m, 1σ): keeps χ² finite for a set
// whose sigmas are zero in one frame and tiny in the other.
constexpr double kNoiseFloorM = 1e-4;
// A hypothesis leaves "noise" when what is left is within this many noise RMS
// (3-D), or within this fraction of the discrepancy it was tested on.
constexpr double kExplainedNoiseFactor = 2.0;
constexpr double kExplainedFraction = 0.1;
// A candidate frame is tested only where it differs from the declared one by
// this many times the noise and the stated accuracy of their tie.
constexpr double kDistinguishableFactor = 2.0;
// How far (in prior sigmas) an estimated quantity may lie from its prior.
constexpr double kPlausiblePriorSigmas = 5.0;
// What a non-explaining hypothesis may score at most (just below decisive).
constexpr double kCapBelowDecisive = 1.99;
// Priors (1σ) of what signature hypotheses estimate.
constexpr double kGeoidPriorM = 0.5;          // EGM96 against the geoid the heights came from
constexpr double kFrameOffsetFloorM = 0.01;   // a catalog path's stated accuracy, at least this
constexpr double kEpochPriorYears = 10.0;     // how far off a declared epoch may be
constexpr double kOriginShiftPriorM = 100.0;  // how far off a nominal ENU origin may be
constexpr double kOriginYawPriorRad = 0.1;    // and its heading (5.7°)
constexpr double kMinDeltaEpochYears = 0.25;  // an epoch error smaller than this is not reported
// The frame used for plate velocities.
constexpr std::string_view kPlateFrame = "ITRF2020";

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

// The discrepancies of the used points under a model: given transform
// (optionally another map) or the declared model fitted again.
struct Engine {
  const ControlSet& set;
  const DiagnoseOptions& options;
  std::vector<std::size_t> used;
  std::vector<double> sigma;  // per used point, m (1σ per coordinate)
  double noise_rms = 0.0;
  geodesy::GeocentricConverter source_geocentric, target_geocentric;  // each frame's ellipsoid

  Engine(const ControlSet& s, const DiagnoseOptions& o) : set(s), options(o), source_geocentric(s.source_input.ellipsoid), target_geocentric(s.target_input.ellipsoid) {
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

  FitOptions fit_options() const {
    FitOptions f = options.fit;
    f.data_snooping = false;
    f.robust = FitOptions::Robust::none;
    if (!f.convention) f.convention = Convention::position_vector;  // residuals do not depend on it
    return f;
  }

  // Residuals t − model(s) of the used points; nullopt when the model cannot
  // be evaluated on `s` (a refused fit, a non-finite position).
  std::optional<Vectors> residuals(const ControlSet& s, const PointMap* map) const {
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

  std::optional<Vectors> baseline_residuals(const ControlSet& s) const {
    return residuals(s, options.transform ? &options.transform->apply : nullptr);
  }
};

// --- correction hypotheses -------------------------------------------------

struct Variant {
  std::string effect;
  std::optional<Vectors> residuals;
};

// The best of several re-readings: the smallest χ², evidence against the
// baseline less log10 of the number tried.
HypothesisResult judge_corrections(Hypothesis name, const Engine& e, const Vectors& base, std::vector<Variant> variants,
                                   const std::string& not_applicable) {
  HypothesisResult h;
  h.name = name;
  h.rms_before_m = h.rms_after_m = rms(base);
  std::erase_if(variants, [](const Variant& v) { return !v.residuals; });
  if (variants.empty()) {
    h.effect = not_applicable;
    return h;
  }
  h.applicable = true;
  h.variants_tried = static_cast<int>(variants.size());
  const double chi_before = chi2(base, e.sigma);
  const Variant* best = nullptr;
  double best_chi = std::numeric_limits<double>::infinity();
  for (const auto& v : variants) {
    const double c = chi2(*v.residuals, e.sigma);
    if (c < best_chi) {
      best_chi = c;
      best = &v;
    }
  }
  h.rms_after_m = rms(*best->residuals);
  h.score = (chi_before - best_chi) / (2.0 * kLn10) - std::log10(static_cast<double>(variants.size()));
  h.effect = best->effect + ": residual RMS " + fmt(h.rms_before_m, 3) + " m → " + fmt(h.rms_after_m, 3) + " m";
  return h;
}

// `set` with one frame's positions replaced by `reread(as_read)`; nullopt if
// any used point does not read (out of range).
std::optional<ControlSet> reread_set(const Engine& e, bool source,
                                     const std::function<std::optional<EcefPosition>(const Eigen::Vector3d&)>& reread) {
  ControlSet s = e.set;
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    auto& p = s.points[i];
    const auto x = reread(source ? p.source_as_read : p.target_as_read);
    if (!x || !x->m.allFinite()) {
      if (p.use) return std::nullopt;
      continue;
    }
    (source ? p.source : p.target) = *x;
  }
  return s;
}

std::optional<EcefPosition> from_geodetic(const Engine& e, bool source, double lat_deg, double lon_deg, double h_m) {
  if (!(std::fabs(lat_deg) <= 90.0) || !(std::fabs(lon_deg) <= 360.0) || !std::isfinite(h_m)) return std::nullopt;
  return (source ? e.source_geocentric : e.target_geocentric).ecef_from_geodetic(geodesy::GeodeticPosition{geodesy::Angle::degrees(lat_deg),
                                                                   geodesy::Angle::degrees(lon_deg),
                                                                   geodesy::EllipsoidalHeight{h_m}});
}

const geodesy::ControlInputForm& input_of(const ControlSet& s, bool source) {
  return source ? s.source_input : s.target_input;
}

std::optional<Vectors> residuals_of(const Engine& e, const std::optional<ControlSet>& s) {
  if (!s) return std::nullopt;
  return e.baseline_residuals(*s);
}

HypothesisResult lat_lon_swap(const Engine& e, const Vectors& base) {
  std::vector<Variant> variants;
  for (bool source : {true, false}) {
    if (input_of(e.set, source).form != CoordinateForm::geodetic) continue;
    const auto s = reread_set(e, source, [&](const Eigen::Vector3d& v) { return from_geodetic(e, source, v[1], v[0], v[2]); });
    variants.push_back({role_name(source) + " latitude and longitude swapped", residuals_of(e, s)});
  }
  return judge_corrections(Hypothesis::lat_lon_swap, e, base, std::move(variants),
                           "no frame has latitude/longitude columns (or its longitudes exceed 90°)");
}

HypothesisResult degrees_radians(const Engine& e, const Vectors& base) {
  std::vector<Variant> variants;
  constexpr double kDegPerRad = 180.0 / std::numbers::pi;
  for (bool source : {true, false}) {
    if (input_of(e.set, source).form != CoordinateForm::geodetic) continue;
    bool all_radian_sized = true;
    for (std::size_t i : e.used) {
      const auto& v = source ? e.set.points[i].source_as_read : e.set.points[i].target_as_read;
      all_radian_sized = all_radian_sized && std::fabs(v[0]) <= std::numbers::pi / 2 && std::fabs(v[1]) <= std::numbers::pi;
    }
    if (all_radian_sized) {
      const auto s = reread_set(
          e, source, [&](const Eigen::Vector3d& v) { return from_geodetic(e, source, v[0] * kDegPerRad, v[1] * kDegPerRad, v[2]); });
      variants.push_back({role_name(source) + " latitude/longitude are radians (read as degrees)", residuals_of(e, s)});
    }
    const auto s = reread_set(
        e, source, [&](const Eigen::Vector3d& v) { return from_geodetic(e, source, v[0] / kDegPerRad, v[1] / kDegPerRad, v[2]); });
    variants.push_back({role_name(source) + " latitude/longitude are degrees converted as if radians (×180/π)",
                        residuals_of(e, s)});
  }
  return judge_corrections(Hypothesis::degrees_radians, e, base, std::move(variants),
                           "no frame has latitude/longitude columns");
}

HypothesisResult web_mercator(const Engine& e, const Vectors& base) {
  std::vector<Variant> variants;
  constexpr double kLooksProjectedM = 1e5;  // ENU values this large may be projected ones
  for (bool source : {true, false}) {
    const auto& in = input_of(e.set, source);
    bool candidate = in.form == CoordinateForm::projected;
    if (in.form == CoordinateForm::enu) {
      for (std::size_t i : e.used) {
        const auto& v = source ? e.set.points[i].source_as_read : e.set.points[i].target_as_read;
        candidate = candidate || std::max(std::fabs(v[0]), std::fabs(v[1])) > kLooksProjectedM;
      }
    }
    if (!candidate) continue;
    const auto s = reread_set(e, source, [&](const Eigen::Vector3d& v) {
      const auto g = geodesy::web_mercator_inverse(v[0], v[1]);
      return from_geodetic(e, source, g.lat.deg(), g.lon.deg(), v[2]);
    });
    variants.push_back({role_name(source) + " easting/northing are Web Mercator (EPSG:3857)", residuals_of(e, s)});
  }
  return judge_corrections(Hypothesis::web_mercator, e, base, std::move(variants),
                           "no frame has projected (easting/northing) coordinates");
}

HypothesisResult utm_zone(const Engine& e, const Vectors& base) {
  std::vector<Variant> variants;
  for (bool source : {true, false}) {
    const auto& in = input_of(e.set, source);
    if (in.form != CoordinateForm::projected || !in.projection || !in.projection->utm) continue;
    const geodesy::UtmZone declared = *in.projection->utm;
    for (int dz = -2; dz <= 2; ++dz) {
      for (auto hemi : {geodesy::Hemisphere::north, geodesy::Hemisphere::south}) {
        const geodesy::UtmZone z{(declared.number - 1 + dz + 60) % 60 + 1, hemi};
        if (z == declared) continue;
        const geodesy::TransverseMercator grid(geodesy::utm_projection(in.projection->ellipsoid, z));
        const auto s = reread_set(e, source, [&](const Eigen::Vector3d& v) -> std::optional<EcefPosition> {
          const auto g = grid.inverse(geodesy::ProjectedPosition{v[0], v[1], geodesy::EllipsoidalHeight{v[2]}, grid.definition()});
          return from_geodetic(e, source, g.lat.deg(), g.lon.deg(), v[2]);
        });
        variants.push_back({role_name(source) + " grid is UTM zone " + z.to_string() + ", not " + declared.to_string(),
                            residuals_of(e, s)});
      }
    }
  }
  return judge_corrections(Hypothesis::utm_zone, e, base, std::move(variants), "no frame is on a declared UTM zone");
}

HypothesisResult convention_swap_correction(const Engine& e, const Vectors& base) {
  std::vector<Variant> variants;
  const auto& t = *e.options.transform;
  variants.push_back({"the transform's rotations read in the other convention", e.residuals(e.set, &t.apply_swapped)});
  return judge_corrections(Hypothesis::convention_swap, e, base, std::move(variants), "");
}

// --- float32 ---------------------------------------------------------------

// log of the standard normal upper tail Q(z), accurate far into the tail.
double log_upper_tail(double z) {
  if (z < 5.0) return std::log(0.5 * std::erfc(z / std::numbers::sqrt2));
  return -0.5 * z * z - std::log(z * std::sqrt(2.0 * std::numbers::pi)) + std::log1p(-1.0 / (z * z));
}

// log P(a < Z < b) for a standard normal Z.
double log_normal_interval(double a, double b) {
  if (a > 0.0) return log_upper_tail(a) + std::log1p(-std::exp(log_upper_tail(b) - log_upper_tail(a)));
  if (b < 0.0) return log_normal_interval(-b, -a);
  return std::log1p(-std::exp(log_upper_tail(b)) - std::exp(log_upper_tail(-a)));
}

HypothesisResult float32_ecef(const Engine& e, const Vectors& base) {
  HypothesisResult h;
  h.name = Hypothesis::float32_ecef;
  h.rms_before_m = h.rms_after_m = rms(base);
  std::vector<bool> roles;
  for (bool source : {true, false}) {
    if (input_of(e.set, source).form != CoordinateForm::ecef) continue;
    bool all = !e.used.empty();
    for (std::size_t i : e.used) {
      const auto& v = source ? e.set.points[i].source_as_read : e.set.points[i].target_as_read;
      all = all && geodesy::is_float32_valued(v[0]) && geodesy::is_float32_valued(v[1]) && geodesy::is_float32_valued(v[2]);
    }
    if (all) roles.push_back(source);
  }
  if (roles.empty()) {
    h.effect = "no frame's ECEF values are all float32 values";
    return h;
  }
  h.applicable = true;
  h.variants_tried = static_cast<int>(roles.size());
  h.score = -std::numeric_limits<double>::infinity();
  for (bool source : roles) {
    double log_ratio = 0.0;
    Vectors excess;
    double widest = 0.0;
    for (std::size_t k = 0; k < e.used.size(); ++k) {
      const auto& p = e.set.points[e.used[k]];
      const auto& v = source ? p.source_as_read : p.target_as_read;
      const double s = e.sigma[k];
      Eigen::Vector3d x = Eigen::Vector3d::Zero();
      for (int c = 0; c < 3; ++c) {
        const double q = geodesy::float32_spacing(v[c]);
        widest = std::max(widest, q);
        const double r = base[k][c];
        // Quantization (uniform over q) plus noise, against noise alone.
        const double log_quantized = log_normal_interval((r - q / 2) / s, (r + q / 2) / s) - std::log(q);
        const double log_noise = -0.5 * (r / s) * (r / s) - std::log(s * std::sqrt(2.0 * std::numbers::pi));
        log_ratio += log_quantized - log_noise;
        x[c] = std::copysign(std::max(0.0, std::fabs(r) - q / 2), r);
      }
      excess.push_back(x);
    }
    const double score = log_ratio / kLn10 - std::log10(static_cast<double>(roles.size()));
    if (score > h.score) {
      h.score = score;
      h.rms_after_m = rms(excess);
      h.effect = role_name(source) + " ECEF coordinates are float32 values (spacing up to " + fmt(widest, 3) +
                 " m): residual RMS " + fmt(h.rms_before_m, 3) + " m, " + fmt(h.rms_after_m, 3) +
                 " m beyond the quantization";
    }
  }
  return h;
}

// --- signature hypotheses ----------------------------------------------------

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

// The discrepancy from what the declared frames (or the given transform) lead
// one to expect, per used point.
struct Expectation {
  std::optional<Vectors> discrepancy;  // t − E(s)
  std::string description;
  std::optional<geodesy::AffineMap> map;  // E as one affine map when it is a catalog path at one epoch
  std::optional<DecimalYear> epoch;
};

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

bool itrf_like(const std::optional<geodesy::Frame>& f) {
  if (!f) return false;
  return f->datum() == "ITRF" || f->datum() == "WGS84" || f->datum() == "IGS" || f->datum() == "IGb";
}

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
