// LAZ tiles through apply_las_tile (issue 15 points 2-4): a tile moved as
// LAZ gives the point records of the same tile moved as LAS, byte for byte,
// in every combination of LAS and LAZ in and out, on one thread or several
// (the same file whatever the threads); laz-perf (npm, the LASzip codec
// compiled to WebAssembly) decodes every LAZ output to those records; a
// LASzip-written sample moves like its uncompressed twin; the tile's own
// coordinates keep every record; the int32-overflow retry writes a LAZ
// output anew; the first error in point order is the one reported whatever
// the threads.

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>

#include "geoanchor/base/error.hpp"
#include "geoanchor/crs/crs.hpp"
#include "geoanchor/crs/crs_operation.hpp"
#include "geoanchor/las/las.hpp"
#include "geoanchor/las/laz.hpp"
#include "geoanchor/io/tile/tile_apply.hpp"
#include "las_builder.hpp"
#include "laz_support.hpp"
#include "temp_folder.hpp"

namespace geoanchor::io {
namespace {

namespace fs = std::filesystem;
using testing::Bytes;
using testing::Content;
using testing::laz_perf;
using testing::make_records;
using testing::SameRecords;

const fs::path kData = GEOANCHOR_LAZ_DATA_DIR;

const char* kHelmert = R"J({"model": "helmert7", "convention": "position_vector",
  "source_frame": "ITRF2014@2024.5", "target_frame": "ETRF2000@2024.5",
  "parameters": {"tx_m": 0.0547, "ty_m": 0.0522, "tz_m": -0.0741, "rx_arcsec": 0.00228, "ry_arcsec": 0.01404,
                 "rz_arcsec": -0.02168, "ds_ppm": 0.00212}})J";

geodesy::LocalOrigin origin(double lat, double lon, double h) {
  return {{geodesy::Angle::degrees(lat), geodesy::Angle::degrees(lon), geodesy::EllipsoidalHeight{h}},
          geodesy::Ellipsoid::grs80()};
}
ArrayFrame enu_frame(const geodesy::LocalOrigin& o) {
  return ArrayFrame{CoordinateKind::enu, geodesy::Ellipsoid::grs80(), o, std::nullopt};
}
const ArrayFrame kA = enu_frame(origin(47.464722, 8.549167, 480.0));
const ArrayFrame kB = enu_frame(origin(47.2597, 11.3439, 581.0));  // a second airport, 210 km away
const ArrayFrame kEcef{CoordinateKind::ecef, geodesy::Ellipsoid::grs80(), std::nullopt, std::nullopt};

// The point records of a LAS or LAZ file as stored, read without
// geoanchor's reader: an uncompressed file's bytes between the offset to
// the point data and its end; a LAZ file through laz-perf.
Bytes stored_records(const fs::path& p, const fs::path& scratch) {
  const Bytes b = testing::slurp_bytes(p);
  std::uint32_t offset = 0;
  std::uint16_t len = 0;
  std::uint64_t count = 0;
  std::memcpy(&offset, b.data() + 96, 4);
  std::memcpy(&len, b.data() + 105, 2);
  if (b[104] & 0x80) {
    const auto r = laz_perf(p, scratch);
    return r ? r->records : Bytes{};
  }
  std::memcpy(&count, b.data() + 247, 8);
  if (b[25] < 4) {
    std::uint32_t legacy = 0;
    std::memcpy(&legacy, b.data() + 107, 4);
    count = legacy;
  }
  return Bytes(b.begin() + offset, b.begin() + static_cast<std::ptrdiff_t>(offset + count * len));
}

