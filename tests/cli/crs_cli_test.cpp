// `geoanchor convert --crs SRC --to-crs DST` and `geoanchor crs` end to end
// (issue 13): the real executable on CSV files, against PROJ's C API on the
// same pair (proj_create_crs_to_crs, normalised for visualisation), at
// random points inside each CRS's area of use; the columns' names are
// derived here from PROJ's axes, independently of geoanchor's rule; every
// bad-input case is checked for its message, its exit code and the absence
// of any output.

#include "crs_cli_fixture.hpp"

namespace geoanchor {
namespace {

using namespace crs_cli_fixture;

TEST_F(CrsCli, Issue13_ConversionsAgreeWithProjAtRandomPointsInFortyPlusCrs) {
  ASSERT_GE(kProjectedCrs.size(), 40u);
  std::vector<TableRow> table;
  std::uint32_t seed = 13;
  for (const auto& code : kProjectedCrs) table.push_back(compare_conversion(code, seed++));

  // The table in docs/crs-acceptance.md is this test's output; it lists
  // every CRS the test checks (GEOANCHOR_CRS_TABLE=PATH rewrites it).
  std::ostringstream md;
  md << "| CRS | name | method | columns | points | worst forward (m) | worst inverse (°) |\n|---|---|---|---|---|---|---|\n";
  std::vector<std::string> lines;
  for (const auto& r : table) {
    char f[32], i[32];
    std::snprintf(f, sizeof f, "%.1e", r.forward_m);
    std::snprintf(i, sizeof i, "%.1e", r.inverse_deg);
    std::ostringstream line;
    line << "| " << r.code << " | " << r.name << " | " << r.method << " | " << r.units << " | " << r.points << " | " << f
         << " | " << i << " |";
    lines.push_back(line.str());
    md << line.str() << "\n";
  }
  if (const char* out = std::getenv("GEOANCHOR_CRS_TABLE")) std::ofstream(out) << md.str();
  const std::string doc = slurp(fs::path(GEOANCHOR_SOURCE_DIR) / "docs" / "crs-acceptance.md");
  // Each row of the page is this run's row, numbers included.
  for (const auto& l : lines) EXPECT_NE(doc.find(l + "\n"), std::string::npos) << "docs/crs-acceptance.md lacks: " << l;
}

// Datum changes: the operation PROJ chooses for the pair, applied by
// geoanchor, agrees with PROJ's own application of it.
TEST_F(CrsCli, Issue13_DatumChangesAndCompoundHeightsAgreeWithProj) {
  struct Case {
    std::string from, to;
    double lon, lat;  // a point inside both areas, degrees
    bool height;
  };
  const std::vector<Case> cases = {
      {"EPSG:4283", "EPSG:7844", 151.2, -33.9, false},            // GDA94 → GDA2020 (Helmert)
      {"EPSG:4979", "EPSG:4326+5773", 8.6, 50.1, true},           // WGS 84 → EGM96 heights (geoid grid)
      {"EPSG:4979", "EPSG:32632+5773", 9.2, 47.4, true},          // and projected
      {"EPSG:7843", "EPSG:7912@2024.3", 151.2, -33.9, true},      // GDA2020 → ITRF2014 at the target epoch
  };
  for (const auto& c : cases) {
    const std::string to_def = c.to.substr(0, c.to.find('@'));
    const Axes in = columns_of(proj_, c.from), out = columns_of(proj_, to_def);
    std::ostringstream csv;
    csv << "id";
    for (const auto& n : in.names) csv << "," << n;
    csv << "\n";
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> jitter(-0.2, 0.2), hh(0.0, 500.0);
    std::vector<std::array<double, 3>> pts;
    for (int i = 0; i < 50; ++i) {
      pts.push_back({c.lon + jitter(rng), c.lat + jitter(rng), hh(rng)});
      csv << "P" << i;
      for (std::size_t k = 0; k < in.names.size(); ++k) csv << "," << fmt(pts.back()[k]);
      csv << "\n";
    }
    write("d.csv", csv.str());
    const Csv got = convert("d.csv", c.from, c.to);
    Pj op = proj_.op(c.from, to_def);
    ASSERT_TRUE(op) << c.from << " -> " << c.to;
    const double t = c.to.find('@') != std::string::npos ? std::stod(c.to.substr(c.to.find('@') + 1)) : HUGE_VAL;
    WorstCase worst;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      PJ_COORD r = proj_trans(op.get(), PJ_FWD, proj_coord(pts[i][0], pts[i][1], in.names.size() > 2 ? pts[i][2] : 0, t));
      double d = std::numeric_limits<double>::quiet_NaN();
      if (i < got.rows.size()) {
        d = 0;
        const double ref[3] = {r.xyz.x, r.xyz.y, r.xyz.z};
        for (std::size_t k = 0; k < out.names.size(); ++k) {
          const auto v = parse_finite_double(got.rows[i][got.col(out.names[k])]);
          const bool angular = out.geographic && k < 2;
          // Angles in degrees are held to 1e-9°, lengths to 1e-6 m: both as a ratio to the tolerance.
          const double diff = v ? std::abs(*v - ref[k]) * (angular ? 1.0 / kVsProjTol_deg : out.to_si[k] / kVsProjTol_m)
                                : std::numeric_limits<double>::quiet_NaN();
          d = testing::nan_max(d, diff);
        }
      }
      worst.add(d, i);
    }
    EXPECT_WORST_WITHIN(worst, 1.0) << c.from << " -> " << c.to << " (ratio to the tolerance)";
  }
}

// The four NTv2 grids of Debian's proj-data, through the CRS pairs whose
// EPSG operation uses them, against PROJ's hgridshift on the grid file
// itself (CHENYX06a.gsb is found although PROJ's database spells it
// CHENyx06a.gsb).
TEST_F(CrsCli, Issue13_NtV2GridsAgreeWithProjHgridshift) {
  struct Case {
    std::string from, to, grid;
    double lon, lat, spread;  // degrees
  };
  const std::vector<Case> cases = {
      {"EPSG:4272", "EPSG:4167", "nzgd2kgrid0005.gsb", 174.8, -41.3, 1.0},  // NZGD49 → NZGD2000
      {"EPSG:4275", "EPSG:4171", "ntf_r93.gsb", 2.35, 48.85, 1.0},          // NTF → RGF93 v1
      {"EPSG:4314", "EPSG:4258", "BETA2007.gsb", 9.7, 52.8, 0.5},           // DHDN → ETRS89, Niedersachsen
  };
  for (const auto& c : cases) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> j(-c.spread, c.spread);
    std::ostringstream csv;
    csv << "id,lat_deg,lon_deg\n";
    std::vector<std::array<double, 2>> pts;
    for (int i = 0; i < 50; ++i) {
      pts.push_back({c.lon + j(rng), c.lat + j(rng)});
      csv << "P" << i << "," << fmt(pts.back()[1]) << "," << fmt(pts.back()[0]) << "\n";
    }
    write("g.csv", csv.str());
    const Csv got = convert("g.csv", c.from, c.to);
    const std::string pipeline = "+proj=pipeline +step +proj=unitconvert +xy_in=deg +xy_out=rad +step +proj=hgridshift "
                                 "+grids=/usr/share/proj/" + c.grid + " +step +proj=unitconvert +xy_in=rad +xy_out=deg";
    Pj op(proj_create(proj_.ctx(), pipeline.c_str()));
    ASSERT_TRUE(op) << pipeline;
    WorstCase worst;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      PJ_COORD r = proj_trans(op.get(), PJ_FWD, proj_coord(pts[i][0], pts[i][1], 0, 0));
      double d = std::numeric_limits<double>::quiet_NaN();
      if (i < got.rows.size()) {
        const auto lat = parse_finite_double(got.rows[i][got.col("lat_deg")]);
        const auto lon = parse_finite_double(got.rows[i][got.col("lon_deg")]);
        // Degrees to metres on the ground (1° of latitude ≈ 111 km: an upper bound for both).
        if (lat && lon) d = testing::nan_max(std::abs(*lat - r.lp.phi), std::abs(*lon - r.lp.lam)) * 111320.0;
      }
      worst.add(d, i);
    }
    EXPECT_WORST_WITHIN(worst, kVsProjTol_m) << c.grid;
  }
  // LV03 → LV95: somerc, CHENYX06a, somerc.
  write("ch.csv", "id,easting_m,northing_m\nBE,600000,200000\nZH,683000,247000\n");
  const Csv got = convert("ch.csv", "EPSG:21781", "EPSG:2056");
  Pj op(proj_create(proj_.ctx(),
                    "+proj=pipeline +step +inv +proj=somerc +lat_0=46.9524055555556 +lon_0=7.43958333333333 +k_0=1 "
                    "+x_0=600000 +y_0=200000 +ellps=bessel +step +proj=hgridshift +grids=/usr/share/proj/CHENYX06a.gsb "
                    "+step +proj=somerc +lat_0=46.9524055555556 +lon_0=7.43958333333333 +k_0=1 +x_0=2600000 "
                    "+y_0=1200000 +ellps=bessel"));
  ASSERT_TRUE(op);
  const double in[2][2] = {{600000, 200000}, {683000, 247000}};
  WorstCase worst;
  for (std::size_t i = 0; i < 2; ++i) {
    PJ_COORD r = proj_trans(op.get(), PJ_FWD, proj_coord(in[i][0], in[i][1], 0, 0));
    double d = std::numeric_limits<double>::quiet_NaN();
    if (i < got.rows.size()) {
      const auto e = parse_finite_double(got.rows[i][got.col("easting_m")]);
      const auto n = parse_finite_double(got.rows[i][got.col("northing_m")]);
      if (e && n) d = testing::nan_max(std::abs(*e - r.xy.x), std::abs(*n - r.xy.y));
    }
    worst.add(d, i);
  }
  EXPECT_WORST_WITHIN(worst, kVsProjTol_m) << "CHENYX06a";
  const auto side = nlohmann::json::parse(slurp(path("out_ch.csv.geoanchor.json")));
  const auto& grids = side["operation"]["candidates"][0]["grids"];
  ASSERT_EQ(grids.size(), 1u);
  EXPECT_EQ(grids[0]["path"], "/usr/share/proj/CHENYX06a.gsb");
  EXPECT_EQ(grids[0]["sha256"].get<std::string>().size(), 64u);
}

