// `geoanchor diagnose`: a clean control set, and the same set corrupted in
// exactly one classic way per hypothesis; diagnose must rank that hypothesis
// first (and find no problem in the clean set).
//
// The marks and their corruptions are computed independently of geoanchor:
// positions with GeographicLib (Geocentric, UTMUPS, LocalCartesian), the
// EGM96 undulation, the Helmert transform, ITRF2014 → ETRF2000 and Web
// Mercator with PROJ, plate motion with PROJ's ITRF2014 init file.

#include <GeographicLib/Geocentric.hpp>
#include <GeographicLib/LocalCartesian.hpp>
#include <GeographicLib/UTMUPS.hpp>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <functional>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "cli_support.hpp"
#include "geoanchor/geodesy/float32.hpp"
#include "proj_reference.hpp"

namespace geoanchor::testing {
namespace {

// Survey noise put on each coordinate of each frame (m, 1σ); the sets state it.
constexpr double kNoiseM = 0.003;
constexpr double kDeclaredEpoch = 2020.0;
constexpr int kMarks = 12;

struct Mark {
  std::string id;
  double lat, lon, h;  // ITRF2014 @ 2020.0, degrees and ellipsoidal metres
};

// Twelve marks over 3 km around Zurich airport (not survey data).
std::vector<Mark> marks() {
  std::vector<Mark> out;
  std::mt19937 rng(20261124);
  std::uniform_real_distribution<double> dlat(-0.013, 0.013), dlon(-0.02, 0.02), dh(-20.0, 40.0);
  for (int i = 0; i < kMarks; ++i) {
    char id[8];
    std::snprintf(id, sizeof id, "M%02d", i + 1);
    out.push_back({id, 47.458 + dlat(rng), 8.548 + dlon(rng), 432.0 + dh(rng)});
  }
  return out;
}

std::string num(double v, int decimals) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", decimals, v);
  return b;
}

Eigen::Vector3d ecef(double lat, double lon, double h) {
  Eigen::Vector3d x;
  GeographicLib::Geocentric::WGS84().Forward(lat, lon, h, x[0], x[1], x[2]);
  return x;
}

void geodetic(const Eigen::Vector3d& x, double& lat, double& lon, double& h) {
  GeographicLib::Geocentric::WGS84().Reverse(x[0], x[1], x[2], lat, lon, h);
}

// How the target of a mark is written: the three numbers, given the true
// target ECEF position (noise already on it).
using TargetWriter = std::function<std::array<double, 3>(const Eigen::Vector3d&)>;

struct SetText {
  std::string header_comments;
  std::string source_columns = "lat_src_deg,lon_src_deg,h_src_m";
  std::string target_columns = "x_dst_m,y_dst_m,z_dst_m";
  int source_decimals = 10, target_decimals = 4;
  // The source as written from the true geodetic source (default: as is).
  std::function<std::array<double, 3>(const Mark&)> source = [](const Mark& m) {
    return std::array<double, 3>{m.lat, m.lon, m.h};
  };
  // The true target ECEF of a source ECEF (default: the same frame).
  std::function<Eigen::Vector3d(const Eigen::Vector3d&)> transform = [](const Eigen::Vector3d& x) { return x; };
  TargetWriter target = [](const Eigen::Vector3d& x) { return std::array<double, 3>{x[0], x[1], x[2]}; };
};

// Noise on the source's geodetic position (as a local E, N, U displacement)
// and on the target's ECEF position, seeded per set.
std::string control_csv(const SetText& s) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, kNoiseM);
  std::string out = s.header_comments + "id," + s.source_columns + "," + s.target_columns + ",sigma_src_m,sigma_dst_m\n";
  for (const auto& m : marks()) {
    GeographicLib::LocalCartesian here(m.lat, m.lon, m.h, GeographicLib::Geocentric::WGS84());
    double lat = 0, lon = 0, h = 0;
    here.Reverse(noise(rng), noise(rng), noise(rng), lat, lon, h);
    const Mark noisy{m.id, lat, lon, h};
    const Eigen::Vector3d truth = s.transform(ecef(m.lat, m.lon, m.h));
    const Eigen::Vector3d target = truth + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    const auto src = s.source(noisy);
    const auto dst = s.target(target);
    out += m.id;
    for (double v : src) out += "," + num(v, s.source_decimals);
    for (double v : dst) out += "," + num(v, s.target_decimals);
    out += "," + num(kNoiseM, 3) + "," + num(kNoiseM, 3) + "\n";
  }
  return out;
}

