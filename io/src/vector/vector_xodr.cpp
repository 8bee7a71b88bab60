// OpenDRIVE maps re-anchored through a PointChain (vector_map.hpp).
//
// A map's road geometry is parametric (lines, arcs, spirals, cubic
// polynomials) in a plane; the header's <offset> places that plane in the
// projection of its <geoReference>:
//   E = x_o + cos(hdg_o)·x − sin(hdg_o)·y,  N = y_o + sin(hdg_o)·x + cos(hdg_o)·y,
//   h = z + z_o
// (the dataset translated by x, y, z and rotated by hdg about the new
// origin, ASAM OpenDRIVE 1.6/1.7 "offset"; the rotation as ASAM OSI's
// ProjFrameOffset writes it). Moving the map exactly would bend its
// geometry; instead geoanchor samples every road's reference line, moves
// the samples exactly, and fits the rigid placement (translation, heading,
// height) that comes closest (least squares): the new <offset>. The largest
// distance between a re-anchored sample and its exactly moved position is
// the re-anchoring's deviation; beyond the tolerance the map is refused.

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <numbers>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "tile/tile_common.hpp"
#include "vector/vector_map_internal.hpp"
#include "xml_edit.hpp"
#include "xml_stream.hpp"

namespace geoanchor::io {
namespace {

using detail::TextSpan;

// Samples along each geometry at most this far apart, plus its ends: the
// deviation of an affine move is largest at the ends of the map, which
// every geometry's end samples hold.
constexpr double kSampleStep_m = 1.0;
constexpr double kPi = std::numbers::pi;
// A longer geometry is no road (and would be a billion samples).
constexpr double kMaxGeometryLength_m = 1e6;

struct Value {
  TextSpan span;
  double v = 0.0;
  bool present = false;
};

enum class GeomKind { none, line, arc, spiral, poly3, param_poly3 };

struct Geometry {
  double s = 0, x = 0, y = 0, hdg = 0, length = 0;
  GeomKind kind = GeomKind::none;
  double k = 0;                 // arc: curvature (1/m)
  double c0 = 0, c1 = 0;        // spiral: curvature at start and end
  double a = 0, b = 0, c = 0, d = 0;  // poly3: v(u)
  std::array<double, 8> uv{};   // paramPoly3: aU bU cU dU aV bV cV dV
  bool normalized = false;      // paramPoly3 pRange
  std::size_t line = 0;
};

struct Elevation {
  double s = 0, a = 0, b = 0, c = 0, d = 0;
};

struct Road {
  std::string id;
  std::size_t line = 0;
  std::vector<Geometry> geometries;
  std::vector<Elevation> elevations;
};

using detail::attribute;

class XodrReader : public detail::XmlHandler {
 public:
  XodrReader(std::string_view text, std::string source) : text_(text), source_(std::move(source)) {}
  void parse() { stream_.parse(text_, source_, "E_XODR"); }

  bool has_geo_reference = false;
  std::string geo_reference;       // its text (CDATA or not)
  TextSpan geo_reference_element;  // from '<geoReference' to the end of '</geoReference>'
  std::size_t geo_reference_line = 0;
  bool has_offset = false;
  TextSpan offset_tag;
  Value ox, oy, oz, ohdg;
  std::vector<Road> roads;

