// The plan: control points in ENU (north up, equal scale) with residual
// arrows and residual ellipses, the vertical residual as colour, every
// mark's id, a scale bar and a legend.

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "geoanchor/gui/workbench_ui.hpp"
#include "plan_layout.hpp"
#include "ui_common.hpp"

namespace geoanchor::gui {

using detail::arrow;
using detail::Box;
using detail::candidates;
using detail::iv;
using detail::col;
using detail::Obstacles;

namespace {

std::string outlier_label(const PointRow& r) { return r.id + " outlier, " + detail::fmt("%.0f mm", r.residual_enu_mm.norm()); }

}  // namespace

// One frame of the plan: what draw_plan works out before it draws (the
// geometry itself is plan_), shared by its steps.
struct WorkbenchUi::PlanFrame {
  ImDrawList* dl = nullptr;
  ImFont* regular = nullptr;
  ImFont* bold = nullptr;
  float font = 0.0f;
  float id_size = 0.0f;  // ids of marks that are not outliers
  ImVec2 c0, avail;
  bool dense = false;
  float r_px = 0.0f, rd = 0.0f;
  float swatch = 0.0f;
  std::string ellipse_entry;
  float legend_w = 0.0f;
  float wrap_w = 0.0f;
  float footer_h = 0.0f;
  std::string caption;
  double max_h_m = 0.0, max_u_mm = 0.0;
  Eigen::Vector2d span = Eigen::Vector2d::Zero();
  std::vector<PlanLabel> labels;
  std::vector<std::string> unlabelled;
  double short_side_px = 0.0, k = 0.0;  // k: pixels per metre of residual
  bool cached = false;

  Eigen::Vector2d residual_px(const PointRow& r) const {
    return Eigen::Vector2d(k * 1e-3 * r.residual_enu_mm.x(), -k * 1e-3 * r.residual_enu_mm.y());
  }
  // An outlier's arrow is shortened to a quarter of the plan's short side at most.
  Eigen::Vector2d drawn_arrow_px(const PointRow& r) const {
    Eigen::Vector2d d = residual_px(r);
    if (r.outlier && d.norm() > 0.25 * short_side_px) d *= 0.25 * short_side_px / d.norm();
    return d;
  }
};

void WorkbenchUi::draw_plan() {
  PlanFrame f;
  begin_plan(f);
  measure_plan(f);
  layout_plan(f);
  PlanGeometry& g = plan_;
  ImDrawList* dl = f.dl;
  const float font = f.font;
  const ImVec2 c0 = f.c0;
  const ImVec2 avail = f.avail;
  const std::string& caption = f.caption;
  const bool cached = f.cached;
  PlanLayout& cache = plan_layout_;
  g.drawn = true;
  g.labels = f.labels;
  g.unlabelled = f.unlabelled;
  g.hovered.clear();
  g.ellipses_drawn = 0;
  if (!cached) cache = {shown_generation_, c0.x, c0.y, avail.x, avail.y, font, g, caption};

  dl->AddRectFilled(ImVec2(g.left, g.top), ImVec2(g.right, g.bottom), col(palette::kBackground));
  dl->AddRect(ImVec2(g.left, g.top), ImVec2(g.right, g.bottom), col(palette::kGrid));
  dl->PushClipRect(ImVec2(g.left, g.top), ImVec2(g.right, g.bottom), true);
  // Ellipses under everything else, then left-out and unused points, used
  // points, outliers on top. A dense plan (more than kDensePlanMarks marks)
  // draws no ellipses, its marks as small squares and its arrows without
  // antialiasing, and labels only the outliers: a tenth of the geometry,
  // and at that density the marks overlap anyway.
  draw_plan_ellipses(f);
  draw_plan_marks(f);
  draw_plan_labels(f);
  detail::north_arrow(audit_, dl, g.left, g.top, font, "plan: north arrow");
  dl->PopClipRect();

  draw_plan_footer(f);
  draw_plan_legend(f);
  plan_pointer(f);
}

// The fonts, the marks' sizes and the legend column.
void WorkbenchUi::begin_plan(PlanFrame& f) {
  f.dl = ImGui::GetWindowDrawList();
  f.regular = ImGui::GetIO().Fonts->Fonts[0];
  f.bold = ImGui::GetIO().Fonts->Fonts[1];
  f.font = ImGui::GetFontSize();
  const float font = f.font;
  f.id_size = std::round(font * 0.8f);  // ids of marks that are not outliers
  f.c0 = ImGui::GetCursorScreenPos();
  f.avail = ImGui::GetContentRegionAvail();
  PlanGeometry& g = plan_;
  g.labels.clear();
  g.unlabelled.clear();
  g.hovered.clear();
  g.ellipses_drawn = 0;
  g.ellipse_k = chi2_2d_factor(kEllipseProbability);
  f.dense = rows_.size() > kDensePlanMarks;
  f.r_px = std::max(3.0f, std::round(font * 0.3f));
  f.rd = std::max(2.0f, std::round(f.r_px * 0.6f));

  // Legend column: as wide as its widest entry.
  f.swatch = font * 1.2f;
  const float swatch = f.swatch;
  f.ellipse_entry = detail::fmt("%.0f %% ellipse", 100.0 * kEllipseProbability);
  const std::string& ellipse_entry = f.ellipse_entry;
  float& legend_w = f.legend_w;
  for (const char* s : {"dU (mm)", "outlier", "not used"}) legend_w = std::max(legend_w, detail::text_size(s).x);
  legend_w = std::max(legend_w, detail::text_size(ellipse_entry).x + swatch + font * 0.5f);
  legend_w = std::max(legend_w, swatch + 6.0f + detail::text_size("−1000").x);
  legend_w = std::round(legend_w + font * 1.5f);
}

// The residuals' largest sizes and the marks' extent and centre.
void WorkbenchUi::measure_plan(PlanFrame& f) {
  PlanGeometry& g = plan_;
  const float font = f.font;
  const ImVec2 avail = f.avail;
  f.wrap_w = std::max(avail.x - font * 0.5f, font * 4.0f);
  f.footer_h = std::round(font * 3.0f);
  double& max_h_m = f.max_h_m;
  double& max_u_mm = f.max_u_mm;
  for (const auto& r : rows_) {
    if (!r.used) continue;
    max_h_m = std::max(max_h_m, 1e-3 * r.residual_enu_mm.head<2>().norm());
    max_u_mm = std::max(max_u_mm, std::abs(r.residual_enu_mm.z()));
  }
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& r : rows_) {
    lo = lo.cwiseMin(r.plan_en_m);
    hi = hi.cwiseMax(r.plan_en_m);
  }
  if (rows_.empty()) lo = hi = Eigen::Vector2d::Zero();
  g.center_en_m = 0.5 * (lo + hi);
  f.span = (hi - lo).cwiseMax(1.0);
}

