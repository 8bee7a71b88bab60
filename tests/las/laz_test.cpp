// LAZ: geoanchor's LASzip codec (io/laz.hpp, LasReader, LasWriter) against
// LAZ files written by the LASzip library and by PDAL (tests/data/laz, see
// its SOURCES.md), against the independent decoder laz-perf (npm, run by
// tests/las-verify/laz-decode.mjs), on generated and random records of every
// supported point format, and on each malformed-file case. Everything is
// compared byte for byte: no tolerance.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <random>
#include <sstream>
#include <thread>
#include <tuple>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/las/las.hpp"
#include "geoanchor/las/laz.hpp"
#include "laz_support.hpp"
#include "temp_folder.hpp"

namespace geoanchor::io {
namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;
using nlohmann::json;

const fs::path kData = GEOANCHOR_LAZ_DATA_DIR;
using testing::base_size;
using testing::Content;
using testing::content_name;
using testing::laz_perf;
using testing::LazPerfRead;
using testing::make_records;
using testing::SameRecords;

Bytes slurp(const fs::path& p) { return testing::slurp_bytes(p); }
void write_file(const fs::path& p, const Bytes& b) {
  std::ofstream(p, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(b.data()),
                                                             static_cast<std::streamsize>(b.size()));
}
template <class T>
T get(const Bytes& b, std::size_t at) {
  T v;
  std::memcpy(&v, b.data() + at, sizeof v);
  return v;
}
template <class T>
void put(Bytes& b, std::size_t at, T v) {
  std::memcpy(b.data() + at, &v, sizeof v);
}

// Every record through read_records, in batches of an odd size that cuts
// across chunks.
Bytes records_of(LasReader& r) {
  Bytes all, batch;
  r.rewind();
  while (r.read_records(batch, 777) != 0) all.insert(all.end(), batch.begin(), batch.end());
  return all;
}
// Every record through decode_chunk.
Bytes chunk_records_of(const LasReader& r) {
  Bytes all, chunk;
  for (std::size_t i = 0; i < r.chunk_count(); ++i) {
    r.decode_chunk(i, chunk);
    EXPECT_EQ(chunk.size(), r.chunk_points(i) * r.header().record_length);
    all.insert(all.end(), chunk.begin(), chunk.end());
  }
  return all;
}

class LazTest : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_.emplace("geoanchor_laz");
    dir_ = folder_->path();
  }
  fs::path path(const std::string& name) const { return dir_ / name; }
  std::optional<testing::TempFolder> folder_;
  fs::path dir_;
};

// ---------------------------------------------------------------------------
// Files written by the LASzip library: their records are their twins'.

struct Twin {
  const char* laz;
  const char* las;
};
constexpr Twin kTwins[] = {
    {"point10.las.laz", "point10.las"},           {"point-time.las.laz", "point-time.las"},
    {"point-color.las.laz", "point-color.las"},   {"point-color-time.las.laz", "point-color-time.las"},
    {"point-time-1.4.las.laz", "point-time.las"}, {"1815.laz", "1815.las"},
    {"extrabytes.laz", "extrabytes.las"},         {"no-points-1.3.laz", "no-points-1.3.las"},
};

TEST_F(LazTest, LaszipFilesDecodeToTheRecordsOfTheirUncompressedTwins) {
  for (const auto& t : kTwins) {
    SCOPED_TRACE(t.laz);
    LasReader laz(kData / t.laz), las(kData / t.las);
    EXPECT_TRUE(laz.compressed());
    EXPECT_FALSE(las.compressed());
    const LasHeader &a = laz.header(), &b = las.header();
    EXPECT_EQ(a.point_format, b.point_format);
    EXPECT_EQ(a.record_length, b.record_length);
    EXPECT_EQ(a.point_count, b.point_count);
    EXPECT_EQ(a.scale, b.scale);
    EXPECT_EQ(a.offset, b.offset);
    // (The pairs' header bounds differ in the last digit: written by different programs.)
    for (const auto& v : laz.vlrs()) EXPECT_NE(v.user_id, kLazVlrUserId) << "the laszip VLR is kept apart";
    const Bytes want = records_of(las);
    const Bytes got = records_of(laz);
    EXPECT_TRUE(SameRecords(got, want, a.record_length));
    EXPECT_TRUE(SameRecords(chunk_records_of(laz), want, a.record_length));
    std::printf("[ laz      ] %-26s %5llu points compared with %s, every byte\n", t.laz,
                static_cast<unsigned long long>(b.point_count), t.las);
  }
}

TEST_F(LazTest, CopcFilesDecodeToWhatLazPerfDecodes) {
  for (const char* name : {"autzen_clip_native.copc.laz", "1.2-with-color.copc.laz"}) {
    SCOPED_TRACE(name);
    LasReader r(kData / name);
    ASSERT_TRUE(r.compressed());
    EXPECT_TRUE(r.laz()->variable_chunks());
    EXPECT_EQ(r.header().point_format, 7);
    const Bytes ours = records_of(r);
    EXPECT_TRUE(SameRecords(chunk_records_of(r), ours, r.header().record_length));
    const auto theirs = laz_perf(kData / name, dir_);
    ASSERT_TRUE(theirs);
    EXPECT_EQ(theirs->report["count"], r.header().point_count);
    EXPECT_TRUE(SameRecords(ours, theirs->records, r.header().record_length));
    std::printf("[ laz      ] %-28s %5llu points in %zu chunks compared with laz-perf, every byte\n", name,
                static_cast<unsigned long long>(r.header().point_count), r.chunk_count());
  }
}

