// `geoanchor apply` on LAZ tiles (issue 15 points 2-4): the bundled tile as
// LAZ moves to the point records it gets as LAS, read back by laz-perf and
// copc; --format both ways and the output names; the tile's own CRS keeps
// every record (LAS <-> LAZ, COPC -> LAZ); folders of LAS, LAZ and files
// that are not tiles (--exclude); one thread and two write the same file;
// the int32-overflow retry with a LAZ output; every malformed LAZ refused
// naming file, byte and chunk, with nothing left behind.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cstring>
#include <fstream>
#include <functional>
#include <sstream>

#include "cli_support.hpp"
#include "geoanchor/las/las.hpp"
#include "geoanchor/las/laz.hpp"
#include "las_builder.hpp"
#include "laz_support.hpp"

namespace geoanchor {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::Bytes;
using testing::CliTest;
using testing::RunResult;
using testing::SameRecords;
using testing::slurp;

const std::string kFixtures = GEOANCHOR_FIXTURES_DIR;
const std::string kTile = kFixtures + "/airport_tile.las";
const fs::path kLazData = fs::path(GEOANCHOR_SOURCE_DIR) / "tests" / "data" / "laz";

// A LAS or LAZ file's point records as stored: an uncompressed file's bytes
// from the offset to the point data (LAS 1.4 count), a LAZ file through
// laz-perf.
Bytes stored_records(const fs::path& p, const fs::path& scratch) {
  const Bytes b = testing::slurp_bytes(p);
  if (b.size() < 375) return {};
  if (b[104] & 0x80) {
    const auto r = testing::laz_perf(p, scratch);
    return r ? r->records : Bytes{};
  }
  std::uint32_t offset = 0;
  std::uint16_t len = 0;
  std::uint64_t count = 0;
  std::memcpy(&offset, b.data() + 96, 4);
  std::memcpy(&len, b.data() + 105, 2);
  std::memcpy(&count, b.data() + 247, 8);
  return Bytes(b.begin() + offset, b.begin() + static_cast<std::ptrdiff_t>(offset + count * len));
}

// `in` (LAS or LAZ) written again by LasWriter as LAZ in chunks of
// `chunk_points`, with every VLR and EVLR and the header as read.
void to_laz(const fs::path& in, const fs::path& out, std::uint32_t chunk_points,
            std::optional<std::array<double, 6>> bounds = std::nullopt) {
  io::LasReader r(in);
  std::vector<io::LasVlr> vlrs, evlrs;
  for (const auto& v : r.vlrs()) (v.extended ? evlrs : vlrs).push_back(v);
  std::ofstream f(out, std::ios::binary | std::ios::trunc);
  io::LasWriter w(f, r.header(), vlrs, evlrs, out.string(), {true, chunk_points});
  Bytes batch;
  while (const std::size_t n = r.read_records(batch, 7777)) w.write_records(batch.data(), n);
  std::array<double, 3> lo = r.header().min, hi = r.header().max;
  if (bounds) lo = {(*bounds)[0], (*bounds)[1], (*bounds)[2]}, hi = {(*bounds)[3], (*bounds)[4], (*bounds)[5]};
  w.finish(r.header().points_by_return, lo, hi);
}

// A tile of `n` realistic format-7 records with 3 extra bytes, in ENU at
// the bundled tile's origin (its sidecar), as LAS.
void write_realistic_las(const fs::path& p, std::size_t n, unsigned seed) {
  const Bytes records = testing::make_records(7, 3, n, testing::Content::realistic, seed);
  io::LasHeader h;
  h.point_format = 7;
  h.record_length = 39;
  h.global_encoding = 1;
  h.offset = {-1000.0, -2000.0, -400.0};  // the generator's scan lines start near (1000, 2000, 480) m
  std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  testing::widen_record_bounds(records.data(), n, 39, h.offset, lo, hi);
  fs::create_directories(p.parent_path());
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  io::LasWriter w(f, h, {}, {}, p.string());
  w.write_records(records.data(), n);
  std::array<std::uint64_t, 15> by_return{};
  by_return[0] = n;
  w.finish(by_return, lo, hi);
}

class ApplyLaz : public CliTest {
 protected:
  fs::path fit() {
    const RunResult r = run("fit " + kFixtures + "/airport_control.csv --remove-outliers --model helmert7 --convention position_vector -o " +
                            path("T.json").string());
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return path("T.json");
  }
  void sidecar_of_the_bundled_tile(const fs::path& tile) const {
    fs::create_directories(tile.parent_path());
    fs::copy_file(kTile + ".geoanchor.json", tile.string() + ".geoanchor.json", fs::copy_options::overwrite_existing);
  }
  // The bundled tile as LAZ (LasWriter, chunks of 500 points: 4 chunks), with its sidecar.
  fs::path airport_laz(const std::string& name) {
    fs::create_directories(path(name).parent_path());
    to_laz(kTile, path(name), 500);
    sidecar_of_the_bundled_tile(path(name));
    return path(name);
  }
  // What laz-decode.mjs reports (laz-perf and copc) for a LAZ file.
  json laz_report(const fs::path& laz) {
    const auto r = testing::laz_perf(laz, dir_);
    return r ? r->report : json();
  }
  // Only the run summaries in `folder`: nothing else was left.
  void expect_only_summaries(const fs::path& folder) const {
    if (!fs::exists(folder)) return;
    for (const auto& f : files(folder)) EXPECT_EQ(f.rfind("geoanchor-apply-summary", 0), 0u) << "left behind: " << f;
  }
};

// issue 15 acceptance: apply on a LAZ tile gives the same points as on the
// same tile as LAS, byte for byte in the point records; a second reader
// (copc) reads the LAZ output's count, bounds and WKT.
TEST_F(ApplyLaz, Issue15_TheBundledTileAsLazMovesToTheRecordsItGetsAsLas) {
  const fs::path t = fit();
  const fs::path laz = airport_laz("in/airport_tile.laz");
  ASSERT_EQ(io::LasReader(laz).chunk_count(), 4u);
  const RunResult a = run("apply " + kTile + " --transform " + t.string() + " --out-dir " + path("las").string());
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const RunResult b = run("apply " + laz.string() + " --transform " + t.string() + " --out-dir " + path("laz").string());
  ASSERT_EQ(b.exit_code, 0) << b.err;
  EXPECT_NE(b.out.find(laz.string() + " -> " + (path("laz") / "airport_tile.laz").string() + ": 2000 points"),
            std::string::npos)
      << b.out;
  const fs::path las_out = path("las") / "airport_tile.las", laz_out = path("laz") / "airport_tile.laz";
  const Bytes want = stored_records(las_out, dir_);
  ASSERT_EQ(want.size(), 2000u * 30);
  EXPECT_TRUE(SameRecords(stored_records(laz_out, dir_), want, 30)) << "laz-perf's decoding of the LAZ output";
  // copc on both: count, header bounds, the points' bounds and the WKT.
  const json las_view = json::parse(las_verify_text(las_out));
  const json laz_view = laz_report(laz_out);
  ASSERT_FALSE(laz_view.is_null());
  EXPECT_EQ(laz_view["copc"]["pointCount"], 2000);
  EXPECT_EQ(laz_view["copc"]["headerMin"], las_view["header"]["min"]);
  EXPECT_EQ(laz_view["copc"]["headerMax"], las_view["header"]["max"]);
  EXPECT_EQ(laz_view["copc"]["pointsMin"], las_view["header"]["min"]);
  EXPECT_EQ(laz_view["copc"]["pointsMax"], las_view["header"]["max"]);
  EXPECT_EQ(laz_view["copc"]["wkt"], las_view["wkt"]);
  EXPECT_NE(laz_view["copc"]["wkt"].get<std::string>().find("ETRF2000@2024.5"), std::string::npos);
  // The sidecar says what was read and written, and how it is compressed.
  const json side = json::parse(slurp(laz_out.string() + ".geoanchor.json"));
  EXPECT_EQ(side["frame"], "ETRF2000@2024.5");
  EXPECT_EQ(side["provenance"]["input_format"], "laz");
  EXPECT_EQ(side["provenance"]["output_format"], "laz");
  EXPECT_EQ(side["provenance"]["compression"]["format"], "LASzip");
  EXPECT_EQ(side["provenance"]["compression"]["compressor"], "layered chunked");
  EXPECT_EQ(side["provenance"]["compression"]["chunk_points"], 50000);
  EXPECT_EQ(side["provenance"]["compression"]["items"], json::array({"POINT14 v3"}));
  EXPECT_EQ(side["provenance"]["request"]["format"], "laz");
  EXPECT_NE(side["horizontal_crs"].get<std::string>().find("LAZ file"), std::string::npos);
  const json las_side = json::parse(slurp(las_out.string() + ".geoanchor.json"));
  EXPECT_EQ(las_side["provenance"]["output_format"], "las");
  EXPECT_TRUE(las_side["provenance"]["compression"].is_null());
  EXPECT_FALSE(las_side["provenance"]["request"].contains("format")) << "LAS outputs keep their request";
  EXPECT_EQ(side["provenance"]["las"], las_side["provenance"]["las"]) << "the same scale and offset";
  // A rerun finds it up to date.
  const RunResult again = run("apply " + laz.string() + " --transform " + t.string() + " --out-dir " + path("laz").string());
  EXPECT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NE(again.out.find("(up to date, skipped)"), std::string::npos) << again.out;
}

// issue 15 point 2: --format las|laz both ways, the output names, and what
// --format refuses.
TEST_F(ApplyLaz, Issue15_FormatWritesLasOrLazAndNamesTheOutputAfterIt) {
  const fs::path t = fit();
  const fs::path laz = airport_laz("in/airport_tile.laz");
  fs::copy_file(kTile, path("in/scan.las"));
  sidecar_of_the_bundled_tile(path("in/scan.las"));
  const std::string common = " --transform " + t.string() + " --quiet --out-dir ";
  ASSERT_EQ(run("apply " + path("in/scan.las").string() + common + path("plain").string()).exit_code, 0);
  const RunResult to_laz_run = run("apply " + path("in/scan.las").string() + " --format laz" + common + path("a").string());
  ASSERT_EQ(to_laz_run.exit_code, 0) << to_laz_run.err;
  const RunResult to_las_run = run("apply " + laz.string() + " --format las" + common + path("b").string());
  ASSERT_EQ(to_las_run.exit_code, 0) << to_las_run.err;
  EXPECT_TRUE(fs::exists(path("a") / "scan.laz")) << "x.las --format laz -> x.laz";
  EXPECT_TRUE(fs::exists(path("a") / "scan.laz.geoanchor.json"));
  EXPECT_FALSE(fs::exists(path("a") / "scan.las"));
  EXPECT_TRUE(fs::exists(path("b") / "airport_tile.las")) << "x.laz --format las -> x.las";
  EXPECT_FALSE(fs::exists(path("b") / "airport_tile.laz"));
  const Bytes want = stored_records(path("plain") / "scan.las", dir_);
  EXPECT_TRUE(SameRecords(stored_records(path("a") / "scan.laz", dir_), want, 30));
  EXPECT_TRUE(SameRecords(stored_records(path("b") / "airport_tile.las", dir_), want, 30));
  EXPECT_EQ(json::parse(slurp(path("b") / "airport_tile.las.geoanchor.json"))["provenance"]["output_format"], "las");

  // An unknown format is a usage error naming it, before any tile.
  const RunResult bad = run("apply " + laz.string() + " --format zip" + common + path("c").string());
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--format zip: expected las or laz"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(path("c")));
  // --format does not apply to a CSV tile: refused, naming it.
  write("in/p.csv", "id,e_m,n_m,u_m\nA,1,2,3\n");
  sidecar_of_the_bundled_tile(path("in/p.csv"));
  const RunResult csv = run("apply " + path("in/p.csv").string() + " --format laz" + common + path("d").string());
  EXPECT_EQ(csv.exit_code, 2);
  EXPECT_NE(csv.err.find("--format laz: " + path("in/p.csv").string() + " is a csv tile"), std::string::npos) << csv.err;
  EXPECT_FALSE(fs::exists(path("d")));
  // x.las and x.laz both into x.laz: refused before any tile.
  fs::copy_file(kTile, path("in/airport_tile.las"));
  sidecar_of_the_bundled_tile(path("in/airport_tile.las"));
  const RunResult clash = run("apply " + path("in/airport_tile.las").string() + " " + laz.string() + " --format laz" +
                              common + path("e").string());
  EXPECT_EQ(clash.exit_code, 2);
  EXPECT_NE(clash.err.find("E_OUTPUT_CLASH"), std::string::npos) << clash.err;
  EXPECT_NE(clash.err.find((path("e") / "airport_tile.laz").string()), std::string::npos) << clash.err;
  EXPECT_FALSE(fs::exists(path("e")));
}

// issue 15 point 2: an apply whose source and target are the same CRS is a
// pure LAS <-> LAZ conversion: every point record byte for byte, both ways
// and LAZ -> LAZ.
TEST_F(ApplyLaz, Issue15_TheSameCrsOnBothSidesKeepsEveryPointRecord) {
  // A realistic tile (format 7, extra bytes; 120 000 points: three units of
  // work) without CRS; --crs states it.
  write_realistic_las(path("in/t.las"), 120000, 12);
  const Bytes original = stored_records(path("in/t.las"), dir_);
  const std::string crs = " --crs EPSG:25832 --to-crs EPSG:25832 --quiet --jobs 2";
  const RunResult a = run("apply " + path("in/t.las").string() + crs + " --format laz --out-dir " + path("a").string());
  ASSERT_EQ(a.exit_code, 0) << a.err;
  EXPECT_TRUE(SameRecords(stored_records(path("a/t.laz"), dir_), original, 39)) << "LAS -> LAZ (laz-perf)";
  // The LAZ output now states its CRS (WKT, sidecar of kind crs): --to-crs alone.
  const RunResult b = run("apply " + path("a/t.laz").string() + " --to-crs EPSG:25832 --format las --quiet --out-dir " +
                          path("b").string());
  ASSERT_EQ(b.exit_code, 0) << b.err;
  EXPECT_TRUE(SameRecords(stored_records(path("b/t.las"), dir_), original, 39)) << "LAZ -> LAS";
  const RunResult c = run("apply " + path("a/t.laz").string() + " --to-crs EPSG:25832 --quiet --out-dir " + path("c").string());
  ASSERT_EQ(c.exit_code, 0) << c.err;
  EXPECT_TRUE(SameRecords(stored_records(path("c/t.laz"), dir_), original, 39)) << "LAZ -> LAZ";
  const json side = json::parse(slurp(path("c/t.laz.geoanchor.json")));
  EXPECT_EQ(side["provenance"]["coordinates_kept"], true);
  EXPECT_FALSE(side["provenance"].contains("crs_operations"));
  EXPECT_EQ(side["provenance"]["las"]["offset"], json::array({-1000.0, -2000.0, -400.0}));
  // A different CRS moves the points (the records change).
  const RunResult d = run("apply " + path("a/t.laz").string() + " --to-crs EPSG:25833 --quiet --out-dir " + path("d").string());
  ASSERT_EQ(d.exit_code, 0) << d.err;
  EXPECT_FALSE(SameRecords(stored_records(path("d/t.laz"), dir_), original, 39));
}

// issue 15 point 2: a COPC file is read as LAZ and written as plain LAZ
// (x.copc.laz -> x.laz), its copc records dropped with a warning.
TEST_F(ApplyLaz, Issue15_ACopcFileIsWrittenAsPlainLazUnderItsPlainName) {
  const fs::path copc = kLazData / "autzen_clip_native.copc.laz";
  // Its own CRS (the WKT in the file) on both sides.
  const std::string wkt = io::LasReader(copc).wkt().value();
  write("autzen.wkt", wkt);
  const RunResult r = run("apply " + copc.string() + " --to-crs @" + path("autzen.wkt").string() + " --out-dir " +
                          path("out").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const fs::path out = path("out") / "autzen_clip_native.laz";
  ASSERT_TRUE(fs::exists(out)) << r.out;
  EXPECT_NE(r.err.find("a COPC file, written as plain LAZ"), std::string::npos) << r.err;
  EXPECT_TRUE(SameRecords(stored_records(out, dir_), stored_records(copc, dir_), 36)) << "laz-perf on both";
  const io::LasReader written(out);
  for (const auto& v : written.vlrs()) EXPECT_NE(v.user_id, "copc") << v.record_id;
  const json side = json::parse(slurp(out.string() + ".geoanchor.json"));
  EXPECT_EQ(side["provenance"]["input_format"], "laz");
  bool warned = false;
  for (const auto& w : side["provenance"]["warnings"]) warned |= w.get<std::string>().find("COPC") != std::string::npos;
  EXPECT_TRUE(warned) << side["provenance"]["warnings"];
  // --format las: x.copc.laz -> x.las.
  const RunResult las = run("apply " + copc.string() + " --to-crs @" + path("autzen.wkt").string() + " --format las --out-dir " +
                            path("las").string());
  ASSERT_EQ(las.exit_code, 0) << las.err;
  EXPECT_TRUE(SameRecords(stored_records(path("las") / "autzen_clip_native.las", dir_), stored_records(copc, dir_), 36));
}

// issue 15 point 2: folders take LAS and LAZ tiles; a file that is neither a
// tile nor a tile's sidecar is an error naming it, unless --exclude leaves it
// out; before this, a folder's x.laz was skipped without a word.
TEST_F(ApplyLaz, Issue15_AFolderOfLasAndLazReportsEveryOtherFileUnlessExcluded) {
  const fs::path t = fit();
  fs::create_directories(path("tiles/sub"));
  fs::copy_file(kTile, path("tiles/a.las"));
  sidecar_of_the_bundled_tile(path("tiles/a.las"));
  airport_laz("tiles/sub/b.laz");
  write("tiles/notes.md", "survey notes\n");
  write("tiles/sub/c.laz.geoanchor.json", slurp(kTile + ".geoanchor.json"));  // a sidecar without its tile
  const std::string cmd = "apply " + path("tiles").string() + " --transform " + t.string() + " --out-dir ";
  const RunResult r = run(cmd + path("out1").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error[E_INPUT_UNKNOWN]: 2 files in the input folders are neither a tile"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(path("tiles/notes.md").string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(path("tiles/sub/c.laz.geoanchor.json").string() + " (a sidecar without its tile)"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("--exclude GLOB"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("a.las.geoanchor.json"), std::string::npos) << "a tile's sidecar is no unknown file: " << r.err;
  EXPECT_FALSE(fs::exists(path("out1"))) << "nothing processed";
  // Excluded by name and by path: both tiles done, the exclusions in the summary.
  const RunResult ok = run(cmd + path("out2").string() + " --exclude '*.md' --exclude 'sub/c.*' --json");
  ASSERT_EQ(ok.exit_code, 0) << ok.err;
  const json summary = json::parse(ok.out);
  EXPECT_EQ(summary["tiles_done"], 2);
  EXPECT_EQ(summary["excluded"], json::array({path("tiles/notes.md").string(), path("tiles/sub/c.laz.geoanchor.json").string()}));
  EXPECT_TRUE(fs::exists(path("out2/a.las")));
  EXPECT_TRUE(fs::exists(path("out2/b.laz")));
  // The output folder of a run, read as input: its sidecars and summaries are known files.
  const RunResult chained = run("apply " + path("out2").string() + " --transform " + t.string() + " --inverse --out-dir " +
                                path("out3").string() + " --quiet");
  EXPECT_EQ(chained.exit_code, 0) << chained.err;
  // A manifest entry that --exclude names is left out; a named file that is no tile is an error.
  write("list.txt", "tiles/a.las\ntiles/notes.md\n");
  const RunResult m = run("apply " + path("list.txt").string() + " --transform " + t.string() + " --exclude '*.md' --quiet --out-dir " +
                          path("out4").string());
  EXPECT_EQ(m.exit_code, 0) << m.err;
  const RunResult named = run("apply " + path("tiles/notes.md").string() + " --out-dir " + path("out5").string());
  EXPECT_EQ(named.exit_code, 2);
  EXPECT_NE(named.err.find("not a tile; expected .las, .laz, .copc.laz, .csv, .txt, .ply, .geojson, .osm or .xodr"), std::string::npos) << named.err;
}

// issue 15 point 3: one tile's chunks on two threads give the file one
// thread gives (LAZ and LAS), and the LAZ one decodes to the LAS one's records.
TEST_F(ApplyLaz, Issue15_OneThreadAndTwoWriteTheSameFile) {
  const fs::path t = fit();
  write_realistic_las(path("in/big.las"), 160000, 7);
  sidecar_of_the_bundled_tile(path("in/big.las"));
  to_laz(path("in/big.las"), path("in/big.laz"), 50000);
  sidecar_of_the_bundled_tile(path("in/big.laz"));
  for (const char* name : {"big.las", "big.laz"}) {
    SCOPED_TRACE(name);
    const std::string in = path(std::string("in/") + name).string();
    for (const char* jobs : {"1", "2"}) {
      const RunResult r = run("apply " + in + " --transform " + t.string() + " --jobs " + jobs + " --quiet --out-dir " +
                              path(std::string("j") + jobs).string());
      ASSERT_EQ(r.exit_code, 0) << r.err;
    }
    EXPECT_TRUE(testing::slurp_bytes(path("j1") / name) == testing::slurp_bytes(path("j2") / name));
  }
  EXPECT_TRUE(SameRecords(stored_records(path("j2/big.laz"), dir_), stored_records(path("j1/big.las"), dir_), 39));
}

// issue 15 point 2: a tile whose header bounds are wrong overflows int32 at
// the offset they suggest; the retry writes the LAZ output anew, and it
// holds what the LAS output holds.
TEST_F(ApplyLaz, Issue15_TheOverflowRetryWithALazOutputGivesTheLasOutputsRecords) {
  testing::LasBuild b;
  b.offset = {1500000.0, 0.0, 0.0};
  b.xyz = {{-1500000000, 0, 0}, {1500000000, 0, 0}, {0, 0, 0}};
  b.stated_bounds = std::array<double, 6>{0, 0, 0, 1, 1, 1};
  fs::create_directories(path("in"));
  testing::write_bytes(path("in/wide.las"), testing::build_las(b));
  sidecar_of_the_bundled_tile(path("in/wide.las"));
  to_laz(path("in/wide.las"), path("in/wide.laz"), 2, std::array<double, 6>{0, 0, 0, 1, 1, 1});
  sidecar_of_the_bundled_tile(path("in/wide.laz"));
  // 3 000 km from the tile's ENU origin on purpose (issue 40 point 3 refuses that by default).
  const std::string wide = " --to ecef --quiet --max-extrapolation 4e6 --out-dir ";
  const RunResult las = run("apply " + path("in/wide.las").string() + wide + path("las").string());
  ASSERT_EQ(las.exit_code, 0) << las.err;
  const RunResult laz = run("apply " + path("in/wide.laz").string() + wide + path("laz").string());
  ASSERT_EQ(laz.exit_code, 0) << laz.err;
  EXPECT_TRUE(SameRecords(stored_records(path("laz/wide.laz"), dir_), stored_records(path("las/wide.las"), dir_), 30));
  EXPECT_EQ(json::parse(slurp(path("laz/wide.laz.geoanchor.json")))["provenance"]["las"],
            json::parse(slurp(path("las/wide.las.geoanchor.json")))["provenance"]["las"]);
  for (const auto& f : files(path("laz"))) EXPECT_EQ(f.find(".tmp-"), std::string::npos) << "left behind: " << f;
}

// issue 15 point 4: every malformed LAZ through apply names the file, the
// byte offset (and the chunk), exits 3 and leaves no output.
struct BadLaz {
  const char* name;
  std::function<void(Bytes&, const io::LasReader&)> edit;
  std::vector<std::string> message;  // substrings
};

class ApplyBadLaz : public ApplyLaz, public ::testing::WithParamInterface<BadLaz> {};

template <class T>
void put(Bytes& b, std::uint64_t at, T v) {
  std::memcpy(b.data() + at, &v, sizeof v);
}
template <class T>
T get(const Bytes& b, std::uint64_t at) {
  T v;
  std::memcpy(&v, b.data() + at, sizeof v);
  return v;
}
// Where the laszip VLR's payload starts.
std::uint64_t laszip_payload(const Bytes& b) {
  std::uint64_t at = get<std::uint16_t>(b, 94);
  for (std::uint32_t i = 0; i < get<std::uint32_t>(b, 100); ++i) {
    if (std::memcmp(b.data() + at + 2, "laszip encoded", 14) == 0) return at + 54;
    at += 54u + get<std::uint16_t>(b, at + 20);
  }
  return 0;
}

TEST_P(ApplyBadLaz, Issue15_NamesTheFileByteAndChunkAndLeavesNoOutput) {
  const BadLaz& c = GetParam();
  // The bundled tile as LAZ in 4 chunks of 500 points, with its sidecar; then broken.
  const fs::path good = airport_laz("good/t.laz");
  const io::LasReader reader(good);
  Bytes b = testing::slurp_bytes(good);
  c.edit(b, reader);
  fs::create_directories(path("in"));
  testing::write_bytes(path("in/t.laz"), b);
  sidecar_of_the_bundled_tile(path("in/t.laz"));
  const RunResult r = run("apply " + path("in/t.laz").string() + " --to ecef --jobs 2 --out-dir " + path("out").string());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find(path("in/t.laz").string() + ": byte "), std::string::npos) << r.err;
  for (const auto& part : c.message) EXPECT_NE(r.err.find(part), std::string::npos) << r.err << "\nlacks: " << part;
  expect_only_summaries(path("out"));
}

INSTANTIATE_TEST_SUITE_P(
    Cases, ApplyBadLaz,
    ::testing::Values(
        BadLaz{"truncated_chunk",
               [](Bytes& b, const io::LasReader& r) {
                 // Chunk 2 cut to half its bytes, the chunk table saying so: its points run out.
                 const io::LasHeader& h = r.header();
                 std::vector<io::LasVlr> vlrs;
                 for (const auto& v : r.vlrs()) vlrs.push_back(v);
                 io::LazChunkEncoder enc(*r.laz());
                 std::ostringstream f;
                 io::LasWriter w(f, h, vlrs, {}, "t.laz", {true, 500});
                 Bytes records, chunk;
                 for (std::size_t i = 0; i < r.chunk_count(); ++i) {
                   r.decode_chunk(i, records);
                   enc.encode(records.data(), 500, chunk);
                   if (i == 2) chunk.resize(chunk.size() / 2);
                   w.write_chunk(chunk, 500);
                 }
                 w.finish(h.points_by_return, h.min, h.max);
                 const std::string s = f.str();
                 b.assign(s.begin(), s.end());
               },
               {"error[E_LAZ_CHUNK]", "chunk 2 of 4 (500 points", "is corrupt: its layers are longer than the chunk"}},
        BadLaz{"chunk_bytes_removed",
               [](Bytes& b, const io::LasReader& r) {
                 // Chunk 2 cut to 5 bytes, the table moved up with the rest: the sizes it lists no longer fit.
                 const std::uint64_t cut = r.chunk_offset(3) - r.chunk_offset(2) - 5;
                 b.erase(b.begin() + static_cast<std::ptrdiff_t>(r.chunk_offset(2) + 5),
                         b.begin() + static_cast<std::ptrdiff_t>(r.chunk_offset(3)));
                 const std::uint32_t offset = get<std::uint32_t>(b, 96);
                 put<std::uint64_t>(b, offset, get<std::uint64_t>(b, offset) - cut);
               },
               {"E_LAZ_CHUNK_TABLE", "runs past the chunk table"}},
        BadLaz{"cut_short",
               [](Bytes& b, const io::LasReader& r) { b.resize(r.chunk_offset(2) + 100); },
               {"E_LAZ_CHUNK_TABLE", "the chunk table offset", "past the end of the file"}},
        BadLaz{"table_count",
               [](Bytes& b, const io::LasReader&) {
                 const std::uint64_t table = get<std::uint64_t>(b, get<std::uint32_t>(b, 96));
                 put<std::uint32_t>(b, table + 4, 5);
               },
               {"E_LAZ_CHUNK_TABLE", "the chunk table lists 5 chunks, but 2000 points in chunks of 500 make 4"}},
        BadLaz{"table_version",
               [](Bytes& b, const io::LasReader&) {
                 const std::uint64_t table = get<std::uint64_t>(b, get<std::uint32_t>(b, 96));
                 put<std::uint32_t>(b, table, 7);
               },
               {"E_LAZ_UNSUPPORTED", "chunk table version 7 is not supported"}},
        BadLaz{"table_cut",
               [](Bytes& b, const io::LasReader&) {
                 const std::uint64_t table = get<std::uint64_t>(b, get<std::uint32_t>(b, 96));
                 b.resize(table + 9);
               },
               {"E_LAZ_CHUNK_TABLE", "the chunk table of 4 chunks is cut short"}},
        BadLaz{"stray_bytes",
               [](Bytes& b, const io::LasReader&) {
                 const std::uint32_t offset = get<std::uint32_t>(b, 96);
                 const std::uint64_t table = get<std::uint64_t>(b, offset);
                 b.insert(b.begin() + static_cast<std::ptrdiff_t>(table), 16, 0);
                 put<std::uint64_t>(b, offset, table + 16);
               },
               {"E_LAZ_CHUNK_TABLE", "the chunk sizes add up to"}},
        BadLaz{"unsupported_item",
               [](Bytes& b, const io::LasReader&) {
                 const std::uint64_t p = laszip_payload(b);
                 put<std::uint16_t>(b, p + 34 + 4, 4);  // POINT14 version 4
               },
               {"E_LAZ_UNSUPPORTED", "POINT14 version 4"}},
        BadLaz{"compressor",
               [](Bytes& b, const io::LasReader&) { put<std::uint16_t>(b, laszip_payload(b), 1); },
               {"E_LAZ_UNSUPPORTED", "compressor"}},
        BadLaz{"waveform",
               [](Bytes& b, const io::LasReader&) { b[104] = 0x80 | 9; },
               {"E_LAZ_UNSUPPORTED", "byte 104", "WAVEPACKET14"}},
        BadLaz{"vlr_missing",
               [](Bytes& b, const io::LasReader&) {
                 const std::uint64_t p = laszip_payload(b);
                 std::memcpy(b.data() + p - 54 + 2, "laszip encodeX", 14);
               },
               {"E_LAZ_VLR", "byte 104", "no laszip VLR"}}),
    [](const ::testing::TestParamInfo<BadLaz>& p) { return std::string(p.param.name); });

}  // namespace
}  // namespace geoanchor
