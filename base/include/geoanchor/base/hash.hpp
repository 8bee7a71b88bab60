#pragma once
// Content hashes for provenance records.

#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <tuple>

namespace geoanchor {

// Lower-case hex SHA-256 of `bytes`.
std::string sha256_hex(std::string_view bytes);
// Of a file's contents; throws geoanchor::Error (io) if unreadable.
std::string sha256_file_hex(const std::filesystem::path& path);

// The SHA-256 of files asked for again and again in one run (a grid file
// for every tile of a batch): each file is read once for as long as its
// size and modification time stay the same. Safe to share between threads.
class FileHashCache {
 public:
  // As sha256_file_hex.
  std::string sha256_hex(const std::filesystem::path& path);

 private:
  using Key = std::tuple<std::string, std::uintmax_t, std::filesystem::file_time_type>;
  std::mutex mutex_;
  std::map<Key, std::string> hashes_;
};

}  // namespace geoanchor