// Outside a grid: refused, naming the grid and the point; nothing written.
TEST_F(CrsCli, Issue13_PointOutsideItsGridIsRefusedByName) {
  write("far.csv", "id,lat_deg,lon_deg\nOK,-41.3,174.8\nFAR,-30.0,160.0\n");
  const RunResult r = run("convert '" + path("far.csv").string() + "' --crs EPSG:4272 --to-crs EPSG:4167 -o '" +
                          path("o.csv").string() + "'");
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("far.csv:3"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("nzgd2kgrid0005"), std::string::npos) << r.err;
  EXPECT_EQ(leftovers({"far.csv"}), std::vector<std::string>{});
}

struct BadCase {
  const char* name;
  std::string header_and_rows;
  std::string args;
  int exit_code;
  std::vector<std::string> message;  // every piece must be in the error
};

TEST_F(CrsCli, Issue13_BadInputIsRefusedByNameWithNoOutput) {
  const std::vector<BadCase> cases = {
      {"unknown code", "id,lat_deg,lon_deg\nA,1,2\n", "--crs EPSG:999999 --to-crs EPSG:4326", 3, {"--crs", "EPSG:999999"}},
      {"unparsable WKT", "id,lat_deg,lon_deg\nA,1,2\n", "--crs 'GEOGCRS[\"x\",DATUM[' --to-crs EPSG:4326", 3,
       {"--crs", "GEOGCRS"}},
      {"feet header in metres", "id,easting_m,northing_m\nA,1,2\n", "--crs EPSG:2236 --to-crs EPSG:4269", 3,
       {"easting_m", "easting_ftus", "EPSG:2236"}},
      {"lat/lon for a projected CRS", "id,lat_deg,lon_deg\nA,1,2\n", "--crs EPSG:2236 --to-crs EPSG:4269", 3,
       {"lat_deg", "EPSG:2236"}},
      {"an ensemble's name where a realization is needed", "id,lat_deg,lon_deg,h_m\nA,50,8,100\n",
       "--crs 'WGS 84' --to-crs 'EPSG:7912@2024.5'", 3, {"E_CRS_ENSEMBLE", "WGS84(G2139)"}},
      {"ambiguous frame name", "id,lat_deg,lon_deg,h_m\nA,50,8,100\n", "--crs ETRS89 --to-crs EPSG:4979", 3,
       {"E_CRS_ENSEMBLE", "ETRF2000"}},
      {"missing grid", "id,lat_deg,lon_deg,h_m\nA,50,8,100\n", "--crs EPSG:4979 --to-crs EPSG:4326+3855", 3,
       {"E_CRS_GRID_MISSING", "us_nga_egm08_25.tif", "/usr/share/proj"}},
      {"dynamic CRS without epoch", "id,lat_deg,lon_deg,h_m\nA,50,8,100\n", "--crs ITRF2014 --to-crs EPSG:7843", 3,
       {"E_EPOCH_MISSING", "ITRF2014@2024.5"}},
      {"epoch on a static CRS", "id,lat_deg,lon_deg\nA,-33,151\n", "--crs EPSG:7844@2020.0 --to-crs EPSG:7856", 3,
       {"E_CRS_EPOCH", "static"}},
      {"only a ballpark operation", "id,lat_deg,lon_deg\nA,45,-100\n", "--crs EPSG:4267 --to-crs EPSG:4258", 3,
       {"E_CRS_NO_OPERATION", "ballpark"}},
      {"not a number", "id,lat_deg,lon_deg\nA,abc,2\n", "--crs EPSG:4326 --to-crs EPSG:32631", 3, {"bad.csv:2", "lat_deg", "abc"}},
      {"3-D output without input heights", "id,lat_deg,lon_deg\nA,1,2\n", "--crs EPSG:4326 --to-crs EPSG:4979", 2,
       {"EPSG:4979", "height"}},
      {"orthometric heights without a vertical CRS", "id,lat_deg,lon_deg,H_m\nA,1,2,3\n", "--crs EPSG:4326 --to-crs EPSG:4979", 3,
       {"H_m", "compound"}},
      {"a flag the CRS already says", "id,lat_deg,lon_deg\nA,1,2\n", "--crs EPSG:4326 --to-crs EPSG:32631 --ellipsoid GRS80", 2,
       {"--ellipsoid"}},
      {"PROJ string without +type=crs", "id,lat_deg,lon_deg\nA,1,2\n", "--crs '+proj=utm +zone=31' --to-crs EPSG:4326", 3,
       {"+type=crs"}},
      {"an operation PROJ lists but cannot run", "id,lat_grad,lon_grad\nA,38.9,8.5\n", "--crs EPSG:4816 --to-crs EPSG:22300",
       3, {"E_CRS_NO_OPERATION", "Unsupported conversion method: Tunisia Mining Grid"}},
      {"a datum change outside its area of use", "id,lat_deg,lon_deg\nPE,-12,-77\n", "--crs EPSG:4618 --to-crs EPSG:4674",
       3, {"E_CRS_TRANSFORM", "bad.csv:2", "SAD69 to SIRGAS 2000 (1)", "Brazil", "lies outside the area of use"}},
      {"an empty epoch", "id,lat_deg,lon_deg\nA,1,2\n", "--crs EPSG:4326@ --to-crs EPSG:32631", 3, {"E_EPOCH", "after '@'"}},
  };
  // Text after a WKT's closing bracket is an epoch or an error, never dropped.
  const char* one_line[] = {"MULTILINE=NO", nullptr};
  Pj itrf_crs = proj_.crs("EPSG:7912");
  const std::string itrf = proj_as_wkt(proj_.ctx(), itrf_crs.get(), PJ_WKT2_2019, one_line);
  std::vector<BadCase> all = cases;
  all.push_back({"text after a WKT", "id,lat_deg,lon_deg,h_m\nA,50,8,100\n", "--crs '" + itrf + " junk' --to-crs EPSG:7789",
                 3, {"E_CRS", "after the CRS's closing bracket", "junk"}});
  all.push_back({"an epoch after a WKT that is no decimal year", "id,lat_deg,lon_deg,h_m\nA,50,8,100\n",
                 "--crs '" + itrf + "@x2024.5' --to-crs EPSG:7789", 3, {"E_EPOCH", "x2024.5"}});
  all.push_back({"an empty epoch after a WKT", "id,lat_deg,lon_deg,h_m\nA,50,8,100\n", "--crs '" + itrf + "@' --to-crs EPSG:7789",
                 3, {"E_EPOCH", "nothing after '@'"}});
  for (const auto& c : all) {
    SCOPED_TRACE(c.name);
    write("bad.csv", c.header_and_rows);
    const RunResult r = run("convert '" + path("bad.csv").string() + "' " + c.args + " -o '" + path("o.csv").string() + "'");
    EXPECT_EQ(r.exit_code, c.exit_code) << r.err;
    for (const auto& piece : c.message) EXPECT_NE(r.err.find(piece), std::string::npos) << piece << " in: " << r.err;
    EXPECT_EQ(leftovers({"bad.csv"}), std::vector<std::string>{});
  }
}

