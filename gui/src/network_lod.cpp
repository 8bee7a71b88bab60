// The network plan's level of detail (network_lod.hpp).

#include "geoanchor/gui/network_lod.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace geoanchor::gui {
namespace {

// How telling a bundled class is: a bundle shows its most telling line.
int rank(MeasurementClass c) {
  switch (c) {
    case MeasurementClass::left_out: return 0;
    case MeasurementClass::untestable: return 1;
    case MeasurementClass::small: return 2;
    case MeasurementClass::elevated: return 3;
    case MeasurementClass::failing: return 4;
    case MeasurementClass::outlier: return 5;
  }
  return 0;
}

bool flagged(MeasurementClass c) { return c == MeasurementClass::failing || c == MeasurementClass::outlier; }

// Whether the box spanned by a and b overlaps the area grown by `margin`.
bool in_view(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const LodArea& area, double margin) {
  return std::max(a.x(), b.x()) >= area.left - margin && std::min(a.x(), b.x()) <= area.right + margin &&
         std::max(a.y(), b.y()) >= area.top - margin && std::min(a.y(), b.y()) <= area.bottom + margin;
}

}  // namespace

PlanLod plan_level_of_detail(const std::vector<Eigen::Vector2d>& station_px, const std::vector<bool>& own_mark,
                             const std::vector<NetworkLine>& lines, const LodArea& area, float cell_px) {
  if (!(cell_px > 0.0f) || !std::isfinite(cell_px)) {
    throw std::invalid_argument("plan_level_of_detail: cell_px=" + std::to_string(cell_px) + ": expected a positive finite size");
  }
  if (!own_mark.empty() && own_mark.size() != station_px.size()) {
    throw std::invalid_argument("plan_level_of_detail: own_mark has " + std::to_string(own_mark.size()) + " entries for " +
                                std::to_string(station_px.size()) + " stations");
  }
  const std::size_t n = station_px.size();
  constexpr std::uint32_t kNoCell = ~0u;
  const double cell = cell_px;
  // Each station's cell; cells numbered in the order their first station comes.
  std::vector<std::uint32_t> cell_of(n, kNoCell);
  std::vector<Eigen::Vector2d> sum;       // per cell: the sum of its stations' pixels
  std::vector<std::size_t> count, marked; // per cell: its stations, and those without a mark of their own
  std::vector<bool> used_in;              // per cell: one of its marked stations is used
  std::unordered_map<std::uint64_t, std::uint32_t> index;
  index.reserve(n);
  for (std::size_t s = 0; s < n; ++s) {
    const Eigen::Vector2d& p = station_px[s];
    if (!std::isfinite(p.x()) || !std::isfinite(p.y())) continue;  // never drawn
    const double cx = std::floor((p.x() - area.left) / cell), cy = std::floor((p.y() - area.top) / cell);
    // Far outside the area (a view zoomed in a long way): clamp, these
    // cells are culled below anyway.
    const auto clamp = [](double v) { return static_cast<std::int64_t>(std::clamp(v, -1e9, 1e9)); };
    const std::uint64_t key = (static_cast<std::uint64_t>(clamp(cx) + (std::int64_t{1} << 31)) << 32) |
                              static_cast<std::uint64_t>(clamp(cy) + (std::int64_t{1} << 31));
    const auto [it, fresh] = index.emplace(key, static_cast<std::uint32_t>(sum.size()));
    if (fresh) {
      sum.push_back(Eigen::Vector2d::Zero());
      count.push_back(0);
      marked.push_back(0);
      used_in.push_back(false);
    }
    const std::uint32_t c = it->second;
    cell_of[s] = c;
    sum[c] += p;
    ++count[c];
  }
  const std::size_t cells = sum.size();
  std::vector<Eigen::Vector2d> centre(cells);
  for (std::size_t c = 0; c < cells; ++c) centre[c] = sum[c] / static_cast<double>(count[c]);

  PlanLod out;
  const double margin = cell;
  // Stations: their own marks, else their cell's.
  std::vector<Eigen::Vector2d> mark_sum(cells, Eigen::Vector2d::Zero());
  for (std::size_t s = 0; s < n; ++s) {
    if (cell_of[s] == kNoCell) continue;
    if (!own_mark.empty() && own_mark[s]) {
      if (in_view(station_px[s], station_px[s], area, margin)) out.stations.push_back(s);
      continue;
    }
    mark_sum[cell_of[s]] += station_px[s];
    ++marked[cell_of[s]];
  }
  // A used station makes its cell's mark ink: NetworkLine::used says which
  // stations a used measurement joins.
  for (const auto& l : lines) {
    if (l.from >= n || l.to >= n) {
      throw std::invalid_argument("plan_level_of_detail: a line joins station " + std::to_string(std::max(l.from, l.to)) + " of " +
                                  std::to_string(n));
    }
    if (!l.used) continue;
    for (std::size_t s : {l.from, l.to}) {
      if (cell_of[s] != kNoCell) used_in[cell_of[s]] = true;
    }
  }
  for (std::size_t c = 0; c < cells; ++c) {
    if (marked[c] == 0) continue;
    const Eigen::Vector2d p = mark_sum[c] / static_cast<double>(marked[c]);
    if (in_view(p, p, area, margin)) out.marks.push_back({p, marked[c], used_in[c]});
  }

  // Lines: flagged ones alone; the others into their cells' bundle.
  std::unordered_map<std::uint64_t, std::size_t> bundle_of;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const NetworkLine& l = lines[i];
    const std::uint32_t a = cell_of[l.from], b = cell_of[l.to];
    if (a == kNoCell || b == kNoCell) {
      ++out.lines_culled;
      continue;
    }
    if (flagged(l.shown_as)) {
      if (in_view(station_px[l.from], station_px[l.to], area, margin)) out.lines.push_back(i);
      else ++out.lines_culled;
      continue;
    }
    if (a == b) {
      if (in_view(centre[a], centre[a], area, margin)) ++out.lines_within_cells;
      else ++out.lines_culled;
      continue;
    }
    if (!in_view(centre[a], centre[b], area, margin)) {
      ++out.lines_culled;
      continue;
    }
    const std::uint64_t key = static_cast<std::uint64_t>(std::min(a, b)) * cells + std::max(a, b);
    const auto [it, fresh] = bundle_of.emplace(key, out.bundles.size());
    if (fresh) out.bundles.push_back({centre[a], centre[b], l.shown_as, 0});
    LodBundle& bundle = out.bundles[it->second];
    if (rank(l.shown_as) > rank(bundle.shown_as)) bundle.shown_as = l.shown_as;
    ++bundle.lines;
    ++out.lines_in_bundles;
  }
  for (const auto& b : out.bundles) ++out.bundles_by_class[static_cast<std::size_t>(b.shown_as)];
  return out;
}

}  // namespace geoanchor::gui
