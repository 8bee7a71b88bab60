// --geoid files read by their content (issue 42 point 2): DynAdjust's
// NTv2 geoid grid and its per-station .geo file for adjust, the .geo file
// refused where a grid is needed, and a file no reader takes named with
// what it is and what is read, leaving no output.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cli_support.hpp"

namespace geoanchor {
namespace {

using testing::CliTest;
using testing::RunResult;

class GeoidFilesCli : public CliTest {};

const std::string kDir = std::string(GEOANCHOR_FIXTURES_DIR) + "/networks/dynadjust/";

TEST_F(GeoidFilesCli, Issue42_AdjustReadsTheNtv2GridAndThePerStationFile) {
  for (const std::string geoid : {"urban-network-geoid.gsb", "urban-network.geo"}) {
    SCOPED_TRACE(geoid);
    const RunResult r = run("adjust '" + kDir + "urban-network.stn' '" + kDir + "urban-network.msr' --geoid '" + kDir + geoid +
                            "' -o '" + path("u.csv").string() + "' --report '" + path("u.txt").string() + "' --overwrite");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const std::string report = testing::slurp(path("u.txt").string());
    EXPECT_NE(report.find("dof = 742"), std::string::npos) << report.substr(0, 600);  // DynAdjust's published dof
  }
}

TEST_F(GeoidFilesCli, Issue42_FilesNoReaderTakesAreNamedAndLeaveNoOutput) {
  write("pts.csv", "# frame = GDA2020\nid,lat_deg,lon_deg,H_m\nP,-37.8,144.96,30\n");
  write("not-a-grid.gtx", "this is text, not a grid\n");
  struct Case {
    std::string command;
    std::vector<std::string> message;
  };
  const std::vector<Case> cases = {
      {"convert '" + path("pts.csv").string() + "' --to ecef -o '" + path("out.csv").string() + "' --geoid '" + kDir + "urban-network.geo'",
       {"E_OPTION", "urban-network.geo", "per-station geoid file", "serves `adjust` only"}},
      {"adjust '" + kDir + "urban-network.stn' '" + kDir + "urban-network.msr' -o '" + path("out.csv").string() + "' --geoid '" +
           path("not-a-grid.gtx").string() + "'",
       {"E_GEOID", "not-a-grid.gtx", "25 bytes", "PROJ cannot read as a vertical grid", "NTv2 geoid grid"}},
      {"adjust '" + kDir + "urban-network.stn' '" + kDir + "urban-network.msr' -o '" + path("out.csv").string() +
           "' --geoid /usr/share/proj/CHENYX06.gsb",
       {"E_GEOID", "CHENYX06.gsb", "horizontal shift grid", "SYSTEM_T"}},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.command);
    const RunResult r = run(c.command);
    EXPECT_NE(r.exit_code, 0);
    for (const auto& piece : c.message) EXPECT_NE(r.err.find(piece), std::string::npos) << piece << " in: " << r.err;
    EXPECT_EQ(leftovers({"pts.csv", "not-a-grid.gtx"}), std::vector<std::string>{});
  }
}


TEST_F(GeoidFilesCli, Issue42_AstronomicMeasurementsWithoutADeflectionAreSaidOnce) {
  // Ellipsoidal heights (LLh): no geoid needed but for the deflection.
  write("k.stn", "!#=DNA 3.01 STN    12.12.2018         GDA94    01.01.1994         3\n"
                 "1013                CCF LLh      -37.4801664550      144.5728376570             41.5521\n"
                 "1014                CCC LLh      -37.4801444060      144.5729820340             42.7148\n"
                 "1017                CCC LLh      -37.4801686470      144.5727483410             40.8815\n");
  write("k.msr", "!#=DNA 3.01 MSR    12.12.2018         GDA94    01.01.1994         3\n"
                 "V 1013                1014                                                   90 24 31.0000   20.000  1.545  0.125\n"
                 "V 1013                1017                                                   91 47 53.0000   20.000  1.545  1.530\n"
                 "K 1013                1017                                                  268 17 00.0000   20.000\n");
  const RunResult r = run("adjust '" + path("k.stn").string() + "' '" + path("k.msr").string() + "' -o '" + path("k.csv").string() +
                          "' --report '" + path("k.txt").string() + "' --accept-failed-global-test");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("1 astronomic measurement(s) (azimuth, latitude, longitude) at stations without a deflection of the vertical: "
                       "adjusted with it zero"),
            std::string::npos)
      << r.err;
  const RunResult g = run("adjust '" + path("k.stn").string() + "' '" + path("k.msr").string() + "' -o '" + path("k.csv").string() +
                          "' --geoid '" + kDir + "urban-network.geo' --overwrite --accept-failed-global-test");
  EXPECT_EQ(g.exit_code, 0) << g.err;
  EXPECT_EQ(g.err.find("astronomic measurement(s)"), std::string::npos) << g.err;  // the .geo file gives 1013's
}

}  // namespace
}  // namespace geoanchor
