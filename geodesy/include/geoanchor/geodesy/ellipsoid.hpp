#pragma once
// A reference ellipsoid: semi-major axis a (metres) and flattening f.

#include <optional>
#include <string>
#include <string_view>

namespace geoanchor::geodesy {

class Ellipsoid {
 public:
  // GRS 80 (EPSG:7019) and WGS 84 (EPSG:7030). They differ only in 1/f
  // (298.257222101 vs 298.257223563): 0.1 mm in b, which matters at our level.
  static Ellipsoid wgs84();
  static Ellipsoid grs80();
  // Any other ellipsoid by a (metres) and inverse flattening rf (> 1; a
  // sphere is not supported). Throws geoanchor::Error (input) for a value
  // outside a in [6.0e6, 7.0e6] m or rf in [250, 350] (every Earth ellipsoid in
  // the EPSG dataset lies inside both ranges).
  static Ellipsoid custom(double a_m, double rf, std::string name = "custom");

  double a_m() const { return a_m_; }
  double f() const { return 1.0 / rf_; }
  double rf() const { return rf_; }
  double b_m() const { return a_m_ * (1.0 - f()); }
  double e2() const { return f() * (2.0 - f()); }  // first eccentricity squared
  const std::string& name() const { return name_; }

  bool operator==(const Ellipsoid& o) const { return a_m_ == o.a_m_ && rf_ == o.rf_; }

 private:
  Ellipsoid(double a_m, double rf, std::string name) : a_m_(a_m), rf_(rf), name_(std::move(name)) {}
  double a_m_;
  double rf_;
  std::string name_;
};

// An ellipsoid by its EPSG name, with a and 1/f as the EPSG dataset defines
// them (tests/geodesy/frame_units_test.cpp compares each with proj.db):
// "GRS 1980" (also "GRS80"), "WGS 84" ("WGS84"), "International 1924",
// "Bessel 1841", "Clarke 1866", "Clarke 1880 (RGS)", "Airy 1830",
// "Krassowsky 1940", "GRS 1967", "Australian National Spheroid". nullopt
// for any other name (compared exactly).
std::optional<Ellipsoid> named_ellipsoid(std::string_view name);
// Those names, for messages: "GRS80, WGS84, International 1924, …".
std::string named_ellipsoid_list();

}  // namespace geoanchor::geodesy
