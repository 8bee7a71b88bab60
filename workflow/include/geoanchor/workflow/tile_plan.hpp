#pragma once
// What frame and coordinates a tile is in, and what it becomes: the first
// step of `apply` for each tile (apply.hpp).
//
// The input's frame comes from, in this order: the tile's sidecar
// (TILE.geoanchor.json), the LAS file's WKT (with the sidecar, the two must
// agree), or the request's --from-* values (which must then not contradict
// the sidecar or WKT: flags are never silently preferred). It is checked
// against the transform's frames and epochs; the output takes the
// transform's target frame (with the input's epoch when the target names
// none) and the requested output coordinates, else the tile's own.
// A tile in a CRS (--crs, a '# crs' comment, a LAS WKT or sidecar of kind
// "crs") or an output in one (--to-crs) is moved through PROJ: without a
// transform by PROJ's own operation between the two CRSs; with one, each
// CRS is converted to and from its datum's geocentric CRS (which must be
// the transform's frame) around the transform.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/units.hpp"
#include "geoanchor/io/tile/tile_apply.hpp"
#include "geoanchor/io/tile/tile_metadata.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "geoanchor/workflow/apply.hpp"

namespace geoanchor::workflow {

struct TilePlan {
  std::filesystem::path input, output, sidecar;
  io::TileFormat format = io::TileFormat::las;         // the input's
  io::TileFormat output_format = io::TileFormat::las;  // the output's (LAS <-> LAZ by --format)
  io::TileMetadata in;
  std::string in_frame_source;  // "sidecar PATH", "LAS WKT", "command line"
  io::TileMetadata out;
  std::optional<geodesy::DecimalYear> epoch;  // for a time-dependent transform
  std::uint64_t las_points = 0;               // LAS: the header's count, for progress
  // CSV: the header and the comments above it, read once while planning.
  std::vector<std::string> csv_header, csv_comments;
  std::vector<std::string> warnings;
  // PROJ's stages around the chain, for a tile in a CRS or an output in
  // one (in.crs, out.crs): the file's coordinates go from `before[0]` to
  // `before[1]` first (into the chain's ECEF input, or, without
  // `chain_used`, straight into the output CRS), and the chain's ECEF
  // output from `after[0]` to `after[1]`.
  std::optional<std::pair<io::Crs, io::Crs>> before, after;
  bool chain_used = true;
  // A LAS/LAZ tile whose output CRS is its own (no transform, no
  // --resolution): its X, Y, Z, scale and offset are kept (no stage runs).
  bool keep_coordinates = false;
};

// The output format of a tile named `input` under `request` (--format for
// LAS and LAZ tiles, else the input's own), and the output's path in
// request.out_dir (io::tile_output_name). Throws geoanchor::Error (usage,
// E_OPTION) for --format other than las or laz; for a CSV or PLY tile with
// --format, naming the tile.
io::TileFormat planned_output_format(const ApplyRequest& request, const std::filesystem::path& input);
std::filesystem::path planned_output_path(const ApplyRequest& request, const std::filesystem::path& input);

class TilePlanner {
 public:
  // Parses the request's output and --from-* values once, so that a bad one
  // fails before any tile (geoanchor::Error, usage, naming the flag).
  // `transform` must outlive the planner.
  TilePlanner(const ApplyRequest& request, const std::optional<io::TransformFile>& transform);

  // Throws geoanchor::Error naming the tile: an unknown or conflicting
  // frame, orthometric heights, a transform whose frames or epochs do not
  // match the tile's, a missing origin or projection for the output.
  TilePlan plan(const std::filesystem::path& input) const;

 private:
  TilePlan plan_coordinates(const std::filesystem::path& input) const;
  // A vector map's frame and coordinates: its sidecar, what the file says
  // (GeoJSON's 'geoanchor' or legacy 'crs' member, OpenDRIVE's
  // geoReference) and the flags (--from-frame, or --crs naming a frame or,
  // for GeoJSON, any CRS), which must agree.
  io::TileMetadata vector_map_metadata(TilePlan& p) const;
  // Refuses an output a vector map's format cannot hold.
  void check_vector_output(const TilePlan& p) const;
  struct OutputSpec {
    std::optional<io::CoordinateKind> kind;
    bool utm = false;
    std::optional<geodesy::Ellipsoid> ellipsoid;
  };
  io::TileMetadata input_metadata(TilePlan& p) const;
  // The CRS a LAS/LAZ tile states (its WKT, else its GeoTIFF keys) into
  // `wkt`, the keys named in `geotiff_keys`; its point count into `p`.
  void read_las_crs(TilePlan& p, const std::optional<io::TileMetadata>& side, const std::filesystem::path& side_path,
                    std::optional<io::TileMetadata>& wkt, std::optional<std::string>& geotiff_keys) const;
  // A tile's coordinates from the flags alone (--from-frame and
  // --from-origin/--from-zone/--from-tm; a CSV's header names the kind).
  io::TileMetadata metadata_from_flags(TilePlan& p, const std::string& tile, const std::filesystem::path& side_path) const;
  // Refuses an input apply cannot move: no frame, no coordinate epoch of a
  // dynamic frame, orthometric heights.
  void check_input_frame(const TilePlan& p, const std::string& tile) const;
  // The output's frame: the tile's own, or the transform's other side once
  // the tile's frame and epoch are checked against it (p.epoch set for a
  // time-dependent transform).
  std::optional<geodesy::Frame> output_frame(TilePlan& p, const std::string& tile) const;
  // The output in geoanchor's own coordinates: kind, ellipsoid, origin or
  // projection, heights.
  void plan_output_coordinates(TilePlan& p, const std::string& tile) const;
  // Refuses a flag that contradicts what the tile states (p.in_frame_source
  // names where); --crs may complete a stated CRS (heights, epoch), which
  // then replaces it in `m`.
  void check_flags_against(io::TileMetadata& m, TilePlan& p, const std::string& tile) const;
  void plan_crs_stages(TilePlan& p) const;
  const ApplyRequest& o_;
  const std::optional<io::TransformFile>& t_;
  OutputSpec out_;
  std::optional<geodesy::Frame> from_frame_;
};

}  // namespace geoanchor::workflow
