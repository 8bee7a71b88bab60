// The statistical views: w-test histogram, point table, parameters with
// their correlation heat map, and the model comparison.

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <optional>

#include "geoanchor/gui/workbench_ui.hpp"
#include "ui_common.hpp"

namespace geoanchor::gui {

using detail::col;

void WorkbenchUi::draw_histogram() {
  const auto& fit = *model_.fit();
  ImDrawList* dl = ImGui::GetWindowDrawList();
  const float font = ImGui::GetFontSize();
  HistogramGeometry& h = histogram_;
  h.w_critical = fit.w_critical;

  // The used points' w-tests, all three axes (each N(0, 1) under H0).
  std::vector<double> w;
  double max_abs = 0.0;
  for (const auto& p : fit.points) {
    if (!p.used) continue;
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(p.w_enu(k))) continue;
      w.push_back(p.w_enu(k));
      max_abs = std::max(max_abs, std::abs(p.w_enu(k)));
    }
  }
  // Symmetric bins covering every value and the critical values with half a bin to spare.
  const double reach = std::max(std::ceil(max_abs / kHistogramBinWidth), std::ceil(fit.w_critical / kHistogramBinWidth) + 1.0);
  const int bins = 2 * static_cast<int>(reach);
  h.w_low = -reach * kHistogramBinWidth;
  h.counts.assign(static_cast<std::size_t>(bins), 0);
  for (double v : w) {
    const int i = std::clamp(static_cast<int>(std::floor((v - h.w_low) / kHistogramBinWidth)), 0, bins - 1);
    ++h.counts[static_cast<std::size_t>(i)];
  }

  detail::wrapped(audit_,
                  std::to_string(w.size()) + " w-tests (E, N, U of " + std::to_string(w.size() / 3) +
                      " used points) against N(0, 1); critical |w| = " + detail::fmt("%.2f", fit.w_critical) +
                      " at α0 = " + detail::fmt("%g", model_.options().alpha_point),
                  "histogram: caption");
  const ImVec2 c0 = ImGui::GetCursorScreenPos();
  const ImVec2 avail = ImGui::GetContentRegionAvail();
  h.left = c0.x + font * 1.0f;
  h.right = c0.x + avail.x - font * 0.5f;
  h.top = c0.y + font * 0.4f;
  h.bottom = c0.y + avail.y - font * 1.6f;
  h.drawn = true;
  const double n = static_cast<double>(w.size());
  const double peak_normal = n * kHistogramBinWidth / std::sqrt(2.0 * std::numbers::pi);
  const double y_max = 1.1 * std::max({1.0, peak_normal, static_cast<double>(*std::max_element(h.counts.begin(), h.counts.end()))});
  const auto y_of = [&](double count) { return h.bottom - static_cast<float>(count / y_max) * (h.bottom - h.top); };

  // Critical values under the bars, the normal curve over them.
  for (double s : {-1.0, 1.0}) {
    const float x = h.x_of(s * fit.w_critical);
    for (float y = h.top; y < h.bottom; y += 8.0f) {
      dl->AddLine(ImVec2(x, y), ImVec2(x, std::min(y + 5.0f, h.bottom)), col(palette::kCritical), 2.0f);
    }
  }
  for (int i = 0; i < bins; ++i) {
    const int c = h.counts[static_cast<std::size_t>(i)];
    if (c == 0) continue;
    const double lo = h.w_low + i * kHistogramBinWidth;
    // At least 3 px tall, so that a bar of one is seen in a large set.
    const float top = std::min(y_of(c), h.bottom - 3.0f);
    dl->AddRectFilled(ImVec2(h.x_of(lo) + 1.0f, top), ImVec2(h.x_of(lo + kHistogramBinWidth) - 1.0f, h.bottom), col(palette::kBar));
  }
  std::vector<ImVec2> curve;
  for (int i = 0; i <= 200; ++i) {
    const double x = h.w_low + (-2.0 * h.w_low) * i / 200.0;
    const double y = peak_normal * std::exp(-0.5 * x * x);
    curve.emplace_back(h.x_of(x), y_of(y));
  }
  dl->AddPolyline(curve.data(), static_cast<int>(curve.size()), col(palette::kInk), ImDrawFlags_None, 1.5f);
  // Axis with integer ticks.
  dl->AddLine(ImVec2(h.left, h.bottom), ImVec2(h.right, h.bottom), col(palette::kInk), 1.0f);
  for (int t = static_cast<int>(std::ceil(h.w_low)); t <= static_cast<int>(std::floor(-h.w_low)); ++t) {
    const float x = h.x_of(t);
    dl->AddLine(ImVec2(x, h.bottom), ImVec2(x, h.bottom + 4), col(palette::kInk));
    const std::string s = t < 0 ? "−" + std::to_string(-t) : std::to_string(t);
    detail::label(audit_, dl, ImVec2(x - ImGui::CalcTextSize(s.c_str()).x * 0.5f, h.bottom + 5), col(palette::kInk), s,
                  "histogram: axis");
  }
  const std::string crit = detail::fmt("±%.2f", fit.w_critical);
  detail::label(audit_, dl, ImVec2(h.x_of(fit.w_critical) - ImGui::CalcTextSize(crit.c_str()).x - 4, h.top), col(palette::kCritical),
                crit, "histogram: critical value");
  // Points removed as outliers: where their largest w-test falls, clamped to
  // the axis; labelled one under the other while there is room, the rest
  // counted in a last line.
  std::vector<const solver::PointResult*> outliers;
  for (const auto& p : fit.points) {
    if (p.outlier) outliers.push_back(&p);
  }
  const float first_y = h.top + font * 1.3f, line = font * 1.1f;
  const std::size_t lines = static_cast<std::size_t>(std::max(0.0f, std::floor((h.bottom - font - first_y) / line)));
  const std::size_t labelled = outliers.size() <= lines ? outliers.size() : (lines > 0 ? lines - 1 : 0);
  for (std::size_t i = 0; i < outliers.size(); ++i) {
    const auto& p = *outliers[i];
    Eigen::Index k = 0;
    p.w_enu.cwiseAbs().maxCoeff(&k);
    const double v = std::clamp(p.w_enu(k), h.w_low, -h.w_low);
    const float x = h.x_of(v);
    dl->AddTriangleFilled(ImVec2(x, h.bottom - font * 0.9f), ImVec2(x - font * 0.45f, h.bottom), ImVec2(x + font * 0.45f, h.bottom),
                          col(palette::kOutlier));
    if (i >= labelled) continue;
    const std::string s = p.id + " (w = " + detail::fmt("%.1f", p.w_enu(k)) + ")";
    const float tw = ImGui::CalcTextSize(s.c_str()).x;
    detail::label(audit_, dl, ImVec2(std::clamp(x - tw * 0.5f, h.left, h.right - tw), first_y + static_cast<float>(i) * line),
                  col(palette::kOutlier), s, "histogram: outlier label", ImVec2(h.left, h.top), ImVec2(h.right, h.bottom));
  }
  if (labelled < outliers.size() && lines > 0) {
    const std::string s = std::to_string(outliers.size() - labelled) + " more outliers (see the table)";
    detail::label(audit_, dl, ImVec2(h.left, first_y + static_cast<float>(labelled) * line), col(palette::kOutlier), s,
                  "histogram: outlier label", ImVec2(h.left, h.top), ImVec2(h.right, h.bottom));
  }
  ImGui::Dummy(avail);
}

