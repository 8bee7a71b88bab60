// libFuzzer target: DynAdjust's DynaML (station and measurement elements,
// in one file or apart) read as `geoanchor adjust` reads an input, in one
// piece and in parts on threads (NetworkReadOptions::dynaml_part_bytes):
// the two readings must give the same network or the same error.

#include <string>

#include "fuzz_support.hpp"

namespace {

using namespace geoanchor;

// What tests/io/network_dynaml_test.cpp compares.
bool same(const geodesy::Network& a, const geodesy::Network& b) {
  if (a.stations.size() != b.stations.size() || a.measurements.size() != b.measurements.size() ||
      a.direction_sets.size() != b.direction_sets.size() || a.warnings != b.warnings ||
      a.frame.has_value() != b.frame.has_value()) {
    return false;
  }
  for (std::size_t i = 0; i < a.stations.size(); ++i) {
    const auto &x = a.stations[i], &y = b.stations[i];
    if (x.id != y.id || x.position != y.position || x.source != y.source || x.constraint.text() != y.constraint.text()) return false;
  }
  for (std::size_t i = 0; i < a.measurements.size(); ++i) {
    const auto &x = a.measurements[i], &y = b.measurements[i];
    if (x.source != y.source || x.kind != y.kind || x.stations != y.stations || x.value != y.value ||
        x.covariance != y.covariance || x.set != y.set || x.ignore != y.ignore || x.frame.has_value() != y.frame.has_value()) {
      return false;
    }
  }
  for (std::size_t i = 0; i < a.direction_sets.size(); ++i) {
    if (a.direction_sets[i].station != b.direction_sets[i].station || a.direction_sets[i].source != b.direction_sets[i].source) {
      return false;
    }
  }
  return true;
}

// The network read, or the error's code and message.
struct Reading {
  std::optional<geodesy::Network> network;
  std::string error;
};

Reading read(const std::string& path, std::size_t part_bytes) {
  io::NetworkReadOptions o;
  o.dynaml_part_bytes = part_bytes;
  try {
    return {io::read_network({path}, o), ""};
  } catch (const Error& e) {
    return {std::nullopt, e.code() + ": " + e.what()};
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  constexpr std::size_t kSmallParts = 64;  // bytes: two parts (on two cores) from 128 bytes on
  try {
    if (io::detect_network_format(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz") !=
        io::NetworkFormat::dynaml) {
      return 0;
    }
  } catch (const Error&) {
    return 0;
  }
  const std::string path = fuzz::as_file(data, size, ".xml").string();
  const Reading whole = read(path, 0), parts = read(path, kSmallParts);
  if (whole.error != parts.error || whole.network.has_value() != parts.network.has_value()) __builtin_trap();
  if (whole.network && !same(*whole.network, *parts.network)) __builtin_trap();
  return 0;
}
