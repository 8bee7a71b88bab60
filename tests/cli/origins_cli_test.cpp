// Issue 40 point 3: convert compares the ENU origin it is given with the
// one a local transform was fitted at (or takes the transform's), and
// refuses points that land farther from a local origin, or outside the
// transform's control network, than --max-extrapolation.

#include <GeographicLib/LocalCartesian.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <sstream>

#include "cli_support.hpp"
#include "test_support.hpp"

namespace geoanchor {
namespace {

namespace fs = std::filesystem;
using testing::CliTest;
using testing::slurp;

constexpr double kVsGeographicLib_deg = 1e-10;  // about 0.01 mm of arc
constexpr double kVsGeographicLib_m = 1e-6;

// An enu-origin correction that moves nothing, so that the result is
// GeographicLib's ENU -> geodetic at the nominal origin; and one that moves.
const char* kIdentityEnuOrigin = R"({"model": "enu-origin",
  "nominal_origin": {"lat_deg": 47.4647, "lon_deg": 8.5492, "h_m": 480.05, "height_type": "ellipsoidal", "ellipsoid": "WGS84"},
  "parameters": {"shift_e_m": 0, "shift_n_m": 0, "shift_u_m": 0, "yaw_arcsec": 0, "ds_ppm": 0}})";
const char* kSiteCalibration = R"({"model": "site-calibration",
  "nominal_origin": {"lat_deg": 46.6, "lon_deg": 7.4, "h_m": 600, "height_type": "ellipsoidal", "ellipsoid": "GRS80"},
  "grid": {"lat0_deg": 46.5, "lon0_deg": 7.5, "k0": 1, "false_easting_m": 0, "false_northing_m": 0, "ellipsoid": "GRS80"},
  "parameters": {"shift_e_m": 500, "shift_n_m": -300, "rotation_arcsec": 126000, "scale_ppm": 45, "vertical_shift_m": 48.2,
                 "slope_n_ppm": 0, "slope_e_ppm": 0, "centroid_e_m": 0, "centroid_n_m": 0}})";

class Origins : public CliTest {};

std::vector<double> first_row(const std::string& csv) {
  std::istringstream in(csv);
  std::string line;
  while (std::getline(in, line) && (line.empty() || line[0] == '#')) {
  }
  std::getline(in, line);
  std::vector<double> v;
  std::stringstream row(line);
  std::string cell;
  std::getline(row, cell, ',');  // id
  while (std::getline(row, cell, ',')) v.push_back(std::stod(cell));
  return v;
}