const std::string kSameFrame = "# source_frame = ITRF2014@2020.0\n# target_frame = ITRF2014@2020.0\n";

class DiagnoseCli : public CliTest {
 protected:
  nlohmann::json diagnose(const SetText& s, const std::string& args = "") {
    const auto control = write("control.csv", control_csv(s));
    const RunResult r = run("diagnose '" + control.string() + "' --json " + args);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out, nullptr, false);
    EXPECT_FALSE(j.is_discarded()) << r.out;
    return j;
  }

  // The schema of the issue: problem_found, verdict, and all ten hypotheses,
  // ranked by score.
  static void expect_schema(const nlohmann::json& j) {
    ASSERT_TRUE(j.contains("problem_found") && j["problem_found"].is_boolean());
    ASSERT_TRUE(j.contains("verdict") && j["verdict"].is_string());
    ASSERT_TRUE(j.contains("hypotheses") && j["hypotheses"].is_array());
    std::vector<std::string> names;
    double previous = std::numeric_limits<double>::infinity();
    for (const auto& h : j["hypotheses"]) {
      for (const char* key : {"name", "score", "rms_before_m", "rms_after_m", "effect"}) ASSERT_TRUE(h.contains(key)) << key;
      names.push_back(h["name"]);
      EXPECT_LE(h["score"].get<double>(), previous) << "ranked best first";
      previous = h["score"];
      EXPECT_GE(h["rms_before_m"].get<double>(), 0.0);
      EXPECT_GE(h["rms_after_m"].get<double>(), 0.0);
    }
    EXPECT_THAT(names, ::testing::UnorderedElementsAre("convention_swap", "lat_lon_swap", "degrees_radians", "height_type",
                                                       "datum_mix", "epoch", "web_mercator", "utm_zone", "float32_ecef",
                                                       "enu_origin"));
  }

  void expect_first(const nlohmann::json& j, const std::string& name) {
    expect_schema(j);
    EXPECT_TRUE(j["problem_found"].get<bool>()) << j.dump(2);
    EXPECT_EQ(j["hypotheses"][0]["name"], name) << j.dump(2);
    EXPECT_LT(j["hypotheses"][0]["rms_after_m"].get<double>(), j["hypotheses"][0]["rms_before_m"].get<double>());
    EXPECT_NE(j["verdict"].get<std::string>().find(name), std::string::npos) << j["verdict"];
  }
};

TEST_F(DiagnoseCli, CleanSetHasNoProblem) {
  SetText s;
  s.header_comments = kSameFrame;
  const auto j = diagnose(s);
  expect_schema(j);
  EXPECT_FALSE(j["problem_found"].get<bool>()) << j.dump(2);
  EXPECT_NE(j["verdict"].get<std::string>().find("No classic mistake"), std::string::npos);
  for (const auto& h : j["hypotheses"]) EXPECT_LT(h["score"].get<double>(), 2.0) << h.dump();
}

TEST_F(DiagnoseCli, CleanSetWithPublishedTransformHasNoProblem) {
  // ITRF2014 → ETRF2000 at 2020.0 as PROJ itself chooses it (EPSG).
  const ProjPipeline itrf_to_etrf = ProjPipeline::crs_to_crs("EPSG:7789", "EPSG:7930");
  SetText s;
  s.header_comments = "# source_frame = ITRF2014@2020.0\n# target_frame = ETRF2000@2020.0\n";
  s.transform = [&](const Eigen::Vector3d& x) { return itrf_to_etrf.forward(x, kDeclaredEpoch); };
  const auto j = diagnose(s);
  expect_schema(j);
  EXPECT_FALSE(j["problem_found"].get<bool>()) << j.dump(2);
}

// A seven-parameter set with rotations large enough to matter (about 0.8 m
// at the Earth's surface).
constexpr const char* kHelmertPv =
    "+proj=helmert +x=0.0547 +y=0.0522 +z=-0.0741 +rx=0.0123 +ry=0.0240 +rz=-0.0317 +s=0.00212 "
    "+convention=position_vector";

