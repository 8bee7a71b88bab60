// Tile metadata: the sidecar schema, the WKT2 of each kind of tile read by
// PROJ (and its meaning checked through PROJ's own crs-to-crs), CSV and PLY
// tiles against PROJ, the propagated uncertainty and the control extent.

#include <gtest/gtest.h>
#include <proj.h>
#include <proj_experimental.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/float32.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/tile/tile_apply.hpp"
#include "geoanchor/io/tile/tile_metadata.hpp"
#include "proj_reference.hpp"
#include "temp_folder.hpp"
#include "test_support.hpp"

namespace geoanchor::io {
namespace {

namespace fs = std::filesystem;
using geodesy::Angle;
using testing::ProjPipeline;

constexpr double kVsProjTol_m = 1e-6;     // issue acceptance for float64 tiles
constexpr double kCrossAirportTol_m = 1e-9;  // ENU(A) -> ENU(B) -> ENU(A), issue acceptance
constexpr double kDegreeTol = 1e-11;      // ≈ 1 µm of latitude

const char* kSidecar = R"J({
  "schema": "geoanchor.tile/1",
  "frame": "ITRF2014@2024.5",
  "coordinates": {"kind": "enu", "ellipsoid": "GRS80", "storage": "int32_scaled"},
  "enu_origin": {"lat_deg": 47.464722, "lon_deg": 8.549167, "h_m": 480.0, "height_type": "ellipsoidal",
                 "source": "AIP"},
  "vertical": {"height_type": "ellipsoidal"},
  "survey": {"method": "mobile LiDAR", "rtk_fixed_percent": 98.5}
})J";

geodesy::LocalOrigin origin(double lat, double lon, double h) {
  return {{Angle::degrees(lat), Angle::degrees(lon), geodesy::EllipsoidalHeight{h}}, geodesy::Ellipsoid::grs80()};
}

TEST(TileMetadata, SidecarReadsBackWhatItWrites) {
  const TileMetadata m = parse_tile_metadata(kSidecar, "t.json");
  ASSERT_TRUE(m.frame);
  EXPECT_EQ(m.frame->to_string(), "ITRF2014@2024.5");
  EXPECT_EQ(m.coordinates.kind, CoordinateKind::enu);
  EXPECT_EQ(m.coordinates.origin->point.lat.deg(), 47.464722);
  EXPECT_EQ(m.origin_source, "AIP");
  EXPECT_EQ(*m.rtk_fixed_percent, 98.5);
  const TileMetadata again = parse_tile_metadata(to_json_text(m), "again.json");
  EXPECT_EQ(describe_mismatch(m, "a", again, "b"), "");
  EXPECT_EQ(again.survey_method, "mobile LiDAR");
}

