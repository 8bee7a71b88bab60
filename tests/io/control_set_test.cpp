// Control sets in CSV and JSON: the same marks read the same way, and bad
// input named by line or JSON path.

#include <gtest/gtest.h>

#include <GeographicLib/Geocentric.hpp>

#include <map>

#include <nlohmann/json.hpp>
#include <sstream>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/io/control/control_csv.hpp"
#include "geoanchor/crs/crs.hpp"
#include "accuracy.hpp"
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

// `s` with the first `from` replaced by `to`.
void replace_first(std::string& s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  ASSERT_NE(at, std::string::npos) << from;
  s.replace(at, from.size(), to);
}

// The error a reader throws for `text`, with `o`: its code and message.
std::pair<std::string, std::string> read_error(const std::string& text, const std::string& name, const ControlReadOptions& o) {
  std::istringstream in(text);
  try {
    if (name.find(".json") != std::string::npos) {
      read_control_json(in, name, o);
    } else {
      read_control_csv(in, name, o);
    }
  } catch (const Error& e) {
    return {e.code(), e.what()};
  }
  return {"accepted", ""};
}

// Marks near LSZH (N ≈ 47.3 m) with orthometric heights in one or both
// frames: H_src_m/H_dst_m, one of them on a UTM 32N grid.
const char* kOrthometricCsv =
    "id,lat_src_deg,lon_src_deg,H_src_m,easting_dst_m,northing_dst_m,H_dst_m,sigma_src_m,sigma_dst_m\n"
    "P1,47.4834644617,8.5283688582,443.8311,464998.123,5258862.456,443.8300,0.003,0.004\n"
    "P2,-33.86,151.2,40.0,465312.5,5257321.25,432.25,0.003,0.004\n";

// issue 12 point 2: an orthometric height column is never read as an
// ellipsoidal one: without a geoid it is refused, naming the column (CSV)
// or the key's path (JSON).
TEST(ControlSet, Point2_OrthometricHeightsWithoutAGeoidAreRefusedNamingTheColumn) {
  ControlReadOptions o;
  o.dst_projection = geodesy::utm_projection(geodesy::Ellipsoid::wgs84(), geodesy::UtmZone{32, geodesy::Hemisphere::north});
  const auto [code, message] = read_error(kOrthometricCsv, "c.csv", o);
  EXPECT_EQ(code, "E_HEIGHT_TYPE");
  EXPECT_NE(message.find("c.csv: column 'H_src_m': orthometric height"), std::string::npos) << message;
  EXPECT_NE(message.find("give --geoid EGM96 (h = H + N)"), std::string::npos) << message;
  // A geoid for the source only: the projected target's H_dst_m is refused.
  o.src_geoid = &geodesy::GeoidGrid::egm96();
  const auto [code_dst, message_dst] = read_error(kOrthometricCsv, "c.csv", o);
  EXPECT_EQ(code_dst, "E_HEIGHT_TYPE");
  EXPECT_NE(message_dst.find("c.csv: column 'H_dst_m': orthometric height"), std::string::npos) << message_dst;

  std::string json = kJson;
  replace_first(json, "\"h_m\": 480.1", "\"H_m\": 432.8");
  const auto [jcode, jmessage] = read_error(json, "c.json", {});
  EXPECT_EQ(jcode, "E_HEIGHT_TYPE");
  EXPECT_NE(jmessage.find("c.json: points[0].source.H_m: orthometric height"), std::string::npos) << jmessage;
  EXPECT_NE(jmessage.find("give --geoid EGM96"), std::string::npos) << jmessage;
  // With a geoid: both heights for one mark, or both types in one frame, are refused.
  ControlReadOptions g;
  g.src_geoid = g.dst_geoid = &geodesy::GeoidGrid::egm96();
  std::string both = kJson;
  replace_first(both, "\"h_m\": 480.1", "\"h_m\": 480.1, \"H_m\": 432.8");
  EXPECT_NE(read_error(both, "c.json", g).second.find("points[0].source.H_m: an ellipsoidal (h_m) and an orthometric (H_m)"),
            std::string::npos)
      << read_error(both, "c.json", g).second;
  EXPECT_NE(read_error(json, "c.json", g).second.find("points[1].source.h_m: an ellipsoidal height, but points[0].source.H_m is "
                                                     "orthometric"),
            std::string::npos)
      << read_error(json, "c.json", g).second;
}

