// Frame descriptors, epochs, angle and scale units.

#include <gtest/gtest.h>

#include <proj.h>

#include <chrono>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "geoanchor/geodesy/ellipsoid.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/frame_catalog.hpp"
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

// Issue 13: frame names as geodesists also write them, kept in the
// catalog's spelling.
TEST(Frame, ReadsFrameNamesInAnyCaseWithSpacesAndShortYears) {
  EXPECT_EQ(Frame::parse("itrf2014@2024.5", "x").to_string(), "ITRF2014@2024.5");
  EXPECT_EQ(Frame::parse("ITRF14", "x").name(), "ITRF2014");
  EXPECT_EQ(Frame::parse("ITRF 2014", "x").name(), "ITRF2014");
  EXPECT_EQ(Frame::parse("ITRF1997", "x").name(), "ITRF97");
  EXPECT_EQ(Frame::parse("etrf00", "x").name(), "ETRF2000");
  EXPECT_EQ(Frame::parse("WGS 84 (G2139)", "x").name(), "WGS84(G2139)");
  EXPECT_EQ(Frame::parse("nad83(csrsv6)", "x").name(), "NAD83(CSRSv6)");
  EXPECT_EQ(Frame::parse("gda2020", "x").name(), "GDA2020");
  EXPECT_EQ(Frame::parse("wgs84", "x").name(), "WGS84");
}

