// The network view's plan: the stations and measurements coloured by their
// w-tests, with error ellipses and labels placed where they cover nothing,
// the scale bar and caption, and the pointer's zoom, pan, tooltips and
// clicks (network_ui.hpp). NetworkUi::draw_plan draws it in named steps
// that share one PlanFrame.

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
using detail::held;
using detail::iv;
using detail::kDrawOrder;
using detail::line;
using detail::LineStyle;
using detail::Obstacles;
using detail::style_of;

Eigen::Vector2d NetworkGeometry::pixel_of(const Eigen::Vector2d& en_m) const {
  const Eigen::Vector2d c(0.5 * (left + right), 0.5 * (top + bottom));
  return c + px_per_m * Eigen::Vector2d(en_m.x() - center_m.x(), -(en_m.y() - center_m.y()));
}

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

// A length in millimetres for the caption: whole millimetres from 10 mm,
// two significant digits below.
std::string mm_text(double mm) { return mm >= 10.0 ? detail::fmt("%.0f", mm) : detail::fmt("%.2g", mm); }

double segment_distance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d d = b - a;
  const double l2 = d.squaredNorm();
  const double t = l2 > 0.0 ? std::clamp((p - a).dot(d) / l2, 0.0, 1.0) : 0.0;
  return (p - (a + t * d)).norm();
}

}  // namespace

// One frame of the plan: what draw_plan works out before it draws (the
// geometry itself is plan_), shared by its steps.
struct NetworkUi::PlanFrame {
  ImDrawList* dl = nullptr;
  ImFont* regular = nullptr;
  ImFont* bold = nullptr;
  float font = 0.0f, id_size = 0.0f;
  ImVec2 c0, avail;
  const geodesy::Network* net = nullptr;
  double w_critical = 0.0;
  float r_px = 0.0f;
  Eigen::Vector2d span = Eigen::Vector2d::Zero();
  float footer_h = 0.0f;
  std::vector<std::size_t> visible;  // the stations in view
  bool dense = false, ellipses = false;
  double max_a_m = 0.0;
  double spacing_m = std::numeric_limits<double>::infinity();
  std::vector<std::pair<double, std::size_t>> flagged_lines;  // (|w|, line index), a measurement's first line
  std::vector<std::size_t> flagged_at_stations;
  float wrap_w = 0.0f;
  std::string caption;
  std::vector<PlanLabel> labels;
  std::vector<std::string> unlabelled;
  double k = 1.0;  // pixels per metre of ellipse
  std::vector<Eigen::Vector2d> px;  // each station's pixel at the settled geometry
  const PlanLod* lod = nullptr;     // dense: the level of detail drawn
};

// --- The plan ----------------------------------------------------------

void NetworkUi::draw_plan() {
  PlanFrame f;
  begin_plan(f);
  NetworkGeometry& g = plan_;
  ImDrawList* dl = f.dl;
  const float font = f.font;
  f.footer_h = std::round(font * 3.0f);
  settle_plan_area(f, f.footer_h);
  find_stations_in_view(f);
  find_flagged(f);
  settle_footer(f);
  g.drawn = true;
  g.labels = f.labels;
  g.unlabelled = f.unlabelled;
  // Each station's pixel at the settled geometry, once (a 10⁵-station
  // network's lines would otherwise project their ends a million times).
  f.px.resize(stations_.size());
  for (std::size_t s = 0; s < stations_.size(); ++s) f.px[s] = g.pixel_of(stations_[s].plan_m);

  dl->AddRectFilled(ImVec2(g.left, g.top), ImVec2(g.right, g.bottom), col(palette::kBackground));
  dl->AddRect(ImVec2(g.left, g.top), ImVec2(g.right, g.bottom), col(palette::kGrid));
  dl->PushClipRect(ImVec2(g.left, g.top), ImVec2(g.right, g.bottom), true);
  draw_ellipses(f);
  draw_lines(f);
  draw_stations(f);
  draw_flag_marks(f);
  draw_labels(f);
  if (!g.schematic) detail::north_arrow(audit_, dl, g.left, g.top, font, "network: north arrow");
  dl->PopClipRect();
  draw_footer(f);
  plan_pointer(f);
}

