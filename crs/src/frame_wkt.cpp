// A coordinate system statement (frame and coordinates, or a CRS) as WKT2:2019, and back through PROJ.

#include <proj.h>

#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <memory>
#include <regex>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/geodesy/physical_range.hpp"
#include "geoanchor/crs/frame_wkt.hpp"
#include "frame_datum_names.hpp"
#include "proj_handles.hpp"
#include "geoanchor/crs/wkt_text.hpp"

namespace geoanchor::io {
namespace {

constexpr char kRemarkPrefix[] = "geoanchor frame ";
constexpr char kEpochRemark[] = "coordinate epoch ";
constexpr double kDegree_rad = 0.0174532925199433;
// Parameters read back from WKT are compared with UTM's after unit
// conversion: 1e-9 degrees and 1e-6 m are far below anything written.
constexpr double kUtmMatchDeg = 1e-9;
constexpr double kUtmMatchM = 1e-6;

std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    out += c;
    if (c == '"') out += '"';  // WKT doubles a quote inside a quoted text
  }
  return out + "\"";
}

std::string ellipsoid_wkt(const geodesy::Ellipsoid& e) {
  const std::string name = e == geodesy::Ellipsoid::wgs84()   ? "WGS 84"
                           : e == geodesy::Ellipsoid::grs80() ? "GRS 1980"
                                                              : e.name();
  return "ELLIPSOID[" + quoted(name) + "," + format_shortest(e.a_m()) + "," + format_shortest(e.rf()) + ",LENGTHUNIT[\"metre\",1]]";
}

const std::string kDegree = "ANGLEUNIT[\"degree\",0.0174532925199433]";
const std::string& kMetre = detail::kWktMetre;
using detail::wkt_parameter;

using detail::CtxDeleter;
using detail::Pj;

[[noreturn]] void fail(std::string_view source, const std::string& problem) {
  throw Error(ErrorKind::input, "E_TILE_CRS", std::string(source) + ": LAS WKT: " + problem);
}

// A CRS that geoanchor's own coordinate kinds do not hold (why): the tile is
// then read as a CRS that PROJ moves.
struct NotTyped {
  std::string why;
};
[[noreturn]] void not_typed(const std::string& why) { throw NotTyped{why}; }

// Refuses a coordinate system whose axes geoanchor would misread: it takes
// a tile's X, Y, Z as the CRS kind's axes in `directions`, in order, each in
// metres or (geographic) degrees. Any other order, direction or unit (a
// State Plane CRS in US survey feet, a grad, a southing) is named; so is a
// prime meridian other than Greenwich. (Issue 13 reads them through PROJ.)
// Returns the number of axes.
int require_understood_axes(PJ_CONTEXT* ctx, PJ* crs, std::string_view crs_name, std::initializer_list<const char*> directions,
                             bool geographic, std::string_view source) {
  constexpr double kUnitMatch = 1e-12;  // relative, of a unit's conversion factor
  Pj cs(proj_crs_get_coordinate_system(ctx, crs));
  const int axes = cs ? proj_cs_get_axis_count(ctx, cs.get()) : -1;
  const std::string what = "'" + std::string(crs_name) + "'";
  if (axes < 0) fail(source, what + ": cannot read its coordinate system");
  std::size_t k = 0;
  for (const char* expected : directions) {
    if (static_cast<int>(k) >= axes) break;
    const char* name = nullptr;
    const char* direction = nullptr;
    const char* unit = nullptr;
    double factor = 0.0;
    if (!proj_cs_get_axis_info(ctx, cs.get(), static_cast<int>(k), &name, nullptr, &direction, &factor, &unit, nullptr,
                               nullptr)) {
      fail(source, what + ": cannot read axis " + std::to_string(k + 1));
    }
    const std::string dir = direction ? direction : "?";
    const bool in_degrees = geographic && k < 2;  // latitude and longitude; the height in metres
    const double expected_factor = in_degrees ? kDegree_rad : 1.0;
    const std::string axis = "axis " + std::to_string(k + 1) + " ('" + (name ? name : "?") + "', " + dir + ", " +
                             (unit ? unit : "?") + ")";
    if (dir != expected) {
      not_typed(what + ": " + axis + ": not the " + expected + " axis of geoanchor's own kinds");
    }
    if (!(std::abs(factor - expected_factor) <= kUnitMatch * expected_factor)) {
      not_typed(what + ": " + axis + ": the unit is not " + (in_degrees ? "the degree" : "the metre"));
    }
    ++k;
  }
  Pj pm(proj_get_prime_meridian(ctx, crs));
  double longitude = 0.0, pm_factor = 0.0;
  const char* pm_unit = nullptr;
  if (pm && proj_prime_meridian_get_parameters(ctx, pm.get(), &longitude, &pm_factor, &pm_unit) && longitude != 0.0) {
    const char* pm_name = proj_get_name(pm.get());
    not_typed(what + ": prime meridian '" + (pm_name ? pm_name : "?") + "' at " + format_shortest(longitude) + " " +
              (pm_unit ? pm_unit : "?") + " from Greenwich");
  }
  return axes;
}

