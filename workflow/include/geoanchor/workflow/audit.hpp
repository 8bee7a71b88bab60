#pragma once
// `geoanchor audit` as a library: the geodetic checks a finished map must
// pass before it goes into a safety case (docs/commands/audit.md). A map is
// what `apply` (and `fit`) wrote: tiles and vector maps, each with its
// sidecar (`<file>.geoanchor.json`, docs/tile-metadata.md), and transform
// files. Each check has a name, the rule it comes from, its limit, a
// verdict and the evidence for it:
//
//   metadata           every artifact carries the map metadata contract with
//                      each reviewer field filled (not "unknown")
//   one_frame          one frame (datum and realization), coordinate epoch and
//                      ENU origin across the map; the artifacts that differ
//   seams              a point on each shared tile boundary, taken back
//                      through one tile's transform and forward through the
//                      other's, lands where it started
//   checkpoints        surveyed marks (--checkpoints): the map's transform of
//                      each source position against its target
//   rtk_fixed_share    each tile's and vector map's RTK-fixed share
//   no_float32_ecef    no coordinates stored as float32 ECEF
//   float32_resolution float32 offsets keep the resolution over the extent
//   tangent_plane      the tangent plane's departure from the ellipsoid,
//                      d²/2R, over the map's extent
//   no_web_mercator    no artifact in (or moved from) Web Mercator
//
// A check that cannot be carried out for an artifact (a tile in a PROJ CRS
// for the seams, a transform file that is gone) fails, saying why: a check
// not done is not a check passed.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "geoanchor/io/tile/tile_metadata.hpp"
#include "geoanchor/io/transform/transform_file.hpp"

namespace geoanchor::workflow {

// The limits, each a flag of `audit` (docs/commands/audit.md gives the
// defaults' reasons).
struct AuditLimits {
  double checkpoint_horizontal_m = 0.05;  // the airside map requirement
  double checkpoint_vertical_m = 0.05;
  double seam_m = 0.01;
  double min_rtk_fixed_percent = 95.0;
  double float32_resolution_m = 0.001;
  double tangent_plane_m = 1.0;
  // Tiles whose horizontal bounds come this close share a boundary.
  double adjacency_gap_m = 1.0;
};

struct AuditRequest {
  std::vector<std::string> inputs;   // folders (recursive), tiles, vector maps, sidecars, transform files
  std::vector<std::string> exclude;  // globs, as apply's --exclude
  std::optional<std::string> checkpoints;  // a control set, as fit reads
  // With it, `checkpoints` holds the marks as the map has them and this
  // file the surveyed ones, joined by id (as fit --src/--dst); ENU columns
  // are at the map's origin.
  std::optional<std::string> checkpoints_dst;
  AuditLimits limits;
};

enum class AuditArtifactKind { tile, vector_map, transform };
std::string_view to_string(AuditArtifactKind k);  // "tile", "vector map", "transform file"

struct AuditArtifact {
  std::filesystem::path path;     // the tile, vector map or transform file
  std::filesystem::path sidecar;  // tiles and vector maps
  AuditArtifactKind kind = AuditArtifactKind::tile;
  std::optional<io::TileMetadata> meta;         // the sidecar, read
  std::optional<io::TransformFile> transform;   // a transform artifact, read
  std::string transform_sha256;                 // of a transform artifact
  std::string unreadable;                       // why the metadata could not be read
};

enum class AuditStatus { pass, fail, not_run };
std::string_view to_string(AuditStatus s);  // "pass", "fail", "not run"

struct AuditCheck {
  std::string name;  // as listed above
  std::string rule;  // where the check comes from
  std::string limit;
  AuditStatus status = AuditStatus::pass;
  std::string summary;                // one line: what was found
  std::vector<std::string> evidence;  // per artifact, pair or mark
};

struct AuditResult {
  std::vector<AuditArtifact> artifacts;
  std::vector<std::string> ignored;  // run summaries, --exclude
  std::vector<AuditCheck> checks;
  // Every check passed (a check not run, --checkpoints absent, does not fail).
  bool passed() const;
};

// Lists and reads the map's artifacts and runs every check. Throws
// geoanchor::Error for inputs that are not a map's files (naming them), an
// unreadable --checkpoints set or a bad limit; what the checks find is in
// the result, never thrown.
AuditResult audit_map(const AuditRequest& request);

// The report: one line per check (PASS/FAIL, name, summary, rule) with its
// evidence below, and the verdict.
std::string audit_text(const AuditResult& r);
// The same as JSON (schema geoanchor.audit/1), indented by 2.
std::string audit_json_text(const AuditResult& r, const AuditRequest& request);

// Whether a CRS's name, identifier or definition (WKT, PROJ string, EPSG
// code, free text) is Web Mercator (EPSG:3857 and its aliases 900913, 3785,
// ESRI 102100/102113, "Pseudo-Mercator", "Popular Visualisation", a
// spherical +proj=merc on a = b = 6378137): what in `text` says so, or "".
std::string web_mercator_mention(std::string_view text);

// The vertical departure of a tangent plane from the ellipsoid at horizontal
// distance d from its origin: d²/2R, R the Gaussian mean radius at the
// origin's latitude.
double tangent_plane_departure_m(double distance_m, double lat_deg, const geodesy::Ellipsoid& e);

// The spacing of float32 values at |x| (the unit in the last place).
double float32_spacing(double x);

}  // namespace geoanchor::workflow

namespace geoanchor::workflow {

// What a map states as one across its artifacts (`locate`): its frame with
// the coordinate epoch, its ENU origin (the aerodrome reference point) on
// the frame's ellipsoid, and the transform its tiles were moved with when
// they share one.
struct MapReference {
  geodesy::Frame frame;
  geodesy::LocalOrigin origin;
  std::string origin_source;  // "unknown" when not stated
  std::optional<io::TransformFile> transform;
  std::string transform_path, transform_sha256;
  bool transform_inverse = false;
  std::optional<double> transform_epoch;
  std::vector<std::string> artifacts;
};

// Throws geoanchor::Error (input, E_MAP_REFERENCE) naming the artifacts when
// the map's frames, epochs or origins differ, or when none states them; as
// audit_map for inputs that are no map's files.
MapReference map_reference(const std::vector<std::string>& inputs, const std::vector<std::string>& exclude);

}  // namespace geoanchor::workflow