// The footer (scale bar and captions) wraps at the panel's width; its
// height follows from the captions, which follow from the scale: settle
// both in up to three passes.
// The layout of the shown fit in this room is taken from the cache when it
// was worked out before.
void WorkbenchUi::layout_plan(PlanFrame& f) {
  PlanGeometry& g = plan_;
  ImFont* regular = f.regular;
  const float font = f.font;
  const ImVec2 c0 = f.c0;
  const ImVec2 avail = f.avail;
  const float wrap_w = f.wrap_w;
  std::string& caption = f.caption;
  std::vector<PlanLabel>& labels = f.labels;
  std::vector<std::string>& unlabelled = f.unlabelled;
  double& short_side_px = f.short_side_px;
  double& k = f.k;
  float& footer_h = f.footer_h;
  PlanLayout& cache = plan_layout_;
  const bool cached = f.cached = cache.generation == shown_generation_ && cache.x == c0.x && cache.y == c0.y && cache.w == avail.x &&
                      cache.h == avail.y && cache.font == font;
  if (cached) {
    g = cache.geometry;
    labels = g.labels;
    unlabelled = g.unlabelled;
    caption = cache.caption;
    short_side_px = std::min(g.right - g.left, g.bottom - g.top);
    k = g.arrow_exaggeration * g.px_per_m;
  }
  for (int pass = 0; pass < 3 && !cached; ++pass) {
    settle_plan_scale(f);
    place_plan_labels(f);
    write_plan_caption(f);
    const float needed = std::ceil(font * 1.5f + detail::text_size(caption, regular, font, wrap_w).y + font * 0.2f);
    if (needed <= footer_h) break;
    footer_h = needed;
  }
}