// issue 12 point 2: with the geoid, h = H + N as PROJ's vgridshift on the
// same egm96_15.gtx gives it, for geodetic and projected columns and for
// JSON; the set records the height type, the column and the model.
TEST(ControlSet, Point2_OrthometricHeightsAreReadThroughTheGeoidAsProjsVgridshift) {
  constexpr double kVsProjTol_m = 1e-6;  // both interpolate the same float32 grid bilinearly in float64
  // vgridshift: z_out = z_in + multiplier × N, so +1 turns H into h.
  const testing::ProjPipeline geodetic(
      "+proj=pipeline +step +proj=vgridshift +grids=egm96_15.gtx +multiplier=1 +step +proj=cart +ellps=WGS84");
  const testing::ProjPipeline projected(
      "+proj=pipeline +step +inv +proj=utm +zone=32 +ellps=WGS84 +step +proj=vgridshift +grids=egm96_15.gtx "
      "+multiplier=1 +step +proj=cart +ellps=WGS84");
  const testing::ProjPipeline undulation("+proj=vgridshift +grids=egm96_15.gtx +multiplier=1");
  ControlReadOptions o;
  o.dst_projection = geodesy::utm_projection(geodesy::Ellipsoid::wgs84(), geodesy::UtmZone{32, geodesy::Hemisphere::north});
  o.src_geoid = o.dst_geoid = &geodesy::GeoidGrid::egm96();
  std::istringstream in(kOrthometricCsv);
  const auto set = read_control_csv(in, "c.csv", o);
  ASSERT_EQ(set.points.size(), 2u);
  const double src[2][3] = {{47.4834644617, 8.5283688582, 443.8311}, {-33.86, 151.2, 40.0}};
  const double dst[2][3] = {{464998.123, 5258862.456, 443.8300}, {465312.5, 5257321.25, 432.25}};
  for (std::size_t i = 0; i < 2; ++i) {
    const Eigen::Vector3d s(testing::proj_radians(src[i][1]), testing::proj_radians(src[i][0]), src[i][2]);
    EXPECT_LT((set.points[i].source.m - geodetic.forward(s)).norm(), kVsProjTol_m) << i;
    EXPECT_LT((set.points[i].target.m - projected.forward(Eigen::Vector3d(dst[i][0], dst[i][1], dst[i][2]))).norm(),
              kVsProjTol_m)
        << i;
    // As read: the ellipsoidal height the reader derived (h = H + N).
    EXPECT_NEAR(set.points[i].source_as_read.z(), undulation.forward(s).z(), kVsProjTol_m) << i;
  }
  EXPECT_GT(set.points[0].source_as_read.z() - src[0][2], 47.0);  // N ≈ 47.3 m at LSZH
  EXPECT_EQ(set.source_input.height_type, geodesy::HeightKind::orthometric);
  EXPECT_EQ(set.source_input.height_column, "H_src_m");
  EXPECT_EQ(set.target_input.height_column, "H_dst_m");
  EXPECT_EQ(set.target_input.geoid_model, geodesy::GeoidGrid::egm96().model_name());

  std::string json = kJson;
  // Without the frames, as the CSV (their ellipsoid would be GRS80, the CSV's WGS84).
  replace_first(json, "\"source_frame\": \"ITRF2014@2024.5\", \"target_frame\": \"ETRF2000@2024.5\", ", "");
  replace_first(json, "\"h_m\": 480.1", "\"H_m\": 443.8311");
  replace_first(json, "\"lat_deg\": 47.46", "\"lat_deg\": 47.4834644617");
  replace_first(json, "\"lon_deg\": 8.55", "\"lon_deg\": 8.5283688582");
  replace_first(json, "\"h_m\": 481.2", "\"H_m\": 433.9");
  std::istringstream jin(json);
  const auto j = read_control_json(jin, "c.json", o);
  EXPECT_LE((j.points[0].source.m - set.points[0].source.m).norm(), kSameValue_m);
  EXPECT_EQ(j.source_input.height_type, geodesy::HeightKind::orthometric);
  EXPECT_EQ(j.source_input.height_column, "H_m");
  EXPECT_EQ(j.target_input.height_type, geodesy::HeightKind::ellipsoidal);  // ECEF
  // Ellipsoidal sets say so.
  std::istringstream plain(kCsv);
  EXPECT_EQ(read_control_csv(plain, "c.csv", {}).source_input.height_type, geodesy::HeightKind::ellipsoidal);
}

