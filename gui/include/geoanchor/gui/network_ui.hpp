#pragma once
// The workbench's network view (issue 14 point 10), drawn with Dear ImGui
// from a NetworkModel: the one code path that the GLFW window
// (`geoanchor gui --view network`) and the off-screen shell (`snapshot
// --view network`, `report --view network`) both show.
//
// Left, the plan (east, north at the network's centroid; a local network's
// x, y turned to east, north by its axes; north up, equal
// scale, scale bar): each station a mark (a triangle where the datum holds
// a component, a circle where it is free, hollow grey where it is not in
// the adjustment), labelled with its id where there is room; each
// measurement between two stations a line coloured and thickened by its
// measurement test and largest |w| (MeasurementClass); each station's error
// ellipse at the adjustment's confidence, exaggerated by a stated factor;
// outliers (removed by data snooping) and measurements failing their
// measurement test labelled on the plan with their number, |w| and kind
// (points and heights at their station, framed). Right, the
// adjustment's statistics, the legend and two tables, stations and
// measurements, whose check boxes leave a station (with every measurement
// naming it) or one measurement out; a click on a station in the plan does
// the same. Each choice re-adjusts (NetworkModel: on a worker thread for
// large networks).
//
// Like the fit's views, no text is clipped: clipped_text() lists any text
// that does not fit in the room it is drawn in (the tests require none at
// the documented sizes); a table's rows scroll, and the line under each
// table says which rows are in view.

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "geoanchor/gui/network_lod.hpp"
#include "geoanchor/gui/network_model.hpp"
#include "geoanchor/gui/workbench_ui.hpp"

namespace geoanchor::gui {

// Above this many stations in view the plan is dense (issue 17 point 6):
// no ellipses, no station ids, only the outliers and failing measurements
// labelled, and the level of detail of network_lod.hpp: the flagged lines
// one by one, every other line bundled with those between the same two
// cells of kLodCell_px, the free stations as one mark per cell, the held
// stations as their own triangles. Zooming in until no more than this many
// stations are in view shows each station and line again.
inline constexpr std::size_t kDenseNetworkStations = 1500;

// Where the last frame drew the network's plan (pixels from the top-left):
// pixel = area centre + px_per_m · (e − ē, −(n − n̄)). In the whole view
// (zoom 1, the default) (ē, n̄) is the centre of the stations' bounding box
// and px_per_m the largest scale at which the box fits with kPlanMarginPx
// free on every side (spans below 1 m count as 1 m); a zoomed view
// multiplies that scale by its zoom and centres on its own (ē, n̄)
// (NetworkUi::set_plan_view). A station is in view when its pixel lies in
// the plotting area.
struct NetworkGeometry {
  bool drawn = false;
  float left = 0, top = 0, right = 0, bottom = 0;  // plotting area
  Eigen::Vector2d center_m = Eigen::Vector2d::Zero();
  double px_per_m = 0.0;
  double zoom = 1.0;
  std::size_t stations_in_view = 0;
  bool aggregated = false;  // dense: drawn at the level of detail of network_lod.hpp
  double scale_bar_m = 0.0;
  // Ellipses: a station's ellipse at the adjustment's confidence (from the
  // a-priori weights, σ0 = 1), drawn × ellipse_exaggeration on the plan's
  // scale: the largest at most a twentieth of the plan's short side and
  // the stations' median nearest-neighbour spacing (1, 2 or 5 × 10^k, at
  // least 1); none on a dense plan or a levelling network's schematic.
  double ellipse_exaggeration = 1.0;
  double confidence = 0.95;
  std::size_t ellipses_drawn = 0;
  std::array<std::size_t, kMeasurementClasses> lines_by_class{};         // lines drawn one by one, by their measurement's class
  std::array<std::size_t, kMeasurementClasses> bundles_by_class{};       // aggregated: bundles drawn, by their most telling class
  std::size_t lines_bundled = 0;      // aggregated: lines the bundles stand for
  std::size_t lines_within_cells = 0; // aggregated: lines shown by their cell's mark alone
  std::size_t marks_drawn = 0;        // aggregated: cell marks
  std::size_t stations_drawn = 0;     // stations drawn with a mark of their own
  std::size_t rings_drawn = 0;        // aggregated: the flagged lines' rings (one each)
  std::array<std::size_t, kMeasurementClasses> measurements_by_class{};  // every measurement (with a line or not), by class
  std::vector<PlanLabel> labels;            // station ids, and measurement labels ("#12 …")
  std::vector<std::size_t> labelled_measurements;  // indices of the measurements labelled on the plan
  std::vector<std::string> unlabelled;      // stations whose id found no room (named under the plan)
  std::string hovered;                      // the station id or measurement ("#12") under the mouse
  bool schematic = false;                   // a levelling network: stations on a circle
  Eigen::Vector2d pixel_of(const Eigen::Vector2d& en_m) const;
};

// What a table drew: the rows wholly in view.
struct NetworkTableGeometry {
  bool drawn = false;
  std::size_t total = 0, first = 0, shown = 0;
  // The first row wholly in view: its top, the rows' height and the
  // table's left edge (pixels; the check box is the first column).
  float left = 0, first_row_top = 0, row_height_px = 0;
};

class NetworkUi {
 public:
  explicit NetworkUi(NetworkModel& model);

