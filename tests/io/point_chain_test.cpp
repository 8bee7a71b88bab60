// The point chain: fused affine chains against PROJ and against the same
// steps taken one at a time; non-affine chains against PROJ.

#include <gtest/gtest.h>

#include <random>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/tile/point_chain.hpp"
#include "proj_reference.hpp"
#include "test_support.hpp"

namespace geoanchor::io {
namespace {

using geodesy::Angle;
using testing::ProjPipeline;

constexpr double kVsProjTol_m = 1e-6;      // PROJ agreement, as everywhere
constexpr double kFusedVsStepsTol_m = 1e-8;  // one long-double composition vs three float64 steps

const char* kHelmert = R"J({"model": "helmert7", "convention": "position_vector",
  "parameters": {"tx_m": 0.3, "ty_m": -0.2, "tz_m": 0.05, "rx_arcsec": 0.02, "ry_arcsec": -0.01, "rz_arcsec": 20,
                 "ds_ppm": 1.5}})J";

geodesy::LocalOrigin origin(double lat, double lon, double h) {
  return {{Angle::degrees(lat), Angle::degrees(lon), geodesy::EllipsoidalHeight{h}}, geodesy::Ellipsoid::wgs84()};
}

std::string topocentric(const geodesy::LocalOrigin& o) {
  char def[200];
  std::snprintf(def, sizeof def, "+proj=topocentric +ellps=WGS84 +lat_0=%.17g +lon_0=%.17g +h_0=%.17g",
                o.point.lat.deg(), o.point.lon.deg(), o.point.h.m);
  return def;
}

TEST(PointChain, CrossAirportReanchoringIsFusedAndAgreesWithProjAndWithTheSteps) {
  const auto a = origin(47.464722, 8.549167, 480.0), b = origin(47.458, 8.561, 470.0);
  const TransformFile t = parse_transform_json(kHelmert, "T.json");
  const PointChain chain(ArrayFrame{CoordinateKind::enu, geodesy::Ellipsoid::wgs84(), a, std::nullopt}, t, false,
                         std::nullopt, ArrayFrame{CoordinateKind::enu, geodesy::Ellipsoid::wgs84(), b, std::nullopt});
  ASSERT_TRUE(chain.fused().has_value());
  const ProjPipeline proj("+proj=pipeline +step +inv " + topocentric(a) +
                          " +step +proj=helmert +x=0.3 +y=-0.2 +z=0.05 +rx=0.02 +ry=-0.01 +rz=20 +s=1.5 "
                          "+convention=position_vector +step " + topocentric(b));
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> d(-3000.0, 3000.0);
  std::vector<double> e(1000), n(1000), u(1000);
  for (std::size_t i = 0; i < e.size(); ++i) e[i] = d(rng), n[i] = d(rng), u[i] = 0.01 * d(rng);
  const auto e0 = e, n0 = n, u0 = u;
  chain.apply(e, n, u);
  const geodesy::LocalTangentPlane pa(a), pb(b);
  const auto h = std::get<geodesy::Helmert7<geodesy::PositionVector>>(t.helmert);
  for (std::size_t i = 0; i < e.size(); ++i) {
    const Eigen::Vector3d ours(e[i], n[i], u[i]), in(e0[i], n0[i], u0[i]);
    EXPECT_THAT(ours, testing::IsNearVector(proj.forward(in), kVsProjTol_m));
    const auto steps = pb.enu_from_ecef(geodesy::apply(h, geodesy::RotationModel::small_angle,
                                                       pa.ecef_from_enu({in, a}))).enu_m;
    EXPECT_THAT(ours, testing::IsNearVector(steps, kFusedVsStepsTol_m));
  }
}

