// Formats whose readers are not written yet: refused by name, never guessed.

#include "geoanchor/geodesy/error.hpp"
#include "network_readers.hpp"

namespace geoanchor::io::detail {
namespace {
[[noreturn]] void pending(std::string_view source, const char* format) {
  throw Error(ErrorKind::input, "E_NETWORK_FORMAT",
              std::string(source) + ": a " + format + " file; this geoanchor does not read " + format +
                  " yet: give the network in geoanchor's network JSON (docs/network-format.md)");
}
}  // namespace

void read_dynaml(std::string_view, std::string_view source, geodesy::Network&) { pending(source, "DynaML"); }
void read_sinex(std::string_view, std::string_view source, geodesy::Network&) { pending(source, "SINEX"); }
void read_gama_local(std::string_view, std::string_view source, geodesy::Network&) { pending(source, "GNU Gama"); }

}  // namespace geoanchor::io::detail
