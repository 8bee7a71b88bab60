// Control sets in CSV and JSON: the same marks read the same way, and bad
// input named by line or JSON path.

#include <gtest/gtest.h>

#include <sstream>

#include "geoanchor/geodesy/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/io/control_csv.hpp"
#include "proj_reference.hpp"

namespace geoanchor::io {
namespace {

constexpr double kSameValue_m = 0.0;  // both readers do the same arithmetic on the same numbers

const char* kCsv =
    "# source_frame = ITRF2014@2024.5\n"
    "# target_frame = ETRF2000@2024.5\n"
    "id,lat_src_deg,lon_src_deg,h_src_m,x_dst_m,y_dst_m,z_dst_m,sigma_src_m,cov_dst_xx_m2,cov_dst_xy_m2,cov_dst_xz_m2,"
    "cov_dst_yy_m2,cov_dst_yz_m2,cov_dst_zz_m2,epoch,use\n"
    "P1,47.46,8.55,480.1,4271315.7,641096.4,4678048.5,0.003,1e-5,1e-6,0,2e-5,0,3e-5,2024.5,1\n"
    "P2,47.47,8.56,481.2,4270315.7,642096.4,4678848.5,0.004,1e-5,0,0,1e-5,0,1e-5,2024.5,0\n";

const char* kJson = R"J({"source_frame": "ITRF2014@2024.5", "target_frame": "ETRF2000@2024.5", "points": [
  {"id": "P1", "source": {"lat_deg": 47.46, "lon_deg": 8.55, "h_m": 480.1},
   "target": {"x_m": 4271315.7, "y_m": 641096.4, "z_m": 4678048.5}, "sigma_src_m": 0.003,
   "cov_dst_m2": [[1e-5, 1e-6, 0], [1e-6, 2e-5, 0], [0, 0, 3e-5]], "epoch": 2024.5, "use": true},
  {"id": "P2", "source": {"lat_deg": 47.47, "lon_deg": 8.56, "h_m": 481.2},
   "target": {"x_m": 4270315.7, "y_m": 642096.4, "z_m": 4678848.5}, "sigma_src_m": 0.004,
   "cov_dst_m2": [[1e-5, 0, 0], [0, 1e-5, 0], [0, 0, 1e-5]], "epoch": 2024.5, "use": false}]})J";

std::string json_error(const std::string& text) {
  std::istringstream in(text);
  try {
    read_control_json(in, "c.json", {});
  } catch (const Error& e) {
    return e.what();
  }
  return "accepted";
}

TEST(ControlSet, CsvAndJsonReadTheSameMarksTheSameWay) {
  std::istringstream csv(kCsv), json(kJson);
  const auto a = read_control_csv(csv, "c.csv", {});
  const auto b = read_control_json(json, "c.json", {});
  ASSERT_EQ(a.points.size(), 2u);
  ASSERT_EQ(b.points.size(), 2u);
  EXPECT_EQ(a.source_frame->to_string(), "ITRF2014@2024.5");
  EXPECT_EQ(b.target_frame->to_string(), "ETRF2000@2024.5");
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(a.points[i].id, b.points[i].id);
    EXPECT_LE((a.points[i].source.m - b.points[i].source.m).norm(), kSameValue_m);
    EXPECT_LE((a.points[i].target.m - b.points[i].target.m).norm(), kSameValue_m);
    EXPECT_LE((a.points[i].source_cov_m2 - b.points[i].source_cov_m2).norm(), kSameValue_m);
    EXPECT_LE((a.points[i].target_cov_m2 - b.points[i].target_cov_m2).norm(), kSameValue_m);
    EXPECT_EQ(a.points[i].use, b.points[i].use);
    EXPECT_EQ(a.points[i].epoch->year, b.points[i].epoch->year);
  }
  // A geodetic source's isotropic sigma stays isotropic in ECEF.
  constexpr double kCovTol_m2 = 1e-18;  // float64 noise on values of 1e-5 m²
  EXPECT_NEAR(a.points[0].source_cov_m2(0, 1), 0.0, kCovTol_m2);
  EXPECT_NEAR(a.points[0].source_cov_m2.trace(), 3 * 0.003 * 0.003, kCovTol_m2);
}