// The fonts, the panel's room, and the stations' extent and centre.
void NetworkUi::begin_plan(PlanFrame& f) {
  f.dl = ImGui::GetWindowDrawList();
  f.regular = ImGui::GetIO().Fonts->Fonts[0];
  f.bold = ImGui::GetIO().Fonts->Fonts[1];
  f.font = ImGui::GetFontSize();
  f.id_size = std::round(f.font * 0.8f);
  f.c0 = ImGui::GetCursorScreenPos();
  f.avail = ImGui::GetContentRegionAvail();
  f.net = &model_.network();
  NetworkGeometry& g = plan_;
  g = NetworkGeometry{};
  g.schematic = model_.schematic_plan();
  g.confidence = model_.options().confidence;
  f.w_critical = model_.w_critical();
  f.r_px = std::max(3.0f, std::round(f.font * 0.25f));

  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& s : stations_) {
    lo = lo.cwiseMin(s.plan_m);
    hi = hi.cwiseMax(s.plan_m);
  }
  if (stations_.empty()) lo = hi = Eigen::Vector2d::Zero();
  g.zoom = zoom_;
  g.center_m = view_center_m_ ? *view_center_m_ : Eigen::Vector2d(0.5 * (lo + hi));
  f.span = (hi - lo).cwiseMax(g.schematic ? 0.5 : 1.0);
}

// The plotting area and scale for a footer of `footer_px`.
void NetworkUi::settle_plan_area(const PlanFrame& f, float footer_px) {
  NetworkGeometry& g = plan_;
  const ImVec2 c0 = f.c0, avail = f.avail;
  const Eigen::Vector2d& span = f.span;
  g.left = c0.x;
  g.top = c0.y;
  g.right = c0.x + std::max(avail.x, 4 * kPlanMarginPx);
  g.bottom = c0.y + std::max(avail.y - footer_px, 4 * kPlanMarginPx);
  g.px_per_m = zoom_ * std::min((g.right - g.left - 2 * kPlanMarginPx) / span.x(), (g.bottom - g.top - 2 * kPlanMarginPx) / span.y());
}

// The stations in view (at the first footer's area: what is dense does
// not change with the caption's height).
void NetworkUi::find_stations_in_view(PlanFrame& f) {
  NetworkGeometry& g = plan_;
  std::vector<std::size_t>& visible = f.visible;
  for (std::size_t s = 0; s < stations_.size(); ++s) {
    const Eigen::Vector2d p = g.pixel_of(stations_[s].plan_m);
    if (p.x() >= g.left && p.x() <= g.right && p.y() >= g.top && p.y() <= g.bottom) visible.push_back(s);
  }
  g.stations_in_view = visible.size();
  const bool dense = f.dense = visible.size() > kDenseNetworkStations;
  g.aggregated = dense;
  double& max_a_m = f.max_a_m;
  for (std::size_t s : visible) {
    if (stations_[s].used) max_a_m = std::max(max_a_m, stations_[s].ellipse_confidence.semi_major_m);
  }
  const bool ellipses = f.ellipses = !dense && !g.schematic && max_a_m > 0.0;
  // The median distance from a station to its nearest neighbour: ellipses
  // whose semi-major axis is drawn longer than it reach their neighbours.
  double& spacing_m = f.spacing_m;
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
}

