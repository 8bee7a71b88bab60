// libFuzzer target: DynAdjust's DNA text (!#=DNA … STN|MSR) read as
// `geoanchor adjust` reads an input, and its per-station geoid file
// (--geoid FILE.geo). Whatever it reads holds no NaN or infinity.

#include <cmath>
#include <string>

#include "geoanchor/io/network/station_geoid.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace geoanchor;
  if (const auto net = fuzz::read_network_input(data, size, io::NetworkFormat::dna, {})) {
    for (const auto& s : net->stations) {
      if (!s.position.allFinite()) __builtin_trap();
    }
    for (const auto& m : net->measurements) {
      if (!m.value.allFinite() || !m.covariance.allFinite() || !std::isfinite(m.instrument_height_m) ||
          !std::isfinite(m.target_height_m)) {
        __builtin_trap();
      }
    }
  }
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  if (io::looks_like_dna_geoid(text)) {
    try {
      for (const auto& [name, g] : io::read_dna_geoid(text, "fuzz.geo").by_station) {
        if (!std::isfinite(g.n_m) || !std::isfinite(g.deflection.xi_rad) || !std::isfinite(g.deflection.eta_rad)) __builtin_trap();
      }
    } catch (const Error&) {
    }
  }
  return 0;
}
