// The adjust text report as a deliverable (issue 43 points 5 and 6): the
// adjusted coordinates listed (the same numbers as the stations CSV, to the
// report's digits), statistics rounded to their meaning, and a datum held
// by measured GNSS positions said so (it read "0 fixed, 0 held").

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <vector>
#include <regex>
#include <sstream>
#include <string>

#include "cli_support.hpp"

namespace geoanchor {
namespace {

using testing::CliTest;
using testing::RunResult;

class AdjustReportCli : public CliTest {};

const std::string kDir = std::string(GEOANCHOR_FIXTURES_DIR) + "/networks/dynadjust/";
constexpr double kReportLatLon_deg = 0.6e-9;  // printed with 9 decimals
constexpr double kReportHeight_m = 0.6e-4;    // printed with 4 decimals

TEST_F(AdjustReportCli, Issue43_TheReportListsTheAdjustedCoordinatesAndRoundsItsStatistics) {
  const RunResult r = run("adjust '" + kDir + "gnss-networkstn.xml' '" + kDir + "gnss-networkmsr.xml' -o '" + path("s.csv").string() +
                          "' --report '" + path("r.txt").string() + "' --accept-failed-global-test");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string report = testing::slurp(path("r.txt"));
  EXPECT_TRUE(std::regex_search(report, std::regex("vtpv = [0-9]+\\.[0-9]{3}, dof = 288"))) << report.substr(0, 1500);
  EXPECT_TRUE(std::regex_search(report, std::regex("\\(variance factor [0-9]\\.[0-9]{4}\\)"))) << report;
  EXPECT_NE(report.find("GNSS point cluster"), std::string::npos) << report.substr(0, 1500);
  const std::size_t listed = report.find("Adjusted coordinates (GDA2020@2020.0, ellipsoid GRS80");
  ASSERT_NE(listed, std::string::npos) << report;
  const std::string coordinates = report.substr(listed, report.find("\n\n", listed) - listed);
  // Every station of the CSV is in the report with the same latitude,
  // longitude and height.
  std::istringstream csv(testing::slurp(path("s.csv")));
  std::string line;
  std::size_t compared = 0;
  while (std::getline(csv, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("id,", 0) == 0) continue;
    std::istringstream f(line);
    std::string id, x, y, z, lat, lon, h;
    std::getline(f, id, ',');
    std::getline(f, x, ','), std::getline(f, y, ','), std::getline(f, z, ',');
    std::getline(f, lat, ','), std::getline(f, lon, ','), std::getline(f, h, ',');
    std::smatch m;
    const std::regex row("\\n  " + id + " +(-?[0-9.]+) +(-?[0-9.]+) +(-?[0-9.]+) ");
    ASSERT_TRUE(std::regex_search(coordinates, m, row)) << id;
    EXPECT_NEAR(std::stod(m[1]), std::stod(lat), kReportLatLon_deg) << id;
    EXPECT_NEAR(std::stod(m[2]), std::stod(lon), kReportLatLon_deg) << id;
    EXPECT_NEAR(std::stod(m[3]), std::stod(h), kReportHeight_m) << id;
    ++compared;
  }
  EXPECT_EQ(compared, 43u);
}

// The airport network's slope distances under an error model (EDM: 1 mm
// + 2 ppm, centring 1 mm at each end), then variance components by model.
std::string with_error_model(std::string json) {
  const std::string schema = "\"schema\": \"geoanchor.network/1\",";
  json.replace(json.find(schema), schema.size(),
               schema + " \"error_models\": {\"EDM\": {\"distance_constant_mm\": 1, \"distance_ppm\": 2, "
                        "\"instrument_centring_mm\": 1, \"target_centring_mm\": 1}},");
  const std::string slope = "\"kind\": \"slope_distance\",";
  for (std::size_t at = json.find(slope); at != std::string::npos; at = json.find(slope, at + 1)) {
    json.insert(at + slope.size(), " \"error_model\": \"EDM\",");
  }
  return json;
}

TEST_F(AdjustReportCli, Issue43_ErrorModelsWidenTheirMeasurementsAndVceReportsEachGroup) {
  const std::string airport = std::string(GEOANCHOR_FIXTURES_DIR) + "/airport_network/lszh_network.json";
  write("net.json", with_error_model(testing::slurp(airport)));
  const RunResult plain = run("adjust '" + airport + "' -o '" + path("a.csv").string() + "' --measurements '" +
                              path("am.csv").string() + "' --report '" + path("a.txt").string() + "'");
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  const RunResult modelled = run("adjust '" + path("net.json").string() + "' -o '" + path("b.csv").string() + "' --measurements '" +
                                 path("bm.csv").string() + "' --report '" + path("b.txt").string() + "'");
  ASSERT_EQ(modelled.exit_code, 0) << modelled.err;
  EXPECT_NE(testing::slurp(path("b.txt")).find("error models EDM added to the covariances of 24 measurement(s)"), std::string::npos);
  // Each slope distance's σ (column 9) grew by the model: √(σ² + 1 mm² +
  // (2 ppm·D)² + centring) > σ; the zenith angles' stayed.
  const auto sigmas = [&](const std::string& file, const std::string& kind) {
    std::vector<double> out;
    std::istringstream in(testing::slurp(path(file)));
    std::string line;
    while (std::getline(in, line)) {
      std::vector<std::string> f;
      std::istringstream row(line);
      for (std::string x; std::getline(row, x, ',');) f.push_back(x);
      if (f.size() > 8 && f[1] == kind) out.push_back(std::stod(f[8]));
    }
    return out;
  };
  const auto before = sigmas("am.csv", "slope_distance"), after = sigmas("bm.csv", "slope_distance");
  ASSERT_EQ(before.size(), 24u);
  ASSERT_EQ(after.size(), 24u);
  for (std::size_t k = 0; k < before.size(); ++k) EXPECT_GT(after[k], std::hypot(before[k], 0.001) - 1e-12) << k;
  EXPECT_EQ(sigmas("am.csv", "zenith_angle"), sigmas("bm.csv", "zenith_angle"));
  const RunResult vce = run("adjust '" + path("net.json").string() + "' -o '" + path("c.csv").string() + "' --vce model --json");
  ASSERT_EQ(vce.exit_code, 0) << vce.err;
  EXPECT_NE(vce.out.find("\"variance_components\""), std::string::npos) << vce.out.substr(0, 2000);
  EXPECT_NE(vce.out.find("\"group\": \"EDM\""), std::string::npos);
  EXPECT_NE(vce.out.find("\"group\": \"(no error model)\""), std::string::npos);
  const RunResult bad = run("adjust '" + path("net.json").string() + "' -o '" + path("d.csv").string() + "' --vce instrument");
  EXPECT_EQ(bad.exit_code, 2) << bad.err;
  EXPECT_NE(bad.err.find("--vce instrument: expected kind, group or model"), std::string::npos) << bad.err;
  EXPECT_FALSE(std::filesystem::exists(path("d.csv")));
  const RunResult planned = run("adjust '" + path("net.json").string() + "' -o '" + path("e.csv").string() + "' --vce kind --preanalysis");
  EXPECT_EQ(planned.exit_code, 2) << planned.err;
  EXPECT_NE(planned.err.find("--vce with --preanalysis"), std::string::npos) << planned.err;
  EXPECT_FALSE(std::filesystem::exists(path("e.csv")));
}

}  // namespace
}  // namespace geoanchor
