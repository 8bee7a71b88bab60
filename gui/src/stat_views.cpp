// The statistical views: w-test histogram, point table, parameters with
// their correlation heat map, and the model comparison.

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>

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

  ImGui::TextWrapped("%s", (std::to_string(w.size()) + " w-tests (E, N, U of " + std::to_string(w.size() / 3) +
                            " used points) against N(0, 1); critical |w| = " + detail::fmt("%.2f", fit.w_critical) +
                            " at α0 = " + detail::fmt("%g", model_.options().alpha_point))
                               .c_str());
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
    dl->AddText(ImVec2(x - ImGui::CalcTextSize(s.c_str()).x * 0.5f, h.bottom + 5), col(palette::kInk), s.c_str());
  }
  const std::string crit = detail::fmt("±%.2f", fit.w_critical);
  dl->AddText(ImVec2(h.x_of(fit.w_critical) - ImGui::CalcTextSize(crit.c_str()).x - 4, h.top), col(palette::kCritical), crit.c_str());
  // Points removed as outliers: where their largest w-test falls, clamped to the axis.
  float label_y = h.top + font * 1.3f;
  for (const auto& p : fit.points) {
    if (!p.outlier) continue;
    Eigen::Index k = 0;
    p.w_enu.cwiseAbs().maxCoeff(&k);
    const double v = std::clamp(p.w_enu(k), h.w_low, -h.w_low);
    const float x = h.x_of(v);
    dl->AddTriangleFilled(ImVec2(x, h.bottom - font * 0.9f), ImVec2(x - font * 0.45f, h.bottom), ImVec2(x + font * 0.45f, h.bottom),
                          col(palette::kOutlier));
    const std::string s = p.id + " (w = " + detail::fmt("%.1f", p.w_enu(k)) + ")";
    const float tw = ImGui::CalcTextSize(s.c_str()).x;
    dl->AddText(ImVec2(std::clamp(x - tw * 0.5f, h.left, h.right - tw), label_y), col(palette::kOutlier), s.c_str());
    label_y += font * 1.1f;
  }
  ImGui::Dummy(avail);
}

