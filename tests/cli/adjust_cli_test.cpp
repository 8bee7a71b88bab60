// geoanchor adjust on the command line: every bad input of issue 14 is
// refused with a message naming the file, the element and the value, and
// leaves no output (stations CSV, sidecar, measurements, report, SINEX);
// the published samples run end to end with every output.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <GeographicLib/Geocentric.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "cli_support.hpp"

namespace geoanchor {
namespace {

using testing::CliTest;
using testing::RunResult;
using testing::slurp;

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

// The readers' own refusals (a review's hostile inputs): a value that would
// otherwise be read as another number, or dropped, is refused by name.
TEST_F(AdjustCli, Issue14_FormatFaultsAreRefusedByNameWithNoOutput) {
  const std::string f = std::string(GEOANCHOR_FIXTURES_DIR) + "/networks/";
  const std::string stn = testing::slurp(f + "dynadjust/gnss-networkstn.xml");
  const std::string gama = testing::slurp(f + "gama/stroner-levelling-a.gkf");
  const std::string snx =
      "%=SNX 2.02 XXX 24:001:00000 XXX 24:001:00000 24:001:00000 P 00003 2 S\n"
      "+SOLUTION/ESTIMATE\n"
      " 1 STAX   ALIC  A    1 17:298:43200 m    1 -.405205265910111E+07 0.26585E-03\n"
      " 2 STAY   ALIC  A    1 17:298:43200 m    1 0.421283600689116E+07 0.27387E-03\n"
      " 3 STAZ   ALIC  A    1 17:298:43200 m    1 -.254510472135050E+07 0.19389E-03\n"
      "-SOLUTION/ESTIMATE\n"
      "+SOLUTION/MATRIX_ESTIMATE L COVA\n"
      "     1     1 0.706765843212940E-07\n"
      "     2     1 -.524564523670720E-07 0.750034116863820E-07\n"
      "     3     1 0.303119344103590E-07 -.321717649662960E-07 0.375942687123970E-07\n"
      "-SOLUTION/MATRIX_ESTIMATE L COVA\n%ENDSNX\n";
  auto replace = [](std::string text, const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
    return text;
  };
  // The SINEX above with its INDEX columns right-aligned as the format has them.
  std::string good_snx = snx;
  for (const char* i : {"1", "2", "3"}) good_snx = replace(good_snx, std::string("\n ") + i + " STA", std::string("\n     ") + i + " STA");
  struct Case {
    std::string name, file, text, args;
    int exit_code;
    std::vector<std::string> message;
  };
  const std::vector<Case> cases = {
      {"DynaML: a misspelt element", "stn.xml", replace(stn, "<Constraints>FFF</Constraints>", "<Constraint>CCC</Constraint>"), "", 3,
       {"E_DYNAML", "stn.xml:", "<Constraint>", "not read"}},
      {"DynaML: an unknown root attribute", "stn.xml", replace(stn, "epoch=\"01.01.2020\"", "epoch=\"01.01.2020\" referenceFrame=\"ITRF2014\""),
       "", 3, {"E_DYNAML", "referenceFrame"}},
      {"DynaML: a value given twice", "stn.xml", replace(stn, "<Height>172.1735</Height>", "<Height>172.1735</Height><Height>1.0</Height>"),
       "", 3, {"E_DYNAML", "<Height> given twice"}},
      {"DynaML: a latitude past 90", "stn.xml", replace(stn, "<XAxis>-36.3348253511</XAxis>", "<XAxis>-91.3348253511</XAxis>"), "", 3,
       {"E_DYNAML", "latitude", "-91.3348253511"}},
      {"Gama: a point given twice with other coordinates", "g.gkf",
       replace(gama, "<point id=\"11\" adj=\"Z\"/>", "<point id=\"11\" adj=\"Z\"/><point id=\"51\" z=\"240\"/>"), "", 3,
       {"E_GAMA", "point 51", "240"}},
      {"Gama: a negative default standard deviation", "g.gkf",
       replace(gama, "<points-observations>", "<points-observations direction-stdev=\"-5\">"), "", 3, {"E_GAMA", "direction-stdev", "-5"}},
      {"Gama: every line of a bench mark misses (wrong approximate height)", "g.gkf",
       replace(gama, "<point id=\"11\" adj=\"Z\"/>", "<point id=\"11\" z=\"200\" adj=\"Z\"/>"), "", 3,
       {"E_GROSS_MISCLOSURE", "station 11"}},
      {"Gama: a zenith angle past the nadir", "t.gkf",
       replace(testing::slurp(f + "gama/tst-tetrahedron-1.gkf"), "val=\" 39.181085\"", "val=\"239.181085\""), "", 3,
       {"E_ANGLE", "t.gkf:", "<z-angle> val=239.181085", "[0, 200] gon"}},
      {"Gama: a correlated set whose covariance is not positive definite (a correlation past 1)", "j.gkf",
       replace(testing::slurp(f + "gama/jezerka-ang.gkf"), "19.22 -9.61   19.22 -9.61   19.22 -9.61   19.22 -9.61   19.22",
               "19.22 -29.61   19.22 -9.61   19.22 -9.61   19.22 -9.61   19.22"),
       "", 3, {"E_COVARIANCE", "j.gkf:28 <obs>: observation set: the covariance is not positive definite", "smallest eigenvalue -"}},
      {"Gama: a correlated set's cov-mat one value short", "j.gkf",
       replace(testing::slurp(f + "gama/jezerka-ang.gkf"), "19.22 -9.61   19.22 -9.61   19.22 -9.61   19.22 -9.61   19.22",
               "19.22 -9.61   19.22 -9.61   19.22 -9.61   19.22 -9.61"),
       "", 3, {"E_GAMA", "j.gkf:40: <cov-mat dim=\"5\" band=\"1\"> holds 8 values; expected 9 (the upper band by rows)"}},
      {"SINEX: a value shifted into the next column", "s.snx",
       replace(good_snx, "m    1 -.405205265910111E+07", "m    1  -.405205265910111E+07"), "--sinex-frame ITRF2005", 3,
       {"E_SINEX", "s.snx:3", "column 69"}},
      {"SINEX: a covariance labelled as correlations", "s.snx", replace(replace(good_snx, "L COVA\n     1", "L CORR\n     1"), "-SOLUTION/MATRIX_ESTIMATE L COVA", "-SOLUTION/MATRIX_ESTIMATE L CORR"),
       "--sinex-frame ITRF2005", 3, {"E_SINEX", "STD_DEV", "CORR"}},
      {"SINEX: a matrix element given twice", "s.snx", replace(good_snx, "-SOLUTION/MATRIX_ESTIMATE L COVA\n%", "     1     1 0.1E-06\n-SOLUTION/MATRIX_ESTIMATE L COVA\n%"),
       "--sinex-frame ITRF2005", 3, {"E_SINEX", "(1, 1) given twice"}},
      {"SINEX: a frame the catalog does not know", "s.snx", good_snx, "--sinex-frame ITRF1066", 2, {"--sinex-frame", "ITRF1066"}},
      {"JSON: local axes with a blank ('e ' is no pair of directions)", "l.json",
       R"({"schema": "geoanchor.network/1", "space": "local", "local": {"axes": "e ", "angles": "clockwise", "dimensions": 2},
           "stations": [{"id": "A", "x_m": 0, "y_m": 0, "constraint": "CCC"}, {"id": "B", "x_m": 100, "y_m": 0}],
           "measurements": [{"kind": "horizontal_distance", "from": "A", "to": "B", "value_m": 100.0, "sigma_m": 0.001}]})",
       "", 3, {"local.axes", "'e '", "expected one of ne en"}},
      {"two outputs on one file", "s.snx", good_snx, "--sinex-frame ITRF2005 --sinex '" + path("m.csv").string() + "'", 2,
       {"--measurements", "--sinex", "same file"}},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    write(c.file, c.text);
    const RunResult r = run("adjust '" + path(c.file).string() + "' -o '" + path("st.csv").string() + "' --measurements '" +
                            path("m.csv").string() + "' --report '" + path("r.txt").string() + "' " + c.args);
    EXPECT_EQ(r.exit_code, c.exit_code) << r.err;
    for (const auto& piece : c.message) EXPECT_NE(r.err.find(piece), std::string::npos) << piece << " in: " << r.err;
    EXPECT_EQ(leftovers({c.file}), std::vector<std::string>{});
    std::filesystem::remove(path(c.file));
  }
  // The well-formed SINEX is read (the cases above refuse only their fault).
  write("s.snx", good_snx);
  const RunResult ok = run("adjust '" + path("s.snx").string() + "' --sinex-frame ITRF2005 -o '" + path("st.csv").string() + "'");
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
}

