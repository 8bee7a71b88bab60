// Lanelet2 OSM XML maps through a PointChain (vector_map.hpp): each node's
// lat/lon attributes and its local_x, local_y and ele tags are rewritten in
// place; every other byte of the file is kept.

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "tile/tile_common.hpp"
#include "vector/vector_map_internal.hpp"
#include "xml_edit.hpp"
#include "xml_stream.hpp"

namespace geoanchor::io {
namespace {

using detail::TextSpan;

// One coordinate value as written in the file.
struct Value {
  TextSpan span;
  double v = 0.0;
  std::size_t line = 0;
  bool present = false;
};

struct Node {
  std::string id;
  std::size_t line = 0;
  Value lat, lon, x, y, ele;
};

using detail::attribute;

class OsmReader : public detail::XmlHandler {
 public:
  OsmReader(std::string_view text, std::string source) : text_(text), source_(std::move(source)) {}
  void parse() { stream_.parse(text_, source_, "E_OSM"); }

  std::vector<Node> nodes;
  std::optional<std::array<Value, 4>> bounds;  // minlat, minlon, maxlat, maxlon

  void start_element(const std::string& name, const XML_Char** attrs) override {
    ++depth_;
    if (depth_ == 1) {
      if (name != "osm") fail("the root element is <" + name + ">; expected <osm> (OSM XML, as Lanelet2 writes it)");
      return;
    }
    if (depth_ == 2 && name == "node") {
      Node n;
      n.line = stream_.line();
      const char* id = attribute(attrs, "id");
      if (!id) fail("a <node> without an id");
      n.id = id;
      n.lat = number(attrs, "lat", "node " + n.id, true);
      n.lon = number(attrs, "lon", "node " + n.id, true);
      nodes.push_back(std::move(n));
      in_node_ = true;
      return;
    }
    if (depth_ == 2 && name == "bounds") {
      std::array<Value, 4> b;
      const char* names[] = {"minlat", "minlon", "maxlat", "maxlon"};
      for (int k = 0; k < 4; ++k) b[static_cast<std::size_t>(k)] = number(attrs, names[k], "<bounds>", true);
      bounds = b;
      return;
    }
    if (depth_ == 3 && in_node_ && name == "tag") {
      const char* k = attribute(attrs, "k");
      if (!k) return;
      const std::string key = k;
      Node& n = nodes.back();
      Value* slot = key == "local_x" ? &n.x : key == "local_y" ? &n.y : key == "ele" ? &n.ele : nullptr;
      if (!slot) return;
      if (slot->present) fail("node " + n.id + ": the tag " + key + " is given twice");
      *slot = number(attrs, "v", "node " + n.id + " tag " + key, true);
    }
  }
  void end_element(const std::string& name) override {
    if (depth_ == 2 && name == "node") in_node_ = false;
    --depth_;
  }
  void character_data(const char*, std::size_t) override {}

 private:
  [[noreturn]] void fail(const std::string& problem) const {
    throw Error(ErrorKind::input, "E_OSM", source_ + ":" + std::to_string(stream_.line()) + ": " + problem);
  }
  // A numeric attribute, its span in the start tag being handled.
  Value number(const XML_Char** attrs, const char* name, const std::string& what, bool required) {
    Value v;
    v.line = stream_.line();
    const detail::AttributeContext at{text_, stream_.byte_index(), stream_.byte_count(), source_, v.line, "E_OSM",
                                      "geoanchor rewrites plain numbers only",
                                      std::string_view(name) == "v" ? " (metres)" : " (degrees or metres)"};
    if (const auto read = detail::finite_attribute_number(at, name, attribute(attrs, name), what, required)) {
      v.span = read->first;
      v.v = read->second;
      v.present = true;
    }
    return v;
  }