  void start_element(const std::string& name, const XML_Char** attrs) override {
    path_.push_back(name);
    const std::size_t depth = path_.size();
    const std::string parent = depth >= 2 ? path_[depth - 2] : std::string();
    const bool in_road = depth >= 3 && path_[1] == "road" && !roads.empty();
    if (depth == 1) {
      if (name != "OpenDRIVE") fail("the root element is <" + name + ">; expected <OpenDRIVE>");
      return;
    }
    if (depth == 3 && parent == "header" && name == "geoReference") {
      if (has_geo_reference) fail("a second <geoReference>");
      has_geo_reference = true;
      in_geo_reference_ = true;
      geo_reference_line = stream_.line();
      geo_reference_element.at = stream_.byte_index();
      geo_reference_start_length_ = stream_.byte_count();
      return;
    }
    if (depth == 3 && parent == "header" && name == "offset") {
      if (has_offset) fail("a second <offset> in <header>");
      has_offset = true;
      offset_tag = {stream_.byte_index(), stream_.byte_count()};
      ox = number(attrs, "x", "<offset>", false);
      oy = number(attrs, "y", "<offset>", false);
      oz = number(attrs, "z", "<offset>", false);
      ohdg = number(attrs, "hdg", "<offset>", false);
      return;
    }
    if (depth == 2 && name == "road") {
      Road r;
      const char* id = attribute(attrs, "id");
      if (!id) fail("a <road> without an id");
      r.id = id;
      r.line = stream_.line();
      roads.push_back(std::move(r));
      return;
    }
    if (in_road && depth == 4 && parent == "planView" && name == "geometry") {
      Geometry g;
      g.line = stream_.line();
      const std::string what = "road " + roads.back().id + " <geometry>";
      g.s = number(attrs, "s", what).v;
      g.x = number(attrs, "x", what).v;
      g.y = number(attrs, "y", what).v;
      g.hdg = number(attrs, "hdg", what).v;
      g.length = number(attrs, "length", what).v;
      if (!(g.length >= 0.0 && g.length <= kMaxGeometryLength_m)) {
        fail(what + ": length=" + format_shortest(g.length) + ": expected 0 to 1000 km (metres); it is sampled every " +
             format_shortest(kSampleStep_m) + " m");
      }
      roads.back().geometries.push_back(g);
      return;
    }
    if (in_road && depth == 5 && parent == "geometry" && path_[2] == "planView") {
      Geometry& g = roads.back().geometries.back();
      const std::string what = "road " + roads.back().id + " <" + name + ">";
      if (name == "userData" || name == "include" || name == "dataQuality") return;
      if (g.kind != GeomKind::none) fail("road " + roads.back().id + ": a <geometry> with two shapes (<" + name + ">)");
      if (name == "line") {
        g.kind = GeomKind::line;
      } else if (name == "arc") {
        g.kind = GeomKind::arc;
        g.k = number(attrs, "curvature", what).v;
      } else if (name == "spiral") {
        g.kind = GeomKind::spiral;
        g.c0 = number(attrs, "curvStart", what).v;
        g.c1 = number(attrs, "curvEnd", what).v;
      } else if (name == "poly3") {
        g.kind = GeomKind::poly3;
        g.a = number(attrs, "a", what).v;
        g.b = number(attrs, "b", what).v;
        g.c = number(attrs, "c", what).v;
        g.d = number(attrs, "d", what).v;
      } else if (name == "paramPoly3") {
        g.kind = GeomKind::param_poly3;
        const char* names[] = {"aU", "bU", "cU", "dU", "aV", "bV", "cV", "dV"};
        for (std::size_t i = 0; i < 8; ++i) g.uv[i] = number(attrs, names[i], what).v;
        const char* range = attribute(attrs, "pRange");
        const std::string pr = range ? range : "normalized";
        if (pr != "arcLength" && pr != "normalized") fail(what + ": pRange='" + pr + "': expected arcLength or normalized");
        g.normalized = pr == "normalized";
      } else {
        throw Error(ErrorKind::input, "E_XODR_GEOMETRY",
                    source_ + ":" + std::to_string(stream_.line()) + ": road " + roads.back().id +
                        ": unknown geometry element <" + name +
                        ">; expected <line>, <arc>, <spiral>, <poly3> or <paramPoly3> (OpenDRIVE 1.6/1.7)");
      }
      return;
    }
    if (in_road && depth == 4 && parent == "elevationProfile" && name == "elevation") {
      const std::string what = "road " + roads.back().id + " <elevation>";
      Elevation e;
      e.s = number(attrs, "s", what).v;
      e.a = number(attrs, "a", what).v;
      e.b = number(attrs, "b", what).v;
      e.c = number(attrs, "c", what).v;
      e.d = number(attrs, "d", what).v;
      roads.back().elevations.push_back(e);
    }
  }