// A tile of `records` (LAS 1.4, scale 1 mm) written by LasWriter, LAZ with
// chunks of `chunk_points` or LAS, with a VLR and an EVLR that must pass
// through, and header bounds `bounds` (default: the records' own).
void write_tile(const fs::path& p, std::uint8_t format, std::size_t extra, const Bytes& records, bool laz,
                std::uint32_t chunk_points, std::optional<std::array<double, 6>> bounds = std::nullopt,
                std::array<double, 3> offset = {0.0, 0.0, 0.0}) {
  LasHeader h;
  h.point_format = format;
  h.record_length = static_cast<std::uint16_t>(testing::base_size(format) + extra);
  h.global_encoding = 1;
  h.scale = {0.001, 0.001, 0.001};
  h.offset = offset;
  const std::size_t n = records.size() / h.record_length;
  std::array<double, 3> lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  testing::widen_record_bounds(records.data(), n, h.record_length, offset, lo, hi);
  if (bounds) lo = {(*bounds)[0], (*bounds)[1], (*bounds)[2]}, hi = {(*bounds)[3], (*bounds)[4], (*bounds)[5]};
  LasVlr vlr{"geoanchor-test", 7, "passes through", {1, 2, 3, 4, 5}, false, 0};
  LasVlr evlr{"geoanchor-test", 8, "passes through too", Bytes(300, 0xAB), true, 0};
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  LasWriter w(f, h, {vlr}, {evlr}, p.string(), {laz, chunk_points});
  w.write_records(records.data(), n);
  std::array<std::uint64_t, 15> by_return{};
  by_return[0] = n;
  w.finish(by_return, lo, hi);
}

class LazTile : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_.emplace("geoanchor_laz_tile");
    dir_ = folder_->path();
  }
  fs::path path(const std::string& name) const { return dir_ / name; }
  // Moves `in` through `chain` into `name`, stored as `out` on `threads`.
  TileApplyResult apply(const fs::path& in, const std::string& name, const PointChain& chain, TileApplyOptions o,
                        TileFormat out, unsigned threads) {
    o.las_output = out;
    o.threads = threads;
    // As apply's own output: made anew for the int32-overflow retry of a LAZ output.
    std::optional<std::ofstream> f;
    f.emplace(path(name), std::ios::binary | std::ios::trunc);
    o.restart_output = [&]() -> std::ostream& {
      f.reset();
      f.emplace(path(name), std::ios::binary | std::ios::trunc);
      return *f;
    };
    const auto r = apply_las_tile(in, *f, name, chain, o);
    f->close();
    return r;
  }
  std::optional<testing::TempFolder> folder_;
  fs::path dir_;
};