  std::string_view text_;
  std::string source_;
  detail::XmlStream stream_{*this};
  int depth_ = 0;
  bool in_node_ = false;
};

double number_in(std::string_view text, std::size_t& at, std::string_view where, std::string_view value) {
  const auto comma = text.find(',', at);
  const std::string_view part = text.substr(at, comma == std::string_view::npos ? std::string_view::npos : comma - at);
  at = comma == std::string_view::npos ? text.size() : comma + 1;
  const auto d = parse_finite_double(part);
  if (!d) {
    throw Error(ErrorKind::usage, "E_OPTION",
                std::string(where) + " " + std::string(value) + ": '" + std::string(part) + "' is no finite number");
  }
  return *d;
}

}  // namespace

LocalXy parse_local_xy(std::string_view text, std::string_view where) {
  LocalXy l;
  l.text = std::string(text);
  const auto colon = text.find(':');
  const std::string_view kind = text.substr(0, colon);
  const std::string_view rest = colon == std::string_view::npos ? std::string_view() : text.substr(colon + 1);
  std::vector<double> v;
  auto bad = [&](const std::string& why) {
    return Error(ErrorKind::usage, "E_OPTION",
                 std::string(where) + " " + std::string(text) + ": " + why +
                     "; expected lanelet2-utm:LAT,LON (Lanelet2's UtmProjector origin), utm:ZONE[,E0,N0] or "
                     "tm:LAT0,LON0,K0,FE,FN (all on WGS 84, as Lanelet2 projects)");
  };
  const auto wgs84 = geodesy::Ellipsoid::wgs84();
  if (kind == "lanelet2-utm") {
    std::size_t at = 0;
    while (at < rest.size()) v.push_back(number_in(rest, at, where, text));
    if (v.size() != 2) throw bad("give the origin's latitude and longitude");
    const geodesy::GeodeticPosition origin{geodesy::Angle::degrees(v[0]), geodesy::Angle::degrees(v[1]), {}};
    const auto zone = geodesy::standard_utm_zone(origin);
    if (!zone) throw bad("the origin lies outside UTM's latitudes");
    l.projection = geodesy::utm_projection(wgs84, *zone);
    const auto p = geodesy::TransverseMercator(l.projection).try_forward(origin);
    if (!p) throw bad("the origin has no UTM position");
    l.e0_m = p->easting_m;
    l.n0_m = p->northing_m;
    return l;
  }
  if (kind == "utm") {
    const auto comma = rest.find(',');
    const auto zone = geodesy::parse_utm_zone(rest.substr(0, comma), where);
    l.projection = geodesy::utm_projection(wgs84, zone);
    if (comma != std::string_view::npos) {
      std::size_t at = comma + 1;
      while (at < rest.size()) v.push_back(number_in(rest, at, where, text));
      if (v.size() != 2) throw bad("give E0 and N0, or neither");
      l.e0_m = v[0];
      l.n0_m = v[1];
    }
    return l;
  }
  if (kind == "tm") {
    std::size_t at = 0;
    while (at < rest.size()) v.push_back(number_in(rest, at, where, text));
    if (v.size() != 5) throw bad("a TM needs five values");
    if (!(std::abs(v[0]) <= 90.0) || !(std::abs(v[1]) <= 180.0) || !(v[2] > 0.0)) {
      throw bad("latitude in [-90, 90], longitude in [-180, 180] and a positive scale factor");
    }
    l.projection = geodesy::ProjectionDef{
        wgs84, {geodesy::Angle::degrees(v[0]), geodesy::Angle::degrees(v[1]), v[2], v[3], v[4]}, std::nullopt};
    return l;
  }
  throw bad("unknown kind '" + std::string(kind) + "'");
}

TileApplyResult apply_osm_map(const std::filesystem::path& in, std::ostream& out, const std::string& out_name,
                              const PointChain& chain, const TileApplyOptions& o) {
  const std::string source = in.string();
  const std::string text = detail::read_whole_file(in);
  OsmReader reader(text, source);
  reader.parse();
  const auto& nodes = reader.nodes;
  const std::size_t n = nodes.size();
  auto name_of = [&](std::size_t i) { return source + ":" + std::to_string(nodes[i].line) + ": node " + nodes[i].id; };

  // The local projection of local_x/local_y, and whether the tags agree
  // with lat/lon before anything moves.
  std::optional<LocalXy> local;
  std::optional<geodesy::TransverseMercator> tm;
  if (o.local_xy) {
    local = parse_local_xy(*o.local_xy, "--local-xy");
    tm.emplace(local->projection);
  }
  auto project = [&](double lat, double lon, double& x, double& y) {
    const auto p = tm->try_forward(geodesy::GeodeticPosition{geodesy::Angle::degrees(lat), geodesy::Angle::degrees(lon), {}});
    x = p ? p->easting_m - local->e0_m : std::nan("");
    y = p ? p->northing_m - local->n0_m : std::nan("");
  };
  std::size_t with_local = 0, without_ele = 0, first_without_ele = 0;
  double worst_before = 0.0;
  std::size_t worst_at = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Node& nd = nodes[i];
    if (!(std::abs(nd.lat.v) <= 90.0) || !(std::abs(nd.lon.v) <= 180.0)) {
      throw Error(ErrorKind::input, "E_RANGE",
                  name_of(i) + ": lat=" + format_shortest(nd.lat.v) + ", lon=" + format_shortest(nd.lon.v) +
                      ": not in [-90, 90] / [-180, 180] degrees");
    }
    if (!nd.ele.present && without_ele++ == 0) first_without_ele = i;
    if (nd.x.present != nd.y.present) {
      throw Error(ErrorKind::input, "E_OSM_LOCAL_XY",
                  name_of(i) + ": has " + (nd.x.present ? "local_x" : "local_y") + " without " +
                      (nd.x.present ? "local_y" : "local_x") + "; a node has both or neither");
    }
    if (!nd.x.present) continue;
    if (!local) {
      throw Error(ErrorKind::usage, "E_OSM_LOCAL_XY",
                  name_of(i) + ": has local_x/local_y tags, whose projection the file does not say; give --local-xy "
                               "lanelet2-utm:LAT,LON (Lanelet2's UtmProjector origin), utm:ZONE[,E0,N0] (e.g. an MGRS "
                               "square's corner) or tm:LAT0,LON0,K0,FE,FN, so that they are moved with lat/lon");
    }
    ++with_local;
    double x = 0.0, y = 0.0;
    project(nd.lat.v, nd.lon.v, x, y);
    const double d = std::hypot(x - nd.x.v, y - nd.y.v);
    if (!(d <= worst_before)) worst_before = d, worst_at = i;
  }
  if (with_local > 0 && !(worst_before <= o.local_xy_tolerance_m)) {
    const Node& nd = nodes[worst_at];
    double x = 0.0, y = 0.0;
    project(nd.lat.v, nd.lon.v, x, y);
    throw Error(ErrorKind::input, "E_OSM_LOCAL_XY",
                name_of(worst_at) + ": local_x=" + format_shortest(nd.x.v) + ", local_y=" + format_shortest(nd.y.v) +
                    " disagree with lat/lon by " + format_shortest(worst_before) + " m (--local-xy " + local->text +
                    " gives " + format_fixed(x, 4) + ", " + format_fixed(y, 4) + "; tolerance --local-xy-tolerance " +
                    format_shortest(o.local_xy_tolerance_m) +
                    " m): the map's local projection is another, or the map contradicts itself; nothing was written");
  }

