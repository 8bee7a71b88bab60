#pragma once
// Transverse Mercator projections (EPSG method 9807) through GeographicLib,
// and where each is evaluated.
//
// UTM is the Transverse Mercator with k0 = 0.9996, false easting 500 000 m,
// false northing 0 (north) or 10 000 000 m (south), central meridian
// 6·zone − 183°, on the ellipsoid of the data (GRS 80 for NAD83/GDA/ETRS89,
// WGS 84 for WGS 84: they differ by up to 0.1 mm in northing).
//
// Domain (issue 12 point 1). Let Δλ = λ − λ0 (reduced to [−180°, 180°]) and
// d = asin(cos φ · |sin Δλ|), the great-circle angle from the point to the
// central meridian (on the sphere; 1° ≈ 111 km). Then
//
//   d ≤ 35°        Krüger's series, GeographicLib::TransverseMercator (6th
//                  order). GeographicLib 2.1 documents it as: "The maximum
//                  error is 5 nm (5 nanometers), ground distance, for all
//                  positions within 35 degrees of the central meridian"
//                  (TransverseMercator.hpp; Karney, J. Geodesy 85, 2011,
//                  Sec. 4). PROJ's +proj=tmerc (Poder/Engsager) and every
//                  UTM implementation agree with it there.
//   35° < d ≤ 75°  general TM only: the exact projection,
//                  GeographicLib::TransverseMercatorExact (Lee 1976), "about
//                  8 nm" everywhere (TransverseMercatorExact.hpp), on the same
//                  ellipsoid, k0 and false origin. Beyond 35° the series
//                  drifts from it: 11 µm at 60°, 5 mm at 70°, 0.32 m at 75°,
//                  140 m at 80° on the equator; past the branch point it
//                  returns garbage or NaN.
//   d > 75°        refused. The exact projection has a branch point on the
//                  equator at Δλ = ±(1 − e)·90° (82.6° on WGS 84, at least
//                  81.9° on every ellipsoid Ellipsoid::custom accepts) where
//                  the scale is infinite, and beyond it along the equator a
//                  branch cut across which the grid jumps by thousands of km
//                  (TransverseMercatorExact.hpp, constructor). 75° keeps every
//                  point at least 6.9° (770 km) from it, where the point scale
//                  k/k0 is at most 4.12.
//   |Δλ| > 90°     refused: the far hemisphere (mapped beyond the pole).
//
// UTM is defined by the series, so a UTM projection is never switched to
// the exact method: it is evaluated to d = 35° and refused beyond, however
// the zone was chosen. Grid coordinates are inverted by the same rule: an
// easting/northing is accepted only when its inverse lies in the domain and
// projects back onto it (within kGridRoundTripTol_m), so grid values no
// point of the domain maps to are refused rather than mapped to garbage.

#include <limits>
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

// The limits of the domain above.
inline constexpr Angle kTmSeriesLimit = Angle::degrees(35.0);  // Krüger series: 5 nm (GeographicLib)
inline constexpr Angle kTmExactLimit = Angle::degrees(75.0);   // exact method, general TM only
// An inverse is accepted when projecting its result reproduces the grid
// coordinates within this: 30× the exact method's 8 nm times its largest
// scale in the domain (4.12), so only grid values outside the domain fail.
inline constexpr double kGridRoundTripTol_m = 1e-6;

enum class TmMethod { series, exact };
std::string_view to_string(TmMethod m);  // "Krüger series", "exact"

// Why a point (or grid position) has no image on a Transverse Mercator.
enum class TmRefusal {
  none,
  non_finite,           // a non-finite coordinate, or |lat| > 90°
  far_hemisphere,       // more than 90° of longitude from the central meridian
  beyond_domain,        // d beyond 35° (UTM) or 75° (TM)
  grid_outside_domain,  // inverse: no point of the domain maps to this easting/northing
  other_projection,     // inverse: the position is on another projection
};

// How one point went through a projection: the method used, or why it was
// refused, and where the point lies (the input of forward, the result of
// inverse when there is one; NaN otherwise).
struct TmOutcome {
  TmRefusal refusal = TmRefusal::none;
  TmMethod method = TmMethod::series;
  Angle lat = Angle::degrees(std::numeric_limits<double>::quiet_NaN());
  Angle lon = Angle::degrees(std::numeric_limits<double>::quiet_NaN());
  Angle from_central_meridian = Angle::degrees(std::numeric_limits<double>::quiet_NaN());  // d
  Angle dlon = Angle::degrees(std::numeric_limits<double>::quiet_NaN());                   // Δλ
  bool ok() const { return refusal == TmRefusal::none; }
};

