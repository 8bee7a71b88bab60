// The tile metadata sidecar, read and written as JSON.

#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/geodesy/physical_range.hpp"
#include "geoanchor/base/utf8.hpp"
#include "geoanchor/io/json_input.hpp"
#include "geoanchor/io/tile/tile_metadata.hpp"
#include "json_fields.hpp"

namespace geoanchor::io {
namespace {

using nlohmann::json;

[[noreturn]] void fail(std::string_view source, const std::string& key, const std::string& problem) {
  throw Error(ErrorKind::input, "E_TILE_METADATA", std::string(source) + ": " + key + ": " + problem);
}

void only_keys(const json& j, std::string_view source, const std::string& where, const std::set<std::string>& known) {
  if (!j.is_object()) fail(source, where, "expected a JSON object");
  if (const auto key = detail::first_unknown_key(j, known)) {
    fail(source, where.empty() ? *key : where + "." + *key, "unknown key; expected one of " + detail::key_list(known));
  }
}

// The value of `key`, or nullptr when absent. null is not a value: a key
// given as null is refused (it would otherwise read as absent, and a default
// would stand in for it), except where the schema writes null itself
// (vertical.geoid_model: member_or_null).
const json* member(const json& j, const char* key, std::string_view source, const std::string& where) {
  const auto it = j.find(key);
  if (it == j.end()) return nullptr;
  if (it->is_null()) {
    fail(source, where.empty() ? std::string(key) : where + "." + key,
         "value null; give the key a value or leave it out");
  }
  return &*it;
}

const json* member_or_null(const json& j, const char* key) {
  const auto it = j.find(key);
  return it == j.end() || it->is_null() ? nullptr : &*it;
}

std::string text(const json& j, std::string_view source, const std::string& key) {
  if (!j.is_string()) fail(source, key, "expected a string, got " + j.dump());
  return j.get<std::string>();
}

double number(const json& j, std::string_view source, const std::string& key, double lo, double hi,
              const std::string& range) {
  if (!j.is_number()) fail(source, key, "expected a number, got " + j.dump());
  const double v = j.get<double>();
  if (!std::isfinite(v) || v < lo || v > hi) fail(source, key, "value " + format_shortest(v) + " not in " + range);
  return v;
}

geodesy::Ellipsoid ellipsoid(const json& j, std::string_view source) {
  if (j.is_string()) {
    const auto name = j.get<std::string>();
    if (const auto named = geodesy::named_ellipsoid(name)) return *named;
    fail(source, "coordinates.ellipsoid",
         "value \"" + name + "\" unknown; expected one of " + geodesy::named_ellipsoid_list() + ", or {\"a_m\", \"rf\"}");
  }
  only_keys(j, source, "coordinates.ellipsoid", {"a_m", "rf", "name"});
  const json* a = member(j, "a_m", source, "coordinates.ellipsoid");
  const json* rf = member(j, "rf", source, "coordinates.ellipsoid");
  if (!a || !rf) fail(source, "coordinates.ellipsoid", "a custom ellipsoid needs a_m and rf");
  const double a_m = number(*a, source, "coordinates.ellipsoid.a_m", 6.0e6, 7.0e6, "[6000000, 7000000] m");
  const double inv_f = number(*rf, source, "coordinates.ellipsoid.rf", 250.0, 350.0, "[250, 350]");
  const json* n = member(j, "name", source, "coordinates.ellipsoid");
  return geodesy::Ellipsoid::custom(a_m, inv_f, n ? text(*n, source, "coordinates.ellipsoid.name") : "custom");
}

nlohmann::ordered_json ellipsoid_json(const geodesy::Ellipsoid& e) {
  if (e == geodesy::Ellipsoid::wgs84()) return "WGS84";
  if (e == geodesy::Ellipsoid::grs80()) return "GRS80";
  return nlohmann::ordered_json{{"name", e.name()}, {"a_m", e.a_m()}, {"rf", e.rf()}};
}

// Coordinates of kind "crs": the CRS (WKT2, with its coordinate epoch), and
// the frame it is on, which a frame named beside it must be.
void read_crs(const json* crs, TileMetadata& m, std::string_view source) {
  if (!crs) fail(source, "crs", "missing for kind \"crs\": {\"wkt2\": \"...\", \"coordinate_epoch\": YEAR}");
  only_keys(*crs, source, "crs", {"wkt2", "coordinate_epoch"});
  const json* w = member(*crs, "wkt2", source, "crs");
  if (!w) fail(source, "crs.wkt2", "missing: the CRS as WKT2");
  std::string definition = text(*w, source, "crs.wkt2");
  if (const json* e = member(*crs, "coordinate_epoch", source, "crs")) {
    definition += "@" + geodesy::format_decimal_year(
                            geodesy::DecimalYear{number(*e, source, "crs.coordinate_epoch", 1900, 2200, "[1900, 2200]")});
  }
  m.crs = Crs::parse(definition, std::string(source) + ": crs");
  const auto& d = m.crs->description();
  if (m.frame && d.catalog_frame.empty()) {
    // The CRS's datum is the frame: another one named beside it would
    // pick a transform for points that PROJ moves on the CRS's datum.
    fail(source, "frame", "\"" + m.frame->to_string() + "\" but the CRS " + m.crs->display_name() + " is on datum '" +
                              d.datum + "', which is no frame of geoanchor's catalog; remove the key (the CRS states "
                              "the datum)");
  }
  if (m.frame && !d.catalog_frame.empty() && m.frame->name() != d.catalog_frame) {
    fail(source, "frame", "\"" + m.frame->to_string() + "\" but the CRS's datum is " + d.catalog_frame);
  }
  if (m.frame && m.crs->epoch() && !(m.frame->epoch() && m.frame->epoch()->year == m.crs->epoch()->year)) {
    fail(source, "frame", "\"" + m.frame->to_string() + "\" but crs.coordinate_epoch is " +
                              geodesy::format_decimal_year(*m.crs->epoch()));
  }
  if (!m.frame && !d.catalog_frame.empty()) {
    m.frame = geodesy::Frame::parse(
        d.catalog_frame + (m.crs->epoch() ? "@" + geodesy::format_decimal_year(*m.crs->epoch()) : ""),
        std::string(source) + ": crs");
  }
}

// The ENU (or NED) origin: on the coordinates' ellipsoid, its height ellipsoidal.
void read_enu_origin(const json* origin, const std::string& k, TileMetadata& m, std::string_view source) {
  m.coordinates.kind = k == "enu" ? CoordinateKind::enu : CoordinateKind::ned;
  if (!origin) fail(source, "enu_origin", "missing for " + k + " coordinates: {\"lat_deg\", \"lon_deg\", \"h_m\", \"height_type\", \"source\"}");
  only_keys(*origin, source, "enu_origin", {"lat_deg", "lon_deg", "h_m", "height_type", "source"});
  const json* lat = member(*origin, "lat_deg", source, "enu_origin");
  const json* lon = member(*origin, "lon_deg", source, "enu_origin");
  const json* h = member(*origin, "h_m", source, "enu_origin");
  const json* ht = member(*origin, "height_type", source, "enu_origin");
  if (!lat || !lon || !h) fail(source, "enu_origin", "needs lat_deg, lon_deg and h_m");
  if (!ht || text(*ht, source, "enu_origin.height_type") != "ellipsoidal") {
    fail(source, "enu_origin.height_type",
         std::string(ht ? "value " + ht->dump() : "missing") + "; an ENU origin's height must be \"ellipsoidal\"");
  }
  geodesy::LocalOrigin o;
  o.ellipsoid = m.coordinates.ellipsoid;
  o.point.lat = geodesy::Angle::degrees(number(*lat, source, "enu_origin.lat_deg", -90, 90, "[-90, 90]"));
  o.point.lon = geodesy::Angle::degrees(number(*lon, source, "enu_origin.lon_deg", -180, 180, "[-180, 180]"));
  o.point.h = geodesy::EllipsoidalHeight{number(*h, source, "enu_origin.h_m", geodesy::kMinEllipsoidalHeight_m,
                                                geodesy::kMaxEllipsoidalHeight_m, geodesy::physical_height_range_text())};
  m.coordinates.origin = o;
  if (const json* src = member(*origin, "source", source, "enu_origin")) m.origin_source = text(*src, source, "enu_origin.source");
}

// The projection of utm or tm coordinates: a UTM zone, or a transverse
// Mercator's parameters.
void read_projection(const json* projection, const std::string& k, TileMetadata& m, std::string_view source) {
  m.coordinates.kind = CoordinateKind::projected;
  if (!projection) fail(source, "projection", "missing for " + k + " coordinates");
  only_keys(*projection, source, "projection", {"utm_zone", "tm"});
  // Each kind reads one of the two; the other would be ignored.
  if (const char* other = k == "utm" ? "tm" : "utm_zone"; projection->contains(other)) {
    fail(source, std::string("projection.") + other, "given for " + k + " coordinates, which read projection." +
                                                          (k == "utm" ? "utm_zone" : "tm") + " only; remove it");
  }
  if (k == "utm") {
    const json* z = member(*projection, "utm_zone", source, "projection");
    if (!z) fail(source, "projection.utm_zone", "missing for utm coordinates (e.g. \"32N\")");
    m.coordinates.projection = geodesy::utm_projection(
        m.coordinates.ellipsoid,
        geodesy::parse_utm_zone(text(*z, source, "projection.utm_zone"), std::string(source) + ": projection.utm_zone"));
  } else {
    const json* t = member(*projection, "tm", source, "projection");
    if (!t) fail(source, "projection.tm", "missing for tm coordinates");
    only_keys(*t, source, "projection.tm", {"lat0_deg", "lon0_deg", "k0", "false_easting_m", "false_northing_m"});
    for (const char* key : {"lat0_deg", "lon0_deg", "k0", "false_easting_m", "false_northing_m"}) {
      if (!member(*t, key, source, "projection.tm")) fail(source, std::string("projection.tm.") + key, "missing");
    }
    geodesy::TransverseMercatorParams p;
    p.lat0 = geodesy::Angle::degrees(number((*t)["lat0_deg"], source, "projection.tm.lat0_deg", -90, 90, "[-90, 90]"));
    p.lon0 = geodesy::Angle::degrees(number((*t)["lon0_deg"], source, "projection.tm.lon0_deg", -180, 180, "[-180, 180]"));
    p.k0 = number((*t)["k0"], source, "projection.tm.k0", 0.5, 1.5, "[0.5, 1.5]");
    p.false_easting_m = number((*t)["false_easting_m"], source, "projection.tm.false_easting_m", -1e8, 1e8, "[-1e8, 1e8] m");
    p.false_northing_m = number((*t)["false_northing_m"], source, "projection.tm.false_northing_m", -1e8, 1e8, "[-1e8, 1e8] m");
    m.coordinates.projection = geodesy::ProjectionDef{m.coordinates.ellipsoid, p, std::nullopt};
  }
}

void read_vertical(const json& v, TileMetadata& m, std::string_view source) {
  only_keys(v, source, "vertical", {"datum", "height_type", "geoid_model"});
  if (const json* d = member(v, "datum", source, "vertical")) m.vertical_datum = text(*d, source, "vertical.datum");
  if (const json* ht = member(v, "height_type", source, "vertical")) {
    m.height_type = text(*ht, source, "vertical.height_type");
    if (m.height_type != "ellipsoidal" && m.height_type != "orthometric") {
      fail(source, "vertical.height_type", "value \"" + m.height_type + "\" unknown; expected ellipsoidal or orthometric");
    }
  }
  if (const json* g = member_or_null(v, "geoid_model")) m.geoid_model = text(*g, source, "vertical.geoid_model");
}

void heights_from_crs(TileMetadata& m, std::string_view source) {
  // The CRS states its heights: the sidecar's labels may repeat them,
  // never contradict them (horizontal_crs is a label for readers).
  const TileMetadata c = tile_metadata_from_crs(*m.crs, source);
  const std::string what = " but the CRS " + m.crs->display_name() + " says ";
  if (!m.height_type.empty() && m.height_type != c.height_type) {
    fail(source, "vertical.height_type",
         "\"" + m.height_type + "\"" + what +
             (c.height_type.empty() ? "it has no height axis (2-D: its Z values are no heights)" : "\"" + c.height_type + "\""));
  }
  if (!m.vertical_datum.empty() && m.vertical_datum != c.vertical_datum) {
    fail(source, "vertical.datum", "\"" + m.vertical_datum + "\"" + what +
                                       (c.vertical_datum.empty() ? "none" : "\"" + c.vertical_datum + "\""));
  }
  if (m.geoid_model && m.geoid_model != c.geoid_model) {
    fail(source, "vertical.geoid_model", "\"" + *m.geoid_model + "\"" + what +
                                             (c.geoid_model ? "\"" + *c.geoid_model + "\"" : "none (no orthometric heights)"));
  }
  m.height_type = c.height_type;
  m.vertical_datum = c.vertical_datum;
  m.geoid_model = c.geoid_model;
}

void read_provenance(const json* p, TileMetadata& m, std::string_view source) {
  if (!p->is_object()) fail(source, "provenance", "expected a JSON object");
  // apply's record of how the tile was made: kept as is, and written only,
  // except the keys apply reads back to decide whether an output is up to
  // date (a value of the wrong type there would make it compare wrongly).
  const std::pair<const char*, const char*> resume_keys[] = {
      {"input_sha256", "a string"}, {"transform_sha256", "a string or null"}, {"request", "an object"},
      {"output_size_bytes", "a byte count"}, {"points", "a point count"}, {"output_sha256", "a string"}};
  for (const auto& [key, expected] : resume_keys) {
    const auto it = p->find(key);
    if (it == p->end()) continue;
    const std::string_view name(key);
    const bool ok = name == "input_sha256" || name == "output_sha256" ? it->is_string()
                    : name == "transform_sha256" ? it->is_string() || it->is_null()
                    : name == "request"          ? it->is_object()
                                                 : it->is_number_unsigned();
    if (!ok) fail(source, std::string("provenance.") + key, "value " + it->dump() + " is not " + expected);
  }
  m.provenance_json = p->dump();
}

// A geoanchor.tile/2 sidecar's map metadata contract, held to the sidecar's own keys.
void read_contract(const json& j, TileMetadata& m, std::string_view source) {
  const json* meta = member(j, "metadata", source, "");
  if (!meta) fail(source, "metadata", "missing: a geoanchor.tile/2 sidecar carries the map metadata contract");
  m.metadata = parse_map_metadata(meta->dump(), std::string(source) + ": metadata");
  // The contract says what the sidecar's own keys say: each of those
  // fields is the same, never "unknown" beside a stated value.
  MapMetadataBuilder b{std::string(source)};
  tile_contract_fields(b, m, "the sidecar's own keys");
  const MapMetadata& own = b.metadata();
  const MapMetadata& c = *m.metadata;
  const auto unknown_beside = [&](bool own_known, bool contract_known, const char* key) {
    if (own_known && !contract_known) fail(source, std::string("metadata.") + key, "\"unknown\" but the sidecar states it");
  };
  unknown_beside(own.frame.has_value(), c.frame.has_value(), "frame");
  unknown_beside(own.coordinate_epoch.has_value(), c.coordinate_epoch.has_value(), "coordinate_epoch");
  unknown_beside(own.enu_origin.has_value(), c.enu_origin.has_value(), "enu_origin");
  unknown_beside(own.enu_origin_source.has_value(), c.enu_origin_source.has_value(), "enu_origin_source");
  unknown_beside(own.horizontal_crs.has_value(), c.horizontal_crs.has_value(), "horizontal_crs");
  unknown_beside(own.vertical_datum.has_value(), c.vertical_datum.has_value(), "vertical_datum");
  unknown_beside(own.geoid_model.has_value(), c.geoid_model.has_value(), "geoid_model");
  unknown_beside(own.rtk_fixed_percent.has_value(), c.rtk_fixed_percent.has_value(), "rtk_fixed_percent");
  unknown_beside(own.coordinate_storage.has_value(), c.coordinate_storage.has_value(), "coordinate_storage");
  const std::string who = "its metadata";
  if (c.frame) b.frame(*c.frame, who);
  if (c.coordinate_epoch) b.coordinate_epoch(*c.coordinate_epoch, who);
  if (c.coordinate_epoch_range && own.coordinate_epoch) b.coordinate_epoch_range(*c.coordinate_epoch_range, who);
  if (c.enu_origin && own.enu_origin) b.enu_origin(*c.enu_origin, who);
  using T = MapMetadataBuilder::Text;
  if (c.enu_origin_source && own.enu_origin_source) b.text(T::enu_origin_source, *c.enu_origin_source, who);
  if (c.horizontal_crs) b.text(T::horizontal_crs, *c.horizontal_crs, who);
  if (c.vertical_datum) b.text(T::vertical_datum, *c.vertical_datum, who);
  if (c.geoid_model && own.geoid_model) b.text(T::geoid_model, *c.geoid_model, who);
  if (c.coordinate_storage) b.text(T::coordinate_storage, *c.coordinate_storage, who);
  if (c.rtk_fixed_percent) b.rtk_fixed_percent(*c.rtk_fixed_percent, who, false);
}

}  // namespace

std::string kind_name(const ArrayFrame& f) {
  switch (f.kind) {
    case CoordinateKind::ecef: return "ecef";
    case CoordinateKind::geodetic: return "geodetic";
    case CoordinateKind::enu: return "enu";
    case CoordinateKind::ned: return "ned";
    case CoordinateKind::projected: return f.projection && f.projection->utm ? "utm" : "tm";
  }
  return "?";
}

std::string kind_name(const TileMetadata& m) { return m.crs ? "crs" : kind_name(m.coordinates); }

std::filesystem::path sidecar_path(const std::filesystem::path& tile) {
  return std::filesystem::path(tile.string() + ".geoanchor.json");
}

TileMetadata read_tile_metadata(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(ErrorKind::io, "E_READ", path.string() + ": cannot open tile metadata");
  std::ostringstream s;
  s << in.rdbuf();
  return parse_tile_metadata(s.str(), path.string());
}

TileMetadata parse_tile_metadata(std::string_view text_in, std::string_view source) {
  const json j = parse_json_strict<json>(text_in, source);
  const json* schema = member(j, "schema", source, "");
  const std::string schema_text = schema && schema->is_string() ? schema->get<std::string>() : std::string();
  const bool v2 = schema_text == kTileSchema;
  if (!v2 && schema_text != kTileSchemaV1) {
    fail(source, "schema", std::string("expected \"") + std::string(kTileSchema) + "\" (or \"" +
                               std::string(kTileSchemaV1) + "\")" +
                               (schema ? ", got " + schema->dump() : std::string(", the key is missing")));
  }
  std::set<std::string> top = {"schema", "frame", "coordinates", "enu_origin", "projection", "crs", "horizontal_crs",
                               "vertical", "survey", "provenance"};
  if (v2) top.insert("metadata");
  only_keys(j, source, "", top);
  TileMetadata m;
  const json* frame = member(j, "frame", source, "");
  const json* coords_for_kind = member(j, "coordinates", source, "");
  const bool crs_kind = coords_for_kind && coords_for_kind->is_object() && coords_for_kind->contains("kind") &&
                        (*coords_for_kind)["kind"] == "crs";
  if (!frame && !crs_kind) {
    fail(source, "frame", "missing: the tile's datum, realization and epoch, e.g. \"ITRF2014@2024.5\"");
  }
  if (frame) m.frame = geodesy::Frame::parse(text(*frame, source, "frame"), std::string(source) + ": frame");
  const json* crs = member(j, "crs", source, "");
  if (crs && !crs_kind) fail(source, "crs", "given for coordinates that are not of kind \"crs\"; remove it or say kind \"crs\"");
  if (crs_kind) read_crs(crs, m, source);

  const json* coords = member(j, "coordinates", source, "");
  if (!coords) fail(source, "coordinates", "missing: {\"kind\", \"ellipsoid\", \"storage\"}");
  only_keys(*coords, source, "coordinates", {"kind", "ellipsoid", "storage"});
  const json* kind = member(*coords, "kind", source, "coordinates");
  if (!kind) fail(source, "coordinates.kind", "missing; expected enu, ned, ecef, geodetic, utm or tm");
  const std::string k = text(*kind, source, "coordinates.kind");
  if (k == "crs" && coords->contains("ellipsoid")) {
    fail(source, "coordinates.ellipsoid", "given for kind \"crs\", whose CRS states its ellipsoid; remove it");
  }
  if (k == "crs") {
    // The CRS says it all.
  } else if (const json* e = member(*coords, "ellipsoid", source, "coordinates")) {
    m.coordinates.ellipsoid = ellipsoid(*e, source);
  } else if (k != "ecef") {
    fail(source, "coordinates.ellipsoid", "missing for " + k + " coordinates; expected WGS84, GRS80 or {\"a_m\", \"rf\"}");
  }
  if (const json* st = member(*coords, "storage", source, "coordinates")) {
    m.storage = text(*st, source, "coordinates.storage");
    if (m.storage != "float64" && m.storage != "float32" && m.storage != "int32_scaled") {
      fail(source, "coordinates.storage", "value \"" + m.storage + "\" unknown; expected float64, float32 or int32_scaled");
    }
  }

  const json* origin = member(j, "enu_origin", source, "");
  const json* projection = member(j, "projection", source, "");
  if (k == "enu" || k == "ned") {
    read_enu_origin(origin, k, m, source);
  } else if (k == "ecef" || k == "crs") {
    m.coordinates.kind = CoordinateKind::ecef;
  } else if (k == "geodetic") {
    m.coordinates.kind = CoordinateKind::geodetic;
  } else if (k == "utm" || k == "tm") {
    read_projection(projection, k, m, source);
  } else {
    fail(source, "coordinates.kind", "value \"" + k + "\" unknown; expected enu, ned, ecef, geodetic, utm, tm or crs");
  }
  if (origin && !m.coordinates.origin) fail(source, "enu_origin", "given for " + k + " coordinates, which have none");
  if (projection && !m.coordinates.projection) fail(source, "projection", "given for " + k + " coordinates, which have none");

  if (const json* hc = member(j, "horizontal_crs", source, "")) m.horizontal_crs = text(*hc, source, "horizontal_crs");
  if (const json* v = member(j, "vertical", source, "")) read_vertical(*v, m, source);
  if (m.crs) heights_from_crs(m, source);
  const bool has_heights = m.coordinates.kind == CoordinateKind::geodetic || m.coordinates.kind == CoordinateKind::projected;
  if (has_heights && m.height_type.empty()) {
    fail(source, "vertical.height_type",
         "missing for " + k + " coordinates: heights must be labelled \"ellipsoidal\" or \"orthometric\"");
  }
  if (m.height_type == "orthometric" && !m.geoid_model) {
    fail(source, "vertical.geoid_model", "missing: orthometric heights need the geoid model that relates them");
  }
  if (const json* s = member(j, "survey", source, "")) {
    only_keys(*s, source, "survey", {"method", "rtk_fixed_percent"});
    if (const json* me = member(*s, "method", source, "survey")) m.survey_method = text(*me, source, "survey.method");
    if (const json* r = member(*s, "rtk_fixed_percent", source, "survey")) {
      m.rtk_fixed_percent = number(*r, source, "survey.rtk_fixed_percent", 0, 100, "[0, 100] %");
    }
  }
  if (const json* p = member(j, "provenance", source, "")) read_provenance(p, m, source);
  if (v2) read_contract(j, m, source);
  return m;
}

bool is_origin_label(const std::string& source) {
  return source.empty() || source == "--origin" || source == "--from-origin" || source == "LAS WKT";
}

void tile_contract_fields(MapMetadataBuilder& b, const TileMetadata& m, const std::string& who) {
  using T = MapMetadataBuilder::Text;
  if (m.frame) {
    b.frame(m.frame->name(), who);
    if (m.frame->epoch()) b.coordinate_epoch(m.frame->epoch()->year, who);
  }
  if (m.coordinates.origin && !m.crs) {
    const auto& o = m.coordinates.origin->point;
    b.enu_origin(MetadataOrigin{o.lat.deg(), o.lon.deg(), o.h.m}, who);
    if (!is_origin_label(m.origin_source)) b.text(T::enu_origin_source, m.origin_source, who);
  }
  if (!m.horizontal_crs.empty()) b.text(T::horizontal_crs, m.horizontal_crs, who);
  if (!m.vertical_datum.empty()) b.text(T::vertical_datum, m.vertical_datum, who);
  if (m.geoid_model) b.text(T::geoid_model, *m.geoid_model, who);
  b.text(T::coordinate_storage, coordinate_storage_text(kind_name(m), m.storage), who);
  if (m.rtk_fixed_percent) b.rtk_fixed_percent(*m.rtk_fixed_percent, who, false);
}

std::string to_json_text(const TileMetadata& m) {
  nlohmann::ordered_json j;
  j["schema"] = m.metadata ? kTileSchema : kTileSchemaV1;
  if (m.frame) j["frame"] = m.frame->to_string();
  if (m.crs) {
    j["coordinates"] = {{"kind", "crs"}, {"storage", m.storage}};
    const std::string wkt = m.crs->wkt2();
    if (const auto problem = utf8_problem(wkt)) {
      throw Error(ErrorKind::input, "E_CRS_NOT_UTF8",
                  "the tile's CRS " + m.crs->display_name() + " has text that is not valid UTF-8 (" + *problem +
                      "): a sidecar holds UTF-8 only");
    }
    nlohmann::ordered_json c = {{"wkt2", wkt}};
    if (m.crs->epoch()) c["coordinate_epoch"] = m.crs->epoch()->year;
    j["crs"] = c;
  } else {
    j["coordinates"] = {{"kind", kind_name(m.coordinates)},
                        {"ellipsoid", ellipsoid_json(m.coordinates.ellipsoid)},
                        {"storage", m.storage}};
  }
  if (m.coordinates.origin) {
    const auto& o = *m.coordinates.origin;
    j["enu_origin"] = {{"lat_deg", o.point.lat.deg()},
                       {"lon_deg", o.point.lon.deg()},
                       {"h_m", o.point.h.m},
                       {"height_type", "ellipsoidal"},
                       {"source", m.origin_source}};
  }
  if (m.coordinates.projection) {
    const auto& p = *m.coordinates.projection;
    if (p.utm) {
      j["projection"] = {{"utm_zone", p.utm->to_string()}};
    } else {
      j["projection"] = {{"tm",
                          {{"lat0_deg", p.tm.lat0.deg()},
                           {"lon0_deg", p.tm.lon0.deg()},
                           {"k0", p.tm.k0},
                           {"false_easting_m", p.tm.false_easting_m},
                           {"false_northing_m", p.tm.false_northing_m}}}};
    }
  }
  if (!m.horizontal_crs.empty()) {
    // The name may come from a tile's WKT, bytes of any encoding: JSON holds
    // UTF-8 only, and a rewritten name would be another CRS's.
    if (const auto problem = utf8_problem(m.horizontal_crs)) {
      throw Error(ErrorKind::input, "E_CRS_NOT_UTF8",
                  "horizontal_crs '" + m.horizontal_crs + "' (the tile's CRS name) is not valid UTF-8 (" + *problem +
                      "): a sidecar holds UTF-8 only");
    }
    j["horizontal_crs"] = m.horizontal_crs;
  }
  nlohmann::ordered_json v = nlohmann::ordered_json::object();
  if (!m.vertical_datum.empty()) v["datum"] = m.vertical_datum;
  if (!m.height_type.empty()) v["height_type"] = m.height_type;
  v["geoid_model"] = m.geoid_model ? nlohmann::ordered_json(*m.geoid_model) : nlohmann::ordered_json(nullptr);
  j["vertical"] = v;
  if (!m.survey_method.empty() || m.rtk_fixed_percent) {
    nlohmann::ordered_json s = nlohmann::ordered_json::object();
    if (!m.survey_method.empty()) s["method"] = m.survey_method;
    if (m.rtk_fixed_percent) s["rtk_fixed_percent"] = *m.rtk_fixed_percent;
    j["survey"] = s;
  }
  if (m.metadata) j["metadata"] = nlohmann::ordered_json::parse(map_metadata_json_text(*m.metadata));
  if (!m.provenance_json.empty()) j["provenance"] = nlohmann::ordered_json::parse(m.provenance_json);
  return j.dump(2) + "\n";
}

}  // namespace geoanchor::io
