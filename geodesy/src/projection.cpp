#include "geoanchor/geodesy/projection.hpp"

#include <GeographicLib/Math.hpp>
#include <GeographicLib/TransverseMercator.hpp>
#include <GeographicLib/TransverseMercatorExact.hpp>
#include <GeographicLib/UTMUPS.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"

namespace geoanchor::geodesy {

std::string UtmZone::to_string() const {
  return std::to_string(number) + (hemisphere == Hemisphere::north ? "N" : "S");
}

UtmZone parse_utm_zone(std::string_view text, std::string_view where) {
  auto fail = [&] {
    return Error(ErrorKind::input, "E_UTM_ZONE",
                 std::string(where) + ": zone=" + std::string(text) +
                     ": not a UTM zone; expected 1..60 followed by N or S, e.g. 32N");
  };
  if (text.size() < 2) throw fail();
  const char h = text.back();
  Hemisphere hemi;
  if (h == 'N' || h == 'n') {
    hemi = Hemisphere::north;
  } else if (h == 'S' || h == 's') {
    hemi = Hemisphere::south;
  } else {
    throw fail();
  }
  int number = 0;
  const auto digits = text.substr(0, text.size() - 1);
  const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), number);
  if (ec != std::errc() || ptr != digits.data() + digits.size() || number < 1 || number > 60) throw fail();
  return UtmZone{number, hemi};
}

std::optional<UtmZone> standard_utm_zone(const GeodeticPosition& p) {
  const double lat = p.lat.deg();
  const double lon = p.lon.deg();
  if (!(lat >= -80.0 && lat < 84.0) || !(lon >= -180.0 && lon <= 180.0)) return std::nullopt;
  const int zone = GeographicLib::UTMUPS::StandardZone(lat, lon);
  if (zone < 1 || zone > 60) return std::nullopt;
  return UtmZone{zone, lat >= 0.0 ? Hemisphere::north : Hemisphere::south};
}

TransverseMercatorParams utm_params(const UtmZone& zone) {
  TransverseMercatorParams p;
  p.lat0 = Angle::degrees(0.0);
  p.lon0 = Angle::degrees(6.0 * zone.number - 183.0);
  p.k0 = 0.9996;
  p.false_easting_m = 500000.0;
  p.false_northing_m = zone.hemisphere == Hemisphere::north ? 0.0 : 10000000.0;
  return p;
}

bool ProjectionDef::operator==(const ProjectionDef& o) const {
  return ellipsoid == o.ellipsoid && tm.lat0 == o.tm.lat0 && tm.lon0 == o.tm.lon0 && tm.k0 == o.tm.k0 &&
         tm.false_easting_m == o.tm.false_easting_m && tm.false_northing_m == o.tm.false_northing_m;
}

ProjectionDef utm_projection(const Ellipsoid& e, const UtmZone& zone) {
  return ProjectionDef{e, utm_params(zone), zone};
}

std::string_view to_string(TmMethod m) { return m == TmMethod::series ? "Krüger series" : "exact"; }

namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
// An inverse's result may lie this far outside the domain's limits (1e-9°,
// 0.1 mm): the rounding of a forward at the limit and back.
constexpr double kInverseSlack_deg = 1e-9;

// Latitude or longitude for a message: what was given, or an inverse's
// result to 1e-9° (0.1 mm) rather than to 17 digits.
std::string angle_text(double deg) {
  if (!std::isfinite(deg)) return format_shortest(deg);
  const double rounded = std::round(deg * 1e9) / 1e9;
  return format_shortest(rounded == 0.0 ? 0.0 : rounded);
}

// "3°E", "3°W", "0°" for a meridian; "52.5°N" for a parallel.
std::string meridian_text(double lon_deg) {
  if (lon_deg == 0.0) return "0°";
  return format_shortest(std::fabs(lon_deg)) + (lon_deg > 0.0 ? "°E" : "°W");
}
std::string parallel_text(double lat_deg) {
  if (lat_deg == 0.0) return "0°";
  return format_shortest(std::fabs(lat_deg)) + (lat_deg > 0.0 ? "°N" : "°S");
}

}  // namespace

struct TransverseMercator::Impl {
  GeographicLib::TransverseMercator series;
  std::optional<GeographicLib::TransverseMercatorExact> exact;  // general TM only: UTM is the series
  double series_origin_northing_m;  // unprojected northing of (lat0, lon0), series
  double exact_origin_northing_m;   // the same, exact method
};

