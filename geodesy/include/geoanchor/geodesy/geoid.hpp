#pragma once
// Geoid undulations from a grid: N such that h (ellipsoidal) = H
// (orthometric) + N. The grid is read from a NOAA VDatum ".gtx" file, the
// format of PROJ's egm96_15.gtx (proj-data), from an AUSGeoid-style NTv2
// file that also carries the deflections of the vertical (load_ntv2), or
// evaluated by PROJ (from_evaluator). A .gtx grid is interpolated in one of
// two ways:
//  - bilinear in latitude and longitude, as PROJ's vgridshift does, so that
//    geoanchor and a PROJ pipeline on the same grid give the same heights
//    (model "EGM96");
//  - as NGA's own INTPT.F interpolates its 15′ grid: a natural cubic spline
//    through the 4 × 4 nodes around the point, along each row and then down
//    the column (model "EGM96-NGA"). It reproduces NGA's published check
//    values (readme of WW15MGH.GRD) to the millimetre they are given in.
// The two differ by up to several centimetres where the geoid is rough (5.6
// cm at one of NGA's six check points); docs/frames.md gives the figures.
//
// EGM96 on its 15′ grid: NGA/NASA's Earth Gravitational Model 1996 (Lemoine
// et al. 1998, NASA/TP-1998-206861) tabulated at 15′ in the tide-free
// system relative to WGS 84.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/geodesy/units.hpp"

namespace geoanchor::geodesy {

// bicubic: the tensor product of Catmull–Rom cubics through the 4 × 4
// nodes around the point (a bicubic Hermite patch whose node derivatives
// are central differences: Numerical Recipes' bcuint as DynAdjust's
// dnageoid evaluates AUSGeoid; nodes past the grid's edge repeat the edge).
enum class GeoidInterpolation { bilinear, nga_spline, bicubic };

const char* to_string(GeoidInterpolation i);  // "bilinear", "bicubic", …

// The deflection of the vertical: ξ = Φ − φ (north–south component,
// positive when the astronomic zenith lies north of the ellipsoid normal)
// and η = (Λ − λ) cos φ (east–west, positive to the east); radians.
struct Deflection {
  double xi_rad = 0.0;
  double eta_rad = 0.0;
};

class GeoidGrid {
 public:
  // Throws geoanchor::Error: io when the file cannot be read, input when it
  // is not a .gtx grid (header, size), naming the file.
  static GeoidGrid load_gtx(const std::filesystem::path& path, std::string model_name);

  // A geoid grid in NTv2 form as AUSGeoid is distributed (Geoscience
  // Australia; DynAdjust's dnageoid reads and writes it): one sub-grid in
  // arc-seconds, longitudes positive west, each node's four float32 fields
  // N (m), ξ (″), η (″) and an unused fourth; SYSTEM_T names the height
  // datum (AHD_1971). Throws geoanchor::Error naming the file and why it is
  // no such grid (a horizontal shift grid, several sub-grids, a short file).
  static GeoidGrid load_ntv2(const std::filesystem::path& path, GeoidInterpolation interpolation);
  // Whether `bytes` begin as an NTv2 file does (NUM_OREC, either byte order).
  static bool looks_like_ntv2(std::string_view bytes);

  // EGM96 from PROJ's data directory ($PROJ_DATA, $PROJ_LIB, then
  // /usr/share/proj), loaded once. Throws as load_gtx, saying which package
  // provides it.
  static const GeoidGrid& egm96();
  // The same grid interpolated as NGA's INTPT.F does (4 × 4 natural cubic
  // spline); its model name says so.
  static const GeoidGrid& egm96_nga();

  // A grid another library evaluates (crs/proj_geoid.hpp: PROJ's
  // vgridshift on any grid format PROJ reads): `n_at(lat_deg, lon_deg)`
  // returns N in metres, NaN outside the grid. It must be safe to call from
  // several threads.
  static GeoidGrid from_evaluator(std::string model_name, std::filesystem::path path,
                                  std::function<double(double, double)> n_at);

  // N in metres at (lat, lon); NaN outside the grid or for NaN input.
  double undulation_m(Angle lat, Angle lon) const;
  // The same, throwing geoanchor::Error (input) that names `where` and the
  // model outside the grid.
  double undulation_m(Angle lat, Angle lon, std::string_view where) const;

  // ξ and η at (lat, lon), interpolated as N is; nullopt when the grid
  // carries no deflections, outside the grid, or for NaN input.
  std::optional<Deflection> deflection(Angle lat, Angle lon) const;
  bool has_deflections() const { return !xi_arcsec_.empty(); }

  const std::string& model_name() const { return name_; }
  GeoidInterpolation interpolation() const { return interpolation_; }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::string name_;
  std::filesystem::path path_;
  double lat0_deg_ = 0, lon0_deg_ = 0, dlat_deg_ = 0, dlon_deg_ = 0;
  std::int32_t rows_ = 0, cols_ = 0;
  bool global_lon_ = false;  // the columns span 360°: longitudes wrap
  GeoidInterpolation interpolation_ = GeoidInterpolation::bilinear;
  double spline_m(double row, double col) const;
  // A field of the grid at (lat, lon) by the grid's interpolation; NaN outside.
  double sample(const std::vector<float>& field, double lat_deg, double lon_deg) const;
  std::vector<float> values_m_;  // rows_ × cols_, south row first, west to east
  std::vector<float> xi_arcsec_, eta_arcsec_;  // the same nodes' deflections (NTv2 geoid grids), else empty
  std::shared_ptr<const std::function<double(double, double)>> external_;  // from_evaluator
};

// The geoid at an ECEF position: N there and the local up (unit vector in
// ECEF). Heights of one frame taken as orthometric where they should be
// ellipsoidal sit N too low along this up: the one computation behind
// `diagnose`'s height_type hypothesis and the fit check that a fitted
// vertical offset looks like N (workflow::orthometric_height_warning).
// n_m is NaN outside the grid.
struct GeoidAlongUp {
  double n_m = 0.0;
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
};
inline GeoidAlongUp geoid_along_up(const GeoidGrid& geoid, const GeocentricConverter& geocentric, const EcefPosition& at) {
  const GeodeticPosition g = geocentric.geodetic_from_ecef(at);
  return {geoid.undulation_m(g.lat, g.lon), enu_from_ecef_rotation(g.lat, g.lon).row(2).transpose()};
}

}  // namespace geoanchor::geodesy