TEST(PointChain, GeodeticThroughAHelmertToUtmRunsPointByPointAndAgreesWithProj) {
  const TransformFile t = parse_transform_json(kHelmert, "T.json");
  const auto utm = geodesy::utm_projection(geodesy::Ellipsoid::wgs84(), {32, geodesy::Hemisphere::north});
  const PointChain chain(ArrayFrame{CoordinateKind::geodetic, geodesy::Ellipsoid::wgs84(), std::nullopt, std::nullopt}, t,
                         false, std::nullopt, ArrayFrame{CoordinateKind::projected, geodesy::Ellipsoid::wgs84(), std::nullopt, utm});
  EXPECT_FALSE(chain.fused().has_value());
  const ProjPipeline proj("+proj=pipeline +step +proj=cart +ellps=WGS84 +step +proj=helmert +x=0.3 +y=-0.2 +z=0.05 "
                          "+rx=0.02 +ry=-0.01 +rz=20 +s=1.5 +convention=position_vector +step +inv +proj=cart "
                          "+ellps=WGS84 +step +proj=utm +zone=32 +ellps=WGS84");
  std::vector<double> lat = {47.46, 46.0, 48.9}, lon = {8.55, 7.1, 10.2}, h = {480.0, 1200.0, -20.0};
  const auto lat0 = lat, lon0 = lon, h0 = h;
  chain.apply(lat, lon, h);
  for (std::size_t i = 0; i < lat.size(); ++i) {
    const Eigen::Vector3d ref = proj.forward({testing::proj_radians(lon0[i]), testing::proj_radians(lat0[i]), h0[i]});
    EXPECT_THAT(Eigen::Vector3d(lat[i], lon[i], h[i]), testing::IsNearVector(ref, kVsProjTol_m));
  }
}

TEST(PointChain, NedToEnuAtOneOriginIsTheAxisSwap) {
  const auto a = origin(-33.95, 151.18, 21.0);
  const PointChain chain(ArrayFrame{CoordinateKind::ned, geodesy::Ellipsoid::wgs84(), a, std::nullopt}, std::nullopt, false,
                         std::nullopt, ArrayFrame{CoordinateKind::enu, geodesy::Ellipsoid::wgs84(), a, std::nullopt});
  std::vector<double> x = {10.0}, y = {20.0}, z = {3.0};
  chain.apply(x, y, z);
  EXPECT_NEAR(x[0], 20.0, kFusedVsStepsTol_m);
  EXPECT_NEAR(y[0], 10.0, kFusedVsStepsTol_m);
  EXPECT_NEAR(z[0], -3.0, kFusedVsStepsTol_m);
}

TEST(PointChain, ATimeDependentTransformWithoutEpochIsRefused) {
  const TransformFile t = parse_transform_json(R"J({"model": "helmert14", "convention": "position_vector",
    "reference_epoch": 2015.0, "parameters": {"tx_m": 0, "ty_m": 0, "tz_m": 0, "rx_arcsec": 0, "ry_arcsec": 0,
    "rz_arcsec": 0, "ds_ppm": 0, "dtx_m_per_year": 0.001, "dty_m_per_year": 0, "dtz_m_per_year": 0,
    "drx_arcsec_per_year": 0, "dry_arcsec_per_year": 0, "drz_arcsec_per_year": 0, "dds_ppm_per_year": 0}})J", "T.json");
  const ArrayFrame ecef;
  std::vector<double> x = {6378137.0}, y = {0.0}, z = {0.0};
  const PointChain no_epoch(ecef, t, false, std::nullopt, ecef);
  EXPECT_THROW(no_epoch.apply(x, y, z), Error);  // only per-point epochs can run it
  const PointChain at_2025(ecef, t, false, geodesy::DecimalYear{2025.0}, ecef);
  at_2025.apply(x, y, z);
  EXPECT_NEAR(x[0], 6378137.0 + 0.010, kFusedVsStepsTol_m);  // 1 mm/yr over 10 years
}