// issue 12 point 12
TEST(TileMetadata, Point12_ACrsNameThatIsNotUtf8IsRefusedNotDumpedAsInternal) {
  TileMetadata m = parse_tile_metadata(kSidecar, "t.json");
  m.horizontal_crs = "CH1903+ / LV95 (Z\xFCrich)";  // Latin-1, as a tile's WKT may hold it
  try {
    (void)to_json_text(m);
    ADD_FAILURE() << "written";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_CRS_NOT_UTF8");
    EXPECT_NE(std::string(e.what()).find("'CH1903+ / LV95 (Z\\xFCrich)'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("byte 18 is 0xFC"), std::string::npos) << e.what();
  }
}

TEST(TileMetadata, SidecarErrorsNameTheKey) {
  auto error_of = [](std::string text) {
    try {
      parse_tile_metadata(text, "t.json");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  auto replaced = [](const std::string& from, const std::string& to) {
    std::string s = kSidecar;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  EXPECT_NE(error_of(replaced("\"frame\"", "\"frmae\"")).find("t.json: frmae: unknown key"), std::string::npos);
  EXPECT_NE(error_of(replaced("\"schema\": \"geoanchor.tile/1\",", "")).find("t.json: schema:"), std::string::npos);
  EXPECT_NE(error_of(replaced("\"kind\": \"enu\"", "\"kind\": \"geodetic\"")).find("enu_origin: given for geodetic"),
            std::string::npos);
  EXPECT_NE(error_of(replaced("\"h_m\": 480.0, ", "")).find("needs lat_deg, lon_deg and h_m"), std::string::npos);
  EXPECT_NE(error_of(replaced("\"rtk_fixed_percent\": 98.5", "\"rtk_fixed_percent\": 101")).find("not in [0, 100]"),
            std::string::npos);
  const std::string geodetic = R"({"schema": "geoanchor.tile/1", "frame": "GDA2020",
      "coordinates": {"kind": "geodetic", "ellipsoid": "GRS80"}})";
  EXPECT_NE(error_of(geodetic).find("vertical.height_type: missing"), std::string::npos);
  const std::string orthometric = R"({"schema": "geoanchor.tile/1", "frame": "GDA2020",
      "coordinates": {"kind": "geodetic", "ellipsoid": "GRS80"}, "vertical": {"height_type": "orthometric"}})";
  EXPECT_NE(error_of(orthometric).find("geoid_model: missing"), std::string::npos);
  // Found by fuzz_sidecar: a number beyond double's range was an uncaught
  // nlohmann out_of_range, not a clear error.
  EXPECT_NE(error_of(replaced("\"h_m\": 480.0", "\"h_m\": 4e999")).find("t.json: not valid JSON"), std::string::npos);
}

// PROJ's own crs-to-crs from a tile WKT to the same datum's geocentric WKT
// (through the reference helper: an error PROJ reports fails the test).
Eigen::Vector3d proj_to_ecef(const std::string& tile_wkt, const std::string& ecef_wkt, const Eigen::Vector3d& p) {
  return ProjPipeline::crs_to_crs(tile_wkt, ecef_wkt).forward(p);
}

TEST(TileMetadata, WktOfEachKindParsesBackAndMeansWhatProjMakesOfIt) {
  TileMetadata base = parse_tile_metadata(kSidecar, "t.json");
  base.height_type = "ellipsoidal";
  TileMetadata ecef = base;
  ecef.coordinates = ArrayFrame{CoordinateKind::ecef, geodesy::Ellipsoid::grs80(), std::nullopt, std::nullopt};
  const std::string ecef_wkt = tile_crs_wkt(ecef);
  TileMetadata geodetic = base;
  geodetic.coordinates = ArrayFrame{CoordinateKind::geodetic, geodesy::Ellipsoid::grs80(), std::nullopt, std::nullopt};
  TileMetadata utm = base;
  utm.coordinates = ArrayFrame{CoordinateKind::projected, geodesy::Ellipsoid::grs80(), std::nullopt,
                               geodesy::utm_projection(geodesy::Ellipsoid::grs80(), geodesy::UtmZone{32, geodesy::Hemisphere::north})};
  TileMetadata tm = base;
  tm.coordinates = ArrayFrame{CoordinateKind::projected, geodesy::Ellipsoid::grs80(), std::nullopt,
                              geodesy::ProjectionDef{geodesy::Ellipsoid::grs80(),
                                                     {Angle::degrees(47.4), Angle::degrees(8.55), 0.99995, 2600000, 1200000},
                                                     std::nullopt}};
  struct Case {
    const char* name;
    TileMetadata m;
    Eigen::Vector3d p;  // in the WKT's axis order
  };
  const std::vector<Case> cases = {{"ENU", base, {123.4, -456.7, 8.9}},
                                   {"ECEF", ecef, {4277686.0, 639405.5, 4672438.6}},
                                   {"geodetic", geodetic, {47.47, 8.56, 455.0}},
                                   {"UTM", utm, {465000.0, 5257000.0, 455.0}},
                                   {"TM", tm, {2683000.0, 1252000.0, 455.0}}};
  ArrayFrame to_ecef{CoordinateKind::ecef, geodesy::Ellipsoid::grs80(), std::nullopt, std::nullopt};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string wkt = tile_crs_wkt(c.m);
    EXPECT_NE(wkt.find("ITRF2014@2024.5"), std::string::npos);
    EXPECT_NE(wkt.find("International Terrestrial Reference Frame 2014"), std::string::npos);
    const TileMetadata back = tile_metadata_from_wkt(wkt, "tile.las");
    EXPECT_EQ(describe_mismatch(c.m, "written", back, "read"), "");
    // What PROJ makes of the WKT equals what geoanchor means by it.
    std::vector<double> a{c.p.x()}, b{c.p.y()}, z{c.p.z()};
    PointChain(c.m.coordinates, std::nullopt, false, std::nullopt, to_ecef).apply(a, b, z);
    const Eigen::Vector3d proj = proj_to_ecef(wkt, ecef_wkt, c.p);
    EXPECT_LT((proj - Eigen::Vector3d(a[0], b[0], z[0])).norm(), kVsProjTol_m) << wkt;
  }
  // Datum names from other tools map to frames; the coordinate epoch is ours.
  EXPECT_EQ(tile_metadata_from_wkt(
                "GEOGCRS[\"x\",DATUM[\"Geocentric Datum of Australia 2020\",ELLIPSOID[\"GRS 1980\",6378137,298.257222101]],"
                "CS[ellipsoidal,3],AXIS[\"lat\",north,ANGLEUNIT[\"degree\",0.0174532925199433]],AXIS[\"lon\",east,"
                "ANGLEUNIT[\"degree\",0.0174532925199433]],AXIS[\"h\",up,LENGTHUNIT[\"metre\",1]]]",
                "t.las")
                .frame->to_string(),
            "GDA2020");
  try {
    tile_metadata_from_wkt("PROJCRS[\"broken\",", "t.las");
    ADD_FAILURE() << "a broken WKT was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("t.las: LAS WKT: PROJ cannot parse it"), std::string::npos) << e.what();
  }
  // A 2-D CRS: read as a CRS whose Z values are no coordinate (apply
  // refuses to place them as heights unless --crs states them).
  const TileMetadata two_d = tile_metadata_from_wkt(
      "GEOGCRS[\"WGS 84\",DATUM[\"World Geodetic System 1984\",ELLIPSOID[\"WGS 84\",6378137,298.257223563]],"
      "CS[ellipsoidal,2],AXIS[\"lat\",north,ANGLEUNIT[\"degree\",0.0174532925199433]],AXIS[\"lon\",east,"
      "ANGLEUNIT[\"degree\",0.0174532925199433]]]",
      "t.las");
  ASSERT_TRUE(two_d.crs.has_value());
  EXPECT_EQ(two_d.crs->description().axes.size(), 2u);
  EXPECT_EQ(two_d.height_type, "");
}

