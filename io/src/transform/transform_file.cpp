#include "geoanchor/io/transform/transform_file.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <thread>
#include <tuple>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/geodesy/physical_range.hpp"
#include "geoanchor/io/json_input.hpp"

namespace geoanchor::io {
namespace {

using geodesy::Angle;
using geodesy::CoordinateFrame;
using geodesy::PositionVector;
using geodesy::ScaleDifference;
using nlohmann::json;

// Top-level keys. What a model reads (model_keys below), what `geoanchor fit`
// adds about the fit (read into FitRecord), and what it adds that describes
// the same transform again (checked against it, never applied).
const std::set<std::string> kTopLevelKeys = {
    "model",       "convention", "rotation_model", "source_frame", "target_frame", "reference_epoch",
    "parameters",  "sigmas",     "correlation",    "statistics",   "points",       "proj_pipeline",
    "epsg_method", "generator",  "format_version", "description",  "alternatives", "nominal_origin",
    "wkt2",        "projjson",   "grid",          "correlation_parameters", "control_extent", "control_crs", "metadata", "gnss_solutions"};

[[noreturn]] void fail(std::string_view source, const std::string& key, const std::string& what) {
  throw Error(ErrorKind::input, "E_TRANSFORM", std::string(source) + ": " + key + ": " + what);
}

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
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

std::string spec_key(const ParamSpec& p, bool rate, bool unit_b) {
  return (rate ? std::string("d") : std::string()) + p.name + "_" + (unit_b ? p.unit_b : p.unit_a) + (rate ? "_per_year" : "");
}

// A parameter a fit estimates, as the file states it: the canonical key
// (what to_json_text writes and FitRecord holds), the key the file's
// `parameters` uses, and the factor from that key's unit to the canonical one.
struct Estimated {
  std::string canonical;
  std::string key;
  double to_canonical = 1.0;
  std::string other_key;  // the same parameter in its other unit ("" if none)
};

// What a sigma may be given for: the model's estimated parameters, and why
// each other parameter key has none.
struct ModelParameters {
  std::vector<Estimated> estimated;
  std::map<std::string, std::string> no_sigma;  // key -> why it has no sigma
};

class ParameterReader {
 public:
  // Misspelt keys are reported first, by name, before any missing parameter.
  ParameterReader(const json& params, std::string_view source) : params_(params), source_(source) {
    if (!params_.is_object()) fail(source_, "parameters", "expected an object of unit-named numbers");
    std::set<std::string> known;
    for (const auto& p : kSeven) {
      for (const bool b : {false, true}) {
        known.insert(spec_key(p, false, b));
        known.insert(spec_key(p, true, b));
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

  // The value in canonical units, or nullopt if absent; `used` receives the
  // key the file spells it with and that key's factor to the canonical unit.
  std::optional<double> get(const ParamSpec& p, bool rate, Estimated* used = nullptr) {
    const std::string key_a = spec_key(p, rate, false), key_b = spec_key(p, rate, true);
    const bool has_a = params_.contains(key_a), has_b = params_.contains(key_b);
    if (has_a && has_b) fail(source_, "parameters." + key_a, "given twice, also as " + key_b + "; keep one");
    if (!has_a && !has_b) return std::nullopt;
    const std::string& key = has_a ? key_a : key_b;
    used_.insert(key);
    const json& v = params_.at(key);
    if (!v.is_number()) fail(source_, "parameters." + key, "value " + v.dump() + " is not a number");
    const double factor = has_a ? p.factor_a : p.factor_b;
    if (used) *used = Estimated{key_a, key, factor, has_a ? key_b : key_a};
    return v.get<double>() * factor;
  }

  // A parameter with a single unit (the Molodensky-Badekas pivot).
  double require_plain(const std::string& key, std::string_view model) {
    if (!params_.contains(key)) fail(source_, "parameters", "missing " + key + " for model " + std::string(model));
    used_.insert(key);
    const json& v = params_.at(key);
    if (!v.is_number()) fail(source_, "parameters." + key, "value " + v.dump() + " is not a number");
    return v.get<double>();
  }

  double require(const ParamSpec& p, bool rate, std::string_view model, Estimated* used = nullptr) {
    const auto v = get(p, rate, used);
    if (!v) {
      fail(source_, "parameters", "missing " + spec_key(p, rate, false) + " (or " + spec_key(p, rate, true) +
                                      ") for model " + std::string(model));
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

// Defined with the writer below.
template <class H>
json parameters_json(const H& h);
TransformFile without_fit_record(const TransformFile& t);
TransformFile swapped_convention(const TransformFile& t);

}  // namespace

namespace {

// Typed access; every message names the file and the key's JSON path.
const json* member(const json& obj, const std::string& key) {
  const auto it = obj.find(key);
  return it == obj.end() ? nullptr : &*it;
}

double number_at(const json& v, const std::string& path, std::string_view source) {
  if (!v.is_number()) fail(source, path, "value " + v.dump() + " is not a number");
  return v.get<double>();
}

double number_field(const json& obj, const std::string& key, const std::string& where, std::string_view source) {
  if (!obj.contains(key)) fail(source, where + key, "missing");
  return number_at(obj.at(key), where + key, source);
}

std::string string_at(const json& v, const std::string& path, std::string_view source) {
  if (!v.is_string()) fail(source, path, "value " + v.dump() + " is not a string");
  return v.get<std::string>();
}

bool bool_at(const json& v, const std::string& path, std::string_view source) {
  if (!v.is_boolean()) fail(source, path, "value " + v.dump() + " is not true or false");
  return v.get<bool>();
}

int count_at(const json& v, const std::string& path, std::string_view source) {
  if (!v.is_number_integer() || v.get<long long>() < 0 || v.get<long long>() > 2147483647LL) {
    fail(source, path, "value " + v.dump() + " is not a count (an integer >= 0)");
  }
  return static_cast<int>(v.get<long long>());
}

// Every key of `obj` must be one of `known`.
void only_keys(const json& obj, const std::string& where, std::string_view source, const std::vector<std::string>& known) {
  if (!obj.is_object()) fail(source, where, "value " + obj.dump() + " is not an object; expected the keys " + joined(known));
  for (const auto& [key, value] : obj.items()) {
    if (std::find(known.begin(), known.end(), key) == known.end()) {
      fail(source, where + "." + key, "unknown key; expected " + joined(known));
    }
  }
}

// A statistic that may be undefined: null (what the writer gives a NaN,
// e.g. the w-test of an axis without redundancy) is read back as NaN.
double number_or_null_at(const json& v, const std::string& path, std::string_view source) {
  return v.is_null() ? std::numeric_limits<double>::quiet_NaN() : number_at(v, path, source);
}

std::array<double, 3> triple_at(const json& v, const std::string& path, std::string_view source, bool null_is_nan = false) {
  if (!v.is_array() || v.size() != 3) fail(source, path, "value " + v.dump() + " is not [e, n, u]");
  std::array<double, 3> out{};
  for (std::size_t k = 0; k < 3; ++k) {
    const std::string at = path + "[" + std::to_string(k) + "]";
    out[k] = null_is_nan ? number_or_null_at(v[k], at, source) : number_at(v[k], at, source);
  }
  return out;
}

geodesy::Ellipsoid ellipsoid_at(const json& v, const std::string& path, std::string_view source) {
  const std::string name = string_at(v, path, source);
  if (name == "WGS84") return geodesy::Ellipsoid::wgs84();
  if (name == "GRS80") return geodesy::Ellipsoid::grs80();
  fail(source, path, "value \"" + name + "\" unknown; expected WGS84 or GRS80");
}

constexpr double kCorrectedOriginTol_m = 0.001;
constexpr double kGridCopyTol_deg = 1e-9;  // the same number written twice; 1e-9° is 0.1 mm
// Correlations: geoanchor writes them at full precision, so a symmetric
// matrix is symmetric to the last bit and its diagonal is 1 within rounding;
// 1e-9 also accepts a matrix typed in with nine or more digits.
constexpr double kCorrelationTol = 1e-9;
// The smallest eigenvalue of a correlation matrix may be this far below 0:
// rounding a correlation matrix to seven significant digits moves its
// eigenvalues by less than 14 × 5e-8 = 7e-7 (14 parameters at most); a typo
// or a wrong sign moves them by ~1e-2 or more.
constexpr double kCorrelationPsdTol = 1e-6;
// alternatives[i].parameters are written as the exact negation of the
// rotations at full precision; 1e-9 (m, ″, ppm) allows a re-spelling in mm,
// mas or ppb.
constexpr double kAlternativeTol = 1e-9;

geodesy::LocalOrigin origin_of(const json& doc, std::string_view model, std::string_view source) {
  const json* no = member(doc, "nominal_origin");
  if (!no) {
    fail(source, "nominal_origin",
         "missing; model " + std::string(model) +
             " needs {\"lat_deg\", \"lon_deg\", \"h_m\", \"height_type\": \"ellipsoidal\", \"ellipsoid\"}");
  }
  only_keys(*no, "nominal_origin", source, {"lat_deg", "lon_deg", "h_m", "height_type", "ellipsoid"});
  geodesy::Ellipsoid e = geodesy::Ellipsoid::wgs84();
  if (const json* el = member(*no, "ellipsoid")) e = ellipsoid_at(*el, "nominal_origin.ellipsoid", source);
  // An origin's h_m is an ellipsoidal height: the only type there is to state.
  if (const json* ht = member(*no, "height_type")) {
    const std::string v = string_at(*ht, "nominal_origin.height_type", source);
    if (v != "ellipsoidal") {
      fail(source, "nominal_origin.height_type",
           "value \"" + v + "\" not read: an origin's h_m is an ellipsoidal height (orthometric origins are not "
                            "supported); expected \"ellipsoidal\"");
    }
  }
  const double lat = number_field(*no, "lat_deg", "nominal_origin.", source);
  const double lon = number_field(*no, "lon_deg", "nominal_origin.", source);
  if (std::fabs(lat) > 90.0) fail(source, "nominal_origin.lat_deg", "latitude " + format_shortest(lat) + " not in [-90, 90]");
  if (std::fabs(lon) > 180.0) fail(source, "nominal_origin.lon_deg", "longitude " + format_shortest(lon) + " not in [-180, 180]");
  const double h = number_field(*no, "h_m", "nominal_origin.", source);
  if (!geodesy::is_physical_height(h)) {
    fail(source, "nominal_origin.h_m", "ellipsoidal height " + format_shortest(h) + " m is not a height on the Earth: expected " +
                                           geodesy::physical_height_range_text());
  }
  return {{Angle::degrees(lat), Angle::degrees(lon), geodesy::EllipsoidalHeight{h}}, e};
}

void frames_of(const json& doc, TransformFile& t, std::string_view source) {
  for (const char* key : {"source_frame", "target_frame"}) {
    if (doc.contains(key)) {
      auto f = geodesy::Frame::parse(string_field(doc, key, source), std::string(source) + ": " + key);
      (std::string_view(key) == "source_frame" ? t.source_frame : t.target_frame) = std::move(f);
    }
  }
  // A transform of fixed parameters between a dynamic frame and another
  // holds at one epoch: a dynamic frame without it would be applied at
  // whatever epoch a tile has (ETRF2000@2020.0 out of a file fitted at
  // 2024.5). fit never writes one (issue 40 point 9); a 14-parameter
  // transform carries its own epochs.
  if (t.model == TransformModel::helmert14) return;
  for (const char* key : {"source_frame", "target_frame"}) {
    const auto& f = std::string_view(key) == "source_frame" ? t.source_frame : t.target_frame;
    if (f && geodesy::is_dynamic(*f) && !f->epoch()) {
      fail(source, key,
           "frame " + f->name() + " is dynamic (its coordinates change by centimetres a year) and names no epoch; a " +
               std::string(to_string(t.model)) + " transform of fixed parameters holds at one epoch: write " + f->name() +
               "@YYYY.Y, the epoch of the coordinates it was fitted to (fit writes it)");
    }
  }
}

// Keys that only some models read: refused by name where they would be ignored.
void check_model_keys(const json& doc, TransformModel m, std::string_view source) {
  const std::string name(to_string(m));
  const bool helmert = m != TransformModel::enu_origin && m != TransformModel::site_calibration;
  if (!helmert) {
    const std::pair<const char*, const char*> not_read[] = {
        {"convention", "its rotation is defined by the model's formula (docs/transform-file.md), not by a convention"},
        {"rotation_model", "its rotation is always exact"},
        {"reference_epoch", "it is not time-dependent"}};
    for (const auto& [key, why] : not_read) {
      if (doc.contains(key)) fail(source, key, "not read for model " + name + ": " + why + "; remove it");
    }
  }
  if (helmert && doc.contains("nominal_origin")) {
    fail(source, "nominal_origin", "not read for model " + name + ": only enu-origin and site-calibration have a nominal origin; remove it");
  }
  if (m != TransformModel::site_calibration && doc.contains("grid")) {
    fail(source, "grid", "not read for model " + name + ": only site-calibration has a grid; remove it");
  }
}

TransformFile parse_enu_origin(const json& doc, TransformFile t, ModelParameters& mp, std::string_view source) {
  frames_of(doc, t, source);
  EnuOriginCorrection c;
  c.nominal = origin_of(doc, "enu-origin", source);
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
  for (const char* key : {"shift_e_m", "shift_n_m", "shift_u_m", "yaw_arcsec", "ds_ppm"}) {
    if (p.contains(key)) {
      mp.estimated.push_back(Estimated{key, key, 1.0, ""});
    } else {
      mp.no_sigma[key] = std::string("parameters states no ") + key + ", so it is held at 0 (not estimated)";
    }
  }
  for (const char* key : {"origin_lat_deg", "origin_lon_deg", "origin_h_m"}) {
    mp.no_sigma[key] = std::string(key) +
                       " is derived from nominal_origin and the shift, not estimated: its uncertainty is that of "
                       "shift_e_m, shift_n_m and shift_u_m";
  }
  // The corrected origin is derived; if given, it must agree with the shift.
  if (p.contains("origin_lat_deg") || p.contains("origin_lon_deg") || p.contains("origin_h_m")) {
    const geodesy::LocalOrigin derived = geodesy::corrected_origin(c.nominal, c.shift_enu_m);
    const geodesy::GeodeticPosition stated{Angle::degrees(number_field(p, "origin_lat_deg", "parameters.", source)),
                                           Angle::degrees(number_field(p, "origin_lon_deg", "parameters.", source)),
                                           geodesy::EllipsoidalHeight{number_field(p, "origin_h_m", "parameters.", source)}};
    const double d = (geodesy::ecef_from_geodetic(e, stated).m - geodesy::ecef_from_geodetic(e, derived.point).m).norm();
    if (!(d <= kCorrectedOriginTol_m)) {
      fail(source, "parameters.origin_lat_deg", "the corrected origin is " + format_shortest(d) +
                                                    " m from nominal_origin + shift; expected them to agree within 1 mm");
    }
  }
  t.enu_origin = c;
  t.rotation_model = geodesy::RotationModel::exact;
  return t;
}

TransformFile parse_site_calibration(const json& doc, TransformFile t, ModelParameters& mp, std::string_view source) {
  frames_of(doc, t, source);
  const geodesy::LocalOrigin local = origin_of(doc, "site-calibration", source);
  if (!doc.contains("grid")) {
    fail(source, "grid", "missing; expected {\"lat0_deg\", \"lon0_deg\", \"k0\", \"false_easting_m\", \"false_northing_m\"}");
  }
  const json& g = doc.at("grid");
  only_keys(g, "grid", source, {"lat0_deg", "lon0_deg", "k0", "false_easting_m", "false_northing_m", "ellipsoid"});
  geodesy::ProjectionDef grid;
  grid.ellipsoid = local.ellipsoid;
  // The grid is on the origin's ellipsoid (fit puts both on --ellipsoid); a
  // file that names another one for the grid would not be applied as it says.
  if (const json* ge = member(g, "ellipsoid")) {
    const geodesy::Ellipsoid named = ellipsoid_at(*ge, "grid.ellipsoid", source);
    if (!(named == local.ellipsoid)) {
      fail(source, "grid.ellipsoid",
           "value \"" + named.name() + "\" differs from nominal_origin.ellipsoid " + local.ellipsoid.name() +
               " (WGS84 when not given); the grid is applied on the origin's ellipsoid: state the same one in both");
    }
  }
  grid.tm.lat0 = Angle::degrees(number_field(g, "lat0_deg", "grid.", source));
  grid.tm.lon0 = Angle::degrees(number_field(g, "lon0_deg", "grid.", source));
  grid.tm.k0 = number_field(g, "k0", "grid.", source);
  grid.tm.false_easting_m = g.contains("false_easting_m") ? number_field(g, "false_easting_m", "grid.", source) : 0.0;
  grid.tm.false_northing_m = g.contains("false_northing_m") ? number_field(g, "false_northing_m", "grid.", source) : 0.0;
  if (!(grid.tm.k0 > 0.0 && grid.tm.k0 < 2.0)) fail(source, "grid.k0", "not in (0, 2)");
  if (!doc.contains("parameters") || !doc.at("parameters").is_object()) fail(source, "parameters", "missing");
  const json& p = doc.at("parameters");
  const std::vector<std::string> estimated = {"shift_e_m",        "shift_n_m",   "rotation_arcsec", "scale_ppm",
                                              "vertical_shift_m", "slope_n_ppm", "slope_e_ppm"};
  std::vector<std::string> known = estimated;
  for (const char* k : {"centroid_e_m", "centroid_n_m", "grid_lat0_deg", "grid_lon0_deg"}) known.emplace_back(k);
  for (const auto& [key, value] : p.items()) {
    if (std::find(known.begin(), known.end(), key) == known.end()) {
      fail(source, "parameters." + key, "unknown parameter for site-calibration; expected " + joined(known));
    }
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
  // The grid's origin repeated among the parameters (as the fit reports it):
  // read, and held to the grid's.
  for (const auto& [key, grid_key, value] : {std::tuple<const char*, const char*, double>{"grid_lat0_deg", "lat0_deg", grid.tm.lat0.deg()},
                                            {"grid_lon0_deg", "lon0_deg", grid.tm.lon0.deg()}}) {
    if (!p.contains(key)) continue;
    const double stated = number_field(p, key, "parameters.", source);
    if (!(std::fabs(stated - value) <= kGridCopyTol_deg)) {
      fail(source, std::string("parameters.") + key,
           "value " + format_shortest(stated) + " differs from grid." + grid_key + " " + format_shortest(value) +
               "; the grid's origin is stated twice, differently: correct one");
    }
  }
  for (const auto& key : estimated) mp.estimated.push_back(Estimated{key, key, 1.0, ""});
  for (const char* key : {"centroid_e_m", "centroid_n_m"}) {
    mp.no_sigma[key] = std::string(key) + " is the point the slopes refer to (the control's centroid), not estimated";
  }
  for (const char* key : {"grid_lat0_deg", "grid_lon0_deg"}) {
    mp.no_sigma[key] = std::string(key) + " is the grid's origin, a given, not estimated";
  }
  t.site_calibration.emplace(local, grid, sp);
  return t;
}

TransformFile parse_transform_doc(const json& doc, std::string_view source, ModelParameters& mp) {
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
  } else if (model == "site-calibration") {
    t.model = TransformModel::site_calibration;
  } else {
    fail(source, "model", "value \"" + model +
                              "\" not read by this command; expected helmert7, helmert6, translation3, helmert14, "
                              "molodensky-badekas, enu-origin or site-calibration");
  }
  check_model_keys(doc, t.model, source);
  if (t.model == TransformModel::enu_origin) return parse_enu_origin(doc, std::move(t), mp, source);
  if (t.model == TransformModel::site_calibration) return parse_site_calibration(doc, std::move(t), mp, source);

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

  frames_of(doc, t, source);

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
    // The parameters the model estimates (and which may have a sigma); the
    // others are held fixed, at 0 unless stated.
    const bool estimated = t.model == TransformModel::helmert7 || t.model == TransformModel::helmert14 ||
                           t.model == TransformModel::molodensky_badekas ||
                           (t.model == TransformModel::helmert6 && !is_scale) ||
                           (t.model == TransformModel::translation3 && is_translation);
    if (estimated) {
      Estimated e;
      p[i] = reader.require(kSeven[i], false, model_name, &e);
      mp.estimated.push_back(e);
    } else {
      p[i] = reader.get(kSeven[i], false).value_or(0.0);
      for (const bool b : {false, true}) {
        mp.no_sigma[spec_key(kSeven[i], false, b)] =
            "model " + std::string(model_name) + " holds " + kSeven[i].name + " fixed (not estimated), so it has no sigma";
      }
    }
  }
  if (!doc.contains("convention") && (p[3] != 0.0 || p[4] != 0.0 || p[5] != 0.0)) {
    fail(source, "convention",
         "missing; parameters states a rotation, whose sign depends on it: expected position_vector or "
         "coordinate_frame (it is never assumed)");
  }
  if (t.model == TransformModel::helmert14) {
    std::array<double, 7> r{};
    for (std::size_t i = 0; i < 7; ++i) {
      Estimated e;
      r[i] = reader.require(kSeven[i], true, model_name, &e);
      mp.estimated.push_back(e);
    }
    if (position_vector) {
      t.helmert = geodesy::Helmert14<PositionVector>{seven_from<PositionVector>(p), rates_from<PositionVector>(r),
                                                     *t.reference_epoch};
    } else {
      t.helmert = geodesy::Helmert14<CoordinateFrame>{seven_from<CoordinateFrame>(p),
                                                      rates_from<CoordinateFrame>(r), *t.reference_epoch};
    }
  } else {
    for (const auto& spec : kSeven) {
      for (const bool b : {false, true}) {
        mp.no_sigma[spec_key(spec, true, b)] = "rates are parameters of model helmert14 only";
      }
    }
    if (position_vector) {
      t.helmert = seven_from<PositionVector>(p);
    } else {
      t.helmert = seven_from<CoordinateFrame>(p);
    }
  }
  if (t.model == TransformModel::molodensky_badekas) {
    t.pivot_m = Eigen::Vector3d(reader.require_plain("px_m", model_name), reader.require_plain("py_m", model_name),
                                reader.require_plain("pz_m", model_name));
  }
  for (const char* pivot : {"px_m", "py_m", "pz_m"}) {
    mp.no_sigma[pivot] = "the pivot is chosen (the control's centroid), not estimated";
  }
  reader.check_all_used(model_name);
  return t;
}

TransformFile parse_transform_core(std::string_view text, std::string_view source, json& doc, ModelParameters& mp) {
  doc = parse_json_strict<json>(text, source);
  return parse_transform_doc(doc, source, mp);
}

// Keys that describe the transform again (for PROJ, EPSG, the other
// convention) or say where it came from: type-checked, and where they state
// the convention or the parameters a second time, held to the first.
// Where two PROJ strings differ: the first step or parameter that does, or
// nullopt when they say the same (numbers equal to 1e-12 relative, as
// written and read back by format_shortest).
std::optional<std::string> pipeline_difference(const std::string& stated, const std::string& expected) {
  const auto tokens = [](const std::string& text) {
    std::vector<std::string> out;
    std::istringstream in(text);
    for (std::string w; in >> w;) out.push_back(w);
    return out;
  };
  const auto a = tokens(stated), b = tokens(expected);
  for (std::size_t i = 0; i < std::max(a.size(), b.size()); ++i) {
    const std::string x = i < a.size() ? a[i] : "(nothing)", y = i < b.size() ? b[i] : "(nothing)";
    if (x == y) continue;
    const auto eq_x = x.find('='), eq_y = y.find('=');
    if (eq_x != std::string::npos && eq_y != std::string::npos && x.substr(0, eq_x) == y.substr(0, eq_y)) {
      const auto u = parse_finite_double(x.substr(eq_x + 1)), v = parse_finite_double(y.substr(eq_y + 1));
      constexpr double kSameNumber = 1e-12;
      if (u && v && std::fabs(*u - *v) <= kSameNumber * std::max({1.0, std::fabs(*u), std::fabs(*v)})) continue;
    }
    return "it has " + x + " where they give " + y;
  }
  return std::nullopt;
}

void check_written_keys(const json& doc, const TransformFile& t, std::string_view source) {
  const std::string model(to_string(t.model));
  if (const json* v = member(doc, "format_version")) {
    if (!v->is_number_integer() || v->get<long long>() != 1) {
      fail(source, "format_version", "value " + v->dump() + " not read by this geoanchor, which reads format 1");
    }
  }
  for (const char* key : {"description", "generator", "proj_pipeline", "wkt2"}) {
    if (const json* v = member(doc, key)) string_at(*v, key, source);
  }
  if (const json* v = member(doc, "projjson")) {
    if (!v->is_object()) fail(source, "projjson", "value is not a JSON object");
  }
  if (const json* v = member(doc, "epsg_method")) {
    const std::string stated = string_at(*v, "epsg_method", source);
    const std::string expected = epsg_method(t);
    if (expected.empty()) {
      fail(source, "epsg_method",
           "value \"" + stated + "\": no EPSG method describes model " + model +
               (t.rotation_model == geodesy::RotationModel::exact
                    ? " with rotation_model exact (EPSG's Helmert methods are the small-angle formulas): the file states "
                      "its rotation model twice, differently; correct one"
                    : "; remove it"));
    }
    if (stated != expected) {
      fail(source, "epsg_method",
           "value \"" + stated + "\" contradicts model " + model + " in convention " + std::string(t.convention_name()) +
               " (" + expected + "): the file states its method twice, differently; correct one");
    }
  }
  // The file's own PROJ pipeline, as written, must be the one its model,
  // convention, rotation model and parameters give (an edited
  // rotation_model was applied without a word: issue 40 point 10).
  if (const json* v = member(doc, "proj_pipeline")) {
    const std::string stated = string_at(*v, "proj_pipeline", source);
    if (const auto diff = pipeline_difference(stated, proj_pipeline(t))) {
      fail(source, "proj_pipeline",
           "contradicts the file's model, convention, rotation_model and parameters (" + *diff +
               "): the file states its transform twice, differently; correct one (or remove proj_pipeline)");
    }
  }
  const json* alts = member(doc, "alternatives");
  if (!alts) return;
  if (t.enu_origin || t.site_calibration) {
    fail(source, "alternatives", "not read for model " + model + ": it has no other rotation convention; remove it");
  }
  if (!alts->is_array()) fail(source, "alternatives", "value is not an array");
  const TransformFile other = swapped_convention(t);
  const std::string other_convention(other.convention_name());
  for (std::size_t i = 0; i < alts->size(); ++i) {
    const std::string where = "alternatives[" + std::to_string(i) + "]";
    const json& a = (*alts)[i];
    only_keys(a, where, source, {"convention", "epsg_method", "parameters", "proj_pipeline", "wkt2", "projjson"});
    if (!a.contains("convention")) fail(source, where + ".convention", "missing");
    const std::string c = string_at(a.at("convention"), where + ".convention", source);
    if (c != other_convention) {
      fail(source, where + ".convention",
           "value \"" + c + "\" is not the other convention of convention " + std::string(t.convention_name()) +
               "; the file states its convention twice, differently: correct one (or remove alternatives)");
    }
    if (const json* e = member(a, "epsg_method")) {
      const std::string stated = string_at(*e, where + ".epsg_method", source);
      if (epsg_method(other).empty()) {
        fail(source, where + ".epsg_method", "value \"" + stated + "\": no EPSG method describes the exact rotation model");
      }
      if (stated != epsg_method(other)) {
        fail(source, where + ".epsg_method", "value \"" + stated + "\" is not " + epsg_method(other) + ", the method of " +
                                                 other_convention);
      }
    }
    for (const char* key : {"proj_pipeline", "wkt2"}) {
      if (const json* v = member(a, key)) string_at(*v, where + "." + key, source);
    }
    if (const json* v = member(a, "projjson")) {
      if (!v->is_object()) fail(source, where + ".projjson", "value is not a JSON object");
    }
    if (const json* params = member(a, "parameters")) {
      // The same transform in the other convention: read as a transform
      // file of its own, then compared parameter by parameter.
      json alt = {{"model", doc.at("model")}, {"convention", c}, {"parameters", *params}};
      for (const char* key : {"rotation_model", "reference_epoch"}) {
        if (doc.contains(key)) alt[key] = doc.at(key);
      }
      ModelParameters unused;
      const TransformFile read = parse_transform_doc(alt, std::string(source) + ": " + where, unused);
      const json got = std::visit([](const auto& h) { return parameters_json(h); }, read.helmert);
      const json want = std::visit([](const auto& h) { return parameters_json(h); }, other.helmert);
      for (const auto& [key, value] : want.items()) {
        const double g = got.at(key).get<double>(), w = value.get<double>();
        if (!(std::fabs(g - w) <= kAlternativeTol)) {
          fail(source, where + ".parameters." + key,
               "value " + format_shortest(g) + " is not the " + other_convention + " form (" + format_shortest(w) +
                   ") of parameters; the file states its parameters twice, differently: correct one (or remove "
                   "alternatives)");
        }
      }
      if (read.pivot_m && t.pivot_m && !((*read.pivot_m - *t.pivot_m).norm() <= kAlternativeTol)) {
        fail(source, where + ".parameters.px_m", "the pivot differs from parameters'");
      }
    }
  }
}

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
                 "; sigmas are read for the estimated parameters, in the units of parameters: " + joined(expected));
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
        fail(source, where, n + " has no sigma in sigmas; expected the parameters sigmas gives: " + joined(sigma_keys));
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

}  // namespace

TransformFile parse_transform_json(std::string_view text, std::string_view source) {
  json doc;
  ModelParameters mp;
  TransformFile t = parse_transform_core(text, source, doc, mp);
  check_written_keys(doc, t, source);
  t.fit = parse_fit_record(doc, t, mp, source);
  if (const json* meta = member(doc, "metadata")) {
    t.metadata = parse_map_metadata(meta->dump(), std::string(source) + ": metadata");
    // The contract describes the target side: its frame and epoch are target_frame's.
    MapMetadataBuilder b{std::string(source)};
    if (t.target_frame) {
      b.frame(t.target_frame->name(), "target_frame");
      if (t.target_frame->epoch()) b.coordinate_epoch(t.target_frame->epoch()->year, "target_frame");
    }
    if (t.metadata->frame) b.frame(*t.metadata->frame, "metadata.frame");
    if (t.metadata->coordinate_epoch) b.coordinate_epoch(*t.metadata->coordinate_epoch, "metadata.coordinate_epoch");
    if (t.target_frame && !t.metadata->frame) fail(source, "metadata.frame", "\"unknown\" but target_frame states it");
  }
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

// The transform without its fit record, member by member: a fit of 10⁶
// marks holds 10⁶ point records, and copying them only to drop them cost a
// second.
TransformFile without_fit_record(const TransformFile& t) {
  TransformFile out;
  out.model = t.model;
  out.rotation_model = t.rotation_model;
  out.helmert = t.helmert;
  out.source_frame = t.source_frame;
  out.target_frame = t.target_frame;
  out.reference_epoch = t.reference_epoch;
  out.pivot_m = t.pivot_m;
  out.enu_origin = t.enu_origin;
  out.site_calibration = t.site_calibration;
  return out;
}

// The same transform in the other rotation convention (no fit record).
TransformFile swapped_convention(const TransformFile& t) {
  TransformFile out = without_fit_record(t);
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
  // EPSG's Helmert methods are the small-angle formulas: finite rotations
  // have none (fit.md "Exports").
  if (t.enu_origin || t.site_calibration || t.rotation_model == geodesy::RotationModel::exact) return "";
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
    TransformFile g = without_fit_record(t);
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

namespace {

// One point record, one JSON object a line, appended to `out` (`first`: the
// array's first element, written without the comma). The record is formed
// in a stack buffer (numbers formatted in place, keys copied with their
// lengths known) and appended once: most of its cost is the 13 shortest
// round-trip numbers.
void append_point_record(std::string& out, const FitPointRecord& p, bool first) {
  // 13 numbers of at most 24 characters, an int, the keys: under 700 bytes.
  char buf[1024];
  char* at = buf;
  const auto lit = [&](std::string_view v) {
    std::memcpy(at, v.data(), v.size());
    at += v.size();
  };
  const auto num = [&](double v) {
    if (!std::isfinite(v)) {
      lit("null");
      return;
    }
    at = std::to_chars(at, at + 32, v).ptr;  // 32 > the longest double, "-2.2250738585072014e-308"
  };
  const auto triple = [&](const std::array<double, 3>& v) {
    *at++ = '[';
    num(v[0]);
    lit(", ");
    num(v[1]);
    lit(", ");
    num(v[2]);
    *at++ = ']';
  };
  const auto flag = [&](bool b) { lit(b ? std::string_view("true") : std::string_view("false")); };
  // A JSON string: as is when nothing in it needs escaping (the common id),
  // else through the JSON library; the record is flushed first, since an id
  // has no length limit.
  const auto text_value = [&](const std::string& v) {
    const bool plain = std::all_of(v.begin(), v.end(), [](char c) {
      return c != '"' && c != '\\' && static_cast<unsigned char>(c) >= 0x20 && c != 0x7f;
    });
    out.append(buf, static_cast<std::size_t>(at - buf));
    at = buf;
    if (plain) {
      out += '"';
      out += v;
      out += '"';
    } else {
      out += json(v).dump();
    }
  };
  lit(first ? std::string_view("\n    {\"id\": ") : std::string_view(",\n    {\"id\": "));
  text_value(p.id);
  lit(", \"mdb_m\": ");
  num(p.mdb_m);
  if (!p.note.empty()) {
    lit(", \"note\": ");
    text_value(p.note);
  }
  lit(", \"outlier\": ");
  flag(p.outlier);
  lit(", \"point_test\": {\"dof\": ");
  at = std::to_chars(at, at + 16, p.point_test_dof).ptr;
  lit(", \"p_value\": ");
  num(p.point_test_p);
  lit(", \"statistic\": ");
  num(p.point_test);
  lit("}, \"redundancy_enu\": ");
  triple(p.redundancy_enu);
  lit(", \"residual_enu_m\": ");
  triple(p.residual_enu_m);
  if (p.robust_weight < 1.0) {
    lit(", \"robust_weight\": ");
    num(p.robust_weight);
  }
  if (p.snooping_rank > 0) {
    lit(", \"snooping_rank\": ");
    at = std::to_chars(at, at + 24, p.snooping_rank).ptr;
  }
  if (p.solution) {
    lit(", \"solution\": \"");
    lit(geodesy::to_string(*p.solution));
    *at++ = '"';
  }
  if (!p.status.empty()) {
    lit(", \"status\": \"");
    lit(p.status);
    *at++ = '"';
  }
  lit(", \"used\": ");
  flag(p.used);
  // w_test is one of w_enu (the largest in magnitude): its text is copied
  // from there, not formed again.
  lit(", \"w_enu\": [");
  std::array<std::pair<const char*, const char*>, 3> w_text{};
  for (std::size_t k = 0; k < 3; ++k) {
    if (k) lit(", ");
    w_text[k].first = at;
    num(p.w_enu[k]);
    w_text[k].second = at;
  }
  lit("], \"w_test\": ");
  const auto same = std::find_if(w_text.begin(), w_text.end(), [&](const auto& t) {
    return std::bit_cast<std::uint64_t>(p.w_enu[static_cast<std::size_t>(&t - w_text.data())]) ==
           std::bit_cast<std::uint64_t>(p.w_test);
  });
  if (same != w_text.end()) {
    lit(std::string_view(same->first, static_cast<std::size_t>(same->second - same->first)));
  } else {
    num(p.w_test);
  }
  *at++ = '}';
  out.append(buf, static_cast<std::size_t>(at - buf));
}

// The "points" array's elements, in order. Formatting the numbers is most of
// a large fit's output time (10⁶ marks: about 450 MB of text, 0.5 s of CPU),
// so blocks of records are formatted by one worker a core (at most 8), each taking the
// next block as it finishes one, while this thread writes the blocks in
// order; the bytes are those of a one-thread loop. The workers run ahead of
// the writer by at most kSlots blocks (about 14 MB), so that a wait for the
// disk (the output's writeback) does not stop them, and no more is held.
// The records are `held`, or else formed by `streamed`.
void write_point_records(std::ostream& out, const std::vector<FitPointRecord>& held, const PointRecordSource* streamed) {
  constexpr std::size_t kBlock = 2048;  // records a worker formats at once (about 0.9 MB)
  constexpr std::size_t kSlots = 16;    // blocks formed and not yet written, at most
  const std::size_t records = streamed ? streamed->count : held.size();
  const std::size_t blocks = (records + kBlock - 1) / kBlock;
  const std::size_t workers = std::min(std::clamp<std::size_t>(std::thread::hardware_concurrency(), 1, 8), blocks);
  const auto format_block = [&](std::size_t b, std::string& text) {
    text.clear();
    FitPointRecord formed;
    const std::size_t end = std::min(records, (b + 1) * kBlock);
    for (std::size_t i = b * kBlock; i < end; ++i) {
      if (streamed) streamed->record(i, formed);
      append_point_record(text, streamed ? formed : held[i], i == 0);
    }
  };
  const auto on_this_thread = [&] {
    std::string text;
    for (std::size_t b = 0; b < blocks; ++b) {
      format_block(b, text);
      out.write(text.data(), static_cast<std::streamsize>(text.size()));
    }
  };
  if (workers <= 1) {
    on_this_thread();
    return;
  }
  struct Slot {
    std::string text;
    std::size_t block = SIZE_MAX;  // the block `text` holds, once formed
    std::exception_ptr error;      // its formatting's failure (bad_alloc)
  };
  std::array<Slot, kSlots> slots;
  std::mutex mutex;
  std::condition_variable formed, written;
  std::size_t next_block = 0;  // the next block a worker takes
  std::size_t done = 0;        // blocks written (their slots free again)
  bool stop = false;           // the writer is done or has failed: the workers end
  const auto work = [&] {
    std::unique_lock lock(mutex);
    while (true) {
      written.wait(lock, [&] { return stop || next_block >= blocks || next_block < done + kSlots; });
      if (stop || next_block >= blocks) return;
      const std::size_t b = next_block++;
      Slot& slot = slots[b % kSlots];
      lock.unlock();
      std::exception_ptr error;
      try {
        format_block(b, slot.text);
      } catch (...) {
        error = std::current_exception();
      }
      lock.lock();
      slot.error = error;
      slot.block = b;
      formed.notify_all();
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(workers);
  // The workers end before this frame does, whatever is thrown.
  struct Join {
    std::vector<std::thread>& pool;
    std::mutex& mutex;
    std::condition_variable& written;
    bool& stop;
    ~Join() {
      {
        const std::lock_guard lock(mutex);
        stop = true;
      }
      written.notify_all();
      for (auto& t : pool) t.join();
    }
  } join{pool, mutex, written, stop};
  for (std::size_t k = 0; k < workers; ++k) {
    try {
      pool.emplace_back(work);
    } catch (const std::system_error&) {  // no more threads to be had: those started do the work
      break;
    }
  }
  if (pool.empty()) {
    on_this_thread();
    return;
  }
  for (std::size_t b = 0; b < blocks; ++b) {
    Slot& slot = slots[b % kSlots];
    {
      std::unique_lock lock(mutex);
      formed.wait(lock, [&] { return slot.block == b; });
      if (slot.error) std::rethrow_exception(slot.error);
    }
    out.write(slot.text.data(), static_cast<std::streamsize>(slot.text.size()));
    {
      const std::lock_guard lock(mutex);
      done = b + 1;
    }
    written.notify_all();
  }
}

}  // namespace

namespace {

// The file's text; its point records those of t.fit, or else `streamed`'s.
void write_json_with(std::ostream& out, const TransformFile& t, const PointRecordSource* streamed) {
  json doc;
  doc["format_version"] = 1;
  doc["model"] = std::string(to_string(t.model));
  if (!t.enu_origin && !t.site_calibration) {
    doc["convention"] = std::string(t.convention_name());
    doc["rotation_model"] = std::string(geodesy::to_string(t.rotation_model));
    if (const std::string m = epsg_method(t); !m.empty()) doc["epsg_method"] = m;
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
                   {"false_easting_m", number(g.tm.false_easting_m)}, {"false_northing_m", number(g.tm.false_northing_m)},
                   {"ellipsoid", g.ellipsoid.name()}};
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
  if (t.metadata) doc["metadata"] = json::parse(map_metadata_json_text(*t.metadata));
  if (t.fit) {
    if (const auto wkt = to_wkt2(t)) doc["wkt2"] = *wkt;
    if (const auto pj = to_projjson(t)) doc["projjson"] = json::parse(*pj);
  }
  if (t.fit) {
    const FitRecord& f = *t.fit;
    if (!f.generator.empty()) doc["generator"] = f.generator;
    if (!f.control_crs_json.empty()) doc["control_crs"] = json::parse(f.control_crs_json);
    json sig = json::object();
    for (const auto& [name, value] : f.sigmas) sig[name] = number(value);
    doc["sigmas"] = sig;
    if (f.uncorrelated && f.correlation.empty()) {
      doc["correlation"] = "none";  // the parameters are uncorrelated, as the file read said
    } else {
      json corr = json::array();
      for (const auto& row : f.correlation) {
        json r = json::array();
        for (double v : row) r.push_back(number(v));
        corr.push_back(r);
      }
      doc["correlation"] = corr;  // rows and columns in the order of correlation_parameters
      doc["correlation_parameters"] = f.correlation_names;
    }
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
        {"sigma0", f.sigma0 ? number(*f.sigma0) : json(nullptr)},
        {"dof", f.dof},
        {"sigmas_scaled_by_sigma0", f.sigmas_scaled_by_sigma0},
        {"alpha", number(f.alpha)},
        {"alpha_point", number(f.alpha_point)},
        {"global_test",
         {{"statistic", json_number_or_null(f.global_statistic)},
          {"critical", json_number_or_null(f.global_critical_upper)},
          {"critical_lower", json_number_or_null(f.global_critical_lower)},
          {"passed", f.global_applicable ? json(f.global_passed) : json(nullptr)},
          {"applicable", f.global_applicable}}},
        {"warnings", f.warnings}};
    if (f.variance_factors) {
      doc["statistics"]["variance_factors"] = {{"source", number(f.variance_factors->first)},
                                               {"target", number(f.variance_factors->second)}};
    }
    if (f.gnss_solutions) {
      json classes = json::object();
      for (const auto s : geodesy::kGnssSolutions) {
        const SolutionTally& c = f.gnss_solutions->classes[geodesy::solution_index(s)];
        classes[std::string(geodesy::to_string(s))] = {
            {"marks", c.marks}, {"used", c.used}, {"excluded", c.excluded}, {"sigma_factor", number(c.sigma_factor)}};
      }
      doc["gnss_solutions"] = {{"policy", std::string(geodesy::to_string(f.gnss_solutions->policy))}, {"classes", classes}};
    }
    doc["points"] = nullptr;  // placeholder: the records are streamed below, one a line
  }
  if (t.fit && !t.enu_origin && !t.site_calibration) {
    // The exports read the parameters and frames alone: no fit record (a
    // copy of 10⁶ marks' records was 200 MB and a fifth of a second).
    const TransformFile other = swapped_convention(t);
    doc["alternatives"] = json::array({json{{"convention", std::string(other.convention_name())},
                                            {"parameters", with_pivot(std::visit([](const auto& h) { return parameters_json(h); }, other.helmert))},
                                            {"proj_pipeline", proj_pipeline(other)}}});
    if (const std::string m = epsg_method(other); !m.empty()) doc["alternatives"][0]["epsg_method"] = m;
    if (const auto wkt = to_wkt2(other)) doc["alternatives"][0]["wkt2"] = *wkt;
    if (const auto pj = to_projjson(other)) doc["alternatives"][0]["projjson"] = json::parse(*pj);
  }
  std::string text = doc.dump(2);
  if (t.fit) {
    // The per-point records, one JSON object a line: a fit of 10⁶ marks
    // writes them in a second instead of building a DOM of 10⁷ values.
    constexpr std::string_view kPlaceholder = "\n  \"points\": null";
    const auto at = text.find(kPlaceholder);
    if (at == std::string::npos) throw std::logic_error("transform file: the points placeholder is missing");
    out.write(text.data(), static_cast<std::streamsize>(at));
    out << "\n  \"points\": [";
    write_point_records(out, t.fit->points, streamed);
    out << ((streamed ? streamed->count : t.fit->points.size()) == 0 ? "]" : "\n  ]");
    const std::size_t rest = at + kPlaceholder.size();
    out.write(text.data() + rest, static_cast<std::streamsize>(text.size() - rest));
  } else {
    out << text;
  }
  out << '\n';
}

}  // namespace

void write_json(std::ostream& out, const TransformFile& t) { write_json_with(out, t, nullptr); }

void write_json(std::ostream& out, const TransformFile& t, const PointRecordSource& points) {
  if (!t.fit || !t.fit->points.empty()) {
    throw std::logic_error("write_json: streamed point records need a fit record without points of its own");
  }
  write_json_with(out, t, &points);
}

std::string to_json_text(const TransformFile& t) {
  std::ostringstream text;
  write_json(text, t);
  return std::move(text).str();
}

}  // namespace geoanchor::io