class TransverseMercator {
 public:
  explicit TransverseMercator(const ProjectionDef& def);
  ~TransverseMercator();
  TransverseMercator(const TransverseMercator&);
  TransverseMercator& operator=(const TransverseMercator&);

  // Easting and northing of `p`, or std::nullopt outside the domain (see
  // the top of this header); `outcome` (optional) says which method was used
  // or why the point was refused. Never throws.
  std::optional<ProjectedPosition> try_forward(const GeodeticPosition& p, TmOutcome* outcome = nullptr) const;
  // The same, with NaN easting and northing where try_forward refuses.
  ProjectedPosition forward(const GeodeticPosition& p) const;

  // Latitude and longitude of `p`, or std::nullopt when `p` is on another
  // projection, not finite, or outside the grid of the domain. Never throws.
  std::optional<GeodeticPosition> try_inverse(const ProjectedPosition& p, TmOutcome* outcome = nullptr) const;
  // The same, with NaN coordinates where try_inverse refuses.
  GeodeticPosition inverse(const ProjectedPosition& p) const;

  // How far the projection is evaluated, for messages: "this Transverse
  // Mercator is computed within 75° of its central meridian 0° (Krüger
  // series to 35°, exact method beyond; refused near the branch point at
  // 82.6° on the equator)", or "UTM zone 31N is computed within 35° of its
  // central meridian 3°E (the Krüger series' 5 nm range; UTM is never
  // switched to the exact method)".
  std::string domain() const;
  // Why `o` was refused, with the numbers and domain(): "lat 10, lon 89:
  // 79.2° from the central meridian 3°E; UTM zone 31N is computed ...".
  std::string explain(const TmOutcome& o) const;

  const ProjectionDef& definition() const { return def_; }

 private:
  struct Impl;
  static std::unique_ptr<Impl> make_impl(const ProjectionDef& def);
  // The domain check of one point; `slack_deg` widens the limits (inverse results).
  TmOutcome locate(Angle lat, Angle lon, double slack_deg = 0.0) const;
  ProjectionDef def_;
  std::unique_ptr<Impl> impl_;
};

// The official band of a UTM zone, and how far a point lies outside it.
// The band is the longitudes that UTMUPS::StandardZone gives the zone at the
// point's latitude (6°, or Norway's 32V widened to 3°E–12°E and 31V narrowed
// to 0°–3°E, Svalbard's 31X 0°–9°E, 33X 9°–21°E, 35X 21°–33°E, 37X
// 33°–42°E; 32X, 34X and 36X have none), in the zone's hemisphere between
// 80°S and 84°N.
struct UtmBandCheck {
  bool band_exists = true;  // false for 32X, 34X, 36X
  // Beyond the band: the larger of the longitude and latitude excess; 0
  // inside. NaN for a non-finite point (refused elsewhere, not warned of).
  Angle excess;
};
UtmBandCheck utm_band_check(const UtmZone& zone, const GeodeticPosition& p);  // cheap: no text
// The band at latitude `lat`, for messages: "0°–6°E, 0°–84°N", or "none:
// UTM zone 32 is not used between 72°N and 84°N (...)".
std::string utm_band_text(const UtmZone& zone, Angle lat);

// A forced zone (--zone, --from-zone, --src-zone, a tile's zone) is used
// without a warning up to this far beyond its band: 1° of longitude, 111 km
// on the equator and 56 km at 60°, about GeographicLib's 100 km of "generous
// overlap between UTM zones" (UTMUPS.hpp). Beyond it the output is still
// computed, with a warning, up to d = 35° (kTmSeriesLimit).
inline constexpr Angle kUtmBandMargin = Angle::degrees(1.0);
// Whether `c` is worth a warning: outside the band by more than the margin,
// or in a zone that does not exist at that latitude.
inline bool outside_band_margin(const UtmBandCheck& c) {
  return !c.band_exists || c.excess.deg() > kUtmBandMargin.deg();
}

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
