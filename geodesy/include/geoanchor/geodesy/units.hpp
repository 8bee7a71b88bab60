#pragma once
// Angles, scale differences and epochs with their unit in the type.
//
// An Angle is built only through a named unit (degrees, radians, arc-seconds,
// milliarc-seconds) and read back only through a named unit, so a bare double
// can never be taken for the wrong one. It is stored in degrees: geographic
// latitudes and longitudes arrive in degrees, and GeographicLib reduces degree
// arguments exactly (sin 90° is exactly 1), so a round trip through this type
// never pushes a pole past 90°.

#include <cmath>
#include <numbers>

namespace geoanchor::geodesy {

class Angle {
 public:
  constexpr Angle() = default;
  static constexpr Angle degrees(double v) { return Angle(v); }
  static constexpr Angle radians(double v) { return Angle(v * (180.0 / std::numbers::pi)); }
  static constexpr Angle arcseconds(double v) { return Angle(v / 3600.0); }
  static constexpr Angle milliarcseconds(double v) { return Angle(v / 3600000.0); }

  constexpr double deg() const { return deg_; }
  constexpr double rad() const { return deg_ * (std::numbers::pi / 180.0); }
  constexpr double arcsec() const { return deg_ * 3600.0; }
  constexpr double mas() const { return deg_ * 3600000.0; }

  constexpr Angle operator-() const { return Angle(-deg_); }
  constexpr Angle operator+(Angle o) const { return Angle(deg_ + o.deg_); }
  constexpr Angle operator-(Angle o) const { return Angle(deg_ - o.deg_); }
  constexpr Angle operator*(double k) const { return Angle(deg_ * k); }
  constexpr bool operator==(const Angle&) const = default;

 private:
  constexpr explicit Angle(double deg) : deg_(deg) {}
  double deg_ = 0.0;
};

// A scale difference ds, so that the scale factor is 1 + ds.
class ScaleDifference {
 public:
  constexpr ScaleDifference() = default;
  static constexpr ScaleDifference ppm(double v) { return ScaleDifference(v * 1e-6); }
  static constexpr ScaleDifference ppb(double v) { return ScaleDifference(v * 1e-9); }
  static constexpr ScaleDifference unitless(double v) { return ScaleDifference(v); }

  constexpr double ppm() const { return ds_ * 1e6; }
  constexpr double ppb() const { return ds_ * 1e9; }
  constexpr double unitless() const { return ds_; }

  constexpr ScaleDifference operator-() const { return ScaleDifference(-ds_); }
  constexpr ScaleDifference operator+(ScaleDifference o) const { return ScaleDifference(ds_ + o.ds_); }
  constexpr ScaleDifference operator*(double k) const { return ScaleDifference(ds_ * k); }
  constexpr bool operator==(const ScaleDifference&) const = default;

 private:
  constexpr explicit ScaleDifference(double ds) : ds_(ds) {}
  double ds_ = 0.0;
};

// A coordinate or reference epoch as a decimal year (2024.5 is 1 July 2024).
struct DecimalYear {
  double year = 0.0;
  constexpr bool operator==(const DecimalYear&) const = default;
};

// Years from `from` to `to` (positive when `to` is later).
constexpr double years_between(DecimalYear from, DecimalYear to) { return to.year - from.year; }

}  // namespace geoanchor::geodesy
