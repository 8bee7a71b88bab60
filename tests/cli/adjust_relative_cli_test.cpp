// adjust --relative, --standard and --relative-output on the command line:
// the bundled airport network's every pair with the ALTA/NSPS 2021
// verdicts (each recomputed here from the CSV's 1σ ellipse and distance:
// 95 % ellipse = √(−2 ln 0.05) a, allowed 20 mm + 50 ppm, Section 3.E of
// the 2021 requirements), the JSON report's `relative` and `standard`; each
// bad pairs file, --relative and --standard refused by name, leaving no output.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "cli_support.hpp"

namespace geoanchor {
namespace {

using testing::CliTest;
using testing::RunResult;
using testing::slurp;

class AdjustRelativeCli : public CliTest {};

constexpr double kEllipse95 = 2.4477468306808166;  // √(−2 ln 0.05)
constexpr double kCsvRounding_m = 2e-6;            // the CSV's 6 decimals, twice
const std::string kNetwork = std::string(GEOANCHOR_FIXTURES_DIR) + "/airport_network/lszh_network.json";

TEST_F(AdjustRelativeCli, EveryPairOfTheAirportNetworkWithItsAltaNspsVerdict) {
  const RunResult r = run("adjust '" + kNetwork + "' -o '" + path("st.csv").string() + "' --relative all --standard alta-nsps-2021 " +
                          "--relative-output '" + path("rel.csv").string() + "' --report '" + path("r.txt").string() + "' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string text = slurp(path("rel.csv"));
  EXPECT_EQ(text.find("nan"), std::string::npos);
  EXPECT_EQ(text.find("inf"), std::string::npos);
  const testing::CsvTable t = testing::parse_csv_table(text);
  ASSERT_EQ(t.rows.size(), 55u);  // 11 stations: 11 · 10 / 2 pairs
  std::size_t pass = 0, fail = 0;
  for (const auto& row : t.rows) {
    const double a = std::stod(row[t.col("ellipse_a_m")]), d = std::stod(row[t.col("distance_m")]);
    const double achieved = kEllipse95 * a, allowed = 0.02 + 50e-6 * d;
    EXPECT_NEAR(std::stod(row[t.col("h_achieved_m")]), achieved, kCsvRounding_m);
    EXPECT_NEAR(std::stod(row[t.col("h_allowed_m")]), allowed, kCsvRounding_m);
    EXPECT_NEAR(std::stod(row[t.col("h_margin_mm")]), 1000.0 * (allowed - achieved), 1000.0 * kCsvRounding_m);
    const bool passes = row[t.col("h_verdict")] == "PASS";
    if (std::abs(allowed - achieved) > kCsvRounding_m) {
      EXPECT_EQ(passes, achieved <= allowed) << row[0] << "," << row[1];
    }
    (passes ? pass : fail) += 1;
  }
  const nlohmann::json j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["relative"].size(), 55u);
  EXPECT_EQ(j["relative_pairs"]["pairs"], "all");
  EXPECT_EQ(j["standard"]["name"], "alta-nsps-2021");
  EXPECT_EQ(j["standard"]["pass"].get<std::size_t>(), pass);
  EXPECT_EQ(j["standard"]["fail"].get<std::size_t>(), fail);
  EXPECT_EQ(j["standard"]["criteria"]["relative_horizontal"]["confidence"], 0.95);
  const std::string report = slurp(path("r.txt"));
  EXPECT_NE(report.find("Standard alta-nsps-2021"), std::string::npos) << report;
  EXPECT_NE(report.find(std::to_string(pass) + " PASS, " + std::to_string(fail) + " FAIL"), std::string::npos) << report;
}

TEST_F(AdjustRelativeCli, BadPairsRelativeAndStandardAreRefusedByNameWithNoOutput) {
  struct Case {
    std::string name, pairs, standard_file, args;
    int exit_code;
    std::vector<std::string> message;
  };
  const std::string bad_standard = R"({"schema": "geoanchor.accuracy-standard/1", "name": "x", "title": "t", "source": "s",
    "criteria": {"relative_horizontal": {"quantity": "relative_ellipse_semi_major", "definition": "d", "confidence": 0.95,
    "constant_m": 0.02, "ppm": 50, "distance": "spatial", "order": 3}}})";
  const std::vector<Case> cases = {
      {"unknown id", "from,to\nREFA,P01\nP02,P99\n", "", "--relative pairs:PAIRS", 3, {"E_PAIRS", "pairs.csv:3", "P99"}},
      {"missing header", "REFA,P01\nP02,P03\n", "", "--relative pairs:PAIRS", 3, {"E_PAIRS", "pairs.csv:1", "from,to"}},
      {"same station twice", "from,to\nP01,P01\n", "", "--relative pairs:PAIRS", 3, {"E_PAIRS", "pairs.csv:2", "P01", "itself"}},
      {"bad --relative", "", "", "--relative nearest", 2, {"E_OPTION", "--relative nearest", "radius:R_M"}},
      {"bad radius", "", "", "--relative radius:-5", 2, {"E_OPTION", "'-5'"}},
      {"unknown standard", "", "", "--standard alta-1999", 2, {"E_OPTION", "alta-1999", "alta-nsps-2021"}},
      {"malformed standard", "", bad_standard, "--standard STANDARD", 3,
       {"E_STANDARD", "std.json", "criteria.relative_horizontal.order", "3"}},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    std::vector<std::string> inputs;
    std::string args = c.args;
    if (!c.pairs.empty()) {
      write("pairs.csv", c.pairs);
      inputs.push_back("pairs.csv");
      args.replace(args.find("PAIRS"), 5, path("pairs.csv").string());
    }
    if (!c.standard_file.empty()) {
      write("std.json", c.standard_file);
      inputs.push_back("std.json");
      args.replace(args.find("STANDARD"), 8, path("std.json").string());
    }
    const RunResult r = run("adjust '" + kNetwork + "' -o '" + path("st.csv").string() + "' --relative-output '" +
                            path("rel.csv").string() + "' --report '" + path("r.txt").string() + "' " + args);
    EXPECT_EQ(r.exit_code, c.exit_code) << r.err;
    for (const auto& piece : c.message) EXPECT_NE(r.err.find(piece), std::string::npos) << piece << " in: " << r.err;
    EXPECT_EQ(leftovers(inputs), std::vector<std::string>{});
    for (const auto& f : inputs) std::filesystem::remove(path(f));
  }
}

}  // namespace
}  // namespace geoanchor
