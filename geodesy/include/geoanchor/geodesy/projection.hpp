#pragma once
// Transverse Mercator projections (EPSG method 9807) through GeographicLib's
// TransverseMercator: Krüger's series to sixth order in n, accurate to 5 nm
// within 3,900 km of the central meridian (Karney 2011).
//
// UTM is the Transverse Mercator with k0 = 0.9996, false easting 500 000 m,
// false northing 0 (north) or 10 000 000 m (south), central meridian
// 6·zone − 183°, on the ellipsoid of the data (GRS 80 for NAD83/GDA/ETRS89,
// WGS 84 for WGS 84: they differ by up to 0.1 mm in northing).

#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "geoanchor/geodesy/ellipsoid.hpp"
#include "geoanchor/geodesy/positions.hpp"

namespace geoanchor::geodesy {

enum class Hemisphere { north, south };

struct UtmZone {
  int number = 0;  // 1..60
  Hemisphere hemisphere = Hemisphere::north;
  std::string to_string() const;  // "32N", "55S"
  bool operator==(const UtmZone&) const = default;
};

// "32N", "32n", "55S" -> zone. Throws geoanchor::Error (input) naming `where`.
UtmZone parse_utm_zone(std::string_view text, std::string_view where);

// The zone a point belongs to on the official UTM grid: 6° zones from 180°W,
// with the Norway (32V widened to 3°E–12°E) and Svalbard (31X, 33X, 35X, 37X)
// exceptions, as GeographicLib's UTMUPS::StandardZone applies them.
// std::nullopt outside UTM's latitude range [-80°, 84°) (the UPS regions).
std::optional<UtmZone> standard_utm_zone(const GeodeticPosition& p);

struct TransverseMercatorParams {
  Angle lat0;                  // latitude of natural origin
  Angle lon0;                  // central meridian
  double k0 = 1.0;             // scale factor on the central meridian
  double false_easting_m = 0.0;
  double false_northing_m = 0.0;
};

TransverseMercatorParams utm_params(const UtmZone& zone);

// A Transverse Mercator on a given ellipsoid; optionally a UTM zone.
struct ProjectionDef {
  Ellipsoid ellipsoid = Ellipsoid::wgs84();
  TransverseMercatorParams tm;
  std::optional<UtmZone> utm;  // set when tm are this zone's UTM parameters

  bool operator==(const ProjectionDef& o) const;
};

ProjectionDef utm_projection(const Ellipsoid& e, const UtmZone& zone);

// Easting, northing on `projection`, and the ellipsoidal height carried along.
struct ProjectedPosition {
  double easting_m = 0.0;
  double northing_m = 0.0;
  EllipsoidalHeight h;
  ProjectionDef projection;
};

class TransverseMercator {
 public:
  explicit TransverseMercator(const ProjectionDef& def);
  ~TransverseMercator();
  TransverseMercator(const TransverseMercator&);
  TransverseMercator& operator=(const TransverseMercator&);

  ProjectedPosition forward(const GeodeticPosition& p) const;
  // NaN coordinates if `p` is on another projection.
  GeodeticPosition inverse(const ProjectedPosition& p) const;

  const ProjectionDef& definition() const { return def_; }

 private:
  struct Impl;
  static std::unique_ptr<Impl> make_impl(const ProjectionDef& def);
  ProjectionDef def_;
  std::unique_ptr<Impl> impl_;
};

// Web Mercator ("Popular Visualisation Pseudo Mercator", EPSG method 1024,
// the projection of EPSG:3857): the spherical Mercator formulas applied to
// WGS 84 latitude and longitude with the sphere's radius a = 6 378 137 m, no
// false origin. It is not conformal on the ellipsoid and its scale is
// 1/cos(lat) everywhere, so its metres are not ground metres (EPSG Guidance
// Note 7-2, method 1024). Latitude and longitude of easting, northing;
// NaN for non-finite input.
struct WebMercatorInverse {
  Angle lat;
  Angle lon;
};
WebMercatorInverse web_mercator_inverse(double easting_m, double northing_m);

}  // namespace geoanchor::geodesy