// 1.2-with-color.copc.laz holds 1.2-with-color.las's points converted by
// PDAL to format 7, in COPC's order and with another offset: the same
// points, field by field, as sets ordered by GPS time and position.
TEST_F(LazTest, CopcFileHoldsThePointsOfItsFormat3Source) {
  LasReader copc(kData / "1.2-with-color.copc.laz"), las(kData / "1.2-with-color.las");
  ASSERT_EQ(las.header().point_format, 3);
  ASSERT_EQ(copc.header().point_format, 7);
  ASSERT_EQ(copc.header().point_count, las.header().point_count);
  ASSERT_EQ(copc.header().scale, las.header().scale);
  // Integer shift between the two offsets (both on the 0.01 m grid).
  std::array<std::int64_t, 3> shift{};
  for (std::size_t k = 0; k < 3; ++k) {
    const double steps = (copc.header().offset[k] - las.header().offset[k]) / las.header().scale[k];
    shift[k] = std::llround(steps);
    ASSERT_EQ(static_cast<double>(shift[k]), std::nearbyint(steps));
  }
  using Fields = std::array<std::int64_t, 17>;
  auto collect = [&](LasReader& r, bool format7) {
    const Bytes rec = records_of(r);
    const std::size_t len = r.header().record_length;
    std::vector<Fields> out;
    for (std::size_t i = 0; i < rec.size() / len; ++i) {
      const std::uint8_t* p = rec.data() + i * len;
      Fields f{};
      for (std::size_t k = 0; k < 3; ++k) {
        std::int32_t q;
        std::memcpy(&q, p + 4 * k, 4);
        f[k] = q + (format7 ? shift[k] : 0);
      }
      std::uint16_t u16;
      std::memcpy(&u16, p + 12, 2);
      f[3] = u16;  // intensity
      double gps;
      std::uint16_t rgb[3];
      if (format7) {
        f[4] = p[14] & 15;                 // return number
        f[5] = p[14] >> 4;                 // number of returns
        f[6] = (p[15] >> 6) & 1;           // scan direction
        f[7] = p[15] >> 7;                 // edge of flight line
        f[8] = p[16];                      // classification
        f[9] = p[15] & 7;                  // synthetic, key-point, withheld
        std::int16_t angle;
        std::memcpy(&angle, p + 18, 2);
        f[10] = angle;                     // 0.006° units
        f[11] = p[17];                     // user data
        std::memcpy(&u16, p + 20, 2);
        f[12] = u16;                       // point source
        std::memcpy(&gps, p + 22, 8);
        std::memcpy(rgb, p + 30, 6);
      } else {
        f[4] = p[14] & 7;
        f[5] = (p[14] >> 3) & 7;
        f[6] = (p[14] >> 6) & 1;
        f[7] = p[14] >> 7;
        f[8] = p[15] & 31;
        f[9] = p[15] >> 5;
        f[10] = std::llround(static_cast<std::int8_t>(p[16]) / 0.006);  // scan angle rank in degrees
        f[11] = p[17];
        std::memcpy(&u16, p + 18, 2);
        f[12] = u16;
        std::memcpy(&gps, p + 20, 8);
        std::memcpy(rgb, p + 28, 6);
      }
      std::int64_t gps_bits;
      std::memcpy(&gps_bits, &gps, 8);
      f[13] = gps_bits;
      for (std::size_t k = 0; k < 3; ++k) f[14 + k] = rgb[k];
      out.push_back(f);
    }
    // Ordered by GPS time, then X, Y, Z: unique in this file.
    std::sort(out.begin(), out.end(), [](const Fields& a, const Fields& b) {
      return std::tie(a[13], a[0], a[1], a[2]) < std::tie(b[13], b[0], b[1], b[2]);
    });
    return out;
  };
  const auto a = collect(copc, true), b = collect(las, false);
  ASSERT_EQ(a.size(), b.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i] != b[i] && differ++ < 3) ADD_FAILURE() << "point " << i << " (in GPS time order) differs";
  }
  EXPECT_EQ(differ, 0u);
  std::printf("[ laz      ] 1.2-with-color: %zu points of the COPC file equal the LAS file's, 17 fields each\n", a.size());
}

// Compressing the twins gives LASzip's chunks: the coder is bit-exact.
TEST_F(LazTest, CompressingTheTwinsGivesLaszipsSizes) {
  constexpr double kSizeRatioLimit = 0.01;  // issue 15 acceptance: within 1 % of LASzip
  for (const auto& t : kTwins) {
    SCOPED_TRACE(t.laz);
    LasReader in(kData / t.las);
    const fs::path out = path("ours.laz");
    {
      std::ofstream f(out, std::ios::binary | std::ios::trunc);
      std::vector<LasVlr> vlrs;
      for (const auto& v : in.vlrs()) vlrs.push_back(v);
      LasWriter w(f, in.header(), vlrs, {}, out.string(), {true, kLazDefaultChunkPoints});
      Bytes batch;
      while (const std::size_t n = in.read_records(batch, 10000)) w.write_records(batch.data(), n);
      w.finish(in.header().points_by_return, in.header().min, in.header().max);
    }
    // The chunks (from the 8-byte table offset to the table), then the
    // chunk table (LASzip's files carry 32 more bytes after it, which no
    // reader uses).
    const Bytes a = slurp(out), b = slurp(kData / t.laz);
    const std::size_t oa = get<std::uint32_t>(a, 96), ob = get<std::uint32_t>(b, 96);
    const auto ta = static_cast<std::size_t>(get<std::uint64_t>(a, oa)), tb = static_cast<std::size_t>(get<std::uint64_t>(b, ob));
    const std::size_t ours = ta - oa - 8, laszip = tb - ob - 8;
    const double ratio = laszip > 0 ? static_cast<double>(ours) / static_cast<double>(laszip) - 1.0 : 0.0;
    std::printf("[ laz      ] %-26s chunks: geoanchor %6zu bytes, LASzip %6zu bytes (%+.4f %%)\n", t.laz, ours, laszip,
                100.0 * ratio);
    EXPECT_LE(std::abs(ratio), kSizeRatioLimit);
    EXPECT_EQ(ours, laszip) << "a bit-exact coder gives LASzip's bytes";
    EXPECT_TRUE(std::equal(a.begin() + static_cast<std::ptrdiff_t>(oa + 8), a.end(), b.begin() + static_cast<std::ptrdiff_t>(ob + 8)))
        << "the chunks and the chunk table, byte for byte";
  }
}

