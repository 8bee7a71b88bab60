#pragma once
// What las.cpp (LAS) and las_laz.cpp (LAZ) share: little-endian fields
// (laz.cpp's too), positioned reads, the LAS error message, the record
// headers' sizes.

#include <unistd.h>

#include <bit>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "geoanchor/base/error.hpp"

namespace geoanchor::io::las_internal {

static_assert(std::endian::native == std::endian::little, "LAS is little-endian; this code reads it with memcpy");

inline constexpr std::size_t kVlrHeaderSize = 54;
inline constexpr std::size_t kEvlrHeaderSize = 60;
inline constexpr std::uint16_t kHeaderSize12 = 227;
inline constexpr std::uint16_t kHeaderSize13 = 235;
inline constexpr std::uint16_t kHeaderSize14 = 375;

template <class T>
T get(const std::uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

template <class T>
void put(std::vector<std::uint8_t>& b, std::size_t at, T v) {
  std::memcpy(b.data() + at, &v, sizeof v);
}

inline Error malformed(const std::filesystem::path& p, std::uint64_t offset, const std::string& what) {
  return Error(ErrorKind::input, "E_LAS", p.string() + ": byte " + std::to_string(offset) + ": " + what);
}

// Reads exactly n bytes at `offset`; false at end of file. Thread-safe (pread).
inline bool read_at(int fd, std::uint64_t offset, std::uint8_t* out, std::size_t n) {
  std::size_t done = 0;
  while (done < n) {
    const ssize_t r = ::pread(fd, out + done, n - done, static_cast<off_t>(offset + done));
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) return false;
    done += static_cast<std::size_t>(r);
  }
  return true;
}

}  // namespace geoanchor::io::las_internal
