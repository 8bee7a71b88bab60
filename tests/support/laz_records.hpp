#pragma once
// Point records with realistic content for every supported point format,
// for the LAZ tests (tests/las/laz_test.cpp, the LAZ tiles of apply's tests)
// and the apply benchmark's LAZ tile. No GoogleTest here: bench/ uses it.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

namespace geoanchor::testing {

using Bytes = std::vector<std::uint8_t>;

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

// `lo` and `hi` widened to the bounds of `n` records of `record_length`
// bytes whose first 12 bytes are X, Y, Z (int32 at scale 0.001, plus
// `offset`): the bounds a LAS header states.
inline void widen_record_bounds(const std::uint8_t* records, std::size_t n, std::size_t record_length,
                                const std::array<double, 3>& offset, std::array<double, 3>& lo, std::array<double, 3>& hi) {
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t k = 0; k < 3; ++k) {
      std::int32_t q;
      std::memcpy(&q, records + i * record_length + 4 * k, 4);
      lo[k] = std::min(lo[k], q * 0.001 + offset[k]);
      hi[k] = std::max(hi[k], q * 0.001 + offset[k]);
    }
  }
}

}  // namespace geoanchor::testing
