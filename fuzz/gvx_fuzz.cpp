// libFuzzer target: NGS GNSS Vector Exchange (<GVX VERSION="1.0">) read as
// `geoanchor adjust` reads an input.

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace geoanchor;
  (void)fuzz::read_network_input(data, size, io::NetworkFormat::gvx, {});
  return 0;
}