  // One frame filling width × height pixels (the context configured by
  // WorkbenchUi::configure_context).
  void draw(float width, float height);

  const NetworkGeometry& plan() const { return plan_; }
  const NetworkTableGeometry& station_table() const { return station_table_; }
  const NetworkTableGeometry& measurement_table() const { return measurement_table_; }
  const std::vector<DrawnText>& drawn_text() const { return audit_.drawn; }
  const std::vector<ClippedText>& clipped_text() const { return audit_.clipped; }

  // A measurement's short name on the plan and in the table: "#12" (its
  // 1-based position in the network's measurements, as the measurements
  // CSV lists them).
  static std::string measurement_name(std::size_t index);

  // The plan's view: `zoom` (at least 1) × the scale at which the whole
  // network fits, centred on `center_m` (plan metres, east and north). In
  // a window the mouse wheel zooms about the pointer, a right-button drag
  // pans and a right double-click shows the whole network again. Throws
  // std::invalid_argument for a zoom below 1 or a value that is not finite.
  void set_plan_view(double zoom, const Eigen::Vector2d& center_m);
  void reset_plan_view();

 private:
  void refresh();
  void draw_plan();
  // The steps of draw_plan (network_plan.cpp), in the order it takes them,
  // sharing one frame's PlanFrame.
  struct PlanFrame;
  void begin_plan(PlanFrame& f);
  // The plotting area and scale for a footer of `footer_px`.
  void settle_plan_area(const PlanFrame& f, float footer_px);
  void find_stations_in_view(PlanFrame& f);
  void find_flagged(PlanFrame& f);
  std::string flagged_label(const PlanFrame& f, std::size_t index) const;
  void settle_footer(PlanFrame& f);
  std::size_t place_labels(PlanFrame& f);
  void write_caption(PlanFrame& f, std::size_t flagged_in_view);
  void draw_ellipses(const PlanFrame& f);
  void draw_lines(PlanFrame& f);
  void draw_stations(const PlanFrame& f);
  void draw_flag_marks(const PlanFrame& f);
  void draw_labels(const PlanFrame& f);
  void draw_footer(const PlanFrame& f);
  void plan_pointer(const PlanFrame& f);
  void zoom_and_pan(const Eigen::Vector2d& m);
  bool station_under_pointer(const PlanFrame& f, const Eigen::Vector2d& m, bool hovered, bool clicked);
  void line_under_pointer(const PlanFrame& f, const Eigen::Vector2d& m, bool hovered);
  void draw_side();
  void draw_station_table(float height);
  void draw_measurement_table(float height);

  NetworkModel& model_;
  unsigned shown_generation_ = ~0u;
  std::vector<NetworkStationRow> stations_;
  std::vector<NetworkMeasurementRow> measurements_;
  std::vector<NetworkLine> lines_;
  NetworkGeometry plan_;
  double zoom_ = 1.0;
  std::optional<Eigen::Vector2d> view_center_m_;  // nullopt: the stations' bounding box centre
  // The level of detail of the last dense frame, kept while the view and
  // the shown adjustment stay as they were.
  struct LodCache {
    bool valid = false;
    unsigned generation = 0;
    double px_per_m = 0.0;
    Eigen::Vector2d center_m = Eigen::Vector2d::Zero();
    float left = 0, top = 0, right = 0, bottom = 0;
    PlanLod lod;
  } lod_cache_;
  const PlanLod& level_of_detail();
  NetworkTableGeometry station_table_, measurement_table_;
  TextAudit audit_;
};

}  // namespace geoanchor::gui
