// libFuzzer target: STAR*NET data files (.dat) read as `geoanchor adjust`
// reads an input (detected by content, then read into a local network).

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace geoanchor;
  (void)fuzz::read_network_input(data, size, io::NetworkFormat::starnet, {});
  return 0;
}