// issue 15 acceptance: apply on a LAZ tile gives the same point records as
// apply on the same tile as LAS, byte for byte; point 3: one tile's chunks
// on several threads give the same file as on one.
TEST_F(LazTile, Issue15_LazInOrOutGivesTheRecordsOfTheLasPathOnAnyNumberOfThreads) {
  const PointChain chain(kA, parse_transform_json(kHelmert, "T"), false, std::nullopt, kB);
  struct Case {
    std::uint8_t format;
    std::size_t extra;
  };
  // 130 001 points: units of 50 000 and a short last one; the LAZ input in
  // chunks of 30 000, which the units cut across.
  constexpr std::size_t kPoints = 130001;
  for (const Case c : {Case{3, 7}, Case{6, 0}, Case{7, 3}, Case{8, 0}}) {
    SCOPED_TRACE("point format " + std::to_string(c.format));
    const Bytes records = make_records(c.format, c.extra, kPoints, Content::realistic, 40 + c.format);
    write_tile(path("in.las"), c.format, c.extra, records, false, 0);
    write_tile(path("in.laz"), c.format, c.extra, records, true, 30000);
    const TileApplyOptions o{kA, kB, std::nullopt, "WKT", 1 << 16, {}};
    apply(path("in.las"), "ref.las", chain, o, TileFormat::las, 1);
    const Bytes ref_file = testing::slurp_bytes(path("ref.las"));
    const Bytes ref = stored_records(path("ref.las"), dir_);
    ASSERT_EQ(ref.size(), records.size());
    // Every byte of every record but X, Y, Z came through; X moved.
    const std::size_t len = records.size() / kPoints;
    std::size_t same_xyz = 0;
    for (std::size_t i = 0; i < kPoints; ++i) {
      ASSERT_EQ(std::memcmp(ref.data() + i * len + 12, records.data() + i * len + 12, len - 12), 0) << "record " << i;
      same_xyz += std::memcmp(ref.data() + i * len, records.data() + i * len, 12) == 0;
    }
    EXPECT_EQ(same_xyz, 0u);

    for (unsigned threads : {1u, 2u, 3u}) {
      SCOPED_TRACE(std::to_string(threads) + " threads");
      apply(path("in.las"), "las_las.las", chain, o, TileFormat::las, threads);
      apply(path("in.laz"), "laz_las.las", chain, o, TileFormat::las, threads);
      EXPECT_TRUE(testing::slurp_bytes(path("las_las.las")) == ref_file) << "LAS -> LAS";
      EXPECT_TRUE(testing::slurp_bytes(path("laz_las.las")) == ref_file) << "LAZ -> LAS: the same file as from LAS";
      const auto r = apply(path("in.laz"), "laz_laz" + std::to_string(threads) + ".laz", chain, o, TileFormat::laz, threads);
      apply(path("in.las"), "las_laz" + std::to_string(threads) + ".laz", chain, o, TileFormat::laz, threads);
      ASSERT_TRUE(r.laz);
      EXPECT_EQ(r.laz->chunk_size, kLazDefaultChunkPoints);
      EXPECT_TRUE(testing::slurp_bytes(path("las_laz" + std::to_string(threads) + ".laz")) ==
                  testing::slurp_bytes(path("laz_laz1.laz")))
          << "the same LAZ file from LAS and from LAZ, on any number of threads";
      EXPECT_TRUE(testing::slurp_bytes(path("laz_laz" + std::to_string(threads) + ".laz")) ==
                  testing::slurp_bytes(path("laz_laz1.laz")));
    }
    // laz-perf decodes the LAZ output to the LAS path's records; its header
    // and VLRs are the LAS output's.
    EXPECT_TRUE(SameRecords(stored_records(path("laz_laz2.laz"), dir_), ref, len));
    LasReader a(path("ref.las")), b(path("laz_laz2.laz"));
    EXPECT_EQ(b.header().point_count, kPoints);
    EXPECT_EQ(b.chunk_count(), 3u);
    EXPECT_EQ(b.header().min, a.header().min);
    EXPECT_EQ(b.header().max, a.header().max);
    EXPECT_EQ(b.header().offset, a.header().offset);
    ASSERT_EQ(b.vlrs().size(), a.vlrs().size());
    for (std::size_t i = 0; i < a.vlrs().size(); ++i) {
      EXPECT_EQ(b.vlrs()[i].user_id, a.vlrs()[i].user_id);
      EXPECT_EQ(b.vlrs()[i].record_id, a.vlrs()[i].record_id);
      EXPECT_TRUE(b.vlrs()[i].data == a.vlrs()[i].data);
      EXPECT_EQ(b.vlrs()[i].extended, a.vlrs()[i].extended);
    }
    EXPECT_TRUE(a.vlrs().back().data == Bytes(300, 0xAB)) << "the EVLR";
  }
}

// issue 15: a LAZ written by the LASzip library moves like its uncompressed twin.
TEST_F(LazTile, Issue15_LaszipWrittenSamplesMoveLikeTheirUncompressedTwins) {
  const PointChain chain(kA, parse_transform_json(kHelmert, "T"), false, std::nullopt, kB);
  for (const auto& [laz, las] : {std::pair{"point-color-time.las.laz", "point-color-time.las"},
                                 std::pair{"extrabytes.laz", "extrabytes.las"}}) {
    SCOPED_TRACE(laz);
    const TileApplyOptions o{kA, kB, std::nullopt, "WKT", 1 << 16, {}};
    apply(kData / las, "twin.las", chain, o, TileFormat::las, 1);
    apply(kData / laz, "sample.las", chain, o, TileFormat::las, 2);
    apply(kData / laz, "sample.laz", chain, o, TileFormat::laz, 2);
    const Bytes want = stored_records(path("twin.las"), dir_);
    const std::size_t len = LasReader(kData / las).header().record_length;
    ASSERT_FALSE(want.empty());
    EXPECT_TRUE(SameRecords(stored_records(path("sample.las"), dir_), want, len));
    EXPECT_TRUE(SameRecords(stored_records(path("sample.laz"), dir_), want, len)) << "through laz-perf";
  }
}

