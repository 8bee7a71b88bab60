// `geoanchor convert` end to end: the real executable on files, compared
// with PROJ, and every bad-input case checked for its message, its exit code
// and the absence of any output file.

#include <GeographicLib/TransverseMercatorExact.hpp>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <thread>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "geoanchor/base/number_text.hpp"
#include "proj_reference.hpp"
#include "cli_support.hpp"
#include "test_support.hpp"

namespace geoanchor {
namespace {

namespace fs = std::filesystem;
using testing::proj_radians;
using testing::ProjPipeline;

constexpr double kRoundTripTol_m = 1e-8;  // issue acceptance: geodetic -> ECEF -> ENU -> ECEF -> geodetic
constexpr double kVsProjEcefTol_m = 1e-8;
constexpr double kVsProjEnuTol_m = 1e-6;
constexpr double kPublishedTol_m = 0.0005;  // GN 7-2 time-dependent example, millimetres

const std::string kOrigin = "47.464722,8.549167,480";  // LSZH aerodrome reference point, ellipsoidal height

using testing::CliTest;
using testing::RunResult;
using testing::slurp;

class ConvertCli : public CliTest {};

// A parsed CSV: header and rows of fields, comments dropped.
struct Table : testing::CsvTable {
  double num(std::size_t row, const std::string& name) const { return *parse_finite_double(rows[row][col(name)]); }
};

Table parse_table(const std::string& text) { return Table{testing::parse_csv_table(text)}; }

const std::string kFixture = std::string(GEOANCHOR_FIXTURES_DIR) + "/airport_points.csv";

TEST_F(ConvertCli, BundledExampleRoundTripsGeodeticEcefEnuEcefGeodetic) {
  const auto ecef = path("ecef.csv"), enu = path("enu.csv"), ecef2 = path("ecef2.csv"), geo = path("geo.csv");
  ASSERT_EQ(run("convert " + kFixture + " --to ecef -o " + ecef.string()).exit_code, 0);
  ASSERT_EQ(run("convert " + ecef.string() + " --to enu --origin " + kOrigin + " -o " + enu.string()).exit_code, 0);
  ASSERT_EQ(run("convert " + enu.string() + " --to ecef --origin " + kOrigin + " -o " + ecef2.string()).exit_code, 0);
  const RunResult last = run("convert " + ecef2.string() + " --to geodetic -o " + geo.string());
  ASSERT_EQ(last.exit_code, 0) << last.err;

  const Table in = parse_table(slurp(kFixture)), t_ecef = parse_table(slurp(ecef)), t_enu = parse_table(slurp(enu)),
              out = parse_table(slurp(geo));
  ASSERT_EQ(in.rows.size(), 36u);
  ASSERT_EQ(out.rows.size(), in.rows.size());
  EXPECT_EQ(t_ecef.header, (std::vector<std::string>{"id", "x_m", "y_m", "z_m", "kind"}));
  EXPECT_EQ(out.header, in.header);

  const ProjPipeline cart("+proj=cart +ellps=WGS84");
  char topo_def[200];
  std::snprintf(topo_def, sizeof topo_def, "+proj=pipeline +step +proj=cart +ellps=WGS84 +step +proj=topocentric "
                "+ellps=WGS84 +lat_0=47.464722 +lon_0=8.549167 +h_0=480");
  const ProjPipeline topo(topo_def);
  auto proj_ecef = [&](const Table& t, std::size_t i) {
    return cart.forward({proj_radians(t.num(i, "lon_deg")), proj_radians(t.num(i, "lat_deg")), t.num(i, "h_m")});
  };
  for (std::size_t i = 0; i < in.rows.size(); ++i) {
    EXPECT_EQ(out.rows[i][0], in.rows[i][0]);  // ids pass through in order
    EXPECT_EQ(out.rows[i][4], in.rows[i][4]);  // so do attributes
    const Eigen::Vector3d expected = proj_ecef(in, i);
    const Eigen::Vector3d ours(t_ecef.num(i, "x_m"), t_ecef.num(i, "y_m"), t_ecef.num(i, "z_m"));
    EXPECT_THAT(ours, testing::IsNearVector(expected, kVsProjEcefTol_m)) << in.rows[i][0];
    const Eigen::Vector3d enu_ref = topo.forward({proj_radians(in.num(i, "lon_deg")), proj_radians(in.num(i, "lat_deg")), in.num(i, "h_m")});
    EXPECT_THAT(Eigen::Vector3d(t_enu.num(i, "e_m"), t_enu.num(i, "n_m"), t_enu.num(i, "u_m")),
                testing::IsNearVector(enu_ref, kVsProjEnuTol_m));
    EXPECT_THAT(proj_ecef(out, i), testing::IsNearVector(expected, kRoundTripTol_m)) << in.rows[i][0];
  }
  // Comments pass through; every output has its provenance sidecar.
  EXPECT_EQ(slurp(geo).rfind("# Airport survey marks", 0), 0u);
  const std::string side = slurp(path("enu.csv.geoanchor.json"));
  EXPECT_NE(side.find("\"lat_deg\": 47.464722"), std::string::npos) << side;
  EXPECT_NE(side.find("\"height_type\": \"ellipsoidal\""), std::string::npos);
}

TEST_F(ConvertCli, StreamsStdinToStdoutWithPrecision) {
  write("in.csv", "id,x_m,y_m,z_m\nA,3771793.968,140253.342,5124304.349\n");
  const RunResult r = run("convert - --to geodetic --precision 3", path("in.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // IOGP GN 7-2 example 9602: 53°48'33.820"N = 53.80939444°, 2°07'46.380"E = 2.12955°, h 73.000 m.
  EXPECT_EQ(r.out, "id,lat_deg,lon_deg,h_m\nA,53.80939444,2.12955000,73.000\n");
}

// issue 12, tests that can fail, item 4: both rows against PROJ (the
// first was checked only for its zone name).
TEST_F(ConvertCli, UtmOutputNamesEachPointsZoneAndReadsItBack) {
  write("in.csv", "id,lat_deg,lon_deg,h_m\nZH,47.46,8.55,480\nSYD,-33.95,151.18,21\n");
  const RunResult r = run("convert " + path("in.csv").string() + " --to utm -o " + path("utm.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Table t = parse_table(slurp(path("utm.csv")));
  EXPECT_EQ(t.rows[0][t.col("utm_zone")], "32N");
  EXPECT_EQ(t.rows[1][t.col("utm_zone")], "56S");
  const ProjPipeline utm32n("+proj=utm +zone=32 +ellps=WGS84");
  const Eigen::Vector3d ref_zh = utm32n.forward({proj_radians(8.55), proj_radians(47.46), 480.0});
  EXPECT_NEAR(t.num(0, "easting_m"), ref_zh.x(), kVsProjEnuTol_m);
  EXPECT_NEAR(t.num(0, "northing_m"), ref_zh.y(), kVsProjEnuTol_m);
  const ProjPipeline utm56s("+proj=utm +zone=56 +south +ellps=WGS84");
  const Eigen::Vector3d ref = utm56s.forward({proj_radians(151.18), proj_radians(-33.95), 21.0});
  EXPECT_NEAR(t.num(1, "easting_m"), ref.x(), kVsProjEnuTol_m);
  EXPECT_NEAR(t.num(1, "northing_m"), ref.y(), kVsProjEnuTol_m);
  const RunResult back = run("convert " + path("utm.csv").string() + " --to geodetic");
  ASSERT_EQ(back.exit_code, 0) << back.err;
  const Table g = parse_table(back.out);
  EXPECT_NEAR(g.num(1, "lat_deg"), -33.95, 1e-12);
  EXPECT_NEAR(g.num(1, "lon_deg"), 151.18, 1e-12);
}

const char* kGda94Transform = R"({"model": "helmert14", "convention": "position_vector", "rotation_model": "small_angle",
 "source_frame": "ITRF2008", "target_frame": "GDA94", "reference_epoch": 1994.0,
 "parameters": {"tx_m": -0.08468, "ty_m": -0.01942, "tz_m": 0.03201, "rx_arcsec": 0.0004254, "ry_arcsec": -0.0022578,
  "rz_arcsec": -0.0024015, "ds_ppm": 0.00971, "dtx_m_per_year": 0.00142, "dty_m_per_year": 0.00134,
  "dtz_m_per_year": 0.00090, "drx_arcsec_per_year": -0.0015461, "dry_arcsec_per_year": -0.0011820,
  "drz_arcsec_per_year": -0.0011551, "dds_ppm_per_year": 0.000109}})";

// issue 12, tests that can fail, item 4: the --epoch output against the
// published value too (it was only taken back by --inverse, i.e. compared
// with geoanchor itself).
TEST_F(ConvertCli, AppliesAFourteenParameterTransformAtTheObservationEpoch) {
  // IOGP GN 7-2, EPSG method 1053 example: ITRF2008 at 2013.90 -> GDA94.
  write("T.json", kGda94Transform);
  write("in.csv", "id,x_m,y_m,z_m,epoch\nALIC,-3789470.710,4841770.404,-1690893.952,2013.90\n");
  const RunResult r = run("convert " + path("in.csv").string() + " --to ecef --transform " + path("T.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Table t = parse_table(r.out);
  EXPECT_NEAR(t.num(0, "x_m"), -3789470.004, kPublishedTol_m);
  EXPECT_NEAR(t.num(0, "y_m"), 4841770.686, kPublishedTol_m);
  EXPECT_NEAR(t.num(0, "z_m"), -1690895.108, kPublishedTol_m);
  EXPECT_EQ(t.rows[0][t.col("epoch")], "2013.90");  // the epoch column passes through

  // --epoch gives the same, and --inverse takes it back exactly.
  write("in2.csv", "id,x_m,y_m,z_m\nALIC,-3789470.710,4841770.404,-1690893.952\n");
  const RunResult r2 = run("convert " + path("in2.csv").string() + " --to ecef --epoch 2013.9 --transform " +
                     path("T.json").string() + " -o " + path("gda94.csv").string());
  ASSERT_EQ(r2.exit_code, 0) << r2.err;
  const Table g = parse_table(slurp(path("gda94.csv")));
  EXPECT_NEAR(g.num(0, "x_m"), -3789470.004, kPublishedTol_m);
  EXPECT_NEAR(g.num(0, "y_m"), 4841770.686, kPublishedTol_m);
  EXPECT_NEAR(g.num(0, "z_m"), -1690895.108, kPublishedTol_m);
  const RunResult back = run("convert " + path("gda94.csv").string() + " --to ecef --epoch 2013.9 --inverse --transform " +
                       path("T.json").string());
  ASSERT_EQ(back.exit_code, 0) << back.err;
  const Table b = parse_table(back.out);
  EXPECT_NEAR(b.num(0, "x_m"), -3789470.710, kRoundTripTol_m);
  EXPECT_NEAR(b.num(0, "y_m"), 4841770.404, kRoundTripTol_m);
  EXPECT_NEAR(b.num(0, "z_m"), -1690893.952, kRoundTripTol_m);
  EXPECT_NE(slurp(path("gda94.csv.geoanchor.json")).find("\"source_frame\": \"ITRF2008\""), std::string::npos);
}

struct BadCase {
  const char* name;
  const char* csv;        // written to in.csv
  const char* transform;  // written to T.json when non-empty
  const char* args;       // after "convert in.csv -o out.csv"
  int exit_code;
  const char* message;    // expected substring of stderr
};

// --geoid EGM96-NGA: orthometric heights at NGA's published check points
// (readme of WW15MGH.GRD, N to the millimetre) with h = 0, so that H = −N.
TEST_F(ConvertCli, NgaInterpolationGivesNgasPublishedUndulations) {
  constexpr double kPublishedEgm96Tol_m = 0.01;  // the issue's bound against published EGM96 values
  const auto in = write("h.csv",
                        "id,lat_deg,lon_deg,h_m\nA,38.6281550,-90.2208450,0\nB,-14.6212170,-54.9788860,0\n"
                        "C,46.8743190,102.4487290,0\nD,-23.6174460,133.8747120,0\nE,38.6254730,-0.0005000,0\n"
                        "F,-0.4667440,0.0023000,0\n");
  const auto r = run("convert " + in.string() + " --to geodetic --geoid EGM96-NGA --output-heights orthometric -o " +
                     path("H.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Table t = parse_table(slurp(path("H.csv")));
  const double published_n[] = {-31.628, -2.969, -43.575, 15.871, 50.066, 17.329};
  for (std::size_t i = 0; i < 6; ++i) EXPECT_NEAR(t.num(i, "H_m"), -published_n[i], kPublishedEgm96Tol_m) << i;
  const auto side = nlohmann::json::parse(slurp(path("H.csv.geoanchor.json")));
  EXPECT_EQ(side["output"]["geoid_model"], "EGM96 (15' grid, egm96_15.gtx, NGA INTPT spline)");
}

// Orthometric heights through EGM96: H_m read as h = H + N and written as
// H = h − N, against PROJ's vgridshift on the same grid followed by its
// geocentric conversion.
TEST_F(ConvertCli, OrthometricHeightsGoThroughEgm96AsProjsVgridshiftDoes) {
  constexpr double kVsProjTol_m = 1e-6;  // the issue's 1 mm; both interpolate the same grid in float64
  const auto in = write("H.csv", "id,lat_deg,lon_deg,H_m\nZH,47.46,8.55,432.0\nSYD,-33.86,151.2,40.0\nIND,5.0,78.0,0.0\n");
  const auto r = run("convert " + in.string() + " --to ecef --geoid EGM96 -o " + path("ecef.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const ProjPipeline proj("+proj=pipeline +step +proj=vgridshift +grids=egm96_15.gtx +multiplier=1 +step +proj=cart +ellps=WGS84");
  const Table t = parse_table(slurp(path("ecef.csv")));
  const double marks[3][3] = {{47.46, 8.55, 432.0}, {-33.86, 151.2, 40.0}, {5.0, 78.0, 0.0}};
  for (std::size_t i = 0; i < 3; ++i) {
    const Eigen::Vector3d expected =
        proj.forward(Eigen::Vector3d(proj_radians(marks[i][1]), proj_radians(marks[i][0]), marks[i][2]));
    const Eigen::Vector3d got(t.num(i, "x_m"), t.num(i, "y_m"), t.num(i, "z_m"));
    EXPECT_LT((got - expected).norm(), kVsProjTol_m) << i;
  }
  const auto side = nlohmann::json::parse(slurp(path("ecef.csv.geoanchor.json")));
  EXPECT_EQ(side["input"]["height_type"], "orthometric");
  EXPECT_EQ(side["input"]["geoid_model"], "EGM96 (15' grid, egm96_15.gtx)");

  // And back: ECEF to geodetic with orthometric heights gives the H we started from.
  const auto back = run("convert " + path("ecef.csv").string() + " --to geodetic --geoid EGM96 --output-heights orthometric -o " +
                        path("back.csv").string());
  ASSERT_EQ(back.exit_code, 0) << back.err;
  const Table b = parse_table(slurp(path("back.csv")));
  for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(b.num(i, "H_m"), marks[i][2], kVsProjTol_m) << i;
  const auto side_back = nlohmann::json::parse(slurp(path("back.csv.geoanchor.json")));
  EXPECT_EQ(side_back["output"]["height_type"], "orthometric");
  EXPECT_EQ(side_back["output"]["geoid_model"], "EGM96 (15' grid, egm96_15.gtx)");

  // A geoid that nothing uses is said so.
  const auto unused = run("convert " + path("ecef.csv").string() + " --to geodetic --geoid EGM96");
  EXPECT_EQ(unused.exit_code, 0) << unused.err;
  EXPECT_NE(unused.err.find("--geoid EGM96 unused"), std::string::npos) << unused.err;

  // Refusals: another model, orthometric output without a geoid, or where no height column exists.
  const struct {
    std::string args, message;
  } bad[] = {
      {"--to ecef --geoid EGM2008", "--geoid EGM2008: not packaged in Debian's proj-data and never downloaded"},
      {"--to geodetic --output-heights orthometric", "--output-heights orthometric: needs the geoid model"},
      {"--to ecef --geoid EGM96 --output-heights orthometric", "only geodetic, UTM and TM outputs have a height column"},
  };
  for (const auto& c : bad) {
    const auto e = run("convert " + in.string() + " " + c.args + " -o " + path("bad.csv").string());
    EXPECT_EQ(e.exit_code, 2) << c.args << ": " << e.err;
    EXPECT_NE(e.err.find(c.message), std::string::npos) << c.args << ": " << e.err;
    EXPECT_FALSE(std::filesystem::exists(path("bad.csv"))) << c.args;
  }
}

class ConvertBadInput : public ConvertCli, public ::testing::WithParamInterface<BadCase> {};

TEST_P(ConvertBadInput, FailsWithAClearMessageAndLeavesNoOutput) {
  const BadCase c = GetParam();
  write("in.csv", c.csv);
  std::vector<std::string> inputs = {"in.csv"};
  if (*c.transform) {
    write("T.json", c.transform);
    inputs.emplace_back("T.json");
  }
  std::string args = std::string("convert ") + path("in.csv").string() + " -o " + path("out.csv").string() + " " + c.args;
  if (*c.transform) args += " --transform " + path("T.json").string();
  const RunResult r = run(args);
  EXPECT_EQ(r.exit_code, c.exit_code) << r.err;
  EXPECT_NE(r.err.find(c.message), std::string::npos) << "stderr: " << r.err;
  EXPECT_EQ(r.err.rfind("geoanchor: error[", 0), 0u) << r.err;
  EXPECT_TRUE(leftovers(inputs).empty()) << "left behind: " << ::testing::PrintToString(leftovers(inputs));
}

void PrintTo(const BadCase& c, std::ostream* os) { *os << c.name; }

const char* kGood = "id,lat_deg,lon_deg,h_m\nA,47.46,8.55,480\nB,47.47,8.56,481\n";
const char* kHelmertNoConvention = R"({"model": "helmert7", "parameters": {"tx_m": 1, "ty_m": 2, "tz_m": 3,
 "rx_arcsec": 0.1, "ry_arcsec": 0.2, "rz_arcsec": 0.3, "ds_ppm": 0.5}})";
const char* kHelmert14NoEpoch = R"({"model": "helmert14", "convention": "coordinate_frame", "parameters": {"tx_m": 0,
 "ty_m": 0, "tz_m": 0, "rx_arcsec": 0, "ry_arcsec": 0, "rz_arcsec": 0, "ds_ppm": 0, "dtx_m_per_year": 0,
 "dty_m_per_year": 0, "dtz_m_per_year": 0, "drx_arcsec_per_year": 0.0015, "dry_arcsec_per_year": 0.0012,
 "drz_arcsec_per_year": 0.0012, "dds_ppm_per_year": 0}})";

INSTANTIATE_TEST_SUITE_P(
    Cases, ConvertBadInput,
    ::testing::Values(
        BadCase{"latitude_out_of_range", "id,lat_deg,lon_deg,h_m\nA,47.46,8.55,480\nB,91.2,8.55,480\n", "", "--to ecef", 3,
                "in.csv:3: lat_deg=91.2: latitude not in [-90, 90] degrees"},
        BadCase{"longitude_out_of_range", "id,lat_deg,lon_deg,h_m\nA,47.46,181,480\n", "", "--to ecef", 3,
                "in.csv:2: lon_deg=181: longitude not in [-180, 180] degrees"},
        BadCase{"nan", "id,x_m,y_m,z_m\nA,4270803.4,nan,4678617.5\n", "", "--to geodetic", 3,
                "in.csv:2: y_m='nan': not a finite number"},
        BadCase{"inf", "id,x_m,y_m,z_m\nA,4270803.4,640437.8,inf\n", "", "--to geodetic", 3,
                "in.csv:2: z_m='inf': not a finite number"},
        BadCase{"empty_field", "id,lat_deg,lon_deg,h_m\nA,47.46,8.55,\n", "", "--to ecef", 3,
                "in.csv:2: h_m='': empty field; expected a number"},
        BadCase{"decimal_comma", "id,lat_deg,lon_deg,h_m\nA,\"47,46\",8.55,480\n", "", "--to ecef", 3,
                "(decimal comma? use '.')"},
        BadCase{"missing_column", "id,lat_deg,h_m\nA,47.46,480\n", "", "--to ecef", 3,
                "header has lat/lon columns but no lon_deg"},
        BadCase{"unknown_column", "id,lat_rad,lon_deg,h_m\nA,0.8,8.55,480\n", "", "--to ecef", 3,
                "header column 2 'lat_rad': unit 'rad' is not read"},
        BadCase{"mixed_frames", "id,lat_deg,lon_deg,z_m\nA,47.46,8.55,480\n", "", "--to ecef", 3,
                "header mixes coordinate kinds (lat/lon and x/y/z)"},
        BadCase{"enu_without_origin", kGood, "", "--to enu", 2, "--to enu needs the local origin: give --origin"},
        BadCase{"enu_input_without_origin", "id,e_m,n_m,u_m\nA,1,2,3\n", "", "--to ecef", 2,
                "enu input needs its origin: give --from-origin"},
        BadCase{"helmert_without_convention", kGood, kHelmertNoConvention, "--to ecef", 3,
                "T.json: convention: missing"},
        BadCase{"helmert14_without_reference_epoch", kGood, kHelmert14NoEpoch, "--to ecef --epoch 2020", 3,
                "T.json: reference_epoch: missing"},
        BadCase{"helmert14_without_observation_epoch", kGood, kGda94Transform, "--to ecef", 2,
                "needs the observation epoch: give --epoch YEAR or an epoch column"},
        BadCase{"helmert14_empty_epoch_cell", "id,lat_deg,lon_deg,h_m,epoch\nA,47.46,8.55,480,2020.5\nB,47.46,8.55,480,\n",
                kGda94Transform, "--to ecef", 3, "in.csv:3: no observation epoch for a 14-parameter"},
        BadCase{"malformed_epoch", "id,lat_deg,lon_deg,h_m,epoch\nA,47.46,8.55,480,yyyy\n", kGda94Transform, "--to ecef", 3,
                "in.csv:2: epoch: epoch=yyyy: not a decimal year"},
        BadCase{"bad_origin_flag", kGood, "", "--to enu --origin 95,8,400", 2,
                "--origin 95,8,400: latitude 95 not in [-90, 90] degrees"},
        BadCase{"bad_zone_flag", kGood, "", "--to utm --zone 61N", 2, "--zone: zone=61N: not a UTM zone"},
        BadCase{"wrong_field_count", "id,lat_deg,lon_deg,h_m\nA,47.46,8.55,480,extra\n", "", "--to ecef", 3,
                "in.csv:2: 5 fields; expected 4"},
        BadCase{"orthometric_height", "id,lat_deg,lon_deg,H_m\nA,47.46,8.55,432\n", "", "--to ecef", 3,
                "'H_m': orthometric height"},
        BadCase{"unknown_to", kGood, "", "--to mercator", 2, "--to mercator: expected geodetic, ecef, enu, ned, utm or tm"}),
    [](const ::testing::TestParamInfo<BadCase>& param_info) { return std::string(param_info.param.name); });

TEST_F(ConvertCli, RefusesToOverwriteWithoutTheFlagOrToWriteOverItsInput) {
  write("in.csv", kGood);
  write("out.csv", "precious\n");
  const RunResult r = run("convert " + path("in.csv").string() + " --to ecef -o " + path("out.csv").string());
  EXPECT_EQ(r.exit_code, 5);
  EXPECT_NE(r.err.find("output already exists; pass --overwrite"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(path("out.csv")), "precious\n");
  const RunResult same = run("convert " + path("in.csv").string() + " --to ecef --overwrite -o " + path("in.csv").string());
  EXPECT_EQ(same.exit_code, 2);
  EXPECT_EQ(slurp(path("in.csv")), kGood);
  const RunResult ok = run("convert " + path("in.csv").string() + " --to ecef --overwrite -o " + path("out.csv").string());
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_EQ(slurp(path("out.csv")).rfind("id,x_m,y_m,z_m\n", 0), 0u);
}

TEST_F(ConvertCli, InterruptedMidStreamLeavesNeitherOutputNorTemporary) {
  // The input is a FIFO we keep open, so convert is provably mid-stream, with
  // its temporary output open, when SIGINT arrives.
  const fs::path fifo = path("in.fifo"), out = path("out.csv");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string exe = CliTest::exe(), cmd = "convert", in = fifo.string(), to = "--to", kind = "ecef", o = "-o",
                    out_s = out.string();
  char* argv[] = {const_cast<char*>(exe.c_str()), const_cast<char*>(cmd.c_str()), const_cast<char*>(in.c_str()),
                  const_cast<char*>(to.c_str()),  const_cast<char*>(kind.c_str()), const_cast<char*>(o.c_str()),
                  const_cast<char*>(out_s.c_str()), nullptr};
  pid_t pid = 0;
  ASSERT_EQ(::posix_spawn(&pid, exe.c_str(), nullptr, nullptr, argv, environ), 0);
  const int fd = ::open(fifo.c_str(), O_WRONLY);  // returns once convert has opened its input
  ASSERT_GE(fd, 0);
  const std::string rows = "id,lat_deg,lon_deg,h_m\nA,47.46,8.55,480\nB,47.47,8.56,481\n";
  ASSERT_EQ(::write(fd, rows.data(), rows.size()), static_cast<ssize_t>(rows.size()));
  bool temporary_seen = false;
  for (int i = 0; i < 500 && !temporary_seen; ++i) {  // up to 5 s
    for (const auto& e : fs::directory_iterator(dir_)) {
      if (e.path().filename().string().rfind(".out.csv.tmp-", 0) == 0) temporary_seen = true;
    }
    if (!temporary_seen) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_TRUE(temporary_seen) << "convert never opened its temporary output";
  ASSERT_EQ(::kill(pid, SIGINT), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ::close(fd);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGINT) << "status " << status;
  EXPECT_TRUE(leftovers({"in.fifo"}).empty()) << "left behind: " << ::testing::PrintToString(leftovers({"in.fifo"}));
}

// ---- issue 12 point 1: no NaN, no infinity, no projection outside its domain ----

// What a refused conversion must leave: nothing but its input.
#define EXPECT_NOTHING_LEFT(...)                                                         \
  do {                                                                                   \
    const std::vector<std::string> inputs_ = {__VA_ARGS__};                              \
    EXPECT_TRUE(leftovers(inputs_).empty()) << "left behind: " << ::testing::PrintToString(leftovers(inputs_)); \
  } while (false)

// issue 12 point 1
TEST_F(ConvertCli, Issue12Point1_TmNinetyDegreesFromTheMeridianIsRefusedNamingTheRowNeverWrittenAsNaN) {
  // The issue's reproduction wrote "-nan,-nan" with exit 0.
  write("in.csv", "id,lat_deg,lon_deg,h_m\nA,10,5,0\nB,0,90,0\n");
  const RunResult r = run("convert - --to tm --tm 0,0,0.9996,0,0", path("in.csv").string());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_EQ(r.out.find("nan"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("error[E_PROJECTION_DOMAIN]: <stdin>:3: outside the projection's domain: lat 0, lon 90: 90.0° "
                       "from the central meridian 0°; this Transverse Mercator is computed within 75°"),
            std::string::npos)
      << r.err;
  const RunResult f = run("convert " + path("in.csv").string() + " --to tm --tm 0,0,0.9996,0,0 -o " + path("out.csv").string());
  EXPECT_EQ(f.exit_code, 3) << f.err;
  EXPECT_NE(f.err.find("in.csv:3: outside the projection's domain: lat 0, lon 90"), std::string::npos) << f.err;
  EXPECT_NOTHING_LEFT("in.csv");
}

// issue 12 point 1
TEST_F(ConvertCli, Issue12Point1_AForcedUtmZoneFarFromThePointIsRefusedNamingTheRow) {
  // The issue's reproduction: lon 89° in zone 31N (central meridian 3°E) wrote a 15 356 km easting.
  write("in.csv", "id,lat_deg,lon_deg,h_m\nFAR,10,89,0\n");
  const RunResult r = run("convert " + path("in.csv").string() + " --to utm --zone 31N -o " + path("out.csv").string());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("in.csv:2: outside the projection's domain: lat 10, lon 89: 79.2° from the central meridian "
                       "3°E; UTM zone 31N is computed within 35°"),
            std::string::npos)
      << r.err;
  EXPECT_NOTHING_LEFT("in.csv");
}

// issue 12 point 1
TEST_F(ConvertCli, Issue12Point1_AnEastingOutsideTheZonesGridIsRefusedNamingTheRow) {
  // 52 000 km of easting in zone 31N was read as lat 0, lon 93 before.
  write("in.csv", "id,easting_m,northing_m,h_m\nOK,500000,5000000,0\nFAR,52000000,1100000,0\n");
  const RunResult r = run("convert " + path("in.csv").string() + " --from-zone 31N --to geodetic -o " + path("out.csv").string());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("error[E_PROJECTED_RANGE]: " + path("in.csv").string() +
                       ":3: easting_m=52000000, northing_m=1100000: outside the projection's domain"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("UTM zone 31N is computed within 35°"), std::string::npos) << r.err;
  EXPECT_NOTHING_LEFT("in.csv");
}

// issue 12 point 1
TEST_F(ConvertCli, Issue12Point1_FortyDegreesFromTheMeridianATmAgreesWithProjTmerc) {
  // 38.5° from the central meridian: the exact method, compared with PROJ's
  // tmerc (Poder/Engsager, 23 nm from the exact projection at 42°).
  write("in.csv", "id,lat_deg,lon_deg,h_m\nP,20,40,12.5\n");
  const RunResult r = run("convert " + path("in.csv").string() + " --to tm --tm 0,0,0.9996,0,0");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Table t = parse_table(r.out);
  const ProjPipeline tmerc("+proj=tmerc +ellps=WGS84 +k=0.9996");
  const Eigen::Vector3d ref = tmerc.forward({proj_radians(40.0), proj_radians(20.0), 12.5});
  EXPECT_NEAR(t.num(0, "easting_m"), ref.x(), kVsProjEnuTol_m);
  EXPECT_NEAR(t.num(0, "northing_m"), ref.y(), kVsProjEnuTol_m);
  EXPECT_NEAR(t.num(0, "h_m"), 12.5, kRoundTripTol_m);  // through ECEF and back
}

// issue 12 point 1
TEST_F(ConvertCli, Issue12Point1_SeventyFourDegreesFromTheMeridianATmIsTheExactProjection) {
  // 74° from the central meridian the series is 0.11 m off; the reference is
  // GeographicLib's TransverseMercatorExact (Lee 1976, about 8 nm everywhere;
  // TransverseMercatorExact.hpp), with the false origin added here.
  write("in.csv", "id,lat_deg,lon_deg,h_m\nP,2,74,0\n");
  const RunResult r = run("convert " + path("in.csv").string() + " --to tm --tm 0,0,0.9996,100000,200000");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Table t = parse_table(r.out);
  const GeographicLib::TransverseMercatorExact exact(6378137.0, 1.0 / 298.257223563, 0.9996);
  double x = 0, y = 0, gamma = 0, k = 0;
  exact.Forward(0.0, 2.0, 74.0, x, y, gamma, k);
  EXPECT_NEAR(t.num(0, "easting_m"), 100000.0 + x, kVsProjEnuTol_m);
  EXPECT_NEAR(t.num(0, "northing_m"), 200000.0 + y, kVsProjEnuTol_m);
  // And back, to the degree's 1e-9 (0.1 mm).
  write("tm.csv", r.out);
  const RunResult back = run("convert " + path("tm.csv").string() + " --from-tm 0,0,0.9996,100000,200000 --to geodetic");
  ASSERT_EQ(back.exit_code, 0) << back.err;
  const Table g = parse_table(back.out);
  EXPECT_NEAR(g.num(0, "lat_deg"), 2.0, 1e-9);
  EXPECT_NEAR(g.num(0, "lon_deg"), 74.0, 1e-9);
}

// issue 12 point 1
TEST_F(ConvertCli, Issue12Point1_AForcedZoneOutsideItsBandWarnsOnStderrAndInTheSidecar) {
  // 10.5°E is 4.5° east of zone 31's band (0°-6°E): still computed, as PROJ's utm does, with a warning.
  write("in.csv", "id,lat_deg,lon_deg,h_m\nIN,47,4,0\nNEAR,47,6.5,0\nOUT,47,10.5,0\n");
  const RunResult r = run("convert " + path("in.csv").string() + " --to utm --zone 31N -o " + path("utm.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string expected = "--zone: output UTM zone 31N: 1 point lies outside the zone's band (0°–6°E, 0°–84°N) by "
                               "more than the 1° margin; the farthest is " + path("in.csv").string() +
                               ":4 (lat 47, lon 10.5), 4.50° beyond";
  EXPECT_NE(r.err.find("geoanchor: warning: " + expected), std::string::npos) << r.err;
  const nlohmann::json side = nlohmann::json::parse(slurp(path("utm.csv.geoanchor.json")));
  ASSERT_EQ(side["warnings"].size(), 1u) << side.dump(2);
  EXPECT_EQ(side["warnings"][0].get<std::string>().rfind(expected, 0), 0u) << side["warnings"][0];
  const Table t = parse_table(slurp(path("utm.csv")));
  const ProjPipeline utm31("+proj=utm +zone=31 +ellps=WGS84");
  const Eigen::Vector3d ref = utm31.forward({proj_radians(10.5), proj_radians(47.0), 0.0});
  EXPECT_NEAR(t.num(2, "easting_m"), ref.x(), kVsProjEnuTol_m);
  EXPECT_NEAR(t.num(2, "northing_m"), ref.y(), kVsProjEnuTol_m);
  // Read back on the same zone, the input side warns as well.
  const RunResult back = run("convert " + path("utm.csv").string() + " --from-zone 31N --to geodetic");
  ASSERT_EQ(back.exit_code, 0) << back.err;
  EXPECT_NE(back.err.find("input UTM zone 31N: 1 point lies outside the zone's band"), std::string::npos) << back.err;
}

// issue 12 point 1
TEST_F(ConvertCli, Issue12Point1_ANonFiniteOutputIsRefusedNeverWritten) {
  // A transform of 1.7e308 m gives an infinite height: it was written as "inf".
  write("T.json", R"({"model": "translation3", "parameters": {"tx_m": 1.7e308, "ty_m": 1.7e308, "tz_m": 0}})");
  write("in.csv", "id,x_m,y_m,z_m\nA,4270000,640000,4680000\n");  // near Zurich, on the ground
  const RunResult r = run("convert " + path("in.csv").string() + " --transform " + path("T.json").string() +
                          " --to geodetic -o " + path("out.csv").string());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("error[E_NON_FINITE]: " + path("in.csv").string() + ":2: output h_m=inf is not finite"),
            std::string::npos)
      << r.err;
  EXPECT_NOTHING_LEFT("in.csv", "T.json");
}

// ---------------------------------------------------------------- issue 12 point 11: outputs

// issue 12 point 11
TEST_F(ConvertCli, Issue12Point11_ConvertOverwriteOntoAFifoOrAFolderIsRefusedAndNothingIsCreated) {
  // The baseline renamed its temporary over the FIFO (a device, as root) and exited 0.
  write("in.csv", "id,lat_deg,lon_deg,h_m\nA,47,8,400\n");
  const std::string cmd = "convert " + path("in.csv").string() + " --to ecef --overwrite -o ";
  ASSERT_EQ(::mkfifo(path("fifo.csv").c_str(), 0644), 0);
  const RunResult fifo = run(cmd + path("fifo.csv").string());
  EXPECT_EQ(fifo.exit_code, 5) << fifo.err;
  EXPECT_NE(fifo.err.find("error[E_OUTPUT_NOT_REGULAR]: " + path("fifo.csv").string() +
                          ": is a FIFO (named pipe), not a regular file; an output only ever replaces a regular file, "
                          "with or without --overwrite"),
            std::string::npos)
      << fifo.err;
  EXPECT_TRUE(fs::is_fifo(path("fifo.csv"))) << "the FIFO was replaced";
  fs::create_directory(path("folder.csv"));
  const RunResult folder = run(cmd + path("folder.csv").string());
  EXPECT_EQ(folder.exit_code, 5) << folder.err;
  EXPECT_NE(folder.err.find("error[E_OUTPUT_NOT_REGULAR]: " + path("folder.csv").string() + ": is a folder, not a regular file"),
            std::string::npos)
      << folder.err;
  EXPECT_TRUE(fs::is_directory(path("folder.csv")) && fs::is_empty(path("folder.csv")));
  // A FIFO where the sidecar goes: refused as well, the data not written either.
  ASSERT_EQ(::mkfifo(path("side.csv.geoanchor.json").c_str(), 0644), 0);
  const RunResult side = run(cmd + path("side.csv").string());
  EXPECT_EQ(side.exit_code, 5) << side.err;
  EXPECT_NE(side.err.find("error[E_OUTPUT_NOT_REGULAR]: " + path("side.csv.geoanchor.json").string() + ": is a FIFO"),
            std::string::npos)
      << side.err;
  EXPECT_NOTHING_LEFT("in.csv", "fifo.csv", "folder.csv", "side.csv.geoanchor.json");
}

// issue 12 point 11
TEST_F(ConvertCli, Issue12Point11_ConvertASidecarThatCannotBeWrittenLeavesNeitherFileAndARerunWritesBoth) {
  write("in.csv", "id,lat_deg,lon_deg,h_m\nA,47,8,400\n");
  const std::string args = "convert " + path("in.csv").string() + " --to ecef -o " + path("out.csv").string();
  // Files limited to 512 bytes (ulimit -f counts 512-byte blocks in sh): the
  // one-row CSV (about 70 bytes) fits, its sidecar (over 600 bytes with this
  // folder's name in it) does not; its write fails with EFBIG as on a full disk.
  const RunResult full = shell("trap '' XFSZ; ulimit -f 1; exec " + exe() + " " + args);
  EXPECT_EQ(full.exit_code, 5) << full.err;
  EXPECT_NE(full.err.find("error[E_WRITE]: " + path("out.csv.geoanchor.json").string() +
                          ": writing failed (File too large); neither " + path("out.csv.geoanchor.json").string() +
                          " nor " + path("out.csv").string() + " was written"),
            std::string::npos)
      << full.err;
  EXPECT_NOTHING_LEFT("in.csv");  // the baseline left out.csv, and the rerun below was refused
  const RunResult rerun = run(args);
  ASSERT_EQ(rerun.exit_code, 0) << rerun.err;
  EXPECT_TRUE(fs::is_regular_file(path("out.csv")));
  const nlohmann::json side = nlohmann::json::parse(slurp(path("out.csv.geoanchor.json")));
  EXPECT_TRUE(side.is_object()) << side.dump(2);
}

// issue 12 point 11
TEST_F(ConvertCli, Issue12Point11_ConvertFitAndDiagnoseOntoAFullStandardOutputExitNonZero) {
  write("in.csv", "id,lat_deg,lon_deg,h_m\nA,47,8,400\n");
  // (in a subshell: shell() redirects the whole command's standard output to a file)
  const RunResult convert = shell("(" + exe() + " convert " + path("in.csv").string() + " --to ecef > /dev/full)");
  EXPECT_EQ(convert.exit_code, 5) << convert.err;
  EXPECT_NE(convert.err.find("error[E_WRITE]: standard output: the converted rows could not be written (No space left on device)"),
            std::string::npos)
      << convert.err;
  // The baseline printed the fit report into the void, wrote T.json and exited 0.
  const std::string control = std::string(GEOANCHOR_FIXTURES_DIR) + "/airport_control.csv";
  const RunResult fit = shell("(" + exe() + " fit " + control + " --remove-outliers --model helmert7 --convention position_vector -o " +
                              path("T.json").string() + " > /dev/full)");
  EXPECT_EQ(fit.exit_code, 5) << fit.err;
  EXPECT_NE(fit.err.find("error[E_WRITE]: standard output: the fit report could not be written"), std::string::npos) << fit.err;
  EXPECT_NE(fit.err.find("; " + path("T.json").string() + " was not written"), std::string::npos) << fit.err;
  EXPECT_FALSE(fs::exists(path("T.json")));
  const RunResult diagnose = shell("(" + exe() + " diagnose " + control + " > /dev/full)");
  EXPECT_EQ(diagnose.exit_code, 5) << diagnose.err;
  EXPECT_NE(diagnose.err.find("error[E_WRITE]: standard output: the diagnosis could not be written"), std::string::npos)
      << diagnose.err;
  EXPECT_NOTHING_LEFT("in.csv");
}

// issue 12 point 11
TEST_F(ConvertCli, Issue12Point11_ConvertRemovesAKilledRunsTemporaryBesideItsOutputAndSaysSo) {
  write("in.csv", "id,lat_deg,lon_deg,h_m\nA,47,8,400\n");
  // What a convert killed by SIGKILL leaves: its temporary, held by no process.
  const fs::path stale = write("out/.out.csv.tmp-0123456789abcdef", "x_m,y_m,z_m\n4300000");
  const fs::path recent = write("out/.out.csv.tmp-00000000000000ff", "being written");  // not 10 s old
  const fs::path other = write("out/.out.csv.tmp-123", "not our pattern");
  const struct timespec old[2] = {{1000000000, 0}, {1000000000, 0}};  // 2001-09-09
  ASSERT_EQ(::utimensat(AT_FDCWD, stale.c_str(), old, AT_SYMLINK_NOFOLLOW), 0);
  ASSERT_EQ(::utimensat(AT_FDCWD, other.c_str(), old, AT_SYMLINK_NOFOLLOW), 0);
  const RunResult r = run("convert " + path("in.csv").string() + " --to ecef -o " + path("out/out.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::exists(stale));
  EXPECT_TRUE(fs::exists(recent));
  EXPECT_TRUE(fs::exists(other));
  const std::string warning = stale.string() + ": removed, a temporary output left by a run that was killed";
  EXPECT_NE(r.err.find("geoanchor: warning: " + warning), std::string::npos) << r.err;
  const nlohmann::json side = nlohmann::json::parse(slurp(path("out/out.csv.geoanchor.json")));
  EXPECT_EQ(side["warnings"], nlohmann::json::array({warning})) << side.dump(2);
}


// ---------------------------------------------------------------- issue 12 point 7: implausible parameters

// fit's limits (geodesy/helmert.hpp, RELIABILITY #15): |t| <= 1 km, |r| <= 10″, |ds| <= 100 ppm.
struct ImplausibleCase {
  const char* name;
  const char* transform;
  std::string expected;  // the warning's start after "geoanchor: warning: T.json"; empty: no implausibility warning
};

// issue 12 point 7
TEST_F(ConvertCli, Issue12Point7_ImplausibleTransformParametersWarnOnStderrAndInTheSidecar) {
  // The baseline applied each of these silently (exit 0, no warning).
  const std::vector<ImplausibleCase> cases = {
      // 20″ at the Earth's mean radius: 20 / 206264.806 × 6371 km = 618 m.
      {"rx", R"({"model": "helmert7", "convention": "position_vector", "parameters": {"tx_m": 0, "ty_m": 0, "tz_m": 0,
        "rx_arcsec": 20, "ry_arcsec": 0, "rz_arcsec": 0, "ds_ppm": 0}})",
       ": rx = 20″ is implausible for a datum transform (> 10″, 618 m at the Earth's surface)"},
      {"ds", R"({"model": "helmert7", "convention": "position_vector", "parameters": {"tx_m": 0, "ty_m": 0, "tz_m": 0,
        "rx_arcsec": 0, "ry_arcsec": 0, "rz_arcsec": 0, "ds_ppm": 200}})",
       ": ds = 200 ppm is implausible for a datum transform (> 100 ppm"},
      {"tx", R"({"model": "translation3", "parameters": {"tx_m": 1e300, "ty_m": 0, "tz_m": 0}})",
       ": tx = 1e+300 m is implausible for a datum transform (> 1e+03 m)"},
      {"plausible", R"({"model": "helmert7", "convention": "position_vector", "parameters": {"tx_m": 100, "ty_m": -50,
        "tz_m": 20, "rx_arcsec": 0.5, "ry_arcsec": -0.2, "rz_arcsec": 1, "ds_ppm": 2}})",
       ""},
  };
  write("in.csv", "id,x_m,y_m,z_m\nA,4277000,639000,4672000\nB,4277100,639050,4671900\n");
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string t = std::string(c.name) + ".json";
    write(t, c.transform);
    const std::string out = std::string(c.name) + ".csv";
    const RunResult r = run("convert " + path("in.csv").string() + " --to ecef --transform " + path(t).string() + " -o " +
                            path(out).string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json side = nlohmann::json::parse(slurp(path(out + ".geoanchor.json")));
    if (c.expected.empty()) {
      EXPECT_EQ(r.err.find("implausible"), std::string::npos) << r.err;
      EXPECT_EQ(side["warnings"].dump().find("implausible"), std::string::npos) << side.dump(2);
      continue;
    }
    const std::string expected = path(t).string() + c.expected;
    // Once per run, not once per row.
    const std::string line = "geoanchor: warning: " + expected;
    const auto first = r.err.find(line);
    EXPECT_NE(first, std::string::npos) << r.err;
    EXPECT_EQ(r.err.find(line, first + 1), std::string::npos) << r.err;
    int recorded = 0;
    for (const auto& w : side["warnings"]) recorded += w.get<std::string>().rfind(expected, 0) == 0 ? 1 : 0;
    EXPECT_EQ(recorded, 1) << side.dump(2);
  }
}

