#include "geoanchor/io/transform_file.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "geoanchor/geodesy/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/number_text.hpp"
#include "geoanchor/io/json_input.hpp"

namespace geoanchor::io {
namespace {

using geodesy::Angle;
using geodesy::CoordinateFrame;
using geodesy::PositionVector;
using geodesy::ScaleDifference;
using nlohmann::json;

// Top-level keys. The fit issue's statistics travel in the same file; apply
// and convert read only what they need and check that nothing is misspelt.
const std::set<std::string> kTopLevelKeys = {
    "model",       "convention", "rotation_model", "source_frame", "target_frame", "reference_epoch",
    "parameters",  "sigmas",     "correlation",    "statistics",   "points",       "proj_pipeline",
    "epsg_method", "generator",  "format_version", "description",  "alternatives", "nominal_origin",
    "wkt2",        "projjson",   "grid",          "correlation_parameters", "control_extent"};

[[noreturn]] void fail(std::string_view source, const std::string& key, const std::string& what) {
  throw Error(ErrorKind::input, "E_TRANSFORM", std::string(source) + ": " + key + ": " + what);
}

// One parameter, which may be written in either of two units.
struct ParamSpec {
  const char* name;     // "tx"
  const char* unit_a;   // "m"
  double factor_a;      // to the canonical unit
  const char* unit_b;   // "mm"
  double factor_b;
};

// Canonical units: metres, arc-seconds, ppm (and per year).
constexpr std::array<ParamSpec, 7> kSeven = {{{"tx", "m", 1.0, "mm", 1e-3},
                                              {"ty", "m", 1.0, "mm", 1e-3},
                                              {"tz", "m", 1.0, "mm", 1e-3},
                                              {"rx", "arcsec", 1.0, "mas", 1e-3},
                                              {"ry", "arcsec", 1.0, "mas", 1e-3},
                                              {"rz", "arcsec", 1.0, "mas", 1e-3},
                                              {"ds", "ppm", 1.0, "ppb", 1e-3}}};

class ParameterReader {
 public:
  // Misspelt keys are reported first, by name, before any missing parameter.
  ParameterReader(const json& params, std::string_view source) : params_(params), source_(source) {
    if (!params_.is_object()) fail(source_, "parameters", "expected an object of unit-named numbers");
    std::set<std::string> known;
    for (const auto& p : kSeven) {
      for (const char* unit : {p.unit_a, p.unit_b}) {
        known.insert(std::string(p.name) + "_" + unit);
        known.insert(std::string("d") + p.name + "_" + unit + "_per_year");
      }
    }
    for (const char* pivot : {"px_m", "py_m", "pz_m"}) known.insert(pivot);
    for (const auto& [key, value] : params_.items()) {
      if (!known.count(key)) {
        fail(source_, "parameters." + key,
             "unknown parameter; expected tx_m ty_m tz_m rx_arcsec ry_arcsec rz_arcsec ds_ppm (mm, mas, ppb also "
             "read) and, for helmert14, their rates d..._per_year");
      }
    }
  }

  // The value in canonical units, or nullopt if absent.
  std::optional<double> get(const ParamSpec& p, bool rate) {
    const std::string suffix = rate ? "_per_year" : "";
    const std::string prefix = rate ? std::string("d") + p.name : std::string(p.name);
    const std::string key_a = prefix + "_" + p.unit_a + suffix;
    const std::string key_b = prefix + "_" + p.unit_b + suffix;
    const bool has_a = params_.contains(key_a), has_b = params_.contains(key_b);
    if (has_a && has_b) fail(source_, "parameters." + key_a, "given twice, also as " + key_b + "; keep one");
    if (!has_a && !has_b) return std::nullopt;
    const std::string& key = has_a ? key_a : key_b;
    used_.insert(key);
    const json& v = params_.at(key);
    if (!v.is_number()) fail(source_, "parameters." + key, "value " + v.dump() + " is not a number");
    return v.get<double>() * (has_a ? p.factor_a : p.factor_b);
  }

  // A parameter with a single unit (the Molodensky-Badekas pivot).
  double require_plain(const std::string& key, std::string_view model) {
    if (!params_.contains(key)) fail(source_, "parameters", "missing " + key + " for model " + std::string(model));
    used_.insert(key);
    const json& v = params_.at(key);
    if (!v.is_number()) fail(source_, "parameters." + key, "value " + v.dump() + " is not a number");
    return v.get<double>();
  }

  double require(const ParamSpec& p, bool rate, std::string_view model) {
    const auto v = get(p, rate);
    if (!v) {
      const std::string prefix = rate ? std::string("d") + p.name : std::string(p.name);
      const std::string suffix = rate ? "_per_year" : "";
      fail(source_, "parameters", "missing " + prefix + "_" + p.unit_a + suffix + " (or " + prefix + "_" + p.unit_b +
                                      suffix + ") for model " + std::string(model));
    }
    return *v;
  }

  // A known parameter that the model does not use (a rate in a 7-parameter
  // set) would be silently ignored: refuse it.
  void check_all_used(std::string_view model) const {
    for (const auto& [key, value] : params_.items()) {
      if (!used_.count(key)) {
        fail(source_, "parameters." + key, "not a parameter of model " + std::string(model) +
                                               (key.find("_per_year") != std::string::npos
                                                    ? "; rates need model helmert14 with a reference_epoch"
                                                    : ""));
      }
    }
  }