void WorkbenchUi::draw_table() {
  const double w_critical = model_.fit() ? model_.fit()->w_critical : 0.0;
  if (!model_.fit()) detail::text_coloured(palette::kOutlier, "No fit: " + model_.error());
  constexpr ImGuiTableFlags kFlags = ImGuiTableFlags_Sortable | ImGuiTableFlags_ScrollY | ImGuiTableFlags_RowBg |
                                     ImGuiTableFlags_BordersOuter | ImGuiTableFlags_BordersV | ImGuiTableFlags_SizingStretchProp;
  if (!ImGui::BeginTable("points", 8, kFlags, ImGui::GetContentRegionAvail())) return;
  enum Column : ImGuiID { kUse, kId, kE, kN, kU, kW, kMdb, kStatus };
  ImGui::TableSetupScrollFreeze(0, 1);
  ImGui::TableSetupColumn("use", ImGuiTableColumnFlags_NoSort | ImGuiTableColumnFlags_WidthFixed, 0.0f, kUse);
  ImGui::TableSetupColumn("id", ImGuiTableColumnFlags_DefaultSort, 1.0f, kId);
  ImGui::TableSetupColumn("dE mm", ImGuiTableColumnFlags_PreferSortDescending, 1.0f, kE);
  ImGui::TableSetupColumn("dN mm", ImGuiTableColumnFlags_PreferSortDescending, 1.0f, kN);
  ImGui::TableSetupColumn("dU mm", ImGuiTableColumnFlags_PreferSortDescending, 1.0f, kU);
  ImGui::TableSetupColumn("w-test", ImGuiTableColumnFlags_PreferSortDescending, 1.0f, kW);
  ImGui::TableSetupColumn("MDB mm", ImGuiTableColumnFlags_PreferSortDescending, 1.0f, kMdb);
  ImGui::TableSetupColumn("status", 0, 2.5f, kStatus);
  ImGui::TableHeadersRow();

  ImGuiTableSortSpecs* specs = ImGui::TableGetSortSpecs();
  if (specs && specs->SpecsDirty) {
    resort_ = true;
    specs->SpecsDirty = false;
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

  ImGuiListClipper clipper;
  clipper.Begin(static_cast<int>(order_.size()));
  std::optional<std::pair<std::string, bool>> toggle;
  while (clipper.Step()) {
    for (int i = clipper.DisplayStart; i < clipper.DisplayEnd; ++i) {
      const PointRow& r = rows_[order_[static_cast<std::size_t>(i)]];
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::PushID(i);
      bool use = !r.left_out;
      const bool fixed_out = !r.left_out && !r.used && !r.outlier;  // use = 0 in the file
      if (fixed_out) ImGui::BeginDisabled();
      if (ImGui::Checkbox("##use", &use)) toggle = {r.id, !use};
      if (fixed_out) ImGui::EndDisabled();
      ImGui::PopID();
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(r.id.c_str());
      for (int k = 0; k < 3; ++k) {
        ImGui::TableNextColumn();
        ImGui::TextUnformatted(detail::fmt("%.1f", r.residual_enu_mm(k)).c_str());
      }
      ImGui::TableNextColumn();
      const std::string w = detail::fmt("%.2f", r.w_test);
      if (std::abs(r.w_test) > w_critical) {
        detail::text_coloured(palette::kOutlier, w);
      } else {
        ImGui::TextUnformatted(w.c_str());
      }
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(std::isfinite(r.mdb_mm) ? detail::fmt("%.1f", r.mdb_mm).c_str() : "-");
      ImGui::TableNextColumn();
      if (r.outlier) {
        detail::text_coloured(palette::kOutlier, "OUTLIER (removed)");
      } else if (r.left_out) {
        detail::text_coloured(palette::kLeftOut, "left out");
      } else if (!r.used) {
        detail::text_coloured(palette::kLeftOut, "not used: " + r.note);
      } else {
        ImGui::TextUnformatted("used");
      }
    }
  }
  ImGui::EndTable();
  if (toggle) model_.set_left_out(toggle->first, toggle->second);
}

void WorkbenchUi::draw_parameters() {
  const auto& fit = *model_.fit();
  const float font = ImGui::GetFontSize();
  const auto params = model_.parameters();
  constexpr ImGuiTableFlags kFlags = ImGuiTableFlags_RowBg | ImGuiTableFlags_BordersOuter | ImGuiTableFlags_SizingStretchProp;
  if (ImGui::BeginTable("parameters", 5, kFlags)) {
    ImGui::TableSetupColumn("#", ImGuiTableColumnFlags_WidthFixed);
    ImGui::TableSetupColumn("parameter", 0, 1.4f);
    ImGui::TableSetupColumn("value", 0, 1.6f);
    ImGui::TableSetupColumn("σ", 0, 1.3f);
    ImGui::TableSetupColumn("unit", 0, 0.8f);
    ImGui::TableHeadersRow();
    int i = 1;
    for (const auto& p : params) {
      const auto nu = detail::split_unit(p.name);
      const int decimals = nu.unit == "″" ? 5 : nu.unit == "ppm" ? 4 : nu.unit == "°" ? 8 : 4;
      char value[48], sigma[48];
      std::snprintf(value, sizeof value, "%.*f", decimals, p.value);
      std::snprintf(sigma, sizeof sigma, "%.*f", decimals, p.sigma);
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::Text("%d", i++);
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(nu.name.c_str());
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(value);
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(sigma);
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(nu.unit.c_str());
    }
    ImGui::EndTable();
  }
  const auto& g = fit.global_test;
  ImGui::TextUnformatted(("σ0 = " + (fit.sigma0 ? detail::fmt("%.3f", *fit.sigma0) : std::string("undefined")) + ", dof = " + std::to_string(fit.dof)).c_str());
  ImGui::TextUnformatted(fit.covariance_scaled_by_sigma0 ? "σ scaled by σ0" : "σ from the a-priori weights (σ0 = 1)");
  if (g.applicable) {
    ImGui::TextUnformatted(("global test χ² = " + detail::fmt("%.2f", g.statistic) + " in [" + detail::fmt("%.2f", g.critical_lower) +
                            ", " + detail::fmt("%.2f", g.critical_upper) + "]")
                               .c_str());
    ImGui::TextUnformatted(("at α = " + detail::fmt("%g", model_.options().alpha) + ": ").c_str());
    ImGui::SameLine(0, 0);
    detail::text_coloured(g.passed ? palette::kPass : palette::kOutlier,
                          g.passed ? "PASSED" : g.statistic > g.critical_upper ? "FAILED (high)" : "FAILED (low)");
  } else {
    ImGui::TextUnformatted("global test: not applicable (no a-priori sigmas, or no redundancy)");
  }

  // Correlation heat map, numbered as the table.
  const Eigen::MatrixXd& r = fit.correlation;
  const int n = static_cast<int>(r.rows());
  if (n == 0) return;
  ImGui::TextUnformatted("correlation");
  ImDrawList* dl = ImGui::GetWindowDrawList();
  const ImVec2 c0 = ImGui::GetCursorScreenPos();
  const ImVec2 avail = ImGui::GetContentRegionAvail();
  const float label = font * 1.6f, legend = font * 2.2f;
  const float cell = std::floor(std::max(4.0f, std::min((avail.x - label) / static_cast<float>(n), (avail.y - label - legend) / static_cast<float>(n))));
  const ImVec2 o(c0.x + label, c0.y + label);
  for (int i = 0; i < n; ++i) {
    const std::string s = std::to_string(i + 1);
    const ImVec2 ts = ImGui::CalcTextSize(s.c_str());
    dl->AddText(ImVec2(o.x + cell * (static_cast<float>(i) + 0.5f) - ts.x * 0.5f, c0.y), col(palette::kInk), s.c_str());
    dl->AddText(ImVec2(c0.x, o.y + cell * (static_cast<float>(i) + 0.5f) - ts.y * 0.5f), col(palette::kInk), s.c_str());
    for (int j = 0; j < n; ++j) {
      const ImVec2 a(o.x + cell * static_cast<float>(j), o.y + cell * static_cast<float>(i));
      const ImVec2 b(a.x + cell - 1, a.y + cell - 1);
      dl->AddRectFilled(a, b, col(palette::diverging(r(i, j))));
      if (cell >= font * 2.4f) {
        const std::string v = detail::fmt("%.2f", r(i, j));
        const ImVec2 vs = ImGui::CalcTextSize(v.c_str());
        dl->AddText(ImVec2(a.x + (cell - vs.x) * 0.5f, a.y + (cell - vs.y) * 0.5f),
                    col(std::abs(r(i, j)) > 0.75 ? palette::kBackground : palette::kInk), v.c_str());
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
  dl->AddText(ImVec2(o.x, ly + font * 0.7f), col(palette::kInk), "−1");
  dl->AddText(ImVec2(o.x + lw * 0.5f - font * 0.3f, ly + font * 0.7f), col(palette::kInk), "0");
  dl->AddText(ImVec2(o.x + lw - font * 1.2f, ly + font * 0.7f), col(palette::kInk), "+1");
  ImGui::Dummy(ImVec2(label + cell * static_cast<float>(n), label + cell * static_cast<float>(n) + legend));
}

void WorkbenchUi::draw_comparison() {
  const auto& rows = model_.comparison();
  if (rows.empty()) {
    ImGui::TextUnformatted(model_.busy() ? "refitting…" : "no model applies to these points");
    return;
  }
  const solver::ModelComparison* best = nullptr;
  for (const auto& c : rows) {
    if (c.fit && (!best || c.aic < best->aic)) best = &c;
  }
  ImGui::TextWrapped("Same points under each model, data snooping off; AIC = Ω + 2u (lower is better; differences above ~10 are strong evidence).");
  constexpr ImGuiTableFlags kFlags = ImGuiTableFlags_RowBg | ImGuiTableFlags_BordersOuter | ImGuiTableFlags_SizingStretchProp |
                                     ImGuiTableFlags_ScrollY;
  if (!ImGui::BeginTable("comparison", 7, kFlags, ImGui::GetContentRegionAvail())) return;
  ImGui::TableSetupScrollFreeze(0, 1);
  ImGui::TableSetupColumn("model", 0, 2.4f);
  ImGui::TableSetupColumn("u", 0, 0.5f);
  ImGui::TableSetupColumn("dof", 0, 0.7f);
  ImGui::TableSetupColumn("σ0", 0, 0.9f);
  ImGui::TableSetupColumn("global", 0, 1.1f);
  ImGui::TableSetupColumn("max|w|", 0, 1.1f);
  ImGui::TableSetupColumn("ΔAIC", 0, 0.9f);
  ImGui::TableHeadersRow();
  for (const auto& c : rows) {
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    const bool current = c.model == model_.options().model;
    std::string name = (current ? "▶ " : "  ") + std::string(solver::to_string(c.model));
    if (&c == best) {
      detail::text_coloured(palette::kPass, name);
    } else {
      ImGui::TextUnformatted(name.c_str());
    }
    if (!c.fit) {
      ImGui::TableNextColumn();
      ImGui::TableNextColumn();
      ImGui::TableNextColumn();
      ImGui::TableNextColumn();
      detail::text_coloured(palette::kLeftOut, "refused");
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", c.refused.c_str());
      continue;
    }
    const auto& g = c.fit->global_test;
    ImGui::TableNextColumn();
    ImGui::Text("%d", c.parameters);
    ImGui::TableNextColumn();
    ImGui::Text("%d", c.fit->dof);
    ImGui::TableNextColumn();
    ImGui::TextUnformatted((c.fit->sigma0 ? detail::fmt("%.3f", *c.fit->sigma0) : std::string("undefined")).c_str());
    ImGui::TableNextColumn();
    if (!g.applicable) {
      ImGui::TextUnformatted("n/a");
    } else {
      detail::text_coloured(g.passed ? palette::kPass : palette::kOutlier, g.passed ? "passed" : "FAILED");
    }
    ImGui::TableNextColumn();
    ImGui::TextUnformatted(detail::fmt("%.2f", c.max_w).c_str());
    ImGui::TableNextColumn();
    ImGui::TextUnformatted(detail::fmt("%.1f", c.aic - best->aic).c_str());
  }
  ImGui::EndTable();
}

}  // namespace geoanchor::gui
