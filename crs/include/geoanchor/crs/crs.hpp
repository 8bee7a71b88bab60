#pragma once
// A coordinate reference system as PROJ reads it: what the user typed
// (EPSG:n, EPSG:h+v, WKT1 or WKT2, PROJJSON, a PROJ string, @FILE holding
// one of those, or a frame name of geoanchor's catalog), optionally with a
// coordinate epoch (CRS@2024.5), and everything geoanchor needs to know
// about it: datum and realization or ensemble, ellipsoid, prime meridian,
// every axis with its direction and unit, the projection, the vertical CRS,
// the area of use and the catalog frame it is (docs/commands/crs.md).
//
// PROJ is the authority for what a CRS means; nothing here parses a CRS by
// hand. PROJ stays private to io: the description is plain data.

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "geoanchor/geodesy/ellipsoid.hpp"
#include "geoanchor/geodesy/units.hpp"

namespace geoanchor::io {

struct CrsAxis {
  std::string name;          // "Easting", "Geodetic latitude"
  std::string abbreviation;  // "E", "Lat"
  std::string direction;     // "east", "north", "south", "up", "geocentricX", …
  std::string unit_name;     // "metre", "US survey foot", "degree", "grad"
  double unit_to_si = 1.0;   // metres or radians per unit
  std::string unit_type;     // "linear" | "angular"
  // The meridian a polar projection's axis points along ("south along
  // 90°E"), degrees east of Greenwich; nullopt when the CRS names none.
  std::optional<double> meridian_deg;
};

struct CrsParameter {
  std::string name;
  std::string epsg_code;  // "" when PROJ names no EPSG code
  double value = 0.0;
  std::string unit_name;
};

struct CrsEllipsoid {
  std::string name;
  double a_m = 0.0;
  double rf = 0.0;  // inverse flattening (0 for a sphere)
};

struct CrsArea {
  std::string name;
  double west_deg = 0.0, south_deg = 0.0, east_deg = 0.0, north_deg = 0.0;  // east < west across 180°
  bool contains(double lon_deg, double lat_deg) const;
};

// What a CRS is, as PROJ reads it. For a compound CRS the horizontal part's
// fields are the top-level ones and `vertical_*` describes the vertical part.
struct CrsDescription {
  std::string name;
  std::string identifier;  // "EPSG:7856" when PROJ names one; "" otherwise
  std::string type;        // "geographic 2D", "geographic 3D", "geocentric", "projected", "compound", "vertical"
  std::string horizontal_type;  // the type of the horizontal part ("projected" for EPSG:7856+5711)
  std::string datum;            // "Geocentric Datum of Australia 2020", or the ensemble's name
  bool ensemble = false;
  std::vector<std::string> ensemble_members;  // the realizations to choose from
  std::optional<double> ensemble_accuracy_m;
  bool dynamic = false;  // a dynamic datum: a coordinate needs its epoch
  std::optional<double> frame_reference_epoch;
  std::string catalog_frame;  // geoanchor's frame name ("GDA2020", "ITRF2014"), "" when none
  std::string prime_meridian;
  double prime_meridian_deg = 0.0;  // from Greenwich
  CrsEllipsoid ellipsoid;
  std::vector<CrsAxis> axes;  // in the CRS's own order, horizontal then vertical
  // The same axes in the order PROJ's proj_normalize_for_visualization
  // gives (longitude or easting first): the order CrsOperation takes.
  std::vector<CrsAxis> visualization_axes;
  std::string projection_method;  // "" for geographic and geocentric CRSs
  std::string projection_method_code;
  std::vector<CrsParameter> projection_parameters;
  std::string vertical_crs;    // "" when none
  std::string vertical_datum;  // "Australian Height Datum"
  // The geoid grid PROJ's best operation from the horizontal CRS's
  // ellipsoidal heights to the vertical CRS uses ("" when PROJ knows none),
  // and whether it is on this machine.
  std::string geoid_model;
  bool geoid_available = false;
  // The operation (or step) that applies that grid, which names the geoid
  // model in the WKT2 geoanchor writes (GEOIDMODEL["WGS 84 to EGM96 height
  // (1)",ID["EPSG",10084]]); "" when none.
  std::string geoid_operation;
  std::string geoid_operation_id;  // "EPSG:10084", or ""
  std::optional<CrsArea> area;
};

// A CRS read through PROJ, with its optional coordinate epoch. Copies share
// one PROJ object and context and are not safe to use from two threads at
// once; a `CrsOperation` builds its own PROJ objects in its own context
// (one per CrsOperation; a thread needs its own CrsOperation).
class Crs {
 public:
  // Throws geoanchor::Error (input, E_CRS) naming `where` (a flag or key)
  // and the text for a code PROJ does not know, text PROJ cannot parse, an
  // unreadable @FILE, an epoch that is not a decimal year, a frame name the
  // catalog does not know, or an ambiguous frame name (WGS84, ETRS89,
  // NAD83(CSRS): E_CRS_ENSEMBLE lists the realizations). An epoch on a
  // static CRS is kept (CrsOperation refuses it where nothing uses it).
  static Crs parse(std::string_view text, std::string_view where);