// Frame names: case-insensitive, the usual aliases, mapped to PROJ's CRS of
// the frame; the catalog frame of an EPSG CRS is named.
TEST_F(CrsCli, Issue13_CrsCommandReportsWhatItUnderstood) {
  const RunResult a = run("crs itrf14@2024.5 --json");
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const auto j = nlohmann::json::parse(a.out);
  EXPECT_EQ(j["schema"], "geoanchor.crs/1");
  EXPECT_EQ(j["identifier"], "EPSG:7912");
  EXPECT_EQ(j["catalog_frame"], "ITRF2014");
  EXPECT_EQ(j["needs_epoch"], true);
  EXPECT_EQ(j["coordinate_epoch"], 2024.5);

  const RunResult b = run("crs EPSG:7844 --json");
  ASSERT_EQ(b.exit_code, 0) << b.err;
  const auto k = nlohmann::json::parse(b.out);
  EXPECT_EQ(k["catalog_frame"], "GDA2020");
  EXPECT_EQ(k["needs_epoch"], false);
  EXPECT_EQ(k["ellipsoid"]["name"], "GRS 1980");

  const RunResult c = run("crs EPSG:2236 --json");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const auto f = nlohmann::json::parse(c.out);
  EXPECT_EQ(f["columns"], nlohmann::json::array({"easting_ftus", "northing_ftus"}));
  EXPECT_EQ(f["axes"][0]["unit"], "US survey foot");
  EXPECT_EQ(f["projection"]["method"], "Transverse Mercator");
  // The WKT2 it writes is read back by PROJ as the same CRS.
  Pj original = proj_.crs("EPSG:2236");
  Pj back(proj_create(proj_.ctx(), f["wkt2"].get<std::string>().c_str()));
  ASSERT_TRUE(back);
  EXPECT_TRUE(proj_is_equivalent_to(original.get(), back.get(), PJ_COMP_EQUIVALENT));

  // A polar projection's axes point along meridians (PROJ: "South along 90°E").
  const RunResult ups = run("crs EPSG:5041 --json");
  ASSERT_EQ(ups.exit_code, 0) << ups.err;
  const auto u = nlohmann::json::parse(ups.out);
  EXPECT_EQ(u["axes"][0]["direction"], "south");
  EXPECT_EQ(u["axes"][0]["meridian_deg"], 90.0);
  EXPECT_EQ(u["axes"][1]["meridian_deg"], 180.0);
  EXPECT_NE(run("crs EPSG:5041").out.find("south along 90°E"), std::string::npos);

  const RunResult d = run("crs 'WGS 84 (G2139)'");
  EXPECT_EQ(d.exit_code, 0) << d.err;
  EXPECT_NE(d.out.find("World Geodetic System 1984 (G2139)"), std::string::npos) << d.out;
  const RunResult e = run("crs WGS84");
  EXPECT_EQ(e.exit_code, 3);
  EXPECT_NE(e.err.find("WGS84(G2139)"), std::string::npos) << e.err;
  const RunResult g = run("crs 'NAD83(CSRS)'");
  EXPECT_EQ(g.exit_code, 3);
  EXPECT_NE(g.err.find("NAD83(CSRSv8)"), std::string::npos) << g.err;
}

