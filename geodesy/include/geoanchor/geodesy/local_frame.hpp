#pragma once
// Local tangent frames at an origin: ECEF <-> ENU (EPSG method 9836,
// "geocentric/topocentric") and ENU <-> NED.
//
// ENU: x east, y north, z up along the ellipsoid normal at the origin.
// NED: x north, y east, z down. Both are right-handed.

#include <Eigen/Core>

#include "geoanchor/geodesy/affine.hpp"
#include "geoanchor/geodesy/positions.hpp"

namespace geoanchor::geodesy {

class LocalTangentPlane {
 public:
  explicit LocalTangentPlane(const LocalOrigin& origin);

  EnuPosition enu_from_ecef(const EcefPosition& p) const;
  // NaN coordinates if `p` belongs to another origin: an ENU vector means
  // nothing without its own origin.
  EcefPosition ecef_from_enu(const EnuPosition& p) const;

  // The same conversions as affine maps, for fusing into longer chains.
  AffineMap enu_from_ecef_map() const;
  AffineMap ecef_from_enu_map() const;

  const LocalOrigin& origin() const { return origin_; }
  const Eigen::Vector3d& origin_ecef_m() const { return origin_ecef_m_; }
  // Rows: the east, north and up unit vectors expressed in ECEF.
  const Eigen::Matrix3d& enu_from_ecef_rotation() const { return rotation_; }

 private:
  LocalOrigin origin_;
  Eigen::Vector3d origin_ecef_m_;
  Eigen::Matrix3d rotation_;
};

// Rows: the east, north and up unit vectors at (lat, lon), in ECEF.
Eigen::Matrix3d enu_from_ecef_rotation(Angle lat, Angle lon);

NedPosition ned_from_enu(const EnuPosition& p);
EnuPosition enu_from_ned(const NedPosition& p);

}  // namespace geoanchor::geodesy