// A conversion parameter in degrees (angles), metres (lengths) or unity,
// taken as written when it is already in that unit so that values round-trip.
double param(PJ_CONTEXT* ctx, PJ* op, int epsg_code, std::string_view source) {
  const int n = proj_coordoperation_get_param_count(ctx, op);
  for (int i = 0; i < n; ++i) {
    const char* name = nullptr;
    const char* auth = nullptr;
    const char* code = nullptr;
    const char* unit = nullptr;
    const char* category = nullptr;
    double value = 0.0, conv = 1.0;
    if (!proj_coordoperation_get_param(ctx, op, i, &name, &auth, &code, &value, nullptr, &conv, &unit, nullptr,
                                       nullptr, &category)) {
      continue;
    }
    if (!code || std::to_string(epsg_code) != code) continue;
    const std::string u = unit ? unit : "";
    const std::string cat = category ? category : "";
    if (cat == "angular") return u == "degree" ? value : value * conv / kDegree_rad;
    return conv == 0.0 || conv == 1.0 ? value : value * conv;
  }
  fail(source, "the projection lacks parameter EPSG:" + std::to_string(epsg_code));
}

}  // namespace

std::string coordinate_system_wkt(const CoordinateSystemStatement& m) {
  if (m.crs) {
    std::string wkt = m.crs->wkt2();
    // PROJ 9.1 writes no coordinate metadata: the epoch goes in a remark,
    // as in geoanchor's own WKTs, which the reader takes it from.
    if (m.crs->epoch() && wkt.find("REMARK[") == std::string::npos && !wkt.empty() && wkt.back() == ']') {
      const std::string epoch = geodesy::format_decimal_year(*m.crs->epoch());
      const std::string& frame = m.crs->description().catalog_frame;
      const std::string text = frame.empty() ? std::string(kEpochRemark) + epoch
                                             : kRemarkPrefix + frame + "@" + epoch + "; " + kEpochRemark + epoch;
      wkt.insert(wkt.size() - 1, ",REMARK[" + quoted(text) + "]");
    }
    return wkt;
  }
  if (!m.frame) throw Error(ErrorKind::usage, "E_FRAME_MISSING", "a tile CRS needs the frame (NAME@EPOCH)");
  if (m.height_type == "orthometric") {
    throw Error(ErrorKind::usage, "E_TILE_CRS",
                "orthometric heights need a compound CRS naming the geoid model; geoanchor writes tiles with "
                "ellipsoidal heights only");
  }
  const ArrayFrame& c = m.coordinates;
  const std::string frame = m.frame->to_string();
  const std::string datum = "DATUM[" + quoted(detail::epsg_datum_name(*m.frame)) + "," + ellipsoid_wkt(c.ellipsoid) + "]," +
                            "PRIMEM[\"Greenwich\",0," + kDegree + "]";
  const std::string remark = ",REMARK[" + quoted(kRemarkPrefix + frame + "; coordinate epoch " +
                                                 (m.frame->epoch() ? geodesy::format_decimal_year(*m.frame->epoch())
                                                                   : std::string("not stated"))) +
                             "]";
  const std::string base = "BASEGEOGCRS[" + quoted(m.frame->name()) + "," + datum + "]";
  const std::string height_axis = "AXIS[\"ellipsoidal height (h)\",up,ORDER[3]," + kMetre + "]";
  switch (c.kind) {
    case CoordinateKind::ecef:
      return "GEODCRS[" + quoted(frame + " geocentric") + "," + datum +
             ",CS[Cartesian,3],AXIS[\"(X)\",geocentricX,ORDER[1]," + kMetre + "],AXIS[\"(Y)\",geocentricY,ORDER[2]," +
             kMetre + "],AXIS[\"(Z)\",geocentricZ,ORDER[3]," + kMetre + "]" + remark + "]";
    case CoordinateKind::geodetic:
      return "GEOGCRS[" + quoted(frame + " geographic 3D") + "," + datum +
             ",CS[ellipsoidal,3],AXIS[\"geodetic latitude (Lat)\",north,ORDER[1]," + kDegree +
             "],AXIS[\"geodetic longitude (Lon)\",east,ORDER[2]," + kDegree + "]," + height_axis + remark + "]";
    case CoordinateKind::enu: {
      const auto& o = *c.origin;
      return "PROJCRS[" + quoted(frame + " ENU") + "," + base +
             ",CONVERSION[\"ENU origin\",METHOD[\"Geographic/topocentric conversions\",ID[\"EPSG\",9837]]" +
             wkt_parameter("Latitude of topocentric origin", o.point.lat.deg(), kDegree, 8834) +
             wkt_parameter("Longitude of topocentric origin", o.point.lon.deg(), kDegree, 8835) +
             wkt_parameter("Ellipsoidal height of topocentric origin", o.point.h.m, kMetre, 8836) +
             "],CS[Cartesian,3],AXIS[\"topocentric East (U)\",east,ORDER[1]," + kMetre +
             "],AXIS[\"topocentric North (V)\",north,ORDER[2]," + kMetre + "],AXIS[\"topocentric height (W)\",up,ORDER[3]," +
             kMetre + "]" + remark + "]";
    }
    case CoordinateKind::projected: {
      const auto& p = *c.projection;
      const std::string conversion_name = p.utm ? "UTM zone " + p.utm->to_string() : "Transverse Mercator";
      return "PROJCRS[" + quoted(frame + " " + conversion_name) + "," + base + ",CONVERSION[" +
             quoted(conversion_name) + ",METHOD[\"Transverse Mercator\",ID[\"EPSG\",9807]]" +
             wkt_parameter("Latitude of natural origin", p.tm.lat0.deg(), kDegree, 8801) +
             wkt_parameter("Longitude of natural origin", p.tm.lon0.deg(), kDegree, 8802) +
             wkt_parameter("Scale factor at natural origin", p.tm.k0, "SCALEUNIT[\"unity\",1]", 8805) +
             wkt_parameter("False easting", p.tm.false_easting_m, kMetre, 8806) +
             wkt_parameter("False northing", p.tm.false_northing_m, kMetre, 8807) +
             "],CS[Cartesian,3],AXIS[\"(E)\",east,ORDER[1]," + kMetre + "],AXIS[\"(N)\",north,ORDER[2]," + kMetre +
             "]," + height_axis + remark + "]";
    }
    case CoordinateKind::ned: break;
  }
  throw Error(ErrorKind::usage, "E_TILE_CRS", "NED tiles have no WKT here; write them as ENU");
}

