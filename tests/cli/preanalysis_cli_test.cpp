// geoanchor adjust --preanalysis on the command line: a generated network
// whose measured values are taken out (null in the network JSON) runs end
// to end with every output, none holding NaN or inf; candidates are ranked
// into their CSV; bad inputs are refused by name with no output.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cctype>
#include <filesystem>
#include <string>
#include <vector>

#include "cli_support.hpp"

namespace geoanchor {
namespace {

using testing::CliTest;
using testing::RunResult;

class PreanalysisCli : public CliTest {
 protected:
  // A generated network with every baseline's value null (planned).
  void planned_network(int stations) {
    ASSERT_EQ(run("adjust --generate " + std::to_string(stations) + " --out-dir '" + path("").string() + "' --seed 4 --blunders 0").exit_code, 0);
    auto doc = nlohmann::json::parse(testing::slurp(path("network.json")));
    for (auto& m : doc.at("measurements")) {
      if (m.contains("dx_m")) m["dx_m"] = nullptr, m["dy_m"] = nullptr, m["dz_m"] = nullptr;
      if (m.contains("baselines")) {
        for (auto& b : m.at("baselines")) b["dx_m"] = nullptr, b["dy_m"] = nullptr, b["dz_m"] = nullptr;
      }
    }
    write("planned.json", doc.dump(1));
  }
  std::string outputs() const {
    return " -o '" + path("st.csv").string() + "' --measurements '" + path("m.csv").string() + "' --report '" + path("r.txt").string() + "'";
  }
  bool any_output() const {
    for (const char* f : {"st.csv", "st.csv.geoanchor.json", "m.csv", "r.txt", "cand.csv"}) {
      if (std::filesystem::exists(path(f))) return true;
    }
    return false;
  }
};

// A value written as NaN or infinity: a field (CSV), a JSON value or a
// word of the report that is nan, inf or infinity, any case and sign (the
// paths inside the outputs may hold those letters).
bool has_nan_or_inf(const std::string& text) {
  const std::string separators = ",:[]{} \t\n\"";
  std::size_t begin = 0;
  while (begin <= text.size()) {
    std::size_t end = text.find_first_of(separators, begin);
    if (end == std::string::npos) end = text.size();
    std::string token = text.substr(begin, end - begin);
    if (!token.empty() && (token[0] == '-' || token[0] == '+')) token.erase(0, 1);
    for (auto& c : token) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (token == "nan" || token == "inf" || token == "infinity") return true;
    begin = end + 1;
  }
  return false;
}

TEST_F(PreanalysisCli, APlannedNetworkGivesEveryOutputWithNumbersOnly) {
  planned_network(30);
  const RunResult r = run("adjust '" + path("planned.json").string() + "' --preanalysis" + outputs() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string report = testing::slurp(path("r.txt"));
  EXPECT_NE(report.find("PRE-ANALYSIS"), std::string::npos) << report;
  EXPECT_NE(report.find("External reliability"), std::string::npos) << report;
  EXPECT_EQ(report.find("global test (chi-squared"), std::string::npos) << report;
  for (const char* f : {"st.csv", "m.csv", "r.txt", "st.csv.geoanchor.json"}) EXPECT_FALSE(has_nan_or_inf(testing::slurp(path(f)))) << f;
  EXPECT_FALSE(has_nan_or_inf(r.out));
  const auto json = nlohmann::json::parse(r.out);
  EXPECT_TRUE(json.at("preanalysis").get<bool>());
  EXPECT_TRUE(json.at("sigma0").is_null());
  // The measurements CSV: observed, adjusted, residual and w empty; sigma,
  // redundancy, MDB and the external reliability given.
  const auto t = testing::parse_csv_table(testing::slurp(path("m.csv")));
  auto col = [&](const std::string& name) {
    const auto at = std::find(t.header.begin(), t.header.end(), name);
    return static_cast<std::size_t>(at - t.header.begin());
  };
  ASSERT_FALSE(t.rows.empty());
  for (const auto& row : t.rows) {
    EXPECT_EQ(row[col("observed")], "");
    EXPECT_EQ(row[col("adjusted")], "");
    EXPECT_EQ(row[col("residual")], "");
    EXPECT_EQ(row[col("w")], "");
    EXPECT_NE(row[col("redundancy")], "");
    EXPECT_NE(row[col("external_m")], "");
  }
}

TEST_F(PreanalysisCli, CandidatesAreRankedIntoTheirCsv) {
  planned_network(30);
  // Three candidate baselines between stations of the design (values null).
  auto doc = nlohmann::json::parse(testing::slurp(path("planned.json")));
  std::vector<std::string> ids;
  for (const auto& s : doc.at("stations")) ids.push_back(s.at("id").get<std::string>());
  nlohmann::json candidates = {{"schema", "geoanchor.network/1"}, {"stations", nlohmann::json::array()}};
  if (doc.contains("frame")) candidates["frame"] = doc.at("frame");
  nlohmann::json ms = nlohmann::json::array();
  for (auto [a, b] : std::vector<std::pair<int, int>>{{1, 17}, {5, 29}, {10, 11}}) {
    ms.push_back({{"kind", "gnss_baseline"}, {"from", ids[static_cast<std::size_t>(a)]}, {"to", ids[static_cast<std::size_t>(b)]},
                  {"dx_m", nullptr}, {"dy_m", nullptr}, {"dz_m", nullptr}, {"sigma_m", 0.003}});
  }
  candidates["measurements"] = ms;
  write("cand.json", candidates.dump(1));
  const RunResult r = run("adjust '" + path("planned.json").string() + "' --preanalysis --candidates '" + path("cand.json").string() +
                          "' --candidates-output '" + path("cand.csv").string() + "'" + outputs());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string csv = testing::slurp(path("cand.csv"));
  EXPECT_EQ(csv.substr(0, csv.find('\n')), "rank,source,kind,stations,measurements,criterion,worst_m,worst_station,improvement_m");
  const auto t = testing::parse_csv_table(csv);
  ASSERT_EQ(t.rows.size(), 3u);
  EXPECT_EQ(t.rows[0][0], "1");
  EXPECT_EQ(t.rows[0][5], "semi_major_95");
  EXPECT_LE(std::stod(t.rows[0][6]), std::stod(t.rows[2][6]));
  EXPECT_FALSE(has_nan_or_inf(csv));
  EXPECT_NE(testing::slurp(path("r.txt")).find("Candidates ranked"), std::string::npos);
}

TEST_F(PreanalysisCli, BadInputIsRefusedByNameWithNoOutput) {
  planned_network(10);
  // An adjustment of planned measurements.
  RunResult r = run("adjust '" + path("planned.json").string() + "'" + outputs());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("E_VALUE_MISSING"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("measurements[0]"), std::string::npos) << r.err;
  EXPECT_FALSE(any_output());
  // --candidates without --preanalysis.
  write("cand.json", testing::slurp(path("planned.json")));
  r = run("adjust '" + path("planned.json").string() + "' --candidates '" + path("cand.json").string() + "'" + outputs());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--candidates: only with --preanalysis"), std::string::npos) << r.err;
  EXPECT_FALSE(any_output());
  // A candidate naming a station no input defines.
  const std::string unknown = R"({"schema": "geoanchor.network/1", "stations": [], "measurements": [{"kind": "slope_distance", )"
                              R"("from": "NOWHERE", "to": "S1", "value_m": null, "sigma_m": 0.002}]})";
  write("cand.json", unknown);
  r = run("adjust '" + path("planned.json").string() + "' --preanalysis --candidates '" + path("cand.json").string() + "'" + outputs());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("NOWHERE"), std::string::npos) << r.err;
  EXPECT_FALSE(any_output());
  // A station without a-priori coordinates (GNU Gama: a point given
  // without them).
  write("local.xml",
        "<?xml version=\"1.0\" ?>\n<gama-local xmlns=\"http://www.gnu.org/software/gama/gama-local\">\n"
        "<network axes-xy=\"ne\" angles=\"left-handed\">\n<points-observations>\n"
        "<point id=\"1\" x=\"0\" y=\"0\" fix=\"xy\"/>\n<point id=\"2\" x=\"100\" y=\"0\" fix=\"xy\"/>\n<point id=\"3\" adj=\"xy\"/>\n"
        "<obs from=\"1\">\n  <distance to=\"3\" val=\"100\" stdev=\"2\"/>\n  <distance to=\"2\" val=\"100\" stdev=\"2\"/>\n</obs>\n"
        "<obs from=\"2\">\n  <distance to=\"3\" val=\"141.42\" stdev=\"2\"/>\n</obs>\n"
        "</points-observations>\n</network>\n</gama-local>\n");
  r = run("adjust '" + path("local.xml").string() + "' --preanalysis" + outputs());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("E_PREANALYSIS_POSITION"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("station 3 "), std::string::npos) << r.err;
  EXPECT_FALSE(any_output());
}

}  // namespace
}  // namespace geoanchor
