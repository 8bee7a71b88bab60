// `geoanchor apply` end to end: the bundled tile fitted and moved, read back
// by an independent LAS reader (npm `copc`, tests/las-verify) and compared
// with PROJ; frame checks, resumable and sharded batches, extrapolation, and
// every bad-input case checked for its message and for the absence of output.

#include "apply_cli_fixture.hpp"

namespace geoanchor {
namespace {

using namespace apply_cli_fixture;

std::string g17(double v) { return format_shortest(v); }

// A 14-parameter set ITRF2014 -> GDA2020 (not the published one) with rates
// large enough that evaluating it at a wrong epoch would show, and the same
// for PROJ.
const char* kHelmert14 = R"J({"model": "helmert14", "convention": "position_vector",
    "source_frame": "ITRF2014", "target_frame": "GDA2020", "reference_epoch": 2020.0,
    "parameters": {"tx_m": 0.1, "ty_m": -0.2, "tz_m": 0.3, "rx_arcsec": 0.01, "ry_arcsec": -0.02, "rz_arcsec": 0.03,
                   "ds_ppm": 0.5, "dtx_m_per_year": 0.01, "dty_m_per_year": -0.02, "dtz_m_per_year": 0.03,
                   "drx_arcsec_per_year": 0.001, "dry_arcsec_per_year": 0.002, "drz_arcsec_per_year": -0.003,
                   "dds_ppm_per_year": 0.1}})J";
const char* kProjHelmert14 =
    "+proj=helmert +x=0.1 +y=-0.2 +z=0.3 +rx=0.01 +ry=-0.02 +rz=0.03 +s=0.5 +dx=0.01 +dy=-0.02 +dz=0.03 +drx=0.001 "
    "+dry=0.002 +drz=-0.003 +ds=0.1 +t_epoch=2020.0 +convention=position_vector";


