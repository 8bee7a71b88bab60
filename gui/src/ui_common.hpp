#pragma once
// Small drawing helpers shared by the view files (private to gui/).

#include <imgui.h>
#include <imgui_internal.h>  // a table column's extent, for the header check

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "geoanchor/gui/palette.hpp"
#include "geoanchor/gui/workbench_ui.hpp"

namespace geoanchor::gui::detail {

inline ImU32 col(Rgb c, int alpha = 255) { return IM_COL32(c.r, c.g, c.b, alpha); }
inline ImVec4 col4(Rgb c) { return ImVec4(c.r / 255.0f, c.g / 255.0f, c.b / 255.0f, 1.0f); }

// 1, 2 or 5 × 10^k, the largest not above v (v > 0).
inline double nice_floor(double v) {
  const double p = std::pow(10.0, std::floor(std::log10(v)));
  const double m = v / p;
  return (m >= 5.0 ? 5.0 : m >= 2.0 ? 2.0 : 1.0) * p;
}
// 1, 2 or 5 × 10^k, the smallest not below v (v > 0).
inline double nice_ceil(double v) {
  const double p = std::pow(10.0, std::floor(std::log10(v)));
  const double m = v / p;
  return (m <= 1.0 ? 1.0 : m <= 2.0 ? 2.0 : m <= 5.0 ? 5.0 : 10.0) * p;
}

inline std::string fmt(const char* format, double v) {
  char b[64];
  std::snprintf(b, sizeof b, format, v);
  return b;
}

// A length in metres as a short label: "500 m", "2 km", "20 cm".
inline std::string length_label(double m) {
  if (m >= 1000.0) return fmt("%g km", m / 1000.0);
  if (m >= 1.0) return fmt("%g m", m);
  if (m >= 0.01) return fmt("%g cm", m * 100.0);
  return fmt("%g mm", m * 1000.0);
}

// Parameter names carry their unit (tx_m, rx_arcsec, dtx_m_per_year): split
// into the shown name and unit.
struct NameUnit {
  std::string name, unit;
};
inline NameUnit split_unit(std::string_view full) {
  static constexpr std::pair<std::string_view, std::string_view> kUnits[] = {
      {"_m_per_year", "m/yr"}, {"_arcsec_per_year", "″/yr"}, {"_ppm_per_year", "ppm/yr"}, {"_arcsec", "″"},
      {"_ppm", "ppm"},         {"_deg", "°"},                {"_rad", "rad"},           {"_m", "m"}};
  for (const auto& [suffix, unit] : kUnits) {
    if (full.size() > suffix.size() && full.substr(full.size() - suffix.size()) == suffix) {
      return {std::string(full.substr(0, full.size() - suffix.size())), std::string(unit)};
    }
  }
  return {std::string(full), "1"};
}

// --- Text that is checked against the room it is drawn in ---------------
// Each helper draws and then records in the audit whether the text's box
// lies inside the current clip rectangle (a window's content, a table
// column) or the given region.

// The last item's box against the current clip rectangle.
inline void check_item(TextAudit& audit, std::string_view text, std::string_view where, bool vertical = true) {
  const ImVec2 a = ImGui::GetItemRectMin(), b = ImGui::GetItemRectMax();
  ImDrawList* dl = ImGui::GetWindowDrawList();
  const ImVec2 ca = dl->GetClipRectMin(), cb = dl->GetClipRectMax();
  audit.check(text, where, a.x, a.y, b.x, b.y, ca.x, ca.y, cb.x, cb.y, vertical);
}

// `vertical` false inside a scrolling table (its rows may run out of view:
// the table says which are in view).
inline void text(TextAudit& audit, const std::string& s, std::string_view where, bool vertical = true) {
  ImGui::TextUnformatted(s.c_str());
  check_item(audit, s, where, vertical);
}

inline void text_coloured(TextAudit& audit, Rgb c, const std::string& s, std::string_view where, bool vertical = true) {
  ImGui::PushStyleColor(ImGuiCol_Text, col4(c));
  ImGui::TextUnformatted(s.c_str());
  ImGui::PopStyleColor();
  check_item(audit, s, where, vertical);
}

// Wrapped at the window's right edge: only the bottom can run out.
inline void wrapped(TextAudit& audit, const std::string& s, std::string_view where) {
  ImGui::PushTextWrapPos(0.0f);
  ImGui::TextUnformatted(s.c_str());
  ImGui::PopTextWrapPos();
  check_item(audit, s, where);
}

inline void wrapped_coloured(TextAudit& audit, Rgb c, const std::string& s, std::string_view where) {
  ImGui::PushStyleColor(ImGuiCol_Text, col4(c));
  wrapped(audit, s, where);
  ImGui::PopStyleColor();
}

// The box of `s` at `size` pixels (0: the current font's size), wrapped at
// `wrap_px` (0: not wrapped) as ImDrawList::AddText wraps it.
inline ImVec2 text_size(const std::string& s, ImFont* font = nullptr, float size = 0.0f, float wrap_px = 0.0f) {
  if (!font) font = ImGui::GetFont();
  if (size <= 0.0f) size = ImGui::GetFontSize();
  return font->CalcTextSizeA(size, FLT_MAX, wrap_px, s.c_str());
}

inline const ImVec2 kNoBound_lo{-FLT_MAX, -FLT_MAX}, kNoBound_hi{FLT_MAX, FLT_MAX};

// Text at `pos` on a draw list, checked against `lo`–`hi` and the list's
// clip rectangle; wrapped at `wrap_px` when that is > 0.
inline void label(TextAudit& audit, ImDrawList* dl, ImVec2 pos, ImU32 colour, const std::string& s, std::string_view where,
                  ImVec2 lo = kNoBound_lo, ImVec2 hi = kNoBound_hi, ImFont* font = nullptr, float size = 0.0f,
                  float wrap_px = 0.0f) {
  if (!font) font = ImGui::GetFont();
  if (size <= 0.0f) size = ImGui::GetFontSize();
  dl->AddText(font, size, pos, colour, s.c_str(), nullptr, wrap_px);
  const ImVec2 ts = text_size(s, font, size, wrap_px);
  const ImVec2 ca = dl->GetClipRectMin(), cb = dl->GetClipRectMax();
  audit.check(s, where, pos.x, pos.y, pos.x + ts.x, pos.y + ts.y, std::max(lo.x, ca.x), std::max(lo.y, ca.y), std::min(hi.x, cb.x),
              std::min(hi.y, cb.y));
}

// A plan's north arrow in its top-left corner; `where` names it for the
// text audit ("plan: north arrow").
inline void north_arrow(TextAudit& audit, ImDrawList* dl, float left, float top, float font, std::string_view where) {
  const ImVec2 na(left + font * 1.2f, top + font * 3.0f);
  dl->AddTriangleFilled(ImVec2(na.x, na.y - font * 1.6f), ImVec2(na.x - font * 0.4f, na.y), ImVec2(na.x + font * 0.4f, na.y),
                        col(palette::kInk));
  label(audit, dl, ImVec2(na.x - font * 0.3f, na.y + 2), col(palette::kInk), "N", where);
}

// A plan's footer under its bottom-left corner: the scale bar of `bar_m`
// metres with its length (unless `with_bar` is false), then the caption
// wrapped at `wrap_px`. `view` names both for the text audit ("plan": "plan:
// scale bar", "plan: caption").
inline void plan_footer(TextAudit& audit, ImDrawList* dl, float left, float bottom, float font, bool with_bar, double bar_m,
                        double px_per_m, const std::string& caption, ImFont* caption_font, float wrap_px, const std::string& view) {
  const float by = bottom + font * 0.7f, bx = left + font * 0.5f;
  if (with_bar) {
    const float bar_px = static_cast<float>(bar_m * px_per_m);
    dl->AddRectFilled(ImVec2(bx, by), ImVec2(bx + bar_px, by + 4), col(palette::kInk));
    dl->AddLine(ImVec2(bx, by - 4), ImVec2(bx, by + 8), col(palette::kInk), 1.5f);
    dl->AddLine(ImVec2(bx + bar_px, by - 4), ImVec2(bx + bar_px, by + 8), col(palette::kInk), 1.5f);
    label(audit, dl, ImVec2(bx + bar_px + font * 0.5f, by - font * 0.5f), col(palette::kInk), length_label(bar_m), view + ": scale bar");
  }
  label(audit, dl, ImVec2(bx, bottom + font * 1.5f), col(palette::kInk), caption, view + ": caption", kNoBound_lo, kNoBound_hi,
        caption_font, font, wrap_px - font * 0.5f);
}

// A table's header row (what ImGui::TableHeadersRow draws), each header
// checked against its column: ImGui would shorten it with "…". A sortable
// column keeps room for the sort arrow.
inline void header_row(TextAudit& audit, std::string_view where) {
  ImGuiTable* table = ImGui::GetCurrentTable();
  ImGui::TableNextRow(ImGuiTableRowFlags_Headers, ImGui::TableGetHeaderRowHeight());
  const int columns = ImGui::TableGetColumnCount();
  for (int c = 0; c < columns; ++c) {
    if (!ImGui::TableSetColumnIndex(c)) continue;
    const char* name = ImGui::TableGetColumnName(c);
    const bool sorts = (table->Flags & ImGuiTableFlags_Sortable) && !(ImGui::TableGetColumnFlags(c) & ImGuiTableColumnFlags_NoSort);
    const float arrow = sorts ? std::floor(ImGui::GetFontSize() * 0.65f + ImGui::GetStyle().FramePadding.x) : 0.0f;
    const float available = table->Columns[c].MaxX - ImGui::GetCursorScreenPos().x;
    ImGui::PushID(c);
    ImGui::TableHeader(name);
    ImGui::PopID();
    audit.check_width(name, where, ImGui::CalcTextSize(name).x + arrow, available);
  }
}

// A plan's caption line for the ids that found no room on it: listed while
// the list takes at most three lines, else counted ("… of N marks" for
// thing "mark").
inline std::string unlabelled_caption(const std::vector<std::string>& unlabelled, std::size_t total, const std::string& thing,
                                      ImFont* font, float size, float wrap_px) {
  std::string ids;
  for (const auto& id : unlabelled) ids += (ids.empty() ? "" : ", ") + id;
  const std::string list = "no room on the plan for the id of " + ids;
  if (text_size(list, font, size, wrap_px).y <= 3.2f * size) return list;
  return "no room on the plan for the ids of " + std::to_string(unlabelled.size()) + " of " + std::to_string(total) + " " + thing +
         "s (hover over a " + thing + ", or see the table)";
}

constexpr ImGuiWindowFlags kPanelFlags = ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse |
                                         ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoBringToFrontOnFocus;

// A fixed window at x, y of w × h pixels titled `title` (the title checked
// against the width), with `body` drawn inside.
template <class Fn>
void panel(TextAudit& audit, const char* title, float x, float y, float w, float h, Fn&& body) {
  ImGui::SetNextWindowPos(ImVec2(x, y), ImGuiCond_Always);
  ImGui::SetNextWindowSize(ImVec2(w, h), ImGuiCond_Always);
  // The title bar shows the title between the frame paddings.
  audit.check_width(title, std::string(title) + ": title", ImGui::CalcTextSize(title).x + 2.0f * ImGui::GetStyle().FramePadding.x, w);
  if (ImGui::Begin(title, nullptr, kPanelFlags)) body();
  ImGui::End();
}

}  // namespace geoanchor::gui::detail
