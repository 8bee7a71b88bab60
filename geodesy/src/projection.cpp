#include "geoanchor/geodesy/projection.hpp"

#include <GeographicLib/TransverseMercator.hpp>
#include <GeographicLib/UTMUPS.hpp>

#include <charconv>
#include <cmath>
#include <limits>

#include "geoanchor/geodesy/error.hpp"

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

struct TransverseMercator::Impl {
  GeographicLib::TransverseMercator tm;
  double northing_of_origin_m;  // unprojected northing of (lat0, lon0)
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
  GeographicLib::TransverseMercator tm(def.ellipsoid.a_m(), def.ellipsoid.f(), def.tm.k0);
  double x = 0, y0 = 0;
  tm.Forward(def.tm.lon0.deg(), def.tm.lat0.deg(), def.tm.lon0.deg(), x, y0);
  return std::make_unique<Impl>(Impl{tm, y0});
}

ProjectedPosition TransverseMercator::forward(const GeodeticPosition& p) const {
  double x = 0, y = 0;
  if (!(std::fabs(p.lat.deg()) <= 90.0)) {
    x = y = std::numeric_limits<double>::quiet_NaN();
  } else {
    impl_->tm.Forward(def_.tm.lon0.deg(), p.lat.deg(), p.lon.deg(), x, y);
  }
  return ProjectedPosition{def_.tm.false_easting_m + x, def_.tm.false_northing_m + (y - impl_->northing_of_origin_m),
                           p.h, def_};
}

GeodeticPosition TransverseMercator::inverse(const ProjectedPosition& p) const {
  if (!(p.projection == def_)) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return GeodeticPosition{Angle::degrees(nan), Angle::degrees(nan), EllipsoidalHeight{nan}};
  }
  double lat = 0, lon = 0;
  impl_->tm.Reverse(def_.tm.lon0.deg(), p.easting_m - def_.tm.false_easting_m,
                    p.northing_m - def_.tm.false_northing_m + impl_->northing_of_origin_m, lat, lon);
  return GeodeticPosition{Angle::degrees(lat), Angle::degrees(lon), p.h};
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