// The plotting area and the scales for this pass's footer.
void WorkbenchUi::settle_plan_scale(PlanFrame& f) {
  PlanGeometry& g = plan_;
  const ImVec2 c0 = f.c0;
  const ImVec2 avail = f.avail;
  const float legend_w = f.legend_w;
  const float footer_h = f.footer_h;
  const double max_h_m = f.max_h_m;
  const double max_u_mm = f.max_u_mm;
  const Eigen::Vector2d& span = f.span;
  double& short_side_px = f.short_side_px;
  double& k = f.k;
  g.left = c0.x;
  g.top = c0.y;
  g.right = c0.x + std::max(avail.x - legend_w, 4 * kPlanMarginPx);
  g.bottom = c0.y + std::max(avail.y - footer_h, 4 * kPlanMarginPx);
  g.px_per_m =
      std::min((g.right - g.left - 2 * kPlanMarginPx) / span.x(), (g.bottom - g.top - 2 * kPlanMarginPx) / span.y());
  // Arrows: the largest horizontal residual of a used point drawn about
  // an eighth of the plan's short side, the factor rounded to 1, 2 or
  // 5 × 10^k. Outliers are drawn at the same factor (shortened, their size
  // written beside them) so that the used points' pattern stays readable.
  short_side_px = std::min(g.right - g.left, g.bottom - g.top);
  g.arrow_exaggeration = max_h_m > 0 ? detail::nice_floor(0.125 * short_side_px / (g.px_per_m * max_h_m)) : 1.0;
  g.du_limit_mm = detail::nice_ceil(std::max(max_u_mm, 1.0));
  g.scale_bar_m = detail::nice_floor(0.25 * (g.right - g.left) / g.px_per_m);
  k = g.arrow_exaggeration * g.px_per_m;
}

// Labels: outliers first, then marks not used, then the rest, each
// beside its mark where it covers no mark, arrow or other label, else
// further out with a leader line; with no room at all, listed below.
void WorkbenchUi::place_plan_labels(PlanFrame& f) {
  PlanGeometry& g = plan_;
  ImFont* regular = f.regular;
  ImFont* bold = f.bold;
  const float font = f.font;
  const float id_size = f.id_size;
  const bool dense = f.dense;
  const float r_px = f.r_px;
  std::vector<PlanLabel>& labels = f.labels;
  std::vector<std::string>& unlabelled = f.unlabelled;
  labels.clear();
  unlabelled.clear();
  const Box area{g.left + 2.0f, g.top + 2.0f, g.right - 2.0f, g.bottom - 2.0f};
  Obstacles obstacles(area, font * 2.0f);
  obstacles.add(Box{g.left, g.top, g.left + font * 2.0f, g.top + font * 4.2f});  // the north arrow
  for (const auto& r : rows_) {
    const Eigen::Vector2d p = g.pixel_of(r.plan_en_m);
    const float s = r.outlier ? r_px + 3.0f : r_px + 1.0f;
    obstacles.add(Box{static_cast<float>(p.x()) - s, static_cast<float>(p.y()) - s, static_cast<float>(p.x()) + s,
                      static_cast<float>(p.y()) + s});
    if ((r.used || r.outlier) && !dense) obstacles.add(p, p + f.drawn_arrow_px(r));
  }
  for (int rank = 0; rank < 3; ++rank) {
    for (const auto& r : rows_) {
      if ((rank == 0) != r.outlier || (rank == 1 && r.used) || (rank == 2 && !r.used)) continue;
      if (dense && !r.outlier) continue;
      const std::string text = r.outlier ? outlier_label(r) : r.id;
      const ImVec2 ts = detail::text_size(text, r.outlier ? bold : regular, r.outlier ? font : id_size);
      const Eigen::Vector2d p = g.pixel_of(r.plan_en_m);
      bool placed = false;
      for (const auto& [box, leader] : candidates(p, r.outlier ? r_px + 3.0f : r_px, ts.x + 2.0f, ts.y, f.drawn_arrow_px(r), id_size)) {
        if (!box.inside(area) || !obstacles.free(box)) continue;
        obstacles.add(box);
        labels.push_back({r.id, box.x0, box.y0, box.x1, box.y1, p, leader, std::nullopt});
        placed = true;
        break;
      }
      if (!placed) unlabelled.push_back(r.id);
    }
  }
}

