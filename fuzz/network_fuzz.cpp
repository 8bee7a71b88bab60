// libFuzzer target: geoanchor's network JSON ("geoanchor.network/1";
// docs/network-format.md) read as `geoanchor adjust` reads an input.

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace geoanchor;
  (void)fuzz::read_network_input(data, size, io::NetworkFormat::json, {});
  return 0;
}
