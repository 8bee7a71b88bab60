#pragma once
// The checks of a map's audit (private to workflow's audit), one function
// each; audit_map runs them in this order.

#include <string>
#include <vector>

#include "audit_moves.hpp"
#include "geoanchor/io/tile/tile_metadata.hpp"
#include "geoanchor/workflow/audit.hpp"

namespace geoanchor::workflow::audit_detail {

AuditCheck make_check(std::string name, std::string rule, std::string limit);

AuditCheck check_data(const std::vector<AuditArtifact>& arts);
AuditCheck check_metadata(const std::vector<AuditArtifact>& arts);
AuditCheck check_one_frame(const std::vector<AuditArtifact>& arts);
AuditCheck check_seams(const std::vector<AuditArtifact>& arts, const AuditLimits& l, Transforms& transforms);
AuditCheck check_checkpoints(const std::vector<AuditArtifact>& arts, const AuditRequest& request, Transforms& transforms);
AuditCheck check_rtk(const std::vector<AuditArtifact>& arts, const AuditLimits& l);
AuditCheck check_float32_ecef(const std::vector<AuditArtifact>& arts);
AuditCheck check_float32_resolution(const std::vector<AuditArtifact>& arts, const AuditLimits& l);
AuditCheck check_tangent_plane(const std::vector<AuditArtifact>& arts, const AuditLimits& l);
AuditCheck check_web_mercator(const std::vector<AuditArtifact>& arts);

// A contract's coordinate epoch (or range) as text, "unknown" without one.
std::string epoch_text(const io::MapMetadata& m);

}  // namespace geoanchor::workflow::audit_detail
