// The diagnosis's correction hypotheses (diagnosis_hypotheses.hpp): the
// data re-read as the mistake would have it (latitude and longitude
// swapped, degrees and radians, Web Mercator, another UTM zone, a transform
// in the other convention) and ECEF values rounded to float32.

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>

#include "diagnosis_hypotheses.hpp"
#include "geoanchor/geodesy/projection.hpp"
#include "geoanchor/geodesy/quantization.hpp"

namespace geoanchor::solver::diagnosis_detail {

using geodesy::ControlSet;
using geodesy::CoordinateForm;
using geodesy::EcefPosition;

namespace {

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

}  // namespace

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

namespace {

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

}  // namespace

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

}  // namespace geoanchor::solver::diagnosis_detail