// issue 12, tests that can fail, item 1: NaN from the per-point epoch
// interpolation fails (it passed while the worst case was a std::max).
TEST(PointChain, PerPointEpochsAgreeWithProjAtEachPointsTime) {
  // ENU -> 14-parameter Helmert -> geodetic, the points spread over 8 years.
  const TransformFile t = parse_transform_json(R"J({"model": "helmert14", "convention": "coordinate_frame",
    "reference_epoch": 2015.0, "parameters": {"tx_m": 0.1, "ty_m": -0.2, "tz_m": 0.3, "rx_arcsec": 0.01,
    "ry_arcsec": -0.02, "rz_arcsec": 0.03, "ds_ppm": 0.5, "dtx_m_per_year": 0.01, "dty_m_per_year": -0.02,
    "dtz_m_per_year": 0.03, "drx_arcsec_per_year": 0.001, "dry_arcsec_per_year": 0.002,
    "drz_arcsec_per_year": -0.003, "dds_ppm_per_year": 0.1}})J", "T.json");
  const auto o = origin(47.464722, 8.549167, 480.0);
  const ArrayFrame enu{CoordinateKind::enu, geodesy::Ellipsoid::wgs84(), o, std::nullopt};
  const ArrayFrame geodetic{CoordinateKind::geodetic, geodesy::Ellipsoid::wgs84(), std::nullopt, std::nullopt};
  const PointChain chain(enu, t, false, std::nullopt, geodetic);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> h(-2000.0, 2000.0), when(2016.0, 2024.0);
  std::vector<double> e(1000), n(1000), u(1000), years(1000);
  for (std::size_t i = 0; i < e.size(); ++i) e[i] = h(rng), n[i] = h(rng), u[i] = h(rng) / 40, years[i] = when(rng);
  const auto e0 = e, n0 = n, u0 = u;
  chain.apply_at_epochs(e, n, u, years);
  // Two PROJ pipelines: PROJ 9.1.1's topocentric step does not carry the
  // time coordinate to the next step (cct shows t = 0 after it), so the
  // time-dependent Helmert must start a pipeline of its own.
  const ProjPipeline to_ecef("+proj=pipeline +step +inv " + topocentric(o));
  const ProjPipeline proj("+proj=pipeline +step +proj=helmert +x=0.1 +y=-0.2 +z=0.3 +rx=0.01 +ry=-0.02 +rz=0.03 +s=0.5 "
                          "+dx=0.01 +dy=-0.02 +dz=0.03 +drx=0.001 +dry=0.002 +drz=-0.003 +ds=0.1 +t_epoch=2015 "
                          "+convention=coordinate_frame +step +inv +proj=cart +ellps=WGS84");
  testing::WorstCase worst_deg, worst_h;
  for (std::size_t i = 0; i < e.size(); ++i) {
    const Eigen::Vector3d p = proj.forward(to_ecef.forward(Eigen::Vector3d(e0[i], n0[i], u0[i])), years[i]);
    worst_deg.add(std::abs(e[i] - testing::proj_degrees(p.y())), i);  // latitude
    worst_deg.add(std::abs(n[i] - testing::proj_degrees(p.x())), i);  // longitude
    worst_h.add(std::abs(u[i] - p.z()), i);
  }
  EXPECT_WORST_WITHIN(worst_deg, kVsProjTol_m / 111000.0);
  EXPECT_WORST_WITHIN(worst_h, kVsProjTol_m);
}

// issue 12 point 1
TEST(PointChain, Issue12Point1_APointOutsideTheOutputProjectionsDomainIsNaNWithItsReason) {
  // Geodetic -> TM on the Greenwich meridian: the array path (batch ECEF ->
  // geodetic, then the projection point by point) and the point-by-point
  // path (a geodetic input) both refuse (0, 90), which the series wrote as
  // -nan before, and keep the point beside it.
  geodesy::TransverseMercatorParams p;
  p.k0 = 0.9996;
  const geodesy::ProjectionDef tm{geodesy::Ellipsoid::wgs84(), p, std::nullopt};
  const ProjPipeline proj("+proj=tmerc +ellps=WGS84 +k=0.9996");
  for (const CoordinateKind from : {CoordinateKind::ecef, CoordinateKind::geodetic}) {
    const PointChain chain(ArrayFrame{from, geodesy::Ellipsoid::wgs84(), std::nullopt, std::nullopt}, std::nullopt, false,
                           std::nullopt, ArrayFrame{CoordinateKind::projected, geodesy::Ellipsoid::wgs84(), std::nullopt, tm});
    std::vector<double> a = {47.0, 0.0, 10.0}, b = {8.0, 90.0, 5.0}, c = {400.0, 0.0, 0.0};
    if (from == CoordinateKind::ecef) {
      const geodesy::GeocentricConverter g(geodesy::Ellipsoid::wgs84());
      for (std::size_t i = 0; i < a.size(); ++i) {
        const auto x = g.ecef_from_geodetic({Angle::degrees(a[i]), Angle::degrees(b[i]), geodesy::EllipsoidalHeight{c[i]}});
        a[i] = x.m.x(), b[i] = x.m.y(), c[i] = x.m.z();
      }
    }
    const ChainReport report = chain.apply(a, b, c);
    ASSERT_TRUE(report.first_refused.has_value());
    EXPECT_EQ(*report.first_refused, 1u);
    EXPECT_TRUE(std::isnan(a[1]) && std::isnan(b[1]));
    EXPECT_NE(report.refusal.find("90.0° from the central meridian 0°"), std::string::npos) << report.refusal;
    EXPECT_NE(report.refusal.find("within 75°"), std::string::npos) << report.refusal;
    const Eigen::Vector3d r0 = proj.forward({testing::proj_radians(8.0), testing::proj_radians(47.0), 0.0});
    EXPECT_NEAR(a[0], r0.x(), kVsProjTol_m);
    EXPECT_NEAR(b[0], r0.y(), kVsProjTol_m);
    const Eigen::Vector3d r2 = proj.forward({testing::proj_radians(5.0), testing::proj_radians(10.0), 0.0});
    EXPECT_NEAR(a[2], r2.x(), kVsProjTol_m);
    EXPECT_NEAR(b[2], r2.y(), kVsProjTol_m);
  }
}