TEST_F(DiagnoseCli, ConventionSwapRanksFirst) {
  const ProjPipeline helmert(kHelmertPv);
  SetText s;
  s.transform = [&](const Eigen::Vector3d& x) { return helmert.forward(x); };
  // The file states the published numbers in the other convention.
  write("t.json", R"({"model": "helmert7", "convention": "coordinate_frame", "rotation_model": "small_angle",
    "parameters": {"tx_m": 0.0547, "ty_m": 0.0522, "tz_m": -0.0741, "rx_arcsec": 0.0123, "ry_arcsec": 0.0240,
                   "rz_arcsec": -0.0317, "ds_ppm": 0.00212}})");
  expect_first(diagnose(s, "--transform '" + path("t.json").string() + "'"), "convention_swap");
}

TEST_F(DiagnoseCli, LatLonSwapRanksFirst) {
  SetText s;
  s.header_comments = kSameFrame;
  s.target_columns = "lat_dst_deg,lon_dst_deg,h_dst_m";
  s.target_decimals = 10;
  s.target = [](const Eigen::Vector3d& x) {
    double lat = 0, lon = 0, h = 0;
    geodetic(x, lat, lon, h);
    return std::array<double, 3>{lon, lat, h};  // the columns' order mixed up
  };
  expect_first(diagnose(s), "lat_lon_swap");
}

TEST_F(DiagnoseCli, RadiansReadAsDegreesRanksFirst) {
  SetText s;
  s.header_comments = kSameFrame;
  s.source = [](const Mark& m) {
    return std::array<double, 3>{m.lat * std::numbers::pi / 180.0, m.lon * std::numbers::pi / 180.0, m.h};
  };
  s.source_decimals = 12;
  expect_first(diagnose(s), "degrees_radians");
}

TEST_F(DiagnoseCli, OrthometricHeightsRankFirst) {
  // PROJ's vgridshift: z_out = z_in + multiplier × N.
  const ProjPipeline minus_n("+proj=vgridshift +grids=egm96_15.gtx +multiplier=-1");
  SetText s;
  s.header_comments = kSameFrame;
  s.target_columns = "lat_dst_deg,lon_dst_deg,h_dst_m";
  s.target_decimals = 10;
  s.target = [&](const Eigen::Vector3d& x) {
    double lat = 0, lon = 0, h = 0;
    geodetic(x, lat, lon, h);
    const double big_h = minus_n.forward(Eigen::Vector3d(proj_radians(lon), proj_radians(lat), h)).z();
    return std::array<double, 3>{lat, lon, big_h};  // H = h − N where h was due
  };
  const auto j = diagnose(s);
  expect_first(j, "height_type");
}

TEST_F(DiagnoseCli, DatumMixRanksFirst) {
  // Declared ITRF2014 at both ends, but the target is ETRF2000 (EPSG, via PROJ).
  const ProjPipeline itrf_to_etrf = ProjPipeline::crs_to_crs("EPSG:7789", "EPSG:7930");
  SetText s;
  s.header_comments = kSameFrame;
  s.transform = [&](const Eigen::Vector3d& x) { return itrf_to_etrf.forward(x, kDeclaredEpoch); };
  const auto j = diagnose(s);
  expect_first(j, "datum_mix");
  EXPECT_NE(j["hypotheses"][0]["effect"].get<std::string>().find("ETRF"), std::string::npos);
}

TEST_F(DiagnoseCli, WrongEpochRanksFirst) {
  // The target is at 2028.0, declared 2020.0: PROJ's ITRF2014 Eurasia plate
  // motion model over 8 years.
  const ProjPipeline eura("+init=ITRF2014:EURA");
  constexpr double kDeltaYears = 8.0;
  SetText s;
  s.header_comments = kSameFrame;
  s.transform = [&](const Eigen::Vector3d& x) {
    return Eigen::Vector3d(x + eura.forward(x, kDeclaredEpoch + kDeltaYears) - eura.forward(x, kDeclaredEpoch));
  };
  const auto j = diagnose(s);
  expect_first(j, "epoch");
}

TEST_F(DiagnoseCli, WebMercatorRanksFirst) {
  // EPSG:3857's formulas (EPSG method 1024) as PROJ evaluates them.
  const ProjPipeline web_mercator("+proj=merc +a=6378137 +b=6378137");
  SetText s;
  s.header_comments = kSameFrame;
  s.target_columns = "easting_dst_m,northing_dst_m,h_dst_m";
  s.target = [&](const Eigen::Vector3d& x) {
    double lat = 0, lon = 0, h = 0;
    geodetic(x, lat, lon, h);
    const Eigen::Vector3d en = web_mercator.forward(Eigen::Vector3d(proj_radians(lon), proj_radians(lat), 0.0));
    return std::array<double, 3>{en.x(), en.y(), h};
  };
  expect_first(diagnose(s, "--dst-zone 32N"), "web_mercator");
}

