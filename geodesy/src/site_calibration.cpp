#include "geoanchor/geodesy/site_calibration.hpp"

#include <GeographicLib/Math.hpp>

namespace geoanchor::geodesy {

SiteCalibration::SiteCalibration(const LocalOrigin& local_origin, const ProjectionDef& grid, const SiteCalibrationParams& p)
    : plane_(local_origin), tm_(grid), geocentric_(grid.ellipsoid), p_(p) {}

Eigen::Vector3d SiteCalibration::grid_from_local(const Eigen::Vector3d& enu) const {
  double s = 0, c = 0;
  GeographicLib::Math::sincosd(p_.rotation.deg(), s, c);
  const double k = 1.0 + p_.scale.unitless(), a = k * c, b = k * s;
  const double e = enu.x(), n = enu.y();
  return Eigen::Vector3d(p_.shift_e_m + a * e - b * n, p_.shift_n_m + b * e + a * n,
                         enu.z() + p_.vertical_shift_m + p_.slope_n * (n - p_.centroid_n_m) +
                             p_.slope_e * (e - p_.centroid_e_m));
}

EcefPosition SiteCalibration::target_from_source(const EcefPosition& source) const {
  const Eigen::Vector3d g = grid_from_local(plane_.enu_from_ecef(source).enu_m);
  return geocentric_.ecef_from_geodetic(tm_.inverse(ProjectedPosition{g.x(), g.y(), EllipsoidalHeight{g.z()}, tm_.definition()}));
}

EcefPosition SiteCalibration::source_from_target(const EcefPosition& target) const {
  const ProjectedPosition q = tm_.forward(geocentric_.geodetic_from_ecef(target));
  double s = 0, c = 0;
  GeographicLib::Math::sincosd(p_.rotation.deg(), s, c);
  const double k = 1.0 + p_.scale.unitless();
  const double de = q.easting_m - p_.shift_e_m, dn = q.northing_m - p_.shift_n_m;
  const double e = (c * de + s * dn) / k, n = (-s * de + c * dn) / k;  // the similarity's inverse
  const double u = q.h.m - p_.vertical_shift_m - p_.slope_n * (n - p_.centroid_n_m) - p_.slope_e * (e - p_.centroid_e_m);
  return plane_.ecef_from_enu(EnuPosition{Eigen::Vector3d(e, n, u), plane_.origin()});
}

}  // namespace geoanchor::geodesy
