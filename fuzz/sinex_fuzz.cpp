// libFuzzer target: SINEX station solutions (SOLUTION/ESTIMATE with
// SOLUTION/MATRIX_ESTIMATE) read as `geoanchor adjust --sinex-frame
// ITRF2014` reads an input.

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace geoanchor;
  static const io::NetworkReadOptions options = [] {
    io::NetworkReadOptions o;
    o.sinex_frame = geodesy::Frame::parse("ITRF2014", "fuzz");
    return o;
  }();
  (void)fuzz::read_network_input(data, size, io::NetworkFormat::sinex, options);
  return 0;
}
