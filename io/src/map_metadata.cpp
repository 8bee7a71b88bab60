// The map metadata contract and the survey-metadata file, read and written
// as JSON (docs/tile-metadata.md, docs/survey-metadata.md).

#include "geoanchor/io/map_metadata.hpp"

#include <nlohmann/json.hpp>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/base/utf8.hpp"
#include "geoanchor/io/json_input.hpp"
#include "json_fields.hpp"

namespace geoanchor::io {
namespace {

using nlohmann::json;
using nlohmann::ordered_json;

constexpr double kOriginTolDeg = 1e-8;  // 1.1 mm of latitude: the digits an origin is written with
constexpr double kOriginTolM = 1e-3;

std::string origin_text(const MetadataOrigin& o) {
  return format_shortest(o.lat_deg) + "," + format_shortest(o.lon_deg) + "," + format_shortest(o.h_m);
}

// A reader of one JSON object's keys whose messages name `where` and the key.
class Fields {
 public:
  Fields(const json& j, std::string where, const char* code) : j_(j), where_(std::move(where)), code_(code) {}

  [[noreturn]] void fail(const std::string& key, const std::string& problem) const {
    throw Error(ErrorKind::input, code_, where_ + (key.empty() ? "" : "." + key) + ": " + problem);
  }
  void only(const std::set<std::string>& known) const {
    if (!j_.is_object()) fail("", "expected a JSON object");
    if (const auto key = detail::first_unknown_key(j_, known)) fail(*key, "unknown key; expected one of " + detail::key_list(known));
  }
  const json* get(const std::string& key, bool required) const {
    const auto it = j_.find(key);
    if (it == j_.end()) {
      if (required) {
        fail(key, std::string("missing") +
                      (std::string_view(code_) == "E_METADATA" ? "; every field of the contract is written, its value or \"unknown\""
                                                               : ""));
      }
      return nullptr;
    }
    if (it->is_null()) fail(key, "value null; write the value or \"unknown\"");
    return &*it;
  }
  static bool is_unknown(const json& v) { return v.is_string() && v.get<std::string>() == kUnknown; }
  // A string, or nullopt for "unknown".
  std::optional<std::string> text(const std::string& key, bool required) const {
    const json* v = get(key, required);
    if (!v || is_unknown(*v)) return std::nullopt;
    if (!v->is_string()) fail(key, "expected a string or \"unknown\", got " + v->dump());
    std::string s = v->get<std::string>();
    if (s.empty()) fail(key, "empty; write the value or \"unknown\"");
    return s;
  }
  double number_value(const json& v, const std::string& key, double lo, double hi, const std::string& range) const {
    if (!v.is_number()) fail(key, "expected a number or \"unknown\", got " + v.dump());
    const double x = v.get<double>();
    if (!std::isfinite(x) || x < lo || x > hi) fail(key, "value " + format_shortest(x) + " not in " + range);
    return x;
  }
  std::optional<double> number(const std::string& key, bool required, double lo, double hi, const std::string& range) const {
    const json* v = get(key, required);
    if (!v || is_unknown(*v)) return std::nullopt;
    return number_value(*v, key, lo, hi, range);
  }
  std::optional<MetadataOrigin> origin(const std::string& key, bool required) const {
    const json* v = get(key, required);
    if (!v || is_unknown(*v)) return std::nullopt;
    const Fields o(*v, where_ + "." + key, code_);
    o.only({"lat_deg", "lon_deg", "h_m", "height_type"});
    MetadataOrigin r;
    r.lat_deg = o.number_value(*o.get("lat_deg", true), "lat_deg", -90, 90, "[-90, 90]");
    r.lon_deg = o.number_value(*o.get("lon_deg", true), "lon_deg", -180, 180, "[-180, 180]");
    r.h_m = o.number_value(*o.get("h_m", true), "h_m", -1.0e4, 1.0e5, "[-10000, 100000] m");
    const json* ht = o.get("height_type", true);
    if (!ht->is_string() || ht->get<std::string>() != "ellipsoidal") {
      o.fail("height_type", "value " + ht->dump() + "; an ENU origin's height must be \"ellipsoidal\"");
    }
    return r;
  }