// PROJ's WKT2:2019 of `crs` (an EPSG code), promoted to 3D when `to_3d`.
std::string projs_wkt(const char* crs, bool to_3d) {
  PJ_CONTEXT* ctx = proj_context_create();
  PJ* p = proj_create(ctx, crs);
  PJ* q = p && to_3d ? proj_crs_promote_to_3D(ctx, nullptr, p) : nullptr;
  const char* wkt = (q ? q : p) ? proj_as_wkt(ctx, q ? q : p, PJ_WKT2_2019, nullptr) : nullptr;
  std::string out = wkt ? wkt : "";
  proj_destroy(q);
  proj_destroy(p);
  proj_context_destroy(ctx);
  return out;
}

// issue 13 (its first defect): a tile CRS in US survey feet, in grads or
// from another prime meridian was read as metres, degrees and Greenwich
// (EPSG:2236 moved a tile 700 km). Now each is read through PROJ as the CRS
// it is (PROJ then moves its coordinates), never as geoanchor's own kinds;
// the metre and the degree from Greenwich still read as those.
TEST(TileMetadata, Issue13_AxesInOtherUnitsOrFromAnotherMeridianAreReadAsTheirCrs) {
  auto crs_of = [](const std::string& wkt) {
    const TileMetadata m = tile_metadata_from_wkt(wkt, "t.las");
    return m.crs ? std::optional<CrsDescription>(m.crs->description()) : std::nullopt;
  };
  const std::string florida = projs_wkt("EPSG:2236", true);  // NAD83 / Florida East (ftUS), TM
  ASSERT_FALSE(florida.empty()) << "PROJ has no EPSG:2236";
  const auto f = crs_of(florida);
  ASSERT_TRUE(f) << "EPSG:2236 read as geoanchor's own TM in metres";
  EXPECT_EQ(f->name, "NAD83 / Florida East (ftUS)");
  EXPECT_EQ(f->axes.at(0).unit_name, "US survey foot");

  const std::string ntf = projs_wkt("EPSG:4807", true);  // NTF (Paris): grads from Paris
  ASSERT_FALSE(ntf.empty()) << "PROJ has no EPSG:4807";
  const auto g = crs_of(ntf);
  ASSERT_TRUE(g);
  EXPECT_EQ(g->axes.at(0).unit_name, "grad");

  // Degrees, but longitudes from Paris.
  const std::string paris =
      "GEOGCRS[\"x\",DATUM[\"Nouvelle Triangulation Francaise (Paris)\",ELLIPSOID[\"Clarke 1880 (IGN)\",6378249.2,"
      "293.466021293627]],PRIMEM[\"Paris\",2.33722917,ANGLEUNIT[\"degree\",0.0174532925199433]],CS[ellipsoidal,3],"
      "AXIS[\"lat\",north,ANGLEUNIT[\"degree\",0.0174532925199433]],AXIS[\"lon\",east,ANGLEUNIT[\"degree\","
      "0.0174532925199433]],AXIS[\"h\",up,LENGTHUNIT[\"metre\",1]]]";
  const auto pm = crs_of(paris);
  ASSERT_TRUE(pm);
  EXPECT_EQ(pm->prime_meridian_deg, 2.33722917);

  // A southing (UPS South, promoted to 3D) is not read as a northing.
  const std::string ups = projs_wkt("EPSG:32761", true);
  ASSERT_FALSE(ups.empty()) << "PROJ has no EPSG:32761";
  EXPECT_TRUE(crs_of(ups));

  // The metre and the degree from Greenwich still read as geoanchor's UTM (32N in 3D).
  const TileMetadata utm = tile_metadata_from_wkt(projs_wkt("EPSG:25832", true), "t.las");
  EXPECT_FALSE(utm.crs.has_value());
  ASSERT_TRUE(utm.coordinates.projection && utm.coordinates.projection->utm);
  EXPECT_EQ(utm.coordinates.projection->utm->to_string(), "32N");
}