// GNU Gama's correlated angles (jezerka-ang.gkf: one observation set of
// angles per station): the measurements CSV has a row per observation, its
// own source, kind and stations, and the set named in `set`; the JSON
// report lists each set's observations with their units.
TEST_F(AdjustCli, Issue42_AnObservationSetHasARowPerObservationWithItsSetNamed) {
  const std::string file = std::string(GEOANCHOR_FIXTURES_DIR) + "/networks/gama/jezerka-ang.gkf";
  const RunResult r = run("adjust '" + file + "' -o '" + path("st.csv").string() + "' --measurements '" + path("m.csv").string() +
                          "' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string csv = slurp(path("m.csv"));
  std::vector<std::string> rows;
  for (std::size_t at = 0, end; (end = csv.find('\n', at)) != std::string::npos; at = end + 1) rows.push_back(csv.substr(at, end - at));
  ASSERT_EQ(rows.size(), 1u + 55u);  // 34 angles, 21 distances
  EXPECT_EQ(rows[0].substr(rows[0].rfind(',')), ",metadata");  // set, then metadata (NGS GVX's), last
  std::size_t angles = 0, in_sets = 0;
  for (const auto& row : rows) {
    if (row.find(",horizontal_angle,") != std::string::npos) {
      ++angles;
      EXPECT_NE(row.find(" <angle>,horizontal_angle,"), std::string::npos) << row;
      EXPECT_NE(row.find(" <obs>"), std::string::npos) << row;  // the set, last
      const std::string head = row.substr(0, row.rfind(','));  // less metadata (empty here)
      in_sets += head.substr(head.rfind(',')).find(" <obs>") != std::string::npos ? 1u : 0u;
    }
    if (row.find(",horizontal_distance,") != std::string::npos) {
      EXPECT_EQ(row.substr(row.size() - 2), ",,") << row;  // no set, no metadata
    }
  }
  EXPECT_EQ(angles, 34u);
  EXPECT_EQ(in_sets, 34u);
  // The first set: the angles at 51, lines 35–39, the set at line 28.
  EXPECT_NE(csv.find("jezerka-ang.gkf:35 <angle>,horizontal_angle,51 54 55,"), std::string::npos);
  EXPECT_NE(csv.find("jezerka-ang.gkf:28 <obs>,\n"), std::string::npos);
  const auto report = nlohmann::json::parse(r.out);
  std::size_t sets = 0;
  for (const auto& m : report.at("measurements")) {
    if (m.at("kind") != "observation_set") continue;
    ++sets;
    EXPECT_FALSE(m.contains("unit"));
    ASSERT_EQ(m.at("parts").size(), m.at("observed").size());
    for (const auto& part : m.at("parts")) {
      EXPECT_EQ(part.at("kind"), "horizontal_angle");
      EXPECT_EQ(part.at("unit"), "rad");
    }
  }
  EXPECT_EQ(sets, 8u);
}

// Motions that move no station are no datum: one held station and a
// baseline to a second (the rotation about the line through both moves
// nothing), and a SINEX solution of one station.
TEST_F(AdjustCli, Issue14_TwoStationsAndOneStationNetworksHaveTheirDatum) {
  write("two.json", network(kA + "," + kB, baseline("A", "B")));
  const RunResult r = run("adjust '" + path("two.json").string() + "' -o '" + path("two.csv").string() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("E_DATUM_DEFECT"), std::string::npos) << r.err;
  write("free.json", network(R"j({"id": "A", "lat_deg": 47.45, "lon_deg": 8.55, "h_m": 430.0})j" + std::string(",") + kB, baseline("A", "B")));
  const RunResult f = run("adjust '" + path("free.json").string() + "' -o '" + path("free.csv").string() + "'");
  EXPECT_EQ(f.exit_code, 3) << f.err;  // the translations are undefined, and named alone
  EXPECT_NE(f.err.find("translation"), std::string::npos) << f.err;
  EXPECT_EQ(f.err.find("rotation"), std::string::npos) << f.err;
}

TEST_F(AdjustCli, Issue14_PublishedSamplesWriteEveryOutput) {
  const std::string f = std::string(GEOANCHOR_FIXTURES_DIR) + "/networks/";
  const RunResult r = run("adjust '" + f + "dynadjust/gnss-networkstn.xml' '" + f + "dynadjust/gnss-networkmsr.xml' -o '" +
                          path("st.csv").string() + "' --measurements '" + path("m.csv").string() + "' --sinex '" +
                          path("s.snx").string() + "' --report '" + path("r.txt").string() + "' --json --accept-failed-global-test");
  ASSERT_EQ(r.exit_code, 0) << r.err;  // (as given, its global test fails high by a hair: 337.28 > 336.90)
  EXPECT_EQ(leftovers({}), (std::vector<std::string>{"m.csv", "r.txt", "s.snx", "st.csv", "st.csv.geoanchor.json"}));
  EXPECT_NE(r.out.find("\"variance_factor\""), std::string::npos);
  const RunResult g = run("adjust '" + f + "gama/tst-tetrahedron-1.gkf' -o '" + path("t.csv").string() + "' --no-snooping");
  EXPECT_EQ(g.exit_code, 4) << g.err;  // Gama's own result fails its global test (m0/σ = 5.97)
  EXPECT_NE(g.err.find("E_ADJUST_GLOBAL_TEST"), std::string::npos) << g.err;
}

// RELIABILITY 41: adjust's outputs (stations CSV and sidecar, SINEX,
// measurements, report) are one group: all are written before any is
// published, so a write that fails leaves none of them, and the rerun
// writes them all. The file-size limit (ulimit -f, 512-byte blocks) is set
// below the largest output's size from a run without it, so one write
// fails with EFBIG as on a full disk.
TEST_F(AdjustCli, Reliability41_AFailedWriteLeavesNoneOfTheOutputsAndARerunWritesThemAll) {
  const std::string network = std::string(GEOANCHOR_FIXTURES_DIR) + "/airport_network/lszh_network.json";
  const auto args = [&](const std::filesystem::path& dir) {
    return "adjust '" + network + "' -o '" + (dir / "st.csv").string() + "' --measurements '" + (dir / "m.csv").string() +
           "' --sinex '" + (dir / "s.snx").string() + "' --report '" + (dir / "r.txt").string() + "'";
  };
  const std::vector<std::string> all{"m.csv", "r.txt", "s.snx", "st.csv", "st.csv.geoanchor.json"};
  const auto whole = path("whole");
  std::filesystem::create_directories(whole);
  ASSERT_EQ(run(args(whole)).exit_code, 0);
  ASSERT_EQ(files(whole), all);
  std::uintmax_t smallest = UINTMAX_MAX, largest = 0;
  for (const auto& f : all) {
    smallest = std::min(smallest, std::filesystem::file_size(whole / f));
    largest = std::max(largest, std::filesystem::file_size(whole / f));
  }
  const std::uintmax_t blocks = (largest - 1) / 512;
  ASSERT_GE(blocks * 512, smallest) << "the limit must let some output through for the group to matter";

  const auto cut = path("cut");
  std::filesystem::create_directories(cut);
  const RunResult failed = shell("trap '' XFSZ; ulimit -f " + std::to_string(blocks) + "; exec " + exe() + " " + args(cut));
  EXPECT_EQ(failed.exit_code, 5) << failed.err;
  EXPECT_NE(failed.err.find("error[E_WRITE]: "), std::string::npos) << failed.err;
  EXPECT_NE(failed.err.find("(File too large); none of "), std::string::npos) << failed.err;
  EXPECT_EQ(files(cut), std::vector<std::string>{}) << "left behind";

  const RunResult rerun = run(args(cut));
  ASSERT_EQ(rerun.exit_code, 0) << rerun.err;
  EXPECT_EQ(files(cut), all);
  EXPECT_EQ(slurp(cut / "m.csv"), slurp(whole / "m.csv"));

  // Standard output is one of the group: when it cannot be written (a full
  // device), no file is left either, whether it carries the stations (-o -)
  // or the JSON report.
  const auto full = path("full");
  std::filesystem::create_directories(full);
  const std::string others = " --sinex '" + (full / "s.snx").string() + "' --report '" + (full / "r.txt").string() + "'";
  // (In braces: the helper redirects the group's output; the command's own goes to /dev/full.)
  const RunResult to_full = shell("{ " + exe() + " adjust '" + network + "' -o -" + others + " > /dev/full; }");
  EXPECT_EQ(to_full.exit_code, 5) << to_full.err;
  EXPECT_NE(to_full.err.find("error[E_WRITE]: standard output: the adjusted stations could not be written"), std::string::npos)
      << to_full.err;
  EXPECT_EQ(files(full), std::vector<std::string>{}) << "left behind";
  const RunResult json_to_full =
      shell("{ " + exe() + " adjust '" + network + "' -o '" + (full / "st.csv").string() + "' --json" + others + " > /dev/full; }");
  EXPECT_EQ(json_to_full.exit_code, 5) << json_to_full.err;
  EXPECT_EQ(files(full), std::vector<std::string>{}) << "left behind";
  // Both on standard output would interleave: refused.
  const RunResult both = run("adjust '" + network + "' -o - --json");
  EXPECT_EQ(both.exit_code, 2);
  EXPECT_NE(both.err.find("--json and -o -: both would go to standard output"), std::string::npos) << both.err;
}

// Issue 17 point 1: `adjust --generate N --out-dir DIR` writes a network
// that `adjust` reads; misuse is refused by name and writes nothing.
TEST_F(AdjustCli, Issue17_GenerateWritesANetworkThatAdjustReads) {
  const RunResult g = run("adjust --generate 300 --out-dir '" + path("").string() + "' --seed 4 --blunders 2");
  ASSERT_EQ(g.exit_code, 0) << g.err;
  EXPECT_NE(g.out.find("generated 300 stations"), std::string::npos) << g.out;
  EXPECT_NE(g.out.find("2 planted blunders"), std::string::npos) << g.out;
  const RunResult a = run("adjust '" + path("network.stn.xml").string() + "' '" + path("network.msr.xml").string() + "' -o '" +
                          path("st.csv").string() + "' --report '" + path("r.txt").string() + "' --remove-outliers");
  EXPECT_EQ(a.exit_code, 0) << a.err;
  const RunResult j = run("adjust '" + path("network.json").string() + "' -o '" + path("st2.csv").string() + "' --report '" +
                          path("r2.txt").string() + "' --remove-outliers");
  EXPECT_EQ(j.exit_code, 0) << j.err;
  // Again into the same folder: every file exists, none is replaced.
  const std::string before = testing::slurp(path("network.json"));
  const RunResult again = run("adjust --generate 300 --out-dir '" + path("").string() + "' --seed 5");
  EXPECT_EQ(again.exit_code, 5) << again.err;
  EXPECT_NE(again.err.find("E_OUTPUT_EXISTS"), std::string::npos) << again.err;
  EXPECT_EQ(testing::slurp(path("network.json")), before);
}

// Issue 17 point 4: the memory the factor needs is stated before it is
// taken; above the budget nothing is factored and nothing written.
TEST_F(AdjustCli, Issue17_AFactorLargerThanTheMemoryIsRefusedBeforeItIsTaken) {
  ASSERT_EQ(run("adjust --generate 2000 --out-dir '" + path("").string() + "'").exit_code, 0);
  const std::string in = "'" + path("network.stn.xml").string() + "' '" + path("network.msr.xml").string() + "'";
  const RunResult r = run("adjust " + in + " -o '" + path("st.csv").string() + "' --report '" + path("r.txt").string() +
                          "' --max-memory 0.001");
  EXPECT_EQ(r.exit_code, 4) << r.err;
  for (const char* piece : {"E_MEMORY", "5991 unknowns", "selected inverse need", "0.00 GB are allowed (--max-memory)"}) {
    EXPECT_NE(r.err.find(piece), std::string::npos) << piece << " in: " << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(path("st.csv")));
  EXPECT_FALSE(std::filesystem::exists(path("r.txt")));
  EXPECT_EQ(run("adjust " + in + " -o '" + path("st.csv").string() + "' --report '" + path("r.txt").string() + "' --max-memory 1 --remove-outliers").exit_code, 0);
}

// The inputs are read in one piece when they are files; a FIFO (a shell's
// `<(…)`) has no size and is read as a stream.
TEST_F(AdjustCli, Issue17_AnInputFromAFifoIsReadWhole) {
  ASSERT_EQ(run("adjust --generate 200 --out-dir '" + path("").string() + "'").exit_code, 0);
  const RunResult r = shell("mkfifo '" + path("fifo").string() + "' && { cat '" + path("network.json").string() + "' > '" +
                            path("fifo").string() + "' & } && " + exe() + " adjust '" + path("fifo").string() + "' -o '" +
                            path("st.csv").string() + "' --report '" + path("r.txt").string() + "' --remove-outliers");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const RunResult direct = run("adjust '" + path("network.json").string() + "' -o '" + path("st2.csv").string() + "' --report '" +
                               path("r2.txt").string() + "' --remove-outliers");
  EXPECT_EQ(direct.exit_code, 0) << direct.err;
  EXPECT_EQ(testing::slurp(path("st.csv")), testing::slurp(path("st2.csv")));
  // A FIFO cannot be read twice: its hash is null (as standard input's), never that of nothing.
  const std::string side = testing::slurp(path("st.csv.geoanchor.json"));
  EXPECT_NE(side.find("\"sha256\": null"), std::string::npos) << side.substr(0, 400);
}

TEST_F(AdjustCli, Issue17_GenerateMisuseIsRefusedByName) {
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
      {"adjust --generate 100", {"E_OPTION", "--out-dir"}},
      {"adjust --generate 100 --out-dir '" + path("").string() + "' -o st.csv", {"E_OPTION", "adjusts nothing"}},
      {"adjust --generate 2 --out-dir '" + path("").string() + "'", {"E_OPTION", "at least 4 stations"}},
      {"adjust --generate 100 --out-dir '" + path("").string() + "' --center 95,8", {"E_OPTION", "--center 95,8"}},
      {"adjust --generate 100 --out-dir '" + path("").string() + "' --center north", {"E_OPTION", "LAT,LON"}},
      {"adjust --generate 100 --out-dir '" + path("nowhere").string() + "'", {"E_OUTPUT_DIR", "nowhere"}},
      {"adjust --seed 3 net.json -o st.csv", {"E_OPTION", "go with --generate"}},
      {"adjust -o st.csv", {"E_OPTION", "INPUT is required"}},
      {"adjust --generate 100 --out-dir '" + path("").string() + "' --side-km nan", {"--side-km", "not a finite number"}},
      {"adjust net.json -o st.csv --jobs nan", {"--jobs", "expected an integer in [1, 256]"}},
      {"adjust net.json -o st.csv --max-memory -1", {"--max-memory"}},
  };
  for (const auto& [args, pieces] : cases) {
    SCOPED_TRACE(args);
    const RunResult r = run(args);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    for (const auto& piece : pieces) EXPECT_NE(r.err.find(piece), std::string::npos) << piece << " in: " << r.err;
    EXPECT_EQ(leftovers({}), std::vector<std::string>{});
  }
}

}  // namespace
}  // namespace geoanchor

