#pragma once
// Geoid undulations from a grid: N such that h (ellipsoidal) = H
// (orthometric) + N. The grid is read from a NOAA VDatum ".gtx" file, the
// format of PROJ's egm96_15.gtx (proj-data), and interpolated bilinearly in
// latitude and longitude as PROJ's vgridshift does, so that geoanchor and a
// PROJ pipeline on the same grid give the same heights.
//
// EGM96 on its 15′ grid: NGA/NASA's Earth Gravitational Model 1996 (Lemoine
// et al. 1998, NASA/TP-1998-206861) tabulated at 15′ in the tide-free
// system relative to WGS 84. Bilinear interpolation of that grid differs
// from the model's spherical-harmonic values by up to several centimetres
// in rough gravity fields; docs/frames.md gives the figures.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "geoanchor/geodesy/units.hpp"

namespace geoanchor::geodesy {

class GeoidGrid {
 public:
  // Throws geoanchor::Error: io when the file cannot be read, input when it
  // is not a .gtx grid (header, size), naming the file.
  static GeoidGrid load_gtx(const std::filesystem::path& path, std::string model_name);

  // EGM96 from PROJ's data directory ($PROJ_DATA, $PROJ_LIB, then
  // /usr/share/proj), loaded once. Throws as load_gtx, saying which package
  // provides it.
  static const GeoidGrid& egm96();

  // N in metres at (lat, lon); NaN outside the grid or for NaN input.
  double undulation_m(Angle lat, Angle lon) const;
  // The same, throwing geoanchor::Error (input) that names `where` and the
  // model outside the grid.
  double undulation_m(Angle lat, Angle lon, std::string_view where) const;

  const std::string& model_name() const { return name_; }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::string name_;
  std::filesystem::path path_;
  double lat0_deg_ = 0, lon0_deg_ = 0, dlat_deg_ = 0, dlon_deg_ = 0;
  std::int32_t rows_ = 0, cols_ = 0;
  bool global_lon_ = false;  // the columns span 360°: longitudes wrap
  std::vector<float> values_m_;  // rows_ × cols_, south row first, west to east
};

}  // namespace geoanchor::geodesy