// ---------------------------------------------------------------------------
// Generated tiles, written by LasWriter, read back and by laz-perf.

const char* kWkt =
    "PROJCRS[\"ETRS89 / UTM zone 32N\",BASEGEOGCRS[\"ETRS89\",DATUM[\"European Terrestrial Reference System "
    "1989\",ELLIPSOID[\"GRS 1980\",6378137,298.257222101]]],CONVERSION[\"UTM zone 32N\",METHOD[\"Transverse "
    "Mercator\"],PARAMETER[\"Latitude of natural origin\",0],PARAMETER[\"Longitude of natural origin\",9],"
    "PARAMETER[\"Scale factor at natural origin\",0.9996],PARAMETER[\"False easting\",500000],PARAMETER[\"False "
    "northing\",0]],CS[Cartesian,2],AXIS[\"easting\",east],AXIS[\"northing\",north],LENGTHUNIT[\"metre\",1],"
    "ID[\"EPSG\",25832]]";

struct Written {
  LasHeader header;
  std::array<double, 3> min{}, max{};
};

// Writes `records` as a LAZ (or LAS) file with a WKT VLR; returns the header
// given and the bounds passed to finish().
Written write_tile(const fs::path& p, std::uint8_t format, std::size_t extra, const Bytes& records, bool laz,
                   std::uint32_t chunk_points, std::size_t batch = 4321) {
  Written w;
  LasHeader& h = w.header;
  h.point_format = format;
  h.record_length = static_cast<std::uint16_t>(base_size(format) + extra);
  h.global_encoding = LasHeader::kWktBit | 1u;
  h.scale = {0.001, 0.001, 0.001};
  h.offset = {0.0, 0.0, 0.0};
  const std::size_t n = records.size() / h.record_length;
  std::array<std::uint64_t, 15> by_return{};
  w.min = {INFINITY, INFINITY, INFINITY};
  w.max = {-INFINITY, -INFINITY, -INFINITY};
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* rec = records.data() + i * h.record_length;
    for (std::size_t k = 0; k < 3; ++k) {
      std::int32_t q;
      std::memcpy(&q, rec + 4 * k, 4);
      const double v = q * h.scale[k] + h.offset[k];
      w.min[k] = std::min(w.min[k], v);
      w.max[k] = std::max(w.max[k], v);
    }
    const unsigned r = format < 6 ? (rec[14] & 7u) : (rec[14] & 15u);
    if (r >= 1 && r <= 15) ++by_return[r - 1];
  }
  if (n == 0) w.min = w.max = {0, 0, 0};
  LasVlr wkt;
  wkt.user_id = "LASF_Projection";
  wkt.record_id = kLasWktRecordId;
  wkt.description = "WKT";
  wkt.data.assign(kWkt, kWkt + std::strlen(kWkt) + 1);
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  LasWriter writer(f, h, {wkt}, {}, p.string(), {laz, chunk_points});
  for (std::size_t i = 0; i < n; i += batch) {
    writer.write_records(records.data() + i * h.record_length, std::min(batch, n - i));
  }
  writer.finish(by_return, w.min, w.max);
  return w;
}

struct RoundTripCase {
  std::uint8_t format;
  std::size_t extra;
  Content content;
};

void PrintTo(const RoundTripCase& c, std::ostream* os) {
  *os << "format " << int{c.format} << ", " << c.extra << " extra bytes, " << content_name(c.content);
}

class LazRoundTrip : public LazTest, public ::testing::WithParamInterface<RoundTripCase> {};