// The caption under the plan, for this pass's scale and labels.
void WorkbenchUi::write_plan_caption(PlanFrame& f) {
  PlanGeometry& g = plan_;
  ImFont* regular = f.regular;
  const float font = f.font;
  const bool dense = f.dense;
  const float wrap_w = f.wrap_w;
  const double k = f.k;
  std::string& caption = f.caption;
  const std::vector<std::string>& unlabelled = f.unlabelled;
  caption = "arrows: horizontal residual × " + detail::fmt("%g", g.arrow_exaggeration) + " (10 px = " +
            detail::fmt("%.2g", 10.0 / k * 1e3) + " mm); outliers' arrows shortened to fit";
  if (dense) {
    caption += "\nmore than " + std::to_string(kDensePlanMarks) +
               " marks: no ellipses, and only outliers' ids (hover over a mark, or see the table)";
  } else {
    caption += "\nellipses: where each horizontal residual falls with " + detail::fmt("%.0f", 100.0 * kEllipseProbability) +
               " % probability if the model and sigmas are right (a-posteriori residual covariance; for marks not in "
               "the fit, the prediction's), " + detail::fmt("%.4f", g.ellipse_k) + " σ, × " + detail::fmt("%g", g.arrow_exaggeration) +
               " as the arrows";
  }
  if (!unlabelled.empty()) caption += "\n" + detail::unlabelled_caption(unlabelled, rows_.size(), "mark", regular, font, wrap_w);
}

void WorkbenchUi::draw_plan_ellipses(PlanFrame& f) {
  PlanGeometry& g = plan_;
  ImDrawList* dl = f.dl;
  const bool dense = f.dense;
  const double k = f.k;
  if (!dense) {
    constexpr int kSegments = 32;  // smooth at the sizes drawn (tens of pixels)
    for (const auto& r : rows_) {
      const Ellipse e = confidence_ellipse(r.residual_cov_en_m2, g.ellipse_k);
      if (!std::isfinite(e.a_m)) continue;
      const Eigen::Vector2d p = g.pixel_of(r.plan_en_m);
      const Eigen::Vector2d major(std::sin(e.azimuth_rad), std::cos(e.azimuth_rad)), minor(major.y(), -major.x());  // E, N
      ImVec2 pts[kSegments];
      for (int i = 0; i < kSegments; ++i) {
        const double t = 2.0 * std::numbers::pi * i / kSegments;
        const Eigen::Vector2d en = e.a_m * std::cos(t) * major + e.b_m * std::sin(t) * minor;
        pts[i] = iv(p + k * Eigen::Vector2d(en.x(), -en.y()));
      }
      const Rgb c = r.outlier ? palette::kOutlier : r.used ? palette::kEllipse : palette::kLeftOut;
      dl->AddPolyline(pts, kSegments, col(c, 150), ImDrawFlags_Closed, 1.0f);
      ++g.ellipses_drawn;
    }
  }
}

void WorkbenchUi::draw_plan_marks(const PlanFrame& f) {
  PlanGeometry& g = plan_;
  ImDrawList* dl = f.dl;
  const float font = f.font;
  const bool dense = f.dense;
  const float r_px = f.r_px;
  const float rd = f.rd;
  const ImDrawListFlags aa = dl->Flags;
  if (dense) dl->Flags &= ~(ImDrawListFlags_AntiAliasedLines | ImDrawListFlags_AntiAliasedFill);
  for (const auto& r : rows_) {
    if (r.used || r.outlier) continue;
    const Eigen::Vector2d p = g.pixel_of(r.plan_en_m);
    if (dense) {
      dl->AddRect(ImVec2(static_cast<float>(p.x()) - rd, static_cast<float>(p.y()) - rd),
                  ImVec2(static_cast<float>(p.x()) + rd, static_cast<float>(p.y()) + rd), col(palette::kLeftOut));
      continue;
    }
    dl->AddCircle(iv(p), r_px, col(palette::kLeftOut), 12, 1.5f);
  }
  for (const auto& r : rows_) {
    if (!r.used) continue;
    const Eigen::Vector2d p = g.pixel_of(r.plan_en_m);
    const Rgb fill = palette::diverging(r.residual_enu_mm.z() / g.du_limit_mm);
    if (dense) {
      arrow(dl, p, p + f.residual_px(r), col(palette::kInk), 1.0f, font * 0.4f);
      dl->AddRectFilled(ImVec2(static_cast<float>(p.x()) - rd, static_cast<float>(p.y()) - rd),
                        ImVec2(static_cast<float>(p.x()) + rd, static_cast<float>(p.y()) + rd), col(fill));
      continue;
    }
    arrow(dl, p, p + f.residual_px(r), col(palette::kInk), 1.5f, font * 0.55f);
    dl->AddCircleFilled(iv(p), r_px, col(fill), 12);
    dl->AddCircle(iv(p), r_px, col(palette::kInk), 12, 1.0f);
  }
  dl->Flags = aa;
  for (const auto& r : rows_) {
    if (!r.outlier) continue;
    const Eigen::Vector2d p = g.pixel_of(r.plan_en_m);
    arrow(dl, p, p + f.drawn_arrow_px(r), col(palette::kOutlier), 3.0f, font * 0.8f);
    const float s = r_px + 2;
    dl->AddRect(ImVec2(static_cast<float>(p.x()) - s, static_cast<float>(p.y()) - s),
                ImVec2(static_cast<float>(p.x()) + s, static_cast<float>(p.y()) + s), col(palette::kOutlier), 0, 0, 2.5f);
  }
}

  // The ids, where the placement put them.
