// The plan: control points in ENU (north up, equal scale) with residual
// arrows, the vertical residual as colour, a scale bar and a legend.

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "geoanchor/gui/workbench_ui.hpp"
#include "ui_common.hpp"

namespace geoanchor::gui {

using detail::col;

namespace {

ImVec2 iv(const Eigen::Vector2d& p) { return ImVec2(static_cast<float>(p.x()), static_cast<float>(p.y())); }

// An arrow from `a` to `b` with a filled head `head` pixels long.
void arrow(ImDrawList* dl, const Eigen::Vector2d& a, const Eigen::Vector2d& b, ImU32 c, float thickness, float head) {
  const Eigen::Vector2d d = b - a;
  const double len = d.norm();
  if (len < 1.0) return;
  const Eigen::Vector2d u = d / len, n(-u.y(), u.x());
  const double h = std::min<double>(head, 0.6 * len);
  const Eigen::Vector2d base = b - h * u;
  dl->AddLine(iv(a), iv(base), c, thickness);
  dl->AddTriangleFilled(iv(b), iv(base + 0.45 * h * n), iv(base - 0.45 * h * n), c);
}

}  // namespace

void WorkbenchUi::draw_plan() {
  ImDrawList* dl = ImGui::GetWindowDrawList();
  const float font = ImGui::GetFontSize();
  const ImVec2 c0 = ImGui::GetCursorScreenPos();
  const ImVec2 avail = ImGui::GetContentRegionAvail();
  const float legend_w = std::round(font * 7.5f), footer_h = std::round(font * 3.0f);
  PlanGeometry& g = plan_;
  g.left = c0.x;
  g.top = c0.y;
  g.right = c0.x + std::max(avail.x - legend_w, 4 * kPlanMarginPx);
  g.bottom = c0.y + std::max(avail.y - footer_h, 4 * kPlanMarginPx);

  // Scale: the points' bounding box fitted with the margin.
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& r : rows_) {
    lo = lo.cwiseMin(r.plan_en_m);
    hi = hi.cwiseMax(r.plan_en_m);
  }
  if (rows_.empty()) lo = hi = Eigen::Vector2d::Zero();
  g.center_en_m = 0.5 * (lo + hi);
  const Eigen::Vector2d span = (hi - lo).cwiseMax(1.0);
  g.px_per_m = std::min((g.right - g.left - 2 * kPlanMarginPx) / span.x(), (g.bottom - g.top - 2 * kPlanMarginPx) / span.y());

  // Arrows: the largest horizontal residual of a used point drawn about an
  // eighth of the plan's short side, the factor rounded to 1, 2 or 5 × 10^k.
  // Outliers are drawn at the same factor (clipped to the plan, their size
  // written beside them) so that the used points' pattern stays readable.
  double max_h_m = 0.0, max_u_mm = 0.0;
  for (const auto& r : rows_) {
    if (!r.used) continue;
    max_h_m = std::max(max_h_m, 1e-3 * r.residual_enu_mm.head<2>().norm());
    max_u_mm = std::max(max_u_mm, std::abs(r.residual_enu_mm.z()));
  }
  const double short_side_px = std::min(g.right - g.left, g.bottom - g.top);
  g.arrow_exaggeration = max_h_m > 0 ? detail::nice_floor(0.125 * short_side_px / (g.px_per_m * max_h_m)) : 1.0;
  g.du_limit_mm = detail::nice_ceil(std::max(max_u_mm, 1.0));
  g.drawn = true;

