// Geodetic <-> ECEF against PROJ (+proj=cart), GeographicLib and the IOGP
// worked example.

#include <GeographicLib/Geocentric.hpp>
#include <gtest/gtest.h>

#include <cmath>

#include "geoanchor/geodesy/geocentric.hpp"
#include "proj_reference.hpp"
#include "test_support.hpp"

namespace geoanchor::geodesy {
namespace {

using testing::proj_radians;
using testing::ProjPipeline;

constexpr double kForwardTol_m = 1e-8;          // issue acceptance, heights up to 10 km
constexpr double kForwardRelTol = 1e-15;        // issue acceptance above 10 km (≈ 4.5 ulp)
constexpr double kRoundTripTol_m = 1e-8;        // float64 spacing at Earth radius is 9.3e-10 m
constexpr double kRoundTripRelTol = 1e-15;      // above 10 km, as for the forward: at 40,000 km the spacing is 7.5e-9 m
constexpr double kInverseHeightTol_m = 1e-8;    // issue acceptance vs GeographicLib
constexpr double kInverseAngleTol_rad = 1e-14;  // issue acceptance vs GeographicLib
constexpr double kPublishedTol_m = 0.0005;      // IOGP values are given to the millimetre
constexpr double kPublishedAngleTol_deg = 0.0005 / 3600.0;  // published to 0.001″
constexpr double kProjInverseTol_m = 5e-8;      // PROJ's one-step inverse: ~14 nm near the surface

TEST(Geocentric, IogpGuidanceNote7_2Example) {
  // IOGP Publication 373-7-2 (GN 7-2), EPSG method 9602 worked example, WGS 84:
  // 53°48'33.820"N, 2°07'46.380"E, h = 73.000 m  <->  X 3771793.968, Y 140253.342, Z 5124304.349 m.
  const GeodeticPosition p{Angle::degrees(53.0 + 48.0 / 60 + 33.820 / 3600), Angle::degrees(2.0 + 7.0 / 60 + 46.380 / 3600),
                           EllipsoidalHeight{73.0}};
  const EcefPosition x = ecef_from_geodetic(Ellipsoid::wgs84(), p);
  EXPECT_NEAR(x.m.x(), 3771793.968, kPublishedTol_m);
  EXPECT_NEAR(x.m.y(), 140253.342, kPublishedTol_m);
  EXPECT_NEAR(x.m.z(), 5124304.349, kPublishedTol_m);

  const GeodeticPosition back = geodetic_from_ecef(Ellipsoid::wgs84(), EcefPosition(3771793.968, 140253.342, 5124304.349));
  EXPECT_NEAR(back.lat.deg(), p.lat.deg(), kPublishedAngleTol_deg);
  EXPECT_NEAR(back.lon.deg(), p.lon.deg(), kPublishedAngleTol_deg);
  EXPECT_NEAR(back.h.m, 73.0, kPublishedTol_m);
}

class GeocentricVsProj : public ::testing::TestWithParam<const char*> {};

TEST_P(GeocentricVsProj, ForwardAgreesWorldwideFromMinus1kmTo40000km) {
  const bool grs80 = std::string(GetParam()) == "GRS80";
  const Ellipsoid e = grs80 ? Ellipsoid::grs80() : Ellipsoid::wgs84();
  const ProjPipeline cart(std::string("+proj=cart +ellps=") + GetParam());
  const GeocentricConverter conv(e);
  const auto points = testing::worldwide_points(10000, -1000.0, 4.0e7);
  testing::WorstCase worst_low_m, worst_high_rel;
  for (const auto& p : points) {
    const Eigen::Vector3d ours = conv.ecef_from_geodetic(p).m;
    const Eigen::Vector3d ref = cart.forward({proj_radians(p.lon.deg()), proj_radians(p.lat.deg()), p.h.m});
    const double tol = p.h.m <= 10000.0 ? kForwardTol_m : kForwardRelTol * ref.norm();
    const double d = (ours - ref).norm();
    if (p.h.m <= 10000.0) {
      worst_low_m.add(d);
    } else {
      worst_high_rel.add(d / ref.norm());
    }
    ASSERT_LE(d, tol) << "lat " << p.lat.deg() << " lon " << p.lon.deg() << " h " << p.h.m;
  }
  EXPECT_WORST_WITHIN(worst_low_m, kForwardTol_m);
  EXPECT_WORST_WITHIN(worst_high_rel, kForwardRelTol);
  RecordProperty("worst_forward_difference_up_to_10km_m", testing::scientific(worst_low_m.value()));
  RecordProperty("worst_forward_relative_difference_above_10km", testing::scientific(worst_high_rel.value()));
}

TEST_P(GeocentricVsProj, InverseAgreesWithProjNearTheSurface) {
  // PROJ's inverse cart is one Bowring step: ~14 nm near the surface only.
  const Ellipsoid e = std::string(GetParam()) == "GRS80" ? Ellipsoid::grs80() : Ellipsoid::wgs84();
  const ProjPipeline cart(std::string("+proj=cart +ellps=") + GetParam());
  const GeocentricConverter conv(e);
  for (const auto& p : testing::worldwide_points(10000, -1000.0, 1000.0, 7)) {
    const EcefPosition x = conv.ecef_from_geodetic(p);
    const GeodeticPosition ours = conv.geodetic_from_ecef(x);
    const Eigen::Vector3d ref = cart.inverse(x.m);  // lon, lat (rad), h
    // Compare as positions: geodetic differences mapped back through the forward.
    const Eigen::Vector3d ref_again =
        cart.forward({ref.x(), ref.y(), ref.z()});
    const Eigen::Vector3d ours_again =
        cart.forward({proj_radians(ours.lon.deg()), proj_radians(ours.lat.deg()), ours.h.m});
    ASSERT_LE((ours_again - ref_again).norm(), kProjInverseTol_m) << "lat " << p.lat.deg() << " lon " << p.lon.deg();
  }
}

INSTANTIATE_TEST_SUITE_P(Ellipsoids, GeocentricVsProj, ::testing::Values("WGS84", "GRS80"));

TEST(Geocentric, InverseAgreesWithGeographicLibEverywhere) {
  const GeographicLib::Geocentric ref(Ellipsoid::wgs84().a_m(), Ellipsoid::wgs84().f());
  const GeocentricConverter conv(Ellipsoid::wgs84());
  for (const auto& p : testing::worldwide_points(10000, -1000.0, 4.0e7, 11)) {
    const EcefPosition x = conv.ecef_from_geodetic(p);
    const GeodeticPosition ours = conv.geodetic_from_ecef(x);
    double lat = 0, lon = 0, h = 0;
    ref.Reverse(x.m.x(), x.m.y(), x.m.z(), lat, lon, h);
    ASSERT_NEAR(ours.h.m, h, kInverseHeightTol_m);
    ASSERT_NEAR(ours.lat.rad(), lat * M_PI / 180.0, kInverseAngleTol_rad);
    if (std::fabs(lat) < 90.0) {
      ASSERT_NEAR(testing::angle_difference_deg(ours.lon.deg(), lon) * M_PI / 180.0, 0.0, kInverseAngleTol_rad);
    }
  }
}

TEST(Geocentric, RoundTripClosesTo1e8mFromMinus1kmTo40000km) {
  const GeocentricConverter conv(Ellipsoid::grs80());
  testing::WorstCase worst_low_m, worst_high_rel;
  for (const auto& p : testing::worldwide_points(10000, -1000.0, 4.0e7, 13)) {
    const EcefPosition x = conv.ecef_from_geodetic(p);
    const EcefPosition again = conv.ecef_from_geodetic(conv.geodetic_from_ecef(x));
    const double d = (again.m - x.m).norm();
    if (p.h.m <= 10000.0) {
      worst_low_m.add(d);
    } else {
      worst_high_rel.add(d / x.m.norm());
    }
    const double tol = p.h.m <= 10000.0 ? kRoundTripTol_m : kRoundTripRelTol * x.m.norm();
    ASSERT_LE(d, tol) << "lat " << p.lat.deg() << " lon " << p.lon.deg() << " h " << p.h.m;
  }
  EXPECT_WORST_WITHIN(worst_low_m, kRoundTripTol_m);
  EXPECT_WORST_WITHIN(worst_high_rel, kRoundTripRelTol);
  RecordProperty("worst_round_trip_up_to_10km_m", testing::scientific(worst_low_m.value()));
  RecordProperty("worst_round_trip_relative_above_10km", testing::scientific(worst_high_rel.value()));
}

TEST(Geocentric, PolesAndAntimeridianAreExact) {
  const GeocentricConverter conv(Ellipsoid::wgs84());
  const double b = Ellipsoid::wgs84().b_m();
  const EcefPosition north = conv.ecef_from_geodetic({Angle::degrees(90), Angle::degrees(37), EllipsoidalHeight{0}});
  EXPECT_EQ(north.m.x(), 0.0);
  EXPECT_EQ(north.m.y(), 0.0);
  EXPECT_NEAR(north.m.z(), b, kRoundTripTol_m);
  const GeodeticPosition pole = conv.geodetic_from_ecef(EcefPosition(0.0, 0.0, -b - 100.0));
  EXPECT_EQ(pole.lat.deg(), -90.0);
  EXPECT_NEAR(pole.h.m, 100.0, kRoundTripTol_m);
  const GeodeticPosition dateline = conv.geodetic_from_ecef(EcefPosition(-6378137.0, 0.0, 0.0));
  EXPECT_EQ(std::fabs(dateline.lon.deg()), 180.0);
  EXPECT_NEAR(dateline.h.m, 0.0, kRoundTripTol_m);
}

TEST(Geocentric, LatitudeBeyondNinetyIsNaNNotAnError) {
  const EcefPosition x = ecef_from_geodetic(Ellipsoid::wgs84(), {Angle::degrees(91.2), Angle::degrees(0), EllipsoidalHeight{0}});
  EXPECT_TRUE(std::isnan(x.m.x()));
}

}  // namespace
}  // namespace geoanchor::geodesy