TEST_F(ApplyCli, BundledTileIsMovedAsProjWouldAndReadsBackIndependently) {
  const fs::path t = fit();
  const fs::path out = out_dir();
  const RunResult r = run("apply " + kTile + " --transform " + t.string() + " --out-dir " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const fs::path las = out / "airport_tile.las";

  // The sidecar names the new frame, the transform's hash and its σ0.
  const json side = json::parse(slurp(out / "airport_tile.las.geoanchor.json"));
  const json tf = json::parse(slurp(t));
  EXPECT_EQ(side["frame"], "ETRF2000@2024.5");
  EXPECT_EQ(side["coordinates"]["kind"], "enu");
  EXPECT_EQ(side["enu_origin"]["lat_deg"], 47.464722);
  const RunResult sha = shell("sha256sum '" + t.string() + "'");
  EXPECT_EQ(side["provenance"]["transform_sha256"], sha.out.substr(0, 64));
  EXPECT_EQ(side["provenance"]["transform_sigma0"], tf["statistics"]["sigma0"]);
  const RunResult in_sha = shell("sha256sum '" + kTile + "'");
  EXPECT_EQ(side["provenance"]["input_sha256"], in_sha.out.substr(0, 64));
  EXPECT_GT(side["provenance"]["propagated_uncertainty"]["sigma_e_m"].get<double>(), 0.0);
  EXPECT_EQ(side["provenance"]["extrapolation"]["distance_outside_control_m"], 0.0);

  // The independent reader: same count and attributes, the WKT names datum and epoch.
  const json in = las_verify(kTile), got = las_verify(las);
  ASSERT_FALSE(got.is_null());
  EXPECT_EQ(got["header"]["pointCount"], 2000);
  EXPECT_EQ(got["header"]["pointDataRecordFormat"], 6);
  EXPECT_EQ(got["header"]["globalEncoding"].get<int>() & 16, 16);
  EXPECT_EQ(got["dimensions"], in["dimensions"]);
  const std::string wkt = got["wkt"];
  EXPECT_NE(wkt.find("ETRF2000@2024.5"), std::string::npos);
  EXPECT_NE(wkt.find("European Terrestrial Reference Frame 2000"), std::string::npos);
  EXPECT_TRUE(testing::proj_parses_crs(wkt)) << wkt;

  // Coordinates against PROJ, built here from the file's parameters.
  const json& p = tf["parameters"];
  const std::string topo = "+proj=topocentric +ellps=GRS80 +lat_0=47.464722 +lon_0=8.549167 +h_0=480";
  const ProjPipeline proj("+proj=pipeline +step +inv " + topo + " +step +proj=helmert +x=" + g17(p["tx_m"]) +
                          " +y=" + g17(p["ty_m"]) + " +z=" + g17(p["tz_m"]) + " +rx=" + g17(p["rx_arcsec"]) +
                          " +ry=" + g17(p["ry_arcsec"]) + " +rz=" + g17(p["rz_arcsec"]) + " +s=" + g17(p["ds_ppm"]) +
                          " +convention=position_vector +step " + topo);
  const double half_step = 0.5 * got["header"]["scale"][0].get<double>();
  testing::WorstCase worst;
  ASSERT_EQ(got["points"].size(), in["points"].size());
  for (std::size_t i = 0; i < in["points"].size(); ++i) {
    const auto& a = in["points"][i];
    const auto& b = got["points"][i];
    const Eigen::Vector3d e = proj.forward(Eigen::Vector3d(a[0], a[1], a[2]));
    for (int k = 0; k < 3; ++k) worst.add(std::abs(b[static_cast<std::size_t>(k)].get<double>() - e(k)), i);
    for (std::size_t k = 3; k < a.size(); ++k) ASSERT_EQ(a[k], b[k]) << "point " << i << " " << in["dimensions"][k];
  }
  EXPECT_WORST_WITHIN(worst, half_step + kVsProjTol_m);
}

// issue 13: a tile in geoanchor's own coordinates (the bundled ENU tile)
// through a transform into a CRS on the transform's target frame (ETRF2000
// geographic 3-D, EPSG:7931): geoanchor's chain to ECEF, PROJ from the
// frame's geocentric CRS. Against PROJ's pipeline of the same steps, to half
// the output step plus the issue's 1e-9°; a CRS on another datum is refused.
TEST_F(ApplyCli, Issue13_AToCrsOutputThroughATransformAgreesWithProj) {
  const fs::path t = fit();
  const fs::path out = out_dir();
  const RunResult r =
      run("apply " + kTile + " --transform " + t.string() + " --to-crs EPSG:7931 --out-dir " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json side = json::parse(slurp(out / "airport_tile.las.geoanchor.json"));
  EXPECT_EQ(side["coordinates"]["kind"], "crs");
  EXPECT_EQ(side["frame"], "ETRF2000@2024.5");
  const json in = las_verify(kTile), got = las_verify(out / "airport_tile.las");
  ASSERT_FALSE(got.is_null());
  const json tf = json::parse(slurp(t));
  const json& p = tf["parameters"];
  const std::string topo = "+proj=topocentric +ellps=GRS80 +lat_0=47.464722 +lon_0=8.549167 +h_0=480";
  const ProjPipeline proj("+proj=pipeline +step +inv " + topo + " +step +proj=helmert +x=" + g17(p["tx_m"]) +
                          " +y=" + g17(p["ty_m"]) + " +z=" + g17(p["tz_m"]) + " +rx=" + g17(p["rx_arcsec"]) +
                          " +ry=" + g17(p["ry_arcsec"]) + " +rz=" + g17(p["rz_arcsec"]) + " +s=" + g17(p["ds_ppm"]) +
                          " +convention=position_vector +step +inv +proj=cart +ellps=GRS80");
  constexpr double kVsProj_deg = 1e-9;
  testing::WorstCase worst;  // in units of each axis's tolerance
  for (std::size_t i = 0; i < in["points"].size(); ++i) {
    const auto& a = in["points"][i];
    const Eigen::Vector3d g = proj.forward(Eigen::Vector3d(a[0], a[1], a[2]));
    const double expected[3] = {testing::proj_degrees(g.x()), testing::proj_degrees(g.y()), g.z()};  // X lon, Y lat
    for (std::size_t k = 0; k < 3; ++k) {
      const double tol = 0.5 * got["header"]["scale"][k].get<double>() + (k < 2 ? kVsProj_deg : kVsProjTol_m);
      worst.add(std::abs(got["points"][i][k].get<double>() - expected[k]) / tol, i);
    }
  }
  EXPECT_WORST_WITHIN(worst, 1.0) << "(ratio to the tolerance)";

  // geoanchor's own output (UTM 32N on ETRF2000@2024.5, its sidecar beside
  // the WKT it wrote) moves on into a CRS of its frame: against PROJ's
  // inverse UTM on GRS80, from the values that file holds.
  const fs::path utm = path("utm");
  const RunResult u = run("apply " + kTile + " --transform " + t.string() + " --to utm --zone 32N --out-dir " + utm.string());
  ASSERT_EQ(u.exit_code, 0) << u.err;
  const fs::path geo = path("geo");
  const RunResult on = run("apply " + (utm / "airport_tile.las").string() + " --to-crs EPSG:7931 --out-dir " + geo.string());
  ASSERT_EQ(on.exit_code, 0) << on.err;
  EXPECT_EQ(json::parse(slurp(geo / "airport_tile.las.geoanchor.json"))["frame"], "ETRF2000@2024.5");
  const json u_in = las_verify(utm / "airport_tile.las"), u_got = las_verify(geo / "airport_tile.las");
  ASSERT_FALSE(u_got.is_null());
  ASSERT_EQ(u_got["points"].size(), u_in["points"].size());
  const ProjPipeline inv_utm("+proj=pipeline +step +inv +proj=utm +zone=32 +ellps=GRS80");
  testing::WorstCase worst_utm;
  for (std::size_t i = 0; i < u_in["points"].size(); ++i) {
    const auto& a = u_in["points"][i];
    const Eigen::Vector3d g = inv_utm.forward(Eigen::Vector3d(a[0], a[1], a[2]));
    const double expected[3] = {testing::proj_degrees(g.x()), testing::proj_degrees(g.y()), g.z()};
    for (std::size_t k = 0; k < 3; ++k) {
      const double tol = 0.5 * u_got["header"]["scale"][k].get<double>() + (k < 2 ? kVsProj_deg : kVsProjTol_m);
      worst_utm.add(std::abs(u_got["points"][i][k].get<double>() - expected[k]) / tol, i);
    }
  }
  EXPECT_WORST_WITHIN(worst_utm, 1.0) << "(ratio to the tolerance)";

  const RunResult other = run("apply " + kTile + " --transform " + t.string() + " --to-crs EPSG:2056 --out-dir " +
                              path("other").string());
  EXPECT_EQ(other.exit_code, 3);
  EXPECT_NE(other.err.find("E_FRAME_MISMATCH"), std::string::npos) << other.err;
  EXPECT_FALSE(fs::exists(path("other/airport_tile.las")));
}

// issue 13: geoanchor's own WKT for its own coordinates (ECEF in the
// dynamic ITRF2014 at 2024.5), its sidecar gone, moved into a CRS: the
// remark's epoch is kept (PROJ alone reads the plain datum as static), the
// output is ITRF2014@2024.5 and agrees with PROJ's inverse cart on GRS80.
TEST_F(ApplyCli, Issue13_GeoanchorsOwnWktWithoutItsSidecarKeepsItsEpoch) {
  const fs::path ecef = path("ecef");
  const RunResult e = run("apply " + kTile + " --to ecef --out-dir " + ecef.string());
  ASSERT_EQ(e.exit_code, 0) << e.err;
  fs::remove(ecef / "airport_tile.las.geoanchor.json");
  const fs::path geo = path("geo");
  const RunResult r = run("apply " + (ecef / "airport_tile.las").string() + " --to-crs EPSG:7912 --out-dir " + geo.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json side = json::parse(slurp(geo / "airport_tile.las.geoanchor.json"));
  EXPECT_EQ(side["frame"], "ITRF2014@2024.5");
  EXPECT_EQ(side["crs"]["coordinate_epoch"], 2024.5) << side["crs"].dump();
  const json in = las_verify(ecef / "airport_tile.las"), got = las_verify(geo / "airport_tile.las");
  ASSERT_FALSE(got.is_null());
  ASSERT_EQ(got["points"].size(), in["points"].size());
  const ProjPipeline proj("+proj=pipeline +step +inv +proj=cart +ellps=GRS80");
  constexpr double kVsProj_deg = 1e-9;
  testing::WorstCase worst;  // in units of each axis's tolerance
  for (std::size_t i = 0; i < in["points"].size(); ++i) {
    const auto& a = in["points"][i];
    const Eigen::Vector3d g = proj.forward(Eigen::Vector3d(a[0], a[1], a[2]));
    const double expected[3] = {testing::proj_degrees(g.x()), testing::proj_degrees(g.y()), g.z()};
    for (std::size_t k = 0; k < 3; ++k) {
      const double tol = 0.5 * got["header"]["scale"][k].get<double>() + (k < 2 ? kVsProj_deg : kVsProjTol_m);
      worst.add(std::abs(got["points"][i][k].get<double>() - expected[k]) / tol, i);
    }
  }
  EXPECT_WORST_WITHIN(worst, 1.0) << "(ratio to the tolerance)";

  // Into a static frame's CRS (ETRF2000, by PROJ's own operation): the
  // output's frame keeps the epoch its points were observed at.
  const fs::path etrf = path("etrf");
  const RunResult s = run("apply " + kTile + " --to-crs EPSG:7931 --out-dir " + etrf.string());
  ASSERT_EQ(s.exit_code, 0) << s.err;
  EXPECT_EQ(json::parse(slurp(etrf / "airport_tile.las.geoanchor.json"))["frame"], "ETRF2000@2024.5");
}

TEST_F(ApplyCli, RefusesATileInAnotherFrameThanTheTransformsSourceAndNamesBoth) {
  const fs::path t = fit();
  const fs::path in = tile("in/tile.las", [](std::string& s) { replace(s, "ITRF2014@2024.5", "ITRF2008@2024.5"); });
  const fs::path out = out_dir();
  const RunResult r = run("apply " + in.string() + " --transform " + t.string() + " --out-dir " + out.string());
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.err.find("error[E_FRAME_MISMATCH]"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("ITRF2008@2024.5"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("ITRF2014@2024.5"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out / "tile.las"));
  EXPECT_FALSE(fs::exists(out / "tile.las.geoanchor.json"));
  // Another epoch of the same realization is another frame for a static transform.
  const fs::path in2 = tile("in2/tile.las", [](std::string& s) { replace(s, "ITRF2014@2024.5", "ITRF2014@2020.0"); });
  const RunResult r2 = run("apply " + in2.string() + " --transform " + t.string() + " --out-dir " + out.string());
  EXPECT_EQ(r2.exit_code, 3);
  EXPECT_NE(r2.err.find("coordinate epochs differ"), std::string::npos) << r2.err;
}

TEST_F(ApplyCli, AnUnknownFrameOrAFlagThatContradictsTheSidecarIsAnError) {
  const fs::path out = out_dir();
  fs::create_directories(path("bare"));
  fs::copy_file(kTile, path("bare/tile.las"));
  const RunResult r = run("apply " + path("bare/tile.las").string() + " --out-dir " + out.string());
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.err.find("the tile's frame is unknown"), std::string::npos) << r.err;
  const fs::path in = tile("in/tile.las");
  const RunResult f = run("apply " + in.string() + " --from-frame ITRF2020@2024.5 --out-dir " + out.string());
  EXPECT_EQ(f.exit_code, 2);
  EXPECT_NE(f.err.find("--from-frame ITRF2020@2024.5 contradicts the sidecar"), std::string::npos) << f.err;
  const RunResult o = run("apply " + in.string() + " --from-origin 47.46,8.55,480 --out-dir " + out.string());
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.err.find("--from-origin 47.46,8.55,480 contradicts"), std::string::npos) << o.err;
  // The same values are no contradiction; flags alone describe a bare tile.
  const RunResult same = run("apply " + in.string() + " --from-frame ITRF2014@2024.5 --to ecef --out-dir " + out.string());
  EXPECT_EQ(same.exit_code, 0) << same.err;
  const RunResult flags = run("apply " + path("bare/tile.las").string() +
                              " --from-frame ITRF2014@2024.5 --from-origin 47.464722,8.549167,480 --ellipsoid GRS80 --to ecef "
                              "--overwrite --out-dir " + out.string());
  EXPECT_EQ(flags.exit_code, 0) << flags.err;
  EXPECT_EQ(json::parse(slurp(out / "tile.las.geoanchor.json"))["provenance"]["input_frame_from"], "command line");
}

TEST_F(ApplyCli, AWktDatumWithoutAFrameNameNeedsFromFrameAndGeoTiffKeysAreNotGuessed) {
  const std::string wkt =
      "GEODCRS[\"site\",DATUM[\"Airport local datum 1998\",ELLIPSOID[\"GRS 1980\",6378137,298.257222101]],"
      "CS[Cartesian,3],AXIS[\"(X)\",geocentricX,LENGTHUNIT[\"metre\",1]],AXIS[\"(Y)\",geocentricY,"
      "LENGTHUNIT[\"metre\",1]],AXIS[\"(Z)\",geocentricZ,LENGTHUNIT[\"metre\",1]]]";
  testing::LasBuild b;
  b.offset = {4277000.0, 639000.0, 4672000.0};
  b.xyz = {{686016, 405550, 438669}, {687016, 406550, 439669}};
  b.vlrs.push_back({"LASF_Projection", 2112, "", std::vector<std::uint8_t>(wkt.begin(), wkt.end())});
  fs::create_directories(path("in"));
  testing::write_bytes(path("in/site.las"), testing::build_las(b));
  const fs::path out = out_dir();
  const RunResult unnamed = run("apply " + path("in/site.las").string() + " --to geodetic --out-dir " + out.string());
  EXPECT_EQ(unnamed.exit_code, 3);
  EXPECT_NE(unnamed.err.find("datum 'Airport local datum 1998' is not a frame geoanchor can name"), std::string::npos)
      << unnamed.err;
  const RunResult named = run("apply " + path("in/site.las").string() +
                              " --to geodetic --from-frame ITRF2014@2024.5 --out-dir " + out.string());
  ASSERT_EQ(named.exit_code, 0) << named.err;
  const json side = json::parse(slurp(out / "site.las.geoanchor.json"));
  EXPECT_EQ(side["frame"], "ITRF2014@2024.5");
  EXPECT_EQ(side["provenance"]["input_frame_from"], "LAS WKT (datum 'Airport local datum 1998' named by --from-frame)");

  testing::LasBuild g = b;
  g.vlrs = {{"LASF_Projection", 34735, "GeoKeyDirectoryTag", std::vector<std::uint8_t>(16, 1)}};
  testing::write_bytes(path("in/geotiff.las"), testing::build_las(g));
  const RunResult geotiff = run("apply " + path("in/geotiff.las").string() + " --out-dir " + out.string());
  EXPECT_EQ(geotiff.exit_code, 3);
  EXPECT_NE(geotiff.err.find("GeoTIFF CRS keys: GeoKeyDirectory version 257; expected 1"), std::string::npos) << geotiff.err;
}

TEST_F(ApplyCli, ARerunSkipsUpToDateOutputsButNeverOverwritesOthersWithoutTheFlag) {
  const fs::path t = fit();
  const fs::path out = out_dir();
  const std::string cmd = "apply " + kTile + " --transform " + t.string() + " --out-dir " + out.string();
  ASSERT_EQ(run(cmd).exit_code, 0);
  const std::string first = slurp(out / "airport_tile.las");
  const RunResult again = run(cmd + " --json");
  ASSERT_EQ(again.exit_code, 0) << again.err;
  const json summary = json::parse(again.out);
  EXPECT_EQ(summary["schema"], "geoanchor.apply-summary/1");
  EXPECT_EQ(summary["tiles_skipped"], 1);
  EXPECT_EQ(summary["tiles"][0]["status"], "skipped");
  // Another request over the same output: refused, the output untouched.
  const RunResult other = run(cmd + " --resolution 0.01");
  EXPECT_EQ(other.exit_code, 5);
  EXPECT_NE(other.err.find("output already exists; pass --overwrite"), std::string::npos) << other.err;
  EXPECT_EQ(slurp(out / "airport_tile.las"), first);
  const RunResult forced = run(cmd + " --resolution 0.01 --overwrite");
  EXPECT_EQ(forced.exit_code, 0) << forced.err;
  EXPECT_EQ(json::parse(slurp(out / "airport_tile.las.geoanchor.json"))["provenance"]["las"]["scale"][0], 0.01);
}

TEST_F(ApplyCli, ShardsPartitionTheManifestAndParallelJobsWriteTheSameBytes) {
  const fs::path t = fit();
  std::string manifest = "# five tiles\n";
  for (int i = 0; i < 5; ++i) {
    tile("tiles/t" + std::to_string(i) + ".las");
    manifest += "tiles/t" + std::to_string(i) + ".las\n";
  }
  write("tiles.txt", manifest);
  std::set<std::string> seen;
  for (int shard = 0; shard < 2; ++shard) {
    const fs::path out = out_dir("shard" + std::to_string(shard));
    const RunResult r = run("apply " + path("tiles.txt").string() + " --transform " + t.string() + " --shard " +
                            std::to_string(shard) + "/2 --quiet --out-dir " + out.string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    for (const auto& f : files(out)) {
      if (f.ends_with(".las")) {
        EXPECT_TRUE(seen.insert(f).second) << f << " in two shards";
      }
    }
    EXPECT_TRUE(fs::exists(out / ("geoanchor-apply-summary.shard-" + std::to_string(shard) + "-of-2.json")));
  }
  EXPECT_EQ(seen.size(), 5u);
  const fs::path all = out_dir("all");
  const RunResult j = run("apply " + path("tiles").string() + " --transform " + t.string() + " --jobs 3 --quiet --out-dir " +
                          all.string());
  ASSERT_EQ(j.exit_code, 0) << j.err;
  for (const auto& name : seen) {
    const fs::path a = fs::exists(path("shard0") / name) ? path("shard0") / name : path("shard1") / name;
    EXPECT_EQ(slurp(a), slurp(all / name)) << name;
  }
  const RunResult bad = run("apply " + path("tiles.txt").string() + " --shard 2/2 --out-dir " + all.string());
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("0-based"), std::string::npos) << bad.err;
}

TEST_F(ApplyCli, AFourteenParameterTransformIsEvaluatedAtTheTilesEpochAsProjDoes) {
  write("T14.json", kHelmert14);
  const std::vector<Eigen::Vector3d> pts = {{-4052052.0, 4212836.0, -2545105.0}, {-4050000.5, 4213000.25, -2546000.75}};
  std::string csv = "id,x_m,y_m,z_m\n";
  for (std::size_t i = 0; i < pts.size(); ++i) {
    csv += "P" + std::to_string(i) + "," + g17(pts[i].x()) + "," + g17(pts[i].y()) + "," + g17(pts[i].z()) + "\n";
  }
  write("in/tile.csv", csv);
  write("in/tile.csv.geoanchor.json", R"({"schema": "geoanchor.tile/1", "frame": "ITRF2014@2022.5",
      "coordinates": {"kind": "ecef", "storage": "float64"}})");
  const fs::path out = out_dir();
  const RunResult r = run("apply " + path("in/tile.csv").string() + " --transform " + path("T14.json").string() +
                          " --out-dir " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json side = json::parse(slurp(out / "tile.csv.geoanchor.json"));
  EXPECT_EQ(side["frame"], "GDA2020@2022.5");
  EXPECT_EQ(side["provenance"]["observation_epoch"], 2022.5);
  const ProjPipeline proj(kProjHelmert14);
  std::istringstream lines(slurp(out / "tile.csv"));
  std::string line;
  std::getline(lines, line);
  EXPECT_EQ(line, "id,x_m,y_m,z_m");
  for (const auto& p : pts) {
    ASSERT_TRUE(std::getline(lines, line));
    std::stringstream f(line);
    std::string id, x, y, z;
    std::getline(f, id, ',');
    std::getline(f, x, ',');
    std::getline(f, y, ',');
    std::getline(f, z, ',');
    const Eigen::Vector3d e = proj.forward(p, 2022.5);
    EXPECT_LT((Eigen::Vector3d(std::stod(x), std::stod(y), std::stod(z)) - e).norm(), kVsProjTol_m) << line;
  }
  // Without the tile's epoch the transform cannot be evaluated.
  write("noepoch/tile.csv", csv);
  write("noepoch/tile.csv.geoanchor.json", R"({"schema": "geoanchor.tile/1", "frame": "ITRF2014",
      "coordinates": {"kind": "ecef"}})");
  const RunResult none = run("apply " + path("noepoch/tile.csv").string() + " --transform " + path("T14.json").string() +
                             " --overwrite --out-dir " + out.string());
  EXPECT_EQ(none.exit_code, 3);
  EXPECT_NE(none.err.find("error[E_EPOCH_MISSING]"), std::string::npos) << none.err;
  EXPECT_NE(none.err.find("the reference epoch is never substituted"), std::string::npos) << none.err;
}

TEST_F(ApplyCli, PerPointEpochsFromLasGpsTimeAgreeWithProjAtEachPointsTime) {
  write("T14.json", kHelmert14);
  // An ECEF tile (1 mm) whose points were taken over six years.
  testing::LasBuild b;
  b.offset = {-4052000.0, 4212800.0, -2545100.0};
  std::vector<double> gps;  // adjusted standard GPS time (GPS seconds - 1e9)
  for (int i = 0; i < 200; ++i) {
    b.xyz.push_back({i * 997 - 100000, i * 331 + 5000, -i * 713});
    gps.push_back(2.0e8 + i * 9.5e5);  // 2016 .. 2022
  }
  std::vector<std::uint8_t> bytes = testing::build_las(b);
  const std::size_t points_at = bytes.size() - b.xyz.size() * 30;
  for (std::size_t i = 0; i < gps.size(); ++i) std::memcpy(&bytes[points_at + i * 30 + 22], &gps[i], 8);
  fs::create_directories(path("in"));
  testing::write_bytes(path("in/tile.las"), bytes);
  write("in/tile.las.geoanchor.json", R"({"schema": "geoanchor.tile/1", "frame": "ITRF2014",
      "coordinates": {"kind": "ecef", "storage": "int32_scaled"}})");
  const fs::path out = out_dir();
  const std::string cmd = "apply " + path("in/tile.las").string() + " --transform " + path("T14.json").string() +
                          " --out-dir " + out.string();
  const RunResult refused = run(cmd);  // the frame has no epoch: refused without per-point epochs
  EXPECT_EQ(refused.exit_code, 3);
  EXPECT_NE(refused.err.find("E_EPOCH_MISSING"), std::string::npos) << refused.err;
  const RunResult r = run(cmd + " --epoch-from-gps-time");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json side = json::parse(slurp(out / "tile.las.geoanchor.json"));
  EXPECT_EQ(side["frame"], "GDA2020");
  EXPECT_EQ(side["provenance"]["observation_epoch"], "per point, from its GPS time");

  const json got = las_verify(out / "tile.las");
  ASSERT_FALSE(got.is_null());
  const ProjPipeline proj(kProjHelmert14);
  using namespace std::chrono;
  const sys_seconds gps_epoch = sys_days{year{1980} / January / 6};
  const double half_step = 0.0005;
  testing::WorstCase worst;
  std::vector<Eigen::Vector3d> expected_ecef;  // PROJ's, at each point's time
  for (std::size_t i = 0; i < gps.size(); ++i) {
    // The point's decimal year by the C++20 calendar (no leap seconds, as documented).
    const double s = gps[i] + 1e9;
    const auto t = gps_epoch + seconds(static_cast<long long>(s));
    const year_month_day ymd{floor<days>(t)};
    const sys_seconds start = sys_days{ymd.year() / January / 1}, end = sys_days{(ymd.year() + years{1}) / January / 1};
    const double when = static_cast<int>(ymd.year()) + static_cast<double>((t - start).count()) / static_cast<double>((end - start).count());
    const Eigen::Vector3d x(b.xyz[i][0] * 0.001 + b.offset[0], b.xyz[i][1] * 0.001 + b.offset[1], b.xyz[i][2] * 0.001 + b.offset[2]);
    const Eigen::Vector3d e = proj.forward(x, when);
    expected_ecef.push_back(e);
    const auto& p = got["points"][i];
    for (int k = 0; k < 3; ++k) worst.add(std::abs(p[static_cast<std::size_t>(k)].get<double>() - e(k)), i);
    EXPECT_EQ(p[17].get<double>(), gps[i]);  // GpsTime passes through
  }
  EXPECT_WORST_WITHIN(worst, half_step + kVsProjTol_m);

  // The same tile in a CRS (no sidecar: --crs ITRF2014 geocentric), into
  // GDA2020's geographic 3-D CRS: PROJ's conversions around the transform
  // need no epoch, the transform takes each point's.
  fs::create_directories(path("crs"));
  testing::write_bytes(path("crs/tile.las"), bytes);
  const fs::path crs_out = path("crs_out");
  const RunResult c = run("apply " + path("crs/tile.las").string() + " --transform " + path("T14.json").string() +
                          " --crs EPSG:7789 --to-crs EPSG:7843 --epoch-from-gps-time --out-dir " + crs_out.string());
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const json in_crs = las_verify(crs_out / "tile.las");
  ASSERT_FALSE(in_crs.is_null());
  // PROJ's helmert at each point's time, then its geodetic coordinates on GRS80.
  const ProjPipeline geodetic("+proj=pipeline +step +inv +proj=cart +ellps=GRS80 +step +proj=unitconvert +xy_in=rad +xy_out=deg");
  testing::WorstCase worst_deg, worst_m;  // ratios to the tolerance
  const double step_deg = in_crs["header"]["scale"][0].get<double>(), step_m = in_crs["header"]["scale"][2].get<double>();
  for (std::size_t i = 0; i < gps.size(); ++i) {
    const Eigen::Vector3d g = geodetic.forward(expected_ecef[i]);  // lon, lat, h
    const auto& p = in_crs["points"][i];
    worst_deg.add(std::abs(p[0].get<double>() - g.x()) / (0.5 * step_deg + kVsProjTol_deg), i);
    worst_deg.add(std::abs(p[1].get<double>() - g.y()) / (0.5 * step_deg + kVsProjTol_deg), i);
    worst_m.add(std::abs(p[2].get<double>() - g.z()) / (0.5 * step_m + kVsProjTol_m), i);
  }
  EXPECT_WORST_WITHIN(worst_deg, 1.0) << "(ratio to the tolerance)";
  EXPECT_WORST_WITHIN(worst_m, 1.0) << "(ratio to the tolerance)";

  // A tile that states its epoch as well is refused: one or the other.
  fs::create_directories(path("dated"));
  testing::write_bytes(path("dated/tile.las"), bytes);
  write("dated/tile.las.geoanchor.json", R"({"schema": "geoanchor.tile/1", "frame": "ITRF2014@2020.0",
      "coordinates": {"kind": "ecef", "storage": "int32_scaled"}})");
  const RunResult both = run("apply " + path("dated/tile.las").string() + " --transform " + path("T14.json").string() +
                             " --epoch-from-gps-time --out-dir " + path("dated_out").string());
  EXPECT_EQ(both.exit_code, 2) << both.err;
  EXPECT_NE(both.err.find("states the coordinate epoch 2020.0"), std::string::npos) << both.err;
  EXPECT_FALSE(fs::exists(path("dated_out/tile.las")));

  // Without a time-dependent transform the epochs would not be used: refused.
  const RunResult unused = run("apply " + path("crs/tile.las").string() + " --crs EPSG:7789 --to-crs EPSG:7843 "
                               "--epoch-from-gps-time --out-dir " + path("unused").string());
  EXPECT_EQ(unused.exit_code, 2) << unused.err;
  EXPECT_NE(unused.err.find("--epoch-from-gps-time"), std::string::npos) << unused.err;
  EXPECT_FALSE(fs::exists(path("unused/tile.las")));
}