TEST_P(LazRoundTrip, DecodesToTheRecordsGivenHereAndInLazPerf) {
  const auto [format, extra, content] = GetParam();
  constexpr std::size_t kPoints = 12345;       // four chunks, the last one short
  constexpr std::uint32_t kChunkPoints = 4000;
  const Bytes records = make_records(format, extra, kPoints, content, static_cast<unsigned>(1000u * format + extra));
  const fs::path p = path("tile.laz");
  const Written w = write_tile(p, format, extra, records, true, kChunkPoints);

  LasReader r(p);
  ASSERT_TRUE(r.compressed());
  EXPECT_EQ(r.header().point_format, format);
  EXPECT_EQ(r.header().point_count, kPoints);
  EXPECT_EQ(r.chunk_count(), 4u);
  EXPECT_EQ(r.chunk_points(0), kChunkPoints);
  ASSERT_TRUE(r.wkt().has_value());
  EXPECT_EQ(*r.wkt(), kWkt);
  const std::size_t len = w.header.record_length;
  EXPECT_TRUE(SameRecords(records_of(r), records, len));
  EXPECT_TRUE(SameRecords(chunk_records_of(r), records, len));

  const auto theirs = laz_perf(p, dir_);
  ASSERT_TRUE(theirs);
  EXPECT_EQ(theirs->report["count"], kPoints);
  EXPECT_EQ(theirs->report["format"], format);
  EXPECT_EQ(theirs->report["length"], len);
  EXPECT_TRUE(SameRecords(theirs->records, records, len)) << "laz-perf";
  // The second reader (copc's header, VLR and point view).
  const json& c = theirs->report["copc"];
  EXPECT_EQ(c["pointCount"], kPoints);
  EXPECT_EQ(c["wkt"], kWkt);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(c["headerMin"][k].get<double>(), w.min[k]);
    EXPECT_EQ(c["headerMax"][k].get<double>(), w.max[k]);
    EXPECT_EQ(c["pointsMin"][k].get<double>(), w.min[k]);
    EXPECT_EQ(c["pointsMax"][k].get<double>(), w.max[k]);
  }
  std::printf("[ laz      ] format %d, %zu extra bytes, %-9s: %zu points, %llu bytes of LAZ (%.1f %% of LAS); "
              "geoanchor and laz-perf decode every byte\n",
              format, extra, content_name(content), kPoints, static_cast<unsigned long long>(fs::file_size(p)),
              100.0 * static_cast<double>(fs::file_size(p)) / static_cast<double>(w.header.offset_to_points + records.size()));
}

std::vector<RoundTripCase> round_trip_cases() {
  std::vector<RoundTripCase> cases;
  for (const std::uint8_t f : std::vector<std::uint8_t>{0, 1, 2, 3, 6, 7, 8}) {
    for (const std::size_t extra : {std::size_t{0}, std::size_t{7}}) {
      for (const Content c : {Content::realistic, Content::still, Content::random}) cases.push_back({f, extra, c});
    }
  }
  return cases;
}
INSTANTIATE_TEST_SUITE_P(Formats, LazRoundTrip, ::testing::ValuesIn(round_trip_cases()),
                         [](const ::testing::TestParamInfo<RoundTripCase>& i) {
                           return "format" + std::to_string(i.param.format) + "_extra" + std::to_string(i.param.extra) +
                                  "_" + content_name(i.param.content);
                         });

// Chunks of one point, and files of one and of no point.
TEST_F(LazTest, TinyChunksAndFilesRoundTrip) {
  for (const std::uint8_t format : std::vector<std::uint8_t>{1, 7}) {
    for (const std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{3}}) {
      for (const std::uint32_t chunk : {1u, 2u, 50000u}) {
        SCOPED_TRACE("format " + std::to_string(format) + ", " + std::to_string(n) + " points, chunks of " + std::to_string(chunk));
        const Bytes records = make_records(format, 2, n, Content::realistic, 7);
        const fs::path p = path("tiny.laz");
        write_tile(p, format, 2, records, true, chunk);
        LasReader r(p);
        EXPECT_EQ(r.chunk_count(), (n + chunk - 1) / chunk);
        EXPECT_TRUE(SameRecords(records_of(r), records, base_size(format) + 2));
        const auto theirs = laz_perf(p, dir_);
        ASSERT_TRUE(theirs);
        EXPECT_TRUE(SameRecords(theirs->records, records, base_size(format) + 2)) << "laz-perf";
      }
    }
  }
}

// Chunks compressed on other threads (LazChunkEncoder) and handed to
// write_chunk give the file write_records gives; chunks decoded on several
// threads give the records read_records gives.
TEST_F(LazTest, ChunksEncodeAndDecodeOnThreads) {
  for (const std::uint8_t format : std::vector<std::uint8_t>{3, 8}) {
    SCOPED_TRACE("format " + std::to_string(format));
    constexpr std::uint32_t kChunkPoints = 3000;
    const Bytes records = make_records(format, 4, 14000, Content::realistic, 99);
    const std::size_t len = base_size(format) + 4;
    const std::size_t n = records.size() / len;
    const fs::path serial = path("serial.laz"), threaded = path("threaded.laz");
    const Written w = write_tile(serial, format, 4, records, true, kChunkPoints);

    const std::size_t chunks = (n + kChunkPoints - 1) / kChunkPoints;
    std::vector<Bytes> coded(chunks);
    LasVlr wkt;
    wkt.user_id = "LASF_Projection";
    wkt.record_id = kLasWktRecordId;
    wkt.description = "WKT";
    wkt.data.assign(kWkt, kWkt + std::strlen(kWkt) + 1);
    {
      std::ofstream f(threaded, std::ios::binary | std::ios::trunc);
      LasWriter writer(f, w.header, {wkt}, {}, threaded.string(), {true, kChunkPoints});
      std::vector<std::thread> workers;
      for (unsigned t = 0; t < 2; ++t) {
        workers.emplace_back([&, t] {
          LazChunkEncoder enc(*writer.laz());
          for (std::size_t i = t; i < chunks; i += 2) {
            const std::size_t first = i * kChunkPoints, count = std::min<std::size_t>(kChunkPoints, n - first);
            enc.encode(records.data() + first * len, count, coded[i]);
          }
        });
      }
      for (auto& t : workers) t.join();
      for (std::size_t i = 0; i < chunks; ++i) {
        writer.write_chunk(coded[i], std::min<std::size_t>(kChunkPoints, n - i * kChunkPoints));
      }
      std::array<std::uint64_t, 15> by_return{};
      LasReader s(serial);
      by_return = s.header().points_by_return;
      writer.finish(by_return, w.min, w.max);
    }
    EXPECT_EQ(slurp(threaded), slurp(serial));

    LasReader r(serial);
    std::vector<Bytes> decoded(r.chunk_count());
    std::vector<std::thread> workers;
    for (unsigned t = 0; t < 2; ++t) {
      workers.emplace_back([&, t] {
        for (std::size_t i = t; i < r.chunk_count(); i += 2) r.decode_chunk(i, decoded[i]);
      });
    }
    for (auto& t : workers) t.join();
    Bytes joined;
    for (const auto& d : decoded) joined.insert(joined.end(), d.begin(), d.end());
    EXPECT_TRUE(SameRecords(joined, records, len));
  }
}

