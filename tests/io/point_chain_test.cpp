// The point chain: fused affine chains against PROJ and against the same
// steps taken one at a time; non-affine chains against PROJ.

#include <gtest/gtest.h>

#include <random>

#include "geoanchor/geodesy/error.hpp"
#include "geoanchor/io/point_chain.hpp"
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

}  // namespace
}  // namespace geoanchor::io