 private:
  const json& params_;
  std::string_view source_;
  std::set<std::string> used_;
};

template <geodesy::RotationConvention C>
geodesy::Helmert7<C> seven_from(const std::array<double, 7>& v) {
  geodesy::Helmert7<C> h;
  h.t_m = Eigen::Vector3d(v[0], v[1], v[2]);
  h.rx = Angle::arcseconds(v[3]);
  h.ry = Angle::arcseconds(v[4]);
  h.rz = Angle::arcseconds(v[5]);
  h.ds = ScaleDifference::ppm(v[6]);
  return h;
}

template <geodesy::RotationConvention C>
geodesy::Helmert7Rates<C> rates_from(const std::array<double, 7>& v) {
  geodesy::Helmert7Rates<C> r;
  r.dt_m_per_year = Eigen::Vector3d(v[0], v[1], v[2]);
  r.drx_per_year = Angle::arcseconds(v[3]);
  r.dry_per_year = Angle::arcseconds(v[4]);
  r.drz_per_year = Angle::arcseconds(v[5]);
  r.dds_per_year = ScaleDifference::ppm(v[6]);
  return r;
}

std::string string_field(const json& doc, const char* key, std::string_view source) {
  const json& v = doc.at(key);
  if (!v.is_string()) fail(source, key, "value " + v.dump() + " is not a string");
  return v.get<std::string>();
}

// Shortest round-trip number for JSON output.
json number(double v) { return json::parse(format_shortest(v)); }

}  // namespace

std::string_view to_string(TransformModel m) {
  switch (m) {
    case TransformModel::helmert7: return "helmert7";
    case TransformModel::helmert6: return "helmert6";
    case TransformModel::translation3: return "translation3";
    case TransformModel::helmert14: return "helmert14";
    case TransformModel::molodensky_badekas: return "molodensky-badekas";
    case TransformModel::enu_origin: return "enu-origin";
    case TransformModel::site_calibration: return "site-calibration";
  }
  return "?";
}

std::string_view TransformFile::convention_name() const {
  return std::visit([](const auto& h) -> std::string_view {
    using H = std::decay_t<decltype(h)>;
    if constexpr (std::is_same_v<H, geodesy::Helmert7<PositionVector>> ||
                  std::is_same_v<H, geodesy::Helmert14<PositionVector>>) {
      return PositionVector::name;
    } else {
      return CoordinateFrame::name;
    }
  }, helmert);
}

geodesy::EcefPosition TransformFile::apply(const geodesy::EcefPosition& x,
                                           std::optional<geodesy::DecimalYear> observation_epoch, bool inverse,
                                           std::string_view where) const {
  if (site_calibration) return inverse ? site_calibration->source_from_target(x) : site_calibration->target_from_source(x);
  const geodesy::AffineMap m = target_from_source(observation_epoch, where);
  return geodesy::EcefPosition((inverse ? m.inverse() : m).apply(x.m));
}

geodesy::AffineMap TransformFile::target_from_source(std::optional<geodesy::DecimalYear> observation_epoch,
                                                     std::string_view where) const {
  if (site_calibration) {
    throw Error(ErrorKind::usage, "E_TRANSFORM", std::string(where) + ": a site calibration is not an affine map");
  }
  if (enu_origin) {
    return geodesy::enu_origin_correction(enu_origin->nominal, enu_origin->shift_enu_m, enu_origin->yaw, enu_origin->ds);
  }
  return std::visit([&](const auto& h) -> geodesy::AffineMap {
    using H = std::decay_t<decltype(h)>;
    if constexpr (std::is_same_v<H, geodesy::Helmert14<PositionVector>> ||
                  std::is_same_v<H, geodesy::Helmert14<CoordinateFrame>>) {
      if (!observation_epoch) {
        throw Error(ErrorKind::input, "E_EPOCH_MISSING",
                    std::string(where) +
                        ": no observation epoch for a 14-parameter (time-dependent) transform; give --epoch YEAR or an "
                        "epoch column (the reference epoch " +
                        geodesy::format_decimal_year(h.reference_epoch) + " is never substituted)");
      }
      return geodesy::target_from_source(geodesy::evaluate_at(h, *observation_epoch), rotation_model);
    } else {
      const geodesy::AffineMap m = geodesy::target_from_source(h, rotation_model);
      if (!pivot_m) return m;
      // p + T + L (x − p) = L x + (T + p − L p)
      return geodesy::AffineMap(m.linear(), m.translation_m() + *pivot_m - m.linear() * *pivot_m);
    }
  }, helmert);
}

namespace {

double number_field(const json& obj, const std::string& key, const std::string& where, std::string_view source) {
  if (!obj.contains(key)) fail(source, where + key, "missing");
  const json& v = obj.at(key);
  if (!v.is_number()) fail(source, where + key, "value " + v.dump() + " is not a number");
  return v.get<double>();
}

constexpr double kCorrectedOriginTol_m = 0.001;

geodesy::LocalOrigin origin_of(const json& doc, std::string_view source) {
  if (!doc.contains("nominal_origin") || !doc.at("nominal_origin").is_object()) {
    fail(source, "nominal_origin", "missing; enu-origin needs {\"lat_deg\", \"lon_deg\", \"h_m\", \"ellipsoid\"}");
  }
  const json& no = doc.at("nominal_origin");
  for (const auto& [key, value] : no.items()) {
    if (key != "lat_deg" && key != "lon_deg" && key != "h_m" && key != "ellipsoid" && key != "height_type") {
      fail(source, "nominal_origin." + key, "unknown key; expected lat_deg, lon_deg, h_m, ellipsoid");
    }
  }
  geodesy::Ellipsoid e = geodesy::Ellipsoid::wgs84();
  if (no.contains("ellipsoid")) {
    const std::string name = string_field(no, "ellipsoid", source);
    if (name == "GRS80") {
      e = geodesy::Ellipsoid::grs80();
    } else if (name != "WGS84") {
      fail(source, "nominal_origin.ellipsoid", "value \"" + name + "\" unknown; expected WGS84 or GRS80");
    }
  }
  const double lat = number_field(no, "lat_deg", "nominal_origin.", source);
  const double lon = number_field(no, "lon_deg", "nominal_origin.", source);
  if (std::fabs(lat) > 90.0) fail(source, "nominal_origin.lat_deg", "latitude " + format_shortest(lat) + " not in [-90, 90]");
  if (std::fabs(lon) > 180.0) fail(source, "nominal_origin.lon_deg", "longitude " + format_shortest(lon) + " not in [-180, 180]");
  return {{Angle::degrees(lat), Angle::degrees(lon), geodesy::EllipsoidalHeight{number_field(no, "h_m", "nominal_origin.", source)}}, e};
}

void frames_of(const json& doc, TransformFile& t, std::string_view source) {
  for (const char* key : {"source_frame", "target_frame"}) {
    if (doc.contains(key)) {
      auto f = geodesy::Frame::parse(string_field(doc, key, source), std::string(source) + ": " + key);
      (std::string_view(key) == "source_frame" ? t.source_frame : t.target_frame) = std::move(f);
    }
  }
}

TransformFile parse_enu_origin(const json& doc, TransformFile t, std::string_view source) {
  frames_of(doc, t, source);
  EnuOriginCorrection c;
  c.nominal = origin_of(doc, source);
  const geodesy::Ellipsoid e = c.nominal.ellipsoid;
  if (!doc.contains("parameters") || !doc.at("parameters").is_object()) fail(source, "parameters", "missing");
  const json& p = doc.at("parameters");
  const std::set<std::string> known = {"shift_e_m", "shift_n_m", "shift_u_m", "yaw_arcsec", "ds_ppm",
                                       "origin_lat_deg", "origin_lon_deg", "origin_h_m"};
  for (const auto& [key, value] : p.items()) {
    if (!known.count(key)) {
      fail(source, "parameters." + key, "unknown parameter for enu-origin; expected shift_e_m shift_n_m shift_u_m "
                                        "yaw_arcsec ds_ppm origin_lat_deg origin_lon_deg origin_h_m");
    }
  }
  c.shift_enu_m = Eigen::Vector3d(number_field(p, "shift_e_m", "parameters.", source),
                                  number_field(p, "shift_n_m", "parameters.", source),
                                  number_field(p, "shift_u_m", "parameters.", source));
  c.yaw = Angle::arcseconds(p.contains("yaw_arcsec") ? number_field(p, "yaw_arcsec", "parameters.", source) : 0.0);
  c.ds = ScaleDifference::ppm(p.contains("ds_ppm") ? number_field(p, "ds_ppm", "parameters.", source) : 0.0);
  // The corrected origin is derived; if given, it must agree with the shift.
  if (p.contains("origin_lat_deg") || p.contains("origin_lon_deg") || p.contains("origin_h_m")) {
    const geodesy::LocalOrigin derived = geodesy::corrected_origin(c.nominal, c.shift_enu_m);
    const geodesy::GeodeticPosition stated{Angle::degrees(number_field(p, "origin_lat_deg", "parameters.", source)),
                                           Angle::degrees(number_field(p, "origin_lon_deg", "parameters.", source)),
                                           geodesy::EllipsoidalHeight{number_field(p, "origin_h_m", "parameters.", source)}};
    const double d = (geodesy::ecef_from_geodetic(e, stated).m - geodesy::ecef_from_geodetic(e, derived.point).m).norm();
    if (d > kCorrectedOriginTol_m) {
      fail(source, "parameters.origin_lat_deg", "the corrected origin is " + format_shortest(d) +
                                                    " m from nominal_origin + shift; expected them to agree within 1 mm");
    }
  }
  t.enu_origin = c;
  t.rotation_model = geodesy::RotationModel::exact;
  return t;
}

TransformFile parse_site_calibration(const json& doc, TransformFile t, std::string_view source) {
  frames_of(doc, t, source);
  const geodesy::LocalOrigin local = origin_of(doc, source);
  if (!doc.contains("grid") || !doc.at("grid").is_object()) {
    fail(source, "grid", "missing; expected {\"lat0_deg\", \"lon0_deg\", \"k0\", \"false_easting_m\", \"false_northing_m\"}");
  }
  const json& g = doc.at("grid");
  for (const auto& [key, value] : g.items()) {
    if (key != "lat0_deg" && key != "lon0_deg" && key != "k0" && key != "false_easting_m" && key != "false_northing_m" &&
        key != "ellipsoid") {
      fail(source, "grid." + key, "unknown key");
    }
  }
  geodesy::ProjectionDef grid;
  grid.ellipsoid = local.ellipsoid;
  grid.tm.lat0 = Angle::degrees(number_field(g, "lat0_deg", "grid.", source));
  grid.tm.lon0 = Angle::degrees(number_field(g, "lon0_deg", "grid.", source));
  grid.tm.k0 = number_field(g, "k0", "grid.", source);
  grid.tm.false_easting_m = g.contains("false_easting_m") ? number_field(g, "false_easting_m", "grid.", source) : 0.0;
  grid.tm.false_northing_m = g.contains("false_northing_m") ? number_field(g, "false_northing_m", "grid.", source) : 0.0;
  if (!(grid.tm.k0 > 0.0 && grid.tm.k0 < 2.0)) fail(source, "grid.k0", "not in (0, 2)");
  if (!doc.contains("parameters") || !doc.at("parameters").is_object()) fail(source, "parameters", "missing");
  const json& p = doc.at("parameters");
  const std::set<std::string> known = {"shift_e_m",   "shift_n_m",   "rotation_arcsec", "scale_ppm",   "vertical_shift_m",
                                       "slope_n_ppm", "slope_e_ppm", "centroid_e_m",    "centroid_n_m", "grid_lat0_deg",
                                       "grid_lon0_deg"};
  for (const auto& [key, value] : p.items()) {
    if (!known.count(key)) fail(source, "parameters." + key, "unknown parameter for site-calibration");
  }
  geodesy::SiteCalibrationParams sp;
  sp.shift_e_m = number_field(p, "shift_e_m", "parameters.", source);
  sp.shift_n_m = number_field(p, "shift_n_m", "parameters.", source);
  sp.rotation = Angle::arcseconds(number_field(p, "rotation_arcsec", "parameters.", source));
  sp.scale = ScaleDifference::ppm(number_field(p, "scale_ppm", "parameters.", source));
  sp.vertical_shift_m = number_field(p, "vertical_shift_m", "parameters.", source);
  sp.slope_n = number_field(p, "slope_n_ppm", "parameters.", source) * 1e-6;
  sp.slope_e = number_field(p, "slope_e_ppm", "parameters.", source) * 1e-6;
  sp.centroid_e_m = number_field(p, "centroid_e_m", "parameters.", source);
  sp.centroid_n_m = number_field(p, "centroid_n_m", "parameters.", source);
  t.site_calibration.emplace(local, grid, sp);
  return t;
}

TransformFile parse_transform_core(std::string_view text, std::string_view source, json& doc) {
  doc = parse_json_strict<json>(text, source);
  if (!doc.is_object()) fail(source, "(top level)", "expected a JSON object");
  for (const auto& [key, value] : doc.items()) {
    if (!kTopLevelKeys.count(key)) {
      fail(source, key, "unknown key; expected model, convention, rotation_model, source_frame, target_frame, "
                        "reference_epoch, parameters (see docs/transform-file.md)");
    }
  }
  TransformFile t;
  if (!doc.contains("model")) fail(source, "model", "missing; expected helmert7, helmert6, translation3 or helmert14");
  const std::string model = string_field(doc, "model", source);
  if (model == "helmert7") {
    t.model = TransformModel::helmert7;
  } else if (model == "helmert6") {
    t.model = TransformModel::helmert6;
  } else if (model == "translation3") {
    t.model = TransformModel::translation3;
  } else if (model == "helmert14") {
    t.model = TransformModel::helmert14;
  } else if (model == "molodensky-badekas") {
    t.model = TransformModel::molodensky_badekas;
  } else if (model == "enu-origin") {
    t.model = TransformModel::enu_origin;
    return parse_enu_origin(doc, std::move(t), source);
  } else if (model == "site-calibration") {
    t.model = TransformModel::site_calibration;
    return parse_site_calibration(doc, std::move(t), source);
  } else {
    fail(source, "model", "value \"" + model +
                              "\" not read by this command; expected helmert7, helmert6, translation3, helmert14, "
                              "molodensky-badekas, enu-origin or site-calibration");
  }

  bool position_vector = true;
  if (doc.contains("convention")) {
    const std::string c = string_field(doc, "convention", source);
    if (c == "position_vector") {
      position_vector = true;
    } else if (c == "coordinate_frame") {
      position_vector = false;
    } else {
      fail(source, "convention", "value \"" + c + "\" unknown; expected position_vector or coordinate_frame");
    }
  } else if (t.model != TransformModel::translation3) {
    fail(source, "convention",
         "missing; the sign of the rotations depends on it: expected position_vector (EPSG 1033/1053, IERS) or "
         "coordinate_frame (EPSG 1032/1056); it is never assumed");
  }

  if (doc.contains("rotation_model")) {
    const std::string r = string_field(doc, "rotation_model", source);
    if (r == "small_angle") {
      t.rotation_model = geodesy::RotationModel::small_angle;
    } else if (r == "exact") {
      t.rotation_model = geodesy::RotationModel::exact;
    } else {
      fail(source, "rotation_model", "value \"" + r + "\" unknown; expected small_angle or exact");
    }
  }

  for (const char* key : {"source_frame", "target_frame"}) {
    if (doc.contains(key)) {
      auto f = geodesy::Frame::parse(string_field(doc, key, source), std::string(source) + ": " + key);
      (std::string_view(key) == "source_frame" ? t.source_frame : t.target_frame) = std::move(f);
    }
  }

  if (doc.contains("reference_epoch")) {
    const json& v = doc.at("reference_epoch");
    if (!v.is_number()) fail(source, "reference_epoch", "value " + v.dump() + " is not a decimal year");
    t.reference_epoch = geodesy::parse_decimal_year(format_shortest(v.get<double>()),
                                                    std::string(source) + ": reference_epoch");
  } else if (t.model == TransformModel::helmert14) {
    fail(source, "reference_epoch", "missing; a 14-parameter transform needs the epoch its parameters refer to");
  }

  if (!doc.contains("parameters")) fail(source, "parameters", "missing");
  ParameterReader reader(doc.at("parameters"), source);
  const std::string_view model_name = to_string(t.model);
  std::array<double, 7> p{};
  for (std::size_t i = 0; i < 7; ++i) {
    const bool is_translation = i < 3, is_scale = i == 6;
    const bool required = t.model == TransformModel::helmert7 || t.model == TransformModel::helmert14 ||
                          t.model == TransformModel::molodensky_badekas ||
                          (t.model == TransformModel::helmert6 && !is_scale) ||
                          (t.model == TransformModel::translation3 && is_translation);
    if (required) {
      p[i] = reader.require(kSeven[i], false, model_name);
    } else {
      p[i] = reader.get(kSeven[i], false).value_or(0.0);  // a fixed parameter, zero unless stated
    }
  }
  if (t.model == TransformModel::helmert14) {
    std::array<double, 7> r{};
    for (std::size_t i = 0; i < 7; ++i) r[i] = reader.require(kSeven[i], true, model_name);
    if (position_vector) {
      t.helmert = geodesy::Helmert14<PositionVector>{seven_from<PositionVector>(p), rates_from<PositionVector>(r),
                                                     *t.reference_epoch};
    } else {
      t.helmert = geodesy::Helmert14<CoordinateFrame>{seven_from<CoordinateFrame>(p),
                                                      rates_from<CoordinateFrame>(r), *t.reference_epoch};
    }
  } else if (position_vector) {
    t.helmert = seven_from<PositionVector>(p);
  } else {
    t.helmert = seven_from<CoordinateFrame>(p);
  }
  if (t.model == TransformModel::molodensky_badekas) {
    t.pivot_m = Eigen::Vector3d(reader.require_plain("px_m", model_name), reader.require_plain("py_m", model_name),
                                reader.require_plain("pz_m", model_name));
  }
  reader.check_all_used(model_name);
  return t;
}

// What convert and apply use of a fit record: the uncertainty and extent.
std::optional<FitRecord> parse_fit_uncertainty(const json& doc, std::string_view source) {
  if (!doc.contains("sigmas")) return std::nullopt;
  FitRecord f;
  const json& sig = doc.at("sigmas");
  if (!sig.is_object()) fail(source, "sigmas", "expected an object of parameter -> sigma");
  for (const auto& [key, value] : sig.items()) {
    if (!value.is_number() || !std::isfinite(value.get<double>()) || value.get<double>() < 0.0) {
      fail(source, "sigmas." + key, "value " + value.dump() + " is not a sigma (a finite number >= 0)");
    }
    f.sigmas.emplace_back(key, value.get<double>());
  }
  if (doc.contains("correlation_parameters")) {
    const json& names = doc.at("correlation_parameters");
    const json& corr = doc.contains("correlation") ? doc.at("correlation") : json();
    if (!names.is_array() || !corr.is_array() || corr.size() != names.size()) {
      fail(source, "correlation", "expected a square matrix with one row per correlation_parameters entry");
    }
    for (const auto& n : names) f.correlation_names.push_back(n.get<std::string>());
    for (std::size_t i = 0; i < corr.size(); ++i) {
      if (!corr[i].is_array() || corr[i].size() != names.size()) {
        fail(source, "correlation[" + std::to_string(i) + "]", "expected " + std::to_string(names.size()) + " values");
      }
      std::vector<double> row;
      for (const auto& v : corr[i]) {
        if (!v.is_number() || !(std::abs(v.get<double>()) <= 1.0 + 1e-9)) {
          fail(source, "correlation[" + std::to_string(i) + "]", "value " + v.dump() + " is not a correlation in [-1, 1]");
        }
        row.push_back(v.get<double>());
      }
      f.correlation.push_back(row);
    }
  }
  if (doc.contains("statistics") && doc.at("statistics").is_object()) {
    const json& st = doc.at("statistics");
    if (st.contains("sigma0") && st.at("sigma0").is_number()) f.sigma0 = st.at("sigma0").get<double>();
    if (st.contains("dof") && st.at("dof").is_number_integer()) f.dof = st.at("dof").get<int>();
    if (st.contains("sigmas_scaled_by_sigma0") && st.at("sigmas_scaled_by_sigma0").is_boolean()) {
      f.sigmas_scaled_by_sigma0 = st.at("sigmas_scaled_by_sigma0").get<bool>();
    }
    // The significance levels the fit used (the workbench reopens with them).
    for (const auto& [key, target] : {std::pair<const char*, double*>{"alpha", &f.alpha}, {"alpha_point", &f.alpha_point}}) {
      if (!st.contains(key)) continue;
      const json& v = st.at(key);
      if (!v.is_number() || !(v.get<double>() > 0.0 && v.get<double>() < 1.0)) {
        fail(source, std::string("statistics.") + key, "value " + v.dump() + " is not a significance level in (0, 1)");
      }
      *target = v.get<double>();
    }
  }
  // Per point: which were used, removed or left out, and why.
  if (doc.contains("points") && doc.at("points").is_array()) {
    std::size_t i = 0;
    for (const auto& jp : doc.at("points")) {
      const std::string where = "points[" + std::to_string(i++) + "]";
      if (!jp.is_object() || !jp.contains("id") || !jp.at("id").is_string()) fail(source, where, "expected an object with a string id");
      FitPointRecord q;
      q.id = jp.at("id").get<std::string>();
      if (jp.contains("used") && jp.at("used").is_boolean()) q.used = jp.at("used").get<bool>();
      if (jp.contains("outlier") && jp.at("outlier").is_boolean()) q.outlier = jp.at("outlier").get<bool>();
      if (jp.contains("note") && jp.at("note").is_string()) q.note = jp.at("note").get<std::string>();
      f.points.push_back(q);
    }
  }
  if (doc.contains("control_extent")) {
    const json& e = doc.at("control_extent");
    const std::string where = "control_extent";
    if (!e.is_object() || !e.contains("centroid") || !e.contains("hull_en_m") || !e.at("hull_en_m").is_array()) {
      fail(source, where, "expected {\"centroid\": {lat_deg, lon_deg, h_m}, \"hull_en_m\": [[e, n], ...]}");
    }
    const json& c = e.at("centroid");
    ControlExtent x;
    x.centroid.point = geodesy::GeodeticPosition{Angle::degrees(number_field(c, "lat_deg", where + ".centroid.", source)),
                                                 Angle::degrees(number_field(c, "lon_deg", where + ".centroid.", source)),
                                                 geodesy::EllipsoidalHeight{number_field(c, "h_m", where + ".centroid.", source)}};
    for (const auto& v : e.at("hull_en_m")) {
      if (!v.is_array() || v.size() != 2 || !v[0].is_number() || !v[1].is_number()) {
        fail(source, where + ".hull_en_m", "value " + v.dump() + " is not [e, n] in metres");
      }
      x.hull_en_m.push_back({v[0].get<double>(), v[1].get<double>()});
    }
    if (x.hull_en_m.empty()) fail(source, where + ".hull_en_m", "empty");
    f.extent = x;
  }
  return f;
}

}  // namespace

TransformFile parse_transform_json(std::string_view text, std::string_view source) {
  json doc;
  TransformFile t = parse_transform_core(text, source, doc);
  t.fit = parse_fit_uncertainty(doc, source);
  return t;
}

TransformFile read_transform_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw Error(ErrorKind::io, "E_READ", path.string() + ": cannot open transform file: " + std::strerror(errno));
  }
  std::ostringstream text;
  text << in.rdbuf();
  return parse_transform_json(text.str(), path.string());
}

