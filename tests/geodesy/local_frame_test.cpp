// ECEF <-> ENU <-> NED against PROJ (+proj=topocentric) and the IOGP example.

#include <gtest/gtest.h>

#include <random>

#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "proj_reference.hpp"
#include "test_support.hpp"

namespace geoanchor::geodesy {
namespace {

using testing::IsNearVector;
using testing::ProjPipeline;

constexpr double kEnuVsProjTol_m = 1e-6;       // issue acceptance
constexpr double kEnuRoundTripTol_m = 1e-9;    // issue acceptance, near the origin
constexpr double kPublishedTol_m = 0.0005;     // IOGP values to the millimetre
constexpr double kPublishedOriginTol_m = 0.00005;  // origin given to 0.1 mm
constexpr double kFusedEnuTol_m = 2e-9;  // the fused map adds one rounding of a 6.4e6 m translation

LocalOrigin origin_at(double lat, double lon, double h, Ellipsoid e = Ellipsoid::wgs84()) {
  return LocalOrigin{GeodeticPosition{Angle::degrees(lat), Angle::degrees(lon), EllipsoidalHeight{h}}, e};
}

TEST(LocalFrame, IogpGeocentricTopocentricExample) {
  // IOGP GN 7-2, EPSG method 9836 worked example, WGS 84: topocentric origin
  // 55°N, 5°E, h 200 m = (3652755.3058, 319574.6799, 5201547.3536); the point
  // (3771793.968, 140253.342, 5124304.349) is E -189013.869, N -128642.040, U -4220.171.
  const LocalTangentPlane plane(origin_at(55.0, 5.0, 200.0));
  EXPECT_THAT(plane.origin_ecef_m(), IsNearVector(Eigen::Vector3d(3652755.3058, 319574.6799, 5201547.3536),
                                                  kPublishedOriginTol_m));
  const EnuPosition enu = plane.enu_from_ecef(EcefPosition(3771793.968, 140253.342, 5124304.349));
  EXPECT_NEAR(enu.enu_m.x(), -189013.869, kPublishedTol_m);
  EXPECT_NEAR(enu.enu_m.y(), -128642.040, kPublishedTol_m);
  EXPECT_NEAR(enu.enu_m.z(), -4220.171, kPublishedTol_m);
}

TEST(LocalFrame, AgreesWithProjTopocentricWorldwide) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> offset(0.0, 20000.0);
  testing::WorstCase worst_m;
  const auto origins = testing::worldwide_points(200, -500.0, 5000.0, 17);
  for (const auto& o : origins) {
    const LocalOrigin origin{o, Ellipsoid::grs80()};
    const LocalTangentPlane plane(origin);
    char def[256];
    std::snprintf(def, sizeof def, "+proj=topocentric +ellps=GRS80 +lat_0=%.17g +lon_0=%.17g +h_0=%.17g", o.lat.deg(),
                  o.lon.deg(), o.h.m);
    const ProjPipeline ref(def);
    for (int i = 0; i < 50; ++i) {
      const Eigen::Vector3d x = plane.origin_ecef_m() + Eigen::Vector3d(offset(rng), offset(rng), offset(rng));
      const Eigen::Vector3d ours = plane.enu_from_ecef(EcefPosition(x)).enu_m;
      worst_m.add((ours - ref.forward(x)).norm());
      ASSERT_THAT(ours, IsNearVector(ref.forward(x), kEnuVsProjTol_m)) << def;
      ASSERT_THAT(plane.ecef_from_enu(EnuPosition{ours, origin}).m, IsNearVector(ref.inverse(ours), kEnuVsProjTol_m));
    }
  }
  EXPECT_WORST_WITHIN(worst_m, kEnuVsProjTol_m);
  RecordProperty("worst_enu_difference_m", testing::scientific(worst_m.value()));
}

TEST(LocalFrame, RoundTripNearTheOriginClosesTo1e9m) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> local(-5000.0, 5000.0);
  testing::WorstCase worst_m;
  for (const auto& o : testing::worldwide_points(500, -100.0, 3000.0, 19)) {
    const LocalOrigin origin{o, Ellipsoid::wgs84()};
    const LocalTangentPlane plane(origin);
    for (int i = 0; i < 20; ++i) {
      const Eigen::Vector3d enu(local(rng), local(rng), 0.02 * local(rng));
      const EcefPosition x = plane.ecef_from_enu(EnuPosition{enu, origin});
      // Per axis: one rounding of an ECEF coordinate is at most 4.7e-10 m.
      const Eigen::Vector3d back = plane.enu_from_ecef(x).enu_m;
      worst_m.add(testing::max_abs_component(back - enu));
      ASSERT_WORST_WITHIN(testing::max_abs_component(back - enu), kEnuRoundTripTol_m);
    }
  }
  EXPECT_WORST_WITHIN(worst_m, kEnuRoundTripTol_m);
  RecordProperty("worst_enu_round_trip_axis_m", testing::scientific(worst_m.value()));
}

TEST(LocalFrame, NedIsEnuWithAxesSwappedAndDownNegated) {
  const LocalOrigin origin = origin_at(47.46, 8.55, 480.0);
  const EnuPosition enu{Eigen::Vector3d(1.0, 2.0, 3.0), origin};
  const NedPosition ned = ned_from_enu(enu);
  EXPECT_EQ(ned.ned_m, Eigen::Vector3d(2.0, 1.0, -3.0));
  EXPECT_EQ(enu_from_ned(ned).enu_m, enu.enu_m);
  EXPECT_TRUE(enu_from_ned(ned).origin == origin);
}

TEST(LocalFrame, EnuOfAnotherOriginIsRefused) {
  const LocalTangentPlane a(origin_at(47.46, 8.55, 480.0));
  const EnuPosition of_b{Eigen::Vector3d(1.0, 2.0, 3.0), origin_at(47.46, 8.56, 480.0)};
  EXPECT_TRUE(std::isnan(a.ecef_from_enu(of_b).m.x()));
}

TEST(LocalFrame, AffineMapsEqualTheDirectConversion) {
  const LocalOrigin origin = origin_at(-33.95, 151.18, 21.0);
  const LocalTangentPlane plane(origin);
  const Eigen::Vector3d enu(1234.5, -987.6, 12.3);
  const Eigen::Vector3d direct = plane.ecef_from_enu(EnuPosition{enu, origin}).m;
  EXPECT_THAT(plane.ecef_from_enu_map().apply(enu), IsNearVector(direct, kEnuRoundTripTol_m));
  EXPECT_THAT(plane.enu_from_ecef_map().apply(direct), IsNearVector(enu, kFusedEnuTol_m));
}

}  // namespace
}  // namespace geoanchor::geodesy
