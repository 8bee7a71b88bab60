#pragma once
// One tile of `apply` (private to workflow's apply): TileRunner plans a
// tile, moves its points into the output and writes its sidecar, in named
// steps across apply_tile.cpp, apply_reach.cpp and apply_provenance.cpp.

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "geoanchor/crs/crs_operation.hpp"
#include "geoanchor/base/hash.hpp"
#include "geoanchor/io/map_metadata.hpp"
#include "geoanchor/io/tile/point_chain.hpp"
#include "geoanchor/io/tile/tile_apply.hpp"
#include "geoanchor/io/tile/tile_metadata.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "geoanchor/workflow/apply.hpp"
#include "geoanchor/workflow/tile_plan.hpp"

namespace geoanchor::workflow::apply_detail {

// How far the tile's points reach outside the fitted transform's control
// network, measured on every point in the transform's source frame (its
// bounding box's corners reached 2 km outside a network its points all
// lie in: issue 40 point 11).
// And how far they lie from an ENU/NED origin, input's and output's (a
// swapped --origin put a tile 4 000 km from it without a word): refused
// past --max-extrapolation, as convert and locate refuse such points.
class PointReach {
 public:
  // Watches the points of plan `p` (`before`: the tile's CRS stage, whose
  // input is no ENU/NED) against the transform `t`'s control network.
  PointReach(const TilePlan& p, const std::optional<io::TransformFile>& t, const std::unique_ptr<io::CrsOperation>& before);
  PointReach(const PointReach&) = delete;
  PointReach& operator=(const PointReach&) = delete;
  // Sets `ao` to report the batches it reads and writes to this.
  void watch(io::TileApplyOptions& ao);

  std::mutex m;
  double worst_m = 0.0;
  double from_origin_m[2] = {0.0, 0.0};  // input's, output's
  const io::ControlExtent* extent = nullptr;  // the transform's control network, where its fit records one
  bool local_in = false, local_out = false;   // ENU/NED with an origin, input's and output's

 private:
  void record(double& worst, double d);
  std::optional<io::PointChain> to_source_ecef;
};

// The tile's bounding-box corners and centre (9 points) in the source
// frame's ECEF, and those of them that lie in the input projection's domain.
struct TileCorners {
  std::vector<double> a, b, c;
  std::vector<std::size_t> usable;
};

class TileRunner {
 public:
  TileRunner(const ApplyRequest& o, const TilePlanner& planner, const std::optional<io::TransformFile>& t,
             const std::string& transform_sha, ApplyProgress& progress, unsigned threads_per_tile)
      : o_(o), planner_(planner), t_(t), transform_sha_(transform_sha), progress_(progress),
        threads_per_tile_(threads_per_tile) {}
  TileRunner(const TileRunner&) = delete;
  TileRunner& operator=(const TileRunner&) = delete;

  TileOutcome run(const std::filesystem::path& input) const;

 private:
  void process(const TilePlan& p, TileOutcome& r) const;
  bool up_to_date(const TilePlan& p, const std::string& input_sha, const nlohmann::json& request, TileOutcome& r) const;
  std::vector<std::string> remove_orphan_sidecar(const TilePlan& p) const;
  io::TileApplyOptions apply_options(const TilePlan& p, const std::string& tile, const std::unique_ptr<io::CrsOperation>& before,
                                     const std::unique_ptr<io::CrsOperation>& after) const;
  void check_origin_distances(const TilePlan& p, const PointReach& reach, const std::string& tile,
                              std::vector<std::string>& warnings) const;
  std::vector<std::string> transform_warnings_of(const TilePlan& p, const io::TileApplyResult& res, TileOutcome& r) const;
  nlohmann::json extrapolation_record(const PointReach& reach, const std::string& tile, std::vector<std::string>& warnings) const;
  nlohmann::json propagated_uncertainty(const TilePlan& p, const io::TileApplyResult& res, const TileCorners& corners) const;
  void record_input(nlohmann::ordered_json& prov, const TilePlan& p, const io::TileApplyResult& res, const std::string& input_sha,
                    const nlohmann::json& request) const;
  void record_transform(nlohmann::ordered_json& prov, const TilePlan& p, const io::TileApplyResult& res,
                        const nlohmann::json& uncertainty, const nlohmann::json& extrapolation) const;

  const ApplyRequest& o_;
  const TilePlanner& planner_;
  const std::optional<io::TransformFile>& t_;
  const std::string& transform_sha_;
  ApplyProgress& progress_;
  unsigned threads_per_tile_ = 1;
  mutable FileHashCache grid_hashes_;  // a grid is hashed once per run, not once per tile
};

// The options that decide an output's content, for the resumability check.
nlohmann::json request_json(const ApplyRequest& o, io::TileFormat input_format, io::TileFormat output_format);

// The tile's points read, moved and written by the reader of its format.
io::TileApplyResult apply_points(const TilePlan& p, std::ostream& out, const io::PointChain& chain, const io::TileApplyOptions& ao);

// The tile's corners in the source frame's ECEF (through `before`, the
// tile's CRS stage); a warning where some lie outside the projection's domain.
TileCorners tile_corners(const TilePlan& p, const io::TileApplyResult& res, const std::unique_ptr<io::CrsOperation>& before,
                         const std::string& tile, std::vector<std::string>& warnings);

// The provenance's PROJ operations (their warnings into `warnings`), and
// what it records of the output.
void record_crs_operations(nlohmann::ordered_json& prov, const TilePlan& p, const std::unique_ptr<io::CrsOperation>& before,
                           const std::unique_ptr<io::CrsOperation>& after, const std::string& tile,
                           std::vector<std::string>& warnings);
void record_output(nlohmann::ordered_json& prov, const TilePlan& p, const io::TileApplyResult& res, std::uint64_t output_size,
                   const std::string& output_sha, const std::vector<std::string>& warnings,
                   const std::vector<std::string>& transform_warnings);

// The output's sidecar: its metadata, the map metadata contract and the provenance.
io::TileMetadata sidecar_metadata(const TilePlan& p, const io::TileApplyResult& res,
                                  const std::optional<io::SurveyMetadata>& survey, const nlohmann::ordered_json& prov);

}  // namespace geoanchor::workflow::apply_detail
