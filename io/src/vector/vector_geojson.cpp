// GeoJSON maps through a PointChain (vector_map.hpp): every position of
// every geometry moved, every other member kept, "bbox" recomputed, the
// frame recorded in the foreign member "geoanchor".

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/json_input.hpp"
#include "json_fields.hpp"
#include "tile/tile_common.hpp"
#include "vector/vector_map_internal.hpp"

namespace geoanchor::io {
namespace {

using Json = nlohmann::ordered_json;

constexpr char kMember[] = "geoanchor";
constexpr char kNote[] =
    "RFC 7946 positions name no datum realization or epoch; this member and the sidecar say which (written by "
    "geoanchor apply)";

[[noreturn]] void fail(const std::string& source, const std::string& path, const std::string& problem,
                       const char* code = "E_GEOJSON") {
  throw Error(ErrorKind::input, code, source + ": " + (path.empty() ? std::string() : path + ": ") + problem);
}

std::string type_of(const Json& j, const std::string& source, const std::string& path) {
  if (!j.is_object()) fail(source, path, "expected a GeoJSON object, got " + std::string(j.type_name()));
  const auto it = j.find("type");
  if (it == j.end() || !it->is_string()) fail(source, path, "no \"type\" string member; every GeoJSON object has one");
  return it->get<std::string>();
}

// Every position of a map, in file order, and the objects with a bbox.
struct Positions {
  std::vector<Json*> at;
  std::vector<std::string> path;
  struct Box {
    Json* bbox;
    std::size_t first, end;
    std::string path;
  };
  std::vector<Box> boxes;
};

class Walker {
 public:
  Walker(std::string source, Positions& out) : source_(std::move(source)), out_(out) {}

  void object(Json& j, const std::string& path) {
    const std::string type = type_of(j, source_, path);
    const std::size_t first = out_.at.size();
    const std::string here = path.empty() ? std::string() : path + ".";
    if (type == "FeatureCollection") {
      auto f = j.find("features");
      if (f == j.end() || !f->is_array()) fail(source_, path, "a FeatureCollection needs a \"features\" array");
      for (std::size_t i = 0; i < f->size(); ++i) {
        const std::string p = here + "features[" + std::to_string(i) + "]";
        if (type_of((*f)[i], source_, p) != "Feature") fail(source_, p, "a FeatureCollection holds Features only");
        object((*f)[i], p);
      }
    } else if (type == "Feature") {
      auto g = j.find("geometry");
      if (g == j.end()) fail(source_, path, "a Feature needs a \"geometry\" member (null when it has none)");
      if (!g->is_null()) geometry(*g, here + "geometry");
    } else {
      geometry(j, path);  // records its own bbox
      return;
    }
    box(j, path, first);
  }

 private:
  void box(Json& j, const std::string& path, std::size_t first) {
    auto b = j.find("bbox");
    if (b == j.end()) return;
    const std::string p = (path.empty() ? std::string() : path + ".") + "bbox";
    if (!b->is_array() || (b->size() != 4 && b->size() != 6)) fail(source_, p, "expected an array of 4 or 6 numbers");
    for (const auto& v : *b) {
      if (!v.is_number()) fail(source_, p, "expected numbers");
    }
    out_.boxes.push_back({&*b, first, out_.at.size(), p});
  }

  void geometry(Json& g, const std::string& path) {
    const std::string type = type_of(g, source_, path);
    const std::size_t first = out_.at.size();
    const std::string here = path.empty() ? std::string() : path + ".";
    int depth = -1;
    if (type == "Point") depth = 0;
    if (type == "MultiPoint" || type == "LineString") depth = 1;
    if (type == "MultiLineString" || type == "Polygon") depth = 2;
    if (type == "MultiPolygon") depth = 3;
    if (type == "GeometryCollection") {
      auto gs = g.find("geometries");
      if (gs == g.end() || !gs->is_array()) fail(source_, path, "a GeometryCollection needs a \"geometries\" array");
      for (std::size_t i = 0; i < gs->size(); ++i) geometry((*gs)[i], here + "geometries[" + std::to_string(i) + "]");
    } else if (depth < 0) {
      fail(source_, path + (path.empty() ? "" : ".") + "type",
           "'" + type + "': expected FeatureCollection, Feature, Point, MultiPoint, LineString, MultiLineString, "
                        "Polygon, MultiPolygon or GeometryCollection (RFC 7946)");
    } else {
      auto c = g.find("coordinates");
      if (c == g.end()) fail(source_, path, "a " + type + " needs a \"coordinates\" member");
      coordinates(*c, depth, here + "coordinates");
    }
    box(g, path, first);
  }

