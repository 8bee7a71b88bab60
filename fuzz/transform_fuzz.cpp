// libFuzzer target: the transform file (JSON; docs/transform-file.md), what
// convert and apply make of it, and its round trip: a file read is written,
// and what is written must read back. (Not to the same text: a ppm value is
// held as a ratio, and ×1e-6 then ×1e6 may move it by an ulp.)

#include <string>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/transform/transform_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace geoanchor;
  const std::string text(reinterpret_cast<const char*>(data), size);
  io::TransformFile t;
  try {
    t = io::parse_transform_json(text, "fuzz.json");
  } catch (const Error&) {
    return 0;
  }
  // What the writer gives must read back.
  try {
    (void)io::parse_transform_json(io::to_json_text(t), "again.json");
  } catch (const Error&) {
    __builtin_trap();
  }
  // A mark near LSZH (ECEF metres) both ways, at an observation epoch.
  const geodesy::EcefPosition x(4271315.7, 641096.4, 4678048.5);
  for (const bool inverse : {false, true}) {
    try {
      (void)t.apply(x, geodesy::DecimalYear{2020.5}, inverse, "fuzz");
    } catch (const Error&) {
    }
  }
  try {
    (void)io::proj_pipeline(t);
    (void)io::to_wkt2(t);
  } catch (const Error&) {
  }
  return 0;
}