void WorkbenchUi::draw_plan_labels(const PlanFrame& f) {
  PlanGeometry& g = plan_;
  ImDrawList* dl = f.dl;
  ImFont* regular = f.regular;
  ImFont* bold = f.bold;
  const float font = f.font;
  const float id_size = f.id_size;
  const float r_px = f.r_px;
  for (const auto& l : g.labels) {
    const PointRow* r = nullptr;
    for (const auto& row : rows_) {
      if (row.id == l.id) {
        r = &row;
        break;
      }
    }
    if (!r) continue;
    const Rgb c = r->outlier ? palette::kOutlier : r->used ? palette::kInk : palette::kLeftOut;
    if (l.leader) {
      const Eigen::Vector2d nearest(std::clamp(l.mark_px.x(), double(l.x0), double(l.x1)), std::clamp(l.mark_px.y(), double(l.y0), double(l.y1)));
      const Eigen::Vector2d d = nearest - l.mark_px;
      if (d.norm() > r_px + 2.0) dl->AddLine(iv(l.mark_px + (r_px + 1.0) * d.normalized()), iv(nearest), col(c, 160), 1.0f);
    }
    if (r->outlier) {
      detail::label(audit_, dl, ImVec2(l.x0 + 1.0f, l.y0), col(c), outlier_label(*r), "plan: outlier label", ImVec2(g.left, g.top),
                    ImVec2(g.right, g.bottom), bold, font);
    } else {
      detail::label(audit_, dl, ImVec2(l.x0 + 1.0f, l.y0), col(c), r->id, "plan: id", ImVec2(g.left, g.top), ImVec2(g.right, g.bottom),
                    regular, id_size);
    }
  }
}

  // Footer: scale bar and what the arrows and ellipses mean.
void WorkbenchUi::draw_plan_footer(const PlanFrame& f) {
  const PlanGeometry& g = plan_;
  detail::plan_footer(audit_, f.dl, g.left, g.bottom, f.font, true, g.scale_bar_m, g.px_per_m, f.caption, f.regular, f.wrap_w, "plan");
}

  // Legend: the vertical residual's colour scale, and the symbols.