// issue 15 point 2: the tile's own coordinates (apply --crs X --to-crs X)
// keep every point record, LAS -> LAZ, LAZ -> LAS and LAZ -> LAZ.
TEST_F(LazTile, Issue15_TheTilesOwnCoordinatesKeepEveryRecordBetweenLasAndLaz) {
  const Bytes records = make_records(7, 5, 70000, Content::realistic, 3);
  write_tile(path("in.las"), 7, 5, records, false, 0);
  const PointChain none(kA, std::nullopt, false, std::nullopt, kA);
  TileApplyOptions o{kA, kA, std::nullopt, "WKT", 1 << 16, {}};
  o.keep_coordinates = true;
  const auto r = apply(path("in.las"), "a.laz", none, o, TileFormat::laz, 2);
  apply(path("a.laz"), "b.las", none, o, TileFormat::las, 2);
  apply(path("a.laz"), "c.laz", none, o, TileFormat::laz, 1);
  const std::size_t len = records.size() / 70000;
  EXPECT_TRUE(SameRecords(stored_records(path("a.laz"), dir_), records, len)) << "LAS -> LAZ";
  EXPECT_TRUE(SameRecords(stored_records(path("b.las"), dir_), records, len)) << "LAZ -> LAS";
  EXPECT_TRUE(SameRecords(stored_records(path("c.laz"), dir_), records, len)) << "LAZ -> LAZ";
  const LasReader input(path("in.las"));
  const LasHeader& h = input.header();
  EXPECT_EQ(r.scale, h.scale);
  EXPECT_EQ(r.offset, h.offset);
  EXPECT_EQ(LasReader(path("b.las")).header().min, h.min);
  EXPECT_EQ(LasReader(path("b.las")).header().max, h.max);
  // The same from a LASzip-written sample to LAS: its twin's records.
  apply(kData / "point-time-1.4.las.laz", "d.las", none, o, TileFormat::las, 1);
  EXPECT_TRUE(SameRecords(stored_records(path("d.las"), dir_), stored_records(kData / "point-time.las", dir_),
                          LasReader(kData / "point-time.las").header().record_length));
}