  dl->AddRectFilled(ImVec2(g.left, g.top), ImVec2(g.right, g.bottom), col(palette::kBackground));
  dl->AddRect(ImVec2(g.left, g.top), ImVec2(g.right, g.bottom), col(palette::kGrid));
  dl->PushClipRect(ImVec2(g.left, g.top), ImVec2(g.right, g.bottom), true);
  const double k = g.arrow_exaggeration * g.px_per_m;  // pixels per metre of residual
  const float r_px = std::max(3.0f, std::round(font * 0.3f));
  const auto residual_px = [&](const PointRow& r) {
    return Eigen::Vector2d(k * 1e-3 * r.residual_enu_mm.x(), -k * 1e-3 * r.residual_enu_mm.y());
  };
  // Left-out and unused points under the rest, then used points, outliers on
  // top. A dense plan (more than kDensePlanMarks marks) draws its marks as
  // small squares and its arrows without antialiasing, labels only the
  // outliers: a tenth of the geometry, and at that density the marks
  // overlap anyway.
  const bool dense = rows_.size() > kDensePlanMarks;
  const ImDrawListFlags aa = dl->Flags;
  if (dense) dl->Flags &= ~(ImDrawListFlags_AntiAliasedLines | ImDrawListFlags_AntiAliasedFill);
  const float rd = std::max(2.0f, std::round(r_px * 0.6f));
  for (const auto& r : rows_) {
    if (r.used || r.outlier) continue;
    const Eigen::Vector2d p = g.pixel_of(r.plan_en_m);
    if (dense) {
      dl->AddRect(ImVec2(static_cast<float>(p.x()) - rd, static_cast<float>(p.y()) - rd),
                  ImVec2(static_cast<float>(p.x()) + rd, static_cast<float>(p.y()) + rd), col(palette::kLeftOut));
      continue;
    }
    dl->AddCircle(iv(p), r_px, col(palette::kLeftOut), 12, 1.5f);
    dl->AddText(ImVec2(static_cast<float>(p.x()) + r_px + 2, static_cast<float>(p.y()) - font * 0.5f), col(palette::kLeftOut),
                r.id.c_str());
  }
  for (const auto& r : rows_) {
    if (!r.used) continue;
    const Eigen::Vector2d p = g.pixel_of(r.plan_en_m);
    const Rgb fill = palette::diverging(r.residual_enu_mm.z() / g.du_limit_mm);
    if (dense) {
      arrow(dl, p, p + residual_px(r), col(palette::kInk), 1.0f, font * 0.4f);
      dl->AddRectFilled(ImVec2(static_cast<float>(p.x()) - rd, static_cast<float>(p.y()) - rd),
                        ImVec2(static_cast<float>(p.x()) + rd, static_cast<float>(p.y()) + rd), col(fill));
      continue;
    }
    arrow(dl, p, p + residual_px(r), col(palette::kInk), 1.5f, font * 0.55f);
    dl->AddCircleFilled(iv(p), r_px, col(fill), 12);
    dl->AddCircle(iv(p), r_px, col(palette::kInk), 12, 1.0f);
  }
  dl->Flags = aa;
  ImGui::PushFont(ImGui::GetIO().Fonts->Fonts[1]);
  for (const auto& r : rows_) {
    if (!r.outlier) continue;
    const Eigen::Vector2d p = g.pixel_of(r.plan_en_m);
    // Shortened to a quarter of the plan's short side at most (the label gives the size).
    Eigen::Vector2d d = residual_px(r);
    if (d.norm() > 0.25 * short_side_px) d *= 0.25 * short_side_px / d.norm();
    arrow(dl, p, p + d, col(palette::kOutlier), 3.0f, font * 0.8f);
    const float s = r_px + 2;
    dl->AddRect(ImVec2(static_cast<float>(p.x()) - s, static_cast<float>(p.y()) - s),
                ImVec2(static_cast<float>(p.x()) + s, static_cast<float>(p.y()) + s), col(palette::kOutlier), 0, 0, 2.5f);
    const std::string label = r.id + " outlier, " + detail::fmt("%.0f mm", r.residual_enu_mm.norm());
    // Beside the square, on the side away from the arrow.
    const float tx = d.x() > 0 ? static_cast<float>(p.x()) - s - 4 - ImGui::CalcTextSize(label.c_str()).x
                               : static_cast<float>(p.x()) + s + 4;
    dl->AddText(ImVec2(tx, static_cast<float>(p.y()) + (d.y() < 0 ? 2.0f : -font - 2.0f)), col(palette::kOutlier), label.c_str());
  }
  ImGui::PopFont();
  // North arrow.
  const ImVec2 na(g.left + font * 1.2f, g.top + font * 3.0f);
  dl->AddTriangleFilled(ImVec2(na.x, na.y - font * 1.6f), ImVec2(na.x - font * 0.4f, na.y), ImVec2(na.x + font * 0.4f, na.y),
                        col(palette::kInk));
  dl->AddText(ImVec2(na.x - font * 0.3f, na.y + 2), col(palette::kInk), "N");
  dl->PopClipRect();

