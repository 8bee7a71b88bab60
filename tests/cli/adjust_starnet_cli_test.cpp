// geoanchor adjust with STAR*NET data files (issue 42 point 6): each bad
// input is refused naming the file, the line and the value, and leaves no
// output; a good file adjusts and writes every output.

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "cli_support.hpp"

namespace geoanchor {
namespace {

using testing::CliTest;
using testing::RunResult;

class AdjustStarnetCli : public CliTest {};

// A braced quadrilateral: A and B fixed, C and D from angles and distances.
const std::string kHeader = "# quadrilateral\n.2D\n.UNITS Meters DMS\n.ORDER NE AtFromTo\n";
const std::string kGood = kHeader +
                          "C A 1000 1000 ! !\nC B 1000 1100 ! !\nC C 899 1101\nC D 901 999\n"
                          "M A-B-C 45-00-00 141.4214 2 0.003\nM A-B-D 90-00-00 100.0000 2 0.003\n"
                          "M B-C-D 45-00-00 141.4214 2 0.003\nD C-D 100.0000 0.003\n";

TEST_F(AdjustStarnetCli, BadInputIsRefusedByNameWithNoOutput) {
  struct Case {
    std::string name, text;
    std::vector<std::string> message;
  };
  const std::vector<Case> cases = {
      {"a measurement without its standard error", kHeader + "C A 0 0 ! !\nD A-B 100\n", {"E_STARNET", "net.dat:6", "project options"}},
      {"a value before .UNITS", "# x\n.2D\n.ORDER NE\nC A 0 0 ! !\n", {"E_STARNET", "net.dat:4", "before any .UNITS"}},
      {"a refraction coefficient in a local network", kHeader + ".REFRACTION 0.07\n",
       {"E_STARNET", "net.dat:5", ".REFRACTION 0.07 in a local network"}},
      {"a GPS vector with no frame before it", kHeader + "G1 A-B 1 2 3\n", {"E_STARNET", "net.dat:5", "G1: a STAR*NET data file names no datum"}},
      {"an angle past the circle", kHeader + "C A 0 0 ! !\nA A-B-C 361-00-00 2\n", {"E_ANGLE", "net.dat:6", "361-00-00"}},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    write("net.dat", c.text);
    const RunResult r = run("adjust '" + path("net.dat").string() + "' -o '" + path("st.csv").string() + "' --measurements '" +
                            path("m.csv").string() + "' --report '" + path("r.txt").string() + "'");
    EXPECT_EQ(r.exit_code, 3) << r.err;
    for (const auto& piece : c.message) EXPECT_NE(r.err.find(piece), std::string::npos) << piece << " in: " << r.err;
    EXPECT_EQ(leftovers({"net.dat"}), std::vector<std::string>{});
  }
}

TEST_F(AdjustStarnetCli, AGoodFileAdjustsAndWritesEveryOutput) {
  write("net.dat", kGood);
  const RunResult r = run("adjust '" + path("net.dat").string() + "' -o '" + path("st.csv").string() + "' --measurements '" +
                          path("m.csv").string() + "' --report '" + path("r.txt").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(leftovers({"net.dat"}), (std::vector<std::string>{"m.csv", "r.txt", "st.csv", "st.csv.geoanchor.json"}));
  // C is 900 north, 1100 east: the angles (clockwise from the backsight,
  // STAR*NET's sense) and distances were computed from A, B fixed and C, D
  // south of them, and rounded to 0.1 mm (141.4214 for 100·√2 = 141.42136);
  // C and D start a metre off.
  constexpr double kRounding_m = 1e-3;
  const std::string st = testing::slurp(path("st.csv").string());
  const std::size_t row = st.find("\nC,");
  ASSERT_NE(row, std::string::npos) << st;
  char* end = nullptr;
  const double x = std::strtod(st.c_str() + row + 3, &end);
  const double y = std::strtod(end + 1, nullptr);
  EXPECT_NEAR(x, 900.0, kRounding_m) << st;
  EXPECT_NEAR(y, 1100.0, kRounding_m) << st;
}

// An ellipsoidal network: a network JSON anchor names the frame, the
// STAR*NET file adds geodetic positions, GPS vectors and a zenith angle
// under .REFRACTION 0.07.
const std::string kAnchor = R"({"schema": "geoanchor.network/1", "frame": "ITRF2014@2020.0", "stations": [
    {"id": "A", "lat_deg": 45, "lon_deg": -120, "h_m": 100, "constraint": "CCC"}], "measurements": []})";
// B 30″ north of A (926.1 m) and 3.5 m up: ΔX ΔY ΔZ from GRS80's closed form,
// rounded to 0.1 mm; the zenith angle from the normal at A, to the second.
const std::string kGeodetic = "# vectors\n.3D\n.UNITS Meters DMS\n.DELTA OFF\n.LONGITUDE NegativeWest\n.GPS WEIGHT StdErrCorr\n"
                              ".REFRACTION 0.07\nPH B 45-00-30 -120-00-00 103.5\n"
                              "G1 A-B 326.2171 565.0245 657.2887\nG2 0.002 0.002 0.003\nG3 0.1 0.2 0.3\nV A-B 89-47-15 5\n";

TEST_F(AdjustStarnetCli, ARefractionOptionThatDiffersFromTheFilesIsRefusedWithNoOutput) {
  write("anchor.json", kAnchor);
  write("net.dat", kGeodetic);
  const RunResult r = run("adjust '" + path("anchor.json").string() + "' '" + path("net.dat").string() + "' --refraction 0.13 -o '" +
                          path("st.csv").string() + "' --report '" + path("r.txt").string() + "'");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--refraction 0.13 differs from the 0.07 of " + path("net.dat").string() + ":7"), std::string::npos) << r.err;
  EXPECT_EQ(leftovers({"anchor.json", "net.dat"}), std::vector<std::string>{});
}

TEST_F(AdjustStarnetCli, GeodeticPositionsAndVectorsAdjustOnTheAnchorsFrame) {
  write("anchor.json", kAnchor);
  write("net.dat", kGeodetic);
  const RunResult r = run("adjust '" + path("anchor.json").string() + "' '" + path("net.dat").string() + "' -o '" +
                          path("st.csv").string() + "' --report '" + path("r.txt").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(leftovers({"anchor.json", "net.dat"}), (std::vector<std::string>{"r.txt", "st.csv", "st.csv.geoanchor.json"}));
  const std::string report = testing::slurp(path("r.txt").string());
  EXPECT_NE(report.find("coefficient of refraction 0.07 from " + path("net.dat").string() + ":7"), std::string::npos) << report;
}

}  // namespace
}  // namespace geoanchor
