// LAZ files that are malformed or cut short, moved from laz_test.cpp: each
// refused with its message, never read out of bounds.

#include "laz_fixture.hpp"

namespace geoanchor::io {
namespace {

using namespace laz_fixture;

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