  void end_element(const std::string& name) override {
    const std::size_t depth = path_.size();
    if (depth == 3 && name == "geoReference" && in_geo_reference_) {
      in_geo_reference_ = false;
      const std::size_t count = stream_.byte_count();
      const std::uint64_t end = count ? stream_.byte_index() + count : geo_reference_element.at + geo_reference_start_length_;
      geo_reference_element.length = static_cast<std::size_t>(end - geo_reference_element.at);
    }
    if (depth == 4 && name == "geometry" && path_[1] == "road" && path_[2] == "planView" && !roads.empty() &&
        !roads.back().geometries.empty() && roads.back().geometries.back().kind == GeomKind::none) {
      throw Error(ErrorKind::input, "E_XODR_GEOMETRY",
                  source_ + ":" + std::to_string(roads.back().geometries.back().line) + ": road " + roads.back().id +
                      ": a <geometry> without its shape; expected <line>, <arc>, <spiral>, <poly3> or <paramPoly3>");
    }
    path_.pop_back();
  }

  void character_data(const char* s, std::size_t n) override {
    if (in_geo_reference_) geo_reference.append(s, n);
  }

 private:
  [[noreturn]] void fail(const std::string& problem) const {
    throw Error(ErrorKind::input, "E_XODR", source_ + ":" + std::to_string(stream_.line()) + ": " + problem);
  }
  Value number(const XML_Char** attrs, const char* name, const std::string& what, bool required = true) {
    Value v;
    const detail::AttributeContext at{text_, stream_.byte_index(), stream_.byte_count(), source_, stream_.line(), "E_XODR",
                                      "expected a plain number", ""};
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
  std::vector<std::string> path_;
  bool in_geo_reference_ = false;
  std::size_t geo_reference_start_length_ = 0;
};

// ------------------------------------------------------------ geometry

// 5-point Gauss–Legendre on [0, 1].
constexpr std::array<double, 5> kGlNodes = {0.04691007703066800, 0.23076534494715845, 0.5, 0.76923465505284155,
                                            0.95308992296933200};
constexpr std::array<double, 5> kGlWeights = {0.11846344252809454, 0.23931433524968324, 0.28444444444444444,
                                              0.23931433524968324, 0.11846344252809454};

template <class F>
double integrate(F f, double t0, double t1) {
  double sum = 0.0;
  for (std::size_t i = 0; i < 5; ++i) sum += kGlWeights[i] * f(t0 + (t1 - t0) * kGlNodes[i]);
  return sum * (t1 - t0);
}

struct Sample {
  double x, y, s;  // map plane, and s along the road
};

// Samples of one geometry (its start, its end, and at most kSampleStep_m
// apart), in the map's plane.
void sample_geometry(const Geometry& g, std::vector<Sample>& out) {
  const double L = g.length;
  const std::size_t n = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(L / kSampleStep_m)));
  const double ch = std::cos(g.hdg), sh = std::sin(g.hdg);
  auto local = [&](double u, double v, double s) { out.push_back({g.x + ch * u - sh * v, g.y + sh * u + ch * v, s}); };
  switch (g.kind) {
    case GeomKind::none:
    case GeomKind::line:
      for (std::size_t k = 0; k <= n; ++k) {
        const double t = L * static_cast<double>(k) / static_cast<double>(n);
        local(t, 0.0, g.s + t);
      }
      return;
    case GeomKind::arc:
      for (std::size_t k = 0; k <= n; ++k) {
        const double t = L * static_cast<double>(k) / static_cast<double>(n);
        if (std::abs(g.k * t) < 1e-12) {
          local(t, 0.0, g.s + t);
        } else {
          // x = sin(k t)/k, y = (1 - cos(k t))/k in the start's frame.
          local(std::sin(g.k * t) / g.k, (1.0 - std::cos(g.k * t)) / g.k, g.s + t);
        }
      }
      return;
    case GeomKind::spiral: {
      // Heading θ(t) = c0·t + (c1 − c0)·t²/(2L) from the start's; position
      // ∫ (cos θ, sin θ) dt, Gauss–Legendre over each step (the Fresnel
      // integrals of the clothoid, to 1e-12 m per metre of step).
      const double dc = L > 0.0 ? (g.c1 - g.c0) / L : 0.0;
      auto theta = [&](double t) { return g.c0 * t + 0.5 * dc * t * t; };
      double u = 0.0, v = 0.0;
      local(0.0, 0.0, g.s);
      for (std::size_t k = 1; k <= n; ++k) {
        const double t0 = L * static_cast<double>(k - 1) / static_cast<double>(n);
        const double t1 = L * static_cast<double>(k) / static_cast<double>(n);
        u += integrate([&](double t) { return std::cos(theta(t)); }, t0, t1);
        v += integrate([&](double t) { return std::sin(theta(t)); }, t0, t1);
        local(u, v, g.s + t1);
      }
      return;
    }
    case GeomKind::poly3: {
      // v(u) in the start's frame; the geometry ends where its arc length
      // reaches `length`.
      auto v = [&](double t) { return g.a + t * (g.b + t * (g.c + t * g.d)); };
      auto ds = [&](double t) {
        const double dv = g.b + t * (2.0 * g.c + 3.0 * g.d * t);
        return std::sqrt(1.0 + dv * dv);
      };
      double u = 0.0, s = 0.0;
      local(0.0, v(0.0), g.s);
      while (s < L) {
        const double step = kSampleStep_m;
        const double grow = integrate(ds, u, u + step);
        if (s + grow < L) {
          u += step;
          s += grow;
          local(u, v(u), g.s + s);
          continue;
        }
        double lo = 0.0, hi = step;  // the last step, cut where s reaches L
        for (int it = 0; it < 60; ++it) {
          const double mid = 0.5 * (lo + hi);
          (s + integrate(ds, u, u + mid) < L ? lo : hi) = mid;
        }
        u += 0.5 * (lo + hi);
        s = L;
        local(u, v(u), g.s + s);
      }
      return;
    }
    case GeomKind::param_poly3: {
      const auto& c = g.uv;
      const double P = g.normalized ? 1.0 : L;
      auto uu = [&](double p) { return c[0] + p * (c[1] + p * (c[2] + p * c[3])); };
      auto vv = [&](double p) { return c[4] + p * (c[5] + p * (c[6] + p * c[7])); };
      auto ds = [&](double p) {
        const double du = c[1] + p * (2.0 * c[2] + 3.0 * c[3] * p), dv = c[5] + p * (2.0 * c[6] + 3.0 * c[7] * p);
        return std::sqrt(du * du + dv * dv);
      };
      double s = 0.0;
      local(uu(0.0), vv(0.0), g.s);
      for (std::size_t k = 1; k <= n; ++k) {
        const double p0 = P * static_cast<double>(k - 1) / static_cast<double>(n);
        const double p1 = P * static_cast<double>(k) / static_cast<double>(n);
        s += integrate(ds, p0, p1);
        local(uu(p1), vv(p1), g.s + s);
      }
      return;
    }
  }
}

// The road's elevation at s (0 without an elevation profile).
double elevation_at(const Road& r, double s) {
  const auto it = std::upper_bound(r.elevations.begin(), r.elevations.end(), s + 1e-9,
                                   [](double x, const Elevation& e) { return x < e.s; });
  if (it == r.elevations.begin()) return r.elevations.empty() ? 0.0 : r.elevations.front().a;
  const Elevation& e = *(it - 1);
  const double t = s - e.s;
  return e.a + t * (e.b + t * (e.c + t * e.d));
}

// The double nearest to `v` rounded to `decimals` decimals (through text,
// so that 47.45 from PROJ's radians is the double "47.45" reads as).
double round_to(double v, int decimals) { return parse_finite_double(format_fixed(v, decimals)).value_or(v); }

std::string trimmed(std::string s) {
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  const auto last = s.find_last_not_of(" \t\r\n");
  return s.substr(first, last - first + 1);
}

// Every road's reference line, sampled: the samples in the plane, their
// heights, and the road each is on.
struct RoadSamples {
  std::vector<Sample> plane;
  std::vector<double> z;
  std::vector<std::size_t> road_of;
  std::size_t geometries = 0;
};

RoadSamples sample_roads(const XodrReader& reader) {
  RoadSamples out;
  std::vector<Sample>& plane = out.plane;
  std::vector<double>& z = out.z;
  std::vector<std::size_t>& road_of = out.road_of;
  std::size_t& geometries = out.geometries;
  for (std::size_t r = 0; r < reader.roads.size(); ++r) {
    const Road& road = reader.roads[r];
    for (const auto& g : road.geometries) {
      const std::size_t first = plane.size();
      sample_geometry(g, plane);
      ++geometries;
      for (std::size_t k = first; k < plane.size(); ++k) {
        z.push_back(elevation_at(road, plane[k].s));
        road_of.push_back(r);
      }
    }
  }
  return out;
}

// The new header's edits: the geoReference when the projection's ellipsoid
// or parameters change (`geo_reference_after`), and the offset's `values`.
std::vector<detail::TextEdit> header_edits(const XodrReader& reader, const std::string& text, const TileApplyOptions& o,
                                           const std::pair<const char*, double> (&values)[4],
                                           std::string& geo_reference_after) {
  std::vector<detail::TextEdit> edits;
  if (o.to.projection && o.from.projection && !(*o.to.projection == *o.from.projection)) {
    geo_reference_after = xodr_geo_reference(*o.to.projection);
    edits.push_back({reader.geo_reference_element.at, reader.geo_reference_element.length,
                     "<geoReference><![CDATA[" + geo_reference_after + "]]></geoReference>"});
  }
  if (reader.has_offset) {
    const Value* have[4] = {&reader.ox, &reader.oy, &reader.oz, &reader.ohdg};
    const auto insert_at = detail::attribute_insert_point(text, reader.offset_tag.at, reader.offset_tag.length);
    for (std::size_t k = 0; k < 4; ++k) {
      const std::string v = detail::plain_number(values[k].second);
      if (have[k]->present) {
        edits.push_back({have[k]->span.at, have[k]->span.length, v});
      } else {
        edits.push_back({insert_at, 0, std::string(" ") + values[k].first + "=\"" + v + "\""});
      }
    }
  } else {
    // After the geoReference, indented as it is.
    const std::uint64_t at = reader.geo_reference_element.at;
    const auto line_start = text.rfind('\n', static_cast<std::size_t>(at));
    std::string indent = line_start == std::string::npos ? std::string() : text.substr(line_start + 1, static_cast<std::size_t>(at) - line_start - 1);
    if (indent.find_first_not_of(" \t") != std::string::npos) indent.clear();
    std::string element = "\n" + indent + "<offset";
    for (const auto& [name, v] : values) element += std::string(" ") + name + "=\"" + detail::plain_number(v) + "\"";
    element += "/>";
    edits.push_back({at + reader.geo_reference_element.length, 0, element});
  }
  return edits;
}

}  // namespace

