#pragma once
// How the network view draws a measurement's class and a station (private
// to gui): the line styles, the order classes are drawn in, which classes
// are flagged and which stations held; shared by the plan and the legend.

#include <imgui.h>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <string>

#include "geoanchor/gui/network_model.hpp"
#include "geoanchor/gui/palette.hpp"
#include "plan_layout.hpp"
#include "ui_common.hpp"

namespace geoanchor::gui::detail {

// A station the datum holds in some component: drawn as a triangle of its
// own, never merged into a cell's mark.
inline bool held(const NetworkStationRow& s) { return s.constraint.find('C') != std::string::npos; }

struct LineStyle {
  Rgb colour;
  float thickness;
  bool dashed;
};

inline LineStyle style_of(MeasurementClass c) {
  switch (c) {
    case MeasurementClass::small: return {palette::kPass, 1.5f, false};
    case MeasurementClass::elevated: return {palette::kWarning, 2.5f, false};
    case MeasurementClass::failing: return {palette::kOutlier, 3.5f, false};
    case MeasurementClass::outlier: return {palette::kOutlier, 3.0f, true};
    case MeasurementClass::untestable: return {palette::kInk, 1.0f, true};
    case MeasurementClass::left_out: return {palette::kLeftOut, 1.0f, true};
  }
  return {palette::kInk, 1.0f, false};
}

// Drawn from the least to the most telling, so that the worst is on top.
inline constexpr std::array<MeasurementClass, kMeasurementClasses> kDrawOrder{MeasurementClass::left_out, MeasurementClass::untestable,
                                                                              MeasurementClass::small,    MeasurementClass::elevated,
                                                                              MeasurementClass::failing,  MeasurementClass::outlier};

inline bool flagged(MeasurementClass c) { return c == MeasurementClass::outlier || c == MeasurementClass::failing; }

inline void line(ImDrawList* dl, const Eigen::Vector2d& a, const Eigen::Vector2d& b, const LineStyle& s) {
  if (!s.dashed) {
    dl->AddLine(iv(a), iv(b), col(s.colour), s.thickness);
    return;
  }
  const double len = (b - a).norm();
  if (len < 1.0) return;
  const Eigen::Vector2d u = (b - a) / len;
  const double on = 3.0 * s.thickness + 3.0, off = 2.0 * s.thickness + 2.0;
  for (double t = 0.0; t < len; t += on + off) dl->AddLine(iv(a + t * u), iv(a + std::min(t + on, len) * u), col(s.colour), s.thickness);
}

}  // namespace geoanchor::gui::detail