namespace {

// The seven (or fourteen) parameters of a Helmert alternative, canonical keys.
template <class H>
json parameters_json(const H& h) {
  json params = json::object();
  auto put7 = [&](const auto& p) {
    params["tx_m"] = number(p.t_m.x());
    params["ty_m"] = number(p.t_m.y());
    params["tz_m"] = number(p.t_m.z());
    params["rx_arcsec"] = number(p.rx.arcsec());
    params["ry_arcsec"] = number(p.ry.arcsec());
    params["rz_arcsec"] = number(p.rz.arcsec());
    params["ds_ppm"] = number(p.ds.ppm());
  };
  if constexpr (std::is_same_v<H, geodesy::Helmert14<PositionVector>> ||
                std::is_same_v<H, geodesy::Helmert14<CoordinateFrame>>) {
    put7(h.at_reference_epoch);
    params["dtx_m_per_year"] = number(h.rates.dt_m_per_year.x());
    params["dty_m_per_year"] = number(h.rates.dt_m_per_year.y());
    params["dtz_m_per_year"] = number(h.rates.dt_m_per_year.z());
    params["drx_arcsec_per_year"] = number(h.rates.drx_per_year.arcsec());
    params["dry_arcsec_per_year"] = number(h.rates.dry_per_year.arcsec());
    params["drz_arcsec_per_year"] = number(h.rates.drz_per_year.arcsec());
    params["dds_ppm_per_year"] = number(h.rates.dds_per_year.ppm());
  } else {
    put7(h);
  }
  return params;
}

// The same transform in the other rotation convention.
TransformFile swapped_convention(const TransformFile& t) {
  TransformFile out = t;
  out.fit.reset();
  std::visit([&](const auto& h) {
    using H = std::decay_t<decltype(h)>;
    if constexpr (std::is_same_v<H, geodesy::Helmert7<PositionVector>> || std::is_same_v<H, geodesy::Helmert14<PositionVector>>) {
      out.helmert = geodesy::to_coordinate_frame(h);
    } else {
      out.helmert = geodesy::to_position_vector(h);
    }
  }, t.helmert);
  return out;
}

json json_number_or_null(double v) { return std::isfinite(v) ? number(v) : json(nullptr); }

}  // namespace

