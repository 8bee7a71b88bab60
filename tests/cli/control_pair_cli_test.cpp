// adjust -> fit -> apply on the bundled airport network (issue 14's
// acceptance), and fit's control from two files, one frame each (--src,
// --dst): the stations adjust writes are one of them.
//
// Expected values are the generator's planted truth
// (fixtures/airport_network/make_airport_network.py: the marks' true
// places and the map origin's shift and yaw), never geoanchor's output;
// the true places are carried to geodetic coordinates by PROJ.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <Eigen/Cholesky>

#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "accuracy.hpp"
#include "cli_support.hpp"
#include "proj_reference.hpp"
#include "test_support.hpp"

namespace geoanchor {
namespace {

using testing::CliTest;
using testing::RunResult;

const std::string kNetworkDir = std::string(GEOANCHOR_FIXTURES_DIR) + "/airport_network/";
const std::string kOrigin = "47.464722,8.549167,480";

// A planted value must lie within this many of its standard deviations
// (from the a-priori weights): the stations CSV carries each station's own
// covariance but not the correlations between stations (the reference
// stations' error is common to every mark), so the fit's σ is optimistic
// by up to √(number of marks) for the common part.
constexpr double kPlantedWithinSigmas = 4.0;

// The generator's truth: ENU (m) about the nominal origin on GRS80.
const std::map<std::string, Eigen::Vector3d> kTruthEnu = {
    {"REFA", {-3512.0, 2488.0, 61.0}}, {"REFB", {4197.0, -3106.0, 12.0}}, {"P01", {102.0, -402.0, -1.2}},
    {"P02", {348.0, -421.0, -0.4}},    {"P03", {601.0, -383.0, 0.6}},     {"P04", {622.0, -198.0, 1.1}},
    {"P05", {598.0, 3.0, 1.9}},        {"P06", {351.0, 22.0, 0.8}},       {"P07", {98.0, -18.0, -0.3}},
    {"P08", {79.0, -203.0, -0.9}},     {"T1", {352.0, -205.0, 0.2}}};
// The map's planted error (make_airport_network.py SHIFT_ENU_M, YAW_ARCSEC).
constexpr double kShiftE = 0.412, kShiftN = -0.287, kShiftU = 0.153, kYawArcsec = 14.0;

class ControlPairCli : public CliTest {};

std::string g17(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

TEST_F(ControlPairCli, Issue14_AirportNetworkAdjustFitApplyRecoversThePlantedTruth) {
  const std::string st = path("stations.csv").string(), t = path("map_to_itrf.json").string();
  RunResult r = run("adjust '" + kNetworkDir + "lszh_network.json' -o '" + st + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;

  // Every station within its standard deviations of the truth, through
  // PROJ's topocentric conversion (ENU about the origin).
  const testing::ProjPipeline enu(
      "+proj=pipeline +step +proj=cart +ellps=GRS80 +step +proj=topocentric +ellps=GRS80 +lat_0=47.464722 "
      "+lon_0=8.549167 +h_0=480");
  const auto table = testing::parse_csv_table(testing::slurp(path("stations.csv")));
  ASSERT_EQ(table.rows.size(), kTruthEnu.size());
  double worst_sigmas = 0.0;
  for (const auto& row : table.rows) {
    const std::string& id = row[table.col("id")];
    ASSERT_TRUE(kTruthEnu.count(id)) << id;
    const Eigen::Vector3d got = enu.forward({std::stod(row[table.col("lon_deg")]) * std::numbers::pi / 180.0,
                                             std::stod(row[table.col("lat_deg")]) * std::numbers::pi / 180.0,
                                             std::stod(row[table.col("h_m")])});
    const Eigen::Vector3d sigma(std::stod(row[table.col("sigma_e_m")]), std::stod(row[table.col("sigma_n_m")]),
                                std::stod(row[table.col("sigma_u_m")]));
    for (int k = 0; k < 3; ++k) {
      worst_sigmas = testing::nan_max(worst_sigmas, std::abs(got(k) - kTruthEnu.at(id)(k)) / sigma(k));
    }
  }
  EXPECT_WORST_WITHIN(worst_sigmas, kPlantedWithinSigmas);

  r = run("fit --src '" + kNetworkDir + "lszh_marks_map.csv' --dst '" + st + "' --model enu-origin --origin " + kOrigin +
          " -o '" + t + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("3 mark(s) of " + st + " are not in"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("REFA, REFB, T1"), std::string::npos) << r.err;
  const auto file = nlohmann::json::parse(testing::slurp(path("map_to_itrf.json")));
  const auto& p = file.at("parameters");
  const auto& s = file.at("sigmas");
  for (const auto& [key, planted] : std::vector<std::pair<std::string, double>>{
           {"shift_e_m", kShiftE}, {"shift_n_m", kShiftN}, {"shift_u_m", kShiftU}, {"yaw_arcsec", kYawArcsec}}) {
    SCOPED_TRACE(key);
    const double off = std::abs(p.at(key).get<double>() - planted) / s.at(key).get<double>();
    EXPECT_WORST_WITHIN(off, kPlantedWithinSigmas);
  }
  EXPECT_EQ(file.at("source_frame"), "ITRF2014@2024.5");
  EXPECT_EQ(file.at("target_frame"), "ITRF2014@2024.5");

  r = run("apply '" + std::string(GEOANCHOR_FIXTURES_DIR) + "/airport_tile.las' --transform '" + t + "' --out-dir '" +
          path("tiles").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto side = nlohmann::json::parse(testing::slurp(path("tiles/airport_tile.las.geoanchor.json")));
  EXPECT_EQ(side.at("frame"), "ITRF2014@2024.5");
  EXPECT_EQ(side.at("provenance").at("extrapolation").at("distance_outside_control_m").get<double>(), 0.0);
}

// The 1998 site survey (lszh_site1998.json, a point cluster in the site
// datum SITE1998) related to the network by an estimated Helmert: the
// planted parameters lie within the estimate's covariance (a site a
// kilometre across determines the geocentric parameters only together:
// σ of tens of metres, correlations near ±1), and the transform takes the
// site survey onto the adjusted stations.
TEST_F(ControlPairCli, Issue14_SiteDatumHelmertIsEstimatedWithTheNetwork) {
  const std::string st = path("stations.csv").string();
  const RunResult r = run("adjust '" + kNetworkDir + "lszh_network.json' '" + kNetworkDir + "lszh_site1998.json' -o '" + st +
                          "' --estimate-helmert '" + kNetworkDir + "lszh_site1998.json' --convention position_vector");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto file = nlohmann::json::parse(testing::slurp(path("stations.helmert.json")));
  EXPECT_EQ(file.at("source_frame"), "SITE1998");
  // make_airport_network.py SITE_HELMERT.
  const std::map<std::string, double> planted = {{"tx_m", -0.512},     {"ty_m", 1.204},      {"tz_m", -0.337},
                                                 {"rx_arcsec", 0.12},  {"ry_arcsec", -0.31}, {"rz_arcsec", 0.45},
                                                 {"ds_ppm", -2.4}};
  const auto& names = file.at("correlation_parameters");
  ASSERT_EQ(names.size(), 7u);
  Eigen::VectorXd d(7), sigma(7);
  Eigen::MatrixXd corr(7, 7);
  for (int i = 0; i < 7; ++i) {
    const std::string n = names[static_cast<std::size_t>(i)];
    d(i) = file.at("parameters").at(n).get<double>() - planted.at(n);
    sigma(i) = file.at("sigmas").at(n).get<double>();
    for (int j = 0; j < 7; ++j) corr(i, j) = file.at("correlation")[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)].get<double>();
  }
  const Eigen::MatrixXd cov = sigma.asDiagonal() * corr * sigma.asDiagonal();
  const double mahalanobis2 = d.dot(cov.ldlt().solve(d));
  // χ²(7) at 0.999 (any table: 24.32).
  constexpr double kChi2Seven999 = 24.32;
  EXPECT_WORST_WITHIN(mahalanobis2, kChi2Seven999);
  RecordProperty("planted_helmert_chi2", std::to_string(mahalanobis2));

  // The site's coordinates of P04 through the file: onto the adjusted P04
  // within the site survey's 5 mm per axis (4σ: 35 mm in 3-D).
  const auto site = nlohmann::json::parse(testing::slurp(kNetworkDir + "lszh_site1998.json"));
  std::string in = "id,x_m,y_m,z_m\n";
  for (const auto& p : site.at("measurements")[0].at("points")) {
    if (p.at("id") == "P04") {
      in += "P04," + g17(p.at("x_m").get<double>()) + "," + g17(p.at("y_m").get<double>()) + "," +
            g17(p.at("z_m").get<double>()) + "\n";
    }
  }
  write("site.csv", in);
  const RunResult c = run("convert '" + path("site.csv").string() + "' --transform '" + path("stations.helmert.json").string() +
                          "' --to ecef --precision 5");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const auto moved = testing::parse_csv_table(c.out);
  const auto adjusted = testing::parse_csv_table(testing::slurp(path("stations.csv")));
  ASSERT_EQ(moved.rows.size(), 1u);
  for (const auto& row : adjusted.rows) {
    if (row[adjusted.col("id")] != "P04") continue;
    Eigen::Vector3d delta;
    for (int k = 0; k < 3; ++k) {
      const char* axis[] = {"x_m", "y_m", "z_m"};
      delta(k) = std::stod(moved.rows[0][moved.col(axis[k])]) - std::stod(row[adjusted.col(axis[k])]);
    }
    constexpr double kSiteSurveyWithinM = 4.0 * 0.005 * 1.7320508;
    EXPECT_WORST_WITHIN(delta.norm(), kSiteSurveyWithinM);
  }
}

// The join itself: ids in both files, in the source file's order, with each
// file's covariance; a held component's zero sigma is accepted.
TEST_F(ControlPairCli, Issue14_TwoFilesAreJoinedByIdWithEachFramesCovariance) {
  write("map.csv",
        "# frame = ITRF2014@2024.5\n"
        "id,e_m,n_m,u_m,sigma_m\n"
        "B,100.0,0.0,1.0,0.01\nA,0.0,0.0,0.0,0.01\nC,0.0,100.0,2.0,0.01\nX,5.0,5.0,0.0,0.01\n");
  // The same marks on the ellipsoid: exactly ENU about the origin (PROJ), with
  // sigmas along east, north, up and A held (CCC, zero sigmas).
  const testing::ProjPipeline geo(
      "+proj=pipeline +step +inv +proj=topocentric +ellps=GRS80 +lat_0=47.464722 +lon_0=8.549167 +h_0=480 "
      "+step +inv +proj=cart +ellps=GRS80");
  const testing::ProjPipeline cart("+proj=cart +ellps=GRS80");
  std::string st =
      "# frame = ITRF2014@2024.5\n# ellipsoid = GRS80\n"
      "id,x_m,y_m,z_m,lat_deg,lon_deg,h_m,sigma_e_m,sigma_n_m,sigma_u_m,corr_en,corr_eu,corr_nu,ellipse_a_m,ellipse_b_m,"
      "ellipse_azimuth_deg,ellipse_conf_a_m,ellipse_conf_b_m,constraint\n";
  const std::vector<std::pair<std::string, Eigen::Vector3d>> marks = {
      {"A", {0.0, 0.0, 0.0}}, {"B", {100.0, 0.0, 1.0}}, {"C", {0.0, 100.0, 2.0}}, {"Y", {50.0, 50.0, 0.0}}};
  for (const auto& [id, e] : marks) {
    const Eigen::Vector3d g = geo.forward(e);
    const Eigen::Vector3d x = cart.forward(g);
    char line[400];
    std::snprintf(line, sizeof line, "%s,%.5f,%.5f,%.5f,%.11f,%.11f,%.5f,%s,0,0,0,0,0,0,0,0,%s\n", id.c_str(), x(0), x(1), x(2),
                  g(1) * 180.0 / std::numbers::pi, g(0) * 180.0 / std::numbers::pi, g(2),
                  id == "A" ? "0,0,0" : "0.002,0.003,0.004", id == "A" ? "CCC" : "FFF");
    st += line;
  }
  write("st.csv", st);
  const RunResult r = run("fit --src '" + path("map.csv").string() + "' --dst '" + path("st.csv").string() +
                          "' --model translation3 --origin " + kOrigin + " --allow-unmatched --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("control").at("points"), 3);
  EXPECT_EQ(j.at("control").at("files").size(), 2u);
  EXPECT_EQ(j.at("control").at("files")[1].at("role"), "target");
  const auto& points = j.at("transform").at("points");
  ASSERT_EQ(points.size(), 3u);
  EXPECT_EQ(points[0].at("id"), "B");  // the source file's order
  EXPECT_EQ(points[1].at("id"), "A");
  // The translation of identical marks is zero to the rounding of the files (10 µm).
  constexpr double kRoundingM = 1e-5;
  for (const char* key : {"tx_m", "ty_m", "tz_m"}) {
    EXPECT_WORST_WITHIN(std::abs(j.at("transform").at("parameters").at(key).get<double>()), kRoundingM) << key;
  }
  EXPECT_NE(r.err.find("1 mark(s) of " + path("map.csv").string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(": X"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(": Y"), std::string::npos) << r.err;
  int recorded = 0;  // both notes recorded with the fit
  for (const auto& w : j.at("transform").at("statistics").at("warnings")) {
    recorded += w.get<std::string>().find("are not part of the control") != std::string::npos ? 1 : 0;
  }
  EXPECT_EQ(recorded, 2);

  // The target in a CRS stated above its header with its coordinate epoch,
  // as convert writes them (EPSG:7912, ITRF2014 geographic 3-D).
  std::string crs_file = "# crs = EPSG:7912\n# coordinate_epoch = 2024.5\nid,lat_deg,lon_deg,h_m,sigma_m\n";
  for (const auto& [id, e] : marks) {
    if (id == "Y") continue;
    const Eigen::Vector3d g = geo.forward(e);
    char line[200];
    std::snprintf(line, sizeof line, "%s,%.11f,%.11f,%.5f,0.003\n", id.c_str(), g(1) * 180.0 / std::numbers::pi,
                  g(0) * 180.0 / std::numbers::pi, g(2));
    crs_file += line;
  }
  write("crs.csv", crs_file);
  write("map3.csv", "# frame = ITRF2014@2024.5\nid,e_m,n_m,u_m,sigma_m\nB,100.0,0.0,1.0,0.01\nA,0.0,0.0,0.0,0.01\nC,0.0,100.0,2.0,0.01\n");
  const RunResult c = run("fit --src '" + path("map3.csv").string() + "' --dst '" + path("crs.csv").string() +
                          "' --model translation3 --origin " + kOrigin + " --json");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const auto jc = nlohmann::json::parse(c.out);
  EXPECT_EQ(jc.at("transform").at("target_frame"), "ITRF2014@2024.5");
  for (const char* key : {"tx_m", "ty_m", "tz_m"}) {
    EXPECT_WORST_WITHIN(std::abs(jc.at("transform").at("parameters").at(key).get<double>()), kRoundingM) << key;
  }
}

struct BadPair {
  std::string name, src, dst, args;
  int exit_code;
  std::vector<std::string> message;
};

TEST_F(ControlPairCli, Issue14_BadRoleFilesAreRefusedByNameWithNoOutput) {
  const std::string map = "# frame = ITRF2014@2024.5\nid,e_m,n_m,u_m,sigma_m\nA,0,0,0,0.01\nB,100,0,0,0.01\nC,0,100,0,0.01\n";
  const std::string head = "# frame = ITRF2014@2024.5\n# ellipsoid = GRS80\nid,x_m,y_m,z_m,lat_deg,lon_deg,h_m,sigma_e_m,sigma_n_m,sigma_u_m,constraint\n";
  // 47.464722, 8.549167, 480 on GRS80 (PROJ cct: +proj=cart +ellps=GRS80).
  const std::string a = "A,4272081.94754,642215.27325,4677200.73799,47.464722,8.549167,480.0,";
  const std::vector<BadPair> cases = {
      {"a role in a column name", "id,e_src_m,n_src_m,u_src_m\nA,0,0,0\n", head + a + "0.002,0.002,0.004,FFF\n", "", 3,
       {"src.csv", "e_src_m", "names no role"}},
      {"a per-point epoch", "id,e_m,n_m,u_m,epoch\nA,0,0,0,2024.5\n", head + a + "0.002,0.002,0.004,FFF\n", "", 3,
       {"src.csv", "'epoch'", "# frame = NAME@EPOCH"}},
      {"x,y,z and lat,lon,h of two points", map,
       head + "A,4272081.94754,642215.27325,4677200.77799,47.464722,8.549167,480.0,0.002,0.002,0.004,FFF\n", "", 3,
       {"dst.csv:4", "x_m", "two different points"}},
      {"a zero sigma on a free component", map, head + a + "0.002,0,0.004,FFF\n", "", 3,
       {"dst.csv:4", "sigma_n_m='0'", "constraint column holds"}},
      {"an ellipsoid the frame contradicts", map,
       "# frame = ITRF2014@2024.5\n# ellipsoid = WGS84\nid,lat_deg,lon_deg,h_m,sigma_m\nA,47.464722,8.549167,480.0,0.01\n", "", 3,
       {"E_ELLIPSOID", "dst.csv", "WGS84", "GRS80"}},
      {"no id in common", map, head + "Z" + a.substr(1) + "0.002,0.002,0.004,FFF\n", "", 3, {"E_NO_COMMON_MARKS", "no id in common"}},
      {"a local network's stations", map, "# local network: axes ne, 3-D\nid,x_m,y_m,z_m,sigma_x_m,sigma_y_m,sigma_z_m,constraint\nA,1,2,3,0,0,0,CCC\n",
       "", 3, {"dst.csv", "local network", "not on a frame"}},
      {"a two-role comment", "# source_frame = ITRF2014@2024.5\nid,e_m,n_m,u_m\nA,0,0,0\n", head + a + "0.002,0.002,0.004,FFF\n", "", 3,
       {"src.csv", "source_frame", "# frame = NAME@EPOCH"}},
      {"an unknown uncertainty column", map, head.substr(0, head.size() - 1) + ",sigma_h_m\n" + a + "0.002,0.002,0.004,FFF,0.01\n", "",
       3, {"dst.csv", "sigma_h_m", "not read"}},
      {"a JSON role file", "{\"points\": []}\n", head + a + "0.002,0.002,0.004,FFF\n", "", 3, {"src.csv", "JSON"}},
      {"CONTROL beside --src", map, head + a + "0.002,0.002,0.004,FFF\n", "'" + path("src.csv").string() + "'", 2,
       {"E_OPTION", "--src FILE --dst FILE"}},
      {"a source mark the target lacks", map, head + a + "0.002,0.002,0.004,FFF\n" + "B" + a.substr(1) + "0.002,0.002,0.004,FFF\n",
       "", 3, {"E_UNMATCHED_ID", "src.csv", "1 mark(s)", ": C", "--allow-unmatched"}},
      {"a held station against a mark without sigma", "# frame = ITRF2014@2024.5\nid,e_m,n_m,u_m\nA,0,0,0\n",
       head + a + "0,0,0,CCC\n", "", 3, {"E_SIGMA", "src.csv:3", "dst.csv:4", "held station"}},
      {"a constraint that is not C/F", map, head + a + "0.002,0.002,0.004,ccf\n", "--allow-unmatched", 3,
       {"dst.csv:4", "constraint='ccf'", "three letters"}},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    write("src.csv", c.src);
    write("dst.csv", c.dst);
    const RunResult r = run("fit " + c.args + " --src '" + path("src.csv").string() + "' --dst '" + path("dst.csv").string() +
                            "' --model translation3 --origin " + kOrigin + " -o '" + path("t.json").string() + "'");
    EXPECT_EQ(r.exit_code, c.exit_code) << r.err;
    for (const auto& piece : c.message) EXPECT_NE(r.err.find(piece), std::string::npos) << piece << " in: " << r.err;
    EXPECT_EQ(leftovers({"src.csv", "dst.csv"}), std::vector<std::string>{});
  }
}

}  // namespace
}  // namespace geoanchor
