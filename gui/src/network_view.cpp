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
#include <stdexcept>
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

namespace {
// A station the datum holds in some component: drawn as a triangle of its
// own, never merged into a cell's mark.
bool held(const NetworkStationRow& s) { return s.constraint.find('C') != std::string::npos; }
}  // namespace

NetworkUi::NetworkUi(NetworkModel& model) : model_(model) {}

void NetworkUi::set_plan_view(double zoom, const Eigen::Vector2d& center_m) {
  if (!std::isfinite(zoom) || zoom < 1.0 || !center_m.allFinite()) {
    throw std::invalid_argument("NetworkUi::set_plan_view: zoom=" + std::to_string(zoom) + ", centre " + std::to_string(center_m.x()) +
                                ", " + std::to_string(center_m.y()) + " m: expected a finite zoom of at least 1 and a finite centre");
  }
  zoom_ = zoom;
  view_center_m_ = center_m;
}

void NetworkUi::reset_plan_view() {
  zoom_ = 1.0;
  view_center_m_.reset();
}

const PlanLod& NetworkUi::level_of_detail() {
  const NetworkGeometry& g = plan_;
  LodCache& c = lod_cache_;
  if (c.valid && c.generation == shown_generation_ && c.px_per_m == g.px_per_m && c.center_m == g.center_m && c.left == g.left &&
      c.top == g.top && c.right == g.right && c.bottom == g.bottom) {
    return c.lod;
  }
  std::vector<Eigen::Vector2d> px(stations_.size());
  std::vector<bool> own(stations_.size());
  for (std::size_t s = 0; s < stations_.size(); ++s) {
    px[s] = g.pixel_of(stations_[s].plan_m);
    own[s] = held(stations_[s]);
  }
  c.lod = plan_level_of_detail(px, own, lines_, LodArea{g.left, g.top, g.right, g.bottom});
  c.valid = true;
  c.generation = shown_generation_;
  c.px_per_m = g.px_per_m;
  c.center_m = g.center_m;
  c.left = g.left, c.top = g.top, c.right = g.right, c.bottom = g.bottom;
  return c.lod;
}

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
  const double w_critical = model_.w_critical();
  const float r_px = std::max(3.0f, std::round(font * 0.25f));

  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& s : stations_) {
    lo = lo.cwiseMin(s.plan_m);
    hi = hi.cwiseMax(s.plan_m);
  }
  if (stations_.empty()) lo = hi = Eigen::Vector2d::Zero();
  g.zoom = zoom_;
  g.center_m = view_center_m_ ? *view_center_m_ : Eigen::Vector2d(0.5 * (lo + hi));
  const Eigen::Vector2d span = (hi - lo).cwiseMax(g.schematic ? 0.5 : 1.0);
  // The plotting area and scale for a footer of `footer_px`.
  const auto settle = [&](float footer_px) {
    g.left = c0.x;
    g.top = c0.y;
    g.right = c0.x + std::max(avail.x, 4 * kPlanMarginPx);
    g.bottom = c0.y + std::max(avail.y - footer_px, 4 * kPlanMarginPx);
    g.px_per_m = zoom_ * std::min((g.right - g.left - 2 * kPlanMarginPx) / span.x(), (g.bottom - g.top - 2 * kPlanMarginPx) / span.y());
  };
  float footer_h = std::round(font * 3.0f);
  settle(footer_h);
  // The stations in view (at the first footer's area: what is dense does
  // not change with the caption's height).
  std::vector<std::size_t> visible;
  for (std::size_t s = 0; s < stations_.size(); ++s) {
    const Eigen::Vector2d p = g.pixel_of(stations_[s].plan_m);
    if (p.x() >= g.left && p.x() <= g.right && p.y() >= g.top && p.y() <= g.bottom) visible.push_back(s);
  }
  g.stations_in_view = visible.size();
  const bool dense = visible.size() > kDenseNetworkStations;
  g.aggregated = dense;
  double max_a_m = 0.0;
  for (std::size_t s : visible) {
    if (stations_[s].used) max_a_m = std::max(max_a_m, stations_[s].ellipse_confidence.semi_major_m);
  }
  const bool ellipses = !dense && !g.schematic && max_a_m > 0.0;
  // The median distance from a station to its nearest neighbour: ellipses
  // whose semi-major axis is drawn longer than it reach their neighbours.
  double spacing_m = std::numeric_limits<double>::infinity();
  if (ellipses) {
    std::vector<double> nearest;
    for (std::size_t a : visible) {
      double d = std::numeric_limits<double>::infinity();
      for (std::size_t b : visible) {
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
  std::string caption;
  std::vector<PlanLabel> labels;
  std::vector<std::string> unlabelled;
  double k = 1.0;  // pixels per metre of ellipse
  for (int pass = 0; pass < 3; ++pass) {
    settle(footer_h);
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
    const auto mark = [&](const Eigen::Vector2d& p) {
      const float e = r_px + 2.0f;
      obstacles.add(Box{static_cast<float>(p.x()) - e, static_cast<float>(p.y()) - e, static_cast<float>(p.x()) + e,
                        static_cast<float>(p.y()) + e});
    };
    if (dense) {
      // Labels go over the cells' marks (on a background of their own),
      // never over a held station or a flagged measurement's stations.
      // (The held stations in view are the level of detail's own marks;
      // the level of detail itself is taken once, at the settled area.)
      for (std::size_t s : visible) {
        if (held(stations_[s])) mark(g.pixel_of(stations_[s].plan_m));
      }
      for (const auto& [w, i] : flagged_lines) {
        mark(g.pixel_of(stations_[lines_[i].from].plan_m));
        mark(g.pixel_of(stations_[lines_[i].to].plan_m));
      }
    } else {
      for (std::size_t s : visible) mark(g.pixel_of(stations_[s].plan_m));
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
    // A flagged measurement out of view is not labelled (nor counted as
    // finding no room).
    const auto in_area = [&](const Eigen::Vector2d& p) { return p.x() >= g.left && p.x() <= g.right && p.y() >= g.top && p.y() <= g.bottom; };
    std::size_t flagged_in_view = 0;
    for (const auto& [w, i] : flagged_lines) {
      const NetworkLine& l = lines_[i];
      const Eigen::Vector2d mid = 0.5 * (g.pixel_of(stations_[l.from].plan_m) + g.pixel_of(stations_[l.to].plan_m));
      if (!in_area(mid)) continue;
      ++flagged_in_view;
      place(measurement_label(l.measurement), l.measurement, mid, bold, font);
    }
    for (std::size_t index : flagged_at_stations) {
      const auto& m = net.measurements[index];
      if (m.stations.empty() || !in_area(g.pixel_of(stations_[m.stations[0]].plan_m))) continue;
      ++flagged_in_view;
      place(measurement_label(index), index, g.pixel_of(stations_[m.stations[0]].plan_m), bold, font);
    }
    if (!dense) {
      for (std::size_t s : visible) {
        if (!place(stations_[s].id, std::nullopt, g.pixel_of(stations_[s].plan_m), regular, id_size)) unlabelled.push_back(stations_[s].id);
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
        caption += "\n" + std::to_string(visible.size()) + " stations in view (more than " + std::to_string(kDenseNetworkStations) +
                   "): lines between the same two " + detail::fmt("%g", kLodCell_px) +
                   " px cells drawn as one, in their most telling class; outliers and failing measurements each drawn on their own, ringed, and labelled where there is room; "
                   "no ellipses and no ids (zoom in, hover over a station, or see the tables)";
      }
      if (zoom_ != 1.0 || view_center_m_) {
        caption += "\nzoomed × " + detail::fmt("%.3g", zoom_) + " (mouse wheel; right-drag pans, right double-click shows the whole network)";
      }
    }
    const std::size_t flagged_count = flagged_in_view;
    if (g.labelled_measurements.size() < flagged_count) {
      caption += "\n" + std::to_string(flagged_count - g.labelled_measurements.size()) + " of " + std::to_string(flagged_count) +
                 " outliers and failing measurements in view found no room for their label: see the measurements table";
    }
    if (!unlabelled.empty()) caption += "\n" + detail::unlabelled_caption(unlabelled, stations_.size(), "station", regular, font, wrap_w);
    const float needed = std::ceil(font * 1.5f + detail::text_size(caption, regular, font, wrap_w).y + font * 0.2f);
    if (needed <= footer_h) break;
    footer_h = needed;
  }
  g.drawn = true;
  g.labels = labels;
  g.unlabelled = unlabelled;
  // Each station's pixel at the settled geometry, once (a 10⁵-station
  // network's lines would otherwise project their ends a million times).
  std::vector<Eigen::Vector2d> px(stations_.size());
  for (std::size_t s = 0; s < stations_.size(); ++s) px[s] = g.pixel_of(stations_[s].plan_m);

  dl->AddRectFilled(ImVec2(g.left, g.top), ImVec2(g.right, g.bottom), col(palette::kBackground));
  dl->AddRect(ImVec2(g.left, g.top), ImVec2(g.right, g.bottom), col(palette::kGrid));
  dl->PushClipRect(ImVec2(g.left, g.top), ImVec2(g.right, g.bottom), true);
  // Ellipses under everything.
  if (ellipses) {
    // Segments of about 3 px along the drawn ellipse (8 to 32): a small
    // ellipse's 32 segments cost the rasterizer without showing more. One
    // pixel wide, which ImGui draws anti-aliased from its line texture (two
    // triangles a segment, against six for a fractional width).
    constexpr int kMinSegments = 8, kMaxSegments = 32;
    constexpr double kSegment_px = 3.0;
    for (std::size_t si : visible) {
      const NetworkStationRow& s = stations_[si];
      const auto& e = s.ellipse_confidence;
      if (!s.used || !(e.semi_major_m > 0.0)) continue;
      const Eigen::Vector2d& p = px[si];
      const Eigen::Vector2d major(std::sin(e.azimuth_rad), std::cos(e.azimuth_rad)), minor(major.y(), -major.x());  // E, N
      const double circumference_px = 2.0 * std::numbers::pi * k * e.semi_major_m;
      const int segments = static_cast<int>(std::clamp(std::ceil(circumference_px / kSegment_px), double{kMinSegments}, double{kMaxSegments}));
      ImVec2 pts[kMaxSegments];
      for (int i = 0; i < segments; ++i) {
        const double t = 2.0 * std::numbers::pi * i / segments;
        const Eigen::Vector2d en = e.semi_major_m * std::cos(t) * major + e.semi_minor_m * std::sin(t) * minor;
        pts[i] = iv(p + k * Eigen::Vector2d(en.x(), -en.y()));
      }
      dl->AddPolyline(pts, segments, col(palette::kEllipse, 170), ImDrawFlags_Closed, 1.0f);
      ++g.ellipses_drawn;
    }
  }
  // Lines, the least telling first: one by one, or (dense) the bundles
  // under the flagged lines, which are always drawn one by one.
  const PlanLod* lod = dense ? &level_of_detail() : nullptr;
  const auto line_in_view = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return std::max(a.x(), b.x()) >= g.left && std::min(a.x(), b.x()) <= g.right && std::max(a.y(), b.y()) >= g.top &&
           std::min(a.y(), b.y()) <= g.bottom;
  };
  // The lines in view, by class, in one sweep.
  std::array<std::vector<std::size_t>, kMeasurementClasses> by_class;
  if (lod) {
    for (std::size_t i : lod->lines) by_class[static_cast<std::size_t>(lines_[i].shown_as)].push_back(i);
  } else {
    for (std::size_t i = 0; i < lines_.size(); ++i) {
      if (line_in_view(px[lines_[i].from], px[lines_[i].to])) by_class[static_cast<std::size_t>(lines_[i].shown_as)].push_back(i);
    }
  }
  for (const MeasurementClass c : kDrawOrder) {
    const LineStyle st = style_of(c);
    if (lod) {
      // Bundles a whole number of pixels wide: ImGui draws those from its
      // line texture, two triangles each (a 10⁵-station plan has some 10⁵).
      LineStyle bundle_style = st;
      bundle_style.thickness = std::max(1.0f, std::floor(st.thickness));
      for (const auto& b : lod->bundles) {
        if (b.shown_as == c) line(dl, b.a_px, b.b_px, bundle_style);
      }
    }
    for (std::size_t i : by_class[static_cast<std::size_t>(c)]) line(dl, px[lines_[i].from], px[lines_[i].to], st);
    g.lines_by_class[static_cast<std::size_t>(c)] = by_class[static_cast<std::size_t>(c)].size();
  }
  if (lod) {
    g.bundles_by_class = lod->bundles_by_class;
    g.lines_bundled = lod->lines_in_bundles;
    g.lines_within_cells = lod->lines_within_cells;
    // A cell's stations: a small square, ink if one of them is adjusted,
    // faint enough that the lines' classes read through. Axis-aligned and
    // pixel-sized: two triangles each, without the anti-aliased fringe
    // AddRectFilled would add (ten).
    const float h = std::max(1.0f, std::round(kLodCell_px * 0.2f));
    dl->PrimReserve(static_cast<int>(6 * lod->marks.size()), static_cast<int>(4 * lod->marks.size()));
    for (const auto& m : lod->marks) {
      const ImVec2 p = iv(m.px);
      dl->PrimRect(ImVec2(p.x - h, p.y - h), ImVec2(p.x + h, p.y + h), col(m.any_used ? palette::kInk : palette::kLeftOut, 150));
    }
    g.marks_drawn = lod->marks.size();
  }
  // Stations: a triangle where the datum holds a component, else a circle;
  // hollow grey when not adjusted; a vermillion square round a station
  // whose point or height measurement is flagged.
  std::vector<std::size_t> own_marks;
  if (lod) own_marks = lod->stations;
  else own_marks = visible;
  g.stations_drawn = own_marks.size();
  for (std::size_t si : own_marks) {
    const NetworkStationRow& s = stations_[si];
    const Eigen::Vector2d& p = px[si];
    const bool is_held = held(s);
    const ImU32 ink = col(s.used ? palette::kInk : palette::kLeftOut);
    if (is_held) {
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
  // Dense: a baseline is a few pixels long, too short to show its class;
  // each flagged one also gets a vermillion ring at its middle, on top.
  if (lod) {
    const float ring = r_px + 3.0f;
    for (std::size_t i : lod->lines) {
      dl->AddCircle(iv(0.5 * (px[lines_[i].from] + px[lines_[i].to])), ring, col(palette::kOutlier), 12, 2.0f);
    }
    g.rings_drawn = lod->lines.size();
  }
  for (std::size_t index : flagged_at_stations) {
    for (std::size_t st : net.measurements[index].stations) {
      const Eigen::Vector2d& p = px[st];
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
      if (dense) dl->AddRectFilled(ImVec2(l.x0, l.y0), ImVec2(l.x1, l.y1), col(palette::kBackground, 230));
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
  const ImGuiIO& io = ImGui::GetIO();
  const ImVec2 mouse = io.MousePos;
  const Eigen::Vector2d m(mouse.x, mouse.y);
  // The view: the wheel zooms about the pointer (the point under it stays
  // there), a right-drag pans, a right double-click shows the whole network.
  if (hovered && !g.schematic) {
    constexpr double kZoomStep = 1.25, kMaxZoom = 1e5;
    const Eigen::Vector2d c_px(0.5 * (g.left + g.right), 0.5 * (g.top + g.bottom));
    const auto plan_at = [&](const Eigen::Vector2d& at_px, double px_per_m) {
      return Eigen::Vector2d(g.center_m.x() + (at_px.x() - c_px.x()) / px_per_m, g.center_m.y() - (at_px.y() - c_px.y()) / px_per_m);
    };
    if (ImGui::IsMouseDoubleClicked(ImGuiMouseButton_Right)) {
      reset_plan_view();
    } else if (io.MouseWheel != 0.0f) {
      const double zoom = std::clamp(zoom_ * std::pow(kZoomStep, static_cast<double>(io.MouseWheel)), 1.0, kMaxZoom);
      const Eigen::Vector2d at = plan_at(m, g.px_per_m);
      const double px_per_m = g.px_per_m / zoom_ * zoom;
      // The centre that keeps `at` under the pointer at the new scale.
      view_center_m_ = at - Eigen::Vector2d((m.x() - c_px.x()) / px_per_m, -(m.y() - c_px.y()) / px_per_m);
      zoom_ = zoom;
    } else if (ImGui::IsMouseDragging(ImGuiMouseButton_Right, 0.0f)) {
      const ImVec2 d = io.MouseDelta;
      view_center_m_ = g.center_m - Eigen::Vector2d(d.x / g.px_per_m, -d.y / g.px_per_m);
    }
  }
  const NetworkStationRow* best = nullptr;
  double best_d = 2.5 * r_px;
  for (std::size_t s = 0; s < stations_.size(); ++s) {
    const double d = (px[s] - m).norm();
    if (d < best_d) best_d = d, best = &stations_[s];
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
    const double d = segment_distance(m, px[l.from], px[l.to]);
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