std::string xodr_geo_reference(const geodesy::ProjectionDef& p) {
  const auto& e = p.ellipsoid;
  const std::string ellps = e == geodesy::Ellipsoid::grs80()   ? "+ellps=GRS80"
                            : e == geodesy::Ellipsoid::wgs84() ? "+ellps=WGS84"
                                                               : "+a=" + format_shortest(e.a_m()) + " +rf=" + format_shortest(e.rf());
  if (p.utm) {
    return "+proj=utm +zone=" + std::to_string(p.utm->number) +
           (p.utm->hemisphere == geodesy::Hemisphere::south ? " +south" : "") + " " + ellps + " +units=m +no_defs";
  }
  return "+proj=tmerc +lat_0=" + format_shortest(p.tm.lat0.deg()) + " +lon_0=" + format_shortest(p.tm.lon0.deg()) +
         " +k=" + format_shortest(p.tm.k0) + " +x_0=" + format_shortest(p.tm.false_easting_m) +
         " +y_0=" + format_shortest(p.tm.false_northing_m) + " " + ellps + " +units=m +no_defs";
}

namespace detail {

VectorMapStatement xodr_statement(const std::filesystem::path& map) {
  const std::string source = map.string();
  const std::string text = read_whole_file(map);
  XodrReader reader(text, source);
  reader.parse();
  auto refuse = [&](const std::string& problem) {
    return Error(ErrorKind::input, "E_XODR_GEOREFERENCE",
                 source + (reader.geo_reference_line ? ":" + std::to_string(reader.geo_reference_line) : std::string()) +
                     ": " + problem);
  };
  const std::string g = trimmed(reader.geo_reference);
  if (!reader.has_geo_reference || g.empty()) {
    throw refuse("no <header><geoReference>: the map's plane is placed on the Earth by nothing; geoanchor re-anchors "
                 "maps whose geoReference is a Transverse Mercator or UTM PROJ string");
  }
  const std::string definition = g[0] == '+' && g.find("+type=crs") == std::string::npos ? g + " +type=crs" : g;
  std::optional<Crs> crs;
  try {
    crs = Crs::parse(definition, source + ": geoReference");
  } catch (const Error& e) {
    throw refuse("geoReference '" + g + "': " + e.what());
  }
  const auto& d = crs->description();
  if (d.type != "projected") {
    throw refuse("geoReference '" + g + "' is a " + d.type + " CRS" +
                 (d.type == "compound" ? " (heights through a geoid)" : "") +
                 "; geoanchor re-anchors OpenDRIVE maps on a Transverse Mercator or UTM projection with ellipsoidal "
                 "heights");
  }
  if (d.projection_method_code != "EPSG:9807") {
    throw refuse("geoReference '" + g + "' uses the projection method '" + d.projection_method +
                 "'; geoanchor re-anchors OpenDRIVE maps on Transverse Mercator (EPSG:9807) or UTM only");
  }
  const auto& axes = d.visualization_axes.empty() ? d.axes : d.visualization_axes;
  if (axes.size() < 2 || axes[0].direction != "east" || axes[1].direction != "north" || axes[0].unit_to_si != 1.0 ||
      axes[1].unit_to_si != 1.0 || d.prime_meridian_deg != 0.0) {
    throw refuse("geoReference '" + g + "': expected easting and northing in metres on Greenwich");
  }
  std::optional<double> lat0, lon0, k0, fe, fn;
  for (const auto& p : d.projection_parameters) {
    const bool angle = p.unit_name == "degree", metre = p.unit_name == "metre", unity = p.unit_name == "unity";
    if (p.epsg_code == "8801" && angle) lat0 = round_to(p.value, 12);
    if (p.epsg_code == "8802" && angle) lon0 = round_to(p.value, 12);
    if (p.epsg_code == "8805" && unity) k0 = round_to(p.value, 15);
    if (p.epsg_code == "8806" && metre) fe = round_to(p.value, 9);
    if (p.epsg_code == "8807" && metre) fn = round_to(p.value, 9);
  }
  if (!lat0 || !lon0 || !k0 || !fe || !fn) {
    throw refuse("geoReference '" + g + "': PROJ gives no latitude/longitude of origin, scale, false easting and "
                                        "northing in degrees, unity and metres");
  }
  const geodesy::Ellipsoid e = typed_ellipsoid(d.ellipsoid);
  geodesy::ProjectionDef def{e, {geodesy::Angle::degrees(*lat0), geodesy::Angle::degrees(*lon0), *k0, *fe, *fn}, std::nullopt};
  const bool utm_named = g.find("+proj=utm") != std::string::npos || d.name.find("UTM zone") != std::string::npos;
  if (utm_named) {
    const int zone = static_cast<int>(std::lround((*lon0 + 183.0) / 6.0));
    const geodesy::UtmZone z{zone, *fn > 0.0 ? geodesy::Hemisphere::south : geodesy::Hemisphere::north};
    const auto u = geodesy::utm_projection(e, z);
    if (zone >= 1 && zone <= 60 && u.tm.lat0 == def.tm.lat0 && u.tm.lon0 == def.tm.lon0 && u.tm.k0 == def.tm.k0 &&
        u.tm.false_easting_m == def.tm.false_easting_m && u.tm.false_northing_m == def.tm.false_northing_m) {
      def = u;
    }
  }
  TileMetadata m;
  m.coordinates.kind = CoordinateKind::projected;
  m.coordinates.ellipsoid = e;
  m.coordinates.projection = def;
  m.height_type = "ellipsoidal";
  m.vertical_datum = "ellipsoid " + e.name();
  m.horizontal_crs = "OpenDRIVE geoReference " + g;
  m.storage = "float64";
  return {std::move(m), "OpenDRIVE geoReference"};
}

}  // namespace detail

