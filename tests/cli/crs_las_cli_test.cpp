// `geoanchor apply --crs/--to-crs` on LAS tiles in any CRS, and geoids by
// name or path (issue 13, moved from crs_cli_test.cpp): the real executable
// against PROJ's C API on the same points.

#include "crs_cli_fixture.hpp"

namespace geoanchor {
namespace {

using namespace crs_cli_fixture;

// PROJ's WKT2:2019 of `def`, promoted to 3-D when `to_3d`, on one line.
std::string wkt_of(const Proj& proj, const std::string& def, bool to_3d) {
  Pj c = proj.crs(def);
  Pj p(c && to_3d ? proj_crs_promote_to_3D(proj.ctx(), nullptr, c.get()) : nullptr);
  const char* opts[] = {"MULTILINE=NO", nullptr};
  const char* w = (p ? p : c) ? proj_as_wkt(proj.ctx(), p ? p.get() : c.get(), PJ_WKT2_2019, opts) : nullptr;
  return w ? w : "";
}

class CrsLas : public CrsCli {
 protected:
  struct Tile {
    std::vector<std::array<double, 3>> xyz;  // the values the file holds (quantized)
  };
  // A LAS 1.4 file (point format 6) in CRS `wkt`, its points at `points`
  // quantized at `scale` (per axis); returns the values the file holds.
  Tile las(const std::string& name, const std::string& wkt, const std::vector<std::array<double, 3>>& points,
           const std::array<double, 3>& scale) {
    testing::LasBuild b;
    b.scale = scale;
    for (std::size_t k = 0; k < 3; ++k) b.offset[k] = std::round(points.front()[k]);
    Tile t;
    for (const auto& p : points) {
      std::array<std::int32_t, 3> q{};
      std::array<double, 3> v{};
      for (std::size_t k = 0; k < 3; ++k) {
        q[k] = static_cast<std::int32_t>(std::lround((p[k] - b.offset[k]) / scale[k]));
        v[k] = q[k] * scale[k] + b.offset[k];
      }
      b.xyz.push_back(q);
      t.xyz.push_back(v);
    }
    b.vlrs.push_back({"LASF_Projection", 2112, "", std::vector<std::uint8_t>(wkt.begin(), wkt.end())});
    fs::create_directories(path(name).parent_path());
    testing::write_bytes(path(name), testing::build_las(b));
    return t;
  }
  json verify(const fs::path& las) {
    const std::string text = las_verify_text(las);
    return text.empty() ? json() : json::parse(text);
  }
  // The written points (`got`, as las-verify reads them) against PROJ's `op`
  // on the input's points, in units of each axis's tolerance: half the
  // output's quantization step plus kVsProjTol_m.
  static testing::WorstCase against_proj(const Pj& op, const Tile& in, const json& got) {
    testing::WorstCase worst;
    for (std::size_t i = 0; i < in.xyz.size(); ++i) {
      const auto& a = in.xyz[i];
      const PJ_COORD e = proj_trans(op.get(), PJ_FWD, proj_coord(a[0], a[1], a[2], 0));
      const double expected[3] = {e.xyz.x, e.xyz.y, e.xyz.z};
      for (std::size_t k = 0; k < 3; ++k) {
        const double tol = 0.5 * got["header"]["scale"][k].get<double>() + kVsProjTol_m;
        worst.add(std::abs(got["points"][i][k].get<double>() - expected[k]) / tol, i);
      }
    }
    return worst;
  }
};

// issue 13, acceptance 2: LAS tiles in EPSG:2236 promoted to 3-D (US survey
// feet), a 2-D projected WKT from another prime meridian (NTF (Paris) /
// Lambert zone II, through the ntf_r93 NTv2 grid) and a compound projected
// + orthometric WKT (UTM 32N + EGM96 height, through egm96_15.gtx) are read,
// moved and written as PROJ's own operation for the pair does (to half the
// output's quantization step plus 1e-6 m, 1e-9°), and each output's WKT is
// read back by PROJ as the output CRS.
TEST_F(CrsLas, Issue13_LasTilesInAnyCrsAreMovedAsProjDoesAndStateTheirCrs) {
  struct Case {
    std::string name, source;
    std::array<double, 4> box;  // west, south, east, north (degrees)
    std::string to_crs, target;
    std::array<double, 3> scale;
    bool two_d;
  };
  const Case cases[] = {
      {"florida", wkt_of(proj_, "EPSG:2236", true), {-81.6, 27.0, -80.4, 28.2}, "EPSG:26917",
       wkt_of(proj_, "EPSG:26917", true), {0.01, 0.01, 0.01}, false},
      {"paris", wkt_of(proj_, "EPSG:27572", false), {1.0, 46.0, 3.0, 48.0}, "EPSG:2154", wkt_of(proj_, "EPSG:2154", false),
       {0.001, 0.001, 0.01}, true},
      {"egm96", wkt_of(proj_, "EPSG:32632+5773", false), {8.0, 46.5, 9.5, 47.5}, "EPSG:4979",
       wkt_of(proj_, "EPSG:4979", false), {0.001, 0.001, 0.001}, false},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    ASSERT_FALSE(c.source.empty() || c.target.empty());
    // A tile's extent (a LAS axis holds 2^32 steps), inside the area of use
    // and, for Paris, inside the ntf_r93 grid.
    const auto points = points_in_box(c.source, c.box, 13);
    const Tile in = las("in/" + c.name + ".las", c.source, points, c.scale);
    const fs::path out = path("out_" + c.name);
    const RunResult r = run("apply '" + path("in/" + c.name + ".las").string() + "' --to-crs " + c.to_crs +
                            " --out-dir '" + out.string() + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const json got = verify(out / (c.name + ".las"));
    ASSERT_FALSE(got.is_null());
    ASSERT_EQ(got["points"].size(), in.xyz.size());

    // The output CRS, read back by PROJ as the one asked for.
    const std::string wkt = got["wkt"];
    Pj written = proj_.crs(wkt), target = proj_.crs(c.target);
    ASSERT_TRUE(written) << wkt;
    EXPECT_TRUE(proj_is_equivalent_to_with_ctx(proj_.ctx(), written.get(), target.get(), PJ_COMP_EQUIVALENT)) << wkt;

    Pj op = proj_.op(c.source, c.target);
    ASSERT_TRUE(op);
    const bool angular = proj_get_type(target.get()) == PJ_TYPE_GEOGRAPHIC_3D_CRS ||
                         proj_get_type(target.get()) == PJ_TYPE_GEOGRAPHIC_2D_CRS;
    testing::WorstCase worst;  // in units of each axis's tolerance
    for (std::size_t i = 0; i < in.xyz.size(); ++i) {
      const auto& a = in.xyz[i];
      PJ_COORD e = proj_trans(op.get(), PJ_FWD, proj_coord(a[0], a[1], c.two_d ? 0.0 : a[2], 0));
      const double expected[3] = {e.xyz.x, e.xyz.y, c.two_d ? a[2] : e.xyz.z};  // a 2-D CRS's Z passes unchanged
      for (std::size_t k = 0; k < 3; ++k) {
        const double step = got["header"]["scale"][k].get<double>();
        const double tol = 0.5 * step + (angular && k < 2 ? kVsProjTol_deg : kVsProjTol_m);
        worst.add(std::abs(got["points"][i][k].get<double>() - expected[k]) / tol, i);
      }
    }
    EXPECT_WORST_WITHIN(worst, 1.0) << "(ratio to the tolerance)";

    const json side = json::parse(slurp(out / (c.name + ".las.geoanchor.json")));
    EXPECT_EQ(side["coordinates"]["kind"], "crs");
    Pj side_crs = proj_.crs(side["crs"]["wkt2"].get<std::string>());
    EXPECT_TRUE(side_crs && proj_is_equivalent_to_with_ctx(proj_.ctx(), side_crs.get(), target.get(), PJ_COMP_EQUIVALENT));
    const json& ops = side["provenance"]["crs_operations"];
    ASSERT_EQ(ops.size(), 1u);
    EXPECT_GT(ops[0]["candidates"].size(), 0u);
    if (c.name == "paris") {
      bool grid = false;
      for (const auto& cand : ops[0]["candidates"]) {
        for (const auto& g : cand["grids"]) {
          if (g["on_this_machine"] == true && cand["points"].get<std::size_t>() > 0) grid = g["sha256"].is_string();
        }
      }
      EXPECT_TRUE(grid) << ops.dump();
    }
    // The output reads back: its sidecar and WKT agree, and it moves on.
    const RunResult again = run("apply '" + (out / (c.name + ".las")).string() + "' --to-crs " + c.to_crs +
                                " --out-dir '" + path("again_" + c.name).string() + "'");
    EXPECT_EQ(again.exit_code, 0) << again.err;
  }
}

// A 2-D CRS's Z values are no heights: moving them into a 3-D CRS is
// refused by name, with nothing written, unless --crs states the same CRS
// in 3-D; and a flag that contradicts the tile's WKT is refused.
TEST_F(CrsLas, Issue13_TwoDimensionalLasWktNeedsItsHeightsStated) {
  const std::string two_d = wkt_of(proj_, "EPSG:2236", false), three_d = wkt_of(proj_, "EPSG:2236", true);
  const auto points = points_in_box(two_d, {-81.6, 27.0, -80.4, 28.2}, 7);
  const Tile in = las("in/fl.las", two_d, points, {0.01, 0.01, 0.01});
  const fs::path out = path("out");
  write("utm3d.wkt", wkt_of(proj_, "EPSG:26917", true));
  const RunResult refused = run("apply '" + path("in/fl.las").string() + "' --to-crs '@" + path("utm3d.wkt").string() +
                                "' --out-dir '" + out.string() + "'");
  EXPECT_EQ(refused.exit_code, 3);
  EXPECT_NE(refused.err.find("E_HEIGHT_TYPE"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("NAD83 / Florida East (ftUS)"), std::string::npos) << refused.err;
  EXPECT_FALSE(fs::exists(out / "fl.las"));
  EXPECT_FALSE(fs::exists(out / "fl.las.geoanchor.json"));

  write("3d.wkt", three_d);
  const RunResult stated = run("apply '" + path("in/fl.las").string() + "' --crs '@" + path("3d.wkt").string() +
                               "' --to-crs EPSG:26917 --out-dir '" + out.string() + "'");
  ASSERT_EQ(stated.exit_code, 0) << stated.err;
  const json got = verify(out / "fl.las");
  ASSERT_FALSE(got.is_null());
  Pj op = proj_.op(three_d, wkt_of(proj_, "EPSG:26917", true));
  EXPECT_WORST_WITHIN(against_proj(op, in, got), 1.0) << "(ratio to the tolerance)";

  const RunResult other = run("apply '" + path("in/fl.las").string() + "' --crs EPSG:2238 --to-crs EPSG:26917 --out-dir '" +
                              path("other").string() + "'");
  EXPECT_EQ(other.exit_code, 2);
  EXPECT_NE(other.err.find("E_FRAME_CONFLICT"), std::string::npos) << other.err;
  EXPECT_FALSE(fs::exists(path("other/fl.las")));
}

// Issue 40 point 2: heights change unit with the CRS (US survey feet and
// international feet to metres and back), each output scale is a power of
// ten in the output's unit (apply.md), and a 2-D tile whose Z would pass
// unchanged from feet into metres is refused naming both units.
TEST_F(CrsLas, Issue40_HeightsChangeUnitWithTheCrsAndScalesArePowersOfTen) {
  struct Case {
    std::string name, source_code;
    std::array<double, 4> box;
    std::string target_code;
    std::array<double, 3> scale;
    double expected_scale;  // in the output's unit
  };
  const Case cases[] = {
      // NAVD88 heights in US survey feet (EPSG:6360) and in international feet (EPSG:8228).
      {"ftus_to_m", "EPSG:2236+6360", {-81.6, 27.0, -80.4, 28.2}, "EPSG:26917+5703", {0.01, 0.01, 0.01}, 0.001},
      {"m_to_ftus", "EPSG:26917+5703", {-81.6, 27.0, -80.4, 28.2}, "EPSG:2236+6360", {0.001, 0.001, 0.001}, 0.001},
      {"ft_to_m", "EPSG:2222+8228", {-110.4, 32.0, -109.6, 36.0}, "EPSG:26912+5703", {0.01, 0.01, 0.01}, 0.001},
      {"m_to_ft", "EPSG:26912+5703", {-110.4, 32.0, -109.6, 36.0}, "EPSG:2222+8228", {0.01, 0.01, 0.01}, 0.01},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const bool compound = c.source_code.find('+') != std::string::npos;
    const std::string source = wkt_of(proj_, c.source_code, !compound);
    const std::string target = wkt_of(proj_, c.target_code, c.target_code.find('+') == std::string::npos);
    const auto points = points_in_box(source, c.box, 11);
    const Tile in = las("in/" + c.name + ".las", source, points, c.scale);
    write(c.name + ".wkt", target);
    const RunResult r = run("apply '" + path("in/" + c.name + ".las").string() + "' --to-crs '@" + path(c.name + ".wkt").string() +
                            "' --out-dir '" + path("out").string() + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const json got = verify(path("out") / (c.name + ".las"));
    ASSERT_FALSE(got.is_null());
    for (std::size_t k = 0; k < 3; ++k) EXPECT_EQ(got["header"]["scale"][k].get<double>(), c.expected_scale) << k;
    // Every axis, the heights included, as PROJ moves them (feet to metres and back).
    Pj op = proj_.op(source, target);
    ASSERT_TRUE(op);
    EXPECT_WORST_WITHIN(against_proj(op, in, got), 1.0) << "(ratio to the tolerance)";
  }
  // 2-D in US survey feet to 2-D in metres: Z has no stated unit, so it is refused, nothing written.
  const std::string two_d = wkt_of(proj_, "EPSG:2236", false);
  las("in/flat.las", two_d, points_in_box(two_d, {-81.6, 27.0, -80.4, 28.2}, 3), {0.01, 0.01, 0.01});
  const RunResult refused =
      run("apply '" + path("in/flat.las").string() + "' --to-crs EPSG:26917 --out-dir '" + path("flat").string() + "'");
  EXPECT_EQ(refused.exit_code, 3) << refused.err;
  EXPECT_NE(refused.err.find("E_HEIGHT_UNIT"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("US survey foot"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("metre"), std::string::npos) << refused.err;
  EXPECT_FALSE(fs::exists(path("flat/flat.las")));
  EXPECT_FALSE(fs::exists(path("flat/flat.las.geoanchor.json")));
}

// --crs completes what a tile's WKT states, compared by PROJ and never by
// name: the heights of a 2-D CRS as a compound CRS whose horizontal part is
// equivalent (the tile's WKT under another name), a dynamic CRS's coordinate
// epoch (CRS@EPOCH), and a 2-D --crs beside a 3-D WKT (it says less, not
// otherwise); the tile's points move as PROJ's own operation moves them.
TEST_F(CrsLas, Issue13_ACrsFlagCompletesTheTilesCrsAsProjReadsIt) {
  // UTM 32N under a name of the surveyor's own: PROJ holds it equivalent to EPSG:32632.
  std::string renamed = wkt_of(proj_, "EPSG:32632", false);
  renamed.replace(renamed.find("WGS 84 / UTM zone 32N"), 21, "Site grid (UTM 32N)");
  renamed.erase(renamed.rfind(",ID[\"EPSG\",32632]"), 17);
  const auto utm_points = points_in_box("EPSG:32632", {8.0, 46.5, 9.5, 47.5}, 5);
  const Tile utm = las("in/site.las", renamed, utm_points, {0.001, 0.001, 0.001});
  const RunResult h = run("apply '" + path("in/site.las").string() + "' --crs EPSG:32632+5773 --to-crs EPSG:4979 --out-dir '" +
                          path("out_site").string() + "'");
  ASSERT_EQ(h.exit_code, 0) << h.err;
  {
    const json got = verify(path("out_site/site.las"));
    ASSERT_FALSE(got.is_null());
    Pj op = proj_.op("EPSG:32632+5773", "EPSG:4979");
    testing::WorstCase worst;  // ratio to the tolerance
    for (std::size_t i = 0; i < utm.xyz.size(); ++i) {
      const auto& a = utm.xyz[i];
      const PJ_COORD e = proj_trans(op.get(), PJ_FWD, proj_coord(a[0], a[1], a[2], 0));
      const double expected[3] = {e.xyz.x, e.xyz.y, e.xyz.z};
      for (std::size_t k = 0; k < 3; ++k) {
        const double tol = 0.5 * got["header"]["scale"][k].get<double>() + (k < 2 ? kVsProjTol_deg : kVsProjTol_m);
        worst.add(std::abs(got["points"][i][k].get<double>() - expected[k]) / tol, i);
      }
    }
    EXPECT_WORST_WITHIN(worst, 1.0) << "(ratio to the tolerance)";
  }
  // A compound CRS on another horizontal CRS is still refused.
  const RunResult other = run("apply '" + path("in/site.las").string() + "' --crs EPSG:32633+5773 --to-crs EPSG:4979 --out-dir '" +
                              path("out_other").string() + "'");
  EXPECT_EQ(other.exit_code, 2) << other.err;
  EXPECT_NE(other.err.find("E_FRAME_CONFLICT"), std::string::npos) << other.err;
  EXPECT_FALSE(fs::exists(path("out_other/site.las")));

  // ITRF2014 geographic 3-D without its epoch: --crs EPSG:7912@2024.5 gives it.
  const auto itrf_points = points_in_box("EPSG:7912", {8.0, 46.5, 9.5, 47.5}, 9);
  const Tile itrf = las("in/itrf.las", wkt_of(proj_, "EPSG:7912", false), itrf_points, {1e-8, 1e-8, 0.001});
  const RunResult missing = run("apply '" + path("in/itrf.las").string() + "' --to-crs EPSG:9989 --out-dir '" +
                                path("out_missing").string() + "'");
  EXPECT_EQ(missing.exit_code, 3) << missing.err;
  EXPECT_NE(missing.err.find("E_EPOCH_MISSING"), std::string::npos) << missing.err;
  const RunResult dated = run("apply '" + path("in/itrf.las").string() + "' --crs EPSG:7912@2024.5 --to-crs EPSG:9989 --out-dir '" +
                              path("out_itrf").string() + "'");
  ASSERT_EQ(dated.exit_code, 0) << dated.err;
  {
    const json got = verify(path("out_itrf/itrf.las"));
    ASSERT_FALSE(got.is_null());
    Pj op = proj_.op("EPSG:7912", "EPSG:9989");
    testing::WorstCase worst;
    for (std::size_t i = 0; i < itrf.xyz.size(); ++i) {
      const auto& a = itrf.xyz[i];
      const PJ_COORD e = proj_trans(op.get(), PJ_FWD, proj_coord(a[0], a[1], a[2], 2024.5));
      const double expected[3] = {e.xyz.x, e.xyz.y, e.xyz.z};
      for (std::size_t k = 0; k < 3; ++k) {
        const double tol = 0.5 * got["header"]["scale"][k].get<double>() + (k < 2 ? kVsProjTol_deg : kVsProjTol_m);
        worst.add(std::abs(got["points"][i][k].get<double>() - expected[k]) / tol, i);
      }
    }
    EXPECT_WORST_WITHIN(worst, 1.0) << "(ratio to the tolerance)";
    const json side = json::parse(slurp(path("out_itrf/itrf.las.geoanchor.json")));
    EXPECT_EQ(side["frame"], "ITRF2020@2024.5");
    EXPECT_EQ(side["crs"]["coordinate_epoch"], 2024.5);
  }
  // A 2-D --crs beside the 3-D WKT says less, not otherwise: the same points.
  const RunResult less = run("apply '" + path("in/itrf.las").string() + "' --crs EPSG:9000@2024.5 --to-crs EPSG:9989 --out-dir '" +
                             path("out_less").string() + "'");
  ASSERT_EQ(less.exit_code, 0) << less.err;
  EXPECT_EQ(verify(path("out_less/itrf.las"))["points"], verify(path("out_itrf/itrf.las"))["points"]);
  // Another epoch than the one the tile states is a contradiction.
  const RunResult twice = run("apply '" + path("out_itrf/itrf.las").string() + "' --crs EPSG:9989@2020.0 --to-crs EPSG:7912 --out-dir '" +
                              path("out_twice").string() + "'");
  EXPECT_EQ(twice.exit_code, 2) << twice.err;
  EXPECT_NE(twice.err.find("E_FRAME_CONFLICT"), std::string::npos) << twice.err;
}

// A tile in a dynamic CRS at its epoch (a CSV stating ITRF2014 geographic
// 3-D and 2024.3) through a 14-parameter transform ITRF2014 -> GDA2020 into
// MGA zone 56 (EPSG:7856, promoted to 3-D): PROJ converts each CRS to and
// from its frame's geocentric CRS around geoanchor's transform, which is
// evaluated at the tile's epoch. The reference is PROJ's pipeline of the
// same steps, written out here from the published definitions.
TEST_F(CrsLas, Issue13_ATransformBetweenTwoCrssIsEvaluatedAtTheTilesEpochAsProjDoes) {
  write("T.json", R"J({"model": "helmert14", "convention": "position_vector",
    "source_frame": "ITRF2014", "target_frame": "GDA2020", "reference_epoch": 2020.0,
    "parameters": {"tx_m": 0.1, "ty_m": -0.2, "tz_m": 0.3, "rx_arcsec": 0.01, "ry_arcsec": -0.02, "rz_arcsec": 0.03,
                   "ds_ppm": 0.5, "dtx_m_per_year": 0.01, "dty_m_per_year": -0.02, "dtz_m_per_year": 0.03,
                   "drx_arcsec_per_year": 0.001, "dry_arcsec_per_year": 0.002, "drz_arcsec_per_year": -0.003,
                   "dds_ppm_per_year": 0.1}})J");
  const auto points = points_in_box("EPSG:7912", {150.5, -34.5, 151.5, -33.5}, 21);
  std::ostringstream csv;
  csv << "# crs = EPSG:7912\n# coordinate_epoch = 2024.3\n# survey: test\nid,lat_deg,lon_deg,h_m,class\n";
  for (std::size_t i = 0; i < points.size(); ++i) {
    csv << "P" << i << "," << format_shortest(points[i][1]) << "," << format_shortest(points[i][0]) << ","
        << format_shortest(points[i][2]) << ",2\n";
  }
  write("in/sydney.csv", csv.str());
  const RunResult r = run("apply '" + path("in/sydney.csv").string() + "' --transform '" + path("T.json").string() +
                          "' --to-crs EPSG:7856 --out-dir '" + path("out").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string text = slurp(path("out/sydney.csv"));
  EXPECT_EQ(text.rfind("# crs = PROJCRS[\"GDA2020 / MGA zone 56\"", 0), 0u) << text.substr(0, 80);
  EXPECT_NE(text.find("\n# survey: test\n"), std::string::npos);
  EXPECT_EQ(text.find("coordinate_epoch"), std::string::npos);  // GDA2020 is static
  const Csv got = testing::parse_csv_table(text);
  ASSERT_EQ(got.rows.size(), points.size());
  EXPECT_EQ(got.header, (std::vector<std::string>{"id", "easting_m", "northing_m", "h_m", "class"}));

  const testing::ProjPipeline proj(
      "+proj=pipeline +step +proj=unitconvert +xy_in=deg +xy_out=rad +step +proj=cart +ellps=GRS80 "
      "+step +proj=helmert +x=0.1 +y=-0.2 +z=0.3 +rx=0.01 +ry=-0.02 +rz=0.03 +s=0.5 +dx=0.01 +dy=-0.02 +dz=0.03 "
      "+drx=0.001 +dry=0.002 +drz=-0.003 +ds=0.1 +t_epoch=2020.0 +convention=position_vector "
      "+step +inv +proj=cart +ellps=GRS80 +step +proj=utm +zone=56 +south +ellps=GRS80");
  WorstCase worst;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d e = proj.forward(Eigen::Vector3d(points[i][0], points[i][1], points[i][2]), 2024.3);
    for (std::size_t k = 0; k < 3; ++k) worst.add(std::abs(std::stod(got.rows[i][k + 1]) - e(static_cast<int>(k))), i);
    EXPECT_EQ(got.rows[i][4], "2");
  }
  EXPECT_WORST_WITHIN(worst, kVsProjTol_m);
  const json side = json::parse(slurp(path("out/sydney.csv.geoanchor.json")));
  EXPECT_EQ(side["frame"], "GDA2020@2024.3");  // a static frame keeps its observation epoch, as typed outputs do
  EXPECT_EQ(side["provenance"]["observation_epoch"], 2024.3);
  EXPECT_EQ(side["provenance"]["crs_operations"].size(), 2u);
}

// Every bad input of a tile in a CRS: named, and nothing written.
TEST_F(CrsLas, Issue13_BadCrsInputToApplyIsRefusedByNameWithNoOutput) {
  write("in/es.csv", "id,lat_deg,lon_deg,h_m\nMAD,40.4,-3.7,600\n");
  write("in/fr.csv", "id,easting_m,northing_m\nA,600000,2400000\n");
  write("in/ch.csv", "# crs = EPSG:21781\nid,easting_m,northing_m,H_m\nA,600000,200000,500\n");
  write("in/lv95.csv", "# crs = EPSG:2056\nid,easting_m,northing_m\nA,2600000,1200000\n");
  write("T.json", R"J({"model": "helmert7", "convention": "position_vector", "source_frame": "ITRF2014@2024.5",
    "target_frame": "GDA2020", "parameters": {"tx_m": 0.1, "ty_m": 0, "tz_m": 0, "rx_arcsec": 0, "ry_arcsec": 0,
    "rz_arcsec": 0, "ds_ppm": 0}})J");
  struct Bad {
    std::string what, tile, args;
    int exit_code;
    std::vector<std::string> says;
  };
  const Bad cases[] = {
      {"--to-crs with --to", "es.csv", "--crs EPSG:4937 --to-crs EPSG:4326 --to ecef", 2, {"E_OPTION", "--to-crs with --to"}},
      {"unknown code", "es.csv", "--crs EPSG:4937 --to-crs EPSG:999999", 3, {"--to-crs", "EPSG:999999"}},
      {"a missing better grid", "es.csv", "--crs EPSG:4230 --to-crs EPSG:4258", 3, {"E_CRS_GRID_MISSING", "es.csv"}},
      {"heights in the wrong kind of column", "fr.csv", "--crs EPSG:27572 --to-crs EPSG:2154", 3,
       {"E_COLUMN", "fr.csv", "EPSG:27572"}},
      {"the tile states another CRS than --crs", "ch.csv", "--crs EPSG:2056 --to-crs EPSG:4326", 2,
       {"E_FRAME_CONFLICT", "--crs EPSG:2056", "EPSG:21781"}},
      {"a transform whose target is not the output CRS's datum", "es.csv",
       "--crs ITRF2014@2024.5 --transform '" + path("T.json").string() + "' --to-crs EPSG:2154", 3,
       {"E_FRAME_MISMATCH", "--to-crs EPSG:2154", "GDA2020"}},
      {"a dynamic CRS without its epoch where the datum changes", "es.csv", "--crs EPSG:7912 --to-crs EPSG:4937", 3,
       {"E_EPOCH_MISSING"}},
      {"an output flag that a tile staying in its CRS cannot use", "lv95.csv", "--zone 32N", 2,
       {"E_OPTION", "EPSG:2056", "--zone"}},
      {"an ellipsoid for a tile staying in its CRS", "lv95.csv", "--ellipsoid GRS80", 2, {"E_OPTION", "--ellipsoid"}},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.what);
    const fs::path out = path("out");
    fs::remove_all(out);
    const RunResult r = run("apply '" + path("in/" + c.tile).string() + "' " + c.args + " --out-dir '" + out.string() + "'");
    EXPECT_EQ(r.exit_code, c.exit_code) << r.err;
    for (const auto& s : c.says) EXPECT_NE(r.err.find(s), std::string::npos) << s << " in: " << r.err;
    EXPECT_FALSE(fs::exists(out / c.tile));
    EXPECT_FALSE(fs::exists(out / (c.tile + ".geoanchor.json")));
  }
}

// --geoid NAME|PATH: a geoid grid by PROJ's name or by path, read by PROJ
// (vgridshift), agrees with PROJ's own vgridshift on the same grid; the
// grid's file and hash are recorded; a grid that is not there is refused
// naming it and where PROJ looked, with no output.
TEST_F(CrsCli, Issue13_AGeoidByNameOrPathAgreesWithProjsVgridshift) {
  const auto points = points_in_box("EPSG:4326", {-179.0, -80.0, 179.0, 80.0}, 5);
  std::ostringstream csv;
  csv << "id,lat_deg,lon_deg,H_m\n";
  for (std::size_t i = 0; i < points.size(); ++i) {
    csv << "P" << i << "," << format_shortest(points[i][1]) << "," << format_shortest(points[i][0]) << ","
        << format_shortest(points[i][2]) << "\n";
  }
  write("h.csv", csv.str());
  std::string grid;
  for (const char* dir : {"/usr/share/proj"}) {
    if (fs::exists(fs::path(dir) / "egm96_15.gtx")) grid = (fs::path(dir) / "egm96_15.gtx").string();
  }
  ASSERT_FALSE(grid.empty()) << "proj-data's egm96_15.gtx is not installed";
  fs::copy_file(grid, path("my geoid.gtx"));
  const testing::ProjPipeline proj(
      "+proj=pipeline +step +proj=unitconvert +xy_in=deg +xy_out=rad +step +proj=vgridshift +grids=" + grid +
      " +multiplier=1 +step +proj=cart +ellps=WGS84");
  for (const std::string& geoid : {std::string("egm96_15.gtx"), "'" + path("my geoid.gtx").string() + "'"}) {
    SCOPED_TRACE(geoid);
    fs::remove(path("o.csv"));
    fs::remove(path("o.csv.geoanchor.json"));
    const RunResult r = run("convert '" + path("h.csv").string() + "' --geoid " + geoid + " --to ecef -o '" +
                            path("o.csv").string() + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Csv got = testing::parse_csv_table(slurp(path("o.csv")));
    ASSERT_EQ(got.rows.size(), points.size());
    WorstCase worst;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Eigen::Vector3d e = proj.forward(Eigen::Vector3d(points[i][0], points[i][1], points[i][2]));
      for (std::size_t k = 0; k < 3; ++k) worst.add(std::abs(std::stod(got.rows[i][k + 1]) - e(static_cast<int>(k))), i);
    }
    EXPECT_WORST_WITHIN(worst, kVsProjTol_m);
    const json side = json::parse(slurp(path("o.csv.geoanchor.json")));
    const RunResult sha = shell("sha256sum '" + grid + "'");
    EXPECT_EQ(side["input"]["geoid"]["sha256"], sha.out.substr(0, 64));
  }
  const RunResult missing = run("convert '" + path("h.csv").string() + "' --geoid us_noaa_g2018u0.tif --to ecef -o '" +
                                path("m.csv").string() + "'");
  EXPECT_EQ(missing.exit_code, 3);
  EXPECT_NE(missing.err.find("E_GEOID_MISSING"), std::string::npos) << missing.err;
  EXPECT_NE(missing.err.find("us_noaa_g2018u0.tif"), std::string::npos) << missing.err;
  EXPECT_NE(missing.err.find("/usr/share/proj"), std::string::npos) << missing.err;
  EXPECT_FALSE(fs::exists(path("m.csv")));
  EXPECT_FALSE(fs::exists(path("m.csv.geoanchor.json")));
}

}  // namespace
}  // namespace geoanchor