// issue 12 point 5: a dynamic frame's coordinates mean nothing without
// their epoch: the frame must name it (or every point must have one), else
// the set is refused naming the comment or key and the frame.
TEST(ControlSet, Point5_DynamicFrameWithoutEpochIsRefusedNamingTheCommentOrKey) {
  auto csv = [](const std::string& comments, const std::string& epochs) {
    return comments +
           "id,lat_src_deg,lon_src_deg,h_src_m,lat_dst_deg,lon_dst_deg,h_dst_m,epoch\n"
           "P1,47.46,8.55,480.1,47.46,8.55,480.2," + epochs.substr(0, epochs.find(',')) + "\n"
           "P2,47.47,8.56,481.2,47.47,8.56,481.3," + epochs.substr(epochs.find(',') + 1) + "\n";
  };
  const auto [code, message] = read_error(csv("# source_frame = ITRF2014\n# target_frame = ETRF2000\n", ","), "c.csv", {});
  EXPECT_EQ(code, "E_EPOCH_MISSING");
  EXPECT_NE(message.find("c.csv: comment '# source_frame = ITRF2014' (above the header on line 3): frame ITRF2014 is dynamic"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("give ITRF2014@YYYY.Y"), std::string::npos) << message;
  const auto wgs = read_error(csv("# source_frame = ETRF2000\n# target_frame = WGS84(G2139)\n", ","), "c.csv", {});
  EXPECT_EQ(wgs.first, "E_EPOCH_MISSING");
  EXPECT_NE(wgs.second.find("'# target_frame = WGS84(G2139)' (above the header on line 3): frame WGS84(G2139) is dynamic"),
            std::string::npos)
      << wgs.second;
  // One point without its epoch is enough to refuse.
  EXPECT_EQ(read_error(csv("# source_frame = ITRF2014\n", "2024.5,"), "c.csv", {}).first, "E_EPOCH_MISSING");
  // Accepted: the frame's epoch, every point's epoch, a plate-fixed frame.
  EXPECT_EQ(read_error(csv("# source_frame = ITRF2014@2024.5\n# target_frame = ETRF2000\n", ","), "c.csv", {}).first,
            "accepted");
  EXPECT_EQ(read_error(csv("# source_frame = ITRF2014\n", "2010.0,2015.0"), "c.csv", {}).first, "accepted");
  EXPECT_EQ(read_error(csv("# source_frame = GDA94\n# target_frame = GDA2020\n", ","), "c.csv", {}).first, "accepted");

  std::string json = kJson;
  replace_first(json, "\"ITRF2014@2024.5\"", "\"IGS14\"");
  replace_first(json, "\"epoch\": 2024.5, \"use\": false", "\"use\": false");
  const auto [jcode, jmessage] = read_error(json, "c.json", {});
  EXPECT_EQ(jcode, "E_EPOCH_MISSING");
  EXPECT_NE(jmessage.find("c.json: source_frame: frame IGS14 is dynamic"), std::string::npos) << jmessage;
  EXPECT_NE(jmessage.find("give IGS14@YYYY.Y"), std::string::npos) << jmessage;
  std::string dated = kJson;  // every point has its epoch
  replace_first(dated, "\"ITRF2014@2024.5\"", "\"ITRF2014\"");
  EXPECT_EQ(read_error(dated, "c.json", {}).first, "accepted");
  // The bundled sets name their epochs.
  for (const char* f : {"airport_control.csv", "airport_control_orthometric.csv"}) {
    EXPECT_NO_THROW(read_control_set(std::string(GEOANCHOR_FIXTURES_DIR) + "/" + f, {})) << f;
  }
}

// The rows are parsed a batch at a time on several threads (issue 12 point
// 13): a file of many batches reads every mark in file order with its line,
// and of several bad rows the error named is the earliest line's, whichever
// kind it is, as a row-by-row read meets them.
TEST(ControlSet, ManyRowsKeepTheirOrderAndTheEarliestErrorIsNamed) {
  constexpr std::size_t kRows = 50000;  // several batches of lines
  const auto file = [&](const std::map<std::size_t, std::string>& bad_rows) {
    std::string text = "# source_frame = ITRF2014@2024.5\n# target_frame = ETRF2000@2024.5\n"
                       "id,x_src_m,y_src_m,z_src_m,x_dst_m,y_dst_m,z_dst_m,sigma_src_m,sigma_dst_m\n";
    for (std::size_t i = 0; i < kRows; ++i) {
      if (const auto b = bad_rows.find(i); b != bad_rows.end()) {
        text += b->second + "\n";
        continue;
      }
      if (i % 1000 == 7) text += "# a comment between rows\n";
      const double x = 4271315.0 + static_cast<double>(i) * 0.25;
      text += "M" + std::to_string(i) + "," + std::to_string(x) + ",641096.4,4678048.5," + std::to_string(x + 0.5) +
              ",641096.9,4678048.1,0.003,0.003\n";
    }
    return text;
  };
  std::istringstream in(file({}));
  const auto set = read_control_csv(in, "big.csv", {});
  ASSERT_EQ(set.points.size(), kRows);
  std::size_t line = 3;  // two comments and the header come first
  for (std::size_t i = 0; i < kRows; ++i) {
    if (i % 1000 == 7) ++line;
    ++line;
    ASSERT_EQ(set.points[i].id, "M" + std::to_string(i)) << i;
    ASSERT_EQ(set.points[i].line, line) << i;
    ASSERT_EQ(set.points[i].source.m.x(), 4271315.0 + static_cast<double>(i) * 0.25) << i;
  }
  // The line of row i when no row is replaced: the header is line 3, a
  // comment precedes rows 7, 1007, ...
  const auto line_of = [](std::size_t i) { return std::to_string(4 + i + (i + 993) / 1000); };
  const std::string bad_number = "B,4271315.0,x,4678048.5,4271315.5,641096.9,4678048.1,0.003,0.003";
  const std::string bad_count = "B,4271315.0,641096.4";
  const std::string not_utf8 = "B\xE9,4271315.0,641096.4,4678048.5,4271315.5,641096.9,4678048.1,0.003,0.003";
  struct Case {
    std::map<std::size_t, std::string> rows;
    std::string code;
    std::size_t first;
  };
  for (const Case& c : {Case{{{30000, bad_number}, {41000, not_utf8}}, "E_VALUE", 30000},
                        Case{{{30000, not_utf8}, {41000, bad_number}}, "E_CSV_NOT_UTF8", 30000},
                        Case{{{9000, bad_count}, {9001, bad_number}}, "E_CSV_FIELDS", 9000},
                        Case{{{9001, bad_count}, {9000, not_utf8}}, "E_CSV_NOT_UTF8", 9000},
                        Case{{{20000, bad_number}, {1000, not_utf8}, {40000, bad_count}}, "E_CSV_NOT_UTF8", 1000},
                        Case{{{kRows - 1, bad_number}, {kRows - 2, bad_count}}, "E_CSV_FIELDS", kRows - 2}}) {
    const auto [code, message] = read_error(file(c.rows), "big.csv", {});
    EXPECT_EQ(code, c.code) << message;
    EXPECT_EQ(message.rfind("big.csv:" + line_of(c.first) + ": ", 0), 0u) << "row " << c.first << ": " << message;
  }
}

TEST(ControlSet, ADuplicateIdAmongManyRowsIsNamedAtItsFirstRepeat) {
  // Enough rows that the ids are checked in two halves at once: a repeat of
  // a first-half id in the second half, and a later pair within the second
  // half; the message names the repeat that comes first in the file.
  constexpr std::size_t kRows = 100000;
  const auto file = [&](const std::map<std::size_t, std::size_t>& repeats) {  // row -> the row whose id it repeats
    std::string text = "# source_frame = ITRF2014@2024.5\n# target_frame = ETRF2000@2024.5\n"
                       "id,x_src_m,y_src_m,z_src_m,x_dst_m,y_dst_m,z_dst_m,sigma_src_m,sigma_dst_m\n";
    for (std::size_t i = 0; i < kRows; ++i) {
      const auto r = repeats.find(i);
      const double x = 4271315.0 + static_cast<double>(i) * 0.25;
      text += "M" + std::to_string(r == repeats.end() ? i : r->second) + "," + std::to_string(x) + ",641096.4,4678048.5," +
              std::to_string(x + 0.5) + ",641096.9,4678048.1,0.003,0.003\n";
    }
    return text;
  };
  const auto line_of = [](std::size_t i) { return std::to_string(4 + i); };  // the header is line 3
  struct Case {
    std::map<std::size_t, std::size_t> repeats;
    std::size_t repeat, first;
  };
  for (const Case& c : {Case{{{90000, 12}, {70000, 60000}}, 70000, 60000},
                        Case{{{60001, 3}, {99999, 60002}}, 60001, 3},
                        Case{{{49999, 7}, {50000, 49998}}, 49999, 7}}) {
    const auto [code, message] = read_error(file(c.repeats), "big.csv", {});
    EXPECT_EQ(code, "E_DUPLICATE_ID") << message;
    EXPECT_EQ(message.rfind("big.csv:" + line_of(c.repeat) + ": id=M" + std::to_string(c.first) + ": duplicate of line " +
                                line_of(c.first),
                            0),
              0u)
        << message;
  }
}

}  // namespace
// issue 13 point 5: the ellipsoid comes from each frame. Geodetic values in
// ITRF2014 are on GRS80 and those in WGS 84 (G2139) on WGS84, each checked
// against PROJ's cart on that ellipsoid; a set that names no frame stays on
// WGS84; --ellipsoid that contradicts a frame whose values use it is refused
// naming both, and one that agrees is taken.
TEST(ControlSet, Issue13_Point5_TheEllipsoidComesFromEachFrame) {
  constexpr double kVsProjTol_m = 1e-6;
  const std::string body =
      "id,lat_src_deg,lon_src_deg,h_src_m,lat_dst_deg,lon_dst_deg,h_dst_m\n"
      "P1,47.4834644617,8.5283688582,443.8311,47.4834644,8.5283689,443.8\n";
  const std::string framed = "# source_frame = ITRF2014@2024.5\n# target_frame = WGS84(G2139)@2024.5\n" + body;
  const testing::ProjPipeline grs80("+proj=cart +ellps=GRS80"), wgs84("+proj=cart +ellps=WGS84");
  const Eigen::Vector3d src(testing::proj_radians(8.5283688582), testing::proj_radians(47.4834644617), 443.8311);
  const Eigen::Vector3d dst(testing::proj_radians(8.5283689), testing::proj_radians(47.4834644), 443.8);
  ControlReadOptions o;
  std::istringstream in(framed);
  const auto set = read_control_csv(in, "c.csv", o);
  EXPECT_EQ(set.source_input.ellipsoid, geodesy::Ellipsoid::grs80());
  EXPECT_EQ(set.target_input.ellipsoid, geodesy::Ellipsoid::wgs84());
  EXPECT_LT((set.points[0].source.m - grs80.forward(src)).norm(), kVsProjTol_m);
  EXPECT_LT((set.points[0].target.m - wgs84.forward(dst)).norm(), kVsProjTol_m);
  // The GRS80 and WGS84 positions of one point differ by 0.1 mm here: the
  // check above tells them apart (1e-6 m).
  EXPECT_GT((grs80.forward(src) - wgs84.forward(src)).norm(), 100 * kVsProjTol_m);

  std::istringstream bare(body);
  const auto unnamed = read_control_csv(bare, "c.csv", o);
  EXPECT_EQ(unnamed.source_input.ellipsoid, geodesy::Ellipsoid::wgs84());

  ControlReadOptions given;
  given.ellipsoid = geodesy::Ellipsoid::wgs84();
  const auto [code, message] = read_error(framed, "c.csv", given);
  EXPECT_EQ(code, "E_ELLIPSOID");
  EXPECT_NE(message.find("--ellipsoid WGS84 contradicts the source frame ITRF2014@2024.5, which is on GRS80"),
            std::string::npos)
      << message;
  // A caller's frame replaces the file's and its ellipsoid follows.
  ControlReadOptions replaced;
  replaced.source_frame.replace = geodesy::Frame::parse("WGS84(G2139)@2024.5", "test");
  std::istringstream again(framed);
  EXPECT_EQ(read_control_csv(again, "c.csv", replaced).source_input.ellipsoid, geodesy::Ellipsoid::wgs84());
}

