#include "geoanchor/geodesy/local_frame.hpp"

#include <GeographicLib/Math.hpp>

#include <limits>

#include "geoanchor/geodesy/geocentric.hpp"

namespace geoanchor::geodesy {

Eigen::Matrix3d enu_from_ecef_rotation(Angle lat, Angle lon) {
  // sincosd reduces degrees exactly, so an origin on the equator or a
  // meridian multiple of 90° gives exact zeros and ones.
  double sphi = 0, cphi = 0, slam = 0, clam = 0;
  GeographicLib::Math::sincosd(lat.deg(), sphi, cphi);
  GeographicLib::Math::sincosd(lon.deg(), slam, clam);
  Eigen::Matrix3d r;
  r << -slam, clam, 0.0,               // east
      -sphi * clam, -sphi * slam, cphi,  // north
      cphi * clam, cphi * slam, sphi;    // up
  return r;
}

LocalTangentPlane::LocalTangentPlane(const LocalOrigin& origin)
    : origin_(origin),
      origin_ecef_m_(ecef_from_geodetic(origin.ellipsoid, origin.point).m),
      rotation_(geodesy::enu_from_ecef_rotation(origin.point.lat, origin.point.lon)) {}

EnuPosition LocalTangentPlane::enu_from_ecef(const EcefPosition& p) const {
  // Subtract first: for points near the origin the difference is exact.
  return EnuPosition{rotation_ * (p.m - origin_ecef_m_), origin_};
}

EcefPosition LocalTangentPlane::ecef_from_enu(const EnuPosition& p) const {
  if (!(p.origin == origin_)) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return EcefPosition(nan, nan, nan);
  }
  return EcefPosition(Eigen::Vector3d(origin_ecef_m_ + rotation_.transpose() * p.enu_m));
}

AffineMap LocalTangentPlane::enu_from_ecef_map() const {
  const Eigen::Matrix<long double, 3, 1> t =
      -(rotation_.cast<long double>() * origin_ecef_m_.cast<long double>());
  return AffineMap(rotation_, t.cast<double>());
}

AffineMap LocalTangentPlane::ecef_from_enu_map() const { return AffineMap(rotation_.transpose(), origin_ecef_m_); }

LocalOrigin corrected_origin(const LocalOrigin& nominal, const Eigen::Vector3d& shift_enu_m) {
  const LocalTangentPlane plane(nominal);
  const EcefPosition moved(Eigen::Vector3d(plane.origin_ecef_m() + plane.enu_from_ecef_rotation().transpose() * shift_enu_m));
  return LocalOrigin{geodetic_from_ecef(nominal.ellipsoid, moved), nominal.ellipsoid};
}

AffineMap enu_origin_correction(const LocalOrigin& nominal, const Eigen::Vector3d& shift_enu_m, Angle yaw,
                                ScaleDifference ds) {
  const LocalTangentPlane from(nominal);
  const LocalTangentPlane to(corrected_origin(nominal, shift_enu_m));
  double s = 0, c = 0;
  GeographicLib::Math::sincosd(yaw.deg(), s, c);
  Eigen::Matrix3d rz;
  rz << c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0;
  const AffineMap turn((1.0 + ds.unitless()) * rz, Eigen::Vector3d::Zero());
  return compose(to.ecef_from_enu_map(), compose(turn, from.enu_from_ecef_map()));
}

NedPosition ned_from_enu(const EnuPosition& p) {
  return NedPosition{Eigen::Vector3d(p.enu_m.y(), p.enu_m.x(), -p.enu_m.z()), p.origin};
}

EnuPosition enu_from_ned(const NedPosition& p) {
  return EnuPosition{Eigen::Vector3d(p.ned_m.y(), p.ned_m.x(), -p.ned_m.z()), p.origin};
}

}  // namespace geoanchor::geodesy