const char* kHelmert = R"J({"model": "helmert7", "convention": "coordinate_frame",
  "parameters": {"tx_m": 0.0547, "ty_m": 0.0522, "tz_m": -0.0741, "rx_arcsec": 0.00228, "ry_arcsec": 0.01404,
                 "rz_arcsec": -0.02168, "ds_ppm": 0.00212}})J";

std::string topocentric(const geodesy::LocalOrigin& o) {
  return "+proj=topocentric +ellps=GRS80 +lat_0=" + format_shortest(o.point.lat.deg()) +
         " +lon_0=" + format_shortest(o.point.lon.deg()) + " +h_0=" + format_shortest(o.point.h.m);
}

TEST(TileFormats, CsvAndPlyTilesAgreeWithProjAndKeepTheirOtherColumns) {
  const auto a = origin(47.464722, 8.549167, 480.0), b = origin(47.2597, 11.3439, 581.0);
  const ArrayFrame fa{CoordinateKind::enu, geodesy::Ellipsoid::grs80(), a, std::nullopt};
  const ArrayFrame geo{CoordinateKind::geodetic, geodesy::Ellipsoid::grs80(), std::nullopt, std::nullopt};
  const TransformFile t = parse_transform_json(kHelmert, "T.json");
  const std::size_t n = 100000;
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> h(-3000.0, 3000.0), v(-20.0, 60.0);
  std::vector<Eigen::Vector3d> pts(n);
  for (auto& p : pts) p = Eigen::Vector3d(h(rng), h(rng), v(rng));
  const ProjPipeline to_geo("+proj=pipeline +step +inv " + topocentric(a) +
                            " +step +proj=helmert +x=0.0547 +y=0.0522 +z=-0.0741 +rx=0.00228 +ry=0.01404 +rz=-0.02168 "
                            "+s=0.00212 +convention=coordinate_frame +step +inv +proj=cart +ellps=GRS80");
  const testing::TempFolder folder;  // issue 12, tests that can fail, item 6: was TempDir() itself, fixed names
  const fs::path& dir = folder.path();

  // CSV: ENU(A) -> Helmert -> geodetic, an id and a class column kept.
  {
    std::ostringstream csv;
    csv << "# a comment\nid,e_m,n_m,u_m,class\n";
    for (std::size_t i = 0; i < n; ++i) {
      csv << "P" << i << "," << format_shortest(pts[i].x()) << "," << format_shortest(pts[i].y()) << ","
          << format_shortest(pts[i].z()) << "," << (i % 7) << "\n";
    }
    const fs::path in = dir / "tile.csv";
    std::ofstream(in) << csv.str();
    std::stringstream out;
    const PointChain chain(fa, t, false, std::nullopt, geo);
    const auto r = apply_csv_tile(in, out, "out.csv", chain, TileApplyOptions{fa, geo, std::nullopt, "", 4096, {}});
    EXPECT_EQ(r.points, n);
    std::string line;
    std::getline(out, line);
    EXPECT_EQ(line, "# a comment");
    std::getline(out, line);
    EXPECT_EQ(line, "id,lat_deg,lon_deg,h_m,class");
    testing::WorstCase worst_deg, worst_h;
    for (std::size_t i = 0; i < n && std::getline(out, line); ++i) {
      std::stringstream s(line);
      std::string id, lat, lon, hh, cls;
      std::getline(s, id, ',');
      std::getline(s, lat, ',');
      std::getline(s, lon, ',');
      std::getline(s, hh, ',');
      std::getline(s, cls, ',');
      ASSERT_EQ(id, "P" + std::to_string(i));
      ASSERT_EQ(cls, std::to_string(i % 7));
      const Eigen::Vector3d e = to_geo.forward(pts[i]);
      worst_deg.add(std::abs(std::stod(lat) - testing::proj_degrees(e.y())), i);
      worst_deg.add(std::abs(std::stod(lon) - testing::proj_degrees(e.x())), i);
      worst_h.add(std::abs(std::stod(hh) - e.z()), i);
    }
    EXPECT_EQ(worst_h.count(), n);  // every row read back
    EXPECT_WORST_WITHIN(worst_deg, kDegreeTol);
    EXPECT_WORST_WITHIN(worst_h, kVsProjTol_m);
    ::testing::Test::RecordProperty("csv_worst_deg", testing::scientific(worst_deg.value()));
    ::testing::Test::RecordProperty("csv_worst_h_m", testing::scientific(worst_h.value()));
  }

  // PLY, binary and ASCII: ENU(A) as float32 offsets and as doubles ->
  // Helmert -> ENU(B); a colour property and a face element kept.
  const ArrayFrame fb{CoordinateKind::enu, geodesy::Ellipsoid::grs80(), b, std::nullopt};
  const ProjPipeline to_b("+proj=pipeline +step +inv " + topocentric(a) +
                          " +step +proj=helmert +x=0.0547 +y=0.0522 +z=-0.0741 +rx=0.00228 +ry=0.01404 +rz=-0.02168 "
                          "+s=0.00212 +convention=coordinate_frame +step " + topocentric(b));
  for (const bool binary : {true, false}) {
    for (const bool as_float : {true, false}) {
      SCOPED_TRACE(std::string(binary ? "binary" : "ascii") + (as_float ? " float" : " double"));
      const std::size_t m = binary ? n : 2000;
      const char* type = as_float ? "float" : "double";
      std::ostringstream ply;
      ply << "ply\nformat " << (binary ? "binary_little_endian" : "ascii") << " 1.0\ncomment test\nelement vertex " << m
          << "\nproperty " << type << " x\nproperty " << type << " y\nproperty " << type << " z\nproperty uchar red\n"
          << "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
      std::vector<Eigen::Vector3d> used(m);
      for (std::size_t i = 0; i < m; ++i) {
        const Eigen::Vector3d p =
            as_float ? Eigen::Vector3d(geodesy::round_to_float32(pts[i].x()), geodesy::round_to_float32(pts[i].y()),
                                       geodesy::round_to_float32(pts[i].z()))
                     : pts[i];
        const float f[3] = {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())};
        used[i] = p;
        if (binary) {
          if (as_float) {
            ply.write(reinterpret_cast<const char*>(f), sizeof f);
          } else {
            ply.write(reinterpret_cast<const char*>(p.data()), 24);
          }
          const auto red = static_cast<char>(i % 251);
          ply.write(&red, 1);
        } else {
          ply << format_shortest(p.x()) << " " << format_shortest(p.y()) << " " << format_shortest(p.z()) << " "
              << (i % 251) << "\n";
        }
      }
      const std::string face = binary ? std::string("\x03\x00\x00\x00\x00\x01\x00\x00\x00\x02\x00\x00\x00", 13) : "3 0 1 2\n";
      ply << face;
      const fs::path in = dir / "tile.ply";
      std::ofstream(in, std::ios::binary) << ply.str();
      std::stringstream out;
      const PointChain chain(fa, t, false, std::nullopt, fb);
      const auto r = apply_ply_tile(in, out, "out.ply", chain, TileApplyOptions{fa, fb, std::nullopt, "", 4096, {}});
      EXPECT_EQ(r.points, m);
      const std::string text = out.str();
      const auto body = text.find("end_header\n") + 11;
      EXPECT_NE(text.find("property double x\nproperty double y\nproperty double z\nproperty uchar red\n"), std::string::npos);
      EXPECT_EQ(text.substr(text.size() - face.size()), face);
      std::istringstream s(text.substr(body));
      testing::WorstCase worst;
      for (std::size_t i = 0; i < m; ++i) {
        Eigen::Vector3d got;
        int red = 0;
        if (binary) {
          s.read(reinterpret_cast<char*>(got.data()), 24);
          char c = 0;
          s.read(&c, 1);
          red = static_cast<unsigned char>(c);
        } else {
          s >> got.x() >> got.y() >> got.z() >> red;
        }
        ASSERT_EQ(red, static_cast<int>(i % 251));
        worst.add((got - to_b.forward(used[i])).norm(), i);
      }
      EXPECT_WORST_WITHIN(worst, kVsProjTol_m);
      ::testing::Test::RecordProperty(std::string("ply_worst_m_") + (binary ? "binary" : "ascii") + (as_float ? "_float" : "_double"),
                                      testing::scientific(worst.value()));
    }
  }
  // float32 is refused where it cannot hold the coordinates.
  std::ofstream(dir / "ecef.ply") << "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                     "property float z\nend_header\n4277686 639405 4672438\n";
  const ArrayFrame ecef{CoordinateKind::ecef, geodesy::Ellipsoid::grs80(), std::nullopt, std::nullopt};
  std::stringstream out;
  try {
    apply_ply_tile(dir / "ecef.ply", out, "o.ply", PointChain(ecef, std::nullopt, false, std::nullopt, ecef),
                   TileApplyOptions{ecef, ecef, std::nullopt, "", 16, {}});
    ADD_FAILURE() << "float32 ECEF accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("float32 is accepted only for map-local ENU/NED"), std::string::npos) << e.what();
  }
}