std::string epsg_method(const TransformFile& t) {
  if (t.enu_origin || t.site_calibration) return "";
  const bool pv = t.convention_name() == PositionVector::name;
  if (t.model == TransformModel::translation3) return "EPSG:1031";
  if (t.model == TransformModel::molodensky_badekas) return pv ? "EPSG:1061" : "EPSG:1034";
  if (t.time_dependent()) return pv ? "EPSG:1053" : "EPSG:1056";
  return pv ? "EPSG:1033" : "EPSG:1032";
}

namespace {
std::string topocentric(const geodesy::LocalOrigin& o) {
  const std::string ell = o.ellipsoid == geodesy::Ellipsoid::grs80() ? "+ellps=GRS80"
                          : o.ellipsoid == geodesy::Ellipsoid::wgs84() ? "+ellps=WGS84"
                                                                       : "+a=" + format_shortest(o.ellipsoid.a_m()) + " +rf=" + format_shortest(o.ellipsoid.rf());
  return "+proj=topocentric " + ell + " +lat_0=" + format_shortest(o.point.lat.deg()) + " +lon_0=" + format_shortest(o.point.lon.deg()) +
         " +h_0=" + format_shortest(o.point.h.m);
}
}  // namespace

std::string proj_pipeline(const TransformFile& t) {
  if (t.site_calibration) {
    // ECEF -> grid E, N and h is one affine map (local ENU, then the
    // similarity and the plane), composed once; then inverse TM and cart.
    // (PROJ refuses topocentric's cartesian output flowing into tmerc.)
    const auto& sc = *t.site_calibration;
    const auto& p = sc.params();
    const double k = 1.0 + p.scale.unitless(), a = k * std::cos(p.rotation.rad()), b = k * std::sin(p.rotation.rad());
    Eigen::Matrix3d l;
    l << a, -b, 0.0, b, a, 0.0, p.slope_e, p.slope_n, 1.0;
    const geodesy::AffineMap local_to_grid(
        l, Eigen::Vector3d(p.shift_e_m, p.shift_n_m, p.vertical_shift_m - p.slope_n * p.centroid_n_m - p.slope_e * p.centroid_e_m));
    const geodesy::AffineMap m =
        geodesy::compose(local_to_grid, geodesy::LocalTangentPlane(sc.local_origin()).enu_from_ecef_map());
    const auto& g = sc.grid();
    const std::string ell = g.ellipsoid == geodesy::Ellipsoid::grs80() ? "+ellps=GRS80"
                            : g.ellipsoid == geodesy::Ellipsoid::wgs84() ? "+ellps=WGS84"
                                                                         : "+a=" + format_shortest(g.ellipsoid.a_m()) + " +rf=" + format_shortest(g.ellipsoid.rf());
    std::string out = "+proj=pipeline +step +proj=affine";
    const char* off[3] = {"xoff", "yoff", "zoff"};
    for (int r = 0; r < 3; ++r) out += std::string(" +") + off[r] + "=" + format_shortest(m.translation_m()(r));
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) out += " +s" + std::to_string(r + 1) + std::to_string(c + 1) + "=" + format_shortest(m.linear()(r, c));
    }
    return out + " +step +inv +proj=tmerc " + ell + " +lat_0=" + format_shortest(g.tm.lat0.deg()) + " +lon_0=" + format_shortest(g.tm.lon0.deg()) +
           " +k=" + format_shortest(g.tm.k0) + " +x_0=" + format_shortest(g.tm.false_easting_m) + " +y_0=" + format_shortest(g.tm.false_northing_m) +
           " +step +proj=cart " + ell;
  }
  if (t.enu_origin) {
    // ECEF -> map ENU at the nominal origin -> turn and scale -> ECEF from the corrected origin.
    const auto& c = *t.enu_origin;
    const double k = 1.0 + c.ds.unitless(), cy = std::cos(c.yaw.rad()), sy = std::sin(c.yaw.rad());
    return "+proj=pipeline +step " + topocentric(c.nominal) + " +step +proj=affine +s11=" + format_shortest(k * cy) + " +s12=" +
           format_shortest(-k * sy) + " +s13=0 +s21=" + format_shortest(k * sy) + " +s22=" + format_shortest(k * cy) + " +s23=0 +s31=0 +s32=0 +s33=" +
           format_shortest(k) + " +step +inv " + topocentric(geodesy::corrected_origin(c.nominal, c.shift_enu_m));
  }
  if (t.pivot_m && t.rotation_model == geodesy::RotationModel::exact) {
    // PROJ's molobadekas has no exact form: write the geocentric equivalent.
    TransformFile g = t;
    const geodesy::AffineMap m = t.target_from_source(std::nullopt, "");
    std::visit([&](auto& h) {
      using H = std::decay_t<decltype(h)>;
      if constexpr (std::is_same_v<H, geodesy::Helmert7<PositionVector>> ||
                    std::is_same_v<H, geodesy::Helmert7<CoordinateFrame>>) {
        h.t_m = m.translation_m();
      }
    }, g.helmert);
    g.pivot_m.reset();
    g.model = TransformModel::helmert7;
    return proj_pipeline(g);
  }
  std::string out = t.pivot_m ? "+proj=pipeline +step +proj=molobadekas" : "+proj=pipeline +step +proj=helmert";
  auto add = [&](const char* key, double v) { out += std::string(" +") + key + "=" + format_shortest(v); };
  auto add7 = [&](const auto& p) {
    add("x", p.t_m.x());
    add("y", p.t_m.y());
    add("z", p.t_m.z());
    add("rx", p.rx.arcsec());
    add("ry", p.ry.arcsec());
    add("rz", p.rz.arcsec());
    add("s", p.ds.ppm());
  };
  std::visit([&](const auto& h) {
    using H = std::decay_t<decltype(h)>;
    if constexpr (std::is_same_v<H, geodesy::Helmert14<PositionVector>> ||
                  std::is_same_v<H, geodesy::Helmert14<CoordinateFrame>>) {
      add7(h.at_reference_epoch);
      add("dx", h.rates.dt_m_per_year.x());
      add("dy", h.rates.dt_m_per_year.y());
      add("dz", h.rates.dt_m_per_year.z());
      add("drx", h.rates.drx_per_year.arcsec());
      add("dry", h.rates.dry_per_year.arcsec());
      add("drz", h.rates.drz_per_year.arcsec());
      add("ds", h.rates.dds_per_year.ppm());
      add("t_epoch", h.reference_epoch.year);
    } else {
      add7(h);
    }
  }, t.helmert);
  if (t.pivot_m) {
    add("px", t.pivot_m->x());
    add("py", t.pivot_m->y());
    add("pz", t.pivot_m->z());
  }
  out += " +convention=" + std::string(t.convention_name());
  if (t.rotation_model == geodesy::RotationModel::exact) out += " +exact";
  return out;
}