  const CrsDescription& description() const;
  const std::optional<geodesy::DecimalYear>& epoch() const { return epoch_; }
  const std::string& text() const { return text_; }  // as the user typed it
  // Whether it was given as a frame name of the catalog ("ITRF2014@2024.5"):
  // a frame, whose geographic or geocentric CRS the columns choose.
  bool from_frame_name() const { return from_frame_name_; }
  std::string display_name() const;                  // "EPSG:7856 (GDA2020 / MGA zone 56)[@epoch]"

  // PROJ's WKT2:2019 and PROJJSON of the CRS (both read back by PROJ as the
  // same CRS). The coordinate epoch is not part of them (PROJ 9.1 has no
  // coordinate metadata); the sidecars record it beside. The WKT2 of a
  // compound CRS names its geoid model (GEOIDMODEL, the operation PROJ
  // applies its grid with) where PROJ knows one and the CRS names none.
  std::string wkt2() const;
  std::string projjson() const;

  // The same CRS at coordinate epoch `epoch` (a dynamic CRS only; throws
  // geoanchor::Error for a static one, as parse does).
  Crs at_epoch(geodesy::DecimalYear epoch, std::string_view where) const;
  // The same CRS with no coordinate epoch (for an operation that does not
  // depend on it, such as the conversion to its own geocentric CRS).
  Crs without_epoch() const;

  // Whether PROJ holds the two for the same CRS (proj_is_equivalent_to,
  // PJ_COMP_EQUIVALENT: names may differ) at the same coordinate epoch.
  bool same_as(const Crs& other) const;

  // The same CRS with an ellipsoidal height axis added (a 2-D geographic or
  // projected CRS); itself when it has three axes already. Throws for a
  // type that cannot be promoted.
  Crs promoted_to_3d(std::string_view where) const;
  // The horizontal part as a 2-D CRS: a compound CRS's first part, a 3-D
  // geographic or projected CRS without its ellipsoidal height axis;
  // itself when it is 2-D already or geocentric. Keeps the epoch.
  Crs horizontal(std::string_view where) const;
  // The geocentric CRS on the same datum (for x_m, y_m, z_m columns), its
  // X axis through Greenwich as geoanchor's ECEF has it: for a datum on
  // another prime meridian (NTF (Paris)) the same datum on Greenwich.
  Crs geocentric(std::string_view where) const;

  struct Impl;
  const Impl& impl() const { return *impl_; }

 private:
  Crs(std::shared_ptr<Impl> impl, std::optional<geodesy::DecimalYear> epoch, std::string text);
  std::shared_ptr<Impl> impl_;
  std::optional<geodesy::DecimalYear> epoch_;
  std::string text_;
  bool from_frame_name_ = false;
};

// The ellipsoid as geoanchor's type: WGS84 or GRS80 when a and 1/f are
// theirs (to 1e-9 relative), else a custom one with the CRS's values.
geodesy::Ellipsoid typed_ellipsoid(const CrsEllipsoid& e);

// The version of the PROJ library geoanchor reads CRSs with ("9.1.1").
std::string proj_version_text();

// The PROJJSON of a WKT (a CRS or a coordinate operation), or nullopt when
// PROJ does not read it.
std::optional<std::string> projjson_from_wkt(const std::string& wkt);

// The unit suffix of an axis's unit in a column name: "m", "ft" (the
// international foot), "ftus" (the US survey foot), "km", "deg", "grad".
// Throws geoanchor::Error (input, E_CRS_UNIT) naming the CRS, the axis and
// its unit for a unit geoanchor has no column name for.
std::string column_unit_suffix(const CrsAxis& axis, std::string_view crs_name);

}  // namespace geoanchor::io