TEST(ControlSet, ProjectedColumnsAreReadOnTheirDeclaredGrid) {
  // UTM 32N on WGS 84, as PROJ inverts it, then to ECEF.
  constexpr double kVsProjTol_m = 1e-6;
  const testing::ProjPipeline utm("+proj=pipeline +step +inv +proj=utm +zone=32 +ellps=WGS84 +step +proj=cart +ellps=WGS84");
  const std::string csv =
      "id,x_src_m,y_src_m,z_src_m,easting_dst_m,northing_dst_m,h_dst_m\n"
      "P1,4271315.7,641096.4,4678048.5,465012.345,5256789.012,480.5\n";
  std::istringstream in(csv);
  ControlReadOptions o;
  o.dst_projection = geodesy::utm_projection(geodesy::Ellipsoid::wgs84(), geodesy::UtmZone{32, geodesy::Hemisphere::north});
  const auto set = read_control_csv(in, "p.csv", o);
  const Eigen::Vector3d expected = utm.forward(Eigen::Vector3d(465012.345, 5256789.012, 480.5));
  EXPECT_LT((set.points[0].target.m - expected).norm(), kVsProjTol_m);
  EXPECT_EQ(set.target_input.form, geodesy::CoordinateForm::projected);
  EXPECT_EQ(set.source_input.form, geodesy::CoordinateForm::ecef);
  EXPECT_EQ(set.points[0].target_as_read, Eigen::Vector3d(465012.345, 5256789.012, 480.5));

  std::istringstream again(csv);
  try {
    read_control_csv(again, "p.csv", {});
    FAIL() << "projected columns without a grid were accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::usage);
    EXPECT_NE(std::string(e.what()).find("--dst-zone"), std::string::npos) << e.what();
  }
}

TEST(ControlSet, JsonErrorsNameThePath) {
  const std::string good = kJson;
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string s = good;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  EXPECT_NE(json_error(replaced("\"lat_deg\": 47.46", "\"lat_deg\": 91.2")).find("c.json: points[0].source: latitude not in [-90, 90]"),
            std::string::npos);
  EXPECT_NE(json_error(replaced("\"sigma_src_m\": 0.003", "\"sigma_src_m\": 0")).find("points[0].sigma_src_m: must be > 0"),
            std::string::npos);
  EXPECT_NE(json_error(replaced("\"id\": \"P2\"", "\"id\": \"P1\"")).find("points[1]: id=P1: duplicate of points[0]"),
            std::string::npos);
  EXPECT_NE(json_error(replaced("\"epoch\": 2024.5, \"use\": true", "\"epoch\": 2024.5, \"usage\": true"))
                .find("points[0].usage: unknown key"),
            std::string::npos);
  EXPECT_NE(json_error(replaced("\"h_m\": 480.1}", "\"h_m\": 480.1, \"x_m\": 1}")).find("mixes coordinate kinds"),
            std::string::npos);
  EXPECT_NE(json_error(replaced("[1e-6, 2e-5, 0]", "[2e-6, 2e-5, 0]")).find("cov_dst_m2: not symmetric"), std::string::npos);
  EXPECT_NE(json_error("{\"points\": [").find("c.json: not valid JSON"), std::string::npos);
}

std::string csv_error(const std::string& text) {
  std::istringstream in(text);
  try {
    read_control_csv(in, "c.csv", {});
  } catch (const Error& e) {
    return e.what();
  }
  return "accepted";
}

// One mark, geodetic source and ECEF target, with an attribute column and
// one more column `extra` (value 0.003).
std::string csv_with(const std::string& extra) {
  return "id,lat_src_deg,lon_src_deg,h_src_m,x_dst_m,y_dst_m,z_dst_m,sigma_src_m,kind," + extra +
         "\nP1,47.46,8.55,480.1,4271315.7,641096.4,4678048.5,0.003,runway_threshold,0.003\n";
}

// issue 12 point 3
TEST(ControlSet, Point3_JsonDuplicateKeyIsRefusedWithItsPath) {
  std::string twice = kJson;
  twice.replace(twice.find("\"sigma_src_m\": 0.003"), 20, "\"sigma_src_m\": 0.003, \"sigma_src_m\": 0.3");
  EXPECT_NE(json_error(twice).find("c.json:3: points[0].sigma_src_m: key given twice"), std::string::npos) << json_error(twice);
  std::string frames = kJson;
  frames.replace(frames.find("\"target_frame\""), 14, "\"source_frame\"");
  EXPECT_NE(json_error(frames).find("c.json:1: source_frame: key given twice"), std::string::npos) << json_error(frames);
}