TEST(TileFormats, CrossAirportRoundTripClosesToANanometre) {
  const auto a = origin(47.464722, 8.549167, 480.0), b = origin(47.2597, 11.3439, 581.0);
  const ArrayFrame fa{CoordinateKind::enu, geodesy::Ellipsoid::grs80(), a, std::nullopt};
  const ArrayFrame fb{CoordinateKind::enu, geodesy::Ellipsoid::grs80(), b, std::nullopt};
  const TransformFile t = parse_transform_json(kHelmert, "T.json");
  const PointChain there(fa, t, false, std::nullopt, fb), back(fb, t, true, std::nullopt, fa);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> h(-5000.0, 5000.0);
  std::vector<double> x(10000), y(10000), z(10000);
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = h(rng), y[i] = h(rng), z[i] = h(rng) / 50;
  auto x0 = x, y0 = y, z0 = z;
  there.apply(x, y, z);
  back.apply(x, y, z);
  testing::WorstCase worst;
  for (std::size_t i = 0; i < x.size(); ++i) {
    worst.add((Eigen::Vector3d(x[i], y[i], z[i]) - Eigen::Vector3d(x0[i], y0[i], z0[i])).norm(), i);
  }
  EXPECT_WORST_WITHIN(worst, kCrossAirportTol_m);
  ::testing::Test::RecordProperty("round_trip_worst_m", testing::scientific(worst.value()));
}