  // Footer: scale bar and what the arrows mean.
  g.scale_bar_m = detail::nice_floor(0.25 * (g.right - g.left) / g.px_per_m);
  const float bar_px = static_cast<float>(g.scale_bar_m * g.px_per_m);
  const float by = g.bottom + font * 0.7f, bx = g.left + font * 0.5f;
  dl->AddRectFilled(ImVec2(bx, by), ImVec2(bx + bar_px, by + 4), col(palette::kInk));
  dl->AddLine(ImVec2(bx, by - 4), ImVec2(bx, by + 8), col(palette::kInk), 1.5f);
  dl->AddLine(ImVec2(bx + bar_px, by - 4), ImVec2(bx + bar_px, by + 8), col(palette::kInk), 1.5f);
  dl->AddText(ImVec2(bx + bar_px + font * 0.5f, by - font * 0.5f), col(palette::kInk), detail::length_label(g.scale_bar_m).c_str());
  const double mm_per_10px = 10.0 / k * 1e3;
  const std::string caption = "arrows: horizontal residual × " + detail::fmt("%g", g.arrow_exaggeration) + " (10 px = " +
                              detail::fmt("%.2g", mm_per_10px) + " mm); outliers' arrows shortened to fit";
  dl->AddText(ImVec2(bx, by + font * 0.6f), col(palette::kInk), caption.c_str());

  // Legend: the vertical residual's colour scale, and the point symbols.
  const float lx = g.right + font * 1.0f, ly0 = g.top + font * 1.6f, lh = std::min(font * 12.0f, (g.bottom - g.top) * 0.5f);
  const float lw = font * 1.2f;
  dl->AddText(ImVec2(lx, g.top), col(palette::kInk), "dU (mm)");
  constexpr int kSteps = 64;
  for (int i = 0; i < kSteps; ++i) {
    const double t = 1.0 - 2.0 * (i + 0.5) / kSteps;
    const float y0 = ly0 + lh * static_cast<float>(i) / kSteps, y1 = ly0 + lh * static_cast<float>(i + 1) / kSteps;
    dl->AddRectFilled(ImVec2(lx, y0), ImVec2(lx + lw, y1), col(palette::diverging(t)));
  }
  dl->AddRect(ImVec2(lx, ly0), ImVec2(lx + lw, ly0 + lh), col(palette::kInk));
  const auto tick = [&](float y, const std::string& s) {
    dl->AddLine(ImVec2(lx + lw, y), ImVec2(lx + lw + 4, y), col(palette::kInk));
    dl->AddText(ImVec2(lx + lw + 6, y - font * 0.5f), col(palette::kInk), s.c_str());
  };
  tick(ly0, detail::fmt("+%g", g.du_limit_mm));
  tick(ly0 + lh * 0.5f, "0");
  tick(ly0 + lh, detail::fmt("−%g", g.du_limit_mm));
  float sy = ly0 + lh + font * 1.5f;
  dl->AddRect(ImVec2(lx, sy), ImVec2(lx + r_px * 2 + 4, sy + r_px * 2 + 4), col(palette::kOutlier), 0, 0, 2.5f);
  dl->AddText(ImVec2(lx + r_px * 2 + 10, sy), col(palette::kOutlier), "outlier");
  sy += font * 1.5f;
  dl->AddCircle(ImVec2(lx + r_px + 2, sy + r_px + 2), r_px, col(palette::kLeftOut), 12, 1.5f);
  dl->AddText(ImVec2(lx + r_px * 2 + 10, sy), col(palette::kLeftOut), "not used");

  // Clicking a point leaves it out or takes it back (not for use = 0 points).
  ImGui::InvisibleButton("plan", ImVec2(g.right - g.left, g.bottom - g.top));
  if (ImGui::IsItemClicked()) {
    const ImVec2 m = ImGui::GetIO().MousePos;
    const PointRow* best = nullptr;
    double best_d = 2.5 * r_px;
    for (const auto& r : rows_) {
      const double d = (g.pixel_of(r.plan_en_m) - Eigen::Vector2d(m.x, m.y)).norm();
      if (d < best_d) {
        best_d = d;
        best = &r;
      }
    }
    if (best) model_.set_left_out(best->id, !best->left_out);
  }
}

}  // namespace geoanchor::gui