namespace {

// The frame geoanchor's remark names ("geoanchor frame ITRF2014@2024.5; …").
std::optional<geodesy::Frame> remark_frame(PJ* crs, std::string_view source) {
  const char* remarks = proj_get_remarks(crs);
  const std::string remark = remarks ? remarks : "";
  const auto at = remark.find(kRemarkPrefix);
  if (at == std::string::npos) return std::nullopt;
  const auto start = at + sizeof kRemarkPrefix - 1;
  const auto end = remark.find(';', start);
  return geodesy::Frame::parse(remark.substr(start, end == std::string::npos ? std::string::npos : end - start),
                               std::string(source) + ": LAS WKT remark");
}

CoordinateSystemStatement typed_statement(std::string_view wkt, std::string_view source) {
  std::unique_ptr<PJ_CONTEXT, CtxDeleter> ctx(proj_context_create());
  proj_log_level(ctx.get(), PJ_LOG_NONE);
  const std::string text(wkt);
  const char* options[] = {"STRICT=NO", nullptr};
  PROJ_STRING_LIST warnings = nullptr;
  PROJ_STRING_LIST errors = nullptr;
  Pj crs(proj_create_from_wkt(ctx.get(), text.c_str(), options, &warnings, &errors));
  std::string first_error = errors && errors[0] ? errors[0] : "";
  proj_string_list_destroy(warnings);
  proj_string_list_destroy(errors);
  if (!crs) {
    fail(source, "PROJ cannot parse it" + (first_error.empty() ? std::string() : ": " + first_error) + "; WKT begins '" +
                     text.substr(0, 60) + "'");
  }
  CoordinateSystemStatement m;
  PJ_TYPE type = proj_get_type(crs.get());
  PJ* h = crs.get();
  if (type == PJ_TYPE_COMPOUND_CRS) not_typed("a compound CRS (orthometric heights through its vertical CRS)");
  m.horizontal_crs = proj_get_name(h) ? proj_get_name(h) : "";

  int axes = 0;
  switch (type) {
    case PJ_TYPE_GEOCENTRIC_CRS:
      axes = require_understood_axes(ctx.get(), h, m.horizontal_crs, {"geocentricX", "geocentricY", "geocentricZ"}, false, source);
      break;
    case PJ_TYPE_GEOGRAPHIC_3D_CRS:
    case PJ_TYPE_GEOGRAPHIC_2D_CRS:
      axes = require_understood_axes(ctx.get(), h, m.horizontal_crs, {"north", "east", "up"}, true, source);
      break;
    case PJ_TYPE_PROJECTED_CRS:
      axes = require_understood_axes(ctx.get(), h, m.horizontal_crs, {"east", "north", "up"}, false, source);
      break;
    default:
      break;  // refused below
  }
  switch (type) {
    case PJ_TYPE_GEOCENTRIC_CRS: m.coordinates.kind = CoordinateKind::ecef; break;
    case PJ_TYPE_GEOGRAPHIC_3D_CRS:
      m.coordinates.kind = CoordinateKind::geodetic;
      m.height_type = "ellipsoidal";
      m.vertical_datum = "ellipsoid";
      break;
    case PJ_TYPE_GEOGRAPHIC_2D_CRS:
      not_typed("a 2-D geographic CRS");
    case PJ_TYPE_PROJECTED_CRS: {
      Pj op(proj_crs_get_coordoperation(ctx.get(), h));
      const char* method = nullptr;
      const char* auth = nullptr;
      const char* code = nullptr;
      if (!op || !proj_coordoperation_get_method_info(ctx.get(), op.get(), &method, &auth, &code)) {
        fail(source, "'" + m.horizontal_crs + "': cannot read its conversion");
      }
      const std::string c = code ? code : "";
      if (c == "9837") {
        m.coordinates.kind = CoordinateKind::enu;
        geodesy::LocalOrigin o;
        o.point.lat = geodesy::Angle::degrees(param(ctx.get(), op.get(), 8834, source));
        o.point.lon = geodesy::Angle::degrees(param(ctx.get(), op.get(), 8835, source));
        o.point.h = geodesy::EllipsoidalHeight{param(ctx.get(), op.get(), 8836, source)};
        if (!geodesy::is_physical_height(o.point.h.m)) {
          fail(source, "'" + m.horizontal_crs + "': its origin's ellipsoidal height " + format_shortest(o.point.h.m) +
                           " m is not a height on the Earth: expected " + geodesy::physical_height_range_text());
        }
        m.coordinates.origin = o;
        m.origin_source = "LAS WKT";
      } else if (c == "9807") {
        m.coordinates.kind = CoordinateKind::projected;
        geodesy::TransverseMercatorParams p;
        p.lat0 = geodesy::Angle::degrees(param(ctx.get(), op.get(), 8801, source));
        p.lon0 = geodesy::Angle::degrees(param(ctx.get(), op.get(), 8802, source));
        p.k0 = param(ctx.get(), op.get(), 8805, source);
        p.false_easting_m = param(ctx.get(), op.get(), 8806, source);
        p.false_northing_m = param(ctx.get(), op.get(), 8807, source);
        m.coordinates.projection = geodesy::ProjectionDef{geodesy::Ellipsoid::wgs84(), p, std::nullopt};
      } else {
        not_typed("projection method '" + std::string(method ? method : "?") + "'");
      }
      if (axes < 3) not_typed("a 2-D projected CRS");
      if (m.coordinates.kind == CoordinateKind::projected && m.height_type.empty()) {
        m.height_type = "ellipsoidal";
        m.vertical_datum = "ellipsoid";
      }
      break;
    }
    default:
      not_typed("not a geocentric, geographic 3D or projected CRS");
  }

  // Datum and ellipsoid.
  Pj datum(proj_crs_get_datum(ctx.get(), h));
  if (!datum) datum.reset(proj_crs_get_datum_ensemble(ctx.get(), h));
  const std::string datum_text = datum && proj_get_name(datum.get()) ? proj_get_name(datum.get()) : "";
  Pj ell(proj_get_ellipsoid(ctx.get(), h));
  double a = 0.0, b = 0.0, rf = 0.0;
  int computed = 0;
  if (!ell || !proj_ellipsoid_get_parameters(ctx.get(), ell.get(), &a, &b, &computed, &rf)) {
    fail(source, "'" + m.horizontal_crs + "': no ellipsoid");
  }
  m.coordinates.ellipsoid = typed_ellipsoid(CrsEllipsoid{"custom", a, rf});
  if (m.coordinates.origin) m.coordinates.origin->ellipsoid = m.coordinates.ellipsoid;
  if (m.coordinates.projection) {
    auto& p = *m.coordinates.projection;
    p.ellipsoid = m.coordinates.ellipsoid;
    // A TM with UTM's parameters is that UTM zone.
    const double zone_f = (p.tm.lon0.deg() + 183.0) / 6.0;
    const int zone = static_cast<int>(std::lround(zone_f));
    const bool north = std::abs(p.tm.false_northing_m) < kUtmMatchM;
    const bool south = std::abs(p.tm.false_northing_m - 10000000.0) < kUtmMatchM;
    if (std::abs(p.tm.lat0.deg()) < kUtmMatchDeg && std::abs(p.tm.k0 - 0.9996) < 1e-12 &&
        std::abs(p.tm.false_easting_m - 500000.0) < kUtmMatchM && (north || south) && zone >= 1 && zone <= 60 &&
        std::abs(zone_f - zone) * 6.0 < kUtmMatchDeg) {
      p = geodesy::utm_projection(p.ellipsoid, geodesy::UtmZone{zone, north ? geodesy::Hemisphere::north
                                                                            : geodesy::Hemisphere::south});
    }
  }

  // The frame: geoanchor's remark (with the coordinate epoch), else the datum.
  const std::string from_datum = detail::frame_name_of_epsg_datum(datum_text);
  if (auto named = remark_frame(crs.get(), source)) {
    m.frame = named;
    if (!from_datum.empty() && from_datum != m.frame->name()) {
      fail(source, "the remark names frame " + m.frame->to_string() + " but the datum is '" + datum_text + "'");
    }
  } else if (!from_datum.empty()) {
    m.frame = geodesy::Frame::parse(from_datum, std::string(source) + ": LAS WKT datum");
  } else {
    try {
      m.frame = geodesy::Frame::parse(datum_text, std::string(source) + ": LAS WKT datum");
    } catch (const Error&) {
      m.frame.reset();  // a datum geoanchor cannot name: the caller asks for --from-frame
    }
  }
  m.wkt_datum = datum_text;
  return m;
}

}  // namespace