TEST_F(ApplyCli, ATileFarOutsideTheControlNetworkIsRefusedAndANearOneWarned) {
  fit();
  // A small ENU tile 60 km east of the reference point.
  testing::LasBuild b;
  b.xyz = {{60000000, 0, 0}, {60100000, 100000, 5000}};
  fs::create_directories(path("far"));
  testing::write_bytes(path("far/tile.las"), testing::build_las(b));
  write("far/tile.las.geoanchor.json", slurp(kTile + ".geoanchor.json"));
  const fs::path out = out_dir();
  const std::string cmd = "apply " + path("far/tile.las").string() + " --transform " + path("T.json").string() + " --out-dir " + out.string();
  const RunResult r = run(cmd);
  EXPECT_EQ(r.exit_code, 4);
  EXPECT_NE(r.err.find("error[E_EXTRAPOLATION]"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("limit --max-extrapolation 10000 m"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out / "tile.las"));
  const RunResult allowed = run(cmd + " --max-extrapolation 100000");
  EXPECT_EQ(allowed.exit_code, 0) << allowed.err;
  EXPECT_NE(allowed.err.find("outside the control network: the transform is extrapolated"), std::string::npos) << allowed.err;
  const json side = json::parse(slurp(out / "tile.las.geoanchor.json"));
  const double d = side["provenance"]["extrapolation"]["distance_outside_control_m"];
  EXPECT_GT(d, 50000.0);
  EXPECT_LT(d, 62000.0);
  // The extrapolation, and (issue 40 point 3) the tangent plane 60 km from the tile's ENU origin.
  EXPECT_EQ(side["provenance"]["warnings"].size(), 2u);
  EXPECT_NE(side["provenance"]["warnings"].dump().find("the tangent plane departs"), std::string::npos) << side["provenance"]["warnings"];
}

struct BadTile {
  const char* name;
  const char* file;  // tile name in the test folder
  std::function<void(const fs::path&)> make;
  const char* message;
};

class ApplyBadInput : public ApplyCli, public ::testing::WithParamInterface<BadTile> {};

std::vector<std::uint8_t> fixture_bytes() {
  const std::string s = slurp(kTile);
  return std::vector<std::uint8_t>(s.begin(), s.end());
}

void with_sidecar(const fs::path& p) {
  std::ofstream(p.string() + ".geoanchor.json") << slurp(kTile + ".geoanchor.json");
}

TEST_P(ApplyBadInput, NamesTheFileAndWhereAndLeavesNoOutput) {
  const BadTile& c = GetParam();
  fs::create_directories(path("in"));
  const fs::path in = path(std::string("in/") + c.file);
  c.make(in);
  const fs::path out = out_dir();
  const RunResult r = run("apply " + in.string() + " --to ecef --out-dir " + out.string());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find(in.string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(c.message), std::string::npos) << r.err;
  for (const auto& f : files(out)) EXPECT_EQ(f.rfind("geoanchor-apply-summary", 0), 0u) << "left behind: " << f;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, ApplyBadInput,
    ::testing::Values(
        BadTile{"truncated", "t.las", [](const fs::path& p) {
                  auto v = fixture_bytes();
                  v.resize(v.size() - 45);
                  testing::write_bytes(p, v);
                  with_sidecar(p);
                }, "byte 60330: truncated point data"},
        BadTile{"count_vs_size", "t.las", [](const fs::path& p) {
                  auto v = fixture_bytes();
                  v.insert(v.end(), 30, 0);
                  testing::write_bytes(p, v);
                  with_sidecar(p);
                }, "disagrees with the file size"},
        BadTile{"unknown_format", "t.las", [](const fs::path& p) {
                  auto v = fixture_bytes();
                  v[104] = 11;
                  testing::write_bytes(p, v);
                  with_sidecar(p);
                }, "byte 104: point data record format 11 is unknown"},
        BadTile{"vlr_past_header", "t.las", [](const fs::path& p) {
                  auto v = fixture_bytes();
                  v[100] = 1;  // one VLR announced, none there
                  testing::write_bytes(p, v);
                  with_sidecar(p);
                }, "byte 375: VLR 1 of 1 runs past the start of the point data"},
        BadTile{"wkt_proj_cannot_parse", "t.las", [](const fs::path& p) {
                  testing::LasBuild b;
                  b.xyz = {{0, 0, 0}};
                  const std::string w = "PROJCRS[\"broken\",BASEGEOGCRS[";
                  b.vlrs.push_back({"LASF_Projection", 2112, "", std::vector<std::uint8_t>(w.begin(), w.end())});
                  testing::write_bytes(p, testing::build_las(b));
                }, "LAS WKT: PROJ cannot parse it"},
        BadTile{"csv_nan", "t.csv", [](const fs::path& p) {
                  std::ofstream(p) << "id,e_m,n_m,u_m\nA,1,2,3\nB,nan,2,3\n";
                  with_sidecar(p);
                }, ":3: "},
        BadTile{"csv_text", "t.csv", [](const fs::path& p) {
                  std::ofstream(p) << "id,e_m,n_m,u_m\nA,1,2,3\nB,1,two,3\n";
                  with_sidecar(p);
                }, ":3: "},
        BadTile{"ply_truncated", "t.ply", [](const fs::path& p) {
                  std::ofstream(p) << "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
                                      "property double z\nend_header\n1 2 3\n4 5 6\n";
                  with_sidecar(p);
                }, ":10: truncated: 3 vertices expected, 2 found"}),
    [](const ::testing::TestParamInfo<BadTile>& p) { return std::string(p.param.name); });

TEST_F(ApplyCli, InterruptedMidTileLeavesNoPartialFileAtTheOutputPath) {
  // A CSV tile big enough that apply is still writing it when SIGINT comes.
  {
    std::ofstream big(path("big.csv"));
    big << "id,e_m,n_m,u_m\n";
    for (int i = 0; i < 1500000; ++i) big << i << "," << (i % 1000) * 0.37 << "," << (i / 1000) * 0.41 << ",1.5\n";
  }
  write("big.csv.geoanchor.json", slurp(kTile + ".geoanchor.json"));
  const fs::path out = out_dir();
  const std::string exe = CliTest::exe();
  std::vector<std::string> args = {exe, "apply", path("big.csv").string(), "--to", "geodetic", "--quiet", "--out-dir", out.string()};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  ASSERT_EQ(::posix_spawn(&pid, exe.c_str(), nullptr, nullptr, argv.data(), environ), 0);
  bool temporary_seen = false;
  for (int i = 0; i < 1000 && !temporary_seen; ++i) {  // up to 10 s
    for (const auto& f : files(out)) temporary_seen |= f.rfind(".big.csv.tmp-", 0) == 0;
    if (!temporary_seen) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_TRUE(temporary_seen) << "apply never opened its temporary output";
  ASSERT_EQ(::kill(pid, SIGINT), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGINT) << "status " << status;
  EXPECT_EQ(files(out), std::vector<std::string>{}) << "left behind";
}

// issue 12 point 3
TEST_F(ApplyCli, Point3_ATransformWithADuplicateKeyIsRefusedAndNothingIsWritten) {
  std::string t = slurp(fit());
  // nlohmann keeps the last: without the check the tile would be moved as coordinate_frame.
  replace(t, "\"convention\": \"position_vector\",", "\"convention\": \"position_vector\",\n  \"convention\": \"coordinate_frame\",");
  write("T2.json", t);
  const fs::path out = out_dir();
  const RunResult r = run("apply " + kTile + " --transform " + path("T2.json").string() + " --out-dir " + out.string());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("error[E_JSON_DUPLICATE_KEY]"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("T2.json:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(": convention: key given twice"), std::string::npos) << r.err;
  EXPECT_EQ(files(out), std::vector<std::string>{});
}

// A translation ITRF2014@2024.5 -> ETRF2000@2024.5 (the bundled tile's frame)
// with one sigma per axis and `fit_keys` after them.
std::string translation_with_sigmas(const std::string& fit_keys) {
  return R"({"model": "translation3", "source_frame": "ITRF2014@2024.5", "target_frame": "ETRF2000@2024.5",
  "parameters": {"tx_m": 0.05, "ty_m": 0.05, "tz_m": -0.07},
  "sigmas": {"tx_m": 0.02, "ty_m": 0.02, "tz_m": 0.02})" +
         fit_keys + "}";
}

// issue 12 point 9
TEST_F(ApplyCli, Point9_SigmasAreCheckedAndPropagatedAsTheFileStatesThem) {
  // Each case in its own folder, so that each refusal is seen on its own.
  fs::path out = out_dir("nocorr");
  // Sigmas without a correlation matrix: the baseline propagated them as uncorrelated.
  write("nocorr.json", translation_with_sigmas(""));
  const RunResult nocorr = run("apply " + kTile + " --transform " + path("nocorr.json").string() + " --out-dir " + out.string());
  EXPECT_EQ(nocorr.exit_code, 3) << nocorr.err;
  EXPECT_NE(nocorr.err.find("nocorr.json: correlation: missing; sigmas without a correlation matrix"), std::string::npos) << nocorr.err;
  EXPECT_EQ(files(out), std::vector<std::string>{});
  // A typo'd sigma key: the baseline dropped it and propagated the rest.
  std::string typo_text = translation_with_sigmas(R"(, "correlation": "none")");
  replace(typo_text, "\"tz_m\": 0.02", "\"tz_n\": 0.02");
  write("typo.json", typo_text);
  out = out_dir("typo");
  const RunResult typo = run("apply " + kTile + " --transform " + path("typo.json").string() + " --out-dir " + out.string());
  EXPECT_EQ(typo.exit_code, 3) << typo.err;
  EXPECT_NE(typo.err.find("typo.json: sigmas.tz_n: not a parameter of model translation3; sigmas are read for the estimated "
                          "parameters, in the units of parameters: tx_m, ty_m, tz_m"),
            std::string::npos)
      << typo.err;
  EXPECT_EQ(files(out), std::vector<std::string>{});
  // A correlation that no covariance can have.
  write("psd.json", translation_with_sigmas(R"(, "correlation_parameters": ["tx_m", "ty_m", "tz_m"],
      "correlation": [[1, 0.9, -0.9], [0.9, 1, 0.9], [-0.9, 0.9, 1]])"));
  out = out_dir("psd");
  const RunResult psd = run("apply " + kTile + " --transform " + path("psd.json").string() + " --out-dir " + out.string());
  EXPECT_EQ(psd.exit_code, 3) << psd.err;
  EXPECT_NE(psd.err.find("psd.json: correlation: not positive semi-definite"), std::string::npos) << psd.err;
  EXPECT_EQ(files(out), std::vector<std::string>{});

  // Stated uncorrelated: Σ = σ² I in ECEF for a translation (J = I), which is
  // σ along any axes, so the tile's east, north and up sigmas are each 0.02 m.
  constexpr double kPropagatedSigmaTol_m = 1e-9;  // a translation is linear: central differences carry only float64 rounding
  write("none.json", translation_with_sigmas(R"(, "correlation": "none")"));
  out = out_dir("none");
  const RunResult ok = run("apply " + kTile + " --transform " + path("none.json").string() + " --out-dir " + out.string());
  ASSERT_EQ(ok.exit_code, 0) << ok.err;
  const json u = json::parse(slurp(out / "airport_tile.las.geoanchor.json"))["provenance"]["propagated_uncertainty"];
  for (const char* k : {"sigma_e_m", "sigma_n_m", "sigma_u_m"}) {
    ASSERT_TRUE(u[k].is_number()) << u.dump();
    EXPECT_NEAR(u[k].get<double>(), 0.02, kPropagatedSigmaTol_m) << k;
  }
}

// issue 12 point 10
TEST_F(ApplyCli, Point10_WronglyTypedFitStatisticsAndNullSidecarValuesAreRefused) {
  std::string t = slurp(fit());
  // The baseline skipped a value of the wrong type and reported unscaled sigmas.
  replace(t, "\"sigmas_scaled_by_sigma0\": false", "\"sigmas_scaled_by_sigma0\": \"false\"");
  write("T2.json", t);
  const fs::path out = out_dir();
  const RunResult r = run("apply " + kTile + " --transform " + path("T2.json").string() + " --out-dir " + out.string());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("T2.json: statistics.sigmas_scaled_by_sigma0: value \"false\" is not true or false"), std::string::npos)
      << r.err;
  EXPECT_EQ(files(out), std::vector<std::string>{});
  // A sidecar value given as null read as absent, and its default stood in.
  const fs::path in = tile("in/tile.las", [](std::string& s) { replace(s, "\"storage\": \"int32_scaled\"", "\"storage\": null"); });
  const fs::path out2 = out_dir("out2");
  const RunResult n = run("apply " + in.string() + " --to ecef --out-dir " + out2.string());
  EXPECT_EQ(n.exit_code, 3) << n.err;
  EXPECT_NE(n.err.find("tile.las.geoanchor.json: coordinates.storage: value null"), std::string::npos) << n.err;
  EXPECT_FALSE(fs::exists(out2 / "tile.las"));  // (the run's summary names the failure)
  EXPECT_FALSE(fs::exists(out2 / "tile.las.geoanchor.json"));
}

// issue 12 point 1
TEST_F(ApplyCli, Issue12Point1_ACsvTileWithAPointOutsideTheTmDomainIsRefusedAndNothingWritten) {
  const std::string side = R"({"schema": "geoanchor.tile/1", "frame": "ITRF2014@2024.5",
      "coordinates": {"kind": "geodetic", "ellipsoid": "WGS84", "storage": "float64"},
      "vertical": {"height_type": "ellipsoidal", "geoid_model": null}})";
  // (0, 85): the series wrote a finite easting 3 280 km from the exact projection's.
  write("in/tile.csv", "id,lat_deg,lon_deg,h_m\nA,10,5,0\nB,0,85,0\nC,20,10,0\n");
  write("in/tile.csv.geoanchor.json", side);
  const fs::path out = out_dir();
  const RunResult r = run("apply " + path("in/tile.csv").string() + " --to tm --tm 0,0,0.9996,0,0 --out-dir " + out.string());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("error[E_TRANSFORM]: " + path("in/tile.csv").string() +
                       ":3: the point has no finite position in the output frame: outside the output projection's "
                       "domain: lat 0, lon 85: 85.0° from the central meridian 0°; this Transverse Mercator is computed "
                       "within 75°"),
            std::string::npos)
      << r.err;
  // Only the run's summaries: the latest run's and this run's own (issue 12 point 11).
  const std::vector<std::string> left = files(out);
  ASSERT_EQ(left.size(), 2u) << ::testing::PrintToString(left);
  EXPECT_EQ(left[1], "geoanchor-apply-summary.json");
  EXPECT_EQ(left[0].rfind("geoanchor-apply-summary.", 0), 0u) << left[0];
}