 private:
  const json& j_;
  std::string where_;
  const char* code_;
};

ordered_json text_or_unknown(const std::optional<std::string>& v) { return v ? ordered_json(*v) : ordered_json(kUnknown); }

// Decimals of a share as written: the fewest (up to six) that give it back.
int decimals_of(double v) {
  for (int d = 0; d < 6; ++d) {
    const double p = std::pow(10.0, d);
    if (std::fabs(std::round(v * p) / p - v) <= 1e-9 * std::max(1.0, std::fabs(v))) return d;
  }
  return 6;
}

}  // namespace

bool share_agrees(double stated, double computed) {
  if (!std::isfinite(stated) || !std::isfinite(computed)) return false;
  const double half_unit = 0.5 * std::pow(10.0, -decimals_of(stated));
  return std::fabs(stated - computed) <= half_unit * (1.0 + 1e-9);
}

std::string coordinate_storage_text(std::string_view kind, std::string_view storage) {
  const std::string s = storage == "int32_scaled" ? "int32 scaled" : std::string(storage);
  if (kind == "enu" || kind == "ned") {
    return "float64 ECEF origin + " + s + (kind == "enu" ? " ENU offsets" : " NED offsets");
  }
  if (kind == "ecef") return s + " ECEF";
  if (kind == "geodetic") return s + " geodetic (longitude, latitude, ellipsoidal height)";
  if (kind == "utm" || kind == "tm") return s + " projected (easting, northing, height)";
  if (kind == "crs") return s + " coordinates of the CRS";
  return s + " " + std::string(kind);
}

std::string map_metadata_json_text(const MapMetadata& m) {
  ordered_json j;
  j["schema"] = kMapMetadataSchema;
  j["frame"] = text_or_unknown(m.frame);
  if (m.coordinate_epoch) {
    j["coordinate_epoch"] = *m.coordinate_epoch;
  } else if (m.coordinate_epoch_range) {
    j["coordinate_epoch"] = {{"from", (*m.coordinate_epoch_range)[0]}, {"to", (*m.coordinate_epoch_range)[1]}};
  } else {
    j["coordinate_epoch"] = kUnknown;
  }
  if (m.enu_origin) {
    j["enu_origin"] = {{"lat_deg", m.enu_origin->lat_deg},
                       {"lon_deg", m.enu_origin->lon_deg},
                       {"h_m", m.enu_origin->h_m},
                       {"height_type", "ellipsoidal"}};
  } else {
    j["enu_origin"] = kUnknown;
  }
  j["enu_origin_source"] = text_or_unknown(m.enu_origin_source);
  j["horizontal_crs"] = text_or_unknown(m.horizontal_crs);
  j["vertical_datum"] = text_or_unknown(m.vertical_datum);
  j["geoid_model"] = text_or_unknown(m.geoid_model);
  j["gnss_method"] = text_or_unknown(m.gnss_method);
  j["gnss_base"] = text_or_unknown(m.gnss_base);
  j["rtk_fixed_percent"] = m.rtk_fixed_percent ? ordered_json(*m.rtk_fixed_percent) : ordered_json(kUnknown);
  j["rtk_fixed_from"] = text_or_unknown(m.rtk_fixed_from);
  if (m.gnss_solution_counts) {
    ordered_json c = ordered_json::object();
    for (const auto s : geodesy::kGnssSolutions) {
      c[std::string(geodesy::to_string(s))] = m.gnss_solution_counts->count[geodesy::solution_index(s)];
    }
    j["gnss_solution_counts"] = c;
  } else {
    j["gnss_solution_counts"] = kUnknown;
  }
  j["coordinate_storage"] = text_or_unknown(m.coordinate_storage);
  for (const auto& [key, value] : j.items()) {
    if (value.is_string()) {
      if (const auto problem = utf8_problem(value.get<std::string>())) {
        throw Error(ErrorKind::input, "E_METADATA", "metadata." + key + ": text that is not valid UTF-8 (" + *problem + ")");
      }
    }
  }
  return j.dump();
}

MapMetadata parse_map_metadata(std::string_view object_json, std::string_view where_in) {
  const std::string where(where_in);
  const json j = json::parse(object_json);
  const Fields f(j, where, "E_METADATA");
  f.only({"schema", "frame", "coordinate_epoch", "enu_origin", "enu_origin_source", "horizontal_crs", "vertical_datum",
          "geoid_model", "gnss_method", "gnss_base", "rtk_fixed_percent", "rtk_fixed_from", "gnss_solution_counts",
          "coordinate_storage"});
  const json* schema = f.get("schema", true);
  if (!schema->is_string() || schema->get<std::string>() != kMapMetadataSchema) {
    f.fail("schema", "expected \"" + std::string(kMapMetadataSchema) + "\", got " + schema->dump());
  }
  MapMetadata m;
  if (const auto fr = f.text("frame", true)) {
    const geodesy::Frame parsed = geodesy::Frame::parse(*fr, where + ".frame");
    if (parsed.epoch()) f.fail("frame", "\"" + *fr + "\" names an epoch; the frame is datum and realization, its epoch is coordinate_epoch");
    m.frame = parsed.name();
  }
  if (const json* e = f.get("coordinate_epoch", true); !Fields::is_unknown(*e)) {
    if (e->is_object()) {
      const Fields r(*e, where + ".coordinate_epoch", "E_METADATA");
      r.only({"from", "to"});
      const double from = r.number_value(*r.get("from", true), "from", 1900, 2200, "[1900, 2200]");
      const double to = r.number_value(*r.get("to", true), "to", 1900, 2200, "[1900, 2200]");
      if (!(from <= to)) r.fail("to", "value " + format_shortest(to) + " is before from " + format_shortest(from));
      m.coordinate_epoch_range = std::array<double, 2>{from, to};
    } else {
      m.coordinate_epoch = f.number_value(*e, "coordinate_epoch", 1900, 2200, "[1900, 2200] (a decimal year)");
    }
  }
  m.enu_origin = f.origin("enu_origin", true);
  m.enu_origin_source = f.text("enu_origin_source", true);
  m.horizontal_crs = f.text("horizontal_crs", true);
  m.vertical_datum = f.text("vertical_datum", true);
  m.geoid_model = f.text("geoid_model", true);
  m.gnss_method = f.text("gnss_method", true);
  m.gnss_base = f.text("gnss_base", true);
  m.rtk_fixed_percent = f.number("rtk_fixed_percent", true, 0, 100, "[0, 100] %");
  m.rtk_fixed_from = f.text("rtk_fixed_from", true);
  if (m.rtk_fixed_from.has_value() != m.rtk_fixed_percent.has_value()) {
    f.fail("rtk_fixed_from", m.rtk_fixed_from ? "says where a share came from, but rtk_fixed_percent is \"unknown\""
                                              : "\"unknown\", but rtk_fixed_percent states a share: say where it came from");
  }
  if (const json* c = f.get("gnss_solution_counts", true); !Fields::is_unknown(*c)) {
    const Fields cf(*c, where + ".gnss_solution_counts", "E_METADATA");
    std::set<std::string> names;
    for (const auto s : geodesy::kGnssSolutions) names.insert(std::string(geodesy::to_string(s)));
    cf.only(names);
    geodesy::SolutionCounts counts;
    for (const auto s : geodesy::kGnssSolutions) {
      const std::string key(geodesy::to_string(s));
      const json* v = cf.get(key, true);
      if (!v->is_number_unsigned()) cf.fail(key, "expected a count (an integer >= 0), got " + v->dump());
      counts.count[geodesy::solution_index(s)] = v->get<std::uint64_t>();
    }
    m.gnss_solution_counts = counts;
    // The share and the counts say one thing.
    const auto computed = counts.rtk_fixed_percent();
    if (m.rtk_fixed_percent && computed && !share_agrees(*m.rtk_fixed_percent, *computed)) {
      f.fail("rtk_fixed_percent", "value " + format_shortest(*m.rtk_fixed_percent) + " but gnss_solution_counts give " +
                                      format_shortest(*computed) + " % fixed or ppk");
    }
  }
  m.coordinate_storage = f.text("coordinate_storage", true);
  return m;
}

SurveyMetadata read_survey_metadata(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw Error(ErrorKind::io, "E_READ", path.string() + ": cannot open the survey metadata: " + std::strerror(errno));
  }
  std::ostringstream s;
  s << in.rdbuf();
  return parse_survey_metadata(s.str(), path.string());
}

