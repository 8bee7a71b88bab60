// How the map's tiles were moved: their provenance's transform, and the
// transform files found among the audited artifacts or at their recorded paths.
#include "audit_moves.hpp"

#include <filesystem>

#include "audit_artifacts.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/base/hash.hpp"

namespace geoanchor::workflow::audit_detail {

namespace fs = std::filesystem;

Move move_of(const AuditArtifact& a) {
  Move m;
  const nlohmann::json p = provenance(a);
  if (p.contains("transform_sha256") && p["transform_sha256"].is_string()) m.sha256 = p["transform_sha256"].get<std::string>();
  if (p.contains("transform") && p["transform"].is_string()) m.path = p["transform"].get<std::string>();
  if (p.contains("transform_direction") && p["transform_direction"].is_string()) {
    m.inverse = p["transform_direction"].get<std::string>().starts_with("inverse");
  }
  if (p.contains("observation_epoch") && p["observation_epoch"].is_number()) m.epoch = p["observation_epoch"].get<double>();
  if (!m.epoch && p.contains("observation_epoch_range") && p["observation_epoch_range"].is_array() &&
      p["observation_epoch_range"].size() == 2) {
    m.epoch = 0.5 * (p["observation_epoch_range"][0].get<double>() + p["observation_epoch_range"][1].get<double>());
  }
  if (p.contains("input_frame") && p["input_frame"].is_string()) m.input_frame = p["input_frame"].get<std::string>();
  if (p.contains("input_crs_wkt2") && p["input_crs_wkt2"].is_string()) m.input_crs = p["input_crs_wkt2"].get<std::string>();
  if (a.meta && a.meta->frame) m.output_frame = a.meta->frame->to_string();
  return m;
}

const io::TransformFile* Transforms::find(const Move& m, const AuditArtifact& tile, std::string& why) {
  if (m.sha256.empty()) return nullptr;
  if (const auto it = by_sha_.find(m.sha256); it != by_sha_.end()) return it->second;
  if (const auto it = loaded_.find(m.sha256); it != loaded_.end()) return &it->second;
  std::vector<fs::path> tries{fs::path(m.path), tile.sidecar.parent_path() / fs::path(m.path).filename()};
  for (const auto& t : tries) {
    std::error_code ec;
    if (m.path.empty() || !fs::is_regular_file(t, ec)) continue;
    try {
      if (sha256_file_hex(t) != m.sha256) {
        why = "the transform file " + t.string() + " it records has changed since (SHA-256 differs)";
        continue;
      }
      return &loaded_.emplace(m.sha256, io::read_transform_file(t)).first->second;
    } catch (const Error& e) {
      why = e.what();
    }
  }
  if (why.empty()) {
    why = "its transform file " + (m.path.empty() ? std::string("(no path recorded)") : m.path) +
          " (SHA-256 " + m.sha256.substr(0, 12) + "…) is neither among the audited files nor at its recorded path";
  }
  return nullptr;
}

std::optional<geodesy::DecimalYear> year(std::optional<double> y) {
  if (!y) return std::nullopt;
  return geodesy::DecimalYear{*y};
}

}  // namespace geoanchor::workflow::audit_detail