  // Chain order (lat, lon, h); a node without ele is moved at h = 0.
  std::vector<double> a(n), b(n), c(n);
  for (std::size_t i = 0; i < n; ++i) {
    a[i] = nodes[i].lat.v;
    b[i] = nodes[i].lon.v;
    c[i] = nodes[i].ele.present ? nodes[i].ele.v : 0.0;
  }
  detail::Bounds in_bounds, out_bounds;
  in_bounds.add(a, b, c);
  const ChainReport report = detail::move_points(chain, o, a, b, c, nullptr, name_of);
  if (const std::size_t bad = detail::first_non_finite(a, b, c); bad < n) {
    throw Error(ErrorKind::input, "E_TRANSFORM",
                name_of(bad) + ": the node has no finite position in the output frame" +
                    detail::refusal_reason(report, bad) + "; nothing was written");
  }
  std::vector<detail::TextEdit> edits;
  edits.reserve(n * 5);
  for (std::size_t i = 0; i < n; ++i) {
    const Node& nd = nodes[i];
    edits.push_back({nd.lat.span.at, nd.lat.span.length, detail::plain_number(a[i])});
    edits.push_back({nd.lon.span.at, nd.lon.span.length, detail::plain_number(b[i])});
    if (nd.ele.present) edits.push_back({nd.ele.span.at, nd.ele.span.length, detail::plain_number(c[i])});
    if (nd.x.present) {
      double x = 0.0, y = 0.0;
      project(a[i], b[i], x, y);
      if (!std::isfinite(x) || !std::isfinite(y)) {
        throw Error(ErrorKind::input, "E_PROJECTION_DOMAIN",
                    name_of(i) + ": the moved node has no position on --local-xy " + local->text + "; nothing was written");
      }
      edits.push_back({nd.x.span.at, nd.x.span.length, detail::plain_number(x)});
      edits.push_back({nd.y.span.at, nd.y.span.length, detail::plain_number(y)});
    }
    const double file[3] = {b[i], a[i], c[i]};  // lon, lat, ele
    out_bounds.add(std::span<const double>(&file[0], 1), std::span<const double>(&file[1], 1),
                   std::span<const double>(&file[2], 1));
  }
  // <bounds>: its corners moved at the nodes' mean height.
  if (reader.bounds) {
    const auto& bd = *reader.bounds;
    double mean_h = 0.0;
    for (std::size_t i = 0; i < n; ++i) mean_h += nodes[i].ele.present ? nodes[i].ele.v : 0.0;
    if (n > 0) mean_h /= static_cast<double>(n);
    double ba[2] = {bd[0].v, bd[2].v}, bb[2] = {bd[1].v, bd[3].v}, bc[2] = {mean_h, mean_h};
    // Not points of the map: apply's reach outside the control is measured on the nodes.
    TileApplyOptions corners = o;
    corners.inspect_input = nullptr;
    corners.inspect_output = nullptr;
    detail::move_points(chain, corners, ba, bb, bc, nullptr, [&](std::size_t) { return source + ": <bounds>"; });
    if (detail::first_non_finite(ba, bb, bc) < 2) {
      throw Error(ErrorKind::input, "E_TRANSFORM", source + ": <bounds> has no finite position in the output frame");
    }
    const double moved[4] = {ba[0], bb[0], ba[1], bb[1]};
    for (std::size_t k = 0; k < 4; ++k) edits.push_back({bd[k].span.at, bd[k].span.length, detail::plain_number(moved[k])});
  }
  detail::write_with_edits(out, text, std::move(edits));
  if (!out) throw Error(ErrorKind::io, "E_WRITE", out_name + ": write failed");

  TileApplyResult r = detail::whole_map_result(o, source, n, report, in_bounds, out_bounds, name_of);
  if (without_ele > 0) {
    r.warnings.push_back(source + ": " + std::to_string(without_ele) + " of " + std::to_string(n) +
                         " nodes have no ele tag (the first " + name_of(first_without_ele) +
                         "): they were moved at h = 0 m on the ellipsoid and no ele was added; their horizontal "
                         "result is off by about the transform's rotation times their true height");
  }
  nlohmann::ordered_json record = {{"nodes", n}, {"nodes_without_ele", without_ele}, {"nodes_with_local_xy", with_local}};
  if (local) {
    record["local_xy"] = {{"projection", local->text},
                          {"ellipsoid", "WGS84"},
                          {"tolerance_m", o.local_xy_tolerance_m},
                          {"largest_difference_before_m", with_local ? nlohmann::ordered_json(worst_before) : nullptr}};
  }
  record["bounds_moved"] = reader.bounds.has_value();
  r.format_record_json = record.dump();
  return r;
}

}  // namespace geoanchor::io
