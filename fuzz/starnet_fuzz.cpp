// libFuzzer target: STAR*NET data files (.dat) read as `geoanchor adjust`
// reads an input (detected by content, then read into a local network),
// and read again after a network JSON anchor that names a frame, as the
// geodetic positions (P, PH, EH) and GPS vectors (G0-G3) need.

#include <string_view>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace geoanchor;
  (void)fuzz::read_network_input(data, size, io::NetworkFormat::starnet, {});
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    if (io::detect_network_format(text, "fuzz") != io::NetworkFormat::starnet) return 0;
    geodesy::Network net;
    io::read_network_text(R"({"schema": "geoanchor.network/1", "frame": "ITRF2014@2020.0", "stations": [
        {"id": "Q", "lat_deg": 45, "lon_deg": -120, "h_m": 100, "constraint": "CCC"}], "measurements": []})",
                          "anchor.json", net);
    io::read_network_text(text, "fuzz.dat", net);
  } catch (const Error&) {
  }
  return 0;
}