TEST(Frame, RejectsMalformedFramesAndEpochsNamingTheValue) {
  for (const char* bad : {"", "@2020", "ITRF2014@yyyy", "ITRF2014@2024,5", "ITRF2014@1850", "NAD83(2011",
                          "NAD83)2011(", "Airport local datum 1998", "ITRF2014@nan", "ITRF2014@"}) {
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


namespace geoanchor::geodesy {
namespace {

// The EPSG spelling of a frame as Frame::name() prints it, for PROJ's
// name and alias search: "WGS84(G2139)" is "WGS 84 (G2139)",
// "NAD83(CSRSv7)" is "NAD83(CSRS)v7"; the other catalog names are EPSG
// aliases as they stand ("ITRF2014", "ETRF2000", "NAD83(2011)", "GDA94").
std::string epsg_spelling(const std::string& name) {
  if (name.rfind("WGS84", 0) == 0) return "WGS 84" + (name.size() > 5 ? " " + name.substr(5) : std::string());
  if (name.rfind("NAD83(CSRSv", 0) == 0) return "NAD83(CSRS)v" + name.substr(11, name.size() - 12);
  return name;
}

// issue 12 point 5: which frames are dynamic is the EPSG dataset's answer,
// read from PROJ 9.1.1's proj.db (a datum is a DynamicGeodeticReferenceFrame
// exactly when geodetic_datum.frame_reference_epoch is set), for every frame
// geoanchor's catalog knows and the other families Frame::parse names.
TEST(Frame, Point5_IsDynamicAgreesWithProjDbForEveryCatalogFrame) {
  std::vector<std::string> names = catalog_frame_names();
  for (const char* other : {"IGS97", "IGS00", "IGS05", "IGS08", "IGS14", "IGb00", "IGb08", "IGb14", "ATRF2014",
                            "WGS84(Transit)", "WGS84", "NAD83(PA11)", "NAD83(MA11)"}) {
    names.emplace_back(other);
  }
  // Newer than PROJ 9.1.1's EPSG v10.076, so not in its proj.db: ETRF2020
  // (EUREF TN1, 2023: plate-fixed like every ETRF), NAD83(CSRS) v8 (NRCan
  // 2022: plate-fixed like v6, v7) and WGS 84 (G2296) (NGA 2024: aligned
  // with ITRF2020, dynamic like every WGS 84 realization; EPSG CRS 10604
  // has a frame epoch in later datasets).
  const std::map<std::string, bool> newer = {{"ETRF2020", false}, {"NAD83(CSRSv8)", false}, {"WGS84(G2296)", true}};
  PJ_CONTEXT* ctx = proj_context_create();
  proj_log_level(ctx, PJ_LOG_NONE);
  const PJ_TYPE types[] = {PJ_TYPE_GEODETIC_REFERENCE_FRAME, PJ_TYPE_DYNAMIC_GEODETIC_REFERENCE_FRAME,
                           PJ_TYPE_DATUM_ENSEMBLE};
  int from_proj_db = 0, dynamic_count = 0;
  std::set<std::string> missing;
  for (const auto& name : names) {
    const std::string epsg = epsg_spelling(name);
    PJ_OBJ_LIST* found = proj_create_from_name(ctx, "EPSG", epsg.c_str(), types, 3, 0, 0, nullptr);
    const int count = found ? proj_list_get_count(found) : 0;
    bool dynamic = false;
    if (count == 0) {
      missing.insert(name);
      ASSERT_EQ(newer.count(name), 1u) << name << " (" << epsg << ") is not in proj.db and not listed as newer";
      dynamic = newer.at(name);
    } else {
      ASSERT_EQ(count, 1) << name << " (" << epsg << "): several EPSG datums";
      PJ* datum = proj_list_get(ctx, found, 0);
      dynamic = proj_get_type(datum) == PJ_TYPE_DYNAMIC_GEODETIC_REFERENCE_FRAME;
      // The same fact as the frame reference epoch proj.db stores (−1: none).
      EXPECT_EQ(dynamic, proj_dynamic_datum_get_frame_reference_epoch(ctx, datum) > 0.0) << name;
      proj_destroy(datum);
      ++from_proj_db;
    }
    if (found) proj_list_destroy(found);
    EXPECT_EQ(is_dynamic(Frame::parse(name, "test")), dynamic) << name << " (" << epsg << ")";
    dynamic_count += dynamic ? 1 : 0;
  }
  proj_context_destroy(ctx);
  // Every listed newer frame really is missing (else proj.db would decide it).
  for (const auto& [name, dynamic] : newer) EXPECT_EQ(missing.count(name), 1u) << name << " is in proj.db now";
  // The check saw the whole catalog: ITRF88…ITRF2020, ETRF89…ETRF2020,
  // NAD83, GDA and WGS 84 frames, both answers many times.
  EXPECT_EQ(from_proj_db, static_cast<int>(names.size() - newer.size()));
  EXPECT_GE(from_proj_db, 45);
  EXPECT_GE(dynamic_count, 20);
  EXPECT_GE(static_cast<int>(names.size()) - dynamic_count, 20);
  RecordProperty("frames_checked_against_proj_db", from_proj_db);
}

// Issue 13 point 5: a frame implies its ellipsoid, and that is the EPSG
// dataset's ellipsoid of the frame's datum (proj.db), for every frame of the
// catalog and the other families Frame::parse names.
TEST(Frame, Issue13_ImpliedEllipsoidIsProjDbsForEveryCatalogFrame) {
  std::vector<std::string> names = catalog_frame_names();
  for (const char* other : {"IGS14", "IGb14", "ATRF2014", "WGS84", "NAD83(PA11)", "ETRS89"}) names.emplace_back(other);
  PJ_CONTEXT* ctx = proj_context_create();
  proj_log_level(ctx, PJ_LOG_NONE);
  const PJ_TYPE types[] = {PJ_TYPE_GEODETIC_REFERENCE_FRAME, PJ_TYPE_DYNAMIC_GEODETIC_REFERENCE_FRAME,
                           PJ_TYPE_DATUM_ENSEMBLE};
  int checked = 0;
  for (const auto& name : names) {
    const auto implied = implied_ellipsoid(Frame::parse(name, "test"));
    ASSERT_TRUE(implied.has_value()) << name;
    std::string epsg = epsg_spelling(name);
    if (name == "ETRS89") epsg = "European Terrestrial Reference System 1989 ensemble";
    PJ_OBJ_LIST* found = proj_create_from_name(ctx, "EPSG", epsg.c_str(), types, 3, 0, 0, nullptr);
    if (found && proj_list_get_count(found) == 1) {
      PJ* datum = proj_list_get(ctx, found, 0);
      if (proj_get_type(datum) == PJ_TYPE_DATUM_ENSEMBLE) {  // its members share one ellipsoid
        PJ* member = proj_datum_ensemble_get_member(ctx, datum, 0);
        proj_destroy(datum);
        datum = member;
      }
      PJ* ell = proj_get_ellipsoid(ctx, datum);
      double a = 0, b = 0, rf = 0;
      int computed = 0;
      ASSERT_TRUE(ell && proj_ellipsoid_get_parameters(ctx, ell, &a, &b, &computed, &rf)) << name;
      EXPECT_EQ(a, implied->a_m()) << name;
      EXPECT_EQ(rf, implied->rf()) << name;
      proj_destroy(ell);
      proj_destroy(datum);
      ++checked;
    }
    if (found) proj_list_destroy(found);
  }
  proj_context_destroy(ctx);
  EXPECT_GE(checked, 40);  // the rest are newer than PROJ 9.1.1's database (ETRF2020, NAD83(CSRS)v8, WGS 84 (G2296))
  EXPECT_FALSE(implied_ellipsoid(Frame::parse("Tokyo", "test")).has_value());
}

// Issue 39 (the SNAP traverse on International 1924): every ellipsoid
// geoanchor knows by name has the EPSG dataset's a and 1/f (proj.db), and a
// name it does not know is nullopt.
TEST(Ellipsoid, Issue39_NamedEllipsoidsAreProjDbs) {
  constexpr double kRfRelative = 1e-13;  // (Clarke 1866 is defined by b: its 1/f computed on both sides)
  PJ_CONTEXT* ctx = proj_context_create();
  proj_log_level(ctx, PJ_LOG_NONE);
  const PJ_TYPE types[] = {PJ_TYPE_ELLIPSOID};
  int checked = 0;
  for (const char* name : {"GRS 1980", "WGS 84", "International 1924", "Bessel 1841", "Clarke 1866", "Clarke 1880 (RGS)",
                           "Airy 1830", "Krassowsky 1940", "GRS 1967", "Australian National Spheroid"}) {
    const auto ours = named_ellipsoid(name);
    ASSERT_TRUE(ours.has_value()) << name;
    PJ_OBJ_LIST* found = proj_create_from_name(ctx, "EPSG", name, types, 1, 0, 0, nullptr);
    ASSERT_TRUE(found && proj_list_get_count(found) >= 1) << name;
    PJ* ell = nullptr;
    for (int k = 0; k < proj_list_get_count(found) && !ell; ++k) {
      PJ* candidate = proj_list_get(ctx, found, k);
      if (std::string(proj_get_name(candidate)) == name) {
        ell = candidate;
      } else {
        proj_destroy(candidate);
      }
    }
    ASSERT_NE(ell, nullptr) << name;
    double a = 0, b = 0, rf = 0;
    int computed = 0;
    ASSERT_TRUE(proj_ellipsoid_get_parameters(ctx, ell, &a, &b, &computed, &rf)) << name;
    EXPECT_EQ(ours->a_m(), a) << name;
    EXPECT_NEAR(ours->rf(), rf, kRfRelative * rf) << name;
    proj_destroy(ell);
    proj_list_destroy(found);
    ++checked;
  }
  proj_context_destroy(ctx);
  EXPECT_EQ(checked, 10);
  EXPECT_EQ(named_ellipsoid("GRS80"), Ellipsoid::grs80());
  EXPECT_EQ(named_ellipsoid("WGS84"), Ellipsoid::wgs84());
  EXPECT_FALSE(named_ellipsoid("Hayford").has_value());
  EXPECT_FALSE(named_ellipsoid("international 1924").has_value());
}

// issue 12 point 5: the refusal names where the frame was read, the frame,
// and the form that would be accepted.
TEST(Frame, Point5_DynamicFrameWithoutEpochIsRefusedNamingWhereAndTheForm) {
  try {
    require_epoch_if_dynamic(Frame::parse("ITRF2014", "c.csv"), "c.csv: comment 'source_frame = ITRF2014'");
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::input);
    EXPECT_EQ(e.code(), "E_EPOCH_MISSING");
    EXPECT_NE(std::string(e.what()).find("c.csv: comment 'source_frame = ITRF2014': frame ITRF2014 is dynamic"),
              std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("give ITRF2014@YYYY.Y"), std::string::npos) << e.what();
  }
  EXPECT_THROW(require_epoch_if_dynamic(Frame::parse("WGS84(G2139)", "x"), "--from-frame", ErrorKind::usage), Error);
  // With the epoch, or a frame whose coordinates do not move, nothing to say.
  EXPECT_NO_THROW(require_epoch_if_dynamic(Frame::parse("ITRF2014@2024.5", "x"), "x"));
  for (const char* fixed : {"ETRF2000", "GDA2020", "GDA94", "NAD83(2011)", "WGS84", "LOCAL1998"}) {
    EXPECT_NO_THROW(require_epoch_if_dynamic(Frame::parse(fixed, "x"), "x")) << fixed;
  }
}

}  // namespace
}  // namespace geoanchor::geodesy