CoordinateSystemStatement coordinate_system_from_wkt_as_crs(std::string_view wkt, std::string_view source) {
  Crs crs = Crs::parse(wkt, std::string(source) + ": LAS WKT");
  const auto& d = crs.description();
  std::unique_ptr<PJ_CONTEXT, CtxDeleter> ctx(proj_context_create());
  proj_log_level(ctx.get(), PJ_LOG_NONE);
  const std::string text(wkt);
  Pj pj(proj_create(ctx.get(), text.c_str()));
  const auto named = pj ? remark_frame(pj.get(), source) : std::nullopt;
  const char* remarks = pj ? proj_get_remarks(pj.get()) : nullptr;
  const std::string remark = remarks ? remarks : "";
  std::optional<geodesy::DecimalYear> epoch = named ? named->epoch() : std::nullopt;
  if (const auto at = remark.find(kEpochRemark); !epoch && at != std::string::npos) {
    const auto start = at + sizeof kEpochRemark - 1;
    const auto end = remark.find_first_of("; ", start);
    epoch = geodesy::parse_decimal_year(remark.substr(start, end == std::string::npos ? std::string::npos : end - start),
                                        std::string(source) + ": LAS WKT remark");
  }
  if (named && !d.catalog_frame.empty() && named->name() != d.catalog_frame) {
    fail(source, "the remark names frame " + named->to_string() + " but the datum is '" + d.datum + "' (" +
                     d.catalog_frame + ")");
  }
  if (epoch && !d.dynamic && named && geodesy::is_dynamic(*named)) {
    // geoanchor's own WKT for its own coordinates names a dynamic frame's
    // datum without DYNAMIC[]: PROJ would read it as static and lose the
    // epoch, so it is read as geoanchor wrote it (its frame and epoch).
    try {
      return typed_statement(wkt, source);
    } catch (const NotTyped& e) {
      fail(source, "the remark names the dynamic frame " + named->to_string() + " but PROJ reads datum '" + d.datum +
                       "' as static (" + e.why + "); give the tile a sidecar or --crs with the CRS at its epoch");
    }
  }
  if (epoch && d.dynamic) crs = crs.at_epoch(*epoch, std::string(source) + ": LAS WKT remark");
  return coordinate_system_from_crs(std::move(crs), source);
}