TransverseMercator::TransverseMercator(const ProjectionDef& def) : def_(def), impl_(make_impl(def)) {}
TransverseMercator::~TransverseMercator() = default;
TransverseMercator::TransverseMercator(const TransverseMercator& o)
    : def_(o.def_), impl_(std::make_unique<Impl>(*o.impl_)) {}
TransverseMercator& TransverseMercator::operator=(const TransverseMercator& o) {
  if (this != &o) {
    def_ = o.def_;
    impl_ = std::make_unique<Impl>(*o.impl_);
  }
  return *this;
}

std::unique_ptr<TransverseMercator::Impl> TransverseMercator::make_impl(const ProjectionDef& def) {
  const double lon0 = def.tm.lon0.deg(), lat0 = def.tm.lat0.deg();
  GeographicLib::TransverseMercator series(def.ellipsoid.a_m(), def.ellipsoid.f(), def.tm.k0);
  double x = 0, y0 = 0;
  series.Forward(lon0, lat0, lon0, x, y0);
  std::optional<GeographicLib::TransverseMercatorExact> exact;
  double y0_exact = kNan;
  if (!def.utm) {
    exact.emplace(def.ellipsoid.a_m(), def.ellipsoid.f(), def.tm.k0);
    double gamma = 0, k = 0;
    exact->Forward(lon0, lat0, lon0, x, y0_exact, gamma, k);
  }
  return std::make_unique<Impl>(Impl{series, exact, y0, y0_exact});
}

TmOutcome TransverseMercator::locate(Angle lat, Angle lon, double slack_deg) const {
  TmOutcome o;
  o.lat = lat;
  o.lon = lon;
  if (!(std::isfinite(lat.deg()) && std::isfinite(lon.deg()) && std::fabs(lat.deg()) <= 90.0)) {
    o.refusal = TmRefusal::non_finite;
    return o;
  }
  const double dlon = GeographicLib::Math::AngDiff(def_.tm.lon0.deg(), lon.deg());
  double sin_phi = 0, cos_phi = 0, sin_dlon = 0, cos_dlon = 0;
  GeographicLib::Math::sincosd(lat.deg(), sin_phi, cos_phi);
  GeographicLib::Math::sincosd(dlon, sin_dlon, cos_dlon);
  const double d = std::asin(std::min(1.0, cos_phi * std::fabs(sin_dlon)));
  o.dlon = Angle::degrees(dlon);
  o.from_central_meridian = Angle::radians(d);
  if (std::fabs(dlon) > 90.0 + slack_deg && cos_phi != 0.0) {  // at a pole every longitude is the central meridian
    o.refusal = TmRefusal::far_hemisphere;
    return o;
  }
  const double limit_deg = def_.utm ? kTmSeriesLimit.deg() : kTmExactLimit.deg();
  if (o.from_central_meridian.deg() > limit_deg + slack_deg) {
    o.refusal = TmRefusal::beyond_domain;
    return o;
  }
  o.method = o.from_central_meridian.deg() <= kTmSeriesLimit.deg() ? TmMethod::series : TmMethod::exact;
  return o;
}

std::optional<ProjectedPosition> TransverseMercator::try_forward(const GeodeticPosition& p, TmOutcome* outcome) const {
  TmOutcome o = locate(p.lat, p.lon);
  double x = kNan, y = kNan;
  if (o.ok()) {
    const double lon0 = def_.tm.lon0.deg();
    if (o.method == TmMethod::series) {
      impl_->series.Forward(lon0, p.lat.deg(), p.lon.deg(), x, y);
      y -= impl_->series_origin_northing_m;
    } else {
      double gamma = 0, k = 0;
      impl_->exact->Forward(lon0, p.lat.deg(), p.lon.deg(), x, y, gamma, k);
      y -= impl_->exact_origin_northing_m;
    }
    if (!std::isfinite(x) || !std::isfinite(y)) o.refusal = TmRefusal::non_finite;
  }
  if (outcome) *outcome = o;
  if (!o.ok()) return std::nullopt;
  return ProjectedPosition{def_.tm.false_easting_m + x, def_.tm.false_northing_m + y, p.h, def_};
}

ProjectedPosition TransverseMercator::forward(const GeodeticPosition& p) const {
  if (auto q = try_forward(p)) return *q;
  return ProjectedPosition{kNan, kNan, p.h, def_};
}