// issue 15 point 2: the int32-overflow retry (the header's bounds were
// wrong) cannot rewrite a LAZ stream in place; it writes the tile anew into
// the output restart_output gives, and the result is the LAS path's.
TEST_F(LazTile, Issue15_TheOverflowRetryWritesALazOutputAnewFromItsFirstByte) {
  // Points from 0 to 3000 km east, the farthest the last one, in the third
  // unit; the header claims a 1 m box, whose middle as the offset leaves
  // that point beyond int32 at 1 mm (after two units were written).
  Bytes records = make_records(6, 0, 120000, Content::realistic, 9);
  for (std::size_t i = 0; i < 120000; ++i) {
    const std::int32_t x = i == 0 ? -1500000000 : (i == 119999 ? 1500000000 : static_cast<std::int32_t>(i));
    std::memcpy(records.data() + i * 30, &x, 4);
  }
  const std::array<double, 6> wrong{0, 0, 0, 1, 1, 1};
  write_tile(path("in.las"), 6, 0, records, false, 0, wrong, {1500000.0, 0.0, 0.0});
  write_tile(path("in.laz"), 6, 0, records, true, 50000, wrong, {1500000.0, 0.0, 0.0});
  const PointChain chain(kA, std::nullopt, false, std::nullopt, kEcef);
  TileApplyOptions o{kA, kEcef, std::nullopt, "WKT", 1 << 16, {}};
  const auto las = apply(path("in.las"), "ref.las", chain, o, TileFormat::las, 1);
  for (const fs::path& in : {path("in.las"), path("in.laz")}) {
    for (unsigned threads : {1u, 3u}) {
      SCOPED_TRACE(in.filename().string() + ", " + std::to_string(threads) + " threads");
      std::ostringstream first;
      std::optional<std::ofstream> second;
      int restarts = 0;
      o.las_output = TileFormat::laz;
      o.threads = threads;
      o.restart_output = [&]() -> std::ostream& {
        ++restarts;
        second.emplace(path("out.laz"), std::ios::binary | std::ios::trunc);
        return *second;
      };
      const auto r = apply_las_tile(in, first, "out.laz", chain, o);
      second->close();
      EXPECT_EQ(restarts, 1);
      EXPECT_EQ(r.offset, las.offset) << "the offset from the true bounds, as the LAS path's";
      EXPECT_TRUE(first.str().size() > 375) << "the first attempt was written to the first stream, then abandoned";
      EXPECT_TRUE(SameRecords(stored_records(path("out.laz"), dir_), stored_records(path("ref.las"), dir_), 30));
    }
  }
  // Without restart_output a LAZ output cannot be retried.
  o.restart_output = {};
  std::ostringstream sink;
  EXPECT_THROW(apply_las_tile(path("in.laz"), sink, "x.laz", chain, o), std::logic_error);
}

// issue 15 point 3: however many threads move a tile, the error reported is
// that of the first bad point in the file.
TEST_F(LazTile, Issue15_TheFirstBadPointIsTheErrorWhateverTheThreads) {
  // Geodetic (X longitude, Y latitude at 1e-7 degrees); latitude 95 degrees
  // at points 60 002 and 110 002 has no ECEF position.
  Bytes records = make_records(6, 0, 130000, Content::realistic, 5);
  for (std::size_t i = 0; i < 130000; ++i) {
    const std::int32_t lon = 85000000 + static_cast<std::int32_t>(i % 1000), lat = (i == 60001 || i == 110001) ? 950000000 : 474000000;
    std::memcpy(records.data() + i * 30, &lon, 4);
    std::memcpy(records.data() + i * 30 + 4, &lat, 4);
  }
  LasHeader h;
  h.point_format = 6;
  h.record_length = 30;
  h.scale = {1e-7, 1e-7, 0.001};
  {
    std::ofstream f(path("geo.laz"), std::ios::binary | std::ios::trunc);
    LasWriter w(f, h, {}, {}, "geo.laz", {true, 20000});
    w.write_records(records.data(), 130000);
    w.finish({}, {8.5, 47.4, 0.0}, {8.51, 95.0, 600.0});
  }
  const ArrayFrame geodetic{CoordinateKind::geodetic, geodesy::Ellipsoid::grs80(), std::nullopt, std::nullopt};
  const PointChain chain(geodetic, std::nullopt, false, std::nullopt, kEcef);
  const LasReader reader(path("geo.laz"));
  for (unsigned threads : {1u, 2u, 3u}) {
    SCOPED_TRACE(std::to_string(threads) + " threads");
    std::ostringstream out;
    TileApplyOptions o{geodetic, kEcef, std::nullopt, "WKT", 1 << 16, {}};
    o.las_output = TileFormat::laz;
    o.threads = threads;
    try {
      apply_las_tile(path("geo.laz"), out, "out.laz", chain, o);
      ADD_FAILURE() << "accepted a latitude of 95 degrees";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), "E_TRANSFORM");
      // Point 60 002 is in chunk 3 (of 20 000 points each).
      const std::string where = path("geo.laz").string() + ": point 60002 (chunk 3 at byte " +
                                std::to_string(reader.chunk_offset(3)) + ") has no finite position";
      EXPECT_NE(std::string(e.what()).find(where), std::string::npos) << e.what();
    }
  }
}

