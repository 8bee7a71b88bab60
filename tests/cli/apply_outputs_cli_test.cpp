// `geoanchor apply` end to end, moved from apply_cli_test.cpp: outputs
// published exclusively and together, dynamic frames, and implausible
// transforms.

#include "apply_cli_fixture.hpp"

namespace geoanchor {
namespace {

using namespace apply_cli_fixture;

// ---------------------------------------------------------------- issue 12 point 11: outputs

class ApplyOutputs : public ApplyCli {
 protected:
  // A two-point ENU CSV tile with the bundled tile's sidecar (its frame and origin).
  fs::path small_tile(const std::string& name) {
    write(name, "id,e_m,n_m,u_m\n1,1.5,2.5,3.5\n2,10.25,-4.5,1.0\n");
    write(name + ".geoanchor.json", slurp(kTile + ".geoanchor.json"));
    return path(name);
  }
  // The names in `folder` other than run summaries.
  std::vector<std::string> outputs_in(const fs::path& folder) const {
    std::vector<std::string> out;
    for (const auto& f : files(folder)) {
      if (f.rfind("geoanchor-apply-summary", 0) != 0) out.push_back(f);
    }
    return out;
  }
  // The tile's sidecar describes the file beside it.
  static void expect_pair(const fs::path& tile) {
    ASSERT_TRUE(fs::is_regular_file(tile)) << tile;
    ASSERT_TRUE(fs::is_regular_file(tile.string() + ".geoanchor.json")) << tile;
    const json prov = json::parse(slurp(tile.string() + ".geoanchor.json"))["provenance"];
    EXPECT_EQ(prov["output_size_bytes"].get<std::uint64_t>(), fs::file_size(tile)) << tile;
  }
};

// Makes `p` older than a stale temporary needs to be (io::kStaleTemporaryAge).
void make_old(const fs::path& p) {
  const struct timespec old[2] = {{1000000000, 0}, {1000000000, 0}};  // 2001-09-09
  ASSERT_EQ(::utimensat(AT_FDCWD, p.c_str(), old, AT_SYMLINK_NOFOLLOW), 0) << p;
}

// issue 12 point 11
TEST_F(ApplyOutputs, Issue12Point11_OverwriteOntoAFifoOrAFolderIsRefusedAndNothingIsCreated) {
  const fs::path in = small_tile("in/t.csv");
  const fs::path out = out_dir();
  const std::string cmd = "apply " + in.string() + " --to geodetic --out-dir " + out.string();
  ASSERT_EQ(::mkfifo((out / "t.csv").c_str(), 0644), 0);
  for (const std::string flag : {" --overwrite", ""}) {
    const RunResult r = run(cmd + flag);
    EXPECT_EQ(r.exit_code, 5) << flag << r.err;
    EXPECT_NE(r.err.find("error[E_OUTPUT_NOT_REGULAR]: " + (out / "t.csv").string() +
                         ": is a FIFO (named pipe), not a regular file; an output only ever replaces a regular file, "
                         "with or without --overwrite"),
              std::string::npos)
        << flag << r.err;
    EXPECT_TRUE(fs::is_fifo(out / "t.csv")) << "the FIFO was replaced" << flag;
    EXPECT_EQ(outputs_in(out), std::vector<std::string>{"t.csv"}) << flag;  // no sidecar, no temporary
  }
  // A folder where the sidecar would go.
  fs::remove(out / "t.csv");
  fs::create_directory(out / "t.csv.geoanchor.json");
  const RunResult folder = run(cmd + " --overwrite");
  EXPECT_EQ(folder.exit_code, 5) << folder.err;
  EXPECT_NE(folder.err.find("error[E_OUTPUT_NOT_REGULAR]: " + (out / "t.csv.geoanchor.json").string() +
                            ": is a folder, not a regular file"),
            std::string::npos)
      << folder.err;
  EXPECT_EQ(outputs_in(out), std::vector<std::string>{"t.csv.geoanchor.json"});
  EXPECT_TRUE(fs::is_empty(out / "t.csv.geoanchor.json"));
  // A FIFO where the sidecar of an existing tile would be read by the
  // resumability check (it blocked there for ever): refused, never opened.
  fs::remove(out / "t.csv.geoanchor.json");
  write("out/t.csv", "id,lat_deg,lon_deg,h_m\n");
  ASSERT_EQ(::mkfifo((out / "t.csv.geoanchor.json").c_str(), 0644), 0);
  const RunResult fifo = shell("timeout 60 " + exe() + " " + cmd + " --overwrite");
  EXPECT_EQ(fifo.exit_code, 5) << fifo.err;
  EXPECT_NE(fifo.err.find("error[E_OUTPUT_NOT_REGULAR]: " + (out / "t.csv.geoanchor.json").string() + ": is a FIFO"),
            std::string::npos)
      << fifo.err;
  const RunResult resume = shell("timeout 60 " + exe() + " " + cmd);
  EXPECT_EQ(resume.exit_code, 5) << "124 is timeout's: the run blocked on the FIFO\n" << resume.err;
  EXPECT_TRUE(fs::is_fifo(out / "t.csv.geoanchor.json"));
  EXPECT_EQ(slurp(out / "t.csv"), "id,lat_deg,lon_deg,h_m\n");
}

// issue 12 point 11
TEST_F(ApplyOutputs, Issue12Point11_TwoConcurrentAppliesPublishEachTileOnceAndKeepBothSummaries) {
  // Tiles large enough (about 0.3 s each) that two runs started together
  // both find them absent and both write them.
  constexpr int kTiles = 3;
  constexpr int kRows = 100000;
  fs::create_directories(path("in"));
  for (int t = 0; t < kTiles; ++t) {
    std::ofstream big(path("in/t" + std::to_string(t) + ".csv"));
    big << "id,e_m,n_m,u_m\n";
    for (int i = 0; i < kRows; ++i) big << i << "," << (i % 1000) * 0.37 << "," << (i / 1000) * 0.41 + t << ",1.5\n";
    write("in/t" + std::to_string(t) + ".csv.geoanchor.json", slurp(kTile + ".geoanchor.json"));
  }
  const fs::path out = out_dir();
  const std::string cmd = exe() + " apply " + path("in").string() + " --to geodetic --quiet --json --out-dir " + out.string();
  const RunResult both = shell("(" + cmd + " > '" + path("a.json").string() + "' 2> '" + path("a.err").string() + "' & " + cmd +
                               " > '" + path("b.json").string() + "' 2> '" + path("b.err").string() + "' & wait)");
  ASSERT_EQ(both.exit_code, 0) << both.err;
  const json a = json::parse(slurp(path("a.json"))), b = json::parse(slurp(path("b.json")));
  ASSERT_EQ(a["tiles"].size(), static_cast<std::size_t>(kTiles)) << a.dump(2);
  ASSERT_EQ(b["tiles"].size(), static_cast<std::size_t>(kTiles)) << b.dump(2);
  int raced = 0;
  for (int t = 0; t < kTiles; ++t) {
    const json& ta = a["tiles"][static_cast<std::size_t>(t)];
    const json& tb = b["tiles"][static_cast<std::size_t>(t)];
    const std::string sa = ta["status"], sb = tb["status"];
    // At most one run published the tile; the other says why it did not.
    EXPECT_TRUE((sa == "done") != (sb == "done")) << "tile " << t << ": " << sa << " and " << sb;
    const json& lost = sa == "done" ? tb : ta;
    if (lost["status"] == "failed") {
      ++raced;
      const std::string code = lost["error_code"];
      EXPECT_TRUE(code == "E_OUTPUT_EXISTS" || code == "E_OUTPUT_BUSY") << lost.dump(2);
      if (code == "E_OUTPUT_EXISTS") {
        EXPECT_NE(lost["error"].get<std::string>().find("another process put a file at this path while this run was writing it"),
                  std::string::npos)
            << lost.dump(2);
      }
    } else {
      EXPECT_EQ(lost["status"], "skipped") << lost.dump(2);  // the other run had finished it: up to date
    }
    expect_pair(out / ("t" + std::to_string(t) + ".csv"));
  }
  RecordProperty("tiles_both_runs_wrote", raced);
  // Each run's own summary, and the latest one under the name scripts read.
  ASSERT_TRUE(a.contains("run_id") && b.contains("run_id")) << a.dump(2);
  EXPECT_NE(a["run_id"], b["run_id"]);
  EXPECT_EQ(slurp(out / a["run_summary"].get<std::string>()), slurp(path("a.json")));
  EXPECT_EQ(slurp(out / b["run_summary"].get<std::string>()), slurp(path("b.json")));
  const std::string latest = slurp(out / "geoanchor-apply-summary.json");
  EXPECT_TRUE(latest == slurp(path("a.json")) || latest == slurp(path("b.json")));
  // No temporary left, and a third run finds every tile up to date.
  std::vector<std::string> expected;
  for (int t = 0; t < kTiles; ++t) {
    expected.push_back("t" + std::to_string(t) + ".csv");
    expected.push_back("t" + std::to_string(t) + ".csv.geoanchor.json");
  }
  EXPECT_EQ(outputs_in(out), expected);
  const RunResult third = run("apply " + path("in").string() + " --to geodetic --quiet --json --out-dir " + out.string());
  ASSERT_EQ(third.exit_code, 0) << third.err;
  EXPECT_EQ(json::parse(third.out)["tiles_skipped"], kTiles) << third.out;
}

// issue 12 point 11
TEST_F(ApplyOutputs, Issue12Point11_ASidecarThatCannotBeWrittenLeavesNeitherFileAndARerunWritesBoth) {
  const fs::path in = small_tile("in/t.csv");
  const fs::path out = out_dir();
  const std::string args = "apply " + in.string() + " --to geodetic --out-dir " + out.string();
  // Files limited to 1 KiB (ulimit -f counts 512-byte blocks in sh): the
  // two-point tile fits, its sidecar (1.6 kB) does not; its write fails with
  // EFBIG as it would on a full disk.
  const RunResult full = shell("trap '' XFSZ; ulimit -f 2; exec " + exe() + " " + args);
  EXPECT_EQ(full.exit_code, 5) << full.err;
  EXPECT_NE(full.err.find("error[E_WRITE]: " + (out / "t.csv.geoanchor.json").string() +
                          ": writing failed (File too large); neither " + (out / "t.csv.geoanchor.json").string() +
                          " nor " + (out / "t.csv").string() + " was written"),
            std::string::npos)
      << full.err;
  EXPECT_EQ(outputs_in(out), std::vector<std::string>{}) << "left behind";
  // The rerun is not blocked by a lone tile: it writes both.
  const RunResult rerun = run(args);
  ASSERT_EQ(rerun.exit_code, 0) << rerun.err;
  expect_pair(out / "t.csv");
  EXPECT_EQ(outputs_in(out), (std::vector<std::string>{"t.csv", "t.csv.geoanchor.json"}));
}

// issue 12 point 11
TEST_F(ApplyOutputs, Issue12Point11_ASidecarLeftWithoutItsTileByAKilledRunIsRedoneOnResume) {
  const fs::path in = small_tile("in/t.csv");
  const fs::path out = out_dir();
  const std::string args = "apply " + in.string() + " --to geodetic --out-dir " + out.string();
  ASSERT_EQ(run(args).exit_code, 0);
  // A run killed between publishing the sidecar and the tile leaves this.
  fs::remove(out / "t.csv");
  const RunResult resume = run(args);
  ASSERT_EQ(resume.exit_code, 0) << resume.err;
  EXPECT_NE(resume.err.find("geoanchor: warning: " + (out / "t.csv.geoanchor.json").string() +
                            ": removed a sidecar without its tile, left by an interrupted run; the tile is redone"),
            std::string::npos)
      << resume.err;
  expect_pair(out / "t.csv");
  // A file of someone else's at the sidecar's path is never removed.
  const fs::path other = out_dir("other");
  write("other/t.csv.geoanchor.json", "notes of someone else's\n");
  const RunResult refused = run("apply " + in.string() + " --to geodetic --out-dir " + other.string());
  EXPECT_EQ(refused.exit_code, 5) << refused.err;
  EXPECT_NE(refused.err.find("error[E_OUTPUT_EXISTS]: " + (other / "t.csv.geoanchor.json").string() +
                             ": output already exists; pass --overwrite"),
            std::string::npos)
      << refused.err;
  EXPECT_EQ(slurp(other / "t.csv.geoanchor.json"), "notes of someone else's\n");
  EXPECT_EQ(outputs_in(other), std::vector<std::string>{"t.csv.geoanchor.json"});
}

// issue 12 point 11
TEST_F(ApplyOutputs, Issue12Point11_TemporariesOfAKilledRunAreRemovedAndALiveOneKept) {
  const fs::path in = small_tile("in/t.csv");
  const fs::path out = out_dir();
  // A run killed by SIGKILL left its temporary: nobody holds it.
  write("out/.t.csv.tmp-0123456789abcdef", "id,lat_deg,lon_deg,h_m\n1,47.4");
  make_old(out / ".t.csv.tmp-0123456789abcdef");
  // Another run, alive, is writing this one: it holds its lock.
  write("out/.u.las.tmp-fedcba9876543210", "LASF");
  make_old(out / ".u.las.tmp-fedcba9876543210");
  const int live = ::open((out / ".u.las.tmp-fedcba9876543210").c_str(), O_WRONLY);
  ASSERT_GE(live, 0);
  ASSERT_EQ(::flock(live, LOCK_EX), 0);
  // Not our pattern: never touched.
  write("out/.t.csv.tmp-keep", "x");
  make_old(out / ".t.csv.tmp-keep");
  const RunResult r = run("apply " + in.string() + " --to geodetic --json --out-dir " + out.string());
  ::close(live);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::exists(out / ".t.csv.tmp-0123456789abcdef"));
  EXPECT_TRUE(fs::exists(out / ".u.las.tmp-fedcba9876543210"));
  EXPECT_TRUE(fs::exists(out / ".t.csv.tmp-keep"));
  EXPECT_NE(r.err.find("geoanchor: warning: " + (out / ".t.csv.tmp-0123456789abcdef").string() +
                       ": removed, a temporary output left by a run that was killed"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(json::parse(r.out)["stale_temporaries_removed"], json::array({(out / ".t.csv.tmp-0123456789abcdef").string()}));
}

// issue 12 point 11
TEST_F(ApplyOutputs, Issue12Point11_ApplyJsonOntoAFullStandardOutputExitsNonZero) {
  const fs::path in = small_tile("in/t.csv");
  const fs::path out = out_dir();
  const RunResult r = shell("(" + exe() + " apply " + in.string() + " --to geodetic --json --out-dir " + out.string() +
                            " > /dev/full)");
  EXPECT_EQ(r.exit_code, 5) << r.err;
  EXPECT_NE(r.err.find("error[E_WRITE]: standard output: the run summary could not be written (No space left on device); "
                       "the outputs and the summary " + out.string() + "/geoanchor-apply-summary."),
            std::string::npos)
      << r.err;
  expect_pair(out / "t.csv");  // as the message says
}

// issue 12 point 5: a tile in a dynamic frame without its coordinate epoch
// is refused, whether the sidecar or --from-frame names the frame, before
// anything is written; the baseline moved it with a static transform.
TEST_F(ApplyCli, Point5_ATileInADynamicFrameWithoutItsEpochIsRefusedNamingTheSidecarOrTheFlag) {
  write("T.json", R"({"model": "translation3", "source_frame": "ITRF2014@2024.5", "target_frame": "ETRF2000",
  "parameters": {"tx_m": 0.05, "ty_m": 0.05, "tz_m": -0.07}})");
  const fs::path in = tile("in/tile.las", [](std::string& s) { replace(s, "\"ITRF2014@2024.5\"", "\"ITRF2014\""); });
  const fs::path out = out_dir();
  const RunResult r = run("apply " + in.string() + " --transform " + path("T.json").string() + " --out-dir " + out.string());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("error[E_EPOCH_MISSING]"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(in.string() + ": sidecar " + in.string() + ".geoanchor.json: frame: frame ITRF2014 is dynamic"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("give ITRF2014@YYYY.Y"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out / "tile.las"));  // (the batch's summary records the refusal)
  EXPECT_FALSE(fs::exists(out / "tile.las.geoanchor.json"));

  fs::create_directories(path("bare"));
  fs::copy_file(kTile, path("bare/tile.las"));
  const std::string flags = " --from-origin 47.464722,8.549167,480 --ellipsoid GRS80 --to ecef --out-dir " + out.string();
  const RunResult f = run("apply " + path("bare/tile.las").string() + " --from-frame ITRF2014" + flags);
  EXPECT_EQ(f.exit_code, 2) << f.err;
  EXPECT_NE(f.err.find("--from-frame: frame ITRF2014 is dynamic"), std::string::npos) << f.err;
  EXPECT_NE(f.err.find("give ITRF2014@YYYY.Y"), std::string::npos) << f.err;
  EXPECT_FALSE(fs::exists(out / "tile.las"));  // (the batch's summary records the refusal)
  EXPECT_FALSE(fs::exists(out / "tile.las.geoanchor.json"));
  // A plate-fixed frame needs no epoch; a dynamic one with its epoch is accepted.
  const RunResult etrf = run("apply " + path("bare/tile.las").string() + " --from-frame ETRF2000" + flags);
  EXPECT_EQ(etrf.exit_code, 0) << etrf.err;
  const RunResult dated = run("apply " + path("bare/tile.las").string() + " --from-frame ITRF2014@2024.5 --overwrite" + flags);
  EXPECT_EQ(dated.exit_code, 0) << dated.err;

  // A LAS WKT naming the realization by its EPSG datum name, without an epoch.
  const std::string wkt =
      "GEODCRS[\"ITRF2014\",DATUM[\"International Terrestrial Reference Frame 2014\",ELLIPSOID[\"GRS 1980\",6378137,"
      "298.257222101]],CS[Cartesian,3],AXIS[\"(X)\",geocentricX,LENGTHUNIT[\"metre\",1]],AXIS[\"(Y)\",geocentricY,"
      "LENGTHUNIT[\"metre\",1]],AXIS[\"(Z)\",geocentricZ,LENGTHUNIT[\"metre\",1]]]";
  testing::LasBuild b;
  b.offset = {4277000.0, 639000.0, 4672000.0};
  b.xyz = {{686016, 405550, 438669}, {687016, 406550, 439669}};
  b.vlrs.push_back({"LASF_Projection", 2112, "", std::vector<std::uint8_t>(wkt.begin(), wkt.end())});
  fs::create_directories(path("wkt"));
  testing::write_bytes(path("wkt/itrf.las"), testing::build_las(b));
  const fs::path out2 = out_dir("out2");
  const RunResult w = run("apply " + path("wkt/itrf.las").string() + " --to geodetic --out-dir " + out2.string());
  EXPECT_EQ(w.exit_code, 3) << w.err;
  EXPECT_NE(w.err.find("itrf.las: LAS WKT: frame ITRF2014 is dynamic"), std::string::npos) << w.err;
  EXPECT_NE(w.err.find("give ITRF2014@YYYY.Y"), std::string::npos) << w.err;
  EXPECT_FALSE(fs::exists(out2 / "itrf.las"));
  EXPECT_FALSE(fs::exists(out2 / "itrf.las.geoanchor.json"));
}


// ---------------------------------------------------------------- issue 12 point 7: implausible parameters

// Two ECEF CSV tiles in ITRF2014 at `epoch_a` and `epoch_b`: in/a.csv and in/b.csv with their sidecars (name, text).
std::vector<std::pair<std::string, std::string>> two_ecef_tiles(const std::string& epoch_a, const std::string& epoch_b) {
  const std::string csv = "id,x_m,y_m,z_m\nP0,4277000,639000,4672000\nP1,4277100,639050,4671900\n";
  std::vector<std::pair<std::string, std::string>> files;
  for (const auto& [name, epoch] : {std::pair{"a", epoch_a}, std::pair{"b", epoch_b}}) {
    files.emplace_back(std::string("in/") + name + ".csv", csv);
    files.emplace_back(std::string("in/") + name + ".csv.geoanchor.json",
                       R"({"schema": "geoanchor.tile/1", "frame": "ITRF2014@)" + epoch + R"(",
      "coordinates": {"kind": "ecef", "storage": "float64"}})");
  }
  return files;
}

// How many of `warnings` (a JSON array) start with `expected`.
int count_starting(const json& warnings, const std::string& expected) {
  int n = 0;
  for (const auto& w : warnings) n += w.get<std::string>().rfind(expected, 0) == 0 ? 1 : 0;
  return n;
}

// How many times `needle` occurs in `hay`.
int occurrences(const std::string& hay, const std::string& needle) {
  int n = 0;
  for (auto at = hay.find(needle); at != std::string::npos; at = hay.find(needle, at + 1)) ++n;
  return n;
}

// issue 12 point 7
TEST_F(ApplyCli, Issue12Point7_ImplausibleTransformParametersWarnOnceAndAreInEveryTileSidecarAndTheSummary) {
  // fit's limits (geodesy/helmert.hpp, RELIABILITY #15): |t| <= 1 km, |r| <= 10″, |ds| <= 100 ppm.
  // The baseline applied each of these silently (exit 0, no warning).
  struct Case {
    const char* name;
    std::string parameters;
    std::string expected;  // after the transform's path; empty: no implausibility warning
  };
  const std::vector<Case> cases = {
      // 20″ at the Earth's mean radius: 20 / 206264.806 × 6371 km = 618 m.
      {"rx", R"("tx_m": 0, "ty_m": 0, "tz_m": 0, "rx_arcsec": 20, "ry_arcsec": 0, "rz_arcsec": 0, "ds_ppm": 0)",
       ": rx = 20″ is implausible for a datum transform (> 10″, 618 m at the Earth's surface)"},
      {"ds", R"("tx_m": 0, "ty_m": 0, "tz_m": 0, "rx_arcsec": 0, "ry_arcsec": 0, "rz_arcsec": 0, "ds_ppm": 200)",
       ": ds = 200 ppm is implausible for a datum transform (> 100 ppm"},
      {"tx", R"("tx_m": 1e300, "ty_m": 0, "tz_m": 0, "rx_arcsec": 0, "ry_arcsec": 0, "rz_arcsec": 0, "ds_ppm": 0)",
       ": tx = 1e+300 m is implausible for a datum transform (> 1e+03 m)"},
      {"plausible", R"("tx_m": 0.05, "ty_m": 0.05, "tz_m": -0.07, "rx_arcsec": 0.002, "ry_arcsec": 0.012, )"
                    R"("rz_arcsec": -0.02, "ds_ppm": 0.003)",
       ""},
  };
  for (const auto& [name, text] : two_ecef_tiles("2024.5", "2024.5")) write(name, text);
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string t = std::string(c.name) + ".json";
    write(t, R"({"model": "helmert7", "convention": "position_vector", "source_frame": "ITRF2014@2024.5",
      "target_frame": "ETRF2000", "parameters": {)" + c.parameters + "}}");
    const fs::path out = out_dir(std::string("out_") + c.name);
    const RunResult r = run("apply " + path("in/a.csv").string() + " " + path("in/b.csv").string() + " --transform " +
                            path(t).string() + " --out-dir " + out.string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const json summary = json::parse(slurp(out / "geoanchor-apply-summary.json"));
    ASSERT_TRUE(summary["warnings"].is_array()) << summary.dump(2);
    if (c.expected.empty()) {
      EXPECT_EQ(r.err.find("implausible"), std::string::npos) << r.err;
      EXPECT_TRUE(summary["warnings"].empty()) << summary.dump(2);
      for (const char* tile : {"a.csv", "b.csv"}) {
        const json prov = json::parse(slurp(out / (std::string(tile) + ".geoanchor.json")))["provenance"];
        EXPECT_EQ(prov["warnings"].dump().find("implausible"), std::string::npos) << prov.dump(2);
      }
      continue;
    }
    const std::string expected = path(t).string() + c.expected;
    EXPECT_EQ(occurrences(r.err, "geoanchor: warning: " + expected), 1) << r.err;  // once per run, not per tile
    EXPECT_EQ(count_starting(summary["warnings"], expected), 1) << summary.dump(2);
    for (const char* tile : {"a.csv", "b.csv"}) {
      const json prov = json::parse(slurp(out / (std::string(tile) + ".geoanchor.json")))["provenance"];
      EXPECT_EQ(count_starting(prov["warnings"], expected), 1) << tile << "\n" << prov.dump(2);
    }
  }
}

// issue 12 point 7
TEST_F(ApplyCli, Issue12Point7_AFourteenParameterSetIsCheckedAtEachTilesEpochAndTheRunsLatest) {
  // rz = 5″ + 1″/yr × (t − 2020): 6″ for the tile at 2021 (plausible), 15″ for the one at 2030.
  write("T14.json", R"({"model": "helmert14", "convention": "position_vector", "source_frame": "ITRF2014",
    "target_frame": "GDA2020", "reference_epoch": 2020.0,
    "parameters": {"tx_m": 0, "ty_m": 0, "tz_m": 0, "rx_arcsec": 0, "ry_arcsec": 0, "rz_arcsec": 5, "ds_ppm": 0,
                   "dtx_m_per_year": 0, "dty_m_per_year": 0, "dtz_m_per_year": 0, "drx_arcsec_per_year": 0,
                   "dry_arcsec_per_year": 0, "drz_arcsec_per_year": 1, "dds_ppm_per_year": 0}})");
  for (const auto& [name, text] : two_ecef_tiles("2021.0", "2030.0")) write(name, text);
  const fs::path out = out_dir();
  const RunResult r = run("apply " + path("in/a.csv").string() + " " + path("in/b.csv").string() + " --transform " +
                          path("T14.json").string() + " --out-dir " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string expected =
      path("T14.json").string() + " at epoch 2030: rz = 15″ is implausible for a datum transform (> 10″";
  EXPECT_EQ(occurrences(r.err, "geoanchor: warning: " + expected), 1) << r.err;
  EXPECT_EQ(r.err.find("at epoch 2021"), std::string::npos) << r.err;
  const json summary = json::parse(slurp(out / "geoanchor-apply-summary.json"));
  EXPECT_EQ(count_starting(summary["warnings"], expected), 1) << summary.dump(2);
  const json early = json::parse(slurp(out / "a.csv.geoanchor.json"))["provenance"];
  EXPECT_EQ(early["warnings"].dump().find("implausible"), std::string::npos) << early.dump(2);
  const json late = json::parse(slurp(out / "b.csv.geoanchor.json"))["provenance"];
  EXPECT_EQ(count_starting(late["warnings"], expected), 1) << late.dump(2);
}

}  // namespace
}  // namespace geoanchor
