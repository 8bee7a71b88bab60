#pragma once
// Control sets generated for tests: marks spread over a region, their
// target coordinates computed by PROJ (the independent reference) through a
// given operation. Deterministic for a given seed.

#include <Eigen/Core>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include "geoanchor/geodesy/control_point.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "proj_reference.hpp"

namespace geoanchor::testing {

// `n` marks within `radius_deg` of (lat, lon), heights in [-50, 2000] m, on GRS 80.
inline std::vector<geodesy::EcefPosition> region(std::size_t n, double lat, double lon, double radius_deg, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> d(-radius_deg, radius_deg), h(-50.0, 2000.0);
  const geodesy::GeocentricConverter conv(geodesy::Ellipsoid::grs80());
  std::vector<geodesy::EcefPosition> out;
  for (std::size_t i = 0; i < n; ++i) {
    out.push_back(conv.ecef_from_geodetic({geodesy::Angle::degrees(std::clamp(lat + d(rng), -89.0, 89.0)),
                                           geodesy::Angle::degrees(lon + d(rng)), geodesy::EllipsoidalHeight{h(rng)}}));
  }
  return out;
}

// Targets = PROJ's `proj` (ECEF in and out) of the sources, at each mark's
// epoch from `epochs` (cycled) when given; isotropic sigma_m/√2 in each frame
// (so sigma_m in their difference); no noise added.
inline geodesy::ControlSet control_from_proj(const std::vector<geodesy::EcefPosition>& src, const std::string& proj,
                                             double sigma_m, const std::vector<double>& epochs = {}) {
  const ProjPipeline pipe(proj);
  geodesy::ControlSet set;
  set.source_name = "generated";
  for (std::size_t i = 0; i < src.size(); ++i) {
    geodesy::ControlPoint p;
    p.id = "P" + std::to_string(i);
    p.line = i + 2;
    p.source = src[i];
    const double t = epochs.empty() ? 0.0 : epochs[i % epochs.size()];
    if (!epochs.empty()) p.epoch = geodesy::DecimalYear{t};
    p.target = geodesy::EcefPosition(pipe.forward(src[i].m, t));
    p.source_cov_m2 = Eigen::Matrix3d::Identity() * sigma_m * sigma_m / 2.0;
    p.target_cov_m2 = Eigen::Matrix3d::Identity() * sigma_m * sigma_m / 2.0;
    p.source_as_read = p.source.m;
    p.target_as_read = p.target.m;
    set.points.push_back(p);
  }
  set.has_a_priori_sigmas = true;
  return set;
}

}  // namespace geoanchor::testing
