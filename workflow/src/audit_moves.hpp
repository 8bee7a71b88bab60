#pragma once
// How the map's tiles were moved (private to workflow's audit): each tile's
// transform file, direction and epoch as its provenance records them, and
// the transform files themselves, found by content.

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "geoanchor/geodesy/units.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "geoanchor/workflow/audit.hpp"

namespace geoanchor::workflow::audit_detail {

// How a tile was moved: its transform file (by content), direction and
// epoch, as its provenance records it.
struct Move {
  std::string sha256;  // "" without a transform
  bool inverse = false;
  std::optional<double> epoch;
  std::string input_frame, output_frame;
  // A tile read through PROJ: its CRS (WKT2) and PROJ's operations, which
  // audit cannot run again; two tiles read from different CRSs are not
  // compared by their transforms alone.
  std::string input_crs;
  std::string path;  // as recorded
  bool operator==(const Move& o) const {
    return sha256 == o.sha256 && inverse == o.inverse && epoch == o.epoch && input_frame == o.input_frame &&
           output_frame == o.output_frame && input_crs == o.input_crs;
  }
};

Move move_of(const AuditArtifact& a);

// The transform files the map's tiles were moved with, by SHA-256: found
// among the audited artifacts, else at the path each provenance records
// (as written, then beside the sidecar), and checked against the hash.
class Transforms {
 public:
  explicit Transforms(const std::vector<AuditArtifact>& arts) {
    for (const auto& a : arts) {
      if (a.transform) by_sha_.emplace(a.transform_sha256, &*a.transform);
    }
  }
  // nullptr with `why` set when it cannot be had.
  const io::TransformFile* find(const Move& m, const AuditArtifact& tile, std::string& why);

 private:
  std::map<std::string, const io::TransformFile*> by_sha_;
  std::map<std::string, io::TransformFile> loaded_;
};

// A recorded epoch as a decimal year.
std::optional<geodesy::DecimalYear> year(std::optional<double> y);

}  // namespace geoanchor::workflow::audit_detail