TEST(ControlExtentTest, DistanceIsZeroInsideAndGrowsOutside) {
  // The hull lives in the tangent plane at the marks' centroid, the test
  // points in the one at the origin: 4-6 km out they differ by about a metre.
  constexpr double kPlanesTol_m = 3.0;
  const geodesy::LocalOrigin o = origin(47.464722, 8.549167, 480.0);
  const geodesy::LocalTangentPlane plane(o);
  std::vector<geodesy::EcefPosition> marks;
  for (const auto& en : std::vector<std::array<double, 2>>{{-1000, -1000}, {1000, -1000}, {1000, 1000}, {-1000, 1000}, {0, 0}}) {
    marks.push_back(plane.ecef_from_enu({Eigen::Vector3d(en[0], en[1], 0), o}));
  }
  const ControlExtent e = ControlExtent::of(marks);
  EXPECT_EQ(e.hull_en_m.size(), 4u);  // the centre mark is inside
  EXPECT_EQ(e.distance_m(plane.ecef_from_enu({Eigen::Vector3d(500, 500, 30), o})), 0.0);
  EXPECT_NEAR(e.distance_m(plane.ecef_from_enu({Eigen::Vector3d(4000, 0, 0), o})), 3000.0, kPlanesTol_m);
  EXPECT_NEAR(e.distance_m(plane.ecef_from_enu({Eigen::Vector3d(4000, 5000, 0), o})), 5000.0, kPlanesTol_m);
}