std::optional<GeodeticPosition> TransverseMercator::try_inverse(const ProjectedPosition& p, TmOutcome* outcome) const {
  TmOutcome o;
  auto done = [&](const TmOutcome& result) -> std::optional<GeodeticPosition> {
    if (outcome) *outcome = result;
    if (!result.ok()) return std::nullopt;
    return GeodeticPosition{result.lat, result.lon, p.h};
  };
  if (!(p.projection == def_)) {
    o.refusal = TmRefusal::other_projection;
    return done(o);
  }
  if (!std::isfinite(p.easting_m) || !std::isfinite(p.northing_m)) {
    o.refusal = TmRefusal::non_finite;
    return done(o);
  }
  const double lon0 = def_.tm.lon0.deg();
  const double x = p.easting_m - def_.tm.false_easting_m;
  const double dy = p.northing_m - def_.tm.false_northing_m;
  // A method's inverse counts only when it projects back onto the grid
  // position: far outside its domain an inverse returns a point that does
  // not (the series diverges; the exact method continues across its branch
  // cut, many grid positions to one point).
  struct Attempt {
    bool closes = false;
    TmOutcome where;  // the point's place in the domain, when it closes
  };
  auto attempt = [&](TmMethod m) {
    Attempt a;
    const double y = dy + (m == TmMethod::series ? impl_->series_origin_northing_m : impl_->exact_origin_northing_m);
    double lat = kNan, lon = kNan, x1 = kNan, y1 = kNan, gamma = 0, k = 0;
    if (m == TmMethod::series) {
      impl_->series.Reverse(lon0, x, y, lat, lon);
      if (std::isfinite(lat) && std::isfinite(lon)) impl_->series.Forward(lon0, lat, lon, x1, y1);
    } else {
      impl_->exact->Reverse(lon0, x, y, lat, lon, gamma, k);
      if (std::isfinite(lat) && std::isfinite(lon)) impl_->exact->Forward(lon0, lat, lon, x1, y1, gamma, k);
    }
    a.closes = std::fabs(x1 - x) <= kGridRoundTripTol_m && std::fabs(y1 - y) <= kGridRoundTripTol_m;
    if (a.closes) a.where = locate(Angle::degrees(lat), Angle::degrees(lon), kInverseSlack_deg);
    return a;
  };
  const Attempt series = attempt(TmMethod::series);
  if (series.closes && series.where.ok() && series.where.method == TmMethod::series) return done(series.where);
  if (impl_->exact) {
    Attempt exact = attempt(TmMethod::exact);
    if (exact.closes) {
      exact.where.method = TmMethod::exact;
      return done(exact.where);  // in the domain, or a point beyond it (refused, with that point)
    }
  } else if (series.closes) {
    return done(series.where);  // UTM: a point beyond its 35°, refused with that point
  }
  o.refusal = TmRefusal::grid_outside_domain;
  return done(o);
}

GeodeticPosition TransverseMercator::inverse(const ProjectedPosition& p) const {
  if (auto g = try_inverse(p)) return *g;
  return GeodeticPosition{Angle::degrees(kNan), Angle::degrees(kNan), EllipsoidalHeight{kNan}};
}

std::string TransverseMercator::domain() const {
  const std::string cm = meridian_text(def_.tm.lon0.deg());
  if (def_.utm) {
    return "UTM zone " + def_.utm->to_string() + " is computed within " + format_shortest(kTmSeriesLimit.deg()) +
           "° of its central meridian " + cm +
           " (the Krüger series' 5 nm range; UTM is never switched to the exact method)";
  }
  return "this Transverse Mercator is computed within " + format_shortest(kTmExactLimit.deg()) +
         "° of its central meridian " + cm + " (Krüger series to " + format_shortest(kTmSeriesLimit.deg()) +
         "°, exact method beyond; refused near the branch point at " +
         format_fixed(90.0 * (1.0 - std::sqrt(def_.ellipsoid.e2())), 1) + "° on the equator)";
}