// LAS -> LAZ -> LAS keeps every record and VLR; the laszip VLR is never
// carried into the LAS.
TEST_F(LazTest, LasToLazToLasKeepsEveryByteOfThePoints) {
  for (const auto& t : kTwins) {
    SCOPED_TRACE(t.las);
    LasReader in(kData / t.las);
    auto copy = [&](LasReader& from, const fs::path& to, bool laz) {
      std::ofstream f(to, std::ios::binary | std::ios::trunc);
      std::vector<LasVlr> vlrs, evlrs;
      for (const auto& v : from.vlrs()) (v.extended ? evlrs : vlrs).push_back(v);
      LasWriter w(f, from.header(), vlrs, evlrs, to.string(), {laz, 500});
      Bytes batch;
      from.rewind();
      while (const std::size_t n = from.read_records(batch, 333)) w.write_records(batch.data(), n);
      w.finish(from.header().points_by_return, from.header().min, from.header().max);
    };
    copy(in, path("a.laz"), true);
    LasReader mid(path("a.laz"));
    copy(mid, path("b.las"), false);
    LasReader out(path("b.las"));
    EXPECT_FALSE(out.compressed());
    EXPECT_TRUE(SameRecords(records_of(out), records_of(in), in.header().record_length));
    ASSERT_EQ(out.vlrs().size(), in.vlrs().size());
    for (std::size_t i = 0; i < in.vlrs().size(); ++i) {
      EXPECT_EQ(out.vlrs()[i].user_id, in.vlrs()[i].user_id);
      EXPECT_EQ(out.vlrs()[i].data, in.vlrs()[i].data);
    }
    const Bytes b = slurp(path("b.las"));
    EXPECT_EQ(std::search(b.begin(), b.end(), std::begin("laszip encoded"), std::end("laszip encoded") - 1), b.end());
  }
}

// A writer that stopped before the chunk table leaves the table offset
// pointing at itself: LASzip then walks fixed-size chunks; so does geoanchor.
// Variable-size chunks cannot be found that way: an error. A table offset of
// -1 means "at the end of the file".
TEST_F(LazTest, MissingChunkTableIsWalkedForFixedChunksOnly) {
  const Bytes records = make_records(3, 0, 9000, Content::realistic, 5);
  write_tile(path("t.laz"), 3, 0, records, true, 2500);
  Bytes b = slurp(path("t.laz"));
  const auto at = get<std::uint32_t>(b, 96);
  put<std::int64_t>(b, at, at);
  write_file(path("crashed.laz"), b);
  LasReader r(path("crashed.laz"));
  EXPECT_EQ(r.chunk_count(), 4u);
  EXPECT_TRUE(SameRecords(records_of(r), records, 34));

  // Written to a stream that could not seek back: offset -1, the table's
  // offset in the file's last 8 bytes.
  Bytes s = slurp(path("t.laz"));
  const auto table = get<std::uint64_t>(s, at);
  put<std::int64_t>(s, at, -1);
  s.resize(s.size() + 8);
  put<std::uint64_t>(s, s.size() - 8, table);
  write_file(path("streamed.laz"), s);
  LasReader streamed(path("streamed.laz"));
  EXPECT_TRUE(SameRecords(records_of(streamed), records, 34));

  Bytes c = slurp(kData / "1.2-with-color.copc.laz");
  const auto cat = get<std::uint32_t>(c, 96);
  put<std::int64_t>(c, cat, cat);
  write_file(path("crashed.copc.laz"), c);
  try {
    LasReader bad(path("crashed.copc.laz"));
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_LAZ_CHUNK_TABLE");
    EXPECT_NE(std::string(e.what()).find("crashed.copc.laz: byte " + std::to_string(cat) + ": no chunk table"), std::string::npos)
        << e.what();
  }
}

// ---------------------------------------------------------------------------
// Malformed files: each refused with its code, the file, the byte offset
// and (for a chunk) its index; a conversion through an atomic output leaves
// nothing behind.

// Reads every record and decodes every chunk of `p`, then converts it to LAS
// through an atomic output; returns the error (or fails).
std::optional<Error> failure_of(const fs::path& p, const fs::path& out) {
  try {
    LasReader r(p);
    AtomicOutputFile f(out, Overwrite::refuse);
    std::vector<LasVlr> vlrs, evlrs;
    for (const auto& v : r.vlrs()) (v.extended ? evlrs : vlrs).push_back(v);
    LasWriter w(f.stream(), r.header(), vlrs, evlrs, out.string());
    Bytes batch;
    while (const std::size_t n = r.read_records(batch, 1000)) w.write_records(batch.data(), n);
    w.finish(r.header().points_by_return, r.header().min, r.header().max);
    f.commit();
  } catch (const Error& e) {
    return e;
  }
  return std::nullopt;
}

struct Malformed {
  const char* name;
  std::string code;
  std::vector<std::string> message;  // substrings, in any order
};