// issue 12 point 10
TEST(ControlSet, Point10_CsvColumnsThatLookLikeOursAreReadOrRefusedByName) {
  EXPECT_EQ(csv_error(csv_with("note")), "accepted");  // an attribute passes through
  EXPECT_NE(csv_error(csv_with("sigma_scr_m"))
                .find("c.csv: header column 10 'sigma_scr_m': not read: a priori sigmas are read from sigma_src_m and "
                      "sigma_dst_m (isotropic, in metres) or the cov_ columns (did you mean sigma_src_m?)"),
            std::string::npos)
      << csv_error(csv_with("sigma_scr_m"));
  EXPECT_NE(csv_error(csv_with("sigma_src_mm")).find("'sigma_src_mm': not read: a priori sigmas are read from sigma_src_m and "
                                                     "sigma_dst_m (isotropic, in metres)"),
            std::string::npos)
      << csv_error(csv_with("sigma_src_mm"));
  EXPECT_NE(csv_error(csv_with("sigma_src_mm")).find("(did you mean sigma_src_m?)"), std::string::npos);
  EXPECT_NE(csv_error(csv_with("cov_dst_xx_m")).find("'cov_dst_xx_m': not read: covariances are read from cov_src_xx_m2"),
            std::string::npos);
  EXPECT_NE(csv_error(csv_with("vx_src_mm_per_year")).find("'vx_src_mm_per_year': not read: velocities are read from vx_src_m_per_year"),
            std::string::npos);
  EXPECT_NE(csv_error(csv_with("h_dst_ft")).find("'h_dst_ft': not read: a frame's coordinates are read from x_src_m"),
            std::string::npos)
      << csv_error(csv_with("h_dst_ft"));
  EXPECT_NE(csv_error(csv_with("lat_src_rad")).find("'lat_src_rad': not read"), std::string::npos);
  EXPECT_NE(csv_error(csv_with("h_m")).find("'h_m': not read: a control set names each coordinate's frame: h_src_m or h_dst_m"),
            std::string::npos)
      << csv_error(csv_with("h_m"));
  // Names we read, but not here: a velocity sigma without velocities, a column given twice.
  EXPECT_NE(csv_error(csv_with("sigma_v_src_m_per_year"))
                .find("'sigma_v_src_m_per_year': not read: a velocity sigma is read only with the velocities"),
            std::string::npos)
      << csv_error(csv_with("sigma_v_src_m_per_year"));
  EXPECT_NE(csv_error(csv_with("sigma_src_m")).find("header column 10 'sigma_src_m': appears twice in the header (also column 8)"),
            std::string::npos)
      << csv_error(csv_with("sigma_src_m"));
  // The bundled set and its attribute column still read.
  EXPECT_EQ(read_control_set(std::string(GEOANCHOR_FIXTURES_DIR) + "/airport_control.csv", {}).points.size(), 36u);
}

// issue 12 point 10
TEST(ControlSet, Point10_JsonKeysAreReadOrRefusedWithTheirPath) {
  const std::string good = kJson;
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string s = good;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  EXPECT_NE(json_error(replaced("\"sigma_src_m\": 0.003", "\"sigma_src_mm\": 3"))
                .find("c.json: points[0].sigma_src_mm: unknown key; expected id, source, target, sigma_src_m, sigma_dst_m"),
            std::string::npos);
  EXPECT_NE(json_error(replaced("\"h_m\": 480.1", "\"h_ft\": 480.1"))
                .find("points[0].source.h_ft: unknown key for these coordinates; expected lat_deg, lon_deg, h_m"),
            std::string::npos);
  EXPECT_NE(json_error(replaced("\"source_frame\": \"ITRF2014@2024.5\"", "\"source_frame\": \"ITRF2014@2024.5\", \"description\": 5"))
                .find("c.json: description: value 5 is not a string"),
            std::string::npos);
  EXPECT_NE(json_error(replaced("[1e-6, 2e-5, 0]", "[1e-6, \"2e-5\", 0]")).find("points[0].cov_dst_m2[1][1]: entry \"2e-5\" is not a number"),
            std::string::npos);
}

}  // namespace
}  // namespace geoanchor::io
