// adjust --estimate-helmert (issue 14 point 7): a group of GNSS point
// clusters in a datum of its own is related to the network's frame by a
// Helmert estimated with the stations, written as a transform file that
// convert uses.
//
// The group's coordinates are made by PROJ's own helmert operation
// (inverse, from the true positions) with planted parameters: with
// noise-free data the adjustment must give back exactly those parameters,
// in both conventions, with and without rates; convert with the written
// file must take the group's coordinates back onto the network's.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <limits>
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

// Noise-free data: what the solver leaves is its convergence and the
// files' 17-digit numbers; 1e-6 m over a few kilometres is 2e-4″ or 0.2 ppb.
constexpr double kTranslationToleranceM = 1e-6;
constexpr double kRotationToleranceArcsec = 1e-4;
constexpr double kScaleTolerancePpm = 1e-3;
constexpr double kRateToleranceFactor = 1.0;  // the same per year over 10 years: the seven's tolerances / 5 years
// convert with the written file: the group's point onto the network's.
constexpr double kConvertToleranceM = 1e-5;

// Planted, position-vector convention (PROJ's +x … +s, arcsec, ppm).
constexpr double kTx = 12.3, kTy = -4.1, kTz = 7.7, kRx = 0.8, kRy = -1.1, kRz = 0.4, kDs = 3.2;
constexpr double kDtx = 0.011, kDty = -0.007, kDtz = 0.015, kDrx = 0.02, kDry = 0.03, kDrz = -0.01, kDds = 0.05;

// Six marks around Zürich, ENU (m) about 47.46, 8.55, 480 on GRS80.
const std::vector<std::pair<std::string, Eigen::Vector3d>> kMarks = {
    {"M1", {0.0, 0.0, 0.0}},          {"M2", {2500.0, 300.0, 12.0}},    {"M3", {-1800.0, 2200.0, 40.0}},
    {"M4", {900.0, -3100.0, -15.0}},  {"M5", {-2600.0, -1500.0, 5.0}}, {"M6", {3100.0, 2800.0, 60.0}}};

std::string number(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

// PROJ's helmert with the planted parameters (and rates, about 2015.0).
std::string planted_helmert(bool rates) {
  return "+proj=helmert +convention=position_vector +x=" + number(kTx) + " +y=" + number(kTy) + " +z=" + number(kTz) +
         " +rx=" + number(kRx) + " +ry=" + number(kRy) + " +rz=" + number(kRz) + " +s=" + number(kDs) +
         (rates ? " +dx=" + number(kDtx) + " +dy=" + number(kDty) + " +dz=" + number(kDtz) + " +drx=" + number(kDrx) +
                      " +dry=" + number(kDry) + " +drz=" + number(kDrz) + " +ds=" + number(kDds) + " +t_epoch=2015"
                : std::string());
}

// The point PROJ's forward helmert takes onto `x`: PROJ's inverse of a
// small-angle Helmert is the transposed rotation (exact to O(r²), 0.2 mm
// at 1″ on the Earth), so its result is refined through the forward
// operation, the definition (EPSG's small-angle form), until it maps onto x.
Eigen::Vector3d exact_inverse(const testing::ProjPipeline& h, const Eigen::Vector3d& x, double t = 0.0) {
  Eigen::Vector3d g = h.inverse(x, t);
  for (int k = 0; k < 4; ++k) g += h.inverse(x, t) - h.inverse(h.forward(g, t), t);
  return g;
}

class AdjustHelmertCli : public CliTest {
 protected:
  // `convert --transform FILE` of one ECEF point (with `args`), read back.
  Eigen::Vector3d converted(const Eigen::Vector3d& g, const std::string& file, const std::string& args) {
    write("in.csv", "id,x_m,y_m,z_m\nP," + number(g.x()) + "," + number(g.y()) + "," + number(g.z()) + "\n");
    const RunResult c = run("convert '" + path("in.csv").string() + "' --transform '" + path(file).string() + "' " + args +
                            " --to ecef --precision 6");
    EXPECT_EQ(c.exit_code, 0) << c.err;
    const auto table = testing::parse_csv_table(c.out);
    if (table.rows.size() != 1) {
      ADD_FAILURE() << "convert gave " << table.rows.size() << " rows: " << c.out << c.err;
      return Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
    }
    return {std::stod(table.rows[0][table.col("x_m")]), std::stod(table.rows[0][table.col("y_m")]),
            std::stod(table.rows[0][table.col("z_m")])};
  }

  // The marks' true ECEF positions (PROJ).
  std::vector<Eigen::Vector3d> truth() const {
    const testing::ProjPipeline to_ecef(
        "+proj=pipeline +step +inv +proj=topocentric +ellps=GRS80 +lat_0=47.46 +lon_0=8.55 +h_0=480 +step +inv +proj=cart "
        "+ellps=GRS80 +step +proj=cart +ellps=GRS80");
    std::vector<Eigen::Vector3d> out;
    for (const auto& m : kMarks) out.push_back(to_ecef.forward(m.second));
    return out;
  }

  // The network: every mark fixed at its truth in ITRF2014@2024.5, and one
  // point cluster per epoch in group "legacy", frame LEGACY, made by PROJ's
  // inverse helmert (with rates when `rates`).
  std::string network(const std::vector<double>& epochs, bool rates) const {
    const testing::ProjPipeline h(planted_helmert(rates));
    const auto x = truth();
    std::string stations, measurements;
    for (std::size_t i = 0; i < kMarks.size(); ++i) {
      stations += std::string(i ? "," : "") + R"({"id": ")" + kMarks[i].first + R"(", "x_m": )" + number(x[i].x()) +
                  R"(, "y_m": )" + number(x[i].y()) + R"(, "z_m": )" + number(x[i].z()) + R"(, "constraint": "CCC"})";
    }
    for (std::size_t e = 0; e < epochs.size(); ++e) {
      std::string points;
      for (std::size_t i = 0; i < kMarks.size(); ++i) {
        const Eigen::Vector3d g = exact_inverse(h, x[i], epochs[e]);
        points += std::string(i ? "," : "") + R"({"id": ")" + kMarks[i].first + R"(", "x_m": )" + number(g.x()) + R"(, "y_m": )" +
                  number(g.y()) + R"(, "z_m": )" + number(g.z()) + R"(, "sigma_m": 0.005})";
      }
      char frame[40];
      std::snprintf(frame, sizeof frame, "LEGACY@%.1f", epochs[e]);
      measurements += std::string(e ? "," : "") + R"({"kind": "gnss_point_cluster", "group": "legacy", "frame": ")" + frame +
                      R"(", "points": [)" + points + "]}";
    }
    return R"({"schema": "geoanchor.network/1", "frame": "ITRF2014@2024.5", "stations": [)" + stations +
           R"(], "measurements": [)" + measurements + "]}";
  }
};