class LazMalformed : public LazTest {
 protected:
  // A two-chunk format-3 file (chunks of 1000 points) and its bytes.
  void SetUp() override {
    LazTest::SetUp();
    records_ = make_records(3, 0, 2000, Content::realistic, 11);
    write_tile(path("good.laz"), 3, 0, records_, true, 1000);
    good_ = slurp(path("good.laz"));
    offset_ = get<std::uint32_t>(good_, 96);
    table_ = get<std::uint64_t>(good_, offset_);
    LasReader r(path("good.laz"));
    chunk1_ = r.chunk_offset(1);
  }
  void expect(const std::string& name, const Bytes& bytes, const std::string& code, std::vector<std::string> parts) {
    SCOPED_TRACE(name);
    const fs::path in = path(name), out = path(name + ".converted.las");
    write_file(in, bytes);
    const auto e = failure_of(in, out);
    ASSERT_TRUE(e) << "no error";
    EXPECT_EQ(e->code(), code) << e->what();
    parts.push_back(in.string() + ": byte ");
    for (const auto& part : parts) EXPECT_NE(std::string(e->what()).find(part), std::string::npos) << e->what() << "\nlacks: " << part;
    EXPECT_FALSE(fs::exists(out)) << "a partial output";
    for (const auto& entry : fs::directory_iterator(dir_)) {
      EXPECT_FALSE(is_temporary_name(entry.path().filename().string())) << entry.path();
    }
    fs::remove(in);
  }
  Bytes records_, good_;
  std::uint32_t offset_ = 0;
  std::uint64_t table_ = 0, chunk1_ = 0;
};

TEST_F(LazMalformed, TruncatedChunk) {
  // The second chunk cut to half its bytes, the chunk table saying so.
  const LasHeader h = LasReader(path("good.laz")).header();
  LazChunkEncoder enc(LazVlr::for_format(3, 34, 1000));
  Bytes c0, c1;
  enc.encode(records_.data(), 1000, c0);
  enc.encode(records_.data() + 1000 * 34, 1000, c1);
  c1.resize(c1.size() / 2);
  {
    std::ofstream f(path("cut.laz"), std::ios::binary | std::ios::trunc);
    LasWriter w(f, h, {}, {}, "cut.laz", {true, 1000});
    w.write_chunk(c0, 1000);
    w.write_chunk(c1, 1000);
    w.finish(h.points_by_return, h.min, h.max);
  }
  LasReader r(path("cut.laz"));
  expect("truncated_chunk.laz", slurp(path("cut.laz")), "E_LAZ_CHUNK",
         {"byte " + std::to_string(r.chunk_offset(1)) + ": chunk 1 of 2 (1000 points, " + std::to_string(c1.size()) +
              " bytes) ends before its points do"});
}

TEST_F(LazMalformed, FileCutShort) {
  Bytes b = good_;
  b.resize(static_cast<std::size_t>(chunk1_ + 100));
  expect("cut_short.laz", b, "E_LAZ_CHUNK_TABLE",
         {"byte " + std::to_string(offset_) + ": the chunk table offset " + std::to_string(table_) + " is outside the point data",
          "past the end of the file"});
}

TEST_F(LazMalformed, ChunkTableOffsetPastTheEnd) {
  Bytes b = good_;
  put<std::uint64_t>(b, offset_, b.size() + 1000);
  expect("offset_past_end.laz", b, "E_LAZ_CHUNK_TABLE",
         {"byte " + std::to_string(offset_) + ": the chunk table offset " + std::to_string(b.size() + 1000), "past the end of the file"});
}

TEST_F(LazMalformed, ChunkTableCountWrong) {
  Bytes b = good_;
  put<std::uint32_t>(b, static_cast<std::size_t>(table_ + 4), 3);
  expect("count_wrong.laz", b, "E_LAZ_CHUNK_TABLE",
         {"byte " + std::to_string(table_ + 4) + ": the chunk table lists 3 chunks, but 2000 points in chunks of 1000 make 2"});
}

TEST_F(LazMalformed, ChunkSizesDoNotAddUp) {
  // 16 stray bytes between the last chunk and the table.
  Bytes b = good_;
  b.insert(b.begin() + static_cast<std::ptrdiff_t>(table_), 16, 0);
  put<std::uint64_t>(b, offset_, table_ + 16);
  expect("sizes_wrong.laz", b, "E_LAZ_CHUNK_TABLE",
         {"byte " + std::to_string(offset_ + 8) + ": the chunk sizes add up to " + std::to_string(table_ - offset_ - 8) +
          " bytes, but the chunk table starts " + std::to_string(table_ + 16 - offset_ - 8)});
}

TEST_F(LazMalformed, ChunkTableCutShort) {
  Bytes b = good_;
  b.resize(static_cast<std::size_t>(table_ + 9));
  expect("table_short.laz", b, "E_LAZ_CHUNK_TABLE", {"byte " + std::to_string(table_) + ": the chunk table of 2 chunks is cut short"});
}

TEST_F(LazMalformed, ChunkTableVersion) {
  Bytes b = good_;
  put<std::uint32_t>(b, static_cast<std::size_t>(table_), 1);
  expect("table_version.laz", b, "E_LAZ_UNSUPPORTED", {"byte " + std::to_string(table_) + ": chunk table version 1"});
}

