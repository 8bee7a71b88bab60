// The network plan's level of detail (issue 17 point 6, network_lod.hpp)
// on 10⁵ stations: every flagged line drawn one by one, every other line
// accounted for exactly once (in the bundle of its two cells, or inside
// one cell's mark), each bundle in the most telling class of its lines,
// every station in exactly one mark, and the drawing bounded by the cells
// rather than the network. And on a sparse plan, where every station has a
// cell of its own, the bundles are exactly the lines.
//
// Independent of the code under test: the cells are recomputed here from
// the documented rule (squares of cell_px from the area's top-left
// corner), and the most telling class from the documented order.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "geoanchor/gui/network_lod.hpp"

namespace geoanchor::gui {
namespace {

constexpr double kPixelTol_px = 1e-9;  // a mean of one position against the position

int documented_rank(MeasurementClass c) {
  // left out < untestable < small < elevated (network_lod.hpp)
  switch (c) {
    case MeasurementClass::left_out: return 0;
    case MeasurementClass::untestable: return 1;
    case MeasurementClass::small: return 2;
    case MeasurementClass::elevated: return 3;
    default: return 9;
  }
}

bool is_flagged(MeasurementClass c) { return c == MeasurementClass::failing || c == MeasurementClass::outlier; }

struct Plan {
  std::vector<Eigen::Vector2d> px;
  std::vector<bool> own;
  std::vector<NetworkLine> lines;
};

// n stations on a jittered grid filling `side_px`, each joined to its right
// and lower neighbours and one diagonal; most lines small, some elevated,
// untestable or left out, `flagged` of them outliers or failing; every
// 10 000th station held.
Plan grid_plan(std::size_t side, double side_px, std::size_t flagged, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3), u(0.0, 1.0);
  Plan p;
  const double step = side_px / static_cast<double>(side);
  for (std::size_t r = 0; r < side; ++r) {
    for (std::size_t c = 0; c < side; ++c) {
      p.px.emplace_back(10.0 + (static_cast<double>(c) + 0.5 + jitter(rng)) * step, 20.0 + (static_cast<double>(r) + 0.5 + jitter(rng)) * step);
      p.own.push_back(p.px.size() % 10000 == 1);
    }
  }
  const auto at = [&](std::size_t r, std::size_t c) { return r * side + c; };
  for (std::size_t r = 0; r < side; ++r) {
    for (std::size_t c = 0; c < side; ++c) {
      const std::pair<std::size_t, std::size_t> next[] = {{r, c + 1}, {r + 1, c}, {r + 1, c + 1}};
      for (const auto& [r2, c2] : next) {
        if (r2 >= side || c2 >= side) continue;
        NetworkLine l;
        l.from = at(r, c);
        l.to = at(r2, c2);
        l.measurement = p.lines.size();
        const double x = u(rng);
        l.shown_as = x < 0.9 ? MeasurementClass::small : x < 0.97 ? MeasurementClass::elevated : x < 0.99 ? MeasurementClass::untestable
                                                                                                    : MeasurementClass::left_out;
        l.used = l.shown_as != MeasurementClass::left_out;
        p.lines.push_back(l);
      }
    }
  }
  std::uniform_int_distribution<std::size_t> pick(0, p.lines.size() - 1);
  for (std::size_t k = 0; k < flagged; ++k) p.lines[pick(rng)].shown_as = k % 2 ? MeasurementClass::failing : MeasurementClass::outlier;
  return p;
}

std::pair<long, long> documented_cell(const Eigen::Vector2d& px, const LodArea& area, float cell) {
  return {static_cast<long>(std::floor((px.x() - area.left) / cell)), static_cast<long>(std::floor((px.y() - area.top) / cell))};
}

TEST(NetworkLod, TenToTheFiveStationsAreDrawnByCellsWithEveryFlaggedLineOnItsOwn) {
  const LodArea area{10.0f, 20.0f, 910.0f, 920.0f};
  const Plan p = grid_plan(317, 900.0, 12, 17);  // 100 489 stations, about 3·10⁵ lines
  ASSERT_GT(p.px.size(), 100000u);
  const PlanLod lod = plan_level_of_detail(p.px, p.own, p.lines, area);

  // Flagged lines: each one by one, none in a bundle.
  std::set<std::size_t> flagged, drawn(lod.lines.begin(), lod.lines.end());
  for (std::size_t i = 0; i < p.lines.size(); ++i) {
    if (is_flagged(p.lines[i].shown_as)) flagged.insert(i);
  }
  EXPECT_EQ(drawn, flagged);
  EXPECT_EQ(lod.lines.size(), flagged.size());

  // Every other line exactly once: in the bundle of its cells, or within a cell.
  std::map<std::pair<std::pair<long, long>, std::pair<long, long>>, std::pair<int, std::size_t>> expected;  // (rank, lines)
  std::size_t within = 0;
  for (const auto& l : p.lines) {
    if (is_flagged(l.shown_as)) continue;
    auto a = documented_cell(p.px[l.from], area, kLodCell_px), b = documented_cell(p.px[l.to], area, kLodCell_px);
    if (a == b) {
      ++within;
      continue;
    }
    if (b < a) std::swap(a, b);
    auto& e = expected[{a, b}];
    e.first = std::max(e.first, documented_rank(l.shown_as));
    ++e.second;
  }
  EXPECT_EQ(lod.lines_culled, 0u);
  EXPECT_EQ(lod.lines_within_cells, within);
  EXPECT_EQ(lod.lines_in_bundles + lod.lines_within_cells + lod.lines.size(), p.lines.size());
  ASSERT_EQ(lod.bundles.size(), expected.size());
  std::size_t bundled = 0;
  for (const auto& b : lod.bundles) {
    auto ca = documented_cell(b.a_px, area, kLodCell_px), cb = documented_cell(b.b_px, area, kLodCell_px);
    if (cb < ca) std::swap(ca, cb);
    const auto it = expected.find({ca, cb});
    ASSERT_NE(it, expected.end()) << "a bundle between cells that no line joins";
    EXPECT_EQ(documented_rank(b.shown_as), it->second.first);
    EXPECT_EQ(b.lines, it->second.second);
    bundled += b.lines;
  }
  EXPECT_EQ(bundled, lod.lines_in_bundles);

  // Every station in exactly one mark: its own (held) or its cell's.
  std::size_t own = 0, in_marks = 0;
  for (bool o : p.own) own += o ? 1u : 0u;
  for (const auto& m : lod.marks) in_marks += m.stations;
  EXPECT_EQ(lod.stations.size(), own);
  EXPECT_EQ(in_marks + lod.stations.size(), p.px.size());

  // What is drawn is bounded by the cells, not by the network: at most one
  // mark per cell and, on this grid, a few bundles per cell.
  const double cells = (900.0 / kLodCell_px) * (900.0 / kLodCell_px);
  EXPECT_LE(static_cast<double>(lod.marks.size()), cells);
  EXPECT_LT(static_cast<double>(lod.bundles.size()), 0.5 * static_cast<double>(p.lines.size()));
}

TEST(NetworkLod, OnASparsePlanTheBundlesAreExactlyTheLines) {
  const LodArea area{0.0f, 0.0f, 1000.0f, 800.0f};
  const Plan p = grid_plan(20, 780.0, 2, 3);  // 400 stations, 39 px apart
  const PlanLod lod = plan_level_of_detail(p.px, {}, p.lines, area);
  EXPECT_EQ(lod.lines_within_cells, 0u);
  EXPECT_EQ(lod.marks.size(), p.px.size());
  for (const auto& m : lod.marks) EXPECT_EQ(m.stations, 1u);
  std::size_t plain = 0;
  for (const auto& l : p.lines) plain += is_flagged(l.shown_as) ? 0u : 1u;
  ASSERT_EQ(lod.bundles.size(), plain);
  std::size_t k = 0;
  for (const auto& l : p.lines) {
    if (is_flagged(l.shown_as)) continue;
    const LodBundle& b = lod.bundles[k++];
    EXPECT_LE((b.a_px - p.px[l.from]).norm(), kPixelTol_px);
    EXPECT_LE((b.b_px - p.px[l.to]).norm(), kPixelTol_px);
    EXPECT_EQ(b.shown_as, l.shown_as);
    EXPECT_EQ(b.lines, 1u);
  }
}

TEST(NetworkLod, WhatIsOutsideTheAreaIsCulled) {
  const Plan p = grid_plan(100, 1000.0, 4, 5);
  const LodArea quarter{10.0f, 20.0f, 260.0f, 270.0f};  // the top-left quarter of the grid
  const PlanLod lod = plan_level_of_detail(p.px, p.own, p.lines, quarter);
  EXPECT_GT(lod.lines_culled, p.lines.size() / 2);
  const double margin = kLodCell_px;
  for (const auto& m : lod.marks) {
    EXPECT_GE(m.px.x(), quarter.left - margin);
    EXPECT_LE(m.px.x(), quarter.right + margin);
    EXPECT_GE(m.px.y(), quarter.top - margin);
    EXPECT_LE(m.px.y(), quarter.bottom + margin);
  }
  EXPECT_EQ(lod.lines_in_bundles + lod.lines_within_cells + lod.lines.size() + lod.lines_culled, p.lines.size());
}

TEST(NetworkLod, ABadCellOrLineIsRefused) {
  const Plan p = grid_plan(3, 30.0, 0, 1);
  EXPECT_THROW(plan_level_of_detail(p.px, p.own, p.lines, LodArea{0, 0, 100, 100}, 0.0f), std::invalid_argument);
  EXPECT_THROW(plan_level_of_detail(p.px, p.own, p.lines, LodArea{0, 0, 100, 100}, std::nanf("")), std::invalid_argument);
  auto lines = p.lines;
  lines.front().to = p.px.size();
  EXPECT_THROW(plan_level_of_detail(p.px, p.own, lines, LodArea{0, 0, 100, 100}), std::invalid_argument);
  EXPECT_THROW(plan_level_of_detail(p.px, std::vector<bool>(2, false), p.lines, LodArea{0, 0, 100, 100}), std::invalid_argument);
}

}  // namespace
}  // namespace geoanchor::gui
