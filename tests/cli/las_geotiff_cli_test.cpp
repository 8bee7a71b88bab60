// Issue 40 point 12: a LAS tile's GeoTIFF CRS keys (GeoKeyDirectory,
// LASF_Projection 34735) are read: a flag that contradicts them is refused
// as a WKT contradiction is, the CRS they name moves the tile as PROJ's own
// operation does, and keys geoanchor cannot read (a user-defined CRS, units
// that contradict the code) are refused by name. Keys as GeoTIFF 1.0
// section 2.7 lays them out: a header (1, 1, 0, count) and four shorts a key.

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <proj.h>

#include <cmath>
#include <cstring>
#include <filesystem>

#include "cli_support.hpp"
#include "las_builder.hpp"
#include "test_support.hpp"

namespace geoanchor {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::CliTest;

constexpr double kVsProj_deg = 1e-9;  // 0.1 mm of arc
constexpr double kStep_m = 0.001;     // the tile's quantization

// Points near Paris in Lambert-93 (EPSG:2154), metres.
const std::array<double, 3> kPoints[] = {{652000.0, 6862000.0, 35.0}, {652500.25, 6862400.5, 36.5}, {651800.75, 6861700.125, 34.0}};

// Keys whose values are doubles (GeoDoubleParams, record 34736): key id and value.
std::pair<std::vector<std::uint8_t>, std::vector<std::uint8_t>> geo_keys(
    const std::vector<std::array<std::uint16_t, 2>>& keys, const std::vector<std::pair<std::uint16_t, double>>& doubles) {
  std::vector<std::uint16_t> v = {1, 1, 0, static_cast<std::uint16_t>(keys.size() + doubles.size())};
  for (const auto& [id, value] : keys) v.insert(v.end(), {id, 0, 1, value});
  std::vector<double> d;
  for (const auto& [id, value] : doubles) {
    v.insert(v.end(), {id, 34736, 1, static_cast<std::uint16_t>(d.size())});
    d.push_back(value);
  }
  std::vector<std::uint8_t> dir(2 * v.size()), params(8 * d.size());
  std::memcpy(dir.data(), v.data(), dir.size());
  if (!d.empty()) std::memcpy(params.data(), d.data(), params.size());  // memcpy takes no null pointer, even for 0 bytes
  return {dir, params};
}

class LasGeoTiff : public CliTest {
 protected:
  fs::path las(const std::string& name, const std::vector<std::array<std::uint16_t, 2>>& keys,
               const std::vector<std::pair<std::uint16_t, double>>& doubles = {}) {
    testing::LasBuild b;
    b.minor = 2;
    b.point_format = 1;
    b.offset = {652000.0, 6862000.0, 0.0};
    for (const auto& p : kPoints) {
      b.xyz.push_back({static_cast<std::int32_t>(std::lround((p[0] - b.offset[0]) / kStep_m)),
                       static_cast<std::int32_t>(std::lround((p[1] - b.offset[1]) / kStep_m)),
                       static_cast<std::int32_t>(std::lround((p[2] - b.offset[2]) / kStep_m))});
    }
    const auto [dir, params] = geo_keys(keys, doubles);
    b.vlrs.push_back({"LASF_Projection", 34735, "GeoKeyDirectoryTag", dir});
    if (!doubles.empty()) b.vlrs.push_back({"LASF_Projection", 34736, "GeoDoubleParamsTag", params});
    fs::create_directories(path("in"));
    testing::write_bytes(path("in/" + name), testing::build_las(b));
    return path("in/" + name);
  }
};

// The tile's points against PROJ's `from` -> `to` (a geographic CRS), longitude first as LAS stores it.
void expect_moved_as(const json& got, const char* from, const char* to) {
  ASSERT_EQ(got["points"].size(), 3u);
  PJ_CONTEXT* ctx = proj_context_create();
  proj_context_set_enable_network(ctx, 0);
  PJ* raw = proj_create_crs_to_crs(ctx, from, to, nullptr);
  PJ* op = proj_normalize_for_visualization(ctx, raw);
  testing::WorstCase worst;
  for (std::size_t i = 0; i < 3; ++i) {
    const PJ_COORD e = proj_trans(op, PJ_FWD, proj_coord(kPoints[i][0], kPoints[i][1], 0, 0));
    const double tol = 0.5 * got["header"]["scale"][0].get<double>() + kVsProj_deg;
    worst.add(std::abs(got["points"][i][0].get<double>() - e.lp.lam) / tol, i);
    worst.add(std::abs(got["points"][i][1].get<double>() - e.lp.phi) / tol, i);
  }
  EXPECT_WORST_WITHIN(worst, 1.0) << "(ratio to the tolerance)";
  proj_destroy(op);
  proj_destroy(raw);
  proj_context_destroy(ctx);
}
void expect_moved_as_lambert93(const json& got) { expect_moved_as(got, "EPSG:2154", "EPSG:4171"); }

TEST_F(LasGeoTiff, Issue40_TheKeysStateTheTilesCrs) {
  // Projected (1), Lambert-93, metres.
  const fs::path in = las("paris.las", {{1024, 1}, {3072, 2154}, {3076, 9001}});
  // A flag that contradicts the keys (Oregon's Lambert in international feet) is refused; nothing written.
  const auto wrong = run("apply " + in.string() + " --crs EPSG:2992 --to-crs EPSG:4326 --out-dir " + path("wrong").string());
  EXPECT_EQ(wrong.exit_code, 2) << wrong.err;
  EXPECT_NE(wrong.err.find("LAS GeoTIFF keys EPSG:2154"), std::string::npos) << wrong.err;
  EXPECT_FALSE(fs::exists(path("wrong/paris.las")));
  // Without a flag the keys' CRS moves the tile, as PROJ's own operation does.
  const auto r = run("apply " + in.string() + " --to-crs EPSG:4171 --out-dir " + path("out").string());  // RGF93 v1 geographic
  ASSERT_EQ(r.exit_code, 0) << r.err;
  expect_moved_as_lambert93(json::parse(las_verify_text(path("out/paris.las"))));
  const json side = json::parse(testing::slurp(path("out/paris.las.geoanchor.json")));
  EXPECT_NE(side["provenance"]["input_frame_from"].get<std::string>().find("LAS GeoTIFF keys EPSG:2154"), std::string::npos)
      << side["provenance"];
}

TEST_F(LasGeoTiff, Issue40_KeysGeoanchorCannotReadAreRefusedByName) {
  struct Case {
    const char* name;
    std::vector<std::array<std::uint16_t, 2>> keys;
    const char* says;
  };
  const Case cases[] = {
      {"user.las", {{1024, 1}, {3072, 32767}}, "the user-defined projected CRS (code 32767) could not be read from its parameter keys"},
      // A projection (CT 9, south-oriented TM) without its parameters: libgeotiff would take them as 0.
      {"params.las", {{1024, 1}, {3072, 32767}, {3074, 32767}, {3075, 9}}, "the user-defined projection takes its parameter from key"},
      {"unread.las", {{1024, 1}, {3072, 2154}, {3074, 16031}}, "key 3074 is not read by geoanchor"},
      {"feet.las", {{1024, 1}, {3072, 2154}, {3076, 9002}}, "ProjLinearUnitsGeoKey 9002 (0.3048 m) contradicts EPSG:2154"},
      {"geocentric.las", {{1024, 3}}, "GTModelTypeGeoKey 3"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const fs::path in = las(c.name, c.keys);
    const auto r = run("apply " + in.string() + " --to-crs EPSG:4326 --out-dir " + path("out").string());
    EXPECT_EQ(r.exit_code, 3) << r.err;
    EXPECT_NE(r.err.find("E_GEOTIFF_KEYS"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(path("out") / c.name));
  }
}

// Keys that repeat what the code states (as libgeotiff and LAStools write
// them) are read and must agree with PROJ's definition of the code
// (EPSG:2154 is on RGF93 v1, datum 6171, GRS 1980 7019, Greenwich 8901);
// VerticalUnitsGeoKey alone states Z's unit, which must be the CRS's.
TEST_F(LasGeoTiff, Issue40_KeysThatRepeatTheCodeAreCheckedAgainstIt) {
  const std::vector<std::array<std::uint16_t, 2>> agreeing = {{1024, 1}, {3072, 2154}, {2048, 4171}, {3076, 9001}, {2050, 6171},
                                                              {2051, 8901}, {2056, 7019}, {2054, 9102}, {4099, 9001}};
  const std::vector<std::pair<std::uint16_t, double>> agreeing_doubles = {
      {3077, 1.0}, {2057, 6378137.0}, {2059, 298.257222101}, {2061, 0.0}};
  const fs::path good = las("repeats.las", agreeing, agreeing_doubles);
  const auto r = run("apply " + good.string() + " --to-crs EPSG:4171 --out-dir " + path("out").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  struct Case {
    const char* name;
    std::vector<std::array<std::uint16_t, 2>> keys;
    std::vector<std::pair<std::uint16_t, double>> doubles;
    const char* says;
  };
  const Case cases[] = {
      {"clarke.las", {{1024, 1}, {3072, 2154}, {2056, 7008}}, {}, "GeogEllipsoidGeoKey 7008 contradicts EPSG:2154's ellipsoid EPSG code, whose value is 7019"},
      {"ntf.las", {{1024, 1}, {3072, 2154}, {2050, 6275}}, {}, "GeogGeodeticDatumGeoKey 6275 contradicts"},
      {"axis.las", {{1024, 1}, {3072, 2154}}, {{2057, 6378206.4}}, "GeogSemiMajorAxisGeoKey 6378206.4 m contradicts EPSG:2154"},
      {"unit.las", {{1024, 1}, {3072, 2154}}, {{3077, 0.3048}}, "ProjLinearUnitSizeGeoKey 0.3048 m contradicts EPSG:2154"},
      {"zfeet.las", {{1024, 1}, {3072, 2154}, {4099, 9002}}, {}, "VerticalUnitsGeoKey 9002 says Z is in units of 0.3048 m"},
      {"vdatum.las", {{1024, 1}, {3072, 2154}, {4098, 5215}}, {}, "VerticalDatumGeoKey (4098) without VerticalCSTypeGeoKey"},
      {"nodouble.las", {{1024, 1}, {3072, 2154}, {2057, 34736}}, {}, "key 2057 is not one value of the GeoDoubleParams record"},
      {"base.las", {{1024, 1}, {3072, 2154}, {2048, 4326}}, {}, "GeographicTypeGeoKey 4326 contradicts EPSG:2154's geographic CRS EPSG code, whose value is 4171"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const fs::path in = las(c.name, c.keys, c.doubles);
    const auto bad = run("apply " + in.string() + " --to-crs EPSG:4171 --out-dir " + path("bad").string());
    EXPECT_EQ(bad.exit_code, 3) << bad.err;
    EXPECT_NE(bad.err.find("E_GEOTIFF_KEYS"), std::string::npos) << bad.err;
    EXPECT_NE(bad.err.find(c.says), std::string::npos) << bad.err;
    EXPECT_FALSE(fs::exists(path("bad") / c.name));
  }
}

// Keys geoanchor cannot read do not stop a tile whose CRS --crs states:
// they are set aside, and the terminal says so.
TEST_F(LasGeoTiff, Issue40_UnreadableKeysGiveWayToTheCrsFlag) {
  const fs::path in = las("user.las", {{1024, 1}, {3072, 32767}, {3074, 32767}});
  const auto r = run("apply " + in.string() + " --crs EPSG:2154 --to-crs EPSG:4171 --out-dir " + path("out").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("set aside: the tile's CRS is the --crs flag's"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(path("out/user.las")));
  // What the keys do state is still checked: a code beside an unread key
  // refuses a --crs that contradicts it, and agrees with one that does not.
  const fs::path coded = las("coded.las", {{1024, 1}, {3072, 2154}, {3074, 16031}});
  const auto oregon = run("apply " + coded.string() + " --crs EPSG:2992 --to-crs EPSG:4171 --out-dir " + path("oregon").string());
  EXPECT_EQ(oregon.exit_code, 2) << oregon.err;
  EXPECT_NE(oregon.err.find("LAS GeoTIFF keys EPSG:2154"), std::string::npos) << oregon.err;
  EXPECT_FALSE(fs::exists(path("oregon/coded.las")));
  const auto lambert = run("apply " + coded.string() + " --crs EPSG:2154 --to-crs EPSG:4171 --out-dir " + path("lambert").string());
  EXPECT_EQ(lambert.exit_code, 0) << lambert.err;
  EXPECT_NE(lambert.err.find("key 3074 is not read by geoanchor"), std::string::npos) << lambert.err;
  EXPECT_NE(lambert.err.find("checked against the keys' EPSG:2154"), std::string::npos) << lambert.err;
  // A key that contradicts the code is never set aside.
  const fs::path feet = las("feet.las", {{1024, 1}, {3072, 2154}, {3076, 9002}, {3074, 16031}});
  const auto contradicted = run("apply " + feet.string() + " --crs EPSG:2154 --to-crs EPSG:4171 --out-dir " + path("feet").string());
  EXPECT_EQ(contradicted.exit_code, 3) << contradicted.err;
  EXPECT_NE(contradicted.err.find("ProjLinearUnitsGeoKey 9002"), std::string::npos) << contradicted.err;
}

// A user-defined CRS (code 32767, its projection as parameter keys) is read
// through libgeotiff, as GDAL and PDAL read it: Lambert-93's parameters
// (EPSG:2154: LCC 2SP, parallels 49 and 44, false origin 3°E 46.5°N,
// 700 000 / 6 600 000 m) on RGF93 v1 (GeographicTypeGeoKey 4171) move the
// tile as EPSG:2154 does, and --crs EPSG:2154 says the same CRS.
TEST_F(LasGeoTiff, Issue40_AUserDefinedCrsIsReadFromItsParameterKeys) {
  const fs::path in = las("lambert.las", {{1024, 1}, {3072, 32767}, {3074, 32767}, {3075, 8}, {3076, 9001}, {2048, 4171}},
                          {{3078, 49.0}, {3079, 44.0}, {3084, 3.0}, {3085, 46.5}, {3086, 700000.0}, {3087, 6600000.0}});
  const auto r = run("apply " + in.string() + " --to-crs EPSG:4171 --out-dir " + path("out").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  expect_moved_as_lambert93(json::parse(las_verify_text(path("out/lambert.las"))));
  const json side = json::parse(testing::slurp(path("out/lambert.las.geoanchor.json")));
  EXPECT_NE(side["provenance"]["input_frame_from"].get<std::string>().find("user-defined projected CRS (code 32767) read from its keys by libgeotiff"),
            std::string::npos)
      << side["provenance"];
  const auto same = run("apply " + in.string() + " --crs EPSG:2154 --to-crs EPSG:4171 --out-dir " + path("same").string());
  EXPECT_EQ(same.exit_code, 0) << same.err;
  const auto oregon = run("apply " + in.string() + " --crs EPSG:2992 --to-crs EPSG:4171 --out-dir " + path("oregon").string());
  EXPECT_EQ(oregon.exit_code, 2) << oregon.err;
  EXPECT_FALSE(fs::exists(path("oregon/lambert.las")));
  // A projection named by its code (ProjectionGeoKey 16032, UTM zone 32N)
  // on ETRS89 (4258), as GDAL writes it: its parameters come from EPSG.
  const fs::path utm = las("utm.las", {{1024, 1}, {3072, 32767}, {3074, 16032}, {3076, 9001}, {2048, 4258}});
  const auto u = run("apply " + utm.string() + " --to-crs EPSG:4258 --out-dir " + path("utm").string());
  ASSERT_EQ(u.exit_code, 0) << u.err;
  expect_moved_as(json::parse(las_verify_text(path("utm/utm.las"))), "EPSG:25832", "EPSG:4258");
  // libgeotiff prints a TM scale factor with 6 decimals (Idaho East's
  // 0.999947368 as 0.999947, 9 cm at 260 km): refused, not read wrong.
  const fs::path tm = las("tm.las", {{1024, 1}, {3072, 32767}, {3074, 32767}, {3075, 1}, {3076, 9001}, {2048, 4269}},
                          {{3080, -112.1666666667}, {3081, 41.6666666667}, {3082, 200000.0}, {3083, 0.0}, {3092, 0.999947368}});
  const auto t = run("apply " + tm.string() + " --to-crs EPSG:4269 --out-dir " + path("tm").string());
  EXPECT_EQ(t.exit_code, 3) << t.err;
  EXPECT_NE(t.err.find("does not carry every parameter at full precision"), std::string::npos) << t.err;
  EXPECT_FALSE(fs::exists(path("tm/tm.las")));
}

}  // namespace
}  // namespace geoanchor