TEST_F(LazMalformed, PointCountsDisagreeWithTheHeader) {
  // Fixed chunks: one point more needs a third chunk.
  Bytes b = good_;
  put<std::uint32_t>(b, 107, 2001);
  put<std::uint64_t>(b, 247, 2001);
  expect("count_fixed.laz", b, "E_LAZ_CHUNK_TABLE", {"lists 2 chunks, but 2001 points in chunks of 1000 make 3"});
  // Variable chunks (COPC): the table's counts against the header's.
  Bytes c = slurp(kData / "1.2-with-color.copc.laz");
  const auto table = get<std::uint64_t>(c, get<std::uint32_t>(c, 96));
  put<std::uint32_t>(c, 107, 1066);
  put<std::uint64_t>(c, 247, 1066);
  expect("count_variable.laz", c, "E_LAZ_CHUNK_TABLE",
         {"byte " + std::to_string(table) + ": the chunk table counts 1065 points, the header 1066"});
}

TEST_F(LazMalformed, ChunkTooLargeToDecodeWhole) {
  // Chunks of 2^23 points and a header to match: two chunks, the first too large.
  Bytes b = good_;
  std::size_t at = get<std::uint16_t>(b, 94);
  while (std::string(reinterpret_cast<const char*>(b.data() + at + 2)) != kLazVlrUserId) at += 54u + get<std::uint16_t>(b, at + 20);
  put<std::uint32_t>(b, at + 54 + 12, 1u << 23);
  put<std::uint32_t>(b, 107, (1u << 23) + 5);
  put<std::uint64_t>(b, 247, (1u << 23) + 5);
  expect("huge_chunk.laz", b, "E_LAZ_UNSUPPORTED",
         {"byte " + std::to_string(offset_ + 8) + ": chunk 0 of 2 holds 8388608 points; chunks of more than 4194304 points"});
}

// The laszip VLR of point10.las.laz: where it is and its payload.
struct VlrAt {
  std::size_t payload = 0;
  std::size_t header = 0;
};
VlrAt laszip_vlr(const Bytes& b) {
  std::size_t at = get<std::uint16_t>(b, 94);
  for (std::uint32_t i = 0; i < get<std::uint32_t>(b, 100); ++i) {
    if (std::string(reinterpret_cast<const char*>(b.data() + at + 2)) == kLazVlrUserId) return {at + 54, at};
    at += 54u + get<std::uint16_t>(b, at + 20);
  }
  return {};
}

TEST_F(LazMalformed, UnsupportedCompressorCoderItemAndVersion) {
  const Bytes base = slurp(kData / "point-time.las.laz");
  const VlrAt v = laszip_vlr(base);
  ASSERT_NE(v.payload, 0u);
  const std::string at = "byte " + std::to_string(v.header) + ": ";
  Bytes b = base;
  put<std::uint16_t>(b, v.payload + 34 + 4, 1);  // POINT10 version 1
  expect("item_v1.laz", b, "E_LAZ_UNSUPPORTED", {at, "item 1 is POINT10 version 1, which is not supported"});
  b = base;
  put<std::uint16_t>(b, v.payload + 34 + 6 + 4, 3);  // GPSTIME11 version 3
  expect("item_v3.laz", b, "E_LAZ_UNSUPPORTED", {at, "item 2 is GPSTIME11 version 3"});
  b = base;
  put<std::uint16_t>(b, v.payload + 2, 1);
  expect("coder.laz", b, "E_LAZ_UNSUPPORTED", {at, "coder 1 is not supported"});
  b = base;
  put<std::uint16_t>(b, v.payload, 1);
  expect("compressor.laz", b, "E_LAZ_UNSUPPORTED", {at, "compressor 1 (pointwise (LASzip 1.x, not chunked))"});
  b = base;
  put<std::uint16_t>(b, v.payload, 3);
  expect("compressor3.laz", b, "E_LAZ_UNSUPPORTED", {at, "compressor 3 (layered chunked) is not supported for point format 1"});
  b = base;
  put<std::uint16_t>(b, v.payload + 34 + 6, 9);  // GPSTIME11 -> WAVEPACKET13
  expect("wavepacket_item.laz", b, "E_LAZ_UNSUPPORTED", {at, "WAVEPACKET13 (8 bytes, version 2) (waveform packets) is not supported"});
}

TEST_F(LazMalformed, WaveformPointFormats) {
  Bytes b = slurp(kData / "point-time.las.laz");
  b[104] = 0x84;
  expect("format4.laz", b, "E_LAZ_UNSUPPORTED", {"byte 104: LAZ point data record format 4 (waveform packets, WAVEPACKET13 items)"});
  // LAS 1.4 format 9.
  Bytes c = good_;
  c[104] = 0x89;
  expect("format9.laz", c, "E_LAZ_UNSUPPORTED", {"byte 104: LAZ point data record format 9 (waveform packets, WAVEPACKET14 items)"});
  // And the writer refuses to compress them.
  LasHeader h;
  h.point_format = 5;
  h.record_length = 63;
  std::ostringstream sink;
  try {
    LasWriter w(sink, h, {}, {}, "x.laz", {true, 1000});
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_LAZ_UNSUPPORTED");
    EXPECT_NE(std::string(e.what()).find("point format 5 carries waveform packets (WAVEPACKET13)"), std::string::npos) << e.what();
  }
}

