// Frame descriptors, epochs, angle and scale units.

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>

#include "geoanchor/geodesy/ellipsoid.hpp"
#include "geoanchor/geodesy/error.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/units.hpp"

namespace geoanchor::geodesy {
namespace {

constexpr double kUnitTol = 1e-15;  // relative: one or two float64 roundings
constexpr double kGrs80MinorAxisTol_m = 5e-7;  // b is published to the micrometre

TEST(Frame, ParsesTheWaysGeodesistsWriteFrames) {
  const Frame itrf = Frame::parse("ITRF2014@2024.5", "--from");
  EXPECT_EQ(itrf.datum(), "ITRF");
  EXPECT_EQ(itrf.realization(), "2014");
  ASSERT_TRUE(itrf.epoch().has_value());
  EXPECT_EQ(itrf.epoch()->year, 2024.5);
  EXPECT_EQ(itrf.to_string(), "ITRF2014@2024.5");

  const Frame nad = Frame::parse(" NAD83(2011) @ 2010.0 ", "--from");
  EXPECT_EQ(nad.datum(), "NAD83");
  EXPECT_EQ(nad.realization(), "2011");
  EXPECT_EQ(nad.to_string(), "NAD83(2011)@2010.0");

  const Frame wgs = Frame::parse("WGS84(G2296)", "--to");
  EXPECT_EQ(wgs.datum(), "WGS84");
  EXPECT_EQ(wgs.realization(), "G2296");
  EXPECT_FALSE(wgs.epoch().has_value());

  EXPECT_EQ(Frame::parse("GDA2020", "x").datum(), "GDA2020");
  EXPECT_EQ(Frame::parse("GDA2020", "x").realization(), "");
  EXPECT_EQ(Frame::parse("ETRF2000", "x").realization(), "2000");
  EXPECT_EQ(Frame::parse("ETRF2000", "x").name(), "ETRF2000");
}

TEST(Frame, RejectsMalformedFramesAndEpochsNamingTheValue) {
  for (const char* bad : {"", "@2020", "ITRF2014@yyyy", "ITRF2014@2024,5", "ITRF2014@1850", "NAD83(2011",
                          "NAD83)2011(", "ITRF 2014", "ITRF2014@nan", "ITRF2014@"}) {
    try {
      Frame::parse(bad, "--from");
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::input);
      EXPECT_NE(std::string(e.what()).find("--from"), std::string::npos) << e.what();
    }
  }
  try {
    parse_decimal_year("yyyy", "points.csv:7: epoch");
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "points.csv:7: epoch: epoch=yyyy: not a decimal year; expected a number such as 2024.5");
  }
}

TEST(Units, AnglesConvertBetweenNamedUnits) {
  EXPECT_NEAR(Angle::arcseconds(3600.0).deg(), 1.0, kUnitTol);
  EXPECT_NEAR(Angle::milliarcseconds(1000.0).arcsec(), 1.0, kUnitTol);
  EXPECT_NEAR(Angle::degrees(180.0).rad(), M_PI, kUnitTol * M_PI);
  EXPECT_NEAR(Angle::radians(1.0).arcsec(), 206264.80624709636, 206264.8 * kUnitTol);
  EXPECT_EQ(Angle::degrees(90.0).deg(), 90.0);  // stored in degrees: poles stay exactly at 90°
}

TEST(Units, ScaleDifferencesConvertBetweenPpmAndPpb) {
  EXPECT_NEAR(ScaleDifference::ppb(9.71).ppm(), 0.00971, 0.00971 * kUnitTol);
  EXPECT_NEAR(ScaleDifference::ppm(1.0).unitless(), 1e-6, 1e-6 * kUnitTol);
}

TEST(Ellipsoid, NamedAndCustomEllipsoids) {
  EXPECT_EQ(Ellipsoid::wgs84().rf(), 298.257223563);
  EXPECT_EQ(Ellipsoid::grs80().rf(), 298.257222101);
  EXPECT_NEAR(Ellipsoid::grs80().b_m(), 6356752.314140, kGrs80MinorAxisTol_m);  // Moritz (1980), Geodetic Reference System 1980: b = 6356752.3141 m
  EXPECT_THROW(Ellipsoid::custom(6378137.0, 0.0), Error);
  EXPECT_THROW(Ellipsoid::custom(-1.0, 298.0), Error);
}

}  // namespace
}  // namespace geoanchor::geodesy

namespace geoanchor::geodesy {
namespace {

// GPS time -> decimal year against the C++20 calendar (std::chrono), with the
// GPS epoch 1980-01-06 and no leap seconds, as documented.
TEST(GpsTime, DecimalYearAgreesWithTheCalendar) {
  using namespace std::chrono;
  constexpr double kYearTol = 1e-12;  // 3e-5 s
  const sys_seconds gps_epoch = sys_days{year{1980} / January / 6};
  for (const double gps_s : {0.0, 1.0e9, 1.4e9, 1.7e9 + 12345.678, 2.0e9}) {
    const auto t = gps_epoch + duration_cast<seconds>(duration<double>(gps_s));
    const double fraction = gps_s - std::floor(gps_s);
    const year_month_day ymd{floor<days>(t)};
    const sys_seconds start = sys_days{ymd.year() / January / 1}, end = sys_days{(ymd.year() + years{1}) / January / 1};
    const double expected = static_cast<int>(ymd.year()) +
                            (static_cast<double>((t - start).count()) + fraction) / static_cast<double>((end - start).count());
    EXPECT_NEAR(decimal_year_from_gps_seconds(gps_s).year, expected, kYearTol) << gps_s;
  }
  // 2024 is a leap year: its middle is 2024-07-02T00:00:00.
  const double mid2024 = static_cast<double>((sys_days{year{2024} / July / 2} - gps_epoch).count());
  EXPECT_NEAR(decimal_year_from_gps_seconds(mid2024).year, 2024.5, kYearTol);
}

}  // namespace
}  // namespace geoanchor::geodesy