// Point 7: the WKT2 geoanchor writes for a compound CRS names its geoid
// model (EPSG's "WGS 84 to EGM96 height (1)", EPSG:10084, for EGM96
// heights), which PROJ reads back as the same CRS, applying the same grid.
TEST_F(CrsCli, Issue13_ACompoundCrsIsWrittenWithItsGeoidModel) {
  const RunResult c = run("crs EPSG:32632+5773 --json");
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const auto j = nlohmann::json::parse(c.out);
  EXPECT_EQ(j["vertical"]["geoid_operation_id"], "EPSG:10084");
  write("h.csv", "id,lat_deg,lon_deg,h_m\nZH,47.4,8.5,500\n");
  const RunResult r = run("convert '" + path("h.csv").string() + "' --crs EPSG:4979 --to-crs EPSG:32632+5773 -o '" +
                          path("H.csv").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string text = slurp(path("H.csv"));
  const std::string line = text.substr(0, text.find('\n'));
  ASSERT_EQ(line.rfind("# crs = ", 0), 0u) << line;
  const std::string wkt = line.substr(8);
  EXPECT_NE(wkt.find("GEOIDMODEL[\"WGS 84 to EGM96 height (1)\",ID[\"EPSG\",10084]]"), std::string::npos) << wkt;
  Pj written = proj_.crs(wkt), asked = proj_.crs("EPSG:32632+5773");
  ASSERT_TRUE(written) << wkt;
  EXPECT_TRUE(proj_is_equivalent_to_with_ctx(proj_.ctx(), written.get(), asked.get(), PJ_COMP_EQUIVALENT));
  // The same heights back from the written WKT as from EPSG's code.
  Pj a = proj_.op(wkt, "EPSG:4979"), b = proj_.op("EPSG:32632+5773", "EPSG:4979");
  ASSERT_TRUE(a && b);
  const PJ_COORD pa = proj_trans(a.get(), PJ_FWD, proj_coord(464000, 5250000, 450, 0));
  const PJ_COORD pb = proj_trans(b.get(), PJ_FWD, proj_coord(464000, 5250000, 450, 0));
  EXPECT_LT(std::abs(pa.xyz.z - pb.xyz.z), kVsProjTol_m);
  EXPECT_GT(std::abs(pa.xyz.z - 450.0), 40.0);  // the geoid was applied (N ≈ 48 m here)
  // NAVD88 heights are GEOID18 in CONUS and GEOID12B in Alaska: no one geoid model is named.
  const RunResult navd = run("crs EPSG:6318+5703 --json");
  ASSERT_EQ(navd.exit_code, 0) << navd.err;
  const auto n = nlohmann::json::parse(navd.out);
  EXPECT_TRUE(n["vertical"]["geoid_operation"].is_null()) << n["vertical"].dump();
  EXPECT_EQ(n["wkt2"].get<std::string>().find("GEOIDMODEL"), std::string::npos);
  // And the file reads back through its own statement.
  const RunResult back = run("convert '" + path("H.csv").string() + "' --to-crs EPSG:4979 -o '" + path("back.csv").string() + "'");
  EXPECT_EQ(back.exit_code, 0) << back.err;
}

// Japan's plane zones are X north, Y east: "easting" is the axis PROJ's
// visualisation order puts first, with the CRS's own numbers.
TEST_F(CrsCli, Issue13_AxisOrderFollowsProjsVisualisationOrder) {
  write("jp.csv", "id,lat_deg,lon_deg\nTokyo,35.68,139.77\n");
  const Csv got = convert("jp.csv", "EPSG:6668", "EPSG:6677");
  ASSERT_EQ(got.header, (std::vector<std::string>{"id", "easting_m", "northing_m"}));
  Pj op = proj_.op("EPSG:6668", "EPSG:6677");
  PJ_COORD r = proj_trans(op.get(), PJ_FWD, proj_coord(139.77, 35.68, 0, 0));
  ASSERT_EQ(got.rows.size(), 1u);
  EXPECT_NEAR(*parse_finite_double(got.rows[0][1]), r.xy.x, kVsProjTol_m);
  EXPECT_NEAR(*parse_finite_double(got.rows[0][2]), r.xy.y, kVsProjTol_m);
  // The first axis of EPSG:6677 as written is X (north): the visualisation order is not the CRS's.
  Pj c = proj_.crs("EPSG:6677");
  Pj cs(proj_crs_get_coordinate_system(proj_.ctx(), c.get()));
  const char* dir = nullptr;
  proj_cs_get_axis_info(proj_.ctx(), cs.get(), 0, nullptr, nullptr, &dir, nullptr, nullptr, nullptr, nullptr);
  EXPECT_STREQ(dir, "north");
}

}  // namespace
}  // namespace geoanchor