// issue 13: a JSON control set reads a CRS as the CSV does (--src-crs, or
// its "source_crs" key), and a covariance given in the CRS's axes (m²) is
// carried into ECEF by the conversion's Jacobian. The reference: PROJ's
// own pipeline for UTM 32N on WGS84, and the test's own central
// differences through it (a tenth of geoanchor's step).
TEST(ControlSet, Issue13_JsonReadsACrsAndCarriesItsCovariance) {
  constexpr double kVsProjTol_m = 1e-6;
  // Relative to the largest entry: both Jacobians are differences of ECEF
  // values near 6e6 m (ulp 1e-9 m) over steps under a metre, so they agree
  // to about 1e-9; a Jacobian without UTM's scale (0.9996) is 4e-4 off.
  constexpr double kCovarianceTol = 1e-8;
  constexpr double kTestStep_m = 0.5;
  const testing::ProjPipeline utm("+proj=pipeline +step +inv +proj=utm +zone=32 +ellps=WGS84 +step +proj=cart +ellps=WGS84");
  const Eigen::Vector3d at(464998.123, 5258862.456, 480.0);
  Eigen::Matrix3d c;  // grid east, grid north, up (m²)
  c << 4e-6, 1e-6, 5e-7, 1e-6, 9e-6, -2e-7, 5e-7, -2e-7, 2.5e-5;
  const std::string json = R"J({"source_crs": "EPSG:32632", "points": [
    {"id": "A", "source": {"easting_m": 464998.123, "northing_m": 5258862.456, "h_m": 480.0},
     "target": {"x_m": 4271315.7, "y_m": 641096.4, "z_m": 4678048.5},
     "cov_src_m2": [[4e-6, 1e-6, 5e-7], [1e-6, 9e-6, -2e-7], [5e-7, -2e-7, 2.5e-5]], "sigma_dst_m": 0.01},
    {"id": "B", "source": {"easting_m": 465998.123, "northing_m": 5259862.456, "h_m": 481.0},
     "target": {"x_m": 4270315.7, "y_m": 642096.4, "z_m": 4678848.5}, "sigma_src_m": 0.002, "sigma_dst_m": 0.01}]})J";
  ControlReadOptions o;
  std::istringstream in(json);
  const auto set = read_control_json(in, "c.json", o);
  ASSERT_EQ(set.points.size(), 2u);
  EXPECT_EQ(set.source_input.form, geodesy::CoordinateForm::crs);
  EXPECT_LT((set.points[0].source.m - utm.forward(at)).norm(), kVsProjTol_m);
  Eigen::Matrix3d j;
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d step = Eigen::Vector3d::Zero();
    step(k) = kTestStep_m;
    j.col(k) = (utm.forward(at + step) - utm.forward(at - step)) / (2.0 * kTestStep_m);
  }
  const Eigen::Matrix3d expected = j * c * j.transpose();
  EXPECT_LT(testing::max_abs_component(set.points[0].source_cov_m2 - expected), kCovarianceTol * testing::max_abs_component(expected))
      << set.points[0].source_cov_m2 << "\nexpected\n" << expected;
  // An isotropic sigma stays isotropic.
  EXPECT_LT(testing::max_abs_component(set.points[1].source_cov_m2 - Eigen::Matrix3d::Identity() * 4e-6), 1e-18);

  // The CSV reads the same covariance the same way.
  const std::string csv =
      "# source_crs = EPSG:32632\n"
      "id,easting_src_m,northing_src_m,h_src_m,x_dst_m,y_dst_m,z_dst_m,cov_src_xx_m2,cov_src_xy_m2,cov_src_xz_m2,"
      "cov_src_yy_m2,cov_src_yz_m2,cov_src_zz_m2\n"
      "A,464998.123,5258862.456,480.0,4271315.7,641096.4,4678048.5,4e-6,1e-6,5e-7,9e-6,-2e-7,2.5e-5\n";
  std::istringstream cin(csv);
  const auto from_csv = read_control_csv(cin, "c.csv", o);
  EXPECT_LT(testing::max_abs_component(from_csv.points[0].source_cov_m2 - expected), kCovarianceTol * testing::max_abs_component(expected));

  // A key that is not the CRS's is refused with its path.
  std::string wrong = json;
  wrong.replace(wrong.find("\"h_m\": 480.0"), 12, "\"z_m\": 480.0");
  std::istringstream win(wrong);
  try {
    (void)read_control_json(win, "c.json", o);
    ADD_FAILURE() << "a key that is not the CRS's was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("c.json: points[0].source"), std::string::npos) << e.what();
  }
  // --src-crs that contradicts the file's source_crs is refused.
  ControlReadOptions other;
  other.src_crs = Crs::parse("EPSG:25832", "--src-crs");
  std::istringstream oin(json);
  try {
    (void)read_control_json(oin, "c.json", other);
    ADD_FAILURE() << "a contradicting --src-crs was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_CRS_CONFLICT") << e.what();
  }
}


