#pragma once
// Geoid undulations from a grid: N such that h (ellipsoidal) = H
// (orthometric) + N. The grid is read from a NOAA VDatum ".gtx" file, the
// format of PROJ's egm96_15.gtx (proj-data), and interpolated in one of two
// ways:
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
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/geodesy/units.hpp"

namespace geoanchor::geodesy {

enum class GeoidInterpolation { bilinear, nga_spline };

class GeoidGrid {
 public:
  // Throws geoanchor::Error: io when the file cannot be read, input when it
  // is not a .gtx grid (header, size), naming the file.
  static GeoidGrid load_gtx(const std::filesystem::path& path, std::string model_name);

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
  std::vector<float> values_m_;  // rows_ × cols_, south row first, west to east
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