TEST_F(Origins, Issue40_ALocalTransformsOriginIsTakenOrCompared) {
  const auto t = write("t.json", kIdentityEnuOrigin);
  const auto in = write("map.csv", "id,e_m,n_m,u_m\nA,100,200,5\n");
  // Without --origin: the transform's.
  const auto r = run("convert " + in.string() + " --to geodetic --transform " + t.string() + " -o " + path("taken.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("origin is the transform's"), std::string::npos) << r.err;
  double lat = 0, lon = 0, h = 0;
  GeographicLib::LocalCartesian(47.4647, 8.5492, 480.05, GeographicLib::Geocentric::WGS84()).Reverse(100, 200, 5, lat, lon, h);
  const auto got = first_row(slurp(path("taken.csv")));
  ASSERT_EQ(got.size(), 3u);
  EXPECT_NEAR(got[0], lat, kVsGeographicLib_deg);
  EXPECT_NEAR(got[1], lon, kVsGeographicLib_deg);
  EXPECT_NEAR(got[2], h, kVsGeographicLib_m);
  // The same origin within 1 mm (0.5 mm up): accepted.
  const auto same = run("convert " + in.string() + " --to geodetic --origin 47.4647,8.5492,480.0505 --transform " + t.string() +
                        " -o " + path("same.csv").string());
  EXPECT_EQ(same.exit_code, 0) << same.err;
  // Another origin: refused naming both and the distance, nothing written.
  const auto other = run("convert " + in.string() + " --to geodetic --origin 47.0,8.0,480 --transform " + t.string() + " -o " +
                         path("other.csv").string());
  EXPECT_EQ(other.exit_code, 2) << other.err;
  EXPECT_NE(other.err.find("E_ORIGIN_MISMATCH"), std::string::npos) << other.err;
  EXPECT_NE(other.err.find("47.000000000,8.000000000"), std::string::npos) << other.err;
  EXPECT_NE(other.err.find("47.464700000,8.549200000"), std::string::npos) << other.err;
  EXPECT_NE(other.err.find(" m from it"), std::string::npos) << other.err;
  EXPECT_FALSE(fs::exists(path("other.csv")));
  // With --inverse the transform's source side is the output.
  const auto inverse = run("convert " + path("taken.csv").string() + " --to enu --origin 47.0,8.0,480 --inverse --transform " +
                           t.string() + " -o " + path("inverse.csv").string());
  EXPECT_EQ(inverse.exit_code, 2) << inverse.err;
  EXPECT_NE(inverse.err.find("E_ORIGIN_MISMATCH"), std::string::npos) << inverse.err;
  EXPECT_FALSE(fs::exists(path("inverse.csv")));
  // A site calibration's local origin, likewise.
  const auto cal = write("cal.json", kSiteCalibration);
  const auto cal_other = run("convert " + in.string() + " --to geodetic --origin 46.61,7.4,600 --ellipsoid GRS80 --transform " +
                             cal.string() + " -o " + path("cal.csv").string());
  EXPECT_EQ(cal_other.exit_code, 2) << cal_other.err;
  EXPECT_NE(cal_other.err.find("site calibration"), std::string::npos) << cal_other.err;
  EXPECT_FALSE(fs::exists(path("cal.csv")));
}

TEST_F(Origins, Issue40_PointsFarFromTheOriginAreRefused) {
  // The second row has latitude and longitude swapped: about 4 900 km away.
  const auto in = write("pts.csv", "id,lat_deg,lon_deg,h_m\nA,47.4650,8.5500,480\nB,8.5500,47.4650,480\n");
  const auto r = run("convert " + in.string() + " --to enu --origin 47.464722,8.549167,480 -o " + path("out.csv").string());
  EXPECT_EQ(r.exit_code, 4) << r.err;
  EXPECT_NE(r.err.find("E_EXTRAPOLATION"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("pts.csv:3"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("swapped"), std::string::npos) << r.err;
  EXPECT_EQ(leftovers({"pts.csv"}), std::vector<std::string>{});
  // Farther than the tangent plane serves (5.6 km: 2.5 m below it) but inside the limit: a warning.
  const auto far = write("far.csv", "id,lat_deg,lon_deg,h_m\nA,47.5150,8.5500,480\n");
  const auto w = run("convert " + far.string() + " --to enu --origin 47.464722,8.549167,480 -o " + path("far_out.csv").string());
  ASSERT_EQ(w.exit_code, 0) << w.err;
  EXPECT_NE(w.err.find("tangent plane departs from the ellipsoid"), std::string::npos) << w.err;
  // The limit is the user's.
  const auto tight = run("convert " + far.string() + " --to enu --origin 47.464722,8.549167,480 --max-extrapolation 1000 -o " +
                         path("tight.csv").string());
  EXPECT_EQ(tight.exit_code, 4) << tight.err;
  EXPECT_FALSE(fs::exists(path("tight.csv")));
}

// Issue 40 point 10: a height or a geocentric position off the Earth (a
// placeholder 1e308, a unit slip) is refused wherever a coordinate enters:
// an origin flag, a CSV row, a control set, a network, a transform file.
// apply measures its tiles from an ENU/NED origin as convert does: a
// swapped --origin (the LSZH tile 4 943 km away) and a local tile 50 km
// from its own origin are refused past --max-extrapolation, nothing
// written; within a raised limit the tile is moved, with a tangent-plane
// warning (d = 50 km: d²/2R = 196 m).
TEST_F(Origins, Issue40_ApplyRefusesTilesFarFromAnEnuOrigin) {
  const fs::path tile = fs::path(GEOANCHOR_SOURCE_DIR) / "fixtures" / "airport_tile.las";
  const auto swapped = run("apply " + tile.string() + " --to enu --origin 8.549167,47.464722,480 --out-dir " + path("swapped").string());
  EXPECT_EQ(swapped.exit_code, 4) << swapped.err;
  EXPECT_NE(swapped.err.find("E_EXTRAPOLATION"), std::string::npos) << swapped.err;
  EXPECT_NE(swapped.err.find("from the output's ENU/NED origin 8.549167000, 47.464722000"), std::string::npos) << swapped.err;
  EXPECT_FALSE(fs::exists(path("swapped/airport_tile.las")));
  const auto far = write("far_enu.csv", "id,e_m,n_m,u_m\nA,50000,0,0\nB,50010,0,0\n");
  const std::string args = far.string() + " --from-frame ITRF2014@2024.5 --from-origin 47.46,8.55,480 --to geodetic --out-dir ";
  const auto refused = run("apply " + args + path("far").string());
  EXPECT_EQ(refused.exit_code, 4) << refused.err;
  EXPECT_NE(refused.err.find("lie up to 50.010 km from the input's ENU/NED origin"), std::string::npos) << refused.err;
  EXPECT_FALSE(fs::exists(path("far/far_enu.csv")));
  const auto allowed = run("apply " + args + path("allowed").string() + " --max-extrapolation 60000");
  EXPECT_EQ(allowed.exit_code, 0) << allowed.err;
  EXPECT_NE(allowed.err.find("the tangent plane departs 196.005 m"), std::string::npos) << allowed.err;
}

// A flag convert reads on no side is said, as an unused --epoch is (a
// --from-origin on geodetic input was dropped without a word).
TEST_F(Origins, Issue40_ConvertSaysWhichFlagsItDoesNotUse) {
  const auto geo = write("geo.csv", "id,lat_deg,lon_deg,h_m\nA,47.4,8.5,400\n");
  const auto from_origin = run("convert " + geo.string() + " --to ecef --from-origin 40,8,0 -o " + path("a.csv").string());
  EXPECT_EQ(from_origin.exit_code, 0) << from_origin.err;
  EXPECT_NE(from_origin.err.find("--from-origin: the input has no ENU/NED columns, so it is not used"), std::string::npos)
      << from_origin.err;
  const auto zone = run("convert " + geo.string() + " --to ecef --zone 32N -o " + path("b.csv").string());
  EXPECT_EQ(zone.exit_code, 0) << zone.err;
  EXPECT_NE(zone.err.find("--zone: neither the input nor the output is UTM, so it is not used"), std::string::npos) << zone.err;
  const auto used = run("convert " + geo.string() + " --to enu --origin 47.4,8.5,400 -o " + path("c.csv").string());
  EXPECT_EQ(used.exit_code, 0) << used.err;
  EXPECT_EQ(used.err.find("not used"), std::string::npos) << used.err;
}

TEST_F(Origins, Issue40_HeightsAndRadiiOffTheEarthAreRefused) {
  const auto pts = write("pts.csv", "id,lat_deg,lon_deg,h_m\nA,47.4650,8.5500,480\n");
  const auto origin = run("convert " + pts.string() + " --to enu --origin 47.4,8.5,1e308 -o " + path("o.csv").string());
  EXPECT_EQ(origin.exit_code, 2) << origin.err;
  EXPECT_NE(origin.err.find("E_HEIGHT_RANGE"), std::string::npos) << origin.err;
  EXPECT_NE(origin.err.find("[-12000, 100000] m"), std::string::npos) << origin.err;
  EXPECT_FALSE(fs::exists(path("o.csv")));
  struct Row {
    const char* name;
    const char* csv;
    const char* code;
  };
  for (const Row& r : {Row{"h", "id,lat_deg,lon_deg,h_m\nA,47.4650,8.5500,1e308\n", "E_HEIGHT_RANGE"},
                       Row{"feet_as_km", "id,lat_deg,lon_deg,h_m\nA,47.4650,8.5500,-480000\n", "E_HEIGHT_RANGE"},
                       Row{"ecef", "id,x_m,y_m,z_m\nA,1,2,3\n", "E_ECEF_RANGE"},
                       Row{"enu", "id,e_m,n_m,u_m\nA,0,0,1e9\n", "E_ECEF_RANGE"},
                       // Inside the radii of the ellipsoid, off the Earth all the same: heights -19.5 km,
                       // -28.1 km (the equator, 6 350 km from the centre) and +113 km (a pole).
                       Row{"enu_deep", "id,e_m,n_m,u_m\nA,350,-200,-20000\n", "E_ECEF_RANGE"},
                       Row{"ecef_equator", "id,x_m,y_m,z_m\nA,6350000,0,0\n", "E_ECEF_RANGE"},
                       Row{"ecef_pole", "id,x_m,y_m,z_m\nA,0,0,6470000\n", "E_ECEF_RANGE"}}) {
    const auto in = write(std::string(r.name) + ".csv", r.csv);
    const auto run_result = run("convert " + in.string() + " --to ecef --origin 47.4,8.5,400 -o " + path("out.csv").string());
    EXPECT_EQ(run_result.exit_code, 3) << r.name << ": " << run_result.err;
    EXPECT_NE(run_result.err.find(r.code), std::string::npos) << r.name << ": " << run_result.err;
    EXPECT_NE(run_result.err.find(std::string(r.name) + ".csv:2"), std::string::npos) << run_result.err;
    EXPECT_FALSE(fs::exists(path("out.csv")));
  }
  // A control set and a transform file's origin.
  const auto control = write("control.csv",
                             "# source_frame = ITRF2014@2024.5\n# target_frame = ITRF2014@2024.5\n"
                             "id,lat_src_deg,lon_src_deg,h_src_m,lat_dst_deg,lon_dst_deg,h_dst_m,sigma_src_m,sigma_dst_m\n"
                             "A,47.40,8.50,400,47.40,8.50,400.01,0.01,0.01\nB,47.41,8.50,400,47.41,8.50,400.01,0.01,0.01\n"
                             "C,47.40,8.51,1e308,47.40,8.51,400.01,0.01,0.01\nD,47.41,8.51,400,47.41,8.51,400.01,0.01,0.01\n");
  const auto fit = run("fit " + control.string() + " --model translation3 -o " + path("t.json").string());
  EXPECT_EQ(fit.exit_code, 3) << fit.err;
  EXPECT_NE(fit.err.find("control.csv:6"), std::string::npos) << fit.err;
  EXPECT_FALSE(fs::exists(path("t.json")));
  // A mark 20 km below the ellipsoid (within its radii at 47°): refused before the solve.
  std::string deep = slurp(control);
  deep.replace(deep.find("1e308"), 5, "400");
  deep.replace(deep.rfind("400.01"), 6, "-20000");
  const auto deep_control = write("deep.csv", deep);
  const auto deep_fit = run("fit " + deep_control.string() + " --model translation3 -o " + path("d.json").string());
  EXPECT_EQ(deep_fit.exit_code, 3) << deep_fit.err;
  EXPECT_NE(deep_fit.err.find("deep.csv:7: D: its target geocentric position"), std::string::npos) << deep_fit.err;
  EXPECT_NE(deep_fit.err.find("ellipsoidal height -20000.000 m"), std::string::npos) << deep_fit.err;
  EXPECT_FALSE(fs::exists(path("d.json")));
  std::string t = kIdentityEnuOrigin;
  t.replace(t.find("480.05"), 6, "1e308");
  const auto bad_t = write("bad_t.json", t);
  const auto map = write("map.csv", "id,e_m,n_m,u_m\nA,100,200,5\n");
  const auto applied = run("convert " + map.string() + " --to geodetic --transform " + bad_t.string() + " -o " + path("m.csv").string());
  EXPECT_EQ(applied.exit_code, 3) << applied.err;
  EXPECT_NE(applied.err.find("nominal_origin.h_m"), std::string::npos) << applied.err;
  EXPECT_FALSE(fs::exists(path("m.csv")));
}

// Issue 40 point 11: a tile of the very marks a transform was fitted to
// lies inside its control network: apply measures every point, not the
// bounding box (whose corners put it 1991.8 m outside).
TEST_F(Origins, Issue40_ATileOfTheControlMarksIsInsideItsNetwork) {
  const fs::path control = fs::path(GEOANCHOR_SOURCE_DIR) / "fixtures" / "airport_control.csv";
  const auto fit = run("fit " + control.string() + " --model helmert7 --convention position_vector --remove-outliers -o " +
                       path("t.json").string());
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  // The marks the fit used (P17, the planted blunder, removed), as a tile in the source frame.
  std::istringstream in(slurp(control));
  std::string line, tile = "lat_deg,lon_deg,h_m\n";
  bool header = false;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (!header) {
      header = true;
      continue;
    }
    std::stringstream row(line);
    std::string id, lat, lon, h;
    std::getline(row, id, ',');
    std::getline(row, lat, ',');
    std::getline(row, lon, ',');
    std::getline(row, h, ',');
    if (id != "P17") tile += lat + "," + lon + "," + h + "\n";
  }
  write("in/marks.csv", tile);
  write("in/marks.csv.geoanchor.json",
        R"({"schema": "geoanchor.tile/1", "frame": "ITRF2014@2024.5", "coordinates": {"kind": "geodetic", "ellipsoid": "GRS80",
        "storage": "float64"}, "vertical": {"datum": "ellipsoid GRS80", "height_type": "ellipsoidal"}})");
  const auto r = run("apply " + path("in/marks.csv").string() + " --transform " + path("t.json").string() + " --out-dir " +
                     path("out").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("outside the control network"), std::string::npos) << r.err;
  const auto side = nlohmann::json::parse(slurp(path("out/marks.csv.geoanchor.json")));
  EXPECT_LT(side["provenance"]["extrapolation"]["distance_outside_control_m"].get<double>(), 1e-3) << side["provenance"];
}

}  // namespace
}  // namespace geoanchor