TEST_F(AdjustHelmertCli, Issue14_Helmert7IsRecoveredExactlyInBothConventions) {
  write("net.json", network({2010.0}, false));
  for (const char* convention : {"position_vector", "coordinate_frame"}) {
    SCOPED_TRACE(convention);
    const double sign = std::string(convention) == "position_vector" ? 1.0 : -1.0;
    const RunResult r = run("adjust '" + path("net.json").string() + "' -o '" + path("st.csv").string() +
                            "' --estimate-helmert legacy --convention " + convention + " --overwrite --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto file = nlohmann::json::parse(testing::slurp(path("st.helmert.json")));
    EXPECT_EQ(file.at("model"), "helmert7");
    EXPECT_EQ(file.at("convention"), convention);
    EXPECT_EQ(file.at("source_frame"), "LEGACY@2010.0");
    EXPECT_EQ(file.at("target_frame"), "ITRF2014@2024.5");
    const auto& p = file.at("parameters");
    double t = 0.0, rot = 0.0;
    t = testing::nan_max(t, std::abs(p.at("tx_m").get<double>() - kTx));
    t = testing::nan_max(t, std::abs(p.at("ty_m").get<double>() - kTy));
    t = testing::nan_max(t, std::abs(p.at("tz_m").get<double>() - kTz));
    rot = testing::nan_max(rot, std::abs(p.at("rx_arcsec").get<double>() - sign * kRx));
    rot = testing::nan_max(rot, std::abs(p.at("ry_arcsec").get<double>() - sign * kRy));
    rot = testing::nan_max(rot, std::abs(p.at("rz_arcsec").get<double>() - sign * kRz));
    EXPECT_WORST_WITHIN(t, kTranslationToleranceM);
    EXPECT_WORST_WITHIN(rot, kRotationToleranceArcsec);
    EXPECT_WORST_WITHIN(std::abs(p.at("ds_ppm").get<double>() - kDs), kScaleTolerancePpm);
    EXPECT_TRUE(file.at("sigmas").contains("rz_arcsec"));
    EXPECT_EQ(file.at("correlation").size(), 7u);
    const auto report = nlohmann::json::parse(r.out);
    EXPECT_EQ(report.at("dof"), 18 - 7);
    EXPECT_EQ(report.at("helmert").at("group"), "legacy");
  }
  // The parameters' standard deviations are fit's for the same marks (its
  // own solver): the group's points as the source with their 5 mm, the
  // fixed stations as the target.
  {
    const auto x_true = truth();
    const testing::ProjPipeline h7(planted_helmert(false));
    std::string control = "# source_frame = LEGACY@2010.0\n# target_frame = ITRF2014@2024.5\n"
                          "id,x_src_m,y_src_m,z_src_m,x_dst_m,y_dst_m,z_dst_m,sigma_src_m\n";
    for (std::size_t i = 0; i < kMarks.size(); ++i) {
      const Eigen::Vector3d g = exact_inverse(h7, x_true[i]);
      control += kMarks[i].first + "," + number(g.x()) + "," + number(g.y()) + "," + number(g.z()) + "," + number(x_true[i].x()) +
                 "," + number(x_true[i].y()) + "," + number(x_true[i].z()) + ",0.005\n";
    }
    write("control.csv", control);
    RunResult a = run("adjust '" + path("net.json").string() + "' -o '" + path("st.csv").string() +
                      "' --estimate-helmert legacy --convention position_vector --overwrite");
    ASSERT_EQ(a.exit_code, 0) << a.err;
    const RunResult f = run("fit '" + path("control.csv").string() + "' --model helmert7 --convention position_vector -o '" +
                            path("fit.json").string() + "'");
    ASSERT_EQ(f.exit_code, 0) << f.err;
    const auto adjusted = nlohmann::json::parse(testing::slurp(path("st.helmert.json"))).at("sigmas");
    const auto fitted = nlohmann::json::parse(testing::slurp(path("fit.json"))).at("sigmas");
    constexpr double kSameSigmaRelative = 1e-6;
    double worst = 0.0;
    for (const char* key : {"tx_m", "ty_m", "tz_m", "rx_arcsec", "ry_arcsec", "rz_arcsec", "ds_ppm"}) {
      worst = testing::nan_max(worst, std::abs(adjusted.at(key).get<double>() / fitted.at(key).get<double>() - 1.0));
    }
    EXPECT_WORST_WITHIN(worst, kSameSigmaRelative);
  }
  // convert with the file: a group coordinate onto the network's.
  const auto x = truth();
  const testing::ProjPipeline h(planted_helmert(false));
  const Eigen::Vector3d got = converted(exact_inverse(h, x[3]), "st.helmert.json", "");
  EXPECT_WORST_WITHIN((got - x[3]).norm(), kConvertToleranceM);
}

TEST_F(AdjustHelmertCli, Issue14_Helmert14IsRecoveredWithItsRatesAtTheMeanEpoch) {
  write("net.json", network({2010.0, 2020.0}, true));
  const RunResult r = run("adjust '" + path("net.json").string() + "' -o '" + path("st.csv").string() +
                          "' --estimate-helmert legacy:helmert14 --convention position_vector --helmert-output '" +
                          path("h14.json").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto file = nlohmann::json::parse(testing::slurp(path("h14.json")));
  EXPECT_EQ(file.at("model"), "helmert14");
  EXPECT_EQ(file.at("source_frame"), "LEGACY");
  EXPECT_DOUBLE_EQ(file.at("reference_epoch").get<double>(), 2015.0);
  const auto& p = file.at("parameters");
  const std::vector<std::tuple<const char*, double, double>> expected = {
      {"tx_m", kTx, kTranslationToleranceM},
      {"rx_arcsec", kRx, kRotationToleranceArcsec},
      {"ds_ppm", kDs, kScaleTolerancePpm},
      {"dtx_m_per_year", kDtx, kRateToleranceFactor * kTranslationToleranceM / 5.0},
      {"dty_m_per_year", kDty, kRateToleranceFactor * kTranslationToleranceM / 5.0},
      {"dtz_m_per_year", kDtz, kRateToleranceFactor * kTranslationToleranceM / 5.0},
      {"drx_arcsec_per_year", kDrx, kRateToleranceFactor * kRotationToleranceArcsec / 5.0},
      {"dry_arcsec_per_year", kDry, kRateToleranceFactor * kRotationToleranceArcsec / 5.0},
      {"drz_arcsec_per_year", kDrz, kRateToleranceFactor * kRotationToleranceArcsec / 5.0},
      {"dds_ppm_per_year", kDds, kRateToleranceFactor * kScaleTolerancePpm / 5.0}};
  for (const auto& [key, planted, tolerance] : expected) {
    SCOPED_TRACE(key);
    EXPECT_WORST_WITHIN(std::abs(p.at(key).get<double>() - planted), tolerance);
  }
  // convert at an epoch five years from the reference epoch: the group's
  // 2010 coordinates of M6 onto the network's.
  const auto x = truth();
  const testing::ProjPipeline h(planted_helmert(true));
  const Eigen::Vector3d got = converted(exact_inverse(h, x[5], 2010.0), "h14.json", "--epoch 2010.0");
  EXPECT_WORST_WITHIN((got - x[5]).norm(), kConvertToleranceM);
}

TEST_F(AdjustHelmertCli, Issue14_BadHelmertGroupsAreRefusedByNameWithNoOutput) {
  write("net.json", network({2010.0}, false));
  struct Case {
    std::string name, args;
    int exit_code;
    std::vector<std::string> message;
  };
  const std::vector<Case> cases = {
      {"no convention", "--estimate-helmert legacy", 2, {"E_OPTION", "--convention"}},
      {"an unknown group", "--estimate-helmert nothere --convention position_vector", 2, {"E_OPTION", "nothere", "legacy"}},
      {"an unknown model", "--estimate-helmert legacy:helmert9 --convention position_vector", 2, {"E_OPTION", "helmert9"}},
      {"rates from one epoch", "--estimate-helmert legacy:helmert14 --convention position_vector", 3,
       {"E_HELMERT_GROUP", "two epochs"}},
      {"with --free", "--estimate-helmert legacy --convention position_vector --free", 2, {"E_OPTION", "--free"}},
      {"a convention without a group", "--convention position_vector", 2, {"E_OPTION", "only with --estimate-helmert"}},
  };
  // Geometry: two stations, and stations along one line (a runway).
  {
    const auto x = truth();
    auto cluster = [&](const std::vector<Eigen::Vector3d>& points) {
      std::string stations, list;
      for (std::size_t i = 0; i < points.size(); ++i) {
        const std::string id = "R" + std::to_string(i);
        stations += std::string(i ? "," : "") + R"({"id": ")" + id + R"(", "x_m": )" + number(points[i].x()) + R"(, "y_m": )" +
                    number(points[i].y()) + R"(, "z_m": )" + number(points[i].z()) + R"(, "constraint": "CCC"})";
        list += std::string(i ? "," : "") + R"({"id": ")" + id + R"(", "x_m": )" + number(points[i].x() + 1.0) +
                R"(, "y_m": )" + number(points[i].y()) + R"(, "z_m": )" + number(points[i].z()) + R"(, "sigma_m": 0.005})";
      }
      return R"({"schema": "geoanchor.network/1", "frame": "ITRF2014@2024.5", "stations": [)" + stations +
             R"(], "measurements": [{"kind": "gnss_point_cluster", "group": "legacy", "frame": "LEGACY", "points": [)" + list +
             "]}]}";
    };
    const Eigen::Vector3d along = (x[1] - x[0]).normalized();
    write("two.json", cluster({x[0], x[1]}));
    write("line.json", cluster({x[0], x[0] + 1000.0 * along, x[0] + 2000.0 * along + Eigen::Vector3d(0.0, 0.0, 1e-3)}));
    for (const auto& [file, piece] : {std::pair<std::string, std::string>{"two.json", "reaches 2 station(s)"},
                                      std::pair<std::string, std::string>{"line.json", "lie on one line"}}) {
      SCOPED_TRACE(file);
      const RunResult r = run("adjust '" + path(file).string() + "' -o '" + path("st.csv").string() +
                              "' --estimate-helmert legacy --convention position_vector");
      EXPECT_EQ(r.exit_code, 3) << r.err;
      EXPECT_NE(r.err.find("E_HELMERT_GROUP"), std::string::npos) << r.err;
      EXPECT_NE(r.err.find(piece), std::string::npos) << r.err;
      EXPECT_EQ(leftovers({"net.json", "two.json", "line.json"}), std::vector<std::string>{});
    }
  }
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const RunResult r = run("adjust '" + path("net.json").string() + "' -o '" + path("st.csv").string() + "' " + c.args);
    EXPECT_EQ(r.exit_code, c.exit_code) << r.err;
    for (const auto& piece : c.message) EXPECT_NE(r.err.find(piece), std::string::npos) << piece << " in: " << r.err;
    EXPECT_EQ(leftovers({"net.json", "two.json", "line.json"}), std::vector<std::string>{});
  }
}

}  // namespace
}  // namespace geoanchor