std::string TransverseMercator::explain(const TmOutcome& o) const {
  const std::string point = "lat " + angle_text(o.lat.deg()) + ", lon " + angle_text(o.lon.deg());
  const std::string cm = meridian_text(def_.tm.lon0.deg());
  switch (o.refusal) {
    case TmRefusal::none: return point + ": " + format_fixed(o.from_central_meridian.deg(), 1) + "° from the central meridian " + cm;
    case TmRefusal::non_finite: return "not a finite position (latitude within [-90, 90] degrees)";
    case TmRefusal::far_hemisphere:
      return point + ": " + format_fixed(std::fabs(o.dlon.deg()), 1) + "° of longitude from the central meridian " + cm +
             ", on the far side of the pole (at most 90°); " + domain();
    case TmRefusal::beyond_domain:
      return point + ": " + format_fixed(o.from_central_meridian.deg(), 1) + "° from the central meridian " + cm + "; " +
             domain();
    case TmRefusal::grid_outside_domain:
      return "no point within the projection's domain maps to this easting/northing; " + domain();
    case TmRefusal::other_projection: return "the position is on another projection";
  }
  return "?";
}

namespace {

// The longitudes UTMUPS::StandardZone gives `zone` at `lat_deg`: 6° zones
// from 180°W; in band V (56°N-64°N) 31 ends and 32 begins at 3°E; in band X
// (72°N-84°N) 31, 33, 35 and 37 cover 0°-9°-21°-33°-42°E and 32, 34, 36 are
// unused (false).
bool utm_band_longitudes(const UtmZone& zone, double lat_deg, double& west, double& east) {
  west = 6.0 * zone.number - 186.0;
  east = west + 6.0;
  if (zone.hemisphere != Hemisphere::north) return true;
  if (lat_deg >= 56.0 && lat_deg < 64.0) {
    if (zone.number == 31) east = 3.0;
    if (zone.number == 32) west = 3.0;
  }
  if (lat_deg >= 72.0 && lat_deg < 84.0) {
    switch (zone.number) {
      case 31: west = 0.0, east = 9.0; break;
      case 33: west = 9.0, east = 21.0; break;
      case 35: west = 21.0, east = 33.0; break;
      case 37: west = 33.0, east = 42.0; break;
      case 32:
      case 34:
      case 36: return false;
      default: break;
    }
  }
  return true;
}

}  // namespace

UtmBandCheck utm_band_check(const UtmZone& zone, const GeodeticPosition& p) {
  UtmBandCheck c;
  const double lat = p.lat.deg(), lon = p.lon.deg();
  if (!std::isfinite(lat) || !std::isfinite(lon)) {
    c.excess = Angle::degrees(kNan);
    return c;
  }
  const bool north = zone.hemisphere == Hemisphere::north;
  const double lat_lo = north ? 0.0 : -80.0, lat_hi = north ? 84.0 : 0.0;
  double west = 0, east = 0;
  c.band_exists = utm_band_longitudes(zone, lat, west, east);
  const double half = 0.5 * (east - west);
  const double off_centre = std::fabs(GeographicLib::Math::AngDiff(west + half, lon));
  const double lon_excess = std::max(0.0, off_centre - half);
  const double lat_excess = std::max({0.0, lat_lo - lat, lat - lat_hi});
  c.excess = Angle::degrees(std::max(lon_excess, lat_excess));
  return c;
}

std::string utm_band_text(const UtmZone& zone, Angle lat) {
  const bool north = zone.hemisphere == Hemisphere::north;
  double west = 0, east = 0;
  if (!utm_band_longitudes(zone, lat.deg(), west, east)) {
    return "none: UTM zone " + std::to_string(zone.number) +
           " is not used between 72°N and 84°N (Svalbard: 31X, 33X, 35X and 37X cover 0°–42°E)";
  }
  return meridian_text(west) + "–" + meridian_text(east) + ", " + parallel_text(north ? 0.0 : -80.0) + "–" +
         parallel_text(north ? 84.0 : 0.0);
}

WebMercatorInverse web_mercator_inverse(double easting_m, double northing_m) {
  constexpr double kRadiusM = 6378137.0;  // EPSG:3857's sphere: the WGS 84 semi-major axis
  // EPSG method 1024: lat = π/2 − 2 atan(exp(−N/a)), lon = E/a; atan(sinh(N/a))
  // is the same function (the inverse Gudermannian) without cancellation.
  const double lat = std::atan(std::sinh(northing_m / kRadiusM));
  const double lon = easting_m / kRadiusM;
  return WebMercatorInverse{Angle::radians(lat), Angle::radians(lon)};
}

}  // namespace geoanchor::geodesy
