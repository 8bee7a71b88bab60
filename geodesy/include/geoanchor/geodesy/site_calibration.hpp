#pragma once
// Site calibration ("localization" on survey controllers): a site's local
// coordinates (e, n, u) mapped onto a Transverse Mercator grid at the site
// and onto ellipsoidal heights:
//
//   E = tE + a·e − b·n          a = (1 + ds)·cos θ, b = (1 + ds)·sin θ
//   N = tN + b·e + a·n          (θ turns the site grid counter-clockwise)
//   h = u + c + slope_n·(n − n0) + slope_e·(e − e0)
//
// E, N are on the grid `projection` (typically k0 = 1 at the site); (e0, n0)
// is the centroid the inclined plane is referred to. The local coordinates
// are held as ENU at `local_origin` (any fixed origin: only the numbers e, n,
// u matter), so that a site calibration maps ECEF to ECEF like every other
// transform.

#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/geodesy/positions.hpp"
#include "geoanchor/geodesy/projection.hpp"

namespace geoanchor::geodesy {

struct SiteCalibrationParams {
  double shift_e_m = 0.0, shift_n_m = 0.0;  // tE, tN
  Angle rotation;                            // θ
  ScaleDifference scale;                     // ds
  double vertical_shift_m = 0.0;             // c
  double slope_n = 0.0, slope_e = 0.0;       // dimensionless (m per m)
  double centroid_e_m = 0.0, centroid_n_m = 0.0;  // e0, n0
};

class SiteCalibration {
 public:
  SiteCalibration(const LocalOrigin& local_origin, const ProjectionDef& grid, const SiteCalibrationParams& p);

  // Grid E, N and ellipsoidal h of local (e, n, u).
  Eigen::Vector3d grid_from_local(const Eigen::Vector3d& enu) const;
  // ECEF (target) of a source position given as ECEF of its local ENU.
  EcefPosition target_from_source(const EcefPosition& source) const;
  // The exact inverse.
  EcefPosition source_from_target(const EcefPosition& target) const;

  const LocalOrigin& local_origin() const { return plane_.origin(); }
  const ProjectionDef& grid() const { return tm_.definition(); }
  const SiteCalibrationParams& params() const { return p_; }

 private:
  LocalTangentPlane plane_;
  TransverseMercator tm_;
  GeocentricConverter geocentric_;
  SiteCalibrationParams p_;
};

}  // namespace geoanchor::geodesy