void WorkbenchUi::draw_table() {
  const double w_critical = model_.fit() ? model_.fit()->w_critical : 0.0;
  if (!model_.fit()) detail::wrapped_coloured(audit_, palette::kOutlier, "No fit: " + model_.error(), "table: no fit");
  TableGeometry& t = table_;
  t.drawn = true;
  t.total = rows_.size();
  t.first = 0;
  t.shown_ids.clear();
  t.shown_use.clear();
  const std::size_t start = std::min(table_start_, rows_.size());
  // Numbers take the width they need; the status takes the rest.
  constexpr ImGuiTableFlags kFlags = ImGuiTableFlags_Sortable | ImGuiTableFlags_ScrollY | ImGuiTableFlags_RowBg |
                                     ImGuiTableFlags_BordersOuter | ImGuiTableFlags_BordersV | ImGuiTableFlags_SizingFixedFit;
  ImVec2 size = ImGui::GetContentRegionAvail();
  size.y = std::max(size.y - ImGui::GetTextLineHeightWithSpacing(), ImGui::GetFrameHeight() * 3.0f);
  if (!ImGui::BeginTable("points", 8, kFlags, size)) return;
  enum Column : ImGuiID { kUse, kId, kE, kN, kU, kW, kMdb, kStatus };
  ImGui::TableSetupScrollFreeze(0, 1);
  ImGui::TableSetupColumn("use", ImGuiTableColumnFlags_NoSort, 0.0f, kUse);
  ImGui::TableSetupColumn("id", ImGuiTableColumnFlags_DefaultSort, 0.0f, kId);
  ImGui::TableSetupColumn("dE mm", ImGuiTableColumnFlags_PreferSortDescending, 0.0f, kE);
  ImGui::TableSetupColumn("dN mm", ImGuiTableColumnFlags_PreferSortDescending, 0.0f, kN);
  ImGui::TableSetupColumn("dU mm", ImGuiTableColumnFlags_PreferSortDescending, 0.0f, kU);
  ImGui::TableSetupColumn("w-test", ImGuiTableColumnFlags_PreferSortDescending, 0.0f, kW);
  ImGui::TableSetupColumn("MDB mm", ImGuiTableColumnFlags_PreferSortDescending, 0.0f, kMdb);
  ImGui::TableSetupColumn("status", ImGuiTableColumnFlags_WidthStretch, 1.0f, kStatus);
  detail::header_row(audit_, "table: header");

  ImGuiTableSortSpecs* specs = ImGui::TableGetSortSpecs();
  if (specs && specs->SpecsDirty) {
    resort_ = true;
    specs->SpecsDirty = false;
  }
  t.sorted_by = "input order";
  if (specs && specs->SpecsCount > 0) {
    const auto& s = specs->Specs[0];
    t.sorted_by = std::string(ImGui::TableGetColumnName(s.ColumnIndex)) +
                  (s.SortDirection == ImGuiSortDirection_Ascending ? " ▲" : " ▼");
  }
  if (resort_ || order_.size() != rows_.size()) {
    order_.resize(rows_.size());
    std::iota(order_.begin(), order_.end(), 0);
    if (specs && specs->SpecsCount > 0) {
      const auto& s = specs->Specs[0];
      const auto key = [&](const PointRow& r) -> double {
        switch (s.ColumnUserID) {
          case kE: return r.residual_enu_mm.x();
          case kN: return r.residual_enu_mm.y();
          case kU: return r.residual_enu_mm.z();
          case kW: return std::abs(r.w_test);
          case kMdb: return r.mdb_mm;
          case kStatus: return r.outlier ? 0 : r.left_out ? 1 : !r.used ? 2 : 3;
          default: return 0.0;
        }
      };
      const bool ascending = s.SortDirection == ImGuiSortDirection_Ascending;
      std::stable_sort(order_.begin(), order_.end(), [&](std::size_t a, std::size_t b) {
        if (s.ColumnUserID == kId) return ascending ? rows_[a].id < rows_[b].id : rows_[b].id < rows_[a].id;
        return ascending ? key(rows_[a]) < key(rows_[b]) : key(rows_[b]) < key(rows_[a]);
      });
    }
    resort_ = false;
  }

  // Which rows are wholly in view: every row is as tall as its check box
  // and the cell padding; the rows' area is the table's below the header.
  ImGuiTable* table = ImGui::GetCurrentTable();
  const float row_h = ImGui::GetFrameHeight() + 2.0f * ImGui::GetStyle().CellPadding.y;
  t.row_height_px = row_h;
  t.left = table->OuterRect.Min.x;
  t.right = table->OuterRect.Max.x;
  bool first_shown = true;
  ImGuiListClipper clipper;
  clipper.Begin(static_cast<int>(order_.size() - start), row_h);
  std::optional<std::pair<std::string, bool>> toggle;
  while (clipper.Step()) {
    for (int i = clipper.DisplayStart; i < clipper.DisplayEnd; ++i) {
      const std::size_t position = start + static_cast<std::size_t>(i);
      const PointRow& r = rows_[order_[position]];
      // A mark data snooping removed is not used: its box is clear, as the
      // status column says (it was ticked: issue 40 point 11).
      const bool ticked = !r.left_out && !r.outlier;
      ImGui::TableNextRow(ImGuiTableRowFlags_None, row_h);
      t.rows_top = table->BgClipRect.Min.y;
      t.rows_bottom = table->BgClipRect.Max.y;
      const float top = table->RowPosY1;
      if (top >= t.rows_top - 0.5f && top + row_h <= t.rows_bottom + 0.5f) {
        if (first_shown) t.first = position;
        first_shown = false;
        t.shown_ids.push_back(r.id);
        t.shown_use.push_back(ticked);
      }
      ImGui::TableNextColumn();
      ImGui::PushID(i);
      bool use = ticked;
      const bool fixed_out = (!r.left_out && !r.used) || r.outlier;  // use = 0 in the file, or removed by the fit
      if (fixed_out) ImGui::BeginDisabled();
      if (ImGui::Checkbox("##use", &use)) toggle = {r.id, !use};
      if (fixed_out) ImGui::EndDisabled();
      ImGui::PopID();
      ImGui::TableNextColumn();
      detail::text(audit_, r.id, "table: id", false);
      for (int k = 0; k < 3; ++k) {
        ImGui::TableNextColumn();
        detail::text(audit_, detail::fmt("%.1f", r.residual_enu_mm(k)), "table: residual", false);
      }
      ImGui::TableNextColumn();
      const std::string w = detail::fmt("%.2f", r.w_test);
      if (std::abs(r.w_test) > w_critical) {
        detail::text_coloured(audit_, palette::kOutlier, w, "table: w-test", false);
      } else {
        detail::text(audit_, w, "table: w-test", false);
      }
      ImGui::TableNextColumn();
      detail::text(audit_, std::isfinite(r.mdb_mm) ? detail::fmt("%.1f", r.mdb_mm) : "-", "table: MDB", false);
      ImGui::TableNextColumn();
      if (r.outlier) {
        detail::text_coloured(audit_, palette::kOutlier, "OUTLIER (removed)", "table: status", false);
      } else if (r.left_out) {
        detail::text_coloured(audit_, palette::kLeftOut, "left out", "table: status", false);
      } else if (!r.used) {
        detail::text_coloured(audit_, palette::kLeftOut, "not used: " + r.note, "table: status", false);
      } else {
        detail::text(audit_, "used", "table: status", false);
      }
    }
  }
  ImGui::EndTable();
  if (toggle) model_.set_left_out(toggle->first, toggle->second);
  // What the rows above show, in words: a picture of the table never hides
  // that marks are missing from it.
  std::string line;
  if (t.total == 0) {
    line = "no marks";
  } else if (t.shown_ids.size() == t.total) {
    line = "all " + std::to_string(t.total) + " marks in view, sorted by " + t.sorted_by;
  } else if (t.shown_ids.empty()) {
    line = "no mark wholly in view of " + std::to_string(t.total) + " (the panel is too short)";
  } else {
    line = "marks " + std::to_string(t.first + 1) + "–" + std::to_string(t.first + t.shown_ids.size()) + " of " +
           std::to_string(t.total) + " in view, sorted by " + t.sorted_by;
  }
  detail::text(audit_, line, "table: rows in view");
}