TEST_F(DiagnoseCli, WrongUtmZoneRanksFirst) {
  SetText s;
  s.header_comments = kSameFrame;
  s.target_columns = "easting_dst_m,northing_dst_m,h_dst_m";
  s.target = [](const Eigen::Vector3d& x) {
    double lat = 0, lon = 0, h = 0, e = 0, n = 0;
    geodetic(x, lat, lon, h);
    int zone = 0;
    bool north = true;
    GeographicLib::UTMUPS::Forward(lat, lon, zone, north, e, n);
    EXPECT_EQ(zone, 32);
    return std::array<double, 3>{e, n, h};
  };
  const auto j = diagnose(s, "--dst-zone 33N");
  expect_first(j, "utm_zone");
  EXPECT_NE(j["hypotheses"][0]["effect"].get<std::string>().find("32N"), std::string::npos);
}

TEST_F(DiagnoseCli, Float32EcefRanksFirst) {
  SetText s;
  s.header_comments = kSameFrame;
  s.target_decimals = 3;
  s.target = [](const Eigen::Vector3d& x) {
    // Stored as float32 somewhere on the way (0.0625–0.5 m spacing here);
    // this array initializer is the shape GCC 12's SLP vectorizer got wrong
    // (see float32.hpp and tests/geodesy/float32_test.cpp).
    return std::array<double, 3>{geodesy::round_to_float32(x[0]), geodesy::round_to_float32(x[1]),
                                 geodesy::round_to_float32(x[2])};
  };
  expect_first(diagnose(s), "float32_ecef");
}

TEST_F(DiagnoseCli, WrongEnuOriginRanksFirst) {
  // The map was made in ENU at the true origin, turned 0.2° by a wrong
  // heading; diagnose is given a nominal origin 30 m east, 20 m north and
  // 1.5 m above it.
  const double lat0 = 47.458, lon0 = 8.548, h0 = 430.0;
  const GeographicLib::LocalCartesian truth(lat0, lon0, h0, GeographicLib::Geocentric::WGS84());
  double nlat = 0, nlon = 0, nh = 0;
  truth.Reverse(30.0, 20.0, 1.5, nlat, nlon, nh);
  constexpr double kYawRad = 0.2 * std::numbers::pi / 180.0;
  SetText s;
  s.source_columns = "e_src_m,n_src_m,u_src_m";
  s.source_decimals = 4;
  s.source = [&](const Mark& m) {
    double e = 0, n = 0, u = 0;
    truth.Forward(m.lat, m.lon, m.h, e, n, u);
    return std::array<double, 3>{std::cos(kYawRad) * e - std::sin(kYawRad) * n, std::sin(kYawRad) * e + std::cos(kYawRad) * n, u};
  };
  const auto j = diagnose(s, "--origin " + num(nlat, 10) + "," + num(nlon, 10) + "," + num(nh, 4));
  expect_first(j, "enu_origin");
}

