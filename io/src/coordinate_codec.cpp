#include "geoanchor/io/coordinate_codec.hpp"

#include <cmath>

#include "geoanchor/geodesy/error.hpp"
#include "geoanchor/geodesy/number_text.hpp"

namespace geoanchor::io {

using geodesy::Angle;
using geodesy::EcefPosition;
using geodesy::EllipsoidalHeight;
using geodesy::GeodeticPosition;

CoordinateDecoder::CoordinateDecoder(const CoordinateColumns& columns, const std::vector<std::string>& header,
                                     InputCoordinateFrame frame, std::string source_name)
    : columns_(columns), header_(header), frame_(std::move(frame)), source_(std::move(source_name)),
      geocentric_(frame_.ellipsoid) {
  switch (columns_.kind) {
    case CoordinateKind::enu:
    case CoordinateKind::ned:
      if (!frame_.origin) {
        throw Error(ErrorKind::usage, "E_ORIGIN_MISSING",
                    source_ + ": " + std::string(to_string(columns_.kind)) +
                        " input needs its origin: give --from-origin LAT,LON,H (or --origin, which then serves input "
                        "and output)");
      }
      plane_.emplace(*frame_.origin);
      break;
    case CoordinateKind::projected:
      if (frame_.projection) {
        projection_.emplace(*frame_.projection);
      } else if (!columns_.utm_zone) {
        throw Error(ErrorKind::usage, "E_PROJECTION_MISSING",
                    source_ + ": easting/northing input needs its projection: give --from-zone ZONE, --from-tm "
                              "LAT0,LON0,K0,FE,FN (or --zone/--tm), or a utm_zone column");
      }
      break;
    default: break;
  }
  if (columns_.orthometric && !frame_.geoid) {
    throw Error(ErrorKind::input, "E_HEIGHT_TYPE",
                source_ + ": column '" + header_[*columns_.third] +
                    "': orthometric height: reading it needs the geoid model: give --geoid EGM96 (h = H + N)");
  }
}

namespace {
// h = H + N at the point's latitude and longitude.
GeodeticPosition with_ellipsoidal_height(GeodeticPosition g, const geodesy::GeoidGrid& geoid, const std::string& where) {
  g.h.m += geoid.undulation_m(g.lat, g.lon, where);
  return g;
}
}  // namespace

double CoordinateDecoder::number(const CsvRecord& r, std::size_t column) const {
  return number_cell(r, column, header_, source_);
}

EcefPosition CoordinateDecoder::decode(const CsvRecord& r) const {
  const double a = number(r, columns_.first);
  const double b = number(r, columns_.second);
  const auto where = [&](std::size_t col) { return source_ + ":" + std::to_string(r.line) + ": " + header_[col]; };
  switch (columns_.kind) {
    case CoordinateKind::geodetic: {
      if (std::fabs(a) > 90.0) {
        throw Error(ErrorKind::input, "E_LATITUDE_RANGE",
                    where(columns_.first) + "=" + r.values[columns_.first] + ": latitude not in [-90, 90] degrees");
      }
      if (std::fabs(b) > 180.0) {
        throw Error(ErrorKind::input, "E_LONGITUDE_RANGE",
                    where(columns_.second) + "=" + r.values[columns_.second] +
                        ": longitude not in [-180, 180] degrees");
      }
      const double h = columns_.third ? number(r, *columns_.third) : 0.0;
      GeodeticPosition g{Angle::degrees(a), Angle::degrees(b), EllipsoidalHeight{h}};
      if (columns_.orthometric) g = with_ellipsoidal_height(g, *frame_.geoid, source_ + ":" + std::to_string(r.line));
      return geocentric_.ecef_from_geodetic(g);
    }
    case CoordinateKind::ecef: return EcefPosition(a, b, number(r, *columns_.third));
    case CoordinateKind::enu:
      return plane_->ecef_from_enu(geodesy::EnuPosition{Eigen::Vector3d(a, b, number(r, *columns_.third)), *frame_.origin});
    case CoordinateKind::ned:
      return plane_->ecef_from_enu(geodesy::enu_from_ned(
          geodesy::NedPosition{Eigen::Vector3d(a, b, number(r, *columns_.third)), *frame_.origin}));
    case CoordinateKind::projected: {
      const double h = columns_.third ? number(r, *columns_.third) : 0.0;
      GeodeticPosition g;
      if (projection_) {
        g = projection_->inverse(geodesy::ProjectedPosition{a, b, EllipsoidalHeight{h}, projection_->definition()});
      } else {
        const auto zone = geodesy::parse_utm_zone(r.values[*columns_.utm_zone], where(*columns_.utm_zone));
        const geodesy::TransverseMercator& tm = utm(zone);
        g = tm.inverse(geodesy::ProjectedPosition{a, b, EllipsoidalHeight{h}, tm.definition()});
      }
      if (!std::isfinite(g.lat.deg()) || !std::isfinite(g.lon.deg())) {
        throw Error(ErrorKind::input, "E_PROJECTED_RANGE",
                    source_ + ":" + std::to_string(r.line) + ": easting/northing " + r.values[columns_.first] + ", " +
                        r.values[columns_.second] + ": outside the projection's domain");
      }
      if (columns_.orthometric) g = with_ellipsoidal_height(g, *frame_.geoid, source_ + ":" + std::to_string(r.line));
      return geocentric_.ecef_from_geodetic(g);
    }
  }
  return EcefPosition();
}

namespace {
// One TransverseMercator per zone met, so rows do not rebuild the series.
const geodesy::TransverseMercator& cached_utm(std::map<std::string, geodesy::TransverseMercator>& cache,
                                             const geodesy::Ellipsoid& e, const geodesy::UtmZone& zone) {
  const std::string key = zone.to_string();
  auto it = cache.find(key);
  if (it == cache.end()) it = cache.emplace(key, geodesy::TransverseMercator(geodesy::utm_projection(e, zone))).first;
  return it->second;
}
}  // namespace

const geodesy::TransverseMercator& CoordinateDecoder::utm(const geodesy::UtmZone& zone) const {
  return cached_utm(utm_by_zone_, frame_.ellipsoid, zone);
}

const geodesy::TransverseMercator& CoordinateEncoder::utm(const geodesy::UtmZone& zone) const {
  return cached_utm(utm_by_zone_, frame_.ellipsoid, zone);
}

std::string_view to_string(OutputKind k) {
  switch (k) {
    case OutputKind::geodetic: return "geodetic";
    case OutputKind::ecef: return "ecef";
    case OutputKind::enu: return "enu";
    case OutputKind::ned: return "ned";
    case OutputKind::utm: return "utm";
    case OutputKind::tm: return "tm";
  }
  return "?";
}

std::string NumberFormat::metres(double v) const {
  return decimals ? format_fixed(v, *decimals) : format_shortest(v);
}
std::string NumberFormat::degrees(double v) const {
  return decimals ? format_fixed(v, *decimals + 5) : format_shortest(v);
}

CoordinateEncoder::CoordinateEncoder(OutputCoordinateFrame frame, NumberFormat format)
    : frame_(std::move(frame)), format_(format), geocentric_(frame_.ellipsoid) {
  switch (frame_.kind) {
    case OutputKind::geodetic: names_ = coordinate_column_names(CoordinateKind::geodetic); break;
    case OutputKind::ecef: names_ = coordinate_column_names(CoordinateKind::ecef); break;
    case OutputKind::enu:
    case OutputKind::ned:
      if (!frame_.origin) {
        throw Error(ErrorKind::usage, "E_ORIGIN_MISSING",
                    "--to " + std::string(to_string(frame_.kind)) +
                        " needs the local origin: give --origin LAT,LON,H (degrees, degrees, ellipsoidal metres)");
      }
      plane_.emplace(*frame_.origin);
      names_ = coordinate_column_names(frame_.kind == OutputKind::enu ? CoordinateKind::enu : CoordinateKind::ned);
      break;
    case OutputKind::utm:
      names_ = coordinate_column_names(CoordinateKind::projected);
      names_.emplace_back("utm_zone");
      if (frame_.zone) projection_.emplace(geodesy::utm_projection(frame_.ellipsoid, *frame_.zone));
      break;
    case OutputKind::tm:
      if (!frame_.tm) {
        throw Error(ErrorKind::usage, "E_PROJECTION_MISSING", "--to tm needs --tm LAT0,LON0,K0,FE,FN");
      }
      projection_.emplace(geodesy::ProjectionDef{frame_.ellipsoid, *frame_.tm, std::nullopt});
      names_ = coordinate_column_names(CoordinateKind::projected);
      break;
  }
  if (frame_.geoid) {
    if (frame_.kind != OutputKind::geodetic && frame_.kind != OutputKind::utm && frame_.kind != OutputKind::tm) {
      throw Error(ErrorKind::usage, "E_OPTION",
                  "--output-heights orthometric: only geodetic, UTM and TM outputs have a height column (not " +
                      std::string(to_string(frame_.kind)) + ")");
    }
    names_[2] = "H_m";
  }
}

double CoordinateEncoder::height(const GeodeticPosition& g, std::string_view where) const {
  return frame_.geoid ? g.h.m - frame_.geoid->undulation_m(g.lat, g.lon, where) : g.h.m;
}

std::vector<std::string> CoordinateEncoder::encode(const EcefPosition& p, std::string_view where) const {
  const auto& f = format_;
  switch (frame_.kind) {
    case OutputKind::ecef: return {f.metres(p.m.x()), f.metres(p.m.y()), f.metres(p.m.z())};
    case OutputKind::geodetic: {
      const auto g = geocentric_.geodetic_from_ecef(p);
      return {f.degrees(g.lat.deg()), f.degrees(g.lon.deg()), f.metres(height(g, where))};
    }
    case OutputKind::enu: {
      const auto e = plane_->enu_from_ecef(p).enu_m;
      return {f.metres(e.x()), f.metres(e.y()), f.metres(e.z())};
    }
    case OutputKind::ned: {
      const auto n = geodesy::ned_from_enu(plane_->enu_from_ecef(p)).ned_m;
      return {f.metres(n.x()), f.metres(n.y()), f.metres(n.z())};
    }
    case OutputKind::utm:
    case OutputKind::tm: {
      const auto g = geocentric_.geodetic_from_ecef(p);
      std::optional<geodesy::UtmZone> zone = frame_.zone;
      geodesy::ProjectedPosition q;
      if (projection_) {
        q = projection_->forward(g);
      } else {
        zone = geodesy::standard_utm_zone(g);
        if (!zone) {
          throw Error(ErrorKind::input, "E_UTM_RANGE",
                      std::string(where) + ": latitude " + format_shortest(g.lat.deg()) +
                          ": outside UTM's [-80, 84) degrees (polar regions use UPS, which convert does not write)");
        }
        q = utm(*zone).forward(g);
      }
      std::vector<std::string> out = {f.metres(q.easting_m), f.metres(q.northing_m), f.metres(height(g, where))};
      if (frame_.kind == OutputKind::utm) out.push_back(zone->to_string());
      return out;
    }
  }
  return {};
}

}  // namespace geoanchor::io