SurveyMetadata parse_survey_metadata(std::string_view text, std::string_view source) {
  const json j = parse_json_strict<json>(text, source);
  const Fields f(j, std::string(source), "E_SURVEY_METADATA");
  f.only({"schema", "description", "frame", "enu_origin", "enu_origin_source", "vertical_datum", "geoid_model",
          "gnss_method", "gnss_base", "rtk_fixed_percent"});
  const json* schema = f.get("schema", false);
  if (!schema || !schema->is_string() || schema->get<std::string>() != kSurveyMetadataSchema) {
    f.fail("schema", "expected \"" + std::string(kSurveyMetadataSchema) + "\"" +
                         (schema ? ", got " + schema->dump() : std::string(", the key is missing")));
  }
  SurveyMetadata s;
  s.source = std::string(source);
  (void)f.text("description", false);
  if (const auto fr = f.text("frame", false)) s.frame = geodesy::Frame::parse(*fr, std::string(source) + ": frame");
  s.enu_origin = f.origin("enu_origin", false);
  s.enu_origin_source = f.text("enu_origin_source", false);
  s.vertical_datum = f.text("vertical_datum", false);
  s.geoid_model = f.text("geoid_model", false);
  s.gnss_method = f.text("gnss_method", false);
  s.gnss_base = f.text("gnss_base", false);
  s.rtk_fixed_percent = f.number("rtk_fixed_percent", false, 0, 100, "[0, 100] %");
  return s;
}

