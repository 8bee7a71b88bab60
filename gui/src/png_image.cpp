#include <stb_image.h>
#include <stb_image_write.h>

#include <fstream>

#include "geoanchor/base/error.hpp"
#include "geoanchor/gui/image.hpp"
#include "geoanchor/io/atomic_file.hpp"

namespace geoanchor::gui {

RgbImage RgbImage::from_gl_rgba(int width, int height, const std::vector<std::uint8_t>& bottom_up_rgba) {
  RgbImage out{width, height, std::vector<std::uint8_t>(3 * static_cast<std::size_t>(width) * static_cast<std::size_t>(height))};
  const auto w = static_cast<std::size_t>(width);
  for (std::size_t y = 0; y < static_cast<std::size_t>(height); ++y) {
    const std::uint8_t* src = bottom_up_rgba.data() + 4 * w * (static_cast<std::size_t>(height) - 1 - y);
    std::uint8_t* dst = out.rgb.data() + 3 * w * y;
    for (std::size_t x = 0; x < w; ++x) {
      dst[3 * x] = src[4 * x];
      dst[3 * x + 1] = src[4 * x + 1];
      dst[3 * x + 2] = src[4 * x + 2];
    }
  }
  return out;
}

namespace {
void append_bytes(void* context, void* data, int size) {
  auto* out = static_cast<std::string*>(context);
  out->append(static_cast<const char*>(data), static_cast<std::size_t>(size));
}
}  // namespace

std::string encode_png(const RgbImage& image, const std::string& name) {
  std::string bytes;
  if (stbi_write_png_to_func(append_bytes, &bytes, image.width, image.height, 3, image.rgb.data(), 3 * image.width) == 0) {
    throw Error(ErrorKind::io, "E_WRITE", name + ": PNG encoding failed");
  }
  return bytes;
}

void write_png(const RgbImage& image, const std::filesystem::path& path, bool overwrite) {
  const std::string bytes = encode_png(image, path.string());
  io::AtomicOutputFile out(path, overwrite ? io::Overwrite::allow : io::Overwrite::refuse);
  out.stream().write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.commit();
}

RgbImage read_png(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw Error(ErrorKind::io, "E_READ", path.string() + ": cannot open");
  std::string bytes(static_cast<std::size_t>(in.tellg()), '\0');
  in.seekg(0);
  if (!in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()))) {
    throw Error(ErrorKind::io, "E_READ", path.string() + ": read failed");
  }
  int w = 0, h = 0, channels = 0;
  stbi_uc* pixels = stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(bytes.data()), static_cast<int>(bytes.size()), &w,
                                          &h, &channels, 3);
  if (!pixels) throw Error(ErrorKind::input, "E_PNG", path.string() + ": not a PNG stb can read: " + stbi_failure_reason());
  RgbImage out{w, h, std::vector<std::uint8_t>(pixels, pixels + 3 * static_cast<std::size_t>(w) * static_cast<std::size_t>(h))};
  stbi_image_free(pixels);
  return out;
}

}  // namespace geoanchor::gui
