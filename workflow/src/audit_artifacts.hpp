#pragma once
// What audit reads (private to workflow's audit): the artifacts of a map,
// listed from the inputs and read with their sidecars, and what each
// states: its provenance, its metadata contract, the map's ENU origin.

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/workflow/audit.hpp"

namespace geoanchor::workflow::audit_detail {

// The artifacts found among the inputs, and the files left out (with why).
struct Listing {
  std::vector<AuditArtifact> artifacts;
  std::vector<std::string> ignored;
};

// Every tile, vector map and transform file among `request.inputs` (folders
// listed recursively, in name order; a sidecar stands for its file); throws
// on a file that is none of them.
Listing list_artifacts(const AuditRequest& request);

// Reads an artifact's transform file or sidecar; what cannot be read goes
// into `a.unreadable`.
void read_artifact(AuditArtifact& a);

std::string name_of(const AuditArtifact& a);

// The provenance object of a sidecar, or an empty object.
nlohmann::json provenance(const AuditArtifact& a);

// The metadata contract an artifact carries (its sidecar's or its transform
// file's), or nullptr.
const io::MapMetadata* contract_of(const AuditArtifact& a);

// Whether an artifact's coordinates are relative to an ENU origin.
bool needs_enu_origin(const AuditArtifact& a);

// The map's reference: the ENU origin its contracts state (the first).
std::optional<geodesy::LocalOrigin> map_origin(const std::vector<AuditArtifact>& arts);

}  // namespace geoanchor::workflow::audit_detail