// A covariance in a geographic CRS is in ground metres east, north and up
// (the columns' order, longitude first, whatever the CRS's own axis order),
// carried into ECEF by the local east/north/up directions at the mark:
// checked against GeographicLib's Geocentric rotation, at 47°N, within
// a centimetre of the north pole, at both poles and on the antimeridian,
// where a finite step in latitude would leave the CRS.
TEST(ControlSet, Issue13_AGeographicCovarianceIsCarriedAtThePoles) {
  // The up column is a central difference of ECEF values near 6.4e6 m (ulp
  // 9.3e-10 m) over 2 m, so about 5e-10 relative, on entries up to 9e-4 m²;
  // east and north are exact. A swap of east and north is 3e-4 m² off.
  constexpr double kCovarianceTol_m2 = 1e-11;
  Eigen::Matrix3d c;  // east, north, up (m²): distinct, so that a swap shows
  c << 1e-4, 2e-5, 0.0, 2e-5, 4e-4, -1e-5, 0.0, -1e-5, 9e-4;
  const double marks[][2] = {{47.46, 8.55}, {89.9999999, 30.0}, {90.0, 45.0}, {-90.0, -120.0}, {-33.0, 180.0}};
  std::string csv = "# source_crs = EPSG:4979\n"
                    "id,lat_src_deg,lon_src_deg,h_src_m,x_dst_m,y_dst_m,z_dst_m,cov_src_xx_m2,cov_src_xy_m2,cov_src_xz_m2,"
                    "cov_src_yy_m2,cov_src_yz_m2,cov_src_zz_m2,sigma_dst_m\n";
  for (std::size_t i = 0; i < std::size(marks); ++i) {
    std::ostringstream row;
    row.precision(12);
    row << "P" << i << "," << marks[i][0] << "," << marks[i][1] << ",100.0,0,0,6378137,1e-4,2e-5,0,4e-4,-1e-5,9e-4,0.01\n";
    csv += row.str();
  }
  std::istringstream in(csv);
  const auto set = read_control_csv(in, "c.csv", {});
  ASSERT_EQ(set.points.size(), std::size(marks));
  for (std::size_t i = 0; i < std::size(marks); ++i) {
    double x = 0, y = 0, z = 0;
    std::vector<double> m(9);
    // m: local east, north, up at the mark -> geocentric, row-major
    GeographicLib::Geocentric::WGS84().Forward(marks[i][0], marks[i][1], 100.0, x, y, z, m);
    Eigen::Matrix3d r;
    r << m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8];
    const Eigen::Matrix3d expected = r * c * r.transpose();
    const double worst = testing::max_abs_component(set.points[i].source_cov_m2 - expected);
    EXPECT_LE(worst, kCovarianceTol_m2) << "mark " << i << "\n" << set.points[i].source_cov_m2 << "\nexpected\n" << expected;
  }
  // The record of how they were read counts the marks, not the neighbours
  // the Jacobian's height column was differenced with.
  const auto record = nlohmann::json::parse(set.source_input.crs_record_json);
  EXPECT_EQ(record["operation"]["candidates"][0]["points"], std::size(marks));

  // NTF (Paris), EPSG:4807: grads, latitude first, longitudes from the
  // Paris meridian (2.5969213 grad east of Greenwich, EPSG:8903).
  constexpr double kParis_deg = 2.5969213 * 0.9;
  const double paris_marks[][2] = {{53.0, 0.5}, {51.2, -3.1}};  // grads
  std::string ntf = "# source_crs = EPSG:4807\n"
                    "id,lat_src_grad,lon_src_grad,h_src_m,x_dst_m,y_dst_m,z_dst_m,cov_src_xx_m2,cov_src_xy_m2,cov_src_xz_m2,"
                    "cov_src_yy_m2,cov_src_yz_m2,cov_src_zz_m2,sigma_dst_m\n";
  for (std::size_t i = 0; i < std::size(paris_marks); ++i) {
    std::ostringstream row;
    row.precision(12);
    row << "F" << i << "," << paris_marks[i][0] << "," << paris_marks[i][1]
        << ",100.0,0,0,6378137,1e-4,2e-5,0,4e-4,-1e-5,9e-4,0.01\n";
    ntf += row.str();
  }
  std::istringstream nin(ntf);
  const auto paris = read_control_csv(nin, "ntf.csv", {});
  for (std::size_t i = 0; i < std::size(paris_marks); ++i) {
    double x = 0, y = 0, z = 0;
    std::vector<double> m(9);
    GeographicLib::Geocentric::WGS84().Forward(paris_marks[i][0] * 0.9, paris_marks[i][1] * 0.9 + kParis_deg, 100.0, x, y, z, m);
    Eigen::Matrix3d r;
    r << m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8];
    const Eigen::Matrix3d expected = r * c * r.transpose();
    // geoanchor's ECEF has its X axis through Greenwich (PROJ's geocentric
    // CRS of NTF (Paris) has it through Paris: 2.34°, 170 km here). PROJ's
    // own Paris meridian (2°20'14.025") is 3e-9° from EPSG's 2.5969213 grad.
    constexpr double kMeridian_m = 5e-4;
    const GeographicLib::Geocentric clarke_ign(6378249.2, 1.0 / 293.466021293627);  // Clarke 1880 (IGN), EPSG:7011
    double gx = 0, gy = 0, gz = 0;
    clarke_ign.Forward(paris_marks[i][0] * 0.9, paris_marks[i][1] * 0.9 + kParis_deg, 100.0, gx, gy, gz);
    EXPECT_LE((paris.points[i].source.m - Eigen::Vector3d(gx, gy, gz)).norm(), kMeridian_m) << "NTF mark " << i;
    EXPECT_LE(testing::max_abs_component(paris.points[i].source_cov_m2 - expected), kCovarianceTol_m2)
        << "NTF mark " << i << "\n" << paris.points[i].source_cov_m2 << "\nexpected\n" << expected;
  }
}


