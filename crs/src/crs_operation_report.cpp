// What CrsOperation says of itself: its warnings, and the record of the
// operation an output keeps (JSON).

#include "geoanchor/crs/crs_operation.hpp"

#include <nlohmann/json.hpp>

#include "crs_operation_impl.hpp"
#include "geoanchor/base/number_text.hpp"

namespace geoanchor::io {

namespace {
// An area's name for a one-line warning (EPSG's run to hundreds of characters).
std::string abridged(const std::string& name) {
  constexpr std::size_t kMaxArea = 120;
  if (name.size() <= kMaxArea) return name;
  std::size_t cut = kMaxArea;
  while (cut > 0 && (static_cast<unsigned char>(name[cut]) & 0xC0u) == 0x80u) --cut;  // not inside a UTF-8 character
  return name.substr(0, cut) + "…";
}
}  // namespace

std::vector<std::string> CrsOperation::warnings() const {
  std::vector<std::string> out = impl_->notes;
  if (!impl_->epoch_probe.empty() && !impl_->probing && impl_->epoch_probed > 0) {
    out.push_back("PROJ's operations between these CRSs depend on time ('" + impl_->epoch_probe +
                  "'), but their result does not depend on the epoch here: at 1990.0 and 2030.0 the " +
                  std::to_string(impl_->epoch_probed) + " points agree to " + format_shortest(impl_->epoch_free_worst_m) +
                  " m, so no epoch was needed");
  }
  if (auto w = impl_->source_area.warning()) out.push_back(*w);
  if (auto w = impl_->target_area.warning()) out.push_back(*w);
  if (impl_->set_aside > 0) {
    out.push_back(std::to_string(impl_->set_aside) + " points lie outside the area of use of the datum change PROJ "
                  "chose for them (PROJ judges areas by a box in the source CRS) and were moved by the most accurate "
                  "operation whose area holds them; the first is " + impl_->first_set_aside);
  }
  if (impl_->fallbacks > 0) {
    std::string why;
    for (const auto& r : impl_->fallback_reasons) why += (why.empty() ? "" : "; ") + r;
    out.push_back(std::to_string(impl_->fallbacks) + (impl_->fallbacks == 1 ? " point was" : " points were") +
                  " moved by a worse operation than PROJ's first choice for them (--allow-fallback): " + why + "; the first is " + impl_->first_fallback);
  }
  // Each operation that moved points with a stated accuracy worse than
  // 0.1 m, or none, is named with its area (issue 40 point 4): a zero
  // shift rated ±1 m must not pass as a datum change.
  constexpr double kCoarseOperation_m = 0.1;
  for (const auto& c : impl_->all) {
    if (c.info.points == 0 || (c.info.accuracy_m && *c.info.accuracy_m <= kCoarseOperation_m)) continue;
    out.push_back(std::to_string(c.info.points) + (c.info.points == 1 ? " point was" : " points were") +
                  " moved by PROJ's operation '" + c.info.name + "'" +
                  (c.info.identifier.empty() ? std::string() : " (" + c.info.identifier + ")") + ", " +
                  (c.info.accuracy_m ? "stated accuracy ±" + format_shortest(*c.info.accuracy_m) + " m"
                                     : std::string("no stated accuracy")) +
                  (c.info.area ? ", area of use: " + abridged(c.info.area->name) : std::string()) +
                  ": coarser than 0.1 m; the sidecar records the operation of each group of points");
  }
  return out;
}

std::string operation_record_json(const CrsOperation& op) {
  using nlohmann::ordered_json;
  ordered_json candidates = ordered_json::array();
  for (const auto& c : op.candidates()) {
    ordered_json grids = ordered_json::array();
    for (const auto& g : c.grids) {
      grids.push_back({{"name", g.name},
                       {"path", g.available ? ordered_json(g.path) : ordered_json(nullptr)},
                       {"sha256", g.available ? ordered_json(g.sha256) : ordered_json(nullptr)},
                       {"on_this_machine", g.available}});
    }
    candidates.push_back({{"name", c.name},
                          {"identifier", c.identifier.empty() ? ordered_json(nullptr) : ordered_json(c.identifier)},
                          {"accuracy_m", c.accuracy_m ? ordered_json(*c.accuracy_m) : ordered_json(nullptr)},
                          {"grids", grids},
                          {"proj_pipeline", c.proj_string.empty() ? ordered_json(nullptr) : ordered_json(c.proj_string)},
                          {"time_dependent", c.time_dependent},
                          {"points", c.points}});
  }
  const ordered_json record = {{"authority", "PROJ " + proj_version_text()},
                               {"epoch", op.epoch() ? ordered_json(*op.epoch()) : ordered_json(nullptr)},
                               {"candidates", candidates}};
  return record.dump();
}

}  // namespace geoanchor::io