// issue 15 point 3: a tile whose CRS PROJ moves gives the same file and the
// same record of PROJ's operation on one thread and on three (the CRS
// stages run unit after unit, in order).
TEST_F(LazTile, Issue15_ACrsTileOnThreadsGivesTheFileAndOperationRecordOfOneThread) {
  // Lambert-93 around Paris, 1 mm.
  Bytes records = make_records(6, 0, 120000, Content::realistic, 21);
  for (std::size_t i = 0; i < 120000; ++i) {
    std::int32_t q[2];
    std::memcpy(q, records.data() + i * 30, 8);
    q[0] += 651000000;  // X near 652 000 m; Y near 6 862 000 m through the header's offset
    // A few points 740 km north of Paris, outside Lambert-93's area of use,
    // in the second and third units: the warning names the first of them.
    if (i == 70001 || i == 70002 || i == 100003) q[1] += 740000000;
    std::memcpy(records.data() + i * 30, q, 8);
  }
  LasHeader h;
  h.point_format = 6;
  h.record_length = 30;
  h.offset = {0.0, 6860000.0, 0.0};
  {
    std::ofstream f(path("l93.laz"), std::ios::binary | std::ios::trunc);
    LasWriter w(f, h, {}, {}, "l93.laz", {true, 50000});
    w.write_records(records.data(), 120000);
    w.finish({}, {651000, 6861000, 400}, {653000, 7603000, 600});
  }
  const Crs src = Crs::parse("EPSG:2154", "test").promoted_to_3d("test");
  const PointChain identity(ArrayFrame{}, std::nullopt, false, std::nullopt, ArrayFrame{});
  // Into RGF93 v1 geographic (a conversion): the points outside Lambert-93's
  // area are warned, the first named. Into LAEA Europe (through ETRS89,
  // whose operation holds in France only): refused at the first.
  for (const char* to : {"EPSG:4171", "EPSG:3035"}) {
    SCOPED_TRACE(to);
    const Crs dst = Crs::parse(to, "test").promoted_to_3d("test");
    std::vector<std::string> records_json, warnings, errors;
    for (unsigned threads : {1u, 3u}) {
      CrsOperation op(src, dst, "test");
      TileApplyOptions o{ArrayFrame{}, ArrayFrame{}, 0.01, "WKT", 1 << 16, {}};  // 1e-8 degrees: 6.6 degrees fit int32
      o.crs_before = &op;
      o.chain_used = false;
      o.file_in = tile_crs_axes(src);
      o.file_out = tile_crs_axes(dst);
      try {
        apply(path("l93.laz"), "out" + std::to_string(threads) + ".laz", identity, o, TileFormat::laz, threads);
      } catch (const Error& e) {
        errors.push_back(e.what());
      }
      records_json.push_back(operation_record_json(op));
      std::string w;
      for (const auto& x : op.warnings()) w += x + "\n";
      warnings.push_back(w);
    }
    EXPECT_EQ(warnings[0], warnings[1]);
    EXPECT_EQ(records_json[0], records_json[1]);
    if (std::string(to) == "EPSG:4171") {
      EXPECT_TRUE(errors.empty()) << errors.front();
      EXPECT_TRUE(testing::slurp_bytes(path("out1.laz")) == testing::slurp_bytes(path("out3.laz")));
      EXPECT_NE(warnings[0].find("point 70002 (chunk 1 at byte"), std::string::npos) << warnings[0];
      EXPECT_NE(records_json[0].find("120000"), std::string::npos) << "every point counted once: " << records_json[0];
    } else {
      ASSERT_EQ(errors.size(), 2u);
      EXPECT_EQ(errors[0], errors[1]);
      EXPECT_NE(errors[0].find("point 70002 (chunk 1 at byte"), std::string::npos) << errors[0];
    }
  }
}

}  // namespace
}  // namespace geoanchor::io
