#pragma once
// CSV cells <-> ECEF for one row, given what the header and the command line
// say about the coordinates. Used by `convert` and by CSV tiles in `apply`.

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/geoid.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/geodesy/projection.hpp"
#include "geoanchor/io/control/coordinate_columns.hpp"
#include "geoanchor/io/csv.hpp"

namespace geoanchor::io {

// The points a UTM zone was forced onto (--zone, --from-zone, a tile's
// zone, a utm_zone column) although they lie outside its band by more than
// geodesy::kUtmBandMargin: how many, and the farthest. They are still
// computed (up to 35° from the central meridian, where UTM keeps its
// accuracy); the tally becomes one warning per zone, not one per point.
struct UtmBandTally {
  std::optional<geodesy::UtmZone> zone;
  std::size_t points = 0;
  double worst_excess_deg = 0.0;  // degrees beyond the band at the farthest point
  double worst_lat_deg = 0.0, worst_lon_deg = 0.0;
  std::size_t worst_index = 0;    // in the arrays of one PointChain call
  std::string worst_where;        // file:line or "point N", set by the caller
  bool zone_unused = false;       // a zone the grid does not use there (32X, 34X, 36X)

  // Counts `p`, whose `check` is outside_band_margin (callers test that
  // first, so that the points inside cost no text).
  void add(const geodesy::UtmZone& z, const geodesy::GeodeticPosition& p, const geodesy::UtmBandCheck& check,
           std::size_t index, std::string_view where);
  // Adds another tally's points; its farthest point is named `where`.
  void absorb(const UtmBandTally& other, std::string_view where);
  // "output UTM zone 31N: 2 points lie outside its band ...", or nothing
  // when no point was counted. `role` says which zone ("output", "--zone").
  std::optional<std::string> warning(std::string_view role) const;
};

// The frame the input coordinates are in, beyond what the header says.
struct InputCoordinateFrame {
  geodesy::Ellipsoid ellipsoid = geodesy::Ellipsoid::wgs84();
  std::optional<geodesy::LocalOrigin> origin;         // ENU/NED input
  std::optional<geodesy::ProjectionDef> projection;   // projected input, unless a utm_zone column gives it
  const geodesy::GeoidGrid* geoid = nullptr;          // for an H_m column (h = H + N)
};

class CoordinateDecoder {
 public:
  // Throws geoanchor::Error (usage) when the frame lacks what `columns`
  // needs (an origin for ENU/NED, a projection for easting/northing), and
  // (input) for an H_m column without a geoid.
  CoordinateDecoder(const CoordinateColumns& columns, const std::vector<std::string>& header,
                    InputCoordinateFrame frame, std::string source_name);

  // ECEF of the record's coordinates. Throws geoanchor::Error (input)
  // naming file:line, column and value for an unparsable, non-finite or
  // out-of-range value.
  geodesy::EcefPosition decode(const CsvRecord& record) const;

  // Geodetic or projected input without an h column (heights read as 0).
  bool heights_missing() const {
    return (columns_.kind == CoordinateKind::geodetic || columns_.kind == CoordinateKind::projected) && !columns_.third;
  }

  // Warnings about the rows decoded so far: easting/northing whose UTM zone
  // (--from-zone, a utm_zone column) does not contain them, one per zone.
  std::vector<std::string> warnings() const;

 private:
  double number(const CsvRecord& r, std::size_t column) const;
  const geodesy::TransverseMercator& utm(const geodesy::UtmZone& zone) const;
  CoordinateColumns columns_;
  std::vector<std::string> header_;
  InputCoordinateFrame frame_;
  std::string source_;
  geodesy::GeocentricConverter geocentric_;
  std::optional<geodesy::LocalTangentPlane> plane_;
  std::optional<geodesy::TransverseMercator> projection_;
  mutable std::map<std::string, geodesy::TransverseMercator> utm_by_zone_;  // per-row zones, built once each
  mutable std::map<std::string, UtmBandTally> band_by_zone_;                // rows outside their zone's band
};

enum class OutputKind { geodetic, ecef, enu, ned, utm, tm };
std::string_view to_string(OutputKind k);

struct OutputCoordinateFrame {
  OutputKind kind = OutputKind::ecef;
  geodesy::Ellipsoid ellipsoid = geodesy::Ellipsoid::wgs84();
  std::optional<geodesy::LocalOrigin> origin;        // enu, ned
  std::optional<geodesy::UtmZone> zone;              // utm: fixed zone, else each point's own
  std::optional<geodesy::TransverseMercatorParams> tm;
  // Geodetic, UTM and TM output: write orthometric heights H_m = h − N on
  // this geoid instead of h_m.
  const geodesy::GeoidGrid* geoid = nullptr;
};

// Text of numbers: full precision (shortest round trip) by default; with
// `decimals`, that many decimals for metres and five more for degrees
// (1e-5° is about 1.1 m on the ground, so both round at the same distance).
struct NumberFormat {
  std::optional<int> decimals;
  std::string metres(double v) const;
  std::string degrees(double v) const;
};

class CoordinateEncoder {
 public:
  // Throws geoanchor::Error (usage) when the frame lacks what `kind` needs.
  explicit CoordinateEncoder(OutputCoordinateFrame frame, NumberFormat format);

  const std::vector<std::string>& column_names() const { return names_; }
  // Text of each output column for a point. Throws geoanchor::Error (input)
  // naming `where` when the point cannot be expressed (UTM outside
  // [-80°, 84°], a projection outside its domain, outside the geoid grid,
  // ...) and whenever a value would not be finite: no NaN or infinity is
  // ever written.
  std::vector<std::string> encode(const geodesy::EcefPosition& p, std::string_view where) const;

  // Warnings about the points encoded so far: points outside the band of
  // the forced --zone (one warning for all of them).
  std::vector<std::string> warnings() const;

 private:
  const geodesy::TransverseMercator& utm(const geodesy::UtmZone& zone) const;
  double height(const geodesy::GeodeticPosition& g, std::string_view where) const;  // h, or H = h − N
  OutputCoordinateFrame frame_;
  NumberFormat format_;
  std::vector<std::string> names_;
  geodesy::GeocentricConverter geocentric_;
  std::optional<geodesy::LocalTangentPlane> plane_;
  std::optional<geodesy::TransverseMercator> projection_;
  mutable std::map<std::string, geodesy::TransverseMercator> utm_by_zone_;  // per-point zones, built once each
  mutable UtmBandTally band_;                                               // points outside the forced --zone's band
};

}  // namespace geoanchor::io
