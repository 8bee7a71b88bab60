// LAZ: geoanchor's LASzip codec (las/laz.hpp, LasReader, LasWriter) against
// LAZ files written by the LASzip library and by PDAL (tests/data/laz, see
// its SOURCES.md), against the independent decoder laz-perf (npm, run by
// tests/las-verify/laz-decode.mjs), on generated and random records of every
// supported point format, and on each malformed-file case. Everything is
// compared byte for byte: no tolerance.

#include "laz_fixture.hpp"

namespace geoanchor::io {
namespace {

using namespace laz_fixture;

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

}  // namespace
}  // namespace geoanchor::io
