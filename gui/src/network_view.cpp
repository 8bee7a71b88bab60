// The network view: the plan of stations and measurements coloured by
// their w-tests, with error ellipses, and beside it the adjustment's
// statistics and the tables whose check boxes leave stations and
// measurements out (network_ui.hpp).

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <utility>

#include "geoanchor/gui/network_ui.hpp"
#include "plan_layout.hpp"
#include "ui_common.hpp"

namespace geoanchor::gui {

using detail::Box;
using detail::candidates;
using detail::col;
using detail::iv;
using detail::Obstacles;
using detail::panel;

Eigen::Vector2d NetworkGeometry::pixel_of(const Eigen::Vector2d& en_m) const {
  const Eigen::Vector2d c(0.5 * (left + right), 0.5 * (top + bottom));
  return c + px_per_m * Eigen::Vector2d(en_m.x() - center_m.x(), -(en_m.y() - center_m.y()));
}

std::string NetworkUi::measurement_name(std::size_t index) { return "#" + std::to_string(index + 1); }

NetworkUi::NetworkUi(NetworkModel& model) : model_(model) {}

namespace {

struct LineStyle {
  Rgb colour;
  float thickness;
  bool dashed;
};

LineStyle style_of(MeasurementClass c) {
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
constexpr std::array<MeasurementClass, kMeasurementClasses> kDrawOrder{MeasurementClass::left_out, MeasurementClass::untestable,
                                                                       MeasurementClass::small,    MeasurementClass::elevated,
                                                                       MeasurementClass::failing,  MeasurementClass::outlier};

// A length in millimetres for the caption: whole millimetres from 10 mm,
// two significant digits below.
std::string mm_text(double mm) { return mm >= 10.0 ? detail::fmt("%.0f", mm) : detail::fmt("%.2g", mm); }

bool flagged(MeasurementClass c) { return c == MeasurementClass::outlier || c == MeasurementClass::failing; }

void line(ImDrawList* dl, const Eigen::Vector2d& a, const Eigen::Vector2d& b, const LineStyle& s) {
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

double segment_distance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d d = b - a;
  const double l2 = d.squaredNorm();
  const double t = l2 > 0.0 ? std::clamp((p - a).dot(d) / l2, 0.0, 1.0) : 0.0;
  return (p - (a + t * d)).norm();
}

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

// --- The plan ----------------------------------------------------------

void NetworkUi::draw_plan() {
  ImDrawList* dl = ImGui::GetWindowDrawList();
  ImFont* regular = ImGui::GetIO().Fonts->Fonts[0];
  ImFont* bold = ImGui::GetIO().Fonts->Fonts[1];
  const float font = ImGui::GetFontSize();
  const float id_size = std::round(font * 0.8f);
  const ImVec2 c0 = ImGui::GetCursorScreenPos();
  const ImVec2 avail = ImGui::GetContentRegionAvail();
  const geodesy::Network& net = model_.network();
  NetworkGeometry& g = plan_;
  g = NetworkGeometry{};
  g.schematic = model_.schematic_plan();
  g.confidence = model_.options().confidence;
  const bool dense = stations_.size() > kDenseNetworkStations;
  const double w_critical = model_.w_critical();
  const float r_px = std::max(3.0f, std::round(font * 0.25f));

  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  double max_a_m = 0.0;
  for (const auto& s : stations_) {
    lo = lo.cwiseMin(s.plan_m);
    hi = hi.cwiseMax(s.plan_m);
    if (s.used) max_a_m = std::max(max_a_m, s.ellipse_confidence.semi_major_m);
  }
  if (stations_.empty()) lo = hi = Eigen::Vector2d::Zero();
  g.center_m = 0.5 * (lo + hi);
  const Eigen::Vector2d span = (hi - lo).cwiseMax(g.schematic ? 0.5 : 1.0);
  const bool ellipses = !dense && !g.schematic && max_a_m > 0.0;
  // The median distance from a station to its nearest neighbour: ellipses
  // whose semi-major axis is drawn longer than it reach their neighbours.
  double spacing_m = std::numeric_limits<double>::infinity();
  if (ellipses) {
    std::vector<double> nearest;
    for (std::size_t a = 0; a < stations_.size(); ++a) {
      double d = std::numeric_limits<double>::infinity();
      for (std::size_t b = 0; b < stations_.size(); ++b) {
        const double ab = (stations_[a].plan_m - stations_[b].plan_m).norm();
        if (b != a && ab > 0.0) d = std::min(d, ab);
      }
      if (std::isfinite(d)) nearest.push_back(d);
    }
    if (!nearest.empty()) {
      std::nth_element(nearest.begin(), nearest.begin() + static_cast<std::ptrdiff_t>(nearest.size() / 2), nearest.end());
      spacing_m = nearest[nearest.size() / 2];
    }
  }

  // The measurements labelled on the plan: outliers and failing ones,
  // worst first; those with lines at their first line's middle, the others
  // (points, heights) at their first station.
  std::vector<std::pair<double, std::size_t>> flagged_lines;  // (|w|, line index), a measurement's first line
  {
    std::vector<bool> seen(measurements_.size(), false);
    for (std::size_t i = 0; i < lines_.size(); ++i) {
      if (!flagged(lines_[i].shown_as) || seen[lines_[i].measurement]) continue;
      seen[lines_[i].measurement] = true;
      flagged_lines.push_back({std::isfinite(lines_[i].w_max) ? lines_[i].w_max : 0.0, i});
    }
  }
  std::stable_sort(flagged_lines.begin(), flagged_lines.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<std::size_t> flagged_at_stations;
  for (const auto& row : measurements_) {
    if (!row.has_line && flagged(row.shown_as)) flagged_at_stations.push_back(row.index);
  }
  const auto measurement_label = [&](std::size_t index) {
    const NetworkMeasurementRow& row = measurements_[index];
    const std::string w = std::isfinite(row.w_max) ? detail::fmt("%.2f", row.w_max) : std::string("-");
    return measurement_name(index) + (row.shown_as == MeasurementClass::outlier ? " outlier" : " fails") + ", |w| " + w + " (" +
           geodesy::to_string(net.measurements[index].kind) + ")";
  };

  // The footer (scale bar and caption) wraps at the panel's width; its
  // height follows from the caption: settle both in up to three passes.
  const float wrap_w = std::max(avail.x - font * 0.5f, font * 4.0f);
  float footer_h = std::round(font * 3.0f);
  std::string caption;
  std::vector<PlanLabel> labels;
  std::vector<std::string> unlabelled;
  double k = 1.0;  // pixels per metre of ellipse
  for (int pass = 0; pass < 3; ++pass) {
    g.left = c0.x;
    g.top = c0.y;
    g.right = c0.x + std::max(avail.x, 4 * kPlanMarginPx);
    g.bottom = c0.y + std::max(avail.y - footer_h, 4 * kPlanMarginPx);
    g.px_per_m = std::min((g.right - g.left - 2 * kPlanMarginPx) / span.x(), (g.bottom - g.top - 2 * kPlanMarginPx) / span.y());
    const double short_side_px = std::min(g.right - g.left, g.bottom - g.top);
    // The largest ellipse at most a twentieth of the plan's short side and
    // the stations' median spacing, the factor rounded down to 1, 2
    // or 5 × 10^k (at least 1).
    const double largest_px = std::min(0.05 * short_side_px, spacing_m * g.px_per_m);
    g.ellipse_exaggeration = ellipses ? std::max(1.0, detail::nice_floor(largest_px / (g.px_per_m * max_a_m))) : 1.0;
    g.scale_bar_m = g.schematic ? 0.0 : detail::nice_floor(0.25 * (g.right - g.left) / g.px_per_m);
    k = g.ellipse_exaggeration * g.px_per_m;

    // Labels: flagged measurements first (at their line's middle), then
    // station ids, each where it covers no mark and no other label.
    labels.clear();
    unlabelled.clear();
    g.labelled_measurements.clear();
    const Box area{g.left + 2.0f, g.top + 2.0f, g.right - 2.0f, g.bottom - 2.0f};
    Obstacles obstacles(area, font * 2.0f);
    obstacles.add(Box{g.left, g.top, g.left + font * 2.0f, g.top + font * 4.2f});  // the north arrow
    for (const auto& s : stations_) {
      const Eigen::Vector2d p = g.pixel_of(s.plan_m);
      const float e = r_px + 2.0f;
      obstacles.add(Box{static_cast<float>(p.x()) - e, static_cast<float>(p.y()) - e, static_cast<float>(p.x()) + e,
                        static_cast<float>(p.y()) + e});
    }
    const auto place = [&](const std::string& text, std::optional<std::size_t> measurement, const Eigen::Vector2d& p, ImFont* f,
                           float size) {
      const ImVec2 ts = detail::text_size(text, f, size);
      for (const auto& [box, leader] : candidates(p, r_px, ts.x + 2.0f, ts.y, Eigen::Vector2d::Zero(), size)) {
        if (!box.inside(area) || !obstacles.free(box)) continue;
        obstacles.add(box);
        const std::string key = measurement ? measurement_name(*measurement) : text;
        labels.push_back({key, box.x0, box.y0, box.x1, box.y1, p, leader, measurement});
        if (measurement) g.labelled_measurements.push_back(*measurement);
        return true;
      }
      return false;
    };
    for (const auto& [w, i] : flagged_lines) {
      const NetworkLine& l = lines_[i];
      const Eigen::Vector2d mid = 0.5 * (g.pixel_of(stations_[l.from].plan_m) + g.pixel_of(stations_[l.to].plan_m));
      place(measurement_label(l.measurement), l.measurement, mid, bold, font);
    }
    for (std::size_t index : flagged_at_stations) {
      const auto& m = net.measurements[index];
      if (!m.stations.empty()) place(measurement_label(index), index, g.pixel_of(stations_[m.stations[0]].plan_m), bold, font);
    }
    if (!dense) {
      for (const auto& s : stations_) {
        if (!place(s.id, std::nullopt, g.pixel_of(s.plan_m), regular, id_size)) unlabelled.push_back(s.id);
      }
    }

    if (g.schematic) {
      caption = "a levelling network has no plan positions: its stations stand on a circle in their order (a schematic); "
                "lines: each measurement's test and largest |w|";
    } else {
      caption = "lines: each measurement's test and largest |w| (see the legend)";
      if (ellipses) {
        caption += "; ellipses: each station's " + detail::fmt("%g", 100.0 * g.confidence) +
                   " % error ellipse (a-priori weights, σ0 = 1) × " + detail::fmt("%g", g.ellipse_exaggeration) + " (10 px = " +
                   mm_text(10.0 / k * 1e3) + " mm)";
      } else if (dense) {
        caption += "\nmore than " + std::to_string(kDenseNetworkStations) +
                   " stations: no ellipses and no ids (hover over a station, or see the tables)";
      }
    }
    const std::size_t flagged_count = flagged_lines.size() + flagged_at_stations.size();
    if (g.labelled_measurements.size() < flagged_count) {
      caption += "\n" + std::to_string(flagged_count - g.labelled_measurements.size()) + " of " + std::to_string(flagged_count) +
                 " outliers and failing measurements found no room for their label: see the measurements table";
    }
    if (!unlabelled.empty()) caption += "\n" + detail::unlabelled_caption(unlabelled, stations_.size(), "station", regular, font, wrap_w);
    const float needed = std::ceil(font * 1.5f + detail::text_size(caption, regular, font, wrap_w).y + font * 0.2f);
    if (needed <= footer_h) break;
    footer_h = needed;
  }
  g.drawn = true;
  g.labels = labels;
  g.unlabelled = unlabelled;

  dl->AddRectFilled(ImVec2(g.left, g.top), ImVec2(g.right, g.bottom), col(palette::kBackground));
  dl->AddRect(ImVec2(g.left, g.top), ImVec2(g.right, g.bottom), col(palette::kGrid));
  dl->PushClipRect(ImVec2(g.left, g.top), ImVec2(g.right, g.bottom), true);
  // Ellipses under everything.
  if (ellipses) {
    constexpr int kSegments = 32;
    for (const auto& s : stations_) {
      const auto& e = s.ellipse_confidence;
      if (!s.used || !(e.semi_major_m > 0.0)) continue;
      const Eigen::Vector2d p = g.pixel_of(s.plan_m);
      const Eigen::Vector2d major(std::sin(e.azimuth_rad), std::cos(e.azimuth_rad)), minor(major.y(), -major.x());  // E, N
      ImVec2 pts[kSegments];
      for (int i = 0; i < kSegments; ++i) {
        const double t = 2.0 * std::numbers::pi * i / kSegments;
        const Eigen::Vector2d en = e.semi_major_m * std::cos(t) * major + e.semi_minor_m * std::sin(t) * minor;
        pts[i] = iv(p + k * Eigen::Vector2d(en.x(), -en.y()));
      }
      dl->AddPolyline(pts, kSegments, col(palette::kEllipse, 170), ImDrawFlags_Closed, 1.2f);
      ++g.ellipses_drawn;
    }
  }
  // Lines, the least telling first.
  for (const MeasurementClass c : kDrawOrder) {
    const LineStyle st = style_of(c);
    for (const auto& l : lines_) {
      if (l.shown_as != c) continue;
      line(dl, g.pixel_of(stations_[l.from].plan_m), g.pixel_of(stations_[l.to].plan_m), st);
      ++g.lines_by_class[static_cast<std::size_t>(c)];
    }
  }
  // Stations: a triangle where the datum holds a component, else a circle;
  // hollow grey when not adjusted; a vermillion square round a station
  // whose point or height measurement is flagged.
  for (const auto& s : stations_) {
    const Eigen::Vector2d p = g.pixel_of(s.plan_m);
    const bool held = s.constraint.find('C') != std::string::npos;
    const ImU32 ink = col(s.used ? palette::kInk : palette::kLeftOut);
    if (held) {
      const float h = r_px * 1.5f;
      const ImVec2 a(static_cast<float>(p.x()), static_cast<float>(p.y()) - h), b(static_cast<float>(p.x()) - h * 0.87f, static_cast<float>(p.y()) + h * 0.5f),
          c(static_cast<float>(p.x()) + h * 0.87f, static_cast<float>(p.y()) + h * 0.5f);
      if (s.used) dl->AddTriangleFilled(a, b, c, col(palette::kBackground));
      dl->AddTriangle(a, b, c, ink, 1.8f);
    } else {
      if (s.used) dl->AddCircleFilled(iv(p), r_px, ink, 12);
      else dl->AddCircle(iv(p), r_px, ink, 12, 1.5f);
    }
  }
  for (std::size_t index : flagged_at_stations) {
    for (std::size_t st : net.measurements[index].stations) {
      const Eigen::Vector2d p = g.pixel_of(stations_[st].plan_m);
      const float e = r_px + 3.0f;
      dl->AddRect(ImVec2(static_cast<float>(p.x()) - e, static_cast<float>(p.y()) - e), ImVec2(static_cast<float>(p.x()) + e, static_cast<float>(p.y()) + e),
                  col(palette::kOutlier), 0, 0, 2.5f);
    }
  }
  // Labels where the placement put them.
  for (const auto& l : g.labels) {
    const Rgb c = l.measurement ? palette::kOutlier : palette::kInk;
    if (l.leader) {
      const Eigen::Vector2d nearest(std::clamp(l.mark_px.x(), double(l.x0), double(l.x1)), std::clamp(l.mark_px.y(), double(l.y0), double(l.y1)));
      const Eigen::Vector2d d = nearest - l.mark_px;
      if (d.norm() > r_px + 2.0) dl->AddLine(iv(l.mark_px + (r_px + 1.0) * d.normalized()), iv(nearest), col(c, 160), 1.0f);
    }
    if (l.measurement) {
      detail::label(audit_, dl, ImVec2(l.x0 + 1.0f, l.y0), col(c), measurement_label(*l.measurement), "network: measurement label",
                    ImVec2(g.left, g.top), ImVec2(g.right, g.bottom), bold, font);
    } else {
      detail::label(audit_, dl, ImVec2(l.x0 + 1.0f, l.y0), col(c), l.id, "network: id", ImVec2(g.left, g.top), ImVec2(g.right, g.bottom),
                    regular, id_size);
    }
  }
  if (!g.schematic) {
    const ImVec2 na(g.left + font * 1.2f, g.top + font * 3.0f);
    dl->AddTriangleFilled(ImVec2(na.x, na.y - font * 1.6f), ImVec2(na.x - font * 0.4f, na.y), ImVec2(na.x + font * 0.4f, na.y),
                          col(palette::kInk));
    detail::label(audit_, dl, ImVec2(na.x - font * 0.3f, na.y + 2), col(palette::kInk), "N", "network: north arrow");
  }
  dl->PopClipRect();

  // Footer: the scale bar and the caption.
  const float by = g.bottom + font * 0.7f, bx = g.left + font * 0.5f;
  if (!g.schematic) {
    const float bar_px = static_cast<float>(g.scale_bar_m * g.px_per_m);
    dl->AddRectFilled(ImVec2(bx, by), ImVec2(bx + bar_px, by + 4), col(palette::kInk));
    dl->AddLine(ImVec2(bx, by - 4), ImVec2(bx, by + 8), col(palette::kInk), 1.5f);
    dl->AddLine(ImVec2(bx + bar_px, by - 4), ImVec2(bx + bar_px, by + 8), col(palette::kInk), 1.5f);
    detail::label(audit_, dl, ImVec2(bx + bar_px + font * 0.5f, by - font * 0.5f), col(palette::kInk), detail::length_label(g.scale_bar_m),
                  "network: scale bar");
  }
  detail::label(audit_, dl, ImVec2(bx, g.bottom + font * 1.5f), col(palette::kInk), caption, "network: caption", detail::kNoBound_lo,
                detail::kNoBound_hi, regular, font, wrap_w - font * 0.5f);

  // Under the mouse: a station (tooltip; a click leaves it out or takes it
  // back), else the measurements along a line (tooltip).
  ImGui::InvisibleButton("network plan", ImVec2(g.right - g.left, g.bottom - g.top));
  const bool hovered = ImGui::IsItemHovered(), clicked = ImGui::IsItemClicked();
  if (!hovered && !clicked) return;
  const ImVec2 mouse = ImGui::GetIO().MousePos;
  const Eigen::Vector2d m(mouse.x, mouse.y);
  const NetworkStationRow* best = nullptr;
  double best_d = 2.5 * r_px;
  for (const auto& s : stations_) {
    const double d = (g.pixel_of(s.plan_m) - m).norm();
    if (d < best_d) best_d = d, best = &s;
  }
  if (best) {
    g.hovered = best->id;
    const bool left_out = model_.station_left_out(static_cast<std::size_t>(best - stations_.data()));
    if (hovered) {
      ImGui::BeginTooltip();
      ImGui::PushFont(bold);
      ImGui::TextUnformatted(best->id.c_str());
      ImGui::PopFont();
      const bool local = net.space == geodesy::NetworkSpace::local;
      if (best->used) {
        ImGui::TextUnformatted((std::string(local ? "σ x/y/z " : "σ E/N/U ") + detail::fmt("%.1f", 1e3 * best->sigma_m.x()) + " / " +
                                detail::fmt("%.1f", 1e3 * best->sigma_m.y()) + " / " + detail::fmt("%.1f", 1e3 * best->sigma_m.z()) + " mm")
                                   .c_str());
        const auto& e = best->ellipse_confidence;
        ImGui::TextUnformatted((detail::fmt("%g", 100.0 * g.confidence) + " % ellipse " + detail::fmt("%.1f", 1e3 * e.semi_major_m) + " × " +
                                detail::fmt("%.1f", 1e3 * e.semi_minor_m) + " mm, azimuth from north " +
                                detail::fmt("%.0f", e.azimuth_rad * 180.0 / std::numbers::pi) + "°")
                                   .c_str());
      }
      ImGui::TextUnformatted(("datum " + best->constraint).c_str());
      ImGui::TextUnformatted(left_out ? "left out (click to take it back)"
                             : best->used   ? "adjusted (click to leave it and its measurements out)"
                                            : "not adjusted: no measurement reaches it");
      ImGui::EndTooltip();
    }
    if (clicked) model_.set_station_left_out(best->id, !left_out);
    return;
  }
  const NetworkLine* near = nullptr;
  double near_d = std::max(4.0, 0.4 * font);
  for (const auto& l : lines_) {
    const double d = segment_distance(m, g.pixel_of(stations_[l.from].plan_m), g.pixel_of(stations_[l.to].plan_m));
    if (d < near_d) near_d = d, near = &l;
  }
  if (!near || !hovered) return;
  g.hovered = measurement_name(near->measurement);
  ImGui::BeginTooltip();
  ImGui::PushFont(bold);
  ImGui::TextUnformatted((stations_[near->from].id + " – " + stations_[near->to].id).c_str());
  ImGui::PopFont();
  for (const auto& l : lines_) {
    const bool same = (l.from == near->from && l.to == near->to) || (l.from == near->to && l.to == near->from);
    if (!same) continue;
    const MeasurementClass c = l.shown_as;
    const std::string w = std::isfinite(l.w_max) ? detail::fmt("%.2f", l.w_max) : std::string("-");
    ImGui::PushStyleColor(ImGuiCol_Text, detail::col4(c == MeasurementClass::small ? palette::kInk : style_of(c).colour));
    ImGui::TextUnformatted((measurement_name(l.measurement) + " " + geodesy::to_string(net.measurements[l.measurement].kind) + ", |w| " + w +
                            ", " + describe(c, w_critical))
                               .c_str());
    ImGui::PopStyleColor();
  }
  ImGui::TextUnformatted("leave a measurement out in the measurements table");
  ImGui::EndTooltip();
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
    std::size_t outliers = 0;
    for (const auto& am : r.measurements) outliers += am.outlier ? 1u : 0u;
    detail::wrapped(audit_,
                    std::to_string(r.iterations) + " iterations, " + (r.converged ? "converged" : "NOT converged") + "; " +
                        std::to_string(outliers) + (outliers == 1 ? " outlier" : " outliers") + " removed by data snooping" +
                        (model_.options().data_snooping ? "" : " (off)"),
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
