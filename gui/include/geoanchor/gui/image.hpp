#pragma once
// An RGB picture as the shells read it back from OpenGL: rows top to bottom,
// 3 bytes per pixel. PNG in and out through stb (libstb-dev).

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace geoanchor::gui {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  friend bool operator==(const Rgb&, const Rgb&) = default;
};

struct RgbImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  // width × height × 3, top row first

  Rgb at(int x, int y) const {
    const auto i = 3 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x));
    return {rgb[i], rgb[i + 1], rgb[i + 2]};
  }
  // From OpenGL's bottom-up RGBA rows.
  static RgbImage from_gl_rgba(int width, int height, const std::vector<std::uint8_t>& bottom_up_rgba);
};

// The PNG file's bytes (a report keeps many pages in memory this way: a
// 1600×1000 view is about 0.2 MB as PNG, 4.8 MB as pixels). Throws
// geoanchor::Error (io) naming `name` when encoding fails.
std::string encode_png(const RgbImage& image, const std::string& name);
// Writes the PNG atomically (temporary file, then rename). Throws
// geoanchor::Error (io) naming the path.
void write_png(const RgbImage& image, const std::filesystem::path& path, bool overwrite);
// Throws geoanchor::Error (input) naming the path when it is not a PNG.
RgbImage read_png(const std::filesystem::path& path);

}  // namespace geoanchor::gui