namespace {

// `s` on the draw list turned a quarter counter-clockwise (read bottom to
// top), its box's bottom-left corner at `bottom_left`; checked against
// `lo`–`hi`. The glyphs are laid out unclipped and then turned.
void rotated_label(TextAudit& audit, ImDrawList* dl, ImVec2 bottom_left, ImU32 colour, const std::string& s, std::string_view where,
                   ImVec2 lo, ImVec2 hi) {
  const ImVec2 ts = detail::text_size(s);
  const int first = dl->VtxBuffer.Size;
  dl->PushClipRectFullScreen();
  dl->AddText(bottom_left, colour, s.c_str());
  dl->PopClipRect();
  for (int i = first; i < dl->VtxBuffer.Size; ++i) {
    ImDrawVert& v = dl->VtxBuffer[i];
    const float dx = v.pos.x - bottom_left.x, dy = v.pos.y - bottom_left.y;
    v.pos = ImVec2(bottom_left.x + dy, bottom_left.y - dx);
  }
  audit.check(s, where, bottom_left.x, bottom_left.y - ts.x, bottom_left.x + ts.y, bottom_left.y, lo.x, lo.y, hi.x, hi.y);
}

}  // namespace

void WorkbenchUi::draw_parameters() {
  const auto& fit = *model_.fit();
  const float font = ImGui::GetFontSize();
  const auto params = model_.parameters();
  constexpr ImGuiTableFlags kFlags = ImGuiTableFlags_RowBg | ImGuiTableFlags_BordersOuter | ImGuiTableFlags_SizingStretchProp;
  if (ImGui::BeginTable("parameters", 4, kFlags)) {
    ImGui::TableSetupColumn("parameter", 0, 1.4f);
    ImGui::TableSetupColumn("value", 0, 1.6f);
    ImGui::TableSetupColumn("σ", 0, 1.3f);
    ImGui::TableSetupColumn("unit", 0, 0.8f);
    detail::header_row(audit_, "parameters: header");
    for (const auto& p : params) {
      const auto nu = detail::split_unit(p.name);
      const int decimals = nu.unit == "″" ? 5 : nu.unit == "ppm" ? 4 : nu.unit == "°" ? 8 : 4;
      char value[48], sigma[48];
      std::snprintf(value, sizeof value, "%.*f", decimals, p.value);
      std::snprintf(sigma, sizeof sigma, "%.*f", decimals, p.sigma);
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      detail::text(audit_, nu.name, "parameters: name");
      ImGui::TableNextColumn();
      detail::text(audit_, value, "parameters: value");
      ImGui::TableNextColumn();
      detail::text(audit_, sigma, "parameters: sigma");
      ImGui::TableNextColumn();
      detail::text(audit_, nu.unit, "parameters: unit");
    }
    ImGui::EndTable();
  }
  const auto& g = fit.global_test;
  detail::wrapped(audit_, "σ0 = " + (fit.sigma0 ? detail::fmt("%.3f", *fit.sigma0) : std::string("undefined")) + ", dof = " + std::to_string(fit.dof) + "; " +
                              (fit.covariance_scaled_by_sigma0 ? "σ scaled by σ0" : "σ from the a-priori weights (σ0 = 1)"),
                  "parameters: statistics");
  if (g.applicable) {
    detail::wrapped(audit_, "global test χ² = " + detail::fmt("%.2f", g.statistic) + " in [" + detail::fmt("%.2f", g.critical_lower) +
                                ", " + detail::fmt("%.2f", g.critical_upper) + "]",
                    "parameters: global test");
    detail::text(audit_, "at α = " + detail::fmt("%g", model_.options().alpha) + ":", "parameters: global test");
    ImGui::SameLine();
    detail::text_coloured(audit_, g.passed ? palette::kPass : palette::kOutlier,
                          g.passed ? "PASSED" : g.failed_high() ? "FAILED (high)" : "FAILED (low)", "parameters: verdict");
  } else {
    detail::wrapped(audit_, "global test: not applicable (no a-priori sigmas, or no redundancy)", "parameters: global test");
  }

  // Correlation heat map, rows and columns labelled with the parameters'
  // names (the covariance's order); the column labels turned upright when
  // they are wider than a cell. Where no cell can be as tall as a line of
  // text, a sentence says where the matrix is shown instead.
  const Eigen::MatrixXd& r = fit.correlation;
  const int n = static_cast<int>(r.rows());
  if (n == 0) return;
  std::vector<std::string> names;
  if (fit.covariance_names.size() == static_cast<std::size_t>(n)) {
    for (const auto& c : fit.covariance_names) names.push_back(detail::split_unit(c).name);
  } else if (params.size() == static_cast<std::size_t>(n)) {
    for (const auto& p : params) names.push_back(detail::split_unit(p.name).name);
  } else {
    for (int i = 0; i < n; ++i) names.push_back("p" + std::to_string(i + 1));
  }
  float name_w = 0.0f;
  for (const auto& s : names) name_w = std::max(name_w, ImGui::CalcTextSize(s.c_str()).x);
  ImGui::Spacing();
  const ImVec2 c0 = ImGui::GetCursorScreenPos();
  const ImVec2 avail = ImGui::GetContentRegionAvail();
  const float title_h = font * 1.3f, legend = font * 2.2f, label_w = std::ceil(name_w + font * 0.5f);
  const auto cell_for = [&](float top_h) {
    return std::floor(std::min((avail.x - label_w) / static_cast<float>(n),
                               (avail.y - title_h - top_h - legend) / static_cast<float>(n)));
  };
  float top_h = font * 1.2f;
  float cell = cell_for(top_h);
  bool upright = name_w > cell - 2.0f;
  if (upright) {
    top_h = name_w + 4.0f;
    cell = cell_for(top_h);
  }
  if (!(cell >= font * 1.05f)) {
    detail::wrapped(audit_,
                    composite_ ? "correlation matrix: no room in this panel (the parameters view shows it)"
                               : "correlation matrix: no room at this size (" + std::to_string(n) + " parameters)",
                    "parameters: correlation");
    return;
  }
  ImDrawList* dl = ImGui::GetWindowDrawList();
  const ImVec2 clip_lo = dl->GetClipRectMin(), clip_hi = dl->GetClipRectMax();
  detail::label(audit_, dl, c0, col(palette::kInk), "correlation", "parameters: correlation");
  const ImVec2 o(c0.x + label_w, c0.y + title_h + top_h);
  for (int i = 0; i < n; ++i) {
    const std::string& s = names[static_cast<std::size_t>(i)];
    const ImVec2 ts = ImGui::CalcTextSize(s.c_str());
    const float centre = cell * (static_cast<float>(i) + 0.5f);
    if (upright) {
      rotated_label(audit_, dl, ImVec2(o.x + centre - ts.y * 0.5f, o.y - 3.0f), col(palette::kInk), s, "parameters: correlation column",
                    clip_lo, clip_hi);
    } else {
      detail::label(audit_, dl, ImVec2(o.x + centre - ts.x * 0.5f, o.y - top_h), col(palette::kInk), s, "parameters: correlation column");
    }
    detail::label(audit_, dl, ImVec2(c0.x, o.y + centre - ts.y * 0.5f), col(palette::kInk), s, "parameters: correlation row");
    for (int j = 0; j < n; ++j) {
      const ImVec2 a(o.x + cell * static_cast<float>(j), o.y + cell * static_cast<float>(i));
      const ImVec2 b(a.x + cell - 1, a.y + cell - 1);
      dl->AddRectFilled(a, b, col(palette::diverging(r(i, j))));
      if (cell >= font * 2.4f) {
        const std::string v = detail::fmt("%.2f", r(i, j));
        const ImVec2 vs = ImGui::CalcTextSize(v.c_str());
        detail::label(audit_, dl, ImVec2(a.x + (cell - vs.x) * 0.5f, a.y + (cell - vs.y) * 0.5f),
                      col(std::abs(r(i, j)) > 0.75 ? palette::kBackground : palette::kInk), v, "parameters: correlation value", a, b);
      }
    }
  }
  // Colour legend, −1 … +1.
  const float ly = o.y + cell * static_cast<float>(n) + font * 0.5f, lw = cell * static_cast<float>(n);
  constexpr int kSteps = 64;
  for (int i = 0; i < kSteps; ++i) {
    const double t = -1.0 + 2.0 * (i + 0.5) / kSteps;
    dl->AddRectFilled(ImVec2(o.x + lw * static_cast<float>(i) / kSteps, ly), ImVec2(o.x + lw * static_cast<float>(i + 1) / kSteps, ly + font * 0.6f),
                      col(palette::diverging(t)));
  }
  detail::label(audit_, dl, ImVec2(o.x, ly + font * 0.7f), col(palette::kInk), "−1", "parameters: correlation legend");
  detail::label(audit_, dl, ImVec2(o.x + lw * 0.5f - ImGui::CalcTextSize("0").x * 0.5f, ly + font * 0.7f), col(palette::kInk), "0",
                "parameters: correlation legend");
  detail::label(audit_, dl, ImVec2(o.x + lw - ImGui::CalcTextSize("+1").x, ly + font * 0.7f), col(palette::kInk), "+1",
                "parameters: correlation legend");
  ImGui::Dummy(ImVec2(label_w + cell * static_cast<float>(n), title_h + top_h + cell * static_cast<float>(n) + legend));
}

