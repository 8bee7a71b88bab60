// Issue 40 point 10: one row of a control set with latitude and longitude
// swapped is found before the solve and named (it ended in Ceres'
// "NO_CONVERGENCE"), in either role, with nothing written.

#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>
#include <string>

#include "cli_support.hpp"

namespace geoanchor {
namespace {

namespace fs = std::filesystem;
using testing::CliTest;
using testing::slurp;

class ControlRows : public CliTest {};

std::string control_with(const std::string& row_c) {
  return "# source_frame = ITRF2014@2024.5\n# target_frame = ETRF2000\n"
         "id,lat_src_deg,lon_src_deg,h_src_m,lat_dst_deg,lon_dst_deg,h_dst_m,sigma_src_m,sigma_dst_m\n"
         "A,47.40,8.50,400,47.40,8.50,400.01,0.01,0.01\n"
         "B,47.41,8.50,400,47.41,8.50,400.01,0.01,0.01\n" +
         row_c +
         "D,47.41,8.51,400,47.41,8.51,400.01,0.01,0.01\n"
         "E,47.42,8.52,400,47.42,8.52,400.01,0.01,0.01\n";
}

TEST_F(ControlRows, Issue40_OneSwappedRowIsNamedBeforeTheSolve) {
  struct Case {
    const char* role;
    const char* row;
  };
  for (const Case& c : {Case{"target", "C,47.40,8.51,400,8.51,47.40,400.01,0.01,0.01\n"},
                        Case{"source", "C,8.51,47.40,400,47.40,8.51,400.01,0.01,0.01\n"}}) {
    const auto in = write(std::string(c.role) + ".csv", control_with(c.row));
    const auto r = run("fit " + in.string() + " --model helmert7 --convention position_vector -o " + path("t.json").string());
    EXPECT_EQ(r.exit_code, 3) << r.err;
    EXPECT_NE(r.err.find("E_MARK_FAR_APART"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(std::string(c.role) + ".csv:6: mark C"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("read with its " + std::string(c.role) + " latitude and longitude the other way round"),
              std::string::npos)
        << r.err;
    EXPECT_EQ(r.err.find("CONVERGENCE"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(path("t.json")));
  }
  // The same set without the slip fits.
  const auto good = write("good.csv", control_with("C,47.40,8.51,400,47.40,8.51,400.01,0.01,0.01\n"));
  EXPECT_EQ(run("fit " + good.string() + " --model helmert7 --convention position_vector -o " + path("t.json").string()).exit_code, 0);
}

// A mark set aside (use = 0) does not stop the fit however far apart its
// roles lie: the check looks at the marks the fit uses.
TEST_F(ControlRows, Issue40_AMarkSetAsideIsNotCheckedForSwaps) {
  std::string text = control_with("C,47.40,8.51,400,8.51,47.40,400.01,0.01,0.01\n");
  // Add a use column: C (line 6) is set aside.
  std::string out;
  std::size_t line = 0;
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t end = text.find('\n', at);
    std::string row = text.substr(at, end - at);
    ++line;
    if (line == 3) row += ",use";
    if (line > 3) row += line == 6 ? ",0" : ",1";
    out += row + "\n";
    at = end + 1;
  }
  const auto in = write("aside.csv", out);
  const auto r = run("fit " + in.string() + " --model helmert7 --convention position_vector -o " + path("t.json").string());
  EXPECT_EQ(r.err.find("E_MARK_FAR_APART"), std::string::npos) << r.err;
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(path("t.json")));
}

// A dynamic frame named without an epoch, every point dated: a transform of
// fixed parameters holds at one epoch, so fit writes the points' mean
// epoch (the transform file's reader refuses a dynamic frame without one,
// issue 40 point 9), and refuses epochs spread over years.
TEST_F(ControlRows, Issue40_FitNamesTheEpochOfADynamicFrame) {
  const auto with_epochs = [](double a, double b) {
    std::string t = "# source_frame = ITRF2014\n# target_frame = ETRF2000\n"
                    "id,epoch,lat_src_deg,lon_src_deg,h_src_m,lat_dst_deg,lon_dst_deg,h_dst_m,sigma_src_m,sigma_dst_m\n";
    const char* rows[] = {"A,47.40,8.50", "B,47.41,8.50", "C,47.40,8.51", "D,47.41,8.51", "E,47.42,8.52"};
    int k = 0;
    for (const char* r : rows) {
      const std::string id(r, 1), ll(r + 2);
      t += id + "," + std::to_string(k++ % 2 ? a : b) + "," + ll + ",400," + ll + ",400.01,0.01,0.01\n";
    }
    return t;
  };
  // Epochs 2024.50 and 2024.52 (a campaign): written at their mean, 2024.508 (3 × 2024.50 + 2 × 2024.52) / 5.
  const auto in = write("dated.csv", with_epochs(2024.52, 2024.50));
  const auto r = run("fit " + in.string() + " --model helmert7 --convention position_vector -o " + path("t.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string file = testing::slurp(path("t.json"));
  EXPECT_NE(file.find("\"source_frame\": \"ITRF2014@2024.508\""), std::string::npos) << file;
  // The file is read back (convert applies it).
  const auto pts = write("p.csv", "lat_deg,lon_deg,h_m\n47.405,8.505,400\n");
  const auto back =
      run("convert " + pts.string() + " --transform " + path("t.json").string() + " --to geodetic -o " + path("p_out.csv").string());
  EXPECT_EQ(back.exit_code, 0) << back.err;
  // Epochs two years apart: refused before the solve, nothing written.
  const auto spread = write("spread.csv", with_epochs(2022.5, 2024.5));
  const auto bad = run("fit " + spread.string() + " --model helmert7 --convention position_vector -o " + path("s.json").string());
  EXPECT_EQ(bad.exit_code, 3) << bad.err;
  EXPECT_NE(bad.err.find("E_EPOCH_SPREAD"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("span 2.000 years"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(path("s.json")));
}

// A mark the input leaves out (use = 0) is a check of the transform: the
// planted 0.12 m blunder P17 of the bundled set, left out, fails its
// prediction test (|w| 21) and the report says so instead of "ignored".
TEST_F(ControlRows, Issue40_AFailingCheckMarkIsReportedAsFailing) {
  std::string text = slurp(fs::path(GEOANCHOR_FIXTURES_DIR) / "airport_control.csv"), out;
  std::size_t line = 0;
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t end = text.find('\n', at);
    std::string row = text.substr(at, end - at);
    at = end + 1;
    if (row.empty() || row[0] == '#') {
      out += row + "\n";
      continue;
    }
    out += row + (line++ == 0 ? ",use" : row.rfind("P17,", 0) == 0 || row.rfind("P05,", 0) == 0 ? ",0" : ",1") + "\n";
  }
  const auto in = write("checks.csv", out);
  const auto r = run("fit " + in.string() + " --model helmert7 --convention position_vector -o " + path("t.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::istringstream report(r.out);
  std::string row, p17, p05;
  while (std::getline(report, row)) {
    if (row.rfind("  P17 ", 0) == 0) p17 = row;
    if (row.rfind("  P05 ", 0) == 0) p05 = row;
  }
  EXPECT_NE(p17.find("ignored, FAILS"), std::string::npos) << r.out;
  ASSERT_FALSE(p05.empty()) << r.out;
  EXPECT_NE(p05.find("ignored"), std::string::npos) << p05;
  EXPECT_EQ(p05.find("FAILS"), std::string::npos) << p05;  // passes its test
  EXPECT_NE(slurp(path("t.json")).find("not used, and fails its prediction test"), std::string::npos);
}

}  // namespace
}  // namespace geoanchor
