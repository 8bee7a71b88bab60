// Issue 40 point 10: one row of a control set with latitude and longitude
// swapped is found before the solve and named (it ended in Ceres'
// "NO_CONVERGENCE"), in either role, with nothing written.

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "cli_support.hpp"

namespace geoanchor {
namespace {

namespace fs = std::filesystem;
using testing::CliTest;

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

}  // namespace
}  // namespace geoanchor