void MapMetadataBuilder::conflict(const std::string& key, const std::string& had, const std::string& had_who,
                                  const std::string& value, const std::string& who) const {
  throw Error(ErrorKind::input, "E_METADATA_CONFLICT",
              artifact_ + ": metadata." + key + ": " + who + " says " + value + " but " + had_who + " says " + had +
                  "; fix the one that is wrong (a stated value is never silently replaced)");
}

void MapMetadataBuilder::frame(const std::string& name, const std::string& who) {
  if (m_.frame && *m_.frame != name) conflict("frame", "\"" + *m_.frame + "\"", who_["frame"], "\"" + name + "\"", who);
  if (!m_.frame) {
    m_.frame = name;
    who_["frame"] = who;
  }
}

void MapMetadataBuilder::coordinate_epoch(double year, const std::string& who) {
  if (m_.coordinate_epoch_range) {
    conflict("coordinate_epoch", "per-point epochs", who_["coordinate_epoch"], format_shortest(year), who);
  }
  if (m_.coordinate_epoch && std::fabs(*m_.coordinate_epoch - year) > 1e-9) {
    conflict("coordinate_epoch", format_shortest(*m_.coordinate_epoch), who_["coordinate_epoch"], format_shortest(year), who);
  }
  if (!m_.coordinate_epoch) {
    m_.coordinate_epoch = year;
    who_["coordinate_epoch"] = who;
  }
}

void MapMetadataBuilder::coordinate_epoch_range(const std::array<double, 2>& range, const std::string& who) {
  if (m_.coordinate_epoch) {
    conflict("coordinate_epoch", format_shortest(*m_.coordinate_epoch), who_["coordinate_epoch"], "per-point epochs", who);
  }
  m_.coordinate_epoch_range = range;
  who_["coordinate_epoch"] = who;
}

void MapMetadataBuilder::enu_origin(const MetadataOrigin& o, const std::string& who) {
  if (m_.enu_origin) {
    const auto& a = *m_.enu_origin;
    if (!(std::fabs(a.lat_deg - o.lat_deg) <= kOriginTolDeg && std::fabs(a.lon_deg - o.lon_deg) <= kOriginTolDeg &&
          std::fabs(a.h_m - o.h_m) <= kOriginTolM)) {
      conflict("enu_origin", origin_text(a), who_["enu_origin"], origin_text(o) + " (beyond 1e-8° or 1 mm)", who);
    }
    return;
  }
  m_.enu_origin = o;
  who_["enu_origin"] = who;
}

