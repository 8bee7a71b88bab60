#pragma once
// What the LAZ tests share: records with realistic content for every
// supported point format (tests/io/laz_test.cpp's generated tiles, the LAZ
// tiles of apply's tests), the independent decoder laz-perf (npm, run by
// tests/las-verify/laz-decode.mjs), and a byte-for-byte comparison of
// records that says where they first differ.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace geoanchor::testing {

namespace laz_fs = std::filesystem;
using Bytes = std::vector<std::uint8_t>;

inline Bytes slurp_bytes(const laz_fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// "0 of N records differ" or where the first difference is.
inline ::testing::AssertionResult SameRecords(const Bytes& got, const Bytes& want, std::size_t len) {
  if (got.size() != want.size()) {
    return ::testing::AssertionFailure() << got.size() / len << " records, expected " << want.size() / len;
  }
  std::size_t differ = 0, first = 0;
  for (std::size_t i = 0; i < got.size() / len; ++i) {
    if (std::memcmp(got.data() + i * len, want.data() + i * len, len) != 0 && differ++ == 0) first = i;
  }
  if (differ == 0) return ::testing::AssertionSuccess() << "all " << got.size() / len << " records equal";
  std::size_t byte = 0;
  while (got[first * len + byte] == want[first * len + byte]) ++byte;
  return ::testing::AssertionFailure() << differ << " of " << got.size() / len << " records differ; the first is record "
                                       << first << " at byte " << byte;
}

// laz-perf's decoding of a LAZ file: its records and what it (and copc) report.
struct LazPerfRead {
  nlohmann::json report;
  Bytes records;
};
inline std::optional<LazPerfRead> laz_perf(const laz_fs::path& laz, const laz_fs::path& scratch) {
  const laz_fs::path kVerify = laz_fs::path(GEOANCHOR_SOURCE_DIR) / "tests" / "las-verify";
  if (!laz_fs::exists(kVerify / "node_modules" / "laz-perf") || !laz_fs::exists(kVerify / "node_modules" / "copc")) {
    ADD_FAILURE() << "the independent LAZ decoder is not installed: run npm ci --prefix " << kVerify.string()
                  << " (scripts/test.sh does)";
    return std::nullopt;
  }
  const laz_fs::path out = scratch / (laz.filename().string() + ".laz-perf.bin");
  const std::string cmd = "node '" + (kVerify / "laz-decode.mjs").string() + "' '" + laz.string() + "' '" + out.string() + "' 2>&1";
  std::string text;
  if (FILE* p = ::popen(cmd.c_str(), "r")) {
    char buf[4096];
    while (const std::size_t n = std::fread(buf, 1, sizeof buf, p)) text.append(buf, n);
    const int status = ::pclose(p);
    if (status != 0) {
      ADD_FAILURE() << "laz-perf could not read " << laz << ": " << text;
      return std::nullopt;
    }
  }
  LazPerfRead r;
  r.report = nlohmann::json::parse(text);
  r.records = slurp_bytes(out);
  laz_fs::remove(out);
  return r;
}


enum class Content { realistic, still, random };
inline const char* content_name(Content c) {
  return c == Content::realistic ? "realistic" : (c == Content::still ? "still" : "random");
}

inline std::size_t base_size(std::uint8_t format) {
  constexpr std::size_t sizes[] = {20, 28, 26, 34, 0, 0, 30, 36, 38};
  return sizes[format];
}

// `n` records of `format` with `extra` bytes. Realistic: scan lines with
// smoothly varying X/Y/Z, pulses of 1..n returns sharing a GPS time, two
// interleaved flight lines (GPS time jumps between them), classes by
// return, smooth RGB and NIR (sometimes grey), scanner channels switching
// every few dozen pulses (formats 6-8), extra bytes as a float and a counter.
// Still: the same, but every attribute except X/Y/Z constant. Random: every
// byte.
inline Bytes make_records(std::uint8_t format, std::size_t extra, std::size_t n, Content content, unsigned seed) {
  const std::size_t len = base_size(format) + extra;
  Bytes out(n * len);
  std::mt19937_64 rng(seed);
  if (content == Content::random) {
    for (auto& b : out) b = static_cast<std::uint8_t>(rng() & 0xFF);
    return out;
  }
  std::normal_distribution<double> noise(0.0, 1.0);
  std::uniform_int_distribution<int> returns(1, format >= 6 ? 9 : 5);
  const bool still = content == Content::still;
  std::size_t i = 0, pulse = 0;
  double t[2] = {311000.25, 318500.75};
  while (i < n) {
    const int line = static_cast<int>((pulse / 250) % 2);
    t[line] += 1.0e-5 * (1.0 + 0.01 * noise(rng));
    const int nr = still ? 1 : std::min(returns(rng), 1 + static_cast<int>(pulse % 4));
    const double xs = 1000.0 + 0.35 * static_cast<double>(pulse % 400) + 0.02 * noise(rng);
    const double ys = 2000.0 + 0.9 * static_cast<double>(pulse / 400) + 150.0 * line + 0.02 * noise(rng);
    const double ground = 480.0 + 12.0 * std::sin(xs / 40.0) + 4.0 * std::cos(ys / 25.0);
    const int channel = static_cast<int>((pulse / 37) % 3);
    const int direction = static_cast<int>((pulse / 100) % 2);
    for (int r = 1; r <= nr && i < n; ++r, ++i) {
      std::uint8_t* p = out.data() + i * len;
      const double z = ground + (nr - r) * 3.1 + 0.01 * noise(rng);
      const std::int32_t q[3] = {static_cast<std::int32_t>(std::lround(xs * 1000.0)),
                                 static_cast<std::int32_t>(std::lround(ys * 1000.0)),
                                 static_cast<std::int32_t>(std::lround(z * 1000.0))};
      std::memcpy(p, q, 12);
      const auto intensity =
          static_cast<std::uint16_t>(still ? 700 : 300 + 40 * r + static_cast<int>(80.0 * std::sin(xs / 7.0)));
      std::memcpy(p + 12, &intensity, 2);
      const std::uint8_t cls = still ? 2 : (r == nr ? 2 : (pulse % 11 == 0 ? 6 : 5));
      const std::uint16_t source = static_cast<std::uint16_t>(still ? 7 : 100 + line);
      const double gps = t[line];
      const bool edge = !still && pulse % 100 == 99;
      std::size_t at;
      if (format < 6) {
        const int rr = std::min(r, 7), nn = std::min(nr, 7);
        p[14] = static_cast<std::uint8_t>(rr | (nn << 3) | ((still ? 0 : direction) << 6) | (edge ? 0x80 : 0));
        p[15] = cls;
        p[16] = static_cast<std::uint8_t>(static_cast<std::int8_t>(still ? 0 : static_cast<int>(pulse % 41) - 20));
        p[17] = static_cast<std::uint8_t>(still ? 0 : r * 10);
        std::memcpy(p + 18, &source, 2);
        at = 20;
        if (format == 1 || format == 3) {
          std::memcpy(p + at, &gps, 8);
          at += 8;
        }
      } else {
        p[14] = static_cast<std::uint8_t>(r | (nr << 4));
        p[15] = static_cast<std::uint8_t>((still ? 0 : (pulse % 50 == 0 ? 1 : 0)) | ((still ? 0 : channel) << 4) |
                                          ((still ? 0 : direction) << 6) | (edge ? 0x80 : 0));
        p[16] = cls;
        p[17] = static_cast<std::uint8_t>(still ? 0 : r * 10);
        const auto angle = static_cast<std::int16_t>(still ? 0 : (static_cast<int>(pulse % 41) - 20) * 167);
        std::memcpy(p + 18, &angle, 2);
        std::memcpy(p + 20, &source, 2);
        std::memcpy(p + 22, &gps, 8);
        at = 30;
      }
      if (format == 2 || format == 3 || format >= 7) {
        std::uint16_t rgb[4];
        const bool grey = pulse % 17 == 0;
        const int base = static_cast<int>(120.0 + 60.0 * std::sin(xs / 30.0));
        rgb[0] = static_cast<std::uint16_t>(still ? 0x4040 : base * 256);
        rgb[1] = static_cast<std::uint16_t>(still ? 0x5050 : (grey ? rgb[0] : (base + 20 + r) * 256));
        rgb[2] = static_cast<std::uint16_t>(still ? 0x6060 : (grey ? rgb[0] : (base / 2 + 3 * r)));
        rgb[3] = static_cast<std::uint16_t>(still ? 0x7070 : 20000 + 50 * r + base);
        const std::size_t colours = format == 8 ? 8 : 6;
        std::memcpy(p + at, rgb, colours);
        at += colours;
      }
      if (extra > 0) {
        const auto amplitude = static_cast<float>(still ? 1.0 : 10.0 + r + 0.1 * noise(rng));
        std::uint8_t e[32] = {};
        std::memcpy(e, &amplitude, 4);
        e[4] = static_cast<std::uint8_t>(still ? 9 : i & 0xFF);
        for (std::size_t k = 5; k < extra && k < sizeof e; ++k) e[k] = static_cast<std::uint8_t>(still ? k : (k * static_cast<std::size_t>(r)) & 0xFF);
        std::memcpy(p + at, e, std::min(extra, sizeof e));
      }
    }
    ++pulse;
  }
  return out;
}

}  // namespace geoanchor::testing