namespace geoanchor {
namespace {

// Issue 39: the refusals it adds name what is wrong and leave no output.
// The stations: four marks around Zürich; their ECEF positions and
// distances by GeographicLib (a reference of its own here).
struct Mark {
  const char* id;
  double lat, lon, h;
};
constexpr Mark kMarks[] = {{"A", 47.45, 8.55, 430.0}, {"B", 47.46, 8.56, 440.0}, {"C", 47.455, 8.57, 435.0}, {"D", 47.447, 8.565, 520.0}};

Eigen::Vector3d ecef_of(const Mark& m) {
  const GeographicLib::Geocentric grs80(6378137.0, 1.0 / 298.257222101);
  Eigen::Vector3d x;
  grs80.Forward(m.lat, m.lon, m.h, x.x(), x.y(), x.z());
  return x;
}

std::string mark_json(const Mark& m, const std::string& constraint = "") {
  char buf[200];
  std::snprintf(buf, sizeof buf, R"({"id": "%s", "lat_deg": %.9f, "lon_deg": %.9f, "h_m": %.4f%s})", m.id, m.lat, m.lon, m.h,
                constraint.empty() ? "" : (", \"constraint\": \"" + constraint + "\"").c_str());
  return buf;
}

TEST_F(AdjustCli, Issue39_BadInputIsRefusedByNameWithNoOutput) {
  const auto run_in = [&](const std::string& json, const std::string& args) {
    write("net.json", json);
    return run("adjust '" + path("net.json").string() + "' -o '" + path("st.csv").string() + "' --measurements '" +
               path("m.csv").string() + "' --report '" + path("r.txt").string() + "' " + args);
  };
  // A GNSS point cluster in ITRF2014, a dynamic frame, with no epoch: never
  // taken at the network's epoch silently.
  const Eigen::Vector3d b = ecef_of(kMarks[1]);
  char cluster[400];
  std::snprintf(cluster, sizeof cluster,
                R"({"kind": "gnss_point_cluster", "frame": "ITRF2014", "cov_m2": [[1e-4,0,0],[0,1e-4,0],[0,0,1e-4]], "points": [{"id": "B", "x_m": %.4f, "y_m": %.4f, "z_m": %.4f}]})",
                b.x(), b.y(), b.z());
  const std::string stations = mark_json(kMarks[0], "CCC") + "," + mark_json(kMarks[1]);
  const std::string dated = network(stations, baseline("A", "B") + "," + cluster);
  const RunResult no_epoch = run_in(dated, "");
  EXPECT_EQ(no_epoch.exit_code, 3) << no_epoch.err;
  for (const char* piece : {"E_EPOCH_MISSING", "net.json: measurements[1]", "in ITRF2014, a dynamic frame, with no coordinate epoch",
                            "--frame NAME@EPOCH"}) {
    EXPECT_NE(no_epoch.err.find(piece), std::string::npos) << piece << " in: " << no_epoch.err;
  }
  EXPECT_EQ(leftovers({"net.json"}), std::vector<std::string>{});
  // With --frame the epoch to assume is given: taken at it, and said so.
  const RunResult assumed = run_in(dated, "--frame ITRF2014@2024.5 --accept-failed-global-test");
  EXPECT_EQ(assumed.exit_code, 0) << assumed.err;
  EXPECT_NE(assumed.err.find("warning: 1 GNSS measurement(s) in a dynamic frame name no coordinate epoch"), std::string::npos)
      << assumed.err;
  EXPECT_NE(testing::slurp(path("r.txt")).find("taken at --frame's epoch, as ITRF2014@2024.5"), std::string::npos);
  for (const char* f : {"st.csv", "st.csv.geoanchor.json", "m.csv", "r.txt"}) std::filesystem::remove(path(f));

  // Inner constraints over stations that do not hold the defect: a
  // tetrahedron of slope distances (free: three translations, three
  // rotations) held at two of its marks leaves the rotation about their line.
  std::string distances;
  for (std::size_t i = 0; i < 4; ++i) {
    for (std::size_t j = i + 1; j < 4; ++j) {
      char d[200];
      std::snprintf(d, sizeof d, R"(%s{"kind": "slope_distance", "from": "%s", "to": "%s", "value_m": %.4f, "sigma_m": 0.002})",
                    distances.empty() ? "" : ",", kMarks[i].id, kMarks[j].id, (ecef_of(kMarks[j]) - ecef_of(kMarks[i])).norm());
      distances += d;
    }
  }
  const std::string tetrahedron = network(mark_json(kMarks[0]) + "," + mark_json(kMarks[1]) + "," + mark_json(kMarks[2]) + "," +
                                              mark_json(kMarks[3]),
                                          distances);
  const RunResult two = run_in(tetrahedron, "--free --inner-constraints A,C");
  EXPECT_EQ(two.exit_code, 2) << two.err;
  for (const char* piece : {"E_INNER_CONSTRAINTS", "--inner-constraints A, C", "rotation about the line through them",
                            "1 of the 6 combinations"}) {
    EXPECT_NE(two.err.find(piece), std::string::npos) << piece << " in: " << two.err;
  }
  EXPECT_EQ(leftovers({"net.json"}), std::vector<std::string>{});
  const RunResult free = run_in(tetrahedron, "--free");
  EXPECT_EQ(free.exit_code, 0) << free.err;
  EXPECT_NE(testing::slurp(path("r.txt")).find("free network: "), std::string::npos);
  for (const char* f : {"st.csv", "st.csv.geoanchor.json", "m.csv", "r.txt"}) std::filesystem::remove(path(f));

  // The default and its opposite together.
  const RunResult both = run_in(tetrahedron, "--free --remove-outliers --no-snooping");
  EXPECT_EQ(both.exit_code, 2) << both.err;
  EXPECT_NE(both.err.find("--remove-outliers and --no-snooping: give one"), std::string::npos) << both.err;
  EXPECT_EQ(leftovers({"net.json"}), std::vector<std::string>{});
}

// A frame outside geoanchor's catalog takes its ellipsoid from PROJ's
// database (NZGD1949: NZGD49, EPSG:4272, on International 1924); a frame
// neither knows names no ellipsoid: never GRS80 by default (the terrestrial
// models, the local axes and the heights are on it). Stated by its EPSG
// name, it is taken; a stated ellipsoid that its frame contradicts is
// refused at its key.
TEST_F(AdjustCli, Issue39_AFrameOutsideTheCatalogNeedsItsEllipsoid) {
  const auto run_in = [&](const std::string& json) {
    write("net.json", json);
    return run("adjust '" + path("net.json").string() + "' -o '" + path("st.csv").string() + "' --accept-failed-global-test");
  };
  std::string stations;
  for (std::size_t i = 0; i < 3; ++i) {
    const Eigen::Vector3d x = ecef_of(kMarks[i]);
    char st[240];
    std::snprintf(st, sizeof st, R"(%s{"id": "%s", "x_m": %.4f, "y_m": %.4f, "z_m": %.4f%s})", i ? "," : "", kMarks[i].id, x.x(), x.y(),
                  x.z(), i == 0 ? R"(, "constraint": "CCC")" : "");
    stations += st;
  }
  const auto in_frame = [&](const std::string& frame, const std::string& ellipsoid) {
    const std::string measurements = baseline("A", "B", "[[1e-6,0,0],[0,1e-6,0],[0,0,1e-6]]", frame) + "," +
                                     baseline("B", "C", "[[1e-6,0,0],[0,1e-6,0],[0,0,1e-6]]", frame) + "," +
                                     baseline("A", "C", "[[1e-6,0,0],[0,1e-6,0],[0,0,1e-6]]", frame);
    return R"({"schema": "geoanchor.network/1", "frame": ")" + frame + R"(", )" + ellipsoid + R"("stations": [)" + stations +
           R"(], "measurements": [)" + measurements + "]}";
  };
  const auto with = [&](const std::string& ellipsoid) { return in_frame("NZGD1949", ellipsoid); };
  const RunResult unknown = run_in(in_frame("SITEGRID", ""));
  EXPECT_EQ(unknown.exit_code, 3) << unknown.err;
  for (const char* piece : {"E_ELLIPSOID", "net.json", "the frame SITEGRID is in neither geoanchor's frame catalog nor PROJ's database",
                            "International 1924"}) {
    EXPECT_NE(unknown.err.find(piece), std::string::npos) << piece << " in: " << unknown.err;
  }
  EXPECT_EQ(leftovers({"net.json"}), std::vector<std::string>{});
  const RunResult from_proj = run_in(with(""));
  EXPECT_EQ(from_proj.exit_code, 0) << from_proj.err;
  for (const char* f : {"st.csv", "st.csv.geoanchor.json"}) std::filesystem::remove(path(f));
  const RunResult stated = run_in(with(R"("ellipsoid": "International 1924", )"));
  EXPECT_EQ(stated.exit_code, 0) << stated.err;
  for (const char* f : {"st.csv", "st.csv.geoanchor.json"}) std::filesystem::remove(path(f));
  const RunResult custom = run_in(with(R"("ellipsoid": {"a_m": 6378388, "rf": 297, "name": "Hayford"}, )"));
  EXPECT_EQ(custom.exit_code, 0) << custom.err;
  for (const char* f : {"st.csv", "st.csv.geoanchor.json"}) std::filesystem::remove(path(f));
  const RunResult misspelt = run_in(with(R"("ellipsoid": "Hayford 1909", )"));
  EXPECT_EQ(misspelt.exit_code, 3) << misspelt.err;
  EXPECT_NE(misspelt.err.find("net.json.ellipsoid: 'Hayford 1909': expected one of GRS80, WGS84, International 1924"), std::string::npos)
      << misspelt.err;
  // GDA2020 is on GRS 1980: International 1924 contradicts it.
  const RunResult contradicted = run_in(R"({"schema": "geoanchor.network/1", "frame": "GDA2020", "ellipsoid": "International 1924", "stations": [)" +
                                        stations + R"(], "measurements": []})");
  EXPECT_EQ(contradicted.exit_code, 3) << contradicted.err;
  EXPECT_NE(contradicted.err.find("International 1924 contradicts the frame GDA2020"), std::string::npos) << contradicted.err;
  EXPECT_EQ(leftovers({"net.json"}), std::vector<std::string>{});
}

// The measurements CSV states what became of each measurement: the
// flagged one with its snooping rank by default, removed with
// --remove-outliers, the ignored one listed as such.
TEST_F(AdjustCli, Issue39_TheMeasurementsCsvSaysWhatBecameOfEachMeasurement) {
  ASSERT_EQ(run("adjust --generate 300 --out-dir '" + path("").string() + "' --seed 9 --blunders 1 --blunder 0.5").exit_code, 0);
  std::string json = testing::slurp(path("network.json"));
  // The first measurement ignored by its input.
  const auto at = json.find("{\"kind\": \"gnss_baseline\"");
  ASSERT_NE(at, std::string::npos);
  json.insert(at + 1, "\"ignore\": true, ");
  write("net.json", json);
  const std::string blunder_line = testing::slurp(path("network.blunders.csv"));
  const RunResult flagged = run("adjust '" + path("net.json").string() + "' -o '" + path("st.csv").string() + "' --measurements '" +
                                path("m.csv").string() + "' --accept-failed-global-test --json");
  ASSERT_EQ(flagged.exit_code, 0) << flagged.err;
  const std::string csv = testing::slurp(path("m.csv"));
  EXPECT_EQ(csv.substr(0, csv.find('\n')),
            "source,kind,stations,component,observed,adjusted,value_unit,residual,sigma,residual_sigma,residual_unit,redundancy,w,mdb,"
            "external_m,external_station,external_horizontal_m,external_horizontal_station,external_vertical_m,external_vertical_station,"
            "status,snooping_rank,set,metadata");  // set: empty but for an observation set's observations
  EXPECT_NE(csv.find(",ignored,,,\n"), std::string::npos);
  EXPECT_NE(csv.find(",flagged,1,,\n"), std::string::npos);
  EXPECT_EQ(csv.find(",removed,"), std::string::npos);
  const auto report = nlohmann::json::parse(flagged.out);
  ASSERT_FALSE(report.at("flagged").empty());
  EXPECT_EQ(report.at("flagged").front().at("snooping_rank"), 1);
  EXPECT_TRUE(report.at("removed").empty());
  const RunResult removed = run("adjust '" + path("net.json").string() + "' -o '" + path("st2.csv").string() + "' --measurements '" +
                                path("m2.csv").string() + "' --remove-outliers --json");
  ASSERT_EQ(removed.exit_code, 0) << removed.err;
  const std::string csv2 = testing::slurp(path("m2.csv"));
  EXPECT_NE(csv2.find(",removed,1,,\n"), std::string::npos);
  const auto report2 = nlohmann::json::parse(removed.out);
  ASSERT_FALSE(report2.at("removed").empty());
  EXPECT_EQ(report2.at("removed").front().at("snooping_rank"), 1);
  EXPECT_EQ(report2.at("removed").front().at("source"), report.at("flagged").front().at("source"));
}

}  // namespace
}  // namespace geoanchor