// The hull of many marks (the candidates are thinned before the sort)
// against its definition: a strictly convex counter-clockwise polygon whose
// vertices are marks and that holds every mark is the convex hull. The
// marks fill a disc, then a square with many marks on one of its edges.
TEST(ControlExtentTest, HullOfManyMarksIsTheirConvexHull) {
  const geodesy::LocalOrigin o = origin(47.464722, 8.549167, 480.0);
  const geodesy::LocalTangentPlane plane(o);
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (const bool disc : {true, false}) {
    std::vector<geodesy::EcefPosition> marks;
    std::vector<std::array<double, 2>> local;
    while (local.size() < 20000) {
      double e = u(rng) * 3000.0, n = u(rng) * 3000.0;
      if (disc && std::hypot(e, n) > 3000.0) continue;
      if (!disc && local.size() % 50 == 0) e = 3000.0;  // an edge with many marks on it
      local.push_back({e, n});
      marks.push_back(plane.ecef_from_enu({Eigen::Vector3d(e, n, 0), o}));
    }
    const ControlExtent x = ControlExtent::of(marks);
    const auto& h = x.hull_en_m;
    ASSERT_GE(h.size(), 3u);
    const auto cross = [](const std::array<double, 2>& a, const std::array<double, 2>& b, const std::array<double, 2>& c) {
      return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    };
    for (std::size_t i = 0; i < h.size(); ++i) {
      EXPECT_GT(cross(h[i], h[(i + 1) % h.size()], h[(i + 2) % h.size()]), 0.0) << "vertex " << i << " not strictly convex";
    }
    // Vertices are marks (in the centroid's plane: compare through ECEF).
    const geodesy::LocalTangentPlane hull_plane(x.centroid);
    std::vector<std::array<double, 2>> in_hull_plane;
    for (const auto& m : marks) {
      const Eigen::Vector3d v = hull_plane.enu_from_ecef(m).enu_m;
      in_hull_plane.push_back({v.x(), v.y()});
    }
    for (const auto& v : h) {
      EXPECT_NE(std::find(in_hull_plane.begin(), in_hull_plane.end(), v), in_hull_plane.end()) << v[0] << "," << v[1];
    }
    std::size_t outside = 0;
    for (const auto& m : marks) outside += x.distance_m(m) == 0.0 ? 0u : 1u;
    EXPECT_EQ(outside, 0u) << (disc ? "disc" : "square");
  }
}

std::string sidecar_error(const std::string& text) {
  try {
    parse_tile_metadata(text, "t.json");
  } catch (const Error& e) {
    return e.what();
  }
  return "accepted";
}

std::string sidecar_with(const std::string& from, const std::string& to) {
  std::string s = kSidecar;
  s.replace(s.find(from), from.size(), to);
  return s;
}

// issue 12 point 3
TEST(TileMetadata, Point3_DuplicateKeyIsRefusedWithItsPathAndLine) {
  const std::string twice = sidecar_with("\"frame\": \"ITRF2014@2024.5\",", "\"frame\": \"ITRF2014@2024.5\", \"frame\": \"ITRF2008@2024.5\",");
  EXPECT_NE(sidecar_error(twice).find("t.json:3: frame: key given twice"), std::string::npos) << sidecar_error(twice);
  const std::string nested = sidecar_with("\"h_m\": 480.0,", "\"h_m\": 480.0, \"h_m\": 0.0,");
  EXPECT_NE(sidecar_error(nested).find("t.json:5: enu_origin.h_m: key given twice"), std::string::npos) << sidecar_error(nested);
}

