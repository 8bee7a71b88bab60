// geoanchor adjust on the command line: every bad input of issue 14 is
// refused with a message naming the file, the element and the value, and
// leaves no output (stations CSV, sidecar, measurements, report, SINEX);
// the published samples run end to end with every output.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
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
                          path("s.snx").string() + "' --report '" + path("r.txt").string() + "' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
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
                          path("st.csv").string() + "' --report '" + path("r.txt").string() + "'");
  EXPECT_EQ(a.exit_code, 0) << a.err;
  const RunResult j = run("adjust '" + path("network.json").string() + "' -o '" + path("st2.csv").string() + "' --report '" +
                          path("r2.txt").string() + "'");
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
  EXPECT_EQ(run("adjust " + in + " -o '" + path("st.csv").string() + "' --report '" + path("r.txt").string() + "' --max-memory 1").exit_code, 0);
}

// The inputs are read in one piece when they are files; a FIFO (a shell's
// `<(…)`) has no size and is read as a stream.
TEST_F(AdjustCli, Issue17_AnInputFromAFifoIsReadWhole) {
  ASSERT_EQ(run("adjust --generate 200 --out-dir '" + path("").string() + "'").exit_code, 0);
  const RunResult r = shell("mkfifo '" + path("fifo").string() + "' && { cat '" + path("network.json").string() + "' > '" +
                            path("fifo").string() + "' & } && " + exe() + " adjust '" + path("fifo").string() + "' -o '" +
                            path("st.csv").string() + "' --report '" + path("r.txt").string() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const RunResult direct = run("adjust '" + path("network.json").string() + "' -o '" + path("st2.csv").string() + "' --report '" +
                               path("r2.txt").string() + "'");
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
