// libFuzzer target: GNU Gama's local-network XML (<gama-local>) read as
// `geoanchor adjust` reads an input.

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace geoanchor;
  (void)fuzz::read_network_input(data, size, io::NetworkFormat::gama_local, {});
  return 0;
}