void WorkbenchUi::draw_comparison() {
  const auto& rows = model_.comparison();
  if (rows.empty()) {
    detail::wrapped(audit_, model_.busy() ? "refitting…" : "no model applies to these points", "comparison: empty");
    return;
  }
  const std::vector<solver::FitModel> lowest = solver::lowest_aic(rows);
  const solver::ModelComparison* best = nullptr;
  for (const auto& c : rows) {
    if (c.fit && (!best || c.aic < best->aic)) best = &c;
  }
  detail::wrapped(audit_,
                  "Same points under each model, data snooping off; AIC = Ω + 2u (lower is better; differences above ~10 are "
                  "strong evidence). ▶ the model fitted; green: the lowest AIC.",
                  "comparison: caption");
  constexpr ImGuiTableFlags kFlags = ImGuiTableFlags_RowBg | ImGuiTableFlags_BordersOuter | ImGuiTableFlags_SizingFixedFit;
  if (!ImGui::BeginTable("comparison", 7, kFlags)) return;
  ImGui::TableSetupColumn("model");
  ImGui::TableSetupColumn("u");
  ImGui::TableSetupColumn("dof");
  ImGui::TableSetupColumn("σ0");
  ImGui::TableSetupColumn("global");
  ImGui::TableSetupColumn("max|w|");
  ImGui::TableSetupColumn("ΔAIC", ImGuiTableColumnFlags_WidthStretch);
  detail::header_row(audit_, "comparison: header");
  for (const auto& c : rows) {
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    const bool current = c.model == model_.options().model;
    const std::string name = (current ? "▶ " : "   ") + std::string(solver::to_string(c.model));
    if (std::find(lowest.begin(), lowest.end(), c.model) != lowest.end()) {
      detail::text_coloured(audit_, palette::kPass, name, "comparison: model");
    } else {
      detail::text(audit_, name, "comparison: model");
    }
    if (!c.fit) {
      ImGui::TableNextColumn();
      detail::text_coloured(audit_, palette::kLeftOut, "refused", "comparison: refused");
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", c.refused.c_str());
      continue;
    }
    const auto& g = c.fit->global_test;
    ImGui::TableNextColumn();
    detail::text(audit_, std::to_string(c.parameters), "comparison: u");
    ImGui::TableNextColumn();
    detail::text(audit_, std::to_string(c.fit->dof), "comparison: dof");
    ImGui::TableNextColumn();
    detail::text(audit_, (c.fit->sigma0 ? detail::fmt("%.3f", *c.fit->sigma0) : std::string("undefined")), "comparison: σ0");
    ImGui::TableNextColumn();
    if (!g.applicable) {
      detail::text(audit_, "n/a", "comparison: global");
    } else {
      detail::text_coloured(audit_, g.passed ? palette::kPass : palette::kOutlier, g.passed ? "passed" : "FAILED", "comparison: global");
    }
    ImGui::TableNextColumn();
    detail::text(audit_, detail::fmt("%.2f", c.max_w), "comparison: max|w|");
    ImGui::TableNextColumn();
    detail::text(audit_, detail::fmt("%.1f", c.aic - best->aic), "comparison: ΔAIC");
  }
  ImGui::EndTable();
  // What a row needs said: molodensky-badekas is helmert7 about a pivot;
  // why a model was refused.
  for (const auto& c : rows) {
    const std::string name(solver::to_string(c.model));
    if (!c.fit) detail::wrapped_coloured(audit_, palette::kLeftOut, name + " refused: " + c.refused, "comparison: note");
    if (!c.note.empty()) detail::wrapped(audit_, name + ": " + c.note, "comparison: note");
  }
}

}  // namespace geoanchor::gui
