// A tile's sidecar: the request that decides its content, its provenance
// (input, transform, PROJ operations, output) and its metadata.
#include "apply_tile.hpp"

#include "geoanchor/base/hash.hpp"
#include "geoanchor/workflow/map_contract.hpp"

namespace geoanchor::workflow::apply_detail {

using io::TileMetadata;
using nlohmann::json;

json request_json(const ApplyRequest& o, io::TileFormat input_format, io::TileFormat output_format) {
  auto opt = [](const std::optional<std::string>& v) { return v ? json(*v) : json(nullptr); };
  json j{{"to", opt(o.to)},
              {"origin", opt(o.origin)},
              {"zone", opt(o.zone)},
              {"tm", opt(o.tm)},
              {"ellipsoid", opt(o.ellipsoid)},
              {"from_frame", opt(o.from_frame)},
              {"from_origin", opt(o.from_origin)},
              {"from_zone", opt(o.from_zone)},
              {"from_tm", opt(o.from_tm)},
              {"inverse", o.inverse},
              {"resolution_m", o.resolution_m ? json(*o.resolution_m) : json(nullptr)},
              {"epoch_from_gps_time", o.epoch_from_gps_time}};
  // Keys added with issue 13, only when used (earlier outputs stay up to date).
  if (o.crs) j["crs"] = *o.crs;
  if (o.to_crs) j["to_crs"] = *o.to_crs;
  if (o.allow_fallback) j["allow_fallback"] = true;
  // Added with issue 15, only for LAZ outputs (earlier LAS outputs stay up to date).
  if (output_format == io::TileFormat::laz) j["format"] = "laz";
  // Vector maps (issue 16): the options that decide their output.
  if (input_format == io::TileFormat::osm) {
    j["local_xy"] = o.local_xy ? json(*o.local_xy) : json(nullptr);
    j["local_xy_tolerance_m"] = o.local_xy_tolerance_m;
  }
  if (input_format == io::TileFormat::xodr) j["max_deviation_m"] = o.max_deviation_m;
  // Added with issue 16: the survey metadata written into the sidecar, by
  // content (another file makes another sidecar), only when given.
  if (o.survey_metadata) j["survey_metadata_sha256"] = sha256_file_hex(*o.survey_metadata);
  return j;
}

void TileRunner::record_input(nlohmann::ordered_json& prov, const TilePlan& p, const io::TileApplyResult& res,
                              const std::string& input_sha, const json& request) const {
  prov["tool"] = o_.tool;
  prov["command"] = o_.command;
  prov["input"] = p.input.string();
  prov["input_sha256"] = input_sha;
  prov["input_format"] = std::string(io::to_string(p.format));
  prov["output_format"] = std::string(io::to_string(p.output_format));
  if (res.laz) {
    // How the LAZ output is compressed: what its laszip VLR says.
    json items = json::array();
    for (const auto& it : res.laz->items) items.push_back(io::laz_item_name(it.type) + " v" + std::to_string(it.version));
    prov["compression"] = {{"format", "LASzip"},
                           {"compressor", res.laz->compressor == 3 ? "layered chunked" : "pointwise chunked"},
                           {"chunk_points", res.laz->chunk_size},
                           {"items", items}};
  } else {
    prov["compression"] = nullptr;
  }
  prov["input_frame"] = p.in.frame ? json(p.in.frame->to_string()) : json(nullptr);
  prov["input_coordinates"] = io::kind_name(p.in);
  if (p.in.crs) {
    prov["input_crs"] = p.in.crs->display_name();
    prov["input_crs_wkt2"] = p.in.crs->wkt2();
    if (p.in.crs->epoch()) prov["input_coordinate_epoch"] = p.in.crs->epoch()->year;
  }
  prov["input_frame_from"] = p.in_frame_source;
  if (p.in.coordinates.origin) {
    const auto& g = p.in.coordinates.origin->point;
    prov["input_enu_origin"] = {{"lat_deg", g.lat.deg()}, {"lon_deg", g.lon.deg()}, {"h_m", g.h.m}};
  }
  prov["request"] = request;
}

void TileRunner::record_transform(nlohmann::ordered_json& prov, const TilePlan& p, const io::TileApplyResult& res,
                                  const json& uncertainty, const json& extrapolation) const {
  if (t_) {
    prov["transform"] = *o_.transform;
    prov["transform_sha256"] = transform_sha_;
    prov["transform_model"] = std::string(io::to_string(t_->model));
    prov["transform_convention"] = std::string(t_->convention_name());
    prov["transform_direction"] = o_.inverse ? "inverse (exact)" : "forward";
    if (t_->source_frame) prov["transform_source_frame"] = t_->source_frame->to_string();
    if (t_->target_frame) prov["transform_target_frame"] = t_->target_frame->to_string();
    prov["transform_sigma0"] = t_->fit ? (t_->fit->sigma0 ? json(*t_->fit->sigma0) : json(nullptr)) : json(nullptr);
    prov["transform_dof"] = t_->fit ? json(t_->fit->dof) : json(nullptr);
    if (p.epoch) prov["observation_epoch"] = p.epoch->year;
    if (res.epoch_range) {
      prov["observation_epoch"] = "per point, from its GPS time";
      prov["observation_epoch_range"] = {(*res.epoch_range)[0], (*res.epoch_range)[1]};
    }
    prov["propagated_uncertainty"] = uncertainty;
    prov["extrapolation"] = extrapolation;
  } else {
    prov["transform_sha256"] = nullptr;
  }
}

void record_crs_operations(nlohmann::ordered_json& prov, const TilePlan& p, const std::unique_ptr<io::CrsOperation>& before,
                           const std::unique_ptr<io::CrsOperation>& after, const std::string& tile,
                           std::vector<std::string>& warnings) {
  if (before || after) {
    json ops = json::array();
    for (const io::CrsOperation* op : {before.get(), after.get()}) {
      if (!op) continue;
      json rec = json::parse(io::operation_record_json(*op));
      rec["stage"] = op == before.get() ? (p.chain_used ? "tile CRS to its geocentric CRS" : "tile CRS to output CRS")
                                        : "output frame's geocentric CRS to output CRS";
      ops.push_back(rec);
      for (const auto& w : op->warnings()) warnings.push_back(tile + ": " + w);
    }
    prov["crs_operations"] = ops;
  }
}

void record_output(nlohmann::ordered_json& prov, const TilePlan& p, const io::TileApplyResult& res, std::uint64_t output_size,
                   const std::string& output_sha, const std::vector<std::string>& warnings,
                   const std::vector<std::string>& transform_warnings) {
  prov["points"] = res.points;
  prov["bounds"] = {{"min", res.min}, {"max", res.max}};
  if (io::is_las_family(p.format)) prov["las"] = {{"scale", res.scale}, {"offset", res.offset}};
  // A vector map's own record: the OpenDRIVE re-anchoring and its deviation,
  // the Lanelet2 local projection, the GeoJSON positions.
  if (!res.format_record_json.empty()) prov[std::string(io::to_string(p.format))] = nlohmann::ordered_json::parse(res.format_record_json);
  if (p.keep_coordinates) prov["coordinates_kept"] = true;  // the tile's own CRS: every point record copied
  prov["output_size_bytes"] = output_size;
  prov["output_sha256"] = output_sha;
  json all_warnings = warnings;
  for (const auto& w : transform_warnings) all_warnings.push_back(w);
  prov["warnings"] = all_warnings;
}

TileMetadata sidecar_metadata(const TilePlan& p, const io::TileApplyResult& res, const std::optional<io::SurveyMetadata>& survey,
                              const nlohmann::ordered_json& prov) {
  TileMetadata meta = p.out;
  meta.horizontal_crs = (meta.crs ? meta.crs->display_name() : meta.frame->to_string() + " " + io::kind_name(meta.coordinates)) +
                        (io::is_las_family(p.format)
                             ? std::string(" (WKT2 in the ") + (p.output_format == io::TileFormat::laz ? "LAZ" : "LAS") +
                                   " file's LASF_Projection 2112 record)"
                             : "");
  // The map metadata contract (docs/tile-metadata.md): derived, carried
  // from the input, computed from the points' GNSS solutions, the survey's.
  meta.metadata = output_map_metadata(meta, p.in, p.in_frame_source, res.epoch_range, res.gnss_solution_counts,
                                      survey ? &*survey : nullptr, p.sidecar.string());
  meta.rtk_fixed_percent = meta.metadata->rtk_fixed_percent;  // survey.rtk_fixed_percent says the same
  meta.provenance_json = prov.dump();
  return meta;
}

}  // namespace geoanchor::workflow::apply_detail
