#pragma once
// Content hashes for provenance records.

#include <filesystem>
#include <string>
#include <string_view>

namespace geoanchor::io {

// Lower-case hex SHA-256 of `bytes`.
std::string sha256_hex(std::string_view bytes);
// Of a file's contents; throws geoanchor::Error (io) if unreadable.
std::string sha256_file_hex(const std::filesystem::path& path);

}  // namespace geoanchor::io
