#pragma once
// Position value types. The kind of coordinate is in the type; what a local
// coordinate is relative to (its origin, its projection) travels inside the
// value, so an ENU vector cannot be converted with somebody else's origin.
//
// Every coordinate is float64. An ECEF position cannot be built from float32
// values: at Earth radius the float32 spacing is 0.5 m.

#include <Eigen/Core>

#include <concepts>

#include "geoanchor/geodesy/ellipsoid.hpp"
#include "geoanchor/geodesy/units.hpp"

namespace geoanchor::geodesy {

// Height above the ellipsoid along the normal, metres.
struct EllipsoidalHeight {
  double m = 0.0;
  constexpr bool operator==(const EllipsoidalHeight&) const = default;
};
// Height above a geoid (mean sea level), metres. It differs from the
// ellipsoidal height by the geoid undulation (tens of metres), so the two are
// distinct types: geodetic -> ECEF accepts only ellipsoidal heights.
struct OrthometricHeight {
  double m = 0.0;
  constexpr bool operator==(const OrthometricHeight&) const = default;
};

template <class Height>
concept HeightType = std::same_as<Height, EllipsoidalHeight> || std::same_as<Height, OrthometricHeight>;

// Geodetic latitude (north positive, [-90°, 90°]), longitude (east positive,
// Greenwich), and a height whose kind is part of the type.
template <HeightType Height>
struct Geodetic {
  Angle lat;
  Angle lon;
  Height h;
};
using GeodeticPosition = Geodetic<EllipsoidalHeight>;
using GeodeticOrthometric = Geodetic<OrthometricHeight>;

// Earth-centred, Earth-fixed Cartesian coordinates, metres: X towards
// (0°N, 0°E), Y towards (0°N, 90°E), Z towards the north pole.
struct EcefPosition {
  Eigen::Vector3d m = Eigen::Vector3d::Zero();

  EcefPosition() = default;
  EcefPosition(double x_m, double y_m, double z_m) : m(x_m, y_m, z_m) {}
  explicit EcefPosition(const Eigen::Vector3d& xyz_m) : m(xyz_m) {}

  // float32 ECEF does not compile: its 0.5 m spacing is a silent error.
  template <std::floating_point T>
    requires(!std::same_as<T, double>)
  EcefPosition(T, T, T) = delete;
  EcefPosition(const Eigen::Vector3f&) = delete;
};

// The origin of a local tangent frame (ENU or NED): a geodetic point with an
// ellipsoidal height, on a stated ellipsoid.
struct LocalOrigin {
  GeodeticPosition point;
  Ellipsoid ellipsoid = Ellipsoid::wgs84();

  bool operator==(const LocalOrigin& o) const {
    return point.lat == o.point.lat && point.lon == o.point.lon && point.h == o.point.h &&
           ellipsoid == o.ellipsoid;
  }
};

// East, north, up in metres, relative to `origin`.
struct EnuPosition {
  Eigen::Vector3d enu_m = Eigen::Vector3d::Zero();
  LocalOrigin origin;
};

// North, east, down in metres, relative to `origin`.
struct NedPosition {
  Eigen::Vector3d ned_m = Eigen::Vector3d::Zero();
  LocalOrigin origin;
};

}  // namespace geoanchor::geodesy
