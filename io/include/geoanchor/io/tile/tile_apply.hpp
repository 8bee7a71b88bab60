#pragma once
// One tile through a PointChain, streamed in bounded chunks: LAS or LAZ in,
// LAS or LAZ out; CSV or PLY in, the same format out. Vector maps (GeoJSON,
// Lanelet2 OSM XML, OpenDRIVE) are moved by io/vector/vector_map.hpp with the same
// options and result. Everything but the coordinates passes through unchanged. The caller owns the output (an
// AtomicOutputFile) so that the tile and its sidecar are committed together.

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include "geoanchor/crs/crs_operation.hpp"
#include "geoanchor/io/control/crs_columns.hpp"
#include "geoanchor/las/laz.hpp"
#include "geoanchor/io/tile/point_chain.hpp"

namespace geoanchor::io {

// A tile's file format. LAS and LAZ hold the same records (LAZ compressed,
// io/laz.hpp); a COPC file (.copc.laz) is read as the LAZ file it is.
// geojson, osm and xodr are vector maps (io/vector/vector_map.hpp).
enum class TileFormat { las, laz, csv, ply, geojson, osm, xodr };
std::string_view to_string(TileFormat f);  // "las", "laz", "csv", "ply", "geojson", "osm", "xodr"
inline bool is_las_family(TileFormat f) { return f == TileFormat::las || f == TileFormat::laz; }
inline bool is_vector_map(TileFormat f) {
  return f == TileFormat::geojson || f == TileFormat::osm || f == TileFormat::xodr;
}
// By extension, case-insensitive: .las; .laz (and .copc.laz); .csv, .txt;
// .ply; .geojson; .osm; .xodr. std::nullopt for anything else.
std::optional<TileFormat> tile_format_of(const std::filesystem::path& p);
// Whether the name ends in .copc.laz (case-insensitive).
bool is_copc_name(const std::filesystem::path& p);
// The output's file name for a tile written as `out`: the input's name when
// the format stays (x.las -> x.las, x.LAZ -> x.LAZ), else its stem with the
// output's extension (x.las -> x.laz, x.laz -> x.las). A COPC file is never
// written as COPC (the octree hierarchy is not rebuilt): x.copc.laz ->
// x.laz, or x.las.
std::string tile_output_name(const std::filesystem::path& input, TileFormat out);

// The file's axes where a tile's coordinates are in a CRS that PROJ moves
// (apply --crs/--to-crs, a LAS WKT geoanchor's own kinds do not hold): X,
// Y, Z in the CRS's visualisation order (longitude or easting first), in
// its units.
struct TileCrsAxes {
  bool angular = false;     // X, Y are longitude and latitude
  bool geocentric = false;  // X, Y, Z are geocentric
  double horizontal_unit = 1.0;  // metres (angular: degrees) per unit of X and Y
  double vertical_m = 1.0;       // metres per unit of Z
  bool has_height = true;        // false: a 2-D CRS; Z is no coordinate and passes unchanged
  // CSV: the CRS's columns (names, units, write order).
  std::optional<CrsColumns> columns = std::nullopt;
};

// The file axes of a tile in `crs` (its visualisation order and units;
// `columns` left for the caller, who has the CSV header).
TileCrsAxes tile_crs_axes(const Crs& crs);

struct TileApplyOptions {
  ArrayFrame from;  // the tile's coordinates
  ArrayFrame to;    // the output's
  // LAS: the output's quantization step in metres for every axis (degrees
  // get the power of ten at or below it); default: the input's.
  std::optional<double> resolution_m;
  std::string output_wkt;  // LAS: the CRS written into the 2112 VLR
  std::size_t chunk_points = 1 << 16;
  // Called after each chunk with the points done so far in this tile.
  std::function<void(std::uint64_t)> progress;
  // Called with each batch of points as the chain reads them (after
  // `crs_before`, in `from`'s coordinates), from any thread; apply measures
  // how far they reach outside a transform's control network.
  std::function<void(std::span<const double>, std::span<const double>, std::span<const double>)> inspect_input = nullptr;
  // The same with each batch as the chain leaves it (before `crs_after`, in
  // `to`'s coordinates): apply measures how far they lie from an output
  // ENU/NED origin.
  std::function<void(std::span<const double>, std::span<const double>, std::span<const double>)> inspect_output = nullptr;
  // LAS: evaluate a time-dependent transform at each point's own epoch,
  // from its GPS time (adjusted standard GPS time, global encoding bit 0).
  bool epochs_from_gps_time = false;
  // CRS stages, run on the file's X, Y, Z (file_in/file_out say their axes):
  // `crs_before` from the file's CRS into the chain's input (`from` is then
  // ECEF), or, without `chain_used`, straight into the output CRS;
  // `crs_after` from the chain's output (`to` ECEF) into the output CRS.
  // Not owned; each tile has its own (a CrsOperation is one thread's).
  CrsOperation* crs_before = nullptr;
  CrsOperation* crs_after = nullptr;
  bool chain_used = true;
  std::optional<TileCrsAxes> file_in = std::nullopt, file_out = std::nullopt;
  // CSV: the comment lines stating the output's CRS (replacing the input's).
  std::vector<std::string> crs_comments = {};
  // LAS/LAZ: how the output is stored (LAZ output: LASzip chunks of
  // `laz_chunk_points`, whatever the input's chunks).
  TileFormat las_output = TileFormat::las;
  // LAS/LAZ: the records one thread takes at a time (read or decompressed,
  // moved, quantized, compressed), and a LAZ output's chunk size; `threads`
  // such units run at once and are written in order, with at most
  // 2 x threads of them in memory. The output does not depend on `threads`.
  std::uint32_t laz_chunk_points = kLazDefaultChunkPoints;
  unsigned threads = 1;
  // LAS/LAZ: the output's coordinates are the tile's own (apply --crs X
  // --to-crs X): X, Y, Z, scale and offset are kept, so every point record
  // is copied byte for byte (a LAS <-> LAZ conversion). The chain and the
  // CRS stages are not run.
  bool keep_coordinates = false;
  // LAZ output: when the header's bounds put a point beyond int32 at the
  // offset they suggest, the tile is written again from its first byte with
  // an offset from the true bounds; a LAZ stream cannot be rewritten in
  // place, so this gives an empty output for that (the caller discards what
  // was written to `out`). Without it, that retry is a std::logic_error.
  std::function<std::ostream&()> restart_output = {};
  // Lanelet2 OSM: the local projection of the nodes' local_x/local_y tags
  // (io/vector/vector_map.hpp, LocalXy); needed when a node has them. The tags
  // must agree with lat/lon within `local_xy_tolerance_m` before the move.
  std::optional<std::string> local_xy = std::nullopt;
  double local_xy_tolerance_m = 0.01;
  // OpenDRIVE: the largest deviation allowed between the re-anchored map
  // and the exactly moved road geometry.
  double max_deviation_m = 0.001;
  // Vector maps: the output's frame as NAME@EPOCH ("" when it has none) and
  // its CRS when it is in one (not owned), which GeoJSON records in its
  // foreign member (and a legacy "crs" member).
  std::string output_frame = {};
  const Crs* output_crs = nullptr;
};

struct TileApplyResult {
  std::uint64_t points = 0;
  // LAS/LAZ with an extra-bytes attribute "gnss_solution" (las.hpp): the
  // points of each GNSS solution type, in the order of geodesy::kGnssSolutions.
  std::optional<std::array<std::uint64_t, 7>> gnss_solution_counts;
  // Output bounds in the file's axes (LAS: X, Y, Z; CSV/PLY: the three
  // coordinate columns in the order written).
  std::array<double, 3> min{}, max{};
  // Input bounds in the chain's order (lat, lon, h for geodetic input).
  std::array<double, 3> in_min{}, in_max{};
  std::array<double, 3> scale{}, offset{};  // LAS
  std::string storage;                      // float64 | float32 | int32_scaled
  std::optional<std::array<double, 2>> epoch_range;  // per-point epochs: earliest, latest
  std::optional<LazVlr> laz;  // a LAZ output's compression (its laszip VLR)
  std::vector<std::string> warnings;
  // Vector maps: what the output's provenance records of the format (JSON
  // text of an object: the OpenDRIVE re-anchoring, the Lanelet2 local
  // projection, the GeoJSON positions); "" for tiles.
  std::string format_record_json;
};

// Each throws geoanchor::Error naming the file and the byte offset (LAS,
// binary PLY), chunk and byte offset (LAZ) or line (CSV, ASCII PLY) of bad
// input, or the point whose output cannot be stored. `out` must be a
// binary, seekable stream. apply_las_tile reads LAS and LAZ and writes
// either (o.las_output); the first error in point order is the one thrown,
// whatever the threads.
TileApplyResult apply_las_tile(const std::filesystem::path& in, std::ostream& out, const std::string& out_name,
                               const PointChain& chain, const TileApplyOptions& o);
TileApplyResult apply_csv_tile(const std::filesystem::path& in, std::ostream& out, const std::string& out_name,
                               const PointChain& chain, const TileApplyOptions& o);
TileApplyResult apply_ply_tile(const std::filesystem::path& in, std::ostream& out, const std::string& out_name,
                               const PointChain& chain, const TileApplyOptions& o);

}  // namespace geoanchor::io
