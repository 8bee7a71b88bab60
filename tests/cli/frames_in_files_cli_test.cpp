// Issue 40 point 9: frames stated in files are honoured. A transform file
// whose dynamic frame names no epoch is refused as fit would refuse to
// write it; convert takes the ellipsoid from a frame the input states and
// writes the output's frame, not a copy of the input's; a tile on the WGS 84
// ensemble is warned of in apply as in fit.

#include <GeographicLib/Geocentric.hpp>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>

#include "cli_support.hpp"

namespace geoanchor {
namespace {

namespace fs = std::filesystem;
using testing::CliTest;
using testing::slurp;

constexpr double kVsGeographicLib_m = 1e-6;

class FramesInFiles : public CliTest {};

TEST_F(FramesInFiles, Issue40_ADynamicFrameWithoutItsEpochInATransformFileIsRefused) {
  const auto in = write("in.csv", "# frame = ITRF2014@2020.0\nid,x_m,y_m,z_m\nA,4270000,640000,4680000\n");
  const auto t = write("t.json", R"({"model": "translation3", "source_frame": "ITRF2014", "target_frame": "ETRF2000",
    "parameters": {"tx_m": 0.05, "ty_m": 0.04, "tz_m": -0.09}})");
  const auto r = run("convert " + in.string() + " --to ecef --transform " + t.string() + " -o " + path("out.csv").string());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("t.json: source_frame: frame ITRF2014 is dynamic"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("ITRF2014@YYYY.Y"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("out.csv")));
  // A 14-parameter file carries its epochs: its frames need none.
  const auto t14 = write("t14.json", R"({"model": "helmert14", "convention": "position_vector", "source_frame": "ITRF2014",
    "target_frame": "ETRF2000", "reference_epoch": 2015.0, "parameters": {"tx_mm": 1, "ty_mm": 2, "tz_mm": 3, "rx_mas": 0,
    "ry_mas": 0, "rz_mas": 0, "ds_ppb": 0, "dtx_mm_per_year": 0, "dty_mm_per_year": 0, "dtz_mm_per_year": 0,
    "drx_mas_per_year": 0, "dry_mas_per_year": 0, "drz_mas_per_year": 0, "dds_ppb_per_year": 0}})");
  const auto ok = run("convert " + in.string() + " --to ecef --epoch 2020.0 --transform " + t14.string() + " -o " +
                      path("ok.csv").string());
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
}

TEST_F(FramesInFiles, Issue40_ConvertTakesTheEllipsoidFromTheStatedFrameAndWritesTheOutputsFrame) {
  const auto in = write("in.csv", "# frame = ITRF2014@2024.5\n# surveyed 2024-07-01\nid,lat_deg,lon_deg,h_m\nA,47.25,8.5,480\n");
  const auto r = run("convert " + in.string() + " --to ecef -o " + path("out.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string csv = slurp(path("out.csv"));
  EXPECT_EQ(csv.rfind("# frame = ITRF2014@2024.5\n# surveyed 2024-07-01\n", 0), 0u) << csv;
  double x = 0, y = 0, z = 0;
  GeographicLib::Geocentric(6378137.0, 1.0 / 298.257222101).Forward(47.25, 8.5, 480, x, y, z);  // GRS80 (EPSG:7019)
  std::istringstream rows(csv);
  std::string line;
  while (std::getline(rows, line) && line.rfind("A,", 0) != 0) {
  }
  double got[3];
  ASSERT_EQ(std::sscanf(line.c_str(), "A,%lf,%lf,%lf", &got[0], &got[1], &got[2]), 3) << line;
  EXPECT_NEAR(got[0], x, kVsGeographicLib_m);
  EXPECT_NEAR(got[1], y, kVsGeographicLib_m);
  EXPECT_NEAR(got[2], z, kVsGeographicLib_m);  // WGS84 is tenths of a millimetre off here: the tolerance is 1 µm
  // A flag that contradicts the frame is refused.
  const auto wgs = run("convert " + in.string() + " --to ecef --ellipsoid WGS84 -o " + path("wgs.csv").string());
  EXPECT_EQ(wgs.exit_code, 2) << wgs.err;
  EXPECT_NE(wgs.err.find("E_ELLIPSOID"), std::string::npos) << wgs.err;
  EXPECT_FALSE(fs::exists(path("wgs.csv")));
  // Through a transform the comment states the target frame; a transform from another frame is refused.
  const auto t = write("t.json", R"({"model": "translation3", "source_frame": "ITRF2014@2024.5", "target_frame": "ETRF2000",
    "parameters": {"tx_m": 0.05, "ty_m": 0.04, "tz_m": -0.09}})");
  const auto moved = run("convert " + in.string() + " --to geodetic --transform " + t.string() + " -o " + path("moved.csv").string());
  ASSERT_EQ(moved.exit_code, 0) << moved.err;
  const std::string moved_csv = slurp(path("moved.csv"));
  EXPECT_EQ(moved_csv.rfind("# frame = ETRF2000\n", 0), 0u) << moved_csv;
  EXPECT_EQ(moved_csv.find("ITRF2014"), std::string::npos) << moved_csv;
  const auto other = write("other.json", R"({"model": "translation3", "source_frame": "ITRF2020@2024.5",
    "target_frame": "ETRF2000", "parameters": {"tx_m": 0.05, "ty_m": 0.04, "tz_m": -0.09}})");
  const auto mismatch = run("convert " + in.string() + " --to geodetic --transform " + other.string() + " -o " +
                            path("mismatch.csv").string());
  EXPECT_EQ(mismatch.exit_code, 3) << mismatch.err;
  EXPECT_NE(mismatch.err.find("E_FRAME_MISMATCH"), std::string::npos) << mismatch.err;
  EXPECT_FALSE(fs::exists(path("mismatch.csv")));
}

