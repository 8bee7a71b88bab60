// The network view: its frame, the plan (network_plan.cpp) and beside it
// the adjustment's statistics, the legend and the tables whose check boxes
// leave stations and measurements out (network_ui.hpp).

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <utility>

#include "geoanchor/gui/network_ui.hpp"
#include "network_style.hpp"
#include "plan_layout.hpp"
#include "ui_common.hpp"

namespace geoanchor::gui {

using detail::Box;
using detail::candidates;
using detail::col;
using detail::flagged;
using detail::iv;
using detail::line;
using detail::Obstacles;
using detail::panel;
using detail::style_of;

std::string NetworkUi::measurement_name(std::size_t index) { return "#" + std::to_string(index + 1); }

NetworkUi::NetworkUi(NetworkModel& model) : model_(model) {}

namespace {

// The stations a measurement names, short: "A→B", "A: B, C", "3 baselines".
std::string stations_text(const geodesy::Network& net, const geodesy::NetworkMeasurement& m) {
  using geodesy::MeasurementKind;
  const auto id = [&](std::size_t k) { return net.stations[m.stations[k]].id; };
  switch (m.kind) {
    case MeasurementKind::gnss_baselines:
      if (m.stations.size() == 2) return id(0) + "→" + id(1);
      return std::to_string(m.stations.size() / 2) + " baselines";
    case MeasurementKind::gnss_points:
      if (m.stations.size() == 1) return id(0);
      return std::to_string(m.stations.size()) + " points";
    case MeasurementKind::horizontal_angle:
      if (m.stations.size() == 3) return id(0) + ": " + id(1) + "→" + id(2);
      break;
    case MeasurementKind::observation_set:
      return std::to_string(m.parts.size()) + " observations at " + id(0);
    default:
      if (m.stations.size() == 2) return id(0) + "→" + id(1);
      if (m.stations.size() == 1) return id(0);
      break;
  }
  std::string s;
  for (std::size_t k = 0; k < m.stations.size(); ++k) s += (k ? ", " : "") + id(k);
  return s;
}

}  // namespace

// --- The frame ---------------------------------------------------------

void NetworkUi::refresh() {
  model_.poll();
  if (model_.generation() == shown_generation_) return;
  shown_generation_ = model_.generation();
  stations_ = model_.stations();
  measurements_ = model_.measurement_rows();
  lines_ = model_.lines();
}

void NetworkUi::draw(float width, float height) {
  refresh();
  plan_.drawn = false;
  station_table_.drawn = false;
  measurement_table_.drawn = false;
  audit_ = TextAudit{};
  const float font = ImGui::GetFontSize();
  // The side panel: 38 % of the width, at least 30 ems, at most half.
  const float side = std::round(std::min(std::max(width * 0.38f, font * 30.0f), width * 0.5f));
  const char* title = model_.schematic_plan() ? "Levelling network (schematic)"
                      : model_.network().space == geodesy::NetworkSpace::local ? "Network plan (local x, y turned to east, north)"
                                                                                : "Network plan (east, north at the centroid)";
  panel(audit_, title, 0, 0, width - side, height, [this] { draw_plan(); });
  panel(audit_, "Adjustment", width - side, 0, side, height, [this] { draw_side(); });
}


// --- The side panel ----------------------------------------------------

void NetworkUi::draw_side() {
  const auto& result = model_.result();
  const geodesy::Network& net = model_.network();
  const float font = ImGui::GetFontSize();
  std::string title = net.source_name + " — " + std::to_string(net.stations.size()) + " stations, " +
                      std::to_string(net.measurements.size()) + " measurements";
  if (net.space == geodesy::NetworkSpace::ellipsoidal && net.frame) title += ", " + net.frame->to_string();
  if (net.space == geodesy::NetworkSpace::local) title += ", local " + std::to_string(net.local_dimensions) + "-D";
  ImGui::PushFont(ImGui::GetIO().Fonts->Fonts[1]);
  detail::wrapped(audit_, title, "adjustment: title");
  ImGui::PopFont();
  if (model_.busy()) detail::wrapped(audit_, "adjusting… (the last result is shown)", "adjustment: status");
  if (!result) {
    detail::wrapped_coloured(audit_, palette::kOutlier, "No adjustment: " + model_.error(), "adjustment: refused");
  } else {
    const auto& r = *result;
    const auto& gt = r.global_test;
    detail::wrapped(audit_,
                    "vᵀPv " + detail::fmt("%.3f", r.vtpv) + ", dof " + std::to_string(r.dof) +
                        (r.sigma0 ? ", σ0 " + detail::fmt("%.4f", *r.sigma0) + " (variance factor " + detail::fmt("%.4f", *r.variance_factor) + ")"
                                  : std::string(", σ0 undefined")),
                    "adjustment: statistics");
    if (gt.applicable) {
      detail::wrapped_coloured(audit_, gt.passed ? palette::kPass : palette::kOutlier,
                               "global test (" + detail::fmt("%g", 100.0 * model_.options().confidence) + " %): " +
                                   detail::fmt("%.2f", gt.statistic) + " in [" + detail::fmt("%.2f", gt.critical_lower) + ", " +
                                   detail::fmt("%.2f", gt.critical_upper) + "]: " + (gt.passed ? "passed" : "FAILED"),
                               "adjustment: global test");
    } else {
      detail::wrapped(audit_, "global test: not applicable (no redundancy)", "adjustment: global test");
    }
    std::size_t outliers = 0, flagged = 0;
    for (const auto& am : r.measurements) {
      outliers += am.outlier ? 1u : 0u;
      flagged += am.status(r.alpha_point) == solver::TestStatus::flagged ? 1u : 0u;
    }
    detail::wrapped(audit_,
                    std::to_string(r.iterations) + " iterations, " + (r.converged ? "converged" : "NOT converged") + "; " +
                        std::to_string(flagged) + " flagged (failing, kept), " + std::to_string(outliers) +
                        " removed" + (model_.options().remove_outliers ? " by data snooping" : " (--remove-outliers off)"),
                    "adjustment: iterations");
  }
  const auto stations_out = model_.stations_left_out();
  const auto measurements_out = model_.measurements_left_out();
  if (!stations_out.empty() || !measurements_out.empty()) {
    std::string s = "left out:";
    if (!stations_out.empty()) {
      s += " stations";
      for (const auto& id : stations_out) s += " " + id;
    }
    if (!measurements_out.empty()) {
      s += std::string(stations_out.empty() ? "" : ";") + " measurements";
      for (std::size_t m : measurements_out) s += " " + measurement_name(m);
    }
    detail::wrapped_coloured(audit_, palette::kLeftOut, s, "adjustment: left out");
  }

  // The legend: each class with its count of measurements, and the station
  // symbols.
  ImDrawList* dl = ImGui::GetWindowDrawList();
  const double w_critical = model_.w_critical();
  std::array<std::size_t, kMeasurementClasses>& counts = plan_.measurements_by_class;
  counts = {};
  for (const auto& row : measurements_) ++counts[static_cast<std::size_t>(row.shown_as)];
  const std::string wc = std::isfinite(w_critical) ? detail::fmt("%.2f", w_critical) : std::string("w_c");
  ImGui::Spacing();
  detail::wrapped(audit_,
                  "Measurements, by their measurement test at α " + detail::fmt("%g", model_.options().alpha_point) + " (critical |w| " +
                      wc + ") and largest |w|; drawn as lines, points and heights framed at their station",
                  "adjustment: legend");
  const float swatch = font * 2.0f;
  for (std::size_t i = 0; i < kMeasurementClasses; ++i) {
    const ImVec2 p = ImGui::GetCursorScreenPos();
    const float y = p.y + ImGui::GetTextLineHeight() * 0.5f;
    const auto c = static_cast<MeasurementClass>(i);
    line(dl, Eigen::Vector2d(p.x, y), Eigen::Vector2d(p.x + swatch, y), style_of(c));
    ImGui::SetCursorScreenPos(ImVec2(p.x + swatch + font * 0.4f, p.y));
    detail::text(audit_, describe(c, w_critical) + ": " + std::to_string(counts[i]), "adjustment: legend");
  }
  detail::wrapped(audit_, "Stations: ▲ datum holds a component, ● free, ○ not adjusted; click one on the plan to leave it out",
                  "adjustment: legend");

  // The two tables share what is left: stations a third, measurements the rest.
  const float line_h = ImGui::GetTextLineHeightWithSpacing();
  const float left = ImGui::GetContentRegionAvail().y;
  const float station_h = std::max(std::floor((left - 4.0f * line_h) * 0.36f), ImGui::GetFrameHeight() * 3.0f);
  ImGui::Spacing();
  draw_station_table(station_h);
  draw_measurement_table(std::max(ImGui::GetContentRegionAvail().y - line_h * 1.2f, ImGui::GetFrameHeight() * 3.0f));
}

namespace {

// A cell's text, checked against its column (rows scroll: only the width counts).
void cell(TextAudit& audit, const std::string& s, std::string_view where, std::optional<Rgb> colour = std::nullopt) {
  ImGuiTable* table = ImGui::GetCurrentTable();
  const float available = table->Columns[table->CurrentColumn].MaxX - ImGui::GetCursorScreenPos().x;
  if (colour) ImGui::PushStyleColor(ImGuiCol_Text, detail::col4(*colour));
  ImGui::TextUnformatted(s.c_str());
  if (colour) ImGui::PopStyleColor();
  audit.check_width(s, where, ImGui::CalcTextSize(s.c_str()).x, available);
}

// The line under a table: which rows are in view.
std::string rows_line(const NetworkTableGeometry& t, const char* what) {
  if (t.total == 0) return std::string("no ") + what;
  if (t.shown == t.total) return "all " + std::to_string(t.total) + " " + what + " in view";
  if (t.shown == 0) return "no whole row in view of " + std::to_string(t.total) + " " + what;
  return std::string(what) + " " + std::to_string(t.first + 1) + "–" + std::to_string(t.first + t.shown) + " of " +
         std::to_string(t.total) + " in view (scroll for the rest)";
}

constexpr ImGuiTableFlags kTableFlags = ImGuiTableFlags_ScrollY | ImGuiTableFlags_RowBg | ImGuiTableFlags_BordersOuter |
                                        ImGuiTableFlags_BordersV | ImGuiTableFlags_SizingFixedFit;

// The rows of the table just begun, `n` of them, clipped to its view:
// `row(i)` fills row i after the row is begun; `t` learns the rows wholly
// in view.
template <class Row>
void clipped_rows(NetworkTableGeometry& t, std::size_t n, Row&& row) {
  ImGuiTable* table = ImGui::GetCurrentTable();
  const float row_h = ImGui::GetFrameHeight() + 2.0f * ImGui::GetStyle().CellPadding.y;
  t.left = table->OuterRect.Min.x;
  t.row_height_px = row_h;
  bool first = true;
  ImGuiListClipper clipper;
  clipper.Begin(static_cast<int>(n), row_h);
  while (clipper.Step()) {
    for (int i = clipper.DisplayStart; i < clipper.DisplayEnd; ++i) {
      ImGui::TableNextRow(ImGuiTableRowFlags_None, row_h);
      const float top = table->RowPosY1;
      if (top >= table->BgClipRect.Min.y - 0.5f && top + row_h <= table->BgClipRect.Max.y + 0.5f) {
        if (first) t.first = static_cast<std::size_t>(i), t.first_row_top = top;
        first = false;
        ++t.shown;
      }
      ImGui::PushID(i);
      row(static_cast<std::size_t>(i));
      ImGui::PopID();
    }
  }
}

}  // namespace

void NetworkUi::draw_station_table(float height) {
  const bool local = model_.network().space == geodesy::NetworkSpace::local;
  const int dimensions = model_.network().local_dimensions;
  NetworkTableGeometry& t = station_table_;
  t = NetworkTableGeometry{};
  t.drawn = true;
  t.total = stations_.size();
  std::optional<std::pair<std::string, bool>> toggle;
  if (ImGui::BeginTable("stations", 7, kTableFlags, ImVec2(0.0f, height))) {
    ImGui::TableSetupScrollFreeze(0, 1);
    ImGui::TableSetupColumn("use");
    ImGui::TableSetupColumn("station");
    ImGui::TableSetupColumn(local ? "σx mm" : "σE mm");
    ImGui::TableSetupColumn(local ? "σy mm" : "σN mm");
    ImGui::TableSetupColumn(local ? "σz mm" : "σU mm");
    ImGui::TableSetupColumn("datum");
    ImGui::TableSetupColumn("status", ImGuiTableColumnFlags_WidthStretch);
    detail::header_row(audit_, "stations: header");
    clipped_rows(t, stations_.size(), [&](std::size_t i) {
      const NetworkStationRow& s = stations_[i];
      const bool left_out = model_.station_left_out(i);  // the choice as it stands, not as last adjusted
      ImGui::TableNextColumn();
      bool use = !left_out;
      if (ImGui::Checkbox("##use", &use)) toggle = {s.id, !use};
      ImGui::TableNextColumn();
      cell(audit_, s.id, "stations: id");
      for (int k = 0; k < 3; ++k) {
        ImGui::TableNextColumn();
        // A levelling network has no x, y; a 2-D network no z.
        const bool absent = local && (dimensions == 1 ? k < 2 : dimensions == 2 && k == 2);
        cell(audit_, s.used && !absent ? detail::fmt("%.1f", 1e3 * s.sigma_m(k)) : std::string("-"), "stations: sigma");
      }
      ImGui::TableNextColumn();
      cell(audit_, s.constraint, "stations: datum");
      ImGui::TableNextColumn();
      if (left_out) {
        cell(audit_, "left out", "stations: status", palette::kLeftOut);
      } else if (!s.used) {
        cell(audit_, "not adjusted", "stations: status", palette::kLeftOut);
      } else {
        cell(audit_, "adjusted", "stations: status");
      }
    });
    ImGui::EndTable();
  }
  detail::text(audit_, rows_line(t, "stations"), "stations: rows");
  if (toggle) model_.set_station_left_out(toggle->first, toggle->second);
}

void NetworkUi::draw_measurement_table(float height) {
  const geodesy::Network& net = model_.network();
  NetworkTableGeometry& t = measurement_table_;
  t = NetworkTableGeometry{};
  t.drawn = true;
  t.total = net.measurements.size();
  std::optional<std::pair<std::size_t, bool>> toggle;
  if (ImGui::BeginTable("measurements", 6, kTableFlags, ImVec2(0.0f, height))) {
    ImGui::TableSetupScrollFreeze(0, 1);
    ImGui::TableSetupColumn("use");
    ImGui::TableSetupColumn("#");
    ImGui::TableSetupColumn("kind");
    ImGui::TableSetupColumn("stations");
    ImGui::TableSetupColumn("max |w|");
    ImGui::TableSetupColumn("status", ImGuiTableColumnFlags_WidthStretch);
    detail::header_row(audit_, "measurements: header");
    clipped_rows(t, net.measurements.size(), [&](std::size_t mi) {
      const auto& m = net.measurements[mi];
      const NetworkMeasurementRow& row = measurements_[mi];
      // The choices as they stand, not as last adjusted.
      const bool by_choice = model_.measurement_left_out(mi), by_station = model_.measurement_out_through_station(mi);
      ImGui::TableNextColumn();
      bool use = !by_choice && !by_station;
      // Out through a station, or ignored by its input: not the user's to take back here.
      const bool fixed = (by_station || m.ignore) && !by_choice;
      if (fixed) ImGui::BeginDisabled();
      if (ImGui::Checkbox("##use", &use)) toggle = {mi, !use};
      if (fixed) ImGui::EndDisabled();
      ImGui::TableNextColumn();
      cell(audit_, measurement_name(mi), "measurements: #");
      ImGui::TableNextColumn();
      cell(audit_, geodesy::to_string(m.kind), "measurements: kind");
      ImGui::TableNextColumn();
      cell(audit_, stations_text(net, m), "measurements: stations");
      ImGui::TableNextColumn();
      const MeasurementClass c = row.shown_as;
      const std::string w = std::isfinite(row.w_max) ? detail::fmt("%.2f", row.w_max) : std::string("-");
      cell(audit_, w, "measurements: w",
           flagged(c)                          ? std::optional<Rgb>(palette::kOutlier)
           : c == MeasurementClass::elevated ? std::optional<Rgb>(palette::kWarning)
                                             : std::nullopt);
      ImGui::TableNextColumn();
      if (by_choice) {
        cell(audit_, "left out", "measurements: status", palette::kLeftOut);
      } else if (by_station) {
        cell(audit_, "left out with its station", "measurements: status", palette::kLeftOut);
      } else if (m.ignore) {
        cell(audit_, "ignored by its input", "measurements: status", palette::kLeftOut);
      } else {
        cell(audit_, status_text(c), "measurements: status",
             flagged(c)                          ? std::optional<Rgb>(palette::kOutlier)
             : c == MeasurementClass::left_out ? std::optional<Rgb>(palette::kLeftOut)
                                               : std::nullopt);
      }
    });
    ImGui::EndTable();
  }
  detail::text(audit_, rows_line(t, "measurements"), "measurements: rows");
  if (toggle) model_.set_measurement_left_out(toggle->first, toggle->second);
}

}  // namespace geoanchor::gui