// issue 12 point 1
TEST_F(ApplyCli, Issue12Point1_ATilePointOutsideTheForcedZonesBandIsWarnedInStderrAndProvenance) {
  const std::string side = R"({"schema": "geoanchor.tile/1", "frame": "ITRF2014@2024.5",
      "coordinates": {"kind": "geodetic", "ellipsoid": "WGS84", "storage": "float64"},
      "vertical": {"height_type": "ellipsoidal", "geoid_model": null}})";
  write("in/tile.csv", "id,lat_deg,lon_deg,h_m\nA,47,4,0\nB,47,10.5,0\n");
  write("in/tile.csv.geoanchor.json", side);
  const fs::path out = out_dir();
  const RunResult r = run("apply " + path("in/tile.csv").string() + " --to utm --zone 31N --out-dir " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string expected = "output UTM zone 31N: 1 point lies outside the zone's band (0°–6°E, 0°–84°N) by more "
                               "than the 1° margin; the farthest is " + path("in/tile.csv").string() +
                               ":3 (lat 47, lon 10.5), 4.50° beyond";
  EXPECT_NE(r.err.find("geoanchor: warning: " + path("in/tile.csv").string() + ": " + expected), std::string::npos) << r.err;
  const json prov = json::parse(slurp(out / "tile.csv.geoanchor.json"))["provenance"];
  bool recorded = false;
  for (const auto& w : prov["warnings"]) recorded = recorded || w.get<std::string>().find(expected) != std::string::npos;
  EXPECT_TRUE(recorded) << prov.dump(2);
  const ProjPipeline utm31("+proj=utm +zone=31 +ellps=WGS84");
  const Eigen::Vector3d ref = utm31.forward({testing::proj_radians(10.5), testing::proj_radians(47.0), 0.0});
  std::istringstream lines(slurp(out / "tile.csv"));
  std::string line;
  std::getline(lines, line);
  std::getline(lines, line);
  std::getline(lines, line);
  std::stringstream f(line);
  std::string id, e, n;
  std::getline(f, id, ',');
  std::getline(f, e, ',');
  std::getline(f, n, ',');
  EXPECT_NEAR(std::stod(e), ref.x(), kVsProjTol_m) << line;
  EXPECT_NEAR(std::stod(n), ref.y(), kVsProjTol_m) << line;
}

