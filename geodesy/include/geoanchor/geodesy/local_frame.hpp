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

// A map's ENU frame re-anchored: the ECEF map taking "ECEF of map point
// read at the nominal origin" to its true ECEF position,
//   x_true = O' + R'ᵀ · (1 + ds) · Rz(yaw) · R (x_nominal − O),
// where O' = O + Rᵀ · shift_enu_m is the corrected origin, R and R' the ENU
// rotations at O and O', and Rz(yaw) turns the map counter-clockwise seen
// from above (east towards north) by `yaw`.
AffineMap enu_origin_correction(const LocalOrigin& nominal, const Eigen::Vector3d& shift_enu_m, Angle yaw,
                                ScaleDifference ds);
// The corrected origin O' of the same correction, on the nominal's ellipsoid.
LocalOrigin corrected_origin(const LocalOrigin& nominal, const Eigen::Vector3d& shift_enu_m);

NedPosition ned_from_enu(const EnuPosition& p);
EnuPosition enu_from_ned(const NedPosition& p);

}  // namespace geoanchor::geodesy