// issue 12 point 7
TEST_F(ConvertCli, Issue12Point7_AFourteenParameterSetIsCheckedAtTheFirstAndLastEpochOfTheRows) {
  // rz = 5″ + 1″/yr × (t − 2020): 6″ at 2021 (plausible), 15″ at 2030 (beyond 10″).
  write("T14.json", R"({"model": "helmert14", "convention": "position_vector", "reference_epoch": 2020.0,
    "parameters": {"tx_m": 0, "ty_m": 0, "tz_m": 0, "rx_arcsec": 0, "ry_arcsec": 0, "rz_arcsec": 5, "ds_ppm": 0,
                   "dtx_m_per_year": 0, "dty_m_per_year": 0, "dtz_m_per_year": 0, "drx_arcsec_per_year": 0,
                   "dry_arcsec_per_year": 0, "drz_arcsec_per_year": 1, "dds_ppm_per_year": 0}})");
  write("in.csv", "id,x_m,y_m,z_m,epoch\nA,4277000,639000,4672000,2021.0\nB,4277100,639050,4671900,2030.0\n"
                  "C,4277100,639050,4671900,2025.0\n");
  const RunResult r = run("convert " + path("in.csv").string() + " --to ecef --transform " + path("T14.json").string() +
                          " -o " + path("out.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string expected = path("T14.json").string() + " at epoch 2030: rz = 15″ is implausible for a datum transform (> 10″";
  EXPECT_NE(r.err.find("geoanchor: warning: " + expected), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("at epoch 2021"), std::string::npos) << r.err;
  const nlohmann::json side = nlohmann::json::parse(slurp(path("out.csv.geoanchor.json")));
  int recorded = 0;
  for (const auto& w : side["warnings"]) recorded += w.get<std::string>().rfind(expected, 0) == 0 ? 1 : 0;
  EXPECT_EQ(recorded, 1) << side.dump(2);
  // Every row at 2021 (by --epoch): nothing to warn about.
  write("in2.csv", "id,x_m,y_m,z_m\nA,4277000,639000,4672000\n");
  const RunResult early = run("convert " + path("in2.csv").string() + " --to ecef --epoch 2021 --transform " +
                              path("T14.json").string() + " -o " + path("early.csv").string());
  ASSERT_EQ(early.exit_code, 0) << early.err;
  EXPECT_EQ(early.err.find("implausible"), std::string::npos) << early.err;
}

}  // namespace
}  // namespace geoanchor