// issue 13 point 5: a role read through a CRS is on the CRS's ellipsoid and
// frame: MGA zone 56 (GDA2020, GRS80) in JSON and CSV; --source-frame may
// add the observation epoch to a static frame, never name another frame.
TEST(ControlSet, Issue13_ACrsRoleKeepsItsEllipsoidAndFrame) {
  const std::string json = R"J({"source_crs": "EPSG:7856", "target_crs": "EPSG:7856", "points": [
    {"id": "A", "source": {"easting_m": 334000.0, "northing_m": 6252000.0, "h_m": 40.0},
     "target": {"easting_m": 334000.1, "northing_m": 6252000.1, "h_m": 40.1}}]})J";
  const std::string csv = "# source_crs = EPSG:7856\n# target_crs = EPSG:7856\n"
                          "id,easting_src_m,northing_src_m,h_src_m,easting_dst_m,northing_dst_m,h_dst_m\n"
                          "A,334000.0,6252000.0,40.0,334000.1,6252000.1,40.1\n";
  auto read = [&](bool as_json, const ControlReadOptions& o) {
    std::istringstream in(as_json ? json : csv);
    return as_json ? read_control_json(in, "c.json", o) : read_control_csv(in, "c.csv", o);
  };
  for (const bool as_json : {true, false}) {
    SCOPED_TRACE(as_json ? "json" : "csv");
    const auto set = read(as_json, ControlReadOptions{});
    EXPECT_TRUE(set.source_input.ellipsoid == geodesy::Ellipsoid::grs80()) << set.source_input.ellipsoid.name();
    EXPECT_TRUE(set.target_input.ellipsoid == geodesy::Ellipsoid::grs80()) << set.target_input.ellipsoid.name();
    ASSERT_TRUE(set.source_frame.has_value());
    EXPECT_EQ(set.source_frame->name(), "GDA2020");

    ControlReadOptions dated;
    dated.source_frame.replace = geodesy::Frame::parse("GDA2020@2024.5", "--source-frame");
    EXPECT_EQ(read(as_json, dated).source_frame->to_string(), "GDA2020@2024.5");

    ControlReadOptions other;
    other.source_frame.replace = geodesy::Frame::parse("ITRF2014@2024.5", "--source-frame");
    try {
      (void)read(as_json, other);
      ADD_FAILURE() << "--source-frame that contradicts the CRS was accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), "E_FRAME_CONFLICT") << e.what();
      EXPECT_NE(std::string(e.what()).find("--source-frame ITRF2014@2024.5 contradicts the source CRS 'GDA2020 / MGA zone 56', whose frame is GDA2020"),
                std::string::npos)
          << e.what();
    }
  }
}

}  // namespace geoanchor::io
