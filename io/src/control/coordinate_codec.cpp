#include "geoanchor/io/control/coordinate_codec.hpp"

#include <cmath>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/geodesy/physical_range.hpp"

namespace geoanchor::io {

using geodesy::Angle;
using geodesy::EcefPosition;
using geodesy::EllipsoidalHeight;
using geodesy::GeodeticPosition;

void UtmBandTally::add(const geodesy::UtmZone& z, const GeodeticPosition& p, const geodesy::UtmBandCheck& check,
                       std::size_t index, std::string_view where) {
  zone = z;
  ++points;
  const double excess = check.excess.deg();
  if (points == 1 || excess > worst_excess_deg) {
    worst_excess_deg = excess;
    worst_lat_deg = p.lat.deg();
    worst_lon_deg = p.lon.deg();
    worst_index = index;
    worst_where = std::string(where);
    zone_unused = !check.band_exists;
  }
}

void UtmBandTally::absorb(const UtmBandTally& other, std::string_view where) {
  if (other.points == 0) return;
  const bool farther = points == 0 || other.worst_excess_deg > worst_excess_deg;
  zone = other.zone;
  points += other.points;
  if (farther) {
    worst_excess_deg = other.worst_excess_deg;
    worst_lat_deg = other.worst_lat_deg;
    worst_lon_deg = other.worst_lon_deg;
    worst_index = other.worst_index;
    worst_where = std::string(where);
    zone_unused = other.zone_unused;
  }
}

std::optional<std::string> UtmBandTally::warning(std::string_view role) const {
  if (points == 0 || !zone) return std::nullopt;
  std::string w = std::string(role) + " UTM zone " + zone->to_string() + ": " + std::to_string(points) +
                  (points == 1 ? " point lies" : " points lie") + " outside the zone's band";
  const std::string band = geodesy::utm_band_text(*zone, Angle::degrees(worst_lat_deg));
  w += zone_unused ? " (" + band + ")" : " (" + band + ") by more than the " +
                                             format_shortest(geodesy::kUtmBandMargin.deg()) + "° margin";
  // To 1e-9° (0.1 mm): the point came through ECEF and back.
  auto deg = [](double v) {
    const double r = std::round(v * 1e9) / 1e9;
    return format_shortest(r == 0.0 ? 0.0 : r);
  };
  w += "; the farthest is " + worst_where + " (lat " + deg(worst_lat_deg) + ", lon " + deg(worst_lon_deg) + ")";
  if (!zone_unused) w += ", " + format_fixed(worst_excess_deg, 2) + "° beyond";
  w += ". Its coordinates are computed (UTM keeps its 5 nm accuracy to " +
       format_shortest(geodesy::kTmSeriesLimit.deg()) +
       "° from the central meridian and is refused beyond), but they are not the point's own zone: check the zone";
  return w;
}

namespace {
// Refuses a non-finite output value: no NaN or infinity is ever written.
void require_finite(const std::vector<double>& values, const std::vector<std::string>& names, const EcefPosition& p,
                    std::string_view where) {
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) {
      throw Error(ErrorKind::input, "E_NON_FINITE",
                  std::string(where) + ": output " + names[i] + "=" + format_shortest(values[i]) +
                      " is not finite for the point at ECEF (" + format_shortest(p.m.x()) + ", " +
                      format_shortest(p.m.y()) + ", " + format_shortest(p.m.z()) +
                      ") m; no NaN or infinity is written: check the input and the transform");
    }
  }
}
}  // namespace

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
      geodesy::require_physical_height(g.h.m, where(columns_.third.value_or(columns_.second)));
      return geocentric_.ecef_from_geodetic(g);
    }
    case CoordinateKind::ecef: {
      const EcefPosition x(a, b, number(r, *columns_.third));
      geodesy::require_physical_ecef(x.m, frame_.ellipsoid, source_ + ":" + std::to_string(r.line));
      return x;
    }
    case CoordinateKind::enu:
    case CoordinateKind::ned: {
      const Eigen::Vector3d v(a, b, number(r, *columns_.third));
      const EcefPosition x = columns_.kind == CoordinateKind::enu
                                 ? plane_->ecef_from_enu(geodesy::EnuPosition{v, *frame_.origin})
                                 : plane_->ecef_from_enu(geodesy::enu_from_ned(geodesy::NedPosition{v, *frame_.origin}));
      geodesy::require_physical_ecef(x.m, frame_.ellipsoid, source_ + ":" + std::to_string(r.line));
      return x;
    }
    case CoordinateKind::projected: {
      const double h = columns_.third ? number(r, *columns_.third) : 0.0;
      std::optional<geodesy::UtmZone> row_zone;
      if (!projection_) row_zone = geodesy::parse_utm_zone(r.values[*columns_.utm_zone], where(*columns_.utm_zone));
      const geodesy::TransverseMercator& tm = projection_ ? *projection_ : utm(*row_zone);
      geodesy::TmOutcome how;
      const auto inverse = tm.try_inverse(geodesy::ProjectedPosition{a, b, EllipsoidalHeight{h}, tm.definition()}, &how);
      if (!inverse) {
        throw Error(ErrorKind::input, "E_PROJECTED_RANGE",
                    where(columns_.first) + "=" + r.values[columns_.first] + ", " + header_[columns_.second] + "=" +
                        r.values[columns_.second] + ": outside the projection's domain: " + tm.explain(how));
      }
      GeodeticPosition g = *inverse;
      if (const auto& z = tm.definition().utm) {
        if (const auto c = geodesy::utm_band_check(*z, g); geodesy::outside_band_margin(c)) {
          band_by_zone_[z->to_string()].add(*z, g, c, 0, source_ + ":" + std::to_string(r.line));
        }
      }
      if (columns_.orthometric) g = with_ellipsoidal_height(g, *frame_.geoid, source_ + ":" + std::to_string(r.line));
      geodesy::require_physical_height(g.h.m, where(columns_.third.value_or(columns_.second)));
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

std::vector<std::string> CoordinateDecoder::warnings() const {
  std::vector<std::string> out;
  const std::string role = projection_ ? "input" : "input (utm_zone column)";
  for (const auto& [name, tally] : band_by_zone_) {
    if (auto w = tally.warning(role)) out.push_back(source_ + ": " + *w);
  }
  return out;
}

std::vector<std::string> CoordinateEncoder::warnings() const {
  std::vector<std::string> out;
  if (auto w = band_.warning("--zone: output")) out.push_back(*w);
  return out;
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
  std::vector<double> v;
  switch (frame_.kind) {
    case OutputKind::ecef:
      v = {p.m.x(), p.m.y(), p.m.z()};
      require_finite(v, names_, p, where);
      return {f.metres(v[0]), f.metres(v[1]), f.metres(v[2])};
    case OutputKind::geodetic: {
      const auto g = geocentric_.geodetic_from_ecef(p);
      v = {g.lat.deg(), g.lon.deg(), height(g, where)};
      require_finite(v, names_, p, where);
      return {f.degrees(v[0]), f.degrees(v[1]), f.metres(v[2])};
    }
    case OutputKind::enu: {
      const auto e = plane_->enu_from_ecef(p).enu_m;
      v = {e.x(), e.y(), e.z()};
      require_finite(v, names_, p, where);
      return {f.metres(v[0]), f.metres(v[1]), f.metres(v[2])};
    }
    case OutputKind::ned: {
      const auto n = geodesy::ned_from_enu(plane_->enu_from_ecef(p)).ned_m;
      v = {n.x(), n.y(), n.z()};
      require_finite(v, names_, p, where);
      return {f.metres(v[0]), f.metres(v[1]), f.metres(v[2])};
    }
    case OutputKind::utm:
    case OutputKind::tm: {
      const auto g = geocentric_.geodetic_from_ecef(p);
      std::optional<geodesy::UtmZone> zone = frame_.zone;
      const geodesy::TransverseMercator* tm = nullptr;
      if (projection_) {
        tm = &*projection_;
      } else {
        zone = geodesy::standard_utm_zone(g);
        if (!zone) {
          throw Error(ErrorKind::input, "E_UTM_RANGE",
                      std::string(where) + ": latitude " + format_shortest(g.lat.deg()) +
                          ": outside UTM's [-80, 84) degrees (polar regions use UPS, which convert does not write)");
        }
        tm = &utm(*zone);
      }
      geodesy::TmOutcome how;
      const auto q = tm->try_forward(g, &how);
      if (!q) {
        throw Error(ErrorKind::input, "E_PROJECTION_DOMAIN",
                    std::string(where) + ": outside the projection's domain: " + tm->explain(how));
      }
      if (frame_.zone) {
        if (const auto c = geodesy::utm_band_check(*frame_.zone, g); geodesy::outside_band_margin(c)) {
          band_.add(*frame_.zone, g, c, 0, where);
        }
      }
      v = {q->easting_m, q->northing_m, height(g, where)};
      require_finite(v, names_, p, where);
      std::vector<std::string> out = {f.metres(v[0]), f.metres(v[1]), f.metres(v[2])};
      if (frame_.kind == OutputKind::utm) out.push_back(zone->to_string());
      return out;
    }
  }
  return {};
}

}  // namespace geoanchor::io
