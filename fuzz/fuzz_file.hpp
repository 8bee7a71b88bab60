#pragma once
// The fuzz input as a temporary file (the readers take paths); nothing of
// geoanchor's, so that the LAS and LAZ targets link the codec alone.

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace geoanchor::fuzz {

// The input written to a file of this process's own, replaced each call.
inline std::filesystem::path as_file(const std::uint8_t* data, std::size_t size, const char* extension) {
  const auto p = std::filesystem::temp_directory_path() /
                 ("geoanchor_fuzz_" + std::to_string(::getpid()) + extension);
  std::ofstream(p, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data),
                                                             static_cast<std::streamsize>(size));
  return p;
}

}  // namespace geoanchor::fuzz
