// Reading a transform file: the model, its convention, frames, epoch and
// parameters (unknown, misspelt, doubled and foreign keys refused by name);
// then what `geoanchor fit` adds (transform_read_restated.cpp,
// transform_read_fit.cpp) and the map metadata contract.

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string_view>
#include <tuple>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/physical_range.hpp"
#include "geoanchor/io/json_input.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "transform/transform_common.hpp"

namespace geoanchor::io {
namespace detail {
namespace {

using geodesy::Angle;
using geodesy::CoordinateFrame;
using geodesy::PositionVector;
using geodesy::ScaleDifference;

// Top-level keys. What a model reads (model_keys below), what `geoanchor fit`
// adds about the fit (read into FitRecord), and what it adds that describes
// the same transform again (checked against it, never applied).
const std::set<std::string> kTopLevelKeys = {
    "model",       "convention", "rotation_model", "source_frame", "target_frame", "reference_epoch",
    "parameters",  "sigmas",     "correlation",    "statistics",   "points",       "proj_pipeline",
    "epsg_method", "generator",  "format_version", "description",  "alternatives", "nominal_origin",
    "wkt2",        "projjson",   "grid",          "correlation_parameters", "control_extent", "control_crs", "metadata", "gnss_solutions"};

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
    if (const auto key = first_unknown_key(params_, known)) {
      fail(source_, "parameters." + *key,
           "unknown parameter; expected tx_m ty_m tz_m rx_arcsec ry_arcsec rz_arcsec ds_ppm (mm, mas, ppb also "
           "read) and, for helmert14, their rates d..._per_year");
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

constexpr double kCorrectedOriginTol_m = 0.001;
constexpr double kGridCopyTol_deg = 1e-9;  // the same number written twice; 1e-9° is 0.1 mm

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
  if (const auto key = first_unknown_key(p, known)) {
    fail(source, "parameters." + *key, "unknown parameter for enu-origin; expected shift_e_m shift_n_m shift_u_m "
                                       "yaw_arcsec ds_ppm origin_lat_deg origin_lon_deg origin_h_m");
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
  if (const auto key = first_unknown_key(p, known)) {
    fail(source, "parameters." + *key, "unknown parameter for site-calibration; expected " + key_list(known));
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

}  // namespace

TransformFile parse_transform_doc(const json& doc, std::string_view source, ModelParameters& mp) {
  if (!doc.is_object()) fail(source, "(top level)", "expected a JSON object");
  if (const auto key = first_unknown_key(doc, kTopLevelKeys)) {
    fail(source, *key, "unknown key; expected model, convention, rotation_model, source_frame, target_frame, "
                       "reference_epoch, parameters (see docs/transform-file.md)");
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

namespace {

TransformFile parse_transform_core(std::string_view text, std::string_view source, json& doc, ModelParameters& mp) {
  doc = parse_json_strict<json>(text, source);
  return parse_transform_doc(doc, source, mp);
}

}  // namespace
}  // namespace detail

using detail::check_written_keys;
using detail::fail;
using detail::json;
using detail::member;
using detail::ModelParameters;
using detail::parse_fit_record;
using detail::parse_transform_core;

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

}  // namespace geoanchor::io