// The measurements labelled on the plan: outliers and failing ones,
// worst first; those with lines at their first line's middle, the others
// (points, heights) at their first station.
void NetworkUi::find_flagged(PlanFrame& f) {
  std::vector<std::pair<double, std::size_t>>& flagged_lines = f.flagged_lines;  // (|w|, line index), a measurement's first line
  {
    std::vector<bool> seen(measurements_.size(), false);
    for (std::size_t i = 0; i < lines_.size(); ++i) {
      if (!flagged(lines_[i].shown_as) || seen[lines_[i].measurement]) continue;
      seen[lines_[i].measurement] = true;
      flagged_lines.push_back({std::isfinite(lines_[i].w_max) ? lines_[i].w_max : 0.0, i});
    }
  }
  std::stable_sort(flagged_lines.begin(), flagged_lines.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<std::size_t>& flagged_at_stations = f.flagged_at_stations;
  for (const auto& row : measurements_) {
    if (!row.has_line && flagged(row.shown_as)) flagged_at_stations.push_back(row.index);
  }
}

// A flagged measurement's label: its number, outlier or fails, |w| and kind.
std::string NetworkUi::flagged_label(const PlanFrame& f, std::size_t index) const {
  const geodesy::Network& net = *f.net;
  const NetworkMeasurementRow& row = measurements_[index];
  const std::string w = std::isfinite(row.w_max) ? detail::fmt("%.2f", row.w_max) : std::string("-");
  return measurement_name(index) + (row.shown_as == MeasurementClass::outlier ? " outlier" : " fails") + ", |w| " + w + " (" +
         geodesy::to_string(net.measurements[index].kind) + ")";
}

// The footer (scale bar and caption) wraps at the panel's width; its
// height follows from the caption: settle both in up to three passes.
void NetworkUi::settle_footer(PlanFrame& f) {
  NetworkGeometry& g = plan_;
  const float font = f.font;
  const bool ellipses = f.ellipses;
  const double max_a_m = f.max_a_m;
  const double spacing_m = f.spacing_m;
  double& k = f.k;
  float& footer_h = f.footer_h;
  const ImVec2 avail = f.avail;
  f.wrap_w = std::max(avail.x - font * 0.5f, font * 4.0f);
  for (int pass = 0; pass < 3; ++pass) {
    settle_plan_area(f, footer_h);
    const double short_side_px = std::min(g.right - g.left, g.bottom - g.top);
    // The largest ellipse at most a twentieth of the plan's short side and
    // the stations' median spacing, the factor rounded down to 1, 2
    // or 5 × 10^k (at least 1).
    const double largest_px = std::min(0.05 * short_side_px, spacing_m * g.px_per_m);
    g.ellipse_exaggeration = ellipses ? std::max(1.0, detail::nice_floor(largest_px / (g.px_per_m * max_a_m))) : 1.0;
    g.scale_bar_m = g.schematic ? 0.0 : detail::nice_floor(0.25 * (g.right - g.left) / g.px_per_m);
    k = g.ellipse_exaggeration * g.px_per_m;
    const std::size_t flagged_in_view = place_labels(f);
    write_caption(f, flagged_in_view);
    const float needed = std::ceil(font * 1.5f + detail::text_size(f.caption, f.regular, font, f.wrap_w).y + font * 0.2f);
    if (needed <= footer_h) break;
    footer_h = needed;
  }
}

// Labels: flagged measurements first (at their line's middle), then
// station ids, each where it covers no mark and no other label.
// Returns how many flagged measurements are in view (each labelled where
// it found room).
std::size_t NetworkUi::place_labels(PlanFrame& f) {
  NetworkGeometry& g = plan_;
  ImFont* regular = f.regular;
  ImFont* bold = f.bold;
  const float font = f.font;
  const float id_size = f.id_size;
  const geodesy::Network& net = *f.net;
  const float r_px = f.r_px;
  const std::vector<std::size_t>& visible = f.visible;
  const bool dense = f.dense;
  const std::vector<std::pair<double, std::size_t>>& flagged_lines = f.flagged_lines;
  const std::vector<std::size_t>& flagged_at_stations = f.flagged_at_stations;
  std::vector<PlanLabel>& labels = f.labels;
  std::vector<std::string>& unlabelled = f.unlabelled;
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
  const auto place = [&](const std::string& text, std::optional<std::size_t> measurement, const Eigen::Vector2d& p, ImFont* face,
                         float size) {
    const ImVec2 ts = detail::text_size(text, face, size);
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
    place(flagged_label(f, l.measurement), l.measurement, mid, bold, font);
  }
  for (std::size_t index : flagged_at_stations) {
    const auto& m = net.measurements[index];
    if (m.stations.empty() || !in_area(g.pixel_of(stations_[m.stations[0]].plan_m))) continue;
    ++flagged_in_view;
    place(flagged_label(f, index), index, g.pixel_of(stations_[m.stations[0]].plan_m), bold, font);
  }
  if (!dense) {
    for (std::size_t s : visible) {
      if (!place(stations_[s].id, std::nullopt, g.pixel_of(stations_[s].plan_m), regular, id_size)) unlabelled.push_back(stations_[s].id);
    }
  }
  return flagged_in_view;
}

// The caption under the plan, for this pass's scale and labels.
void NetworkUi::write_caption(PlanFrame& f, std::size_t flagged_in_view) {
  NetworkGeometry& g = plan_;
  ImFont* regular = f.regular;
  const float font = f.font;
  const std::vector<std::size_t>& visible = f.visible;
  const bool dense = f.dense;
  const bool ellipses = f.ellipses;
  const double k = f.k;
  const float wrap_w = f.wrap_w;
  std::string& caption = f.caption;
  const std::vector<std::string>& unlabelled = f.unlabelled;
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
}

  // Ellipses under everything.
void NetworkUi::draw_ellipses(const PlanFrame& f) {
  NetworkGeometry& g = plan_;
  ImDrawList* dl = f.dl;
  const std::vector<std::size_t>& visible = f.visible;
  const bool ellipses = f.ellipses;
  const double k = f.k;
  const std::vector<Eigen::Vector2d>& px = f.px;
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
}

  // Lines, the least telling first: one by one, or (dense) the bundles
  // under the flagged lines, which are always drawn one by one.
void NetworkUi::draw_lines(PlanFrame& f) {
  NetworkGeometry& g = plan_;
  ImDrawList* dl = f.dl;
  const bool dense = f.dense;
  const std::vector<Eigen::Vector2d>& px = f.px;
  const PlanLod* lod = f.lod = dense ? &level_of_detail() : nullptr;
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
}

  // Stations: a triangle where the datum holds a component, else a circle;
  // hollow grey when not adjusted; a vermillion square round a station
  // whose point or height measurement is flagged.
void NetworkUi::draw_stations(const PlanFrame& f) {
  NetworkGeometry& g = plan_;
  ImDrawList* dl = f.dl;
  const float r_px = f.r_px;
  const std::vector<std::size_t>& visible = f.visible;
  const std::vector<Eigen::Vector2d>& px = f.px;
  const PlanLod* lod = f.lod;
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
}

  // Dense: a baseline is a few pixels long, too short to show its class;
  // each flagged one also gets a vermillion ring at its middle, on top.
// And a vermillion square round each station of a flagged point or height.
void NetworkUi::draw_flag_marks(const PlanFrame& f) {
  NetworkGeometry& g = plan_;
  ImDrawList* dl = f.dl;
  const geodesy::Network& net = *f.net;
  const float r_px = f.r_px;
  const std::vector<std::size_t>& flagged_at_stations = f.flagged_at_stations;
  const std::vector<Eigen::Vector2d>& px = f.px;
  const PlanLod* lod = f.lod;
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
}

  // Labels where the placement put them.
void NetworkUi::draw_labels(const PlanFrame& f) {
  NetworkGeometry& g = plan_;
  ImDrawList* dl = f.dl;
  ImFont* regular = f.regular;
  ImFont* bold = f.bold;
  const float font = f.font;
  const float id_size = f.id_size;
  const float r_px = f.r_px;
  const bool dense = f.dense;
  for (const auto& l : g.labels) {
    const Rgb c = l.measurement ? palette::kOutlier : palette::kInk;
    if (l.leader) {
      const Eigen::Vector2d nearest(std::clamp(l.mark_px.x(), double(l.x0), double(l.x1)), std::clamp(l.mark_px.y(), double(l.y0), double(l.y1)));
      const Eigen::Vector2d d = nearest - l.mark_px;
      if (d.norm() > r_px + 2.0) dl->AddLine(iv(l.mark_px + (r_px + 1.0) * d.normalized()), iv(nearest), col(c, 160), 1.0f);
    }
    if (l.measurement) {
      if (dense) dl->AddRectFilled(ImVec2(l.x0, l.y0), ImVec2(l.x1, l.y1), col(palette::kBackground, 230));
      detail::label(audit_, dl, ImVec2(l.x0 + 1.0f, l.y0), col(c), flagged_label(f, *l.measurement), "network: measurement label",
                    ImVec2(g.left, g.top), ImVec2(g.right, g.bottom), bold, font);
    } else {
      detail::label(audit_, dl, ImVec2(l.x0 + 1.0f, l.y0), col(c), l.id, "network: id", ImVec2(g.left, g.top), ImVec2(g.right, g.bottom),
                    regular, id_size);
    }
  }
}

  // Footer: the scale bar and the caption.
void NetworkUi::draw_footer(const PlanFrame& f) {
  const NetworkGeometry& g = plan_;
  detail::plan_footer(audit_, f.dl, g.left, g.bottom, f.font, !g.schematic, g.scale_bar_m, g.px_per_m, f.caption, f.regular, f.wrap_w,
                      "network");
}

  // Under the mouse: a station (tooltip; a click leaves it out or takes it
  // back), else the measurements along a line (tooltip).
void NetworkUi::plan_pointer(const PlanFrame& f) {
  NetworkGeometry& g = plan_;
  ImGui::InvisibleButton("network plan", ImVec2(g.right - g.left, g.bottom - g.top));
  const bool hovered = ImGui::IsItemHovered(), clicked = ImGui::IsItemClicked();
  if (!hovered && !clicked) return;
  const ImGuiIO& io = ImGui::GetIO();
  const ImVec2 mouse = io.MousePos;
  const Eigen::Vector2d m(mouse.x, mouse.y);
  // The view: the wheel zooms about the pointer (the point under it stays
  // there), a right-drag pans, a right double-click shows the whole network.
  if (hovered && !g.schematic) zoom_and_pan(m);
  if (station_under_pointer(f, m, hovered, clicked)) return;
  line_under_pointer(f, m, hovered);
}

void NetworkUi::zoom_and_pan(const Eigen::Vector2d& m) {
  NetworkGeometry& g = plan_;
  const ImGuiIO& io = ImGui::GetIO();
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

// A station within reach of the pointer: its tooltip, and a click leaves
// it out or takes it back. False when there is none.
bool NetworkUi::station_under_pointer(const PlanFrame& f, const Eigen::Vector2d& m, bool hovered, bool clicked) {
  NetworkGeometry& g = plan_;
  ImFont* bold = f.bold;
  const geodesy::Network& net = *f.net;
  const float r_px = f.r_px;
  const std::vector<Eigen::Vector2d>& px = f.px;
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
    return true;
  }
  return false;
}

// The measurements along the line under the pointer: a tooltip.
void NetworkUi::line_under_pointer(const PlanFrame& f, const Eigen::Vector2d& m, bool hovered) {
  NetworkGeometry& g = plan_;
  ImFont* bold = f.bold;
  const float font = f.font;
  const geodesy::Network& net = *f.net;
  const double w_critical = f.w_critical;
  const std::vector<Eigen::Vector2d>& px = f.px;
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

}  // namespace geoanchor::gui
