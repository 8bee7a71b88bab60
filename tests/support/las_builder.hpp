#pragma once
// LAS files for tests, assembled byte by byte from the ASPRS LAS 1.4 R15
// tables (header field offsets, VLR and EVLR headers, point record sizes)
// without any of geoanchor's LAS code, so that the reader is tested against
// an independent construction. Every non-coordinate byte of a record gets a
// pattern value, so that a test can check they pass through unchanged.

#include <algorithm>
#include <array>
#include <optional>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace geoanchor::testing {

struct LasRecordSpec {
  std::string user_id;
  std::uint16_t record_id = 0;
  std::string description;
  std::vector<std::uint8_t> data;
};

struct LasBuild {
  std::uint8_t minor = 4;         // 2, 3 or 4
  std::uint8_t point_format = 6;  // written as given (tests use invalid ones too)
  std::uint16_t extra_bytes = 0;  // appended to each record
  std::uint16_t global_encoding = 1;
  std::array<double, 3> scale{0.001, 0.001, 0.001};
  std::array<double, 3> offset{0, 0, 0};
  std::vector<std::array<std::int32_t, 3>> xyz;
  std::vector<LasRecordSpec> vlrs, evlrs;
  // Overrides for broken files.
  std::optional<std::uint64_t> stated_count;
  std::optional<std::uint32_t> stated_vlr_count;
  std::optional<std::uint16_t> stated_record_length;
  std::optional<std::array<double, 6>> stated_bounds;  // min x, y, z, max x, y, z
};

// The record size of the standard formats (Table 7 ff.): 0..10.
inline std::uint16_t las_format_size(std::uint8_t f) {
  static const std::uint16_t sizes[] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
  return f <= 10 ? sizes[f] : 30;
}

// The pattern byte at byte k of record i (bytes 0..11 are X, Y, Z).
inline std::uint8_t las_pattern(std::size_t i, std::size_t k) { return static_cast<std::uint8_t>((i * 131 + k * 7 + 3) & 0xff); }

template <class T>
void las_put(std::vector<std::uint8_t>& b, std::size_t at, T v) {
  std::array<std::uint8_t, sizeof(T)> bytes;
  std::memcpy(bytes.data(), &v, sizeof v);
  for (std::size_t j = 0; j < sizeof(T); ++j) b.at(at + j) = bytes[j];
}

inline std::vector<std::uint8_t> build_las(const LasBuild& s) {
  const std::uint16_t header_size = s.minor == 2 ? 227 : (s.minor == 3 ? 235 : 375);
  const std::uint16_t length = s.stated_record_length.value_or(
      static_cast<std::uint16_t>(las_format_size(s.point_format & 0x3f) + s.extra_bytes));
  std::vector<std::uint8_t> h(header_size, 0);
  std::memcpy(h.data(), "LASF", 4);
  las_put(h, 6, s.global_encoding);
  h[24] = 1;
  h[25] = s.minor;
  std::memcpy(&h[26], "geoanchor tests", 15);
  std::memcpy(&h[58], "las_builder.hpp", 15);
  las_put(h, 90, std::uint16_t{100});
  las_put(h, 92, std::uint16_t{2026});
  las_put(h, 94, header_size);
  std::size_t vlr_bytes = 0;
  for (const auto& v : s.vlrs) vlr_bytes += 54 + v.data.size();
  const auto offset_to_points = static_cast<std::uint32_t>(header_size + vlr_bytes);
  las_put(h, 96, offset_to_points);
  las_put(h, 100, s.stated_vlr_count.value_or(static_cast<std::uint32_t>(s.vlrs.size())));
  h[104] = s.point_format;
  las_put(h, 105, length);
  const std::uint64_t count = s.stated_count.value_or(s.xyz.size());
  const bool legacy = (s.point_format & 0x3f) < 6;
  las_put(h, 107, static_cast<std::uint32_t>(legacy ? count : 0));
  if (legacy) las_put(h, 111, static_cast<std::uint32_t>(count));  // all first returns
  std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (const auto& p : s.xyz) {
    for (std::size_t k = 0; k < 3; ++k) {
      const double v = p[k] * s.scale[k] + s.offset[k];
      lo[k] = std::min(lo[k], v);
      hi[k] = std::max(hi[k], v);
    }
  }
  if (s.stated_bounds) {
    for (std::size_t k = 0; k < 3; ++k) lo[k] = (*s.stated_bounds)[k], hi[k] = (*s.stated_bounds)[k + 3];
  }
  for (std::size_t k = 0; k < 3; ++k) {
    las_put(h, 131 + 8 * k, s.scale[k]);
    las_put(h, 155 + 8 * k, s.offset[k]);
    las_put(h, 179 + 16 * k, s.xyz.empty() ? 0.0 : hi[k]);
    las_put(h, 187 + 16 * k, s.xyz.empty() ? 0.0 : lo[k]);
  }
  const std::uint64_t points_end = offset_to_points + s.xyz.size() * length;
  if (s.minor == 4) {
    las_put(h, 235, s.evlrs.empty() ? std::uint64_t{0} : points_end);
    las_put(h, 243, static_cast<std::uint32_t>(s.evlrs.size()));
    las_put(h, 247, count);
    las_put(h, 255, count);
  }
  std::vector<std::uint8_t> out = h;
  for (const auto& v : s.vlrs) {
    std::vector<std::uint8_t> vh(54, 0);
    std::memcpy(&vh[2], v.user_id.data(), std::min<std::size_t>(16, v.user_id.size()));
    las_put(vh, 18, v.record_id);
    las_put(vh, 20, static_cast<std::uint16_t>(v.data.size()));
    std::memcpy(&vh[22], v.description.data(), std::min<std::size_t>(32, v.description.size()));
    out.insert(out.end(), vh.begin(), vh.end());
    out.insert(out.end(), v.data.begin(), v.data.end());
  }
  for (std::size_t i = 0; i < s.xyz.size(); ++i) {
    std::vector<std::uint8_t> r(length, 0);
    for (std::size_t k = 12; k < length; ++k) r[k] = las_pattern(i, k);
    for (std::size_t k = 0; k < 3; ++k) las_put(r, 4 * k, s.xyz[i][k]);
    out.insert(out.end(), r.begin(), r.end());
  }
  for (const auto& v : s.evlrs) {
    std::vector<std::uint8_t> eh(60, 0);
    std::memcpy(&eh[2], v.user_id.data(), std::min<std::size_t>(16, v.user_id.size()));
    las_put(eh, 18, v.record_id);
    las_put(eh, 20, static_cast<std::uint64_t>(v.data.size()));
    std::memcpy(&eh[28], v.description.data(), std::min<std::size_t>(32, v.description.size()));
    out.insert(out.end(), eh.begin(), eh.end());
    out.insert(out.end(), v.data.begin(), v.data.end());
  }
  return out;
}

inline void write_bytes(const std::filesystem::path& p, const std::vector<std::uint8_t>& b) {
  std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}

}  // namespace geoanchor::testing