CoordinateSystemStatement coordinate_system_from_wkt(std::string_view wkt, std::string_view source) {
  try {
    return typed_statement(wkt, source);
  } catch (const NotTyped&) {
    return coordinate_system_from_wkt_as_crs(wkt, source);
  }
}

CoordinateSystemStatement coordinate_system_from_crs(Crs crs, std::string_view source) {
  CoordinateSystemStatement m;
  const auto& d = crs.description();
  if (!d.catalog_frame.empty()) {
    m.frame = geodesy::Frame::parse(d.catalog_frame + (crs.epoch() ? "@" + geodesy::format_decimal_year(*crs.epoch()) : ""),
                                    std::string(source) + ": the CRS's datum");
  }
  m.horizontal_crs = d.name;
  m.wkt_datum = d.datum;
  const bool compound = d.type == "compound";
  m.height_type = compound ? "orthometric" : d.axes.size() >= 3 && d.type != "geocentric" ? "ellipsoidal" : "";
  m.vertical_datum = compound ? d.vertical_datum : m.height_type.empty() ? "" : "ellipsoid";
  if (compound) m.geoid_model = d.geoid_model.empty() ? d.vertical_datum : d.geoid_model;
  m.crs = std::move(crs);
  return m;
}

}  // namespace geoanchor::io
