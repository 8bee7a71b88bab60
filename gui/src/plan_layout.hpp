#pragma once
// Geometry shared by the plans (the fit's plan and the network view),
// private to gui/: an arrow, label boxes and where a label may go without
// covering a mark, an arrow, a line or another label.

#include <imgui.h>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

namespace geoanchor::gui::detail {

inline ImVec2 iv(const Eigen::Vector2d& p) { return ImVec2(static_cast<float>(p.x()), static_cast<float>(p.y())); }

// An arrow from `a` to `b` with a filled head `head` pixels long.
inline void arrow(ImDrawList* dl, const Eigen::Vector2d& a, const Eigen::Vector2d& b, ImU32 c, float thickness, float head) {
  const Eigen::Vector2d d = b - a;
  const double len = d.norm();
  if (len < 1.0) return;
  const Eigen::Vector2d u = d / len, n(-u.y(), u.x());
  const double h = std::min<double>(head, 0.6 * len);
  const Eigen::Vector2d base = b - h * u;
  dl->AddLine(iv(a), iv(base), c, thickness);
  dl->AddTriangleFilled(iv(b), iv(base + 0.45 * h * n), iv(base - 0.45 * h * n), c);
}

struct Box {
  float x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool overlaps(const Box& o) const { return x0 < o.x1 && o.x0 < x1 && y0 < o.y1 && o.y0 < y1; }
  bool inside(const Box& o) const { return x0 >= o.x0 && y0 >= o.y0 && x1 <= o.x1 && y1 <= o.y1; }
};

// Whether the segment a–b passes through the box (Liang–Barsky).
inline bool segment_hits(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Box& r) {
  double t0 = 0.0, t1 = 1.0;
  const double d[2] = {b.x() - a.x(), b.y() - a.y()};
  const double lo[2] = {r.x0 - a.x(), r.y0 - a.y()}, hi[2] = {r.x1 - a.x(), r.y1 - a.y()};
  for (int k = 0; k < 2; ++k) {
    if (d[k] == 0.0) {
      if (lo[k] > 0.0 || hi[k] < 0.0) return false;
      continue;
    }
    double ta = lo[k] / d[k], tb = hi[k] / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

// What labels must not cover: marks, arrows, labels already placed. A
// uniform grid over the plan keeps each query to the items nearby.
class Obstacles {
 public:
  Obstacles(const Box& area, float cell) : area_(area), cell_(std::max(cell, 4.0f)) {
    cols_ = std::max(1, static_cast<int>(std::ceil((area.x1 - area.x0) / cell_)));
    rows_ = std::max(1, static_cast<int>(std::ceil((area.y1 - area.y0) / cell_)));
    cells_.resize(static_cast<std::size_t>(cols_ * rows_));
  }
  void add(const Box& b) {
    boxes_.push_back(b);
    insert(b, static_cast<int>(boxes_.size()));
  }
  void add(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    segments_.emplace_back(a, b);
    const Box bb{static_cast<float>(std::min(a.x(), b.x())), static_cast<float>(std::min(a.y(), b.y())),
                 static_cast<float>(std::max(a.x(), b.x())), static_cast<float>(std::max(a.y(), b.y()))};
    insert(bb, -static_cast<int>(segments_.size()));
  }
  bool free(const Box& b) const {
    const auto [c0, r0, c1, r1] = span(b);
    for (int r = r0; r <= r1; ++r) {
      for (int c = c0; c <= c1; ++c) {
        for (int item : cells_[static_cast<std::size_t>(r * cols_ + c)]) {
          if (item > 0 ? boxes_[static_cast<std::size_t>(item - 1)].overlaps(b)
                       : segment_hits(segments_[static_cast<std::size_t>(-item - 1)].first,
                                      segments_[static_cast<std::size_t>(-item - 1)].second, b)) {
            return false;
          }
        }
      }
    }
    return true;
  }

 private:
  std::array<int, 4> span(const Box& b) const {
    const auto cx = [&](float x) { return std::clamp(static_cast<int>(std::floor((x - area_.x0) / cell_)), 0, cols_ - 1); };
    const auto cy = [&](float y) { return std::clamp(static_cast<int>(std::floor((y - area_.y0) / cell_)), 0, rows_ - 1); };
    return {cx(b.x0), cy(b.y0), cx(b.x1), cy(b.y1)};
  }
  void insert(const Box& b, int item) {
    const auto [c0, r0, c1, r1] = span(b);
    for (int r = r0; r <= r1; ++r) {
      for (int c = c0; c <= c1; ++c) cells_[static_cast<std::size_t>(r * cols_ + c)].push_back(item);
    }
  }
  Box area_;
  float cell_;
  int cols_ = 1, rows_ = 1;
  std::vector<std::vector<int>> cells_;
  std::vector<Box> boxes_;
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> segments_;
};

// Candidate boxes for a label w × h beside a mark at p (radius r): eight
// directions, nearest first, turned away from the mark's own arrow `away`;
// then the same further out (drawn with a leader line).
inline std::vector<std::pair<Box, bool>> candidates(const Eigen::Vector2d& p, float r, float w, float h, const Eigen::Vector2d& arrow_px,
                                             float step) {
  static const Eigen::Vector2d kDirections[8] = {{1, 0},          {-1, 0},         {0.7071, -0.7071}, {0.7071, 0.7071},
                                                 {-0.7071, -0.7071}, {-0.7071, 0.7071}, {0, -1},          {0, 1}};
  std::array<int, 8> order{0, 1, 2, 3, 4, 5, 6, 7};
  if (arrow_px.norm() > 1.0) {
    const Eigen::Vector2d away = -arrow_px.normalized();
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return kDirections[a].dot(away) > kDirections[b].dot(away); });
  }
  std::vector<std::pair<Box, bool>> out;
  for (const float ring : {0.0f, 1.0f, 2.5f, 4.0f}) {
    const double d = r + 3.0 + ring * step;
    for (int k : order) {
      const Eigen::Vector2d u = kDirections[k];
      // The box's point nearest the mark sits at distance d along u.
      const Eigen::Vector2d q = p + d * u;
      const float x0 = u.x() > 0.3 ? static_cast<float>(q.x()) : u.x() < -0.3 ? static_cast<float>(q.x()) - w : static_cast<float>(q.x()) - 0.5f * w;
      const float y0 = u.y() > 0.3 ? static_cast<float>(q.y()) : u.y() < -0.3 ? static_cast<float>(q.y()) - h : static_cast<float>(q.y()) - 0.5f * h;
      out.push_back({Box{x0, y0, x0 + w, y0 + h}, ring > 0.0f});
    }
  }
  return out;
}

}  // namespace geoanchor::gui::detail