// issue 12 point 1
TEST(PointChain, Issue12Point1_PointsOutsideAForcedUtmZonesBandAreCountedAndEastingsOutsideTheGridRefused) {
  const auto z31 = geodesy::utm_projection(geodesy::Ellipsoid::wgs84(), {31, geodesy::Hemisphere::north});
  const PointChain out(ArrayFrame{CoordinateKind::geodetic, geodesy::Ellipsoid::wgs84(), std::nullopt, std::nullopt},
                       std::nullopt, false, std::nullopt,
                       ArrayFrame{CoordinateKind::projected, geodesy::Ellipsoid::wgs84(), std::nullopt, z31});
  // Inside the band, 0.5° beyond it (within the margin), 7° beyond it (counted), 83° beyond it (refused).
  std::vector<double> a = {45.0, 45.0, 45.0, 10.0}, b = {3.0, 6.5, 13.0, 89.0}, c = {0.0, 0.0, 0.0, 0.0};
  const ChainReport report = out.apply(a, b, c);
  EXPECT_EQ(report.output_band.points, 1u);
  EXPECT_EQ(report.output_band.worst_index, 2u);
  EXPECT_NEAR(report.output_band.worst_excess_deg, 7.0, 1e-9);
  ASSERT_TRUE(report.first_refused.has_value());
  EXPECT_EQ(*report.first_refused, 3u);
  EXPECT_NE(report.refusal.find("UTM zone 31N is computed within 35°"), std::string::npos) << report.refusal;
  const ProjPipeline utm("+proj=utm +zone=31 +ellps=WGS84");
  const Eigen::Vector3d r = utm.forward({testing::proj_radians(13.0), testing::proj_radians(45.0), 0.0});
  EXPECT_NEAR(a[2], r.x(), kVsProjTol_m);  // still computed, as PROJ does
  EXPECT_NEAR(b[2], r.y(), kVsProjTol_m);
  const auto w = report.output_band.warning("output");
  ASSERT_TRUE(w.has_value());
  EXPECT_NE(w->find("output UTM zone 31N: 1 point lies outside the zone's band (0°–6°E, 0°–84°N)"), std::string::npos) << *w;

  // Input on zone 31N: an easting 52 000 km out is refused, not read as a point.
  const PointChain in(ArrayFrame{CoordinateKind::projected, geodesy::Ellipsoid::wgs84(), std::nullopt, z31}, std::nullopt,
                      false, std::nullopt,
                      ArrayFrame{CoordinateKind::geodetic, geodesy::Ellipsoid::wgs84(), std::nullopt, std::nullopt});
  std::vector<double> e = {500000.0, 52.0e6}, n = {5.0e6, 1.1e6}, h = {0.0, 0.0};
  const ChainReport back = in.apply(e, n, h);
  ASSERT_TRUE(back.first_refused.has_value());
  EXPECT_EQ(*back.first_refused, 1u);
  EXPECT_TRUE(std::isnan(e[1]) && std::isnan(n[1]));
  EXPECT_TRUE(std::isfinite(e[0]) && std::isfinite(n[0]));
  EXPECT_NE(back.refusal.find("input easting/northing 5.2e+07, 1100000: outside the projection's domain: no point "
                              "within the projection's domain maps to this easting/northing; UTM zone 31N is computed "
                              "within 35°"),
            std::string::npos)
      << back.refusal;
}

}  // namespace
}  // namespace geoanchor::io