// issue 12 point 10
TEST(TileMetadata, Point10_NullsWrongTypesAndUnreadKeysAreRefused) {
  // null would read as absent, and a default would stand in for it.
  EXPECT_NE(sidecar_error(sidecar_with("\"storage\": \"int32_scaled\"", "\"storage\": null"))
                .find("t.json: coordinates.storage: value null; give the key a value or leave it out"),
            std::string::npos);
  EXPECT_NE(sidecar_error(sidecar_with("\"survey\": {", "\"horizontal_crs\": null, \"survey\": {")).find("t.json: horizontal_crs: value null"),
            std::string::npos);
  // geoid_model is written as null and reads as none.
  EXPECT_EQ(sidecar_error(sidecar_with("\"vertical\": {\"height_type\": \"ellipsoidal\"}",
                                       "\"vertical\": {\"height_type\": \"ellipsoidal\", \"geoid_model\": null}")),
            "accepted");
  // A utm tile reads projection.utm_zone only; a tm next to it would be ignored.
  const std::string utm = R"({"schema": "geoanchor.tile/1", "frame": "ETRF2000@2024.5",
      "coordinates": {"kind": "utm", "ellipsoid": "GRS80"}, "vertical": {"height_type": "ellipsoidal"},
      "projection": {"utm_zone": "32N", "tm": {"lat0_deg": 0, "lon0_deg": 9, "k0": 0.9996, "false_easting_m": 500000,
                     "false_northing_m": 0}}})";
  EXPECT_NE(sidecar_error(utm).find("t.json: projection.tm: given for utm coordinates, which read projection.utm_zone only"),
            std::string::npos)
      << sidecar_error(utm);
  // The provenance keys apply reads back to resume are typed.
  EXPECT_EQ(sidecar_error(sidecar_with("\"survey\": {", "\"provenance\": {\"input_sha256\": \"ab\", \"points\": 12}, \"survey\": {")),
            "accepted");
  EXPECT_NE(sidecar_error(sidecar_with("\"survey\": {", "\"provenance\": {\"input_sha256\": 12}, \"survey\": {"))
                .find("t.json: provenance.input_sha256: value 12 is not a string"),
            std::string::npos);
  EXPECT_NE(sidecar_error(sidecar_with("\"survey\": {", "\"provenance\": {\"output_size_bytes\": \"12\"}, \"survey\": {"))
                .find("provenance.output_size_bytes: value \"12\" is not a byte count"),
            std::string::npos);
}


// issue 13: a sidecar of kind "crs" states its coordinates by the CRS
// alone: a frame beside a CRS whose datum is no catalog frame, or height
// labels that contradict the CRS, are refused by key; labels that repeat
// it are accepted, and a written sidecar reads back.
TEST(TileMetadata, Issue13_ACrsSidecarsFrameAndHeightsMustNotContradictItsCrs) {
  auto crs_sidecar = [](const char* crs, const std::string& extra) {
    const std::string wkt = projs_wkt(crs, false);
    return std::string(R"({"schema": "geoanchor.tile/1", "coordinates": {"kind": "crs", "storage": "float64"}, "crs": {"wkt2": )") +
           nlohmann::json(wkt).dump() + "}" + extra + "}";
  };
  // NTF (Paris) / Lambert zone II: a datum of no catalog frame.
  const std::string framed = crs_sidecar("EPSG:27572", R"(, "frame": "ETRF2000")");
  EXPECT_NE(sidecar_error(framed).find("t.json: frame: \"ETRF2000\" but the CRS"), std::string::npos) << sidecar_error(framed);
  EXPECT_NE(sidecar_error(framed).find("no frame of geoanchor's catalog"), std::string::npos) << sidecar_error(framed);
  // UTM 32N + EGM96 height: orthometric heights on the EGM96 geoid.
  const std::string ortho = crs_sidecar("EPSG:32632+5773", R"(, "vertical": {"height_type": "ellipsoidal"})");
  EXPECT_NE(sidecar_error(ortho).find("t.json: vertical.height_type: \"ellipsoidal\" but the CRS"), std::string::npos)
      << sidecar_error(ortho);
  EXPECT_NE(sidecar_error(crs_sidecar("EPSG:32632+5773", R"(, "vertical": {"geoid_model": "some other geoid"})"))
                .find("vertical.geoid_model: \"some other geoid\" but the CRS"),
            std::string::npos);
  // A 2-D CRS has no heights to label.
  EXPECT_NE(sidecar_error(crs_sidecar("EPSG:27572", R"(, "vertical": {"height_type": "ellipsoidal"})"))
                .find("it has no height axis"),
            std::string::npos);
  const TileMetadata m = parse_tile_metadata(crs_sidecar("EPSG:32632+5773", R"(, "vertical": {"height_type": "orthometric"})"), "t.json");
  EXPECT_EQ(m.height_type, "orthometric");
  ASSERT_TRUE(m.geoid_model.has_value());
  const TileMetadata again = parse_tile_metadata(to_json_text(m), "again.json");
  EXPECT_EQ(describe_mismatch(m, "a", again, "b"), "");
  EXPECT_EQ(again.geoid_model, m.geoid_model);
}

}  // namespace
}  // namespace geoanchor::io