TEST_F(DiagnoseCli, TextReportAndRefusals) {
  SetText s;
  s.header_comments = kSameFrame;
  const auto control = write("control.csv", control_csv(s));
  const RunResult text = run("diagnose '" + control.string() + "'");
  EXPECT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("verdict: No classic mistake"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("height_type"), std::string::npos);

  const RunResult missing = run("diagnose '" + path("none.csv").string() + "'");
  EXPECT_EQ(missing.exit_code, 5) << missing.err;
  EXPECT_NE(missing.err.find("none.csv"), std::string::npos);

  SetText projected;
  projected.target_columns = "easting_dst_m,northing_dst_m,h_dst_m";
  const auto p = write("projected.csv", control_csv(projected));
  const RunResult no_grid = run("diagnose '" + p.string() + "'");
  EXPECT_EQ(no_grid.exit_code, 2) << no_grid.err;
  EXPECT_NE(no_grid.err.find("--dst-zone"), std::string::npos) << no_grid.err;

  const RunResult both = run("diagnose '" + p.string() + "' --dst-zone 32N --dst-tm 0,9,1,0,0");
  EXPECT_EQ(both.exit_code, 2) << both.err;

  // A time-dependent transform on points without an epoch (and no frame
  // epoch to fall back on) is refused, not diagnosed.
  const auto undated = write("undated.csv", control_csv(SetText{}));
  write("t14.json", R"({"model": "helmert14", "convention": "position_vector", "rotation_model": "small_angle",
    "reference_epoch": 2010.0,
    "parameters": {"tx_m": 0.01, "ty_m": 0.0, "tz_m": 0.0, "rx_arcsec": 0.0, "ry_arcsec": 0.0, "rz_arcsec": 0.0,
                   "ds_ppm": 0.0, "dtx_m_per_year": 0.001, "dty_m_per_year": 0.0, "dtz_m_per_year": 0.0,
                   "drx_arcsec_per_year": 0.0, "dry_arcsec_per_year": 0.0, "drz_arcsec_per_year": 0.0,
                   "dds_ppm_per_year": 0.0}})");
  const RunResult no_epoch = run("diagnose '" + undated.string() + "' --transform '" + path("t14.json").string() + "'");
  EXPECT_EQ(no_epoch.exit_code, 3) << no_epoch.err;
  EXPECT_NE(no_epoch.err.find("epoch"), std::string::npos) << no_epoch.err;
}

// issue 12 point 2: orthometric heights named as such (H_dst_m) are read
// through --geoid, and then no mistake is left; without it they are refused.
TEST_F(DiagnoseCli, Point2_OrthometricHeightsNamedAsSuchAreReadThroughTheGeoidOrRefused) {
  const ProjPipeline minus_n("+proj=vgridshift +grids=egm96_15.gtx +multiplier=-1");
  SetText s;
  s.header_comments = kSameFrame;
  s.target_columns = "lat_dst_deg,lon_dst_deg,H_dst_m";
  s.target_decimals = 10;
  s.target = [&](const Eigen::Vector3d& x) {
    double lat = 0, lon = 0, h = 0;
    geodetic(x, lat, lon, h);
    return std::array<double, 3>{lat, lon, minus_n.forward(Eigen::Vector3d(proj_radians(lon), proj_radians(lat), h)).z()};
  };
  const auto control = write("control.csv", control_csv(s));
  const RunResult refused = run("diagnose '" + control.string() + "'");
  EXPECT_EQ(refused.exit_code, 3) << refused.err;
  EXPECT_NE(refused.err.find("control.csv: column 'H_dst_m': orthometric height"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("give --geoid EGM96"), std::string::npos) << refused.err;
  const auto j = diagnose(s, "--geoid EGM96");
  expect_schema(j);
  EXPECT_FALSE(j["problem_found"].get<bool>()) << j.dump(2);
}

// issue 12 point 5: a dynamic frame without its epoch, in the set or on the
// command line, is refused naming where it was given.
TEST_F(DiagnoseCli, Point5_ADynamicFrameWithoutItsEpochIsRefusedNamingTheCommentOrTheFlag) {
  SetText s;
  s.header_comments = "# source_frame = ITRF2014\n# target_frame = ITRF2014\n";
  const auto control = write("control.csv", control_csv(s));
  const RunResult file = run("diagnose '" + control.string() + "'");
  EXPECT_EQ(file.exit_code, 3) << file.err;
  EXPECT_NE(file.err.find("control.csv: comment '# source_frame = ITRF2014'"), std::string::npos) << file.err;
  EXPECT_NE(file.err.find("give ITRF2014@YYYY.Y"), std::string::npos) << file.err;
  s.header_comments = kSameFrame;
  const auto dated = write("dated.csv", control_csv(s));
  const RunResult flag = run("diagnose '" + dated.string() + "' --target-frame ITRF2020");
  EXPECT_EQ(flag.exit_code, 2) << flag.err;
  EXPECT_NE(flag.err.find("--target-frame: frame ITRF2020 is dynamic"), std::string::npos) << flag.err;
  // The flags with their epochs replace the file's frames.
  const RunResult given =
      run("diagnose '" + control.string() + "' --source-frame ITRF2014@2020.0 --target-frame ITRF2014@2020.0");
  EXPECT_EQ(given.exit_code, 0) << given.err;
}

}  // namespace
}  // namespace geoanchor::testing