void MapMetadataBuilder::text(Text field, const std::string& value, const std::string& who) {
  std::optional<std::string>* slot = nullptr;
  const char* key = "";
  switch (field) {
    case Text::enu_origin_source: slot = &m_.enu_origin_source, key = "enu_origin_source"; break;
    case Text::horizontal_crs: slot = &m_.horizontal_crs, key = "horizontal_crs"; break;
    case Text::vertical_datum: slot = &m_.vertical_datum, key = "vertical_datum"; break;
    case Text::geoid_model: slot = &m_.geoid_model, key = "geoid_model"; break;
    case Text::gnss_method: slot = &m_.gnss_method, key = "gnss_method"; break;
    case Text::gnss_base: slot = &m_.gnss_base, key = "gnss_base"; break;
    case Text::coordinate_storage: slot = &m_.coordinate_storage, key = "coordinate_storage"; break;
  }
  if (value.empty() || value == kUnknown) return;
  if (*slot && **slot != value) conflict(key, "\"" + **slot + "\"", who_[key], "\"" + value + "\"", who);
  if (!*slot) {
    *slot = value;
    who_[key] = who;
  }
}

void MapMetadataBuilder::rtk_fixed_percent(double percent, const std::string& who, bool computed) {
  if (m_.rtk_fixed_percent) {
    const bool had_computed = who_["rtk_fixed_percent:computed"] == "yes";
    const bool agree = had_computed ? share_agrees(percent, *m_.rtk_fixed_percent)
                       : computed   ? share_agrees(*m_.rtk_fixed_percent, percent)
                                    : share_agrees(percent, *m_.rtk_fixed_percent) ||
                                        share_agrees(*m_.rtk_fixed_percent, percent);
    if (!agree) {
      conflict("rtk_fixed_percent", format_shortest(*m_.rtk_fixed_percent) + " %", who_["rtk_fixed_percent"],
               format_shortest(percent) + " % (beyond the stated value's rounding)", who);
    }
    if (!computed || had_computed) return;  // the computed share is kept
  }
  m_.rtk_fixed_percent = percent;
  m_.rtk_fixed_from = who;
  who_["rtk_fixed_percent"] = who;
  who_["rtk_fixed_percent:computed"] = computed ? "yes" : "no";
}

void MapMetadataBuilder::gnss_solution_counts(const geodesy::SolutionCounts& c, const std::string& who) {
  if (m_.gnss_solution_counts) {
    if (m_.gnss_solution_counts->count != c.count) {
      conflict("gnss_solution_counts", "other counts", who_["gnss_solution_counts"], "these", who);
    }
    return;
  }
  m_.gnss_solution_counts = c;
  who_["gnss_solution_counts"] = who;
  if (const auto share = c.rtk_fixed_percent()) rtk_fixed_percent(*share, who, true);
}

void MapMetadataBuilder::survey(const SurveyMetadata& s, bool frame_bound) {
  const std::string who = "survey metadata " + s.source;
  if (frame_bound) {
    if (s.frame) {
      frame(s.frame->name(), who);
      if (s.frame->epoch()) coordinate_epoch(s.frame->epoch()->year, who);
    }
    if (s.enu_origin) enu_origin(*s.enu_origin, who);
    if (s.enu_origin_source) text(Text::enu_origin_source, *s.enu_origin_source, who);
    if (s.vertical_datum) text(Text::vertical_datum, *s.vertical_datum, who);
  }
  if (s.geoid_model) text(Text::geoid_model, *s.geoid_model, who);
  if (s.gnss_method) text(Text::gnss_method, *s.gnss_method, who);
  if (s.gnss_base) text(Text::gnss_base, *s.gnss_base, who);
  if (s.rtk_fixed_percent) rtk_fixed_percent(*s.rtk_fixed_percent, who, false);
}

}  // namespace geoanchor::io