void WorkbenchUi::draw_plan_legend(const PlanFrame& f) {
  PlanGeometry& g = plan_;
  ImDrawList* dl = f.dl;
  const float font = f.font;
  const bool dense = f.dense;
  const float r_px = f.r_px;
  const float swatch = f.swatch;
  const std::string& ellipse_entry = f.ellipse_entry;
  const float lx = g.right + font * 1.0f, ly0 = g.top + font * 1.6f;
  const float symbols_h = font * 4.8f;
  const float lh = std::max(font * 2.0f, std::min(font * 12.0f, g.bottom - ly0 - symbols_h - font * 0.5f));
  detail::label(audit_, dl, ImVec2(lx, g.top), col(palette::kInk), "dU (mm)", "plan: legend");
  constexpr int kSteps = 64;
  for (int i = 0; i < kSteps; ++i) {
    const double t = 1.0 - 2.0 * (i + 0.5) / kSteps;
    const float y0 = ly0 + lh * static_cast<float>(i) / kSteps, y1 = ly0 + lh * static_cast<float>(i + 1) / kSteps;
    dl->AddRectFilled(ImVec2(lx, y0), ImVec2(lx + swatch, y1), col(palette::diverging(t)));
  }
  dl->AddRect(ImVec2(lx, ly0), ImVec2(lx + swatch, ly0 + lh), col(palette::kInk));
  const auto tick = [&](float y, const std::string& s) {
    dl->AddLine(ImVec2(lx + swatch, y), ImVec2(lx + swatch + 4, y), col(palette::kInk));
    detail::label(audit_, dl, ImVec2(lx + swatch + 6, y - font * 0.5f), col(palette::kInk), s, "plan: legend");
  };
  tick(ly0, detail::fmt("+%g", g.du_limit_mm));
  tick(ly0 + lh * 0.5f, "0");
  tick(ly0 + lh, detail::fmt("−%g", g.du_limit_mm));
  float sy = ly0 + lh + font * 1.0f;
  dl->AddRect(ImVec2(lx, sy), ImVec2(lx + r_px * 2 + 4, sy + r_px * 2 + 4), col(palette::kOutlier), 0, 0, 2.5f);
  detail::label(audit_, dl, ImVec2(lx + swatch + font * 0.5f, sy), col(palette::kOutlier), "outlier", "plan: legend");
  sy += font * 1.5f;
  dl->AddCircle(ImVec2(lx + r_px + 2, sy + r_px + 2), r_px, col(palette::kLeftOut), 12, 1.5f);
  detail::label(audit_, dl, ImVec2(lx + swatch + font * 0.5f, sy), col(palette::kLeftOut), "not used", "plan: legend");
  if (!dense) {
    sy += font * 1.5f;
    constexpr int kSegments = 32;
    ImVec2 pts[kSegments];
    for (int i = 0; i < kSegments; ++i) {
      const double t = 2.0 * std::numbers::pi * i / kSegments;
      pts[i] = ImVec2(lx + swatch * 0.5f + swatch * 0.5f * static_cast<float>(std::cos(t)),
                      sy + font * 0.5f + font * 0.3f * static_cast<float>(std::sin(t)));
    }
    dl->AddPolyline(pts, kSegments, col(palette::kEllipse, 200), ImDrawFlags_Closed, 1.0f);
    detail::label(audit_, dl, ImVec2(lx + swatch + font * 0.5f, sy), col(palette::kInk), ellipse_entry, "plan: legend");
  }
}

  // The mark under the mouse: a tooltip with its id and numbers; a click
  // leaves it out or takes it back (not for use = 0 points).
void WorkbenchUi::plan_pointer(const PlanFrame& f) {
  PlanGeometry& g = plan_;
  ImFont* bold = f.bold;
  const float r_px = f.r_px;
  ImGui::InvisibleButton("plan", ImVec2(g.right - g.left, g.bottom - g.top));
  const bool hovered = ImGui::IsItemHovered(), clicked = ImGui::IsItemClicked();
  if (hovered || clicked) {
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
    if (best && hovered) {
      g.hovered = best->id;
      ImGui::BeginTooltip();
      ImGui::PushFont(bold);
      ImGui::TextUnformatted(best->id.c_str());
      ImGui::PopFont();
      ImGui::TextUnformatted(("residual E/N/U " + detail::fmt("%.1f", best->residual_enu_mm.x()) + " / " +
                              detail::fmt("%.1f", best->residual_enu_mm.y()) + " / " + detail::fmt("%.1f", best->residual_enu_mm.z()) +
                              " mm, w-test " + detail::fmt("%.2f", best->w_test))
                                 .c_str());
      const Ellipse e = confidence_ellipse(best->residual_cov_en_m2, g.ellipse_k);
      if (std::isfinite(e.a_m)) {
        ImGui::TextUnformatted((detail::fmt("%.0f", 100.0 * kEllipseProbability) + " % ellipse " + detail::fmt("%.1f", 1e3 * e.a_m) + " × " +
                                detail::fmt("%.1f", 1e3 * e.b_m) + " mm, azimuth " +
                                detail::fmt("%.0f", e.azimuth_rad * 180.0 / std::numbers::pi) + "°")
                                   .c_str());
      }
      ImGui::TextUnformatted(best->outlier ? "outlier (removed by data snooping)"
                             : best->left_out ? "left out (click to take it back)"
                             : !best->used    ? ("not used: " + best->note).c_str()
                                              : "used (click to leave it out)");
      ImGui::EndTooltip();
    }
    if (best && clicked) model_.set_left_out(best->id, !best->left_out);
  }
}

}  // namespace geoanchor::gui

