// The audit's measures on their own (issue 16 point 4): Web Mercator told
// from other Mercators in PROJ's own WKT of each CRS, float32 spacing from
// the IEEE 754 binary32 layout, and the tangent plane's departure against
// the ellipsoidal heights of points on the plane.

#include <gtest/gtest.h>
#include <proj.h>

#include <cmath>
#include <memory>
#include <string>

#include "geoanchor/geodesy/ellipsoid.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/workflow/audit.hpp"

namespace geoanchor {
namespace {

// PROJ's WKT2:2019 of a CRS it knows.
std::string proj_wkt(const char* definition) {
  PJ_CONTEXT* ctx = proj_context_create();
  PJ* crs = proj_create(ctx, definition);
  EXPECT_NE(crs, nullptr) << definition;
  const char* wkt = crs ? proj_as_wkt(ctx, crs, PJ_WKT2_2019, nullptr) : nullptr;
  std::string out = wkt ? wkt : "";
  if (crs) proj_destroy(crs);
  proj_context_destroy(ctx);
  return out;
}

TEST(Audit, Issue16_WebMercatorIsToldFromOtherMercatorsInPROJsWkt) {
  EXPECT_NE(workflow::web_mercator_mention(proj_wkt("EPSG:3857")), "");
  EXPECT_NE(workflow::web_mercator_mention("EPSG:3857 (WGS 84 / Pseudo-Mercator)"), "");
  EXPECT_NE(workflow::web_mercator_mention("+proj=merc +a=6378137 +b=6378137 +lat_ts=0 +lon_0=0 +x_0=0 +y_0=0 +k=1 +units=m"), "");
  EXPECT_NE(workflow::web_mercator_mention("urn:ogc:def:crs:EPSG::3857"), "");
  EXPECT_NE(workflow::web_mercator_mention("EPSG:900913"), "");
  // World Mercator on the ellipsoid, a UTM zone and a code that merely starts with 3857 are not.
  EXPECT_EQ(workflow::web_mercator_mention(proj_wkt("EPSG:3395")), "");
  EXPECT_EQ(workflow::web_mercator_mention(proj_wkt("EPSG:32632")), "");
  EXPECT_EQ(workflow::web_mercator_mention("EPSG:38570"), "");
  EXPECT_EQ(workflow::web_mercator_mention("ETRF2000@2024.5 enu"), "");
}

TEST(Audit, Issue16_Float32SpacingFollowsTheBinary32Layout) {
  // binary32: 24-bit significand, so values in [2^e, 2^(e+1)) are 2^(e-23) apart.
  EXPECT_EQ(workflow::float32_spacing(1.0), std::ldexp(1.0, -23));
  EXPECT_EQ(workflow::float32_spacing(5000.0), std::ldexp(1.0, 12 - 23));   // [4096, 8192)
  EXPECT_EQ(workflow::float32_spacing(8192.0), std::ldexp(1.0, 13 - 23));   // 0.98 mm
  EXPECT_EQ(workflow::float32_spacing(-20000.0), std::ldexp(1.0, 14 - 23));  // 1.95 mm
  EXPECT_EQ(workflow::float32_spacing(6.4e6), 0.5);                          // [2^22, 2^23): ECEF at the Earth's radius
}

TEST(Audit, Issue16_TangentPlaneDepartureLiesBetweenItsNormalSections) {
  // A point on the tangent plane at distance d east (north) of the origin
  // stands d²/2N (d²/2M) above the ellipsoid to first order; the Gaussian
  // mean radius √(MN) lies between, so d²/2R lies between the two heights.
  const geodesy::Ellipsoid e = geodesy::Ellipsoid::grs80();
  const geodesy::LocalOrigin origin{
      geodesy::GeodeticPosition{geodesy::Angle::degrees(47.464722), geodesy::Angle::degrees(8.549167), geodesy::EllipsoidalHeight{480.0}}, e};
  const geodesy::LocalTangentPlane plane(origin);
  for (const double d : {1000.0, 3000.0, 10000.0}) {
    const auto height_at = [&](double east, double north) {
      const geodesy::EcefPosition x = plane.ecef_from_enu(geodesy::EnuPosition{Eigen::Vector3d(east, north, 0.0), origin});
      return geodesy::geodetic_from_ecef(e, x).h.m - 480.0;
    };
    const double h_east = height_at(d, 0.0), h_north = height_at(0.0, d);
    const double departure = workflow::tangent_plane_departure_m(d, 47.464722, e);
    const double lo = std::min(h_east, h_north), hi = std::max(h_east, h_north);
    constexpr double kSecondOrder = 1e-3;  // relative: the heights' d⁴ terms at 10 km
    EXPECT_GE(departure, lo * (1.0 - kSecondOrder)) << d;
    EXPECT_LE(departure, hi * (1.0 + kSecondOrder)) << d;
  }
  // 1 m, the default limit, is reached at about 3.57 km.
  EXPECT_NEAR(workflow::tangent_plane_departure_m(3570.0, 47.46, e), 1.0, 0.01);
}

}  // namespace
}  // namespace geoanchor
