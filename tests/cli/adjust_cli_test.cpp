// geoanchor adjust on the command line: every bad input of issue 14 is
// refused with a message naming the file, the element and the value, and
// leaves no output (stations CSV, sidecar, measurements, report, SINEX);
// the published samples run end to end with every output.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cli_support.hpp"

namespace geoanchor {
namespace {

using testing::CliTest;
using testing::RunResult;

class AdjustCli : public CliTest {};

// A small network on GRS80 around Zürich: A fixed, B and C reached by
// baselines (values consistent to the millimetre).
std::string network(const std::string& stations, const std::string& measurements) {
  return R"({"schema": "geoanchor.network/1", "frame": "ITRF2014@2024.5", "stations": [)" + stations +
         R"(], "measurements": [)" + measurements + "]}";
}
const std::string kA = R"({"id": "A", "lat_deg": 47.45, "lon_deg": 8.55, "h_m": 430.0, "constraint": "CCC"})";
const std::string kB = R"({"id": "B", "lat_deg": 47.46, "lon_deg": 8.56, "h_m": 440.0})";
const std::string kC = R"({"id": "C", "lat_deg": 47.455, "lon_deg": 8.57, "h_m": 435.0})";
std::string baseline(const std::string& from, const std::string& to, const std::string& cov = "[[1e-6,0,0],[0,1e-6,0],[0,0,1e-6]]",
                     const std::string& frame = "ITRF2014@2024.5") {
  // Values: exact differences are not needed for the refusals tested here.
  return R"({"kind": "gnss_baseline", "from": ")" + from + R"(", "to": ")" + to +
         R"(", "dx_m": 10.0, "dy_m": 20.0, "dz_m": 30.0, "cov_m2": )" + cov + R"(, "frame": ")" + frame + R"("})";
}

struct BadCase {
  std::string name;
  std::string json;
  std::string args;
  int exit_code;
  std::vector<std::string> message;
};

TEST_F(AdjustCli, Issue14_BadInputIsRefusedByNameWithNoOutput) {
  const std::vector<BadCase> cases = {
      {"undefined station", network(kA + "," + kB, baseline("A", "B") + "," + baseline("B", "Z")), "", 3,
       {"E_STATION_UNDEFINED", "net.json", "measurements[1]", "Z"}},
      {"duplicate station", network(kA + "," + kB + "," + R"({"id": "B", "lat_deg": 47.47, "lon_deg": 8.56, "h_m": 440.0})",
                                    baseline("A", "B")),
       "", 3, {"E_STATION_DUPLICATE", "stations[2]", "B"}},
      {"covariance not positive definite", network(kA + "," + kB, baseline("A", "B", "[[1e-6,2e-6,0],[2e-6,1e-6,0],[0,0,1e-6]]")), "",
       3, {"E_COVARIANCE", "measurements[0]", "smallest eigenvalue -"}},
      {"frame the catalog cannot reach", network(kA + "," + kB, baseline("A", "B", "[[1e-6,0,0],[0,1e-6,0],[0,0,1e-6]]", "MARS2000@2024.5")),
       "", 3, {"measurements[0]", "MARS2000"}},
      {"undefined datum", network(R"j({"id": "A", "lat_deg": 47.45, "lon_deg": 8.55, "h_m": 430.0})j" + std::string(",") + kB, baseline("A", "B")), "", 3,
       {"E_DATUM_DEFECT", "translation"}},
      {"disconnected network",
       network(kA + "," + kB + "," + kC + "," + R"({"id": "D", "lat_deg": 47.44, "lon_deg": 8.57, "h_m": 435.0, "constraint": "CCC"})",
               baseline("A", "B") + "," + baseline("C", "D")),
       "", 3, {"E_NETWORK_DISCONNECTED", "2 parts"}},
      {"global test failing high", network(kA + "," + kB + "," + kC, baseline("A", "B") + "," + baseline("B", "C") + "," + baseline("A", "C")),
       "--no-snooping", 4, {"E_ADJUST_GLOBAL_TEST", "variance factor"}},
      {"a dynamic frame without epoch", network(kA + "," + kB, baseline("A", "B")), "--frame ITRF2014 --sinex s.snx", 2,
       {"E_EPOCH_MISSING", "ITRF2014@"}},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    write("net.json", c.json);
    const RunResult r = run("adjust '" + path("net.json").string() + "' -o '" + path("st.csv").string() + "' --measurements '" +
                            path("m.csv").string() + "' --report '" + path("r.txt").string() + "' " + c.args);
    EXPECT_EQ(r.exit_code, c.exit_code) << r.err;
    for (const auto& piece : c.message) EXPECT_NE(r.err.find(piece), std::string::npos) << piece << " in: " << r.err;
    EXPECT_EQ(leftovers({"net.json"}), std::vector<std::string>{});
  }
}

TEST_F(AdjustCli, Issue14_PublishedSamplesWriteEveryOutput) {
  const std::string f = std::string(GEOANCHOR_FIXTURES_DIR) + "/networks/";
  const RunResult r = run("adjust '" + f + "dynadjust/gnss-networkstn.xml' '" + f + "dynadjust/gnss-networkmsr.xml' -o '" +
                          path("st.csv").string() + "' --measurements '" + path("m.csv").string() + "' --sinex '" +
                          path("s.snx").string() + "' --report '" + path("r.txt").string() + "' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(leftovers({}), (std::vector<std::string>{"m.csv", "r.txt", "s.snx", "st.csv", "st.csv.geoanchor.json"}));
  EXPECT_NE(r.out.find("\"variance_factor\""), std::string::npos);
  const RunResult g = run("adjust '" + f + "gama/tst-tetrahedron-1.gkf' -o '" + path("t.csv").string() + "' --no-snooping");
  EXPECT_EQ(g.exit_code, 4) << g.err;  // Gama's own result fails its global test (m0/σ = 5.97)
  EXPECT_NE(g.err.find("E_ADJUST_GLOBAL_TEST"), std::string::npos) << g.err;
}

}  // namespace
}  // namespace geoanchor