// A 14-parameter transform is evaluated at the coordinates' epoch, which
// the input's '# frame = NAME@EPOCH' comment states: --epoch and an epoch
// column may only repeat it, and the output's dynamic frame is written at
// it. Expected: with no rotation or scale, x moves by tx(t) = tx + dtx (t −
// t0) = 1 mm + 1 mm/yr × 5 yr = 6 mm at 2020.0 (reference epoch 2015.0).
TEST_F(FramesInFiles, Issue40_AHelmert14IsEvaluatedAtTheEpochTheInputsFrameStates) {
  const auto t14 = write("t14.json", R"({"model": "helmert14", "convention": "position_vector", "source_frame": "ITRF2014",
    "target_frame": "ITRF2008", "reference_epoch": 2015.0, "parameters": {"tx_mm": 1, "ty_mm": 0, "tz_mm": 0, "rx_mas": 0,
    "ry_mas": 0, "rz_mas": 0, "ds_ppb": 0, "dtx_mm_per_year": 1, "dty_mm_per_year": 0, "dtz_mm_per_year": 0,
    "drx_mas_per_year": 0, "dry_mas_per_year": 0, "drz_mas_per_year": 0, "dds_ppb_per_year": 0}})");
  const auto in = write("in.csv", "# frame = ITRF2014@2020.0\nid,x_m,y_m,z_m\nA,4270000,640000,4680000\n");
  const auto r = run("convert " + in.string() + " --to ecef --transform " + t14.string() + " -o " + path("out.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string csv = slurp(path("out.csv"));
  EXPECT_EQ(csv.rfind("# frame = ITRF2008@2020.0\n", 0), 0u) << csv;
  double got[3];
  ASSERT_EQ(std::sscanf(csv.substr(csv.find("\nA,") + 1).c_str(), "A,%lf,%lf,%lf", &got[0], &got[1], &got[2]), 3) << csv;
  EXPECT_NEAR(got[0], 4270000.006, kVsGeographicLib_m);
  // --epoch or an epoch column that contradicts the comment: refused, nothing written.
  const auto flag = run("convert " + in.string() + " --to ecef --epoch 2021.0 --transform " + t14.string() + " -o " +
                        path("flag.csv").string());
  EXPECT_EQ(flag.exit_code, 2) << flag.err;
  EXPECT_NE(flag.err.find("E_EPOCH_CONFLICT"), std::string::npos) << flag.err;
  EXPECT_FALSE(fs::exists(path("flag.csv")));
  const auto dated = write("dated.csv", "# frame = ITRF2014@2020.0\nid,epoch,x_m,y_m,z_m\nA,2020.0,4270000,640000,4680000\n"
                                        "B,2021.0,4270000,640000,4680000\n");
  const auto column = run("convert " + dated.string() + " --to ecef --transform " + t14.string() + " -o " + path("col.csv").string());
  EXPECT_EQ(column.exit_code, 3) << column.err;
  EXPECT_NE(column.err.find("dated.csv:4: epoch 2021.0 contradicts"), std::string::npos) << column.err;
  EXPECT_FALSE(fs::exists(path("col.csv")));
}

// Without a '# frame' comment, the input's coordinates are in the
// transform's source frame, whose ellipsoid reads them (ITRF2014: GRS80,
// not the WGS84 default): a zero translation leaves GRS80's ECEF.
TEST_F(FramesInFiles, Issue40_ConvertReadsTheInputOnTheTransformsSourceEllipsoid) {
  const auto t = write("t.json", R"({"model": "translation3", "source_frame": "ITRF2014@2024.5", "target_frame": "ETRF2000@2024.5",
    "parameters": {"tx_m": 0, "ty_m": 0, "tz_m": 0}})");
  const auto in = write("in.csv", "id,lat_deg,lon_deg,h_m\nA,47.25,8.5,480\n");
  const auto r = run("convert " + in.string() + " --to ecef --transform " + t.string() + " -o " + path("out.csv").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string csv = slurp(path("out.csv"));
  double x = 0, y = 0, z = 0;
  GeographicLib::Geocentric(6378137.0, 1.0 / 298.257222101).Forward(47.25, 8.5, 480, x, y, z);  // GRS80 (EPSG:7019)
  double got[3];
  ASSERT_EQ(std::sscanf(csv.substr(csv.find("\nA,") + 1).c_str(), "A,%lf,%lf,%lf", &got[0], &got[1], &got[2]), 3) << csv;
  EXPECT_NEAR(got[2], z, kVsGeographicLib_m);
  // A flag that contradicts the transform's frame is refused.
  const auto wgs = run("convert " + in.string() + " --to ecef --ellipsoid WGS84 --transform " + t.string() + " -o " +
                       path("wgs.csv").string());
  EXPECT_EQ(wgs.exit_code, 2) << wgs.err;
  EXPECT_NE(wgs.err.find("contradicts frame ITRF2014@2024.5"), std::string::npos) << wgs.err;
}

// transform and convert --crs do not copy a '# frame' comment that the
// move makes false: transform checks it against --from and writes --to's;
// in CRS mode the '# crs' comments state the output's CRS and the frame
// comment is checked against the input's CRS and dropped.
TEST_F(FramesInFiles, Issue40_TransformAndConvertCrsRestateOrDropTheFrameComment) {
  const auto in = write("in.csv", "# frame = ITRF2014@2020.0\n# site Zurich\nid,x_m,y_m,z_m\nA,4270000,640000,4680000\n");
  const auto t = run("transform " + in.string() + " --from ITRF2014@2020.0 --to ITRF2008@2020.0 -o " + path("t.csv").string());
  ASSERT_EQ(t.exit_code, 0) << t.err;
  const std::string moved = slurp(path("t.csv"));
  EXPECT_EQ(moved.rfind("# frame = ITRF2008@2020.0\n# site Zurich\n", 0), 0u) << moved;
  const auto wrong = run("transform " + in.string() + " --from ITRF2008@2020.0 --to ITRF2014@2020.0 -o " + path("w.csv").string());
  EXPECT_EQ(wrong.exit_code, 3) << wrong.err;
  EXPECT_NE(wrong.err.find("E_FRAME_MISMATCH"), std::string::npos) << wrong.err;
  EXPECT_FALSE(fs::exists(path("w.csv")));
  const auto c = run("convert " + in.string() + " --crs ITRF2014@2020.0 --to-crs ITRF2008@2020.0 --to ecef -o " + path("c.csv").string());
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const std::string converted = slurp(path("c.csv"));
  EXPECT_EQ(converted.find("# frame ="), std::string::npos) << converted;
  EXPECT_NE(converted.find("# site Zurich\n"), std::string::npos) << converted;
  const auto cw = run("convert " + in.string() + " --crs ITRF2008@2020.0 --to-crs ITRF2014@2020.0 --to ecef -o " + path("cw.csv").string());
  EXPECT_EQ(cw.exit_code, 3) << cw.err;
  EXPECT_NE(cw.err.find("E_FRAME_MISMATCH"), std::string::npos) << cw.err;
  EXPECT_FALSE(fs::exists(path("cw.csv")));
}

// apply checks a CSV tile's '# frame' comment against the tile's frame and
// does not copy it into the moved tile (its sidecar states the new frame).
TEST_F(FramesInFiles, Issue40_ApplyChecksAndDropsACsvTilesFrameComment) {
  const auto t = write("t.json", R"({"model": "translation3", "source_frame": "ITRF2014@2024.5", "target_frame": "ETRF2000@2024.5",
    "parameters": {"tx_m": 0.05, "ty_m": 0.04, "tz_m": -0.09}})");
  fs::create_directories(path("in"));
  const auto tile = write("in/tile.csv", "# frame = ITRF2014@2024.5\n# note\nx_m,y_m,z_m\n4270000,640000,4680000\n");
  const auto r = run("apply " + tile.string() + " --from-frame ITRF2014@2024.5 --transform " + t.string() + " --out-dir " +
                     path("out").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(slurp(path("out/tile.csv")).rfind("# note\nx_m,y_m,z_m\n", 0), 0u) << slurp(path("out/tile.csv"));
  const auto other = write("in2/tile.csv", "# frame = ITRF2008@2024.5\nx_m,y_m,z_m\n4270000,640000,4680000\n");
  const auto bad = run("apply " + other.string() + " --from-frame ITRF2014@2024.5 --transform " + t.string() + " --out-dir " +
                       path("bad").string());
  EXPECT_EQ(bad.exit_code, 3) << bad.err;
  EXPECT_NE(bad.err.find("comment contradicts the tile's frame ITRF2014@2024.5"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(path("bad/tile.csv")));
}

TEST_F(FramesInFiles, Issue40_ApplyWarnsOfATileOnTheWgs84Ensemble) {
  write("in/tile.csv", "e_m,n_m,u_m\n1,2,3\n");
  write("in/tile.csv.geoanchor.json",
        R"({"schema": "geoanchor.tile/1", "frame": "WGS84", "coordinates": {"kind": "enu", "ellipsoid": "WGS84",
        "storage": "float64"}, "enu_origin": {"lat_deg": 47.46, "lon_deg": 8.55, "h_m": 480, "height_type": "ellipsoidal"}})");
  const auto r = run("apply " + path("in/tile.csv").string() + " --to ecef --out-dir " + path("out").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("is the WGS 84 ensemble: its realizations differ by up to about 2 m"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace geoanchor
