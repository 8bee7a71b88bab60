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

}  // namespace
}  // namespace geoanchor
