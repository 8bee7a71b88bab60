#pragma once
// `geoanchor convert`, both modes (frames, and CRSs through PROJ): the run's
// warnings with standard output committed, and the sidecar's first keys.

#include <nlohmann/json.hpp>

#include <iostream>
#include <string>
#include <vector>

#include "convert_command.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/base/hash.hpp"
#include "version.hpp"

namespace geoanchor::cli {

// Prints the run's warnings (and the stale temporaries removed) on standard
// error; commits standard output, which gets no sidecar. True when it did.
inline bool warn_and_commit_standard_output(std::vector<std::string>& warnings, io::DataOutput& output) {
  for (const auto& t : io::take_removed_stale_temporaries()) warnings.push_back(io::stale_temporary_warning(t));
  for (const auto& w : warnings) std::cerr << "geoanchor: warning: " << w << '\n';
  if (!output.is_standard_output()) return false;
  output.commit("the converted rows");
  return true;
}

// The sidecar's first keys: schema, version, command line, the input's path and hash.
inline nlohmann::json sidecar_start(const ConvertOptions& o, bool from_stdin) {
  using nlohmann::json;
  json side;
  side["schema"] = "geoanchor.convert-provenance/1";
  side["geoanchor_version"] = GEOANCHOR_VERSION;
  side["command"] = o.argv;
  side["input"] = {{"path", from_stdin ? json(nullptr) : json(o.input)},
                   {"sha256", from_stdin ? json(nullptr) : json(sha256_file_hex(o.input))}};
  return side;
}

}  // namespace geoanchor::cli