TEST_F(LazMalformed, CorruptOrMissingVlr) {
  const Bytes base = slurp(kData / "point-time.las.laz");
  const VlrAt v = laszip_vlr(base);
  Bytes b = base;
  put<std::uint16_t>(b, v.payload + 32, 3);  // three items in a payload of two
  expect("vlr_items.laz", b, "E_LAZ_VLR",
         {"byte " + std::to_string(v.header) + ": laszip VLR: lists 3 items, which take 52 bytes, but holds 46"});
  b = base;
  b[v.header + 2] = 'X';  // no longer "laszip encoded"
  expect("vlr_missing.laz", b, "E_LAZ_VLR", {"byte 104: point data record format byte 129 marks compressed (LAZ) points, but there is no laszip VLR"});
  b = base;
  b[104] = 0x80;  // format 0 with 28-byte records: POINT10 + BYTE(8) expected
  expect("vlr_format.laz", b, "E_LAZ_VLR",
         {"byte " + std::to_string(v.header) + ": laszip VLR: items POINT10 (20 bytes, version 2), GPSTIME11 (8 bytes, version 2)",
          "do not describe point format 0 with 28-byte records; expected POINT10 (20 bytes, version 2), BYTE (8 bytes, version 2)"});
}

// Corrupted chunk bytes: decoding ends in an error or in some records,
// never in a crash, an endless loop or a read outside the chunk (ASan and
// UBSan runs of this suite check the last).
TEST_F(LazTest, CorruptChunksNeverReadOutOfBounds) {
  for (const std::uint8_t format : std::vector<std::uint8_t>{3, 7}) {
    const Bytes records = make_records(format, 3, 600, Content::realistic, 3);
    const fs::path p = path("c.laz");
    write_tile(p, format, 3, records, true, 600);
    const LasReader r(p);
    const std::size_t len = r.header().record_length;
    Bytes chunk = slurp(p);
    const auto start = static_cast<std::ptrdiff_t>(r.chunk_offset(0));
    const auto bytes = static_cast<std::ptrdiff_t>(get<std::uint64_t>(chunk, get<std::uint32_t>(chunk, 96))) - start;
    chunk = Bytes(chunk.begin() + start, chunk.begin() + start + bytes);
    LazChunkDecoder dec(*r.laz());
    Bytes out(600 * len);
    std::mt19937 rng(format);
    std::size_t errors = 0, decoded = 0;
    for (int trial = 0; trial < 300; ++trial) {
      Bytes bad = chunk;
      const int flips = 1 + trial % 8;
      for (int k = 0; k < flips; ++k) bad[rng() % bad.size()] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
      if (trial % 3 == 0) bad.resize(rng() % bad.size());
      // An exact-size copy, so that ASan sees a read past its end.
      const auto exact = std::make_unique<std::uint8_t[]>(bad.size());
      std::copy(bad.begin(), bad.end(), exact.get());
      try {
        dec.decode(exact.get(), bad.size(), 600, out.data());
        ++decoded;
      } catch (const Error& e) {
        EXPECT_EQ(e.code(), "E_LAZ_CHUNK");
        ++errors;
      }
    }
    EXPECT_EQ(errors + decoded, 300u);
    std::printf("[ laz      ] format %d: 300 corrupted chunks: %zu refused, %zu decoded to some records\n", format, errors, decoded);
  }
}

// Issue 40 point 8: a header that counts fewer points than the chunks hold
// (1 100 of 1 200 here, chunks of 500) is refused naming both counts, for a
// pointwise-compressed format (3: bytes left in the last chunk) and a
// layered one (7: the chunk's own count); nothing is read.
TEST_F(LazTest, Issue40_AHeaderCountingFewerPointsThanTheChunksIsRefused) {
  for (const std::uint8_t format : std::vector<std::uint8_t>{3, 7}) {
    SCOPED_TRACE(static_cast<int>(format));
    const Bytes records = make_records(format, 0, 1200, Content::realistic, 5);
    const fs::path p = path("short.laz");
    write_tile(p, format, 0, records, true, 500);
    Bytes file = slurp(p);
    // LAS 1.4: the 64-bit count at byte 247, the legacy 32-bit one at 107 (0 for formats 6-10).
    put<std::uint64_t>(file, 247, 1100);
    if (format < 6) put<std::uint32_t>(file, 107, 1100);
    {
      std::ofstream f(p, std::ios::binary | std::ios::trunc);
      f.write(reinterpret_cast<const char*>(file.data()), static_cast<std::streamsize>(file.size()));
    }
    try {
      LasReader r(p);
      records_of(r);
      ADD_FAILURE() << "read 1100 of the 1200 points without a word";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), "E_LAZ_POINT_COUNT") << e.what();
      EXPECT_NE(std::string(e.what()).find("1100 points"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("chunk 2 of 3"), std::string::npos) << e.what();
      // Both counts: the last chunk's 200 points (100 by the header) and the chunks' 1200.
      EXPECT_NE(std::string(e.what()).find("holds 200 points (the chunks hold 1200 points)"), std::string::npos) << e.what();
    }
  }
}

// The same without a chunk table (a writer that stopped before it): the
// chunks are walked by the header's count, and a chunk after the last one
// it implies is refused, not dropped.
TEST_F(LazTest, Issue40_AHeaderCountingFewerPointsIsRefusedWithoutAChunkTable) {
  const Bytes records = make_records(3, 0, 9000, Content::realistic, 5);
  write_tile(path("t.laz"), 3, 0, records, true, 2500);
  Bytes b = slurp(path("t.laz"));
  const auto at = get<std::uint32_t>(b, 96);
  put<std::int64_t>(b, at, at);  // no chunk table
  put<std::uint32_t>(b, 107, 5000);
  put<std::uint64_t>(b, 247, 5000);
  write_file(path("short.laz"), b);
  try {
    LasReader r(path("short.laz"));
    records_of(r);
    ADD_FAILURE() << "read 5000 of the 9000 points without a word";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), "E_LAZ_POINT_COUNT") << e.what();
    EXPECT_NE(std::string(e.what()).find("the 5000 points the header counts end here, but another chunk follows"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace geoanchor::io