  void coordinates(Json& c, int depth, const std::string& path) {
    if (!c.is_array()) fail(source_, path, "expected an array, got " + std::string(c.type_name()));
    if (depth == 0) {
      if (c.size() < 2 || c.size() > 3) {
        fail(source_, path,
             "a position of " + std::to_string(c.size()) +
                 " numbers; expected [longitude, latitude] or [longitude, latitude, height] (RFC 7946 3.1.1)");
      }
      for (std::size_t k = 0; k < c.size(); ++k) {
        if (!c[k].is_number()) {
          fail(source_, path + "[" + std::to_string(k) + "]", "expected a number, got " + c[k].dump());
        }
      }
      out_.at.push_back(&c);
      out_.path.push_back(path);
      return;
    }
    for (std::size_t i = 0; i < c.size(); ++i) coordinates(c[i], depth - 1, path + "[" + std::to_string(i) + "]");
  }

  std::string source_;
  Positions& out_;
};

geodesy::Ellipsoid ellipsoid_of(const Json& e, const std::string& source, const std::string& path) {
  if (e.is_string()) {
    const auto name = e.get<std::string>();
    if (name == "GRS80") return geodesy::Ellipsoid::grs80();
    if (name == "WGS84") return geodesy::Ellipsoid::wgs84();
  } else if (e.is_object() && e.size() == 2 && e.contains("a_m") && e.contains("rf") && e["a_m"].is_number() &&
             e["rf"].is_number()) {
    return geodesy::Ellipsoid::custom(e["a_m"].get<double>(), e["rf"].get<double>());
  }
  fail(source, path, e.dump() + ": expected \"GRS80\", \"WGS84\" or {\"a_m\": A, \"rf\": RF}");
}

// The legacy (GeoJSON 2008) "crs" member read through PROJ: nullopt for
// CRS84 and WGS 84's geographic CRSs, which RFC 7946 positions are anyway.
std::optional<Crs> legacy_crs(const Json& c, const std::string& source) {
  const bool named = c.is_object() && c.value("type", Json()) == "name" && c.contains("properties") &&
                     c["properties"].is_object() && c["properties"].contains("name") &&
                     c["properties"]["name"].is_string();
  if (!named) {
    fail(source, "crs",
         c.dump() + ": a legacy crs member geoanchor cannot read; only {\"type\": \"name\", \"properties\": {\"name\": "
                    "\"urn:ogc:def:crs:EPSG::N\"}} is read (through PROJ). RFC 7946 removed \"crs\": remove it if the "
                    "positions are longitude and latitude, and give the frame with --from-frame or a sidecar",
         "E_GEOJSON_CRS");
  }
  const std::string name = c["properties"]["name"].get<std::string>();
  std::optional<Crs> crs;
  try {
    crs = Crs::parse(name, source + ": crs.properties.name");
  } catch (const Error& e) {
    fail(source, "crs.properties.name",
         "'" + name + "': a legacy crs member PROJ cannot read (" + e.what() +
             "); RFC 7946 removed \"crs\": remove it if the positions are longitude and latitude, and give the frame "
             "with --from-frame or a sidecar",
         "E_GEOJSON_CRS");
  }
  const auto& d = crs->description();
  const bool geographic = d.type == "geographic 2D" || d.type == "geographic 3D";
  if (geographic && d.ensemble && d.datum.find("World Geodetic System 1984") != std::string::npos &&
      d.prime_meridian_deg == 0.0) {
    return std::nullopt;  // CRS84 / EPSG:4326 / EPSG:4979: what RFC 7946 positions are
  }
  return crs;
}

}  // namespace

namespace detail {

VectorMapStatement geojson_statement(const std::filesystem::path& map) {
  const std::string source = map.string();
  const Json j = parse_json_strict<Json>(read_whole_file(map), source);
  if (!j.is_object()) fail(source, "", "the top level is no GeoJSON object");
  VectorMapStatement s;
  std::optional<TileMetadata> from_crs;
  if (const auto c = j.find("crs"); c != j.end()) {
    if (auto crs = legacy_crs(*c, source)) {
      from_crs = tile_metadata_from_crs(std::move(*crs), source);
      from_crs->storage = "float64";
    }
  }
  const auto g = j.find(kMember);
  if (g == j.end()) {
    if (from_crs) s = {std::move(from_crs), "GeoJSON 'crs' member"};
    return s;
  }
  if (!g->is_object()) fail(source, kMember, "expected an object (written by geoanchor apply)");
  static const char* const kKeys[] = {"frame", "coordinates", "ellipsoid", "height_type", "crs", "sidecar", "note"};
  if (const auto key = detail::first_unknown_key(*g, kKeys)) {
    fail(source, std::string(kMember) + "." + *key, "unknown key; expected frame, coordinates, ellipsoid, height_type, crs, sidecar, note");
  }
  const auto kind_it = g->find("coordinates");
  if (kind_it != g->end() && !kind_it->is_string()) fail(source, "geoanchor.coordinates", "expected geodetic or crs");
  const std::string kind = kind_it == g->end() ? std::string("geodetic") : kind_it->get<std::string>();
  const auto f = g->find("frame");
  if (kind == "crs") {
    // The CRS states the ellipsoid and the heights: keys that would say so
    // too are refused rather than read and ignored.
    for (const char* k : {"ellipsoid", "height_type"}) {
      if (g->contains(k)) fail(source, std::string(kMember) + "." + k, "not with coordinates 'crs': the crs member's CRS states it");
    }
  }
  if (kind == "crs" && f != g->end() && f->is_null()) {
    if (!from_crs) fail(source, "geoanchor.coordinates", "'crs' but the map has no legacy crs member naming it");
    s = {std::move(from_crs), "GeoJSON 'crs' member"};  // a CRS on a datum outside geoanchor's catalog
    return s;
  }
  if (f == g->end() || !f->is_string()) fail(source, std::string(kMember) + ".frame", "expected a frame NAME@EPOCH");
  const geodesy::Frame frame = geodesy::Frame::parse(f->get<std::string>(), source + ": geoanchor.frame");
  if (kind == "crs") {
    if (!from_crs) fail(source, "geoanchor.coordinates", "'crs' but the map has no legacy crs member naming it");
    if (from_crs->crs->description().dynamic && !from_crs->crs->epoch() && frame.epoch()) {
      from_crs = tile_metadata_from_crs(from_crs->crs->at_epoch(*frame.epoch(), source + ": geoanchor.frame"), source);
      from_crs->storage = "float64";
    }
    if (from_crs->frame && !(*from_crs->frame == frame)) {
      throw Error(ErrorKind::input, "E_FRAME_CONFLICT",
                  source + ": geoanchor.frame " + frame.to_string() + " contradicts the crs member's " +
                      from_crs->frame->to_string());
    }
    s = {std::move(from_crs), "GeoJSON 'crs' and 'geoanchor' members"};
    return s;
  }
  if (kind != "geodetic") fail(source, "geoanchor.coordinates", "'" + kind + "': expected geodetic or crs");
  if (from_crs) fail(source, "crs", "a crs member beside geoanchor.coordinates 'geodetic'; remove one");
  if (g->value("height_type", std::string("ellipsoidal")) != "ellipsoidal") {
    fail(source, "geoanchor.height_type", "expected ellipsoidal (apply moves ellipsoidal heights only)", "E_HEIGHT_TYPE");
  }
  TileMetadata m;
  m.frame = frame;
  m.coordinates.kind = CoordinateKind::geodetic;
  const auto implied = geodesy::implied_ellipsoid(frame);
  if (const auto e = g->find("ellipsoid"); e != g->end()) {
    m.coordinates.ellipsoid = ellipsoid_of(*e, source, "geoanchor.ellipsoid");
    if (implied && !(*implied == m.coordinates.ellipsoid)) {
      fail(source, "geoanchor.ellipsoid",
           m.coordinates.ellipsoid.name() + " contradicts the frame " + frame.to_string() + ", which is on " +
               implied->name(),
           "E_ELLIPSOID");
    }
  } else if (implied) {
    m.coordinates.ellipsoid = *implied;
  } else {
    fail(source, "geoanchor.ellipsoid", "missing; the frame " + frame.to_string() + " implies none");
  }
  m.height_type = "ellipsoidal";
  m.vertical_datum = "ellipsoid " + m.coordinates.ellipsoid.name();
  m.storage = "float64";
  s = {std::move(m), "GeoJSON 'geoanchor' member"};
  return s;
}

}  // namespace detail

TileApplyResult apply_geojson_map(const std::filesystem::path& in, std::ostream& out, const std::string& out_name,
                                  const PointChain& chain, const TileApplyOptions& o) {
  const std::string source = in.string();
  Json j = parse_json_strict<Json>(detail::read_whole_file(in), source);
  Positions pos;
  Walker(source, pos).object(j, "");
  const std::size_t n = pos.at.size();
  // Chain order: (lat, lon, h) for geodetic coordinates; a CRS's axes in
  // its visualisation order (x, y, z as GeoJSON 2008 stores them).
  const bool crs_in = o.file_in.has_value(), crs_out = o.file_out.has_value();
  std::vector<double> a(n), b(n), c(n);
  std::size_t without_height = 0, first_without = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Json& p = *pos.at[i];
    const double x = p[0].get<double>(), y = p[1].get<double>();
    const double z = p.size() > 2 ? p[2].get<double>() : 0.0;
    if (p.size() < 3 && without_height++ == 0) first_without = i;
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
      fail(source, pos.path[i], p.dump() + ": not a finite number", "E_NON_FINITE");
    }
    if (crs_in) {
      a[i] = x, b[i] = y, c[i] = z;
      continue;
    }
    if (!(std::abs(y) <= 90.0) || !(std::abs(x) <= 180.0)) {
      fail(source, pos.path[i], p.dump() + ": longitude not in [-180, 180] or latitude not in [-90, 90] degrees "
                                           "(RFC 7946 positions are [longitude, latitude, height])",
           "E_RANGE");
    }
    a[i] = y, b[i] = x, c[i] = z;
  }
  if (without_height > 0 && o.file_in && o.file_in->has_height) {
    fail(source, pos.path[first_without], "positions without a height in a 3-D CRS; give every position its height", "E_HEIGHT_TYPE");
  }
  detail::Bounds in_bounds, out_bounds;
  in_bounds.add(a, b, c);
  auto name_of = [&](std::size_t i) { return source + ": " + pos.path[i]; };
  const ChainReport report = detail::move_points(chain, o, a, b, c, nullptr, name_of);
  if (const std::size_t bad = detail::first_non_finite(a, b, c); bad < n) {
    throw Error(ErrorKind::input, "E_TRANSFORM",
                name_of(bad) + ": the position has no finite value in the output frame" +
                    detail::refusal_reason(report, bad) + "; nothing was written");
  }
  for (std::size_t i = 0; i < n; ++i) {
    Json& p = *pos.at[i];
    const double x = crs_out ? a[i] : b[i], y = crs_out ? b[i] : a[i];
    p[0] = x;
    p[1] = y;
    if (p.size() > 2) p[2] = c[i];
    const double file[3] = {x, y, c[i]};
    out_bounds.add(std::span<const double>(&file[0], 1), std::span<const double>(&file[1], 1),
                   std::span<const double>(&file[2], 1));
  }
  // Each bbox from the moved positions beneath it (RFC 7946 5: west, south,
  // [low,] east, north[, high]).
  for (const auto& box : pos.boxes) {
    Json& bb = *box.bbox;
    const bool three = bb.size() == 6;
    if (bb[0].get<double>() > bb[three ? 3 : 2].get<double>()) {
      fail(source, box.path, bb.dump() + ": crosses the antimeridian (west > east); geoanchor does not recompute such a "
                                         "bbox; remove it");
    }
    if (box.first == box.end) continue;
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (std::size_t i = box.first; i < box.end; ++i) {
      const Json& p = *pos.at[i];
      for (std::size_t k = 0; k < p.size(); ++k) {
        lo[k] = std::min(lo[k], p[k].get<double>());
        hi[k] = std::max(hi[k], p[k].get<double>());
      }
    }
    if (three && !(lo[2] <= hi[2])) {
      fail(source, box.path, "a bbox with heights over positions without them; remove it or give the heights");
    }
    bb = three ? Json::array({lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]}) : Json::array({lo[0], lo[1], hi[0], hi[1]});
  }
  // The frame: the foreign member (replaced), and a legacy crs member only
  // for an output in a CRS other than WGS 84's longitude and latitude.
  Json member = Json::object();
  member["frame"] = o.output_frame.empty() ? Json(nullptr) : Json(o.output_frame);
  if (o.output_crs) {
    const auto& d = o.output_crs->description();
    const auto colon = d.identifier.find(':');
    if (d.identifier.empty() || colon == std::string::npos || d.identifier.find('+') != std::string::npos) {
      throw Error(ErrorKind::usage, "E_GEOJSON_CRS",
                  source + ": the output CRS " + o.output_crs->display_name() +
                      " has no single authority code to name in a GeoJSON crs member; give --to geodetic (RFC 7946 "
                      "longitude, latitude) or a --to-crs with an EPSG code");
    }
    j["crs"] = {{"type", "name"},
                {"properties",
                 {{"name", "urn:ogc:def:crs:" + d.identifier.substr(0, colon) + "::" + d.identifier.substr(colon + 1)}}}};
    member["coordinates"] = "crs";
    member["crs"] = o.output_crs->display_name();
  } else {
    j.erase("crs");
    member["coordinates"] = "geodetic";
    const auto& e = o.to.ellipsoid;
    member["ellipsoid"] = e == geodesy::Ellipsoid::grs80()   ? Json("GRS80")
                          : e == geodesy::Ellipsoid::wgs84() ? Json("WGS84")
                                                             : Json{{"a_m", e.a_m()}, {"rf", e.rf()}};
    member["height_type"] = "ellipsoidal";
  }
  member["sidecar"] = std::filesystem::path(out_name).filename().string() + ".geoanchor.json";
  member["note"] = kNote;
  j[kMember] = member;
  out << j.dump() << '\n';
  if (!out) throw Error(ErrorKind::io, "E_WRITE", out_name + ": write failed");

  TileApplyResult r = detail::whole_map_result(o, source, n, report, in_bounds, out_bounds, name_of);
  if (without_height > 0) {
    r.warnings.push_back(source + ": " + std::to_string(without_height) + " of " + std::to_string(n) +
                         " positions have no height (the first " + pos.path[first_without] +
                         "): they were moved at h = 0 m on the ellipsoid and written without one; their horizontal "
                         "result is off by about the transform's rotation times their true height (0.5 mm for 1e-6 "
                         "rad at 500 m); write 3-D positions to avoid it");
  }
  const Json record = {{"positions", n},
                       {"positions_without_height", without_height},
                       {"bboxes_recomputed", pos.boxes.size()},
                       {"foreign_member", kMember}};
  r.format_record_json = record.dump();
  return r;
}

}  // namespace geoanchor::io