// issue 13 point 5: the ellipsoid comes from the frame. A CSV tile named by
// flags only in GDA2020 on MGA zone 56 is on GRS80 (it was read on WGS84,
// 0.1 mm off in height and up to 1e-9° in latitude), checked against PROJ's
// inverse UTM on GRS80; --ellipsoid WGS84 that contradicts GDA2020 is refused.
TEST_F(ApplyCli, Issue13_Point5_AFramesEllipsoidIsUsedAndAContradictingFlagRefused) {
  write("in/mga.csv", "id,easting_m,northing_m,h_m\nA,334000,6252000,50\nB,340000,6260000,80\n");
  const fs::path out = out_dir();
  const RunResult r = run("apply " + path("in/mga.csv").string() +
                          " --from-frame GDA2020 --from-zone 56S --to geodetic --out-dir " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto got = testing::parse_csv_table(slurp(out / "mga.csv"));
  ASSERT_EQ(got.rows.size(), 2u);
  constexpr double kVsProj_deg = 1e-11;  // about 1 µm; WGS84 instead of GRS80 moves latitude 9e-10°
  const ProjPipeline utm56("+proj=utm +zone=56 +south +ellps=GRS80");
  const double in[2][3] = {{334000, 6252000, 50}, {340000, 6260000, 80}};
  for (std::size_t i = 0; i < 2; ++i) {
    const Eigen::Vector3d g = utm56.inverse(Eigen::Vector3d(in[i][0], in[i][1], in[i][2]));
    EXPECT_NEAR(std::stod(got.rows[i][got.col("lat_deg")]), testing::proj_degrees(g.y()), kVsProj_deg) << i;
    EXPECT_NEAR(std::stod(got.rows[i][got.col("lon_deg")]), testing::proj_degrees(g.x()), kVsProj_deg) << i;
  }
  const json side = json::parse(slurp(out / "mga.csv.geoanchor.json"));
  EXPECT_EQ(side["coordinates"]["ellipsoid"], "GRS80");
  const RunResult contradicted = run("apply " + path("in/mga.csv").string() +
                                     " --from-frame GDA2020 --from-zone 56S --to geodetic --ellipsoid WGS84 --out-dir " +
                                     path("out2").string());
  EXPECT_EQ(contradicted.exit_code, 2);
  EXPECT_NE(contradicted.err.find("--ellipsoid WGS84 contradicts the output frame GDA2020, which is on GRS80"),
            std::string::npos)
      << contradicted.err;
  EXPECT_FALSE(fs::exists(path("out2/mga.csv")));
}

}  // namespace
}  // namespace geoanchor
