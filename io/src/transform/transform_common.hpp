#pragma once
// What the transform file's reader and writer share (private to io): the
// failure that names the file and the key, typed access to the JSON, the
// parameters a model estimates, and the readers and writers each part of
// the file's text calls on in another file.

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <map>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "json_fields.hpp"

namespace geoanchor::io::detail {

using nlohmann::json;

[[noreturn]] inline void fail(std::string_view source, const std::string& key, const std::string& what) {
  throw Error(ErrorKind::input, "E_TRANSFORM", std::string(source) + ": " + key + ": " + what);
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

// Shortest round-trip number for JSON output.
inline json number(double v) { return json::parse(format_shortest(v)); }

// Typed access; every message names the file and the key's JSON path.
inline const json* member(const json& obj, const std::string& key) {
  const auto it = obj.find(key);
  return it == obj.end() ? nullptr : &*it;
}

inline double number_at(const json& v, const std::string& path, std::string_view source) {
  if (!v.is_number()) fail(source, path, "value " + v.dump() + " is not a number");
  return v.get<double>();
}

inline double number_field(const json& obj, const std::string& key, const std::string& where, std::string_view source) {
  if (!obj.contains(key)) fail(source, where + key, "missing");
  return number_at(obj.at(key), where + key, source);
}

inline std::string string_at(const json& v, const std::string& path, std::string_view source) {
  if (!v.is_string()) fail(source, path, "value " + v.dump() + " is not a string");
  return v.get<std::string>();
}

inline bool bool_at(const json& v, const std::string& path, std::string_view source) {
  if (!v.is_boolean()) fail(source, path, "value " + v.dump() + " is not true or false");
  return v.get<bool>();
}

inline int count_at(const json& v, const std::string& path, std::string_view source) {
  if (!v.is_number_integer() || v.get<long long>() < 0 || v.get<long long>() > 2147483647LL) {
    fail(source, path, "value " + v.dump() + " is not a count (an integer >= 0)");
  }
  return static_cast<int>(v.get<long long>());
}

// Every key of `obj` must be one of `known`.
inline void only_keys(const json& obj, const std::string& where, std::string_view source, const std::vector<std::string>& known) {
  if (!obj.is_object()) fail(source, where, "value " + obj.dump() + " is not an object; expected the keys " + key_list(known));
  if (const auto key = first_unknown_key(obj, known)) fail(source, where + "." + *key, "unknown key; expected " + key_list(known));
}

// A statistic that may be undefined: null (what the writer gives a NaN,
// e.g. the w-test of an axis without redundancy) is read back as NaN.
inline double number_or_null_at(const json& v, const std::string& path, std::string_view source) {
  return v.is_null() ? std::numeric_limits<double>::quiet_NaN() : number_at(v, path, source);
}

inline std::array<double, 3> triple_at(const json& v, const std::string& path, std::string_view source, bool null_is_nan = false) {
  if (!v.is_array() || v.size() != 3) fail(source, path, "value " + v.dump() + " is not [e, n, u]");
  std::array<double, 3> out{};
  for (std::size_t k = 0; k < 3; ++k) {
    const std::string at = path + "[" + std::to_string(k) + "]";
    out[k] = null_is_nan ? number_or_null_at(v[k], at, source) : number_at(v[k], at, source);
  }
  return out;
}

inline geodesy::Ellipsoid ellipsoid_at(const json& v, const std::string& path, std::string_view source) {
  const std::string name = string_at(v, path, source);
  if (name == "WGS84") return geodesy::Ellipsoid::wgs84();
  if (name == "GRS80") return geodesy::Ellipsoid::grs80();
  fail(source, path, "value \"" + name + "\" unknown; expected WGS84 or GRS80");
}

// ------------------------------------------------ defined in other files

// The model part of a document (transform_read.cpp); `mp` receives what a
// sigma may be given for.
TransformFile parse_transform_doc(const json& doc, std::string_view source, ModelParameters& mp);
// The keys that state the transform again, held to it (transform_read_restated.cpp).
void check_written_keys(const json& doc, const TransformFile& t, std::string_view source);
// The fit record, or nullopt when the file has none (transform_read_fit.cpp).
std::optional<FitRecord> parse_fit_record(const json& doc, const TransformFile& t, const ModelParameters& mp,
                                          std::string_view source);
// Where two PROJ strings differ (transform_pipeline.cpp).
std::optional<std::string> pipeline_difference(const std::string& stated, const std::string& expected);
// The transform without its fit record, and in the other rotation
// convention (transform_file.cpp).
TransformFile without_fit_record(const TransformFile& t);
TransformFile swapped_convention(const TransformFile& t);
// The "points" array's elements, in order (transform_write_points.cpp).
void write_point_records(std::ostream& out, const std::vector<FitPointRecord>& held, const PointRecordSource* streamed);

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
  if constexpr (std::is_same_v<H, geodesy::Helmert14<geodesy::PositionVector>> ||
                std::is_same_v<H, geodesy::Helmert14<geodesy::CoordinateFrame>>) {
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

}  // namespace geoanchor::io::detail