namespace geoanchor {
namespace {

// Points outside the source CRS's area of use are converted with one
// warning, counted and naming the first, in the sidecar too; points inside
// give none (whether the batch is decided at once or point by point). A
// datum change is another matter: its parameters hold in its own area only,
// so a point outside it is refused (PROJ would apply it anyway).
TEST_F(CrsCli, Issue13_PointsOutsideTheAreaOfUseAreWarnedAndRecorded) {
  // Lambert-93 covers France (longitude -9.86° to 10.38°, latitude 41.15° to 51.56°):
  // (3000000, 6600000) lies near 31.7°E, outside.
  write("l93.csv", "id,easting_m,northing_m\nPARIS,652000,6862000\nLYON,842000,6519000\nFAR,3000000,6600000\n");
  const Csv got = convert("l93.csv", "EPSG:2154", "EPSG:4171");  // RGF93 v1 geographic: the same datum
  EXPECT_EQ(got.rows.size(), 3u);
  const auto side = nlohmann::json::parse(slurp(path("out_l93.csv.geoanchor.json")));
  std::string warning;
  for (const auto& w : side["warnings"]) {
    if (w.get<std::string>().find("outside the area of use") != std::string::npos) warning = w;
  }
  EXPECT_NE(warning.find("1 of 3 points"), std::string::npos) << side["warnings"].dump();
  EXPECT_NE(warning.find("l93.csv:4"), std::string::npos) << warning;

  write("in.csv", "id,easting_m,northing_m\nPARIS,652000,6862000\nLYON,842000,6519000\n");
  convert("in.csv", "EPSG:2154", "EPSG:3035");
  const auto inside = nlohmann::json::parse(slurp(path("out_in.csv.geoanchor.json")));
  for (const auto& w : inside["warnings"]) {
    EXPECT_EQ(w.get<std::string>().find("outside the area of use"), std::string::npos) << w;
  }

  // Into LAEA Europe on ETRS89, through "RGF93 v1 to ETRS89 (1)" (France):
  // FAR is refused by name and nothing is written.
  const RunResult r = run("convert '" + path("l93.csv").string() + "' --crs EPSG:2154 --to-crs EPSG:3035 -o '" +
                          path("far.csv").string() + "'");
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("l93.csv:4"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("lies outside the area of use of PROJ's only operation"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(path("far.csv")));
}

}  // namespace
}  // namespace geoanchor

namespace geoanchor {
namespace {

// transform --from/--to with CRSs: the catalog's frame path between the
// CRSs' datums (EPSG:7856 is on GDA2020), PROJ's conversions at both ends,
// against PROJ's own operation for the pair at the target epoch.
TEST_F(CrsCli, Issue13_TransformReadsCrssWhoseDatumIsACatalogFrame) {
  write("mga.csv", "id,easting_m,northing_m,h_m\nA,334368.634,6250948.345,50\nB,315290.169,6236040.861,10\n");
  const RunResult r = run("transform '" + path("mga.csv").string() + "' --from EPSG:7856 --to 'EPSG:7912@2024.3' -o '" +
                          path("t.csv").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Csv got = parse_csv(slurp(path("t.csv")));
  ASSERT_EQ(got.header, (std::vector<std::string>{"id", "lat_deg", "lon_deg", "h_m"}));
  Pj src2d = proj_.crs("EPSG:7856");
  Pj src(proj_crs_promote_to_3D(proj_.ctx(), nullptr, src2d.get()));
  Pj dst = proj_.crs("EPSG:7912");
  Pj raw(proj_create_crs_to_crs_from_pj(proj_.ctx(), src.get(), dst.get(), nullptr, nullptr));
  Pj op(proj_normalize_for_visualization(proj_.ctx(), raw.get()));
  const double in[2][3] = {{334368.634, 6250948.345, 50}, {315290.169, 6236040.861, 10}};
  WorstCase angle, height;
  for (std::size_t i = 0; i < 2; ++i) {
    PJ_COORD e = proj_trans(op.get(), PJ_FWD, proj_coord(in[i][0], in[i][1], in[i][2], 2024.3));
    double da = std::numeric_limits<double>::quiet_NaN(), dh = da;
    if (i < got.rows.size()) {
      da = testing::nan_max(std::abs(*parse_finite_double(got.rows[i][1]) - e.lpz.phi),
                            std::abs(*parse_finite_double(got.rows[i][2]) - e.lpz.lam));
      dh = std::abs(*parse_finite_double(got.rows[i][3]) - e.lpz.z);
    }
    angle.add(da, i);
    height.add(dh, i);
  }
  EXPECT_WORST_WITHIN(angle, kVsProjTol_deg);
  EXPECT_WORST_WITHIN(height, kVsProjTol_m);

  // Without a height, and on a datum the catalog does not hold: refused by name, nothing written.
  write("two.csv", "id,easting_m,northing_m\nA,334368.634,6250948.345\n");
  const RunResult flat = run("transform '" + path("two.csv").string() + "' --from EPSG:7856 --to 'EPSG:7912@2024.3' -o '" +
                             path("x.csv").string() + "'");
  EXPECT_EQ(flat.exit_code, 3);
  EXPECT_NE(flat.err.find("height"), std::string::npos) << flat.err;
  const RunResult osgb = run("transform '" + path("mga.csv").string() + "' --from EPSG:27700 --to 'ITRF2014@2024.3' -o '" +
                             path("x.csv").string() + "'");
  EXPECT_EQ(osgb.exit_code, 3);
  EXPECT_NE(osgb.err.find("Ordnance Survey of Great Britain 1936"), std::string::npos) << osgb.err;
  EXPECT_FALSE(fs::exists(path("x.csv")));
}

}  // namespace
}  // namespace geoanchor

namespace geoanchor {
namespace {

// Issue 13 point 7: the output CSV states its CRS above the header (PROJ's
// WKT2, which PROJ reads back as the same CRS, and the coordinate epoch of
// a dynamic CRS); convert reads that statement back without --crs, and
// refuses a --crs that contradicts it.
TEST_F(CrsCli, Issue13_TheCsvStatesItsCrsAndIsReadBackByIt) {
  write("syd.csv", "# surveyed 2026-11-30\nid,lat_deg,lon_deg,h_m\nA,-33.8688,151.2093,50\n");
  convert("syd.csv", "EPSG:7843", "EPSG:7856");
  const std::string text = slurp(path("out_syd.csv"));
  ASSERT_EQ(text.rfind("# crs = PROJCRS[", 0), 0u) << text.substr(0, 80);
  const std::string wkt = text.substr(8, text.find('\n') - 8);
  Pj stated(proj_create(proj_.ctx(), wkt.c_str()));
  ASSERT_TRUE(stated) << wkt.substr(0, 80);
  Pj mga = proj_.crs("EPSG:7856");
  Pj mga3d(proj_crs_promote_to_3D(proj_.ctx(), nullptr, mga.get()));
  EXPECT_TRUE(proj_is_equivalent_to(stated.get(), mga3d.get(), PJ_COMP_EQUIVALENT));
  EXPECT_NE(text.find("# surveyed 2026-11-30\n"), std::string::npos);  // other comments stay

  // Back without --crs: the statement is read, and replaced by the output's own.
  const RunResult back = run("convert '" + path("out_syd.csv").string() + "' --to-crs EPSG:7843 -o '" + path("b.csv").string() + "'");
  ASSERT_EQ(back.exit_code, 0) << back.err;
  const std::string b = slurp(path("b.csv"));
  EXPECT_EQ(b.rfind("# crs = GEOGCRS[\"GDA2020\"", 0), 0u) << b.substr(0, 80);
  EXPECT_EQ(b.find("PROJCRS"), std::string::npos);
  const Csv table = parse_csv(b);
  ASSERT_EQ(table.rows.size(), 1u);
  EXPECT_NEAR(*parse_finite_double(table.rows[0][table.col("lat_deg")]), -33.8688, kVsProjTol_deg);

  // A --crs that contradicts it: refused, nothing written.
  const RunResult clash = run("convert '" + path("out_syd.csv").string() + "' --crs EPSG:7855 --to-crs EPSG:7843 -o '" +
                              path("c.csv").string() + "'");
  EXPECT_EQ(clash.exit_code, 3);
  EXPECT_NE(clash.err.find("E_CRS_CONFLICT"), std::string::npos) << clash.err;
  EXPECT_FALSE(fs::exists(path("c.csv")));

  // A dynamic output at the epoch the operation was evaluated at.
  convert("syd.csv", "ITRF2014@2020.0", "ITRF2020");
  EXPECT_NE(slurp(path("out_syd.csv")).find("\n# coordinate_epoch = 2020.0\n"), std::string::npos);
}

}  // namespace
}  // namespace geoanchor

namespace geoanchor {
namespace {

// fit --src-crs / "# source_crs = …": control in State Plane feet (EPSG:2236)
// against the same marks in NAD83 geographic coordinates made by PROJ: the
// fitted Helmert is the identity (a unit or axis read wrongly would show as
// metres of translation or a large scale).
TEST_F(CrsCli, Issue13_FitReadsControlInAnyCrs) {
  constexpr double kIdentity_m = 1e-4;    // translation, metres (PROJ's own round trip is ~1e-9 m)
  constexpr double kIdentity_ppm = 1e-3;  // scale
  // The same marks: in State Plane feet (source, read through --src-crs) and
  // as ECEF on NAD83's GRS 80 made by PROJ's cart (target, geoanchor's own
  // x_dst_m columns), so the CRS path is checked against an independent one.
  Pj op = proj_.op("EPSG:4269", "EPSG:2236");
  PJ* cart = proj_create(proj_.ctx(), "+proj=pipeline +step +proj=unitconvert +xy_in=deg +xy_out=rad +step +proj=cart +ellps=GRS80");
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> dlat(-0.1, 0.1), dlon(-0.1, 0.1), hh(0.0, 60.0);
  std::ostringstream csv, stated;
  const std::string header = "id,easting_src_ftus,northing_src_ftus,h_src_m,x_dst_m,y_dst_m,z_dst_m\n";
  csv << header;
  for (int i = 0; i < 12; ++i) {
    const double lat = 28.4 + dlat(rng), lon = -81.3 + dlon(rng), h = hh(rng);
    PJ_COORD p = proj_trans(op.get(), PJ_FWD, proj_coord(lon, lat, 0, 0));
    PJ_COORD x = proj_trans(cart, PJ_FWD, proj_coord(lon, lat, h, 0));
    csv << "P" << i << "," << fmt(p.xy.x) << "," << fmt(p.xy.y) << "," << fmt(h) << "," << fmt(x.xyz.x) << ","
        << fmt(x.xyz.y) << "," << fmt(x.xyz.z) << "\n";
  }
  proj_destroy(cart);
  write("ctl.csv", csv.str());
  const std::string common = " --model helmert7 --convention position_vector -o '" + path("t.json").string() + "' --overwrite";
  const RunResult r = run("fit '" + path("ctl.csv").string() + "' --src-crs EPSG:2236" + common);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto written = nlohmann::json::parse(slurp(path("t.json")));
  auto params = written["parameters"];
  for (const char* t : {"tx_m", "ty_m", "tz_m"}) EXPECT_LT(std::abs(params[t].get<double>()), kIdentity_m) << t;
  // The transform file records how the source was read: the CRS and PROJ's operation.
  EXPECT_EQ(written["control_crs"]["source"]["crs"], "EPSG:2236");
  EXPECT_EQ(written["control_crs"]["source"]["operation"]["candidates"][0]["points"], 12);
  EXPECT_FALSE(written["control_crs"].contains("target"));
  EXPECT_LT(std::abs(params["ds_ppm"].get<double>()), kIdentity_ppm);

  // The same file stating its CRS above the header needs no --src-crs.
  write("stated.csv", "# source_crs = EPSG:2236\n" + csv.str());
  const RunResult s = run("fit '" + path("stated.csv").string() + "'" + common);
  ASSERT_EQ(s.exit_code, 0) << s.err;
  params = nlohmann::json::parse(slurp(path("t.json")))["parameters"];
  EXPECT_LT(std::abs(params["tx_m"].get<double>()), kIdentity_m);

  // Refused by name: a contradicting flag, metres where the CRS is in feet, a grid said twice.
  const RunResult clash = run("fit '" + path("stated.csv").string() + "' --src-crs EPSG:2881" + common);
  EXPECT_EQ(clash.exit_code, 3);
  EXPECT_NE(clash.err.find("E_CRS_CONFLICT"), std::string::npos) << clash.err;
  std::string metres = csv.str();
  metres.replace(metres.find("easting_src_ftus"), 16, "easting_src_m");
  write("metres.csv", metres);
  const RunResult unit = run("fit '" + path("metres.csv").string() + "' --src-crs EPSG:2236" + common);
  EXPECT_EQ(unit.exit_code, 3);
  EXPECT_NE(unit.err.find("easting_src_ftus"), std::string::npos) << unit.err;
  const RunResult twice = run("fit '" + path("ctl.csv").string() + "' --src-crs EPSG:2236 --src-zone 17N" + common);
  EXPECT_EQ(twice.exit_code, 2);
  EXPECT_NE(twice.err.find("--src-crs"), std::string::npos) << twice.err;
}

}  // namespace
}  // namespace geoanchor

namespace geoanchor {
namespace {

// Where several operations compete, the one used for each point is PROJ's
// own choice (proj_get_suggested_operation): against proj_trans of
// proj_create_crs_to_crs on the same pair, at points chosen where a simpler
// rule goes wrong (a geocentric source, whose latitude must come from x, y
// and z; onshore Tunisia, where an offshore set has the better accuracy),
// and for a pair whose best route PROJ finds only past a missing grid
// (GDA94 -> ITRF2014).
TEST_F(CrsCli, Issue13_TheOperationPerPointIsProjsOwnChoice) {
  struct Case {
    const char* what;
    std::string from, to;
    std::vector<std::array<double, 3>> points;  // in `from`, visualisation order
    double t;
    std::string reference_from;  // the source PROJ's reference starts from ("": `from`)
  };
  // Surface points in Dar es Salaam as WGS 84 ECEF (PROJ, from -6.8°, 39.28°, 0 m and -6.85°, 39.2°, 30 m).
  Pj to_ecef = proj_.op("EPSG:4979", "EPSG:4978");
  std::vector<std::array<double, 3>> dar, dar_geographic = {{39.28, -6.8, 0.0}, {39.2, -6.85, 30.0}};
  for (const auto& g : dar_geographic) {
    PJ_COORD e = proj_trans(to_ecef.get(), PJ_FWD, proj_coord(g[0], g[1], g[2], 0));
    dar.push_back({e.xyz.x, e.xyz.y, e.xyz.z});
  }
  const std::vector<Case> cases = {
      // PROJ 9.1.1 chooses a geocentric point's operation as if it were at
      // latitude 0 (Kenya's set here, 3.6 m off); geoanchor chooses from the
      // point's latitude: PROJ's choice for the same point given as latitude,
      // longitude and height.
      {"geocentric WGS 84 -> Arc 1960 in Dar es Salaam", "EPSG:4978", "EPSG:4210", dar, 0.0, "EPSG:4979"},
      {"Carthage -> WGS 84 (G1762) onshore Tunis", "EPSG:4223", "EPSG:9057@2024.5", {{10.2, 36.8, 0.0}, {10.1, 36.7, 0.0}},
       2024.5, ""},
      {"GDA94 -> ITRF2014 at 2024.3", "EPSG:4939", "EPSG:7912@2024.3", {{151.2, -33.9, 10.0}, {115.86, -31.95, 20.0}},
       2024.3, ""},
      // Two static frames with a time-dependent operation between them: the epoch given on either.
      {"ETRF2000@2020.0 -> ETRF2014", "EPSG:7931@2020.0", "EPSG:8403", {{8.0, 50.0, 100.0}, {15.0, 45.0, 300.0}}, 2020.0, ""},
      // One batch across ED50's national operations (EPSG 1133-1989, each
      // for its country: Norway, Denmark, Türkiye, France, Sicily, Portugal,
      // Greece, Malta, Sardinia, Cyprus; not Spain, whose best needs a grid
      // that is not here), cities repeated in between: each point takes its
      // own country's, as proj_trans does.
      {"ED50 -> WGS 84 (G1762) across Europe in one batch",
       "EPSG:4230",
       "EPSG:9057@2024.5",
       {{10.75, 59.91, 0.0}, {12.57, 55.68, 0.0}, {32.85, 39.93, 0.0}, {2.35, 48.85, 0.0}, {13.36, 38.12, 0.0},
        {-9.14, 38.72, 0.0}, {23.73, 37.98, 0.0}, {10.75, 59.91, 0.0}, {14.51, 35.90, 0.0}, {9.11, 39.22, 0.0},
        {33.36, 35.17, 0.0}, {12.57, 55.68, 0.0}, {2.35, 48.85, 0.0}},
       2024.5,
       ""},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.what);
    const std::string to_def = c.to.substr(0, c.to.find('@')), from_def = c.from.substr(0, c.from.find('@'));
    Axes in = columns_of(proj_, from_def), out = columns_of(proj_, to_def);
    std::ostringstream csv;
    csv << "id," << in.names[0] << "," << in.names[1];
    if (in.names.size() == 3) csv << "," << in.names[2];
    csv << "\n";
    for (std::size_t i = 0; i < c.points.size(); ++i) {
      csv << "P" << i << "," << fmt(c.points[i][0]) << "," << fmt(c.points[i][1]);
      if (in.names.size() == 3) csv << "," << fmt(c.points[i][2]);
      csv << "\n";
    }
    write("p.csv", csv.str());
    const Csv got = convert("p.csv", c.from, c.to);
    const bool geographic_reference = !c.reference_from.empty();
    Pj op = proj_.op(geographic_reference ? c.reference_from : from_def, to_def);
    ASSERT_TRUE(op);
    WorstCase worst;
    for (std::size_t i = 0; i < c.points.size(); ++i) {
      const auto& q = geographic_reference ? dar_geographic[i] : c.points[i];
      PJ_COORD r = proj_trans(op.get(), PJ_FWD, proj_coord(q[0], q[1], q[2], c.t));
      double d = std::numeric_limits<double>::quiet_NaN();
      if (i < got.rows.size()) {
        d = 0.0;
        const double ref[3] = {r.xyz.x, r.xyz.y, r.xyz.z};
        for (std::size_t k = 0; k < std::min<std::size_t>(out.names.size(), 3); ++k) {
          const auto v = parse_finite_double(got.rows[i][got.col(out.names[k])]);
          const bool angular = out.geographic && k < 2;
          d = testing::nan_max(d, v ? std::abs(*v - ref[k]) * (angular ? 1.0 / kVsProjTol_deg : out.to_si[k] / kVsProjTol_m)
                                    : std::numeric_limits<double>::quiet_NaN());
        }
      }
      worst.add(d, i);
    }
    EXPECT_WORST_WITHIN(worst, 1.0) << "(ratio to the tolerance)";
  }
}

// A better operation whose grid is missing: refused naming it, or with
// --allow-fallback the next one, counted in the warnings.
TEST_F(CrsCli, Issue13_AFallbackPastAMissingGridIsRefusedOrCounted) {
  write("es.csv", "id,lat_deg,lon_deg\nMAD,40.4,-3.7\nBCN,41.4,2.2\n");
  const RunResult refused = run("convert '" + path("es.csv").string() + "' --crs EPSG:4230 --to-crs EPSG:4258 -o '" +
                                path("o.csv").string() + "'");
  EXPECT_EQ(refused.exit_code, 3);
  EXPECT_NE(refused.err.find("E_CRS_GRID_MISSING"), std::string::npos) << refused.err;
  EXPECT_FALSE(fs::exists(path("o.csv")));
  const RunResult allowed = run("convert '" + path("es.csv").string() + "' --crs EPSG:4230 --to-crs EPSG:4258 -o '" +
                                path("o.csv").string() + "' --allow-fallback");
  ASSERT_EQ(allowed.exit_code, 0) << allowed.err;
  EXPECT_NE(allowed.err.find("2 points were moved by a worse operation"), std::string::npos) << allowed.err;

  // One batch whose first point (Cabo da Roca, west of 9.37°W) lies outside
  // the area of the better operation with the missing grid (EPSG:15932,
  // Spain's box) and whose second (Lisbon) inside it: the second is still
  // judged on its own, as PROJ judges each point.
  write("pt.csv", "id,lat_deg,lon_deg\nCABO,38.78,-9.50\nLIS,38.72,-9.14\n");
  const RunResult mixed = run("convert '" + path("pt.csv").string() + "' --crs EPSG:4230 --to-crs EPSG:4258 -o '" +
                              path("p.csv").string() + "'");
  EXPECT_EQ(mixed.exit_code, 3) << mixed.err;
  EXPECT_NE(mixed.err.find("E_CRS_GRID_MISSING"), std::string::npos) << mixed.err;
  EXPECT_NE(mixed.err.find("pt.csv:3"), std::string::npos) << mixed.err;
  EXPECT_FALSE(fs::exists(path("p.csv")));
}

}  // namespace
}  // namespace geoanchor

namespace geoanchor {
namespace {

// A file that states its CRS is never read by a path that does not read
// the statement (it would go on stating the input's CRS for the output):
// refused, nothing written; transform with a CRS checks it and states its
// own output's CRS and epoch.
TEST_F(CrsCli, Issue13_AStatedCrsIsReadOrRefusedNeverCopied) {
  write("g.csv", "id,lat_deg,lon_deg,h_m\nA,-33.8688,151.2093,50\n");
  convert("g.csv", "EPSG:4939", "EPSG:7843");  // makes a file stating GDA2020 geographic 3D
  const auto stated = path("out_g.csv");
  fs::copy_file(stated, path("s.csv"));
  const RunResult typed = run("convert '" + path("s.csv").string() + "' --to ecef -o '" + path("x.csv").string() + "'");
  EXPECT_EQ(typed.exit_code, 3);
  EXPECT_NE(typed.err.find("E_CRS_STATED"), std::string::npos) << typed.err;
  const RunResult framed = run("transform '" + path("s.csv").string() + "' --from GDA2020 --to ITRF2014@2024.3 -o '" +
                               path("x.csv").string() + "'");
  EXPECT_EQ(framed.exit_code, 3);
  EXPECT_NE(framed.err.find("E_CRS_STATED"), std::string::npos) << framed.err;
  EXPECT_FALSE(fs::exists(path("x.csv")));

  const RunResult moved = run("transform '" + path("s.csv").string() + "' --from EPSG:7843 --to 'EPSG:7912@2024.3' -o '" +
                              path("t.csv").string() + "'");
  ASSERT_EQ(moved.exit_code, 0) << moved.err;
  const std::string t = slurp(path("t.csv"));
  EXPECT_EQ(t.rfind("# crs = GEOGCRS[\"ITRF2014\"", 0), 0u) << t.substr(0, 60);
  EXPECT_NE(t.find("\n# coordinate_epoch = 2024.3\n"), std::string::npos);
  EXPECT_EQ(t.find("GDA2020"), std::string::npos);  // the input's statement is not copied
  const RunResult clash = run("transform '" + path("s.csv").string() + "' --from EPSG:4939 --to 'EPSG:7912@2024.3' -o '" +
                              path("c.csv").string() + "'");
  EXPECT_EQ(clash.exit_code, 3);
  EXPECT_NE(clash.err.find("E_CRS_CONFLICT"), std::string::npos) << clash.err;
}

}  // namespace
}  // namespace geoanchor
