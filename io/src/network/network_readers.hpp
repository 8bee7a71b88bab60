#pragma once
// The readers of each network input format (private to io): each adds what
// one input holds to `into`, stations matched by name (NetworkBuilder).

#include <string_view>

#include "geoanchor/geodesy/network.hpp"
#include "geoanchor/io/network/network_input.hpp"

namespace geoanchor::io::detail {

void read_network_json(std::string_view text, std::string_view source, geodesy::Network& into);  // network_json.cpp
void read_dynaml(std::string_view text, std::string_view source, geodesy::Network& into,
                 const NetworkReadOptions& options);                                               // network_dynaml.cpp
void read_dna(std::string_view text, std::string_view source, geodesy::Network& into,
              const NetworkReadOptions& options);                                                  // network_dna.cpp
void read_sinex(std::string_view text, std::string_view source, geodesy::Network& into,
                const NetworkReadOptions& options);                                                // network_sinex.cpp
void read_gama_local(std::string_view text, std::string_view source, geodesy::Network& into);    // network_gama.cpp
void read_gvx(std::string_view text, std::string_view source, geodesy::Network& into);           // network_gvx.cpp
// STAR*NET data file; .INCLUDE files are read relative to `source`'s folder.
void read_starnet(std::string_view text, std::string_view source, geodesy::Network& into,
                  const NetworkReadOptions& options);  // network_starnet.cpp

}  // namespace geoanchor::io::detail
