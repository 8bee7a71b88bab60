// `geoanchor adjust` on NGS GVX 1.0 inputs: the vectors' metadata in the
// measurements CSV's last column, and each bad input refused (exit 3) with
// its message and no output file left.

#include <gtest/gtest.h>

#include <GeographicLib/Geocentric.hpp>

#include <string>
#include <vector>

#include "cli_support.hpp"
#include "gvx_text.hpp"

namespace geoanchor {
namespace {

using testing::CliTest;
using testing::GvxPoint;
using testing::GvxVector;
using testing::RunResult;

class AdjustGvxCli : public CliTest {
 protected:
  static Eigen::Vector3d ecef(const GvxPoint& p) {
    static const GeographicLib::Geocentric grs80(6378137.0, 1.0 / 298.257222101);
    Eigen::Vector3d x;
    grs80.Forward(p.lat_deg, p.lon_deg, p.h_m, x.x(), x.y(), x.z());
    return x;
  }
  static std::string gvx() {
    const std::vector<GvxPoint> p = {{"P1", "BASE1", 40.0, -105.25, 1650.0, "Keyed-in", "E1"},
                                     {"P2", "ROV1", 40.01, -105.24, 1660.1234, "Fixed", "E2"},
                                     {"P3", "ROV2", 39.995, -105.26, 1645.5, "Fixed", "E2"}};
    GvxVector v1{"V1", "P1", "P2"}, v2{"V2", "P1", "P3"}, v3{"V3", "P2", "P3", "S2"};
    v1.d_m = ecef(p[1]) - ecef(p[0]);
    v2.d_m = ecef(p[2]) - ecef(p[0]);
    v3.d_m = ecef(p[2]) - ecef(p[1]) + Eigen::Vector3d(0.002, -0.001, 0.001);
    return testing::gvx_document(p, {v1, v2, v3});
  }
  RunResult adjust_file() {
    return run("adjust '" + path("net.gvx").string() + "' -o '" + path("st.csv").string() + "' --measurements '" +
               path("m.csv").string() + "' --constrain BASE1=CCC");
  }
};

TEST_F(AdjustGvxCli, MetadataIsTheMeasurementsLastColumn) {
  write("net.gvx", gvx());
  const RunResult r = adjust_file();
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string csv = testing::slurp(path("m.csv"));
  EXPECT_EQ(csv.substr(0, csv.find('\n')),
            "source,kind,stations,component,observed,adjusted,value_unit,residual,sigma,residual_sigma,residual_unit,redundancy,w,mdb,"
            "external_m,external_station,external_horizontal_m,external_horizontal_station,external_vertical_m,external_vertical_station,"
            "status,snooping_rank,set,metadata");
  // The first baseline's rows carry its metadata, ';'-separated, with '='
  // inside a value escaped.
  EXPECT_NE(csv.find("GNSS_VECTOR/ID=V1;"), std::string::npos);
  EXPECT_NE(csv.find(";SURVEY_SETUP/SOLUTION_TYPE=NetworkRTK;"), std::string::npos);
  EXPECT_NE(csv.find(";GNSS_VECTOR/QUALITY_CONTROL/DILUTION_PRECISION/PDOP=1.6;"), std::string::npos);
  EXPECT_NE(csv.find(";TERMINAL_POINT/EQUIPMENT/RECEIVER/TYPE=LEICA GS18;"), std::string::npos);
  EXPECT_NE(csv.find(";REMARK=end of file\n"), std::string::npos);
}

TEST_F(AdjustGvxCli, EachBadInputIsRefusedAndLeavesNoOutput) {
  struct Case {
    const char* what;
    const char* from;
    const char* to;
    const char* message;
  };
  const Case cases[] = {
      {"an unknown element", "<PDOP>1.6</PDOP>", "<PDOPX>1.6</PDOPX>", "<PDOPX> in <DILUTION_PRECISION>"},
      {"feet", "<NAME>meters</NAME>", "<NAME>feet</NAME>", "LINEAR_UNIT/NAME='feet' is not one of meters, metres"},
      {"a frame the catalog cannot reach", "<ID>131</ID>\n    <NAME>WGS 84 (G1762)</NAME>", "<ID>724</ID>\n    <NAME>IGb14</NAME>",
       "REFERENCE_SYSTEM ID 724 is IGb14, a frame geoanchor's catalog does not reach"},
      {"an ISO number unknown", "<ID>126</ID>", "<ID>216</ID>", "REFERENCE_SYSTEM ID 216"},
      {"not positive definite", "<PXY>0.5</PXY>", "<PXY>1</PXY>", "CORRELATION_MATRIX is not positive definite"},
      {"a session", "<REMARK>end of file</REMARK>", "<SESSION ID=\"S\" TOTAL_VECTORS=\"2\"/>", "<SESSION> (the cross-correlations"},
      {"a missing delta", "<SDZ>0.004</SDZ>", "", "GNSS_VECTOR V1 has no CORRELATION_MATRIX/SDZ"},
      {"an unknown point", "<INITIAL_POINT_ID>P1</INITIAL_POINT_ID>", "<INITIAL_POINT_ID>P9</INITIAL_POINT_ID>",
       "INITIAL_POINT_ID 'P9' names no POINT of the file"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    std::string text = gvx();
    const auto at = text.find(c.from);
    ASSERT_NE(at, std::string::npos);
    write("net.gvx", text.replace(at, std::string(c.from).size(), c.to));
    const RunResult r = adjust_file();
    EXPECT_EQ(r.exit_code, 3) << r.err;
    EXPECT_NE(r.err.find("error[E_GVX]"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << r.err;
    EXPECT_EQ(leftovers({"net.gvx"}), std::vector<std::string>{});
  }
}

}  // namespace
}  // namespace geoanchor