std::string to_json_text(const TransformFile& t) {
  json doc;
  doc["format_version"] = 1;
  doc["model"] = std::string(to_string(t.model));
  if (!t.enu_origin && !t.site_calibration) {
    doc["convention"] = std::string(t.convention_name());
    doc["rotation_model"] = std::string(geodesy::to_string(t.rotation_model));
    doc["epsg_method"] = epsg_method(t);
  }
  if (t.source_frame) doc["source_frame"] = t.source_frame->to_string();
  if (t.target_frame) doc["target_frame"] = t.target_frame->to_string();
  if (t.reference_epoch) doc["reference_epoch"] = number(t.reference_epoch->year);
  auto with_pivot = [&](json params) {
    if (t.pivot_m) {
      params["px_m"] = number(t.pivot_m->x());
      params["py_m"] = number(t.pivot_m->y());
      params["pz_m"] = number(t.pivot_m->z());
    }
    return params;
  };
  if (t.site_calibration) {
    const auto& sc = *t.site_calibration;
    const auto& o = sc.local_origin();
    const auto& p = sc.params();
    const auto& g = sc.grid();
    doc["nominal_origin"] = {{"lat_deg", number(o.point.lat.deg())}, {"lon_deg", number(o.point.lon.deg())},
                             {"h_m", number(o.point.h.m)}, {"height_type", "ellipsoidal"}, {"ellipsoid", o.ellipsoid.name()}};
    doc["grid"] = {{"lat0_deg", number(g.tm.lat0.deg())}, {"lon0_deg", number(g.tm.lon0.deg())}, {"k0", number(g.tm.k0)},
                   {"false_easting_m", number(g.tm.false_easting_m)}, {"false_northing_m", number(g.tm.false_northing_m)}};
    doc["parameters"] = {{"shift_e_m", number(p.shift_e_m)},           {"shift_n_m", number(p.shift_n_m)},
                         {"rotation_arcsec", number(p.rotation.arcsec())}, {"scale_ppm", number(p.scale.ppm())},
                         {"vertical_shift_m", number(p.vertical_shift_m)}, {"slope_n_ppm", number(p.slope_n * 1e6)},
                         {"slope_e_ppm", number(p.slope_e * 1e6)},     {"centroid_e_m", number(p.centroid_e_m)},
                         {"centroid_n_m", number(p.centroid_n_m)}};
  } else if (t.enu_origin) {
    const auto& c = *t.enu_origin;
    const geodesy::LocalOrigin corrected = geodesy::corrected_origin(c.nominal, c.shift_enu_m);
    doc["nominal_origin"] = {{"lat_deg", number(c.nominal.point.lat.deg())}, {"lon_deg", number(c.nominal.point.lon.deg())},
                             {"h_m", number(c.nominal.point.h.m)}, {"height_type", "ellipsoidal"},
                             {"ellipsoid", c.nominal.ellipsoid.name()}};
    doc["parameters"] = {{"shift_e_m", number(c.shift_enu_m.x())}, {"shift_n_m", number(c.shift_enu_m.y())},
                         {"shift_u_m", number(c.shift_enu_m.z())}, {"yaw_arcsec", number(c.yaw.arcsec())},
                         {"ds_ppm", number(c.ds.ppm())},           {"origin_lat_deg", number(corrected.point.lat.deg())},
                         {"origin_lon_deg", number(corrected.point.lon.deg())}, {"origin_h_m", number(corrected.point.h.m)}};
  } else {
    doc["parameters"] = with_pivot(std::visit([](const auto& h) { return parameters_json(h); }, t.helmert));
  }
  doc["proj_pipeline"] = proj_pipeline(t);
  if (t.fit) {
    if (const auto wkt = to_wkt2(t)) doc["wkt2"] = *wkt;
    if (const auto pj = to_projjson(t)) doc["projjson"] = json::parse(*pj);
  }
  if (t.fit) {
    const FitRecord& f = *t.fit;
    if (!f.generator.empty()) doc["generator"] = f.generator;
    json sig = json::object();
    for (const auto& [name, value] : f.sigmas) sig[name] = number(value);
    doc["sigmas"] = sig;
    json corr = json::array();
    for (const auto& row : f.correlation) {
      json r = json::array();
      for (double v : row) r.push_back(number(v));
      corr.push_back(r);
    }
    doc["correlation"] = corr;  // rows and columns in the order of correlation_parameters
    doc["correlation_parameters"] = f.correlation_names;
    if (f.extent) {
      json hull = json::array();
      for (const auto& v : f.extent->hull_en_m) hull.push_back({number(v[0]), number(v[1])});
      doc["control_extent"] = {{"centroid",
                                {{"lat_deg", number(f.extent->centroid.point.lat.deg())},
                                 {"lon_deg", number(f.extent->centroid.point.lon.deg())},
                                 {"h_m", number(f.extent->centroid.point.h.m)},
                                 {"ellipsoid", "WGS84"}}},
                               {"hull_en_m", hull}};
    }
    doc["statistics"] = {
        {"sigma0", number(f.sigma0)},
        {"dof", f.dof},
        {"sigmas_scaled_by_sigma0", f.sigmas_scaled_by_sigma0},
        {"alpha", number(f.alpha)},
        {"alpha_point", number(f.alpha_point)},
        {"global_test",
         {{"statistic", number(f.global_statistic)},
          {"critical", number(f.global_critical_upper)},
          {"critical_lower", number(f.global_critical_lower)},
          {"passed", f.global_applicable ? json(f.global_passed) : json(nullptr)},
          {"applicable", f.global_applicable}}},
        {"warnings", f.warnings}};
    if (f.variance_factors) {
      doc["statistics"]["variance_factors"] = {{"source", number(f.variance_factors->first)},
                                               {"target", number(f.variance_factors->second)}};
    }
    json pts = json::array();
    for (const auto& p : f.points) {
      json jp = {{"id", p.id},
                 {"residual_enu_m", {number(p.residual_enu_m[0]), number(p.residual_enu_m[1]), number(p.residual_enu_m[2])}},
                 {"w_test", number(p.w_test)},
                 {"w_enu", {number(p.w_enu[0]), number(p.w_enu[1]), number(p.w_enu[2])}},
                 {"redundancy_enu", {number(p.redundancy_enu[0]), number(p.redundancy_enu[1]), number(p.redundancy_enu[2])}},
                 {"mdb_m", json_number_or_null(p.mdb_m)},
                 {"point_test", {{"statistic", number(p.point_test)}, {"dof", p.point_test_dof}, {"p_value", number(p.point_test_p)}}},
                 {"outlier", p.outlier},
                 {"used", p.used}};
      if (!p.note.empty()) jp["note"] = p.note;
      if (p.robust_weight < 1.0) jp["robust_weight"] = number(p.robust_weight);
      pts.push_back(jp);
    }
    doc["points"] = pts;
  }
  if (t.fit && !t.enu_origin && !t.site_calibration) {
    TransformFile other = swapped_convention(t);
    other.fit = t.fit;  // for the exports below
    doc["alternatives"] = json::array({json{{"convention", std::string(other.convention_name())},
                                            {"epsg_method", epsg_method(other)},
                                            {"parameters", with_pivot(std::visit([](const auto& h) { return parameters_json(h); }, other.helmert))},
                                            {"proj_pipeline", proj_pipeline(other)}}});
    if (const auto wkt = to_wkt2(other)) doc["alternatives"][0]["wkt2"] = *wkt;
    if (const auto pj = to_projjson(other)) doc["alternatives"][0]["projjson"] = json::parse(*pj);
  }
  return doc.dump(2) + "\n";
}

}  // namespace geoanchor::io