TileApplyResult apply_xodr_map(const std::filesystem::path& in, std::ostream& out, const std::string& out_name,
                               const PointChain& chain, const TileApplyOptions& o) {
  const std::string source = in.string();
  const std::string text = detail::read_whole_file(in);
  XodrReader reader(text, source);
  reader.parse();
  if (!reader.has_geo_reference) {
    throw Error(ErrorKind::input, "E_XODR_GEOREFERENCE", source + ": no <header><geoReference>");
  }
  const double ox = reader.ox.v, oy = reader.oy.v, oz = reader.oz.v, ohdg = reader.ohdg.v;
  const double co = std::cos(ohdg), so = std::sin(ohdg);

  // Every road's reference line, sampled.
  const RoadSamples samples = sample_roads(reader);
  const std::vector<Sample>& plane = samples.plane;
  const std::vector<double>& z = samples.z;
  const std::vector<std::size_t>& road_of = samples.road_of;
  const std::size_t geometries = samples.geometries;
  const std::size_t n = plane.size();
  if (n == 0) {
    throw Error(ErrorKind::input, "E_XODR_GEOMETRY", source + ": no road has a <planView> geometry; nothing to re-anchor");
  }
  auto name_of = [&](std::size_t i) {
    return source + ": road " + reader.roads[road_of[i]].id + " at s = " + format_fixed(plane[i].s, 3) + " m";
  };
  // Into the projection (chain order easting, northing, h), then moved exactly.
  std::vector<double> a(n), b(n), c(n);
  for (std::size_t i = 0; i < n; ++i) {
    a[i] = ox + co * plane[i].x - so * plane[i].y;
    b[i] = oy + so * plane[i].x + co * plane[i].y;
    c[i] = z[i] + oz;
    if (!std::isfinite(a[i]) || !std::isfinite(b[i]) || !std::isfinite(c[i])) {
      throw Error(ErrorKind::input, "E_NON_FINITE", name_of(i) + ": the road geometry has no finite position");
    }
  }
  detail::Bounds in_bounds, out_bounds;
  in_bounds.add(a, b, c);
  const ChainReport report = detail::move_points(chain, o, a, b, c, nullptr, name_of);
  if (const std::size_t bad = detail::first_non_finite(a, b, c); bad < n) {
    throw Error(ErrorKind::input, "E_TRANSFORM",
                name_of(bad) + ": the sample has no finite position in the output frame" +
                    detail::refusal_reason(report, bad) + "; nothing was written");
  }

  // The rigid placement closest to the moved samples (least squares, about
  // the centroids): heading θ, translation t, height offset.
  long double px = 0, py = 0, qx = 0, qy = 0, dz = 0;
  for (std::size_t i = 0; i < n; ++i) {
    px += plane[i].x, py += plane[i].y, qx += a[i], qy += b[i], dz += c[i] - z[i];
  }
  const long double nn = static_cast<long double>(n);
  px /= nn, py /= nn, qx /= nn, qy /= nn, dz /= nn;
  long double sxx = 0, sxy = 0, syx = 0, syy = 0;
  double min_x = HUGE_VAL, max_x = -HUGE_VAL, min_y = HUGE_VAL, max_y = -HUGE_VAL;
  for (std::size_t i = 0; i < n; ++i) {
    const long double ux = plane[i].x - px, uy = plane[i].y - py, vx = a[i] - qx, vy = b[i] - qy;
    sxx += ux * vx, sxy += ux * vy, syx += uy * vx, syy += uy * vy;
    min_x = std::min(min_x, plane[i].x), max_x = std::max(max_x, plane[i].x);
    min_y = std::min(min_y, plane[i].y), max_y = std::max(max_y, plane[i].y);
  }
  const double theta = static_cast<double>(std::atan2(sxy - syx, sxx + syy));
  const double ct = std::cos(theta), st = std::sin(theta);
  const double tx = static_cast<double>(qx - (ct * px - st * py));
  const double ty = static_cast<double>(qy - (st * px + ct * py));
  const double new_z = static_cast<double>(dz);
  double worst = 0.0, worst_h = 0.0, worst_v = 0.0;
  std::size_t worst_at = 0;
  for (std::size_t i = 0; i < n; ++i) {
    // The re-anchored sample (what the file holds, and its bounds are the
    // output's: audit reads them back) against the exactly moved one.
    const double rx = tx + ct * plane[i].x - st * plane[i].y, ry = ty + st * plane[i].x + ct * plane[i].y, rz = z[i] + new_z;
    out_bounds.add(std::span<const double>(&rx, 1), std::span<const double>(&ry, 1), std::span<const double>(&rz, 1));
    const double ex = rx - a[i];
    const double ey = ry - b[i];
    const double ev = rz - c[i];
    const double dh = std::hypot(ex, ey), d = std::hypot(dh, ev);
    worst_h = std::max(worst_h, dh);
    worst_v = std::max(worst_v, std::abs(ev));
    if (!(d <= worst)) worst = d, worst_at = i;
  }
  const double extent = std::hypot(max_x - min_x, max_y - min_y);
  if (!(worst <= o.max_deviation_m)) {
    throw Error(ErrorKind::rejected, "E_XODR_NOT_RIGID",
                source + ": the re-anchored map would deviate from the exactly moved road geometry by " +
                    format_fixed(worst * 1000.0, 2) + " mm at road " + reader.roads[road_of[worst_at]].id +
                    ", s = " + format_fixed(plane[worst_at].s, 3) + " m (largest horizontal " +
                    format_fixed(worst_h * 1000.0, 2) + " mm, vertical " + format_fixed(worst_v * 1000.0, 2) +
                    " mm; " + std::to_string(n) + " samples along " + std::to_string(reader.roads.size()) +
                    " roads), beyond --max-deviation " + format_shortest(o.max_deviation_m) +
                    " m: an OpenDRIVE <offset> can only shift, turn and raise the map, and the transform is not "
                    "rigid enough over this map's extent (" + format_fixed(extent / 1000.0, 2) +
                    " km across; a scale difference of s moves the ends by about s times half of it); nothing "
                    "was written");
  }

  // The new header: the geoReference when the projection's ellipsoid or
  // parameters change, and the offset.
  std::string geo_reference_after = trimmed(reader.geo_reference);
  double hdg = std::remainder(theta, 2.0 * kPi);
  if (hdg == -kPi) hdg = kPi;
  const std::pair<const char*, double> values[4] = {{"x", tx}, {"y", ty}, {"z", new_z}, {"hdg", hdg}};
  std::vector<detail::TextEdit> edits = header_edits(reader, text, o, values, geo_reference_after);
  detail::write_with_edits(out, text, std::move(edits));
  if (!out) throw Error(ErrorKind::io, "E_WRITE", out_name + ": write failed");

  TileApplyResult r = detail::whole_map_result(o, source, n, report, in_bounds, out_bounds, name_of);
  using J = nlohmann::ordered_json;
  const J record = {
      {"roads", reader.roads.size()},
      {"geometries", geometries},
      {"samples", n},
      {"sample_step_m", kSampleStep_m},
      {"geo_reference_before", trimmed(reader.geo_reference)},
      {"geo_reference_after", geo_reference_after},
      {"offset_before", {{"x", ox}, {"y", oy}, {"z", oz}, {"hdg", ohdg}}},
      {"offset_after", {{"x", tx}, {"y", ty}, {"z", new_z}, {"hdg", hdg}}},
      {"offset_convention", "E = x + cos(hdg)*u - sin(hdg)*v, N = y + sin(hdg)*u + cos(hdg)*v, h = z + w"},
      {"max_deviation_m", worst},
      {"max_horizontal_deviation_m", worst_h},
      {"max_vertical_deviation_m", worst_v},
      {"at", {{"road", reader.roads[road_of[worst_at]].id}, {"s_m", plane[worst_at].s}}},
      {"tolerance_m", o.max_deviation_m},
      {"map_extent_m", extent},
      {"heights", "OpenDRIVE z plus the offset's z, read as ellipsoidal heights on the geoReference's ellipsoid"}};
  r.format_record_json = record.dump();
  return r;
}

}  // namespace geoanchor::io
