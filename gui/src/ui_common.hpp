#pragma once
// Small drawing helpers shared by the view files (private to gui/).

#include <imgui.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>

#include "geoanchor/gui/palette.hpp"

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

inline void text_coloured(Rgb c, const std::string& s) {
  ImGui::PushStyleColor(ImGuiCol_Text, col4(c));
  ImGui::TextUnformatted(s.c_str());
  ImGui::PopStyleColor();
}

}  // namespace geoanchor::gui::detail
