#pragma once
// The network plan's level of detail (issue 17 point 6): how a plan of
// 10⁵ stations and their lines is drawn in a few thousand marks and
// segments without hiding anything a geodesist looks for. Pure geometry on
// pixel positions, no graphics: the view (network_plan.cpp) draws what it
// returns, and the tests check it directly.
//
// The plan is cut into square cells of `cell_px` pixels. Stations that are
// drawn one by one (those the caller asks for: held stations) keep their
// own mark; the others become one mark per occupied cell, at the mean of
// their pixels. A line whose measurement is flagged (failing its test, or
// an outlier removed by data snooping) is always drawn one by one, at its
// stations' exact pixels, so that each one can be seen and labelled. Every
// other line joins the bundle of its two cells: one segment per pair of
// cells, between the cells' mark positions, drawn in the most telling
// class among its lines (left out < untestable < small < elevated); a line
// whose two stations share a cell is shown by that cell's mark alone.
// Lines and marks wholly outside the plotting area are culled.
//
// Where each station has a cell of its own (a sparse or zoomed-in view)
// the bundles are exactly the lines, at the stations' own pixels up to
// the mean of one position: the aggregation costs nothing in what is
// shown.

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <vector>

#include "geoanchor/gui/network_model.hpp"

namespace geoanchor::gui {

// The cell of a dense plan, pixels: about the size of a station's mark.
inline constexpr float kLodCell_px = 6.0f;

struct LodArea {
  float left = 0, top = 0, right = 0, bottom = 0;  // pixels
};

// A segment standing for the non-flagged lines between two cells.
struct LodBundle {
  Eigen::Vector2d a_px = Eigen::Vector2d::Zero(), b_px = Eigen::Vector2d::Zero();
  MeasurementClass shown_as = MeasurementClass::small;  // the most telling of its lines
  std::size_t lines = 0;                                // how many it stands for
};

// A mark standing for the stations of one cell.
struct LodMark {
  Eigen::Vector2d px = Eigen::Vector2d::Zero();  // the mean of their pixels
  std::size_t stations = 0;
  bool any_used = false;  // one of them is in the shown adjustment
};

struct PlanLod {
  std::vector<std::size_t> lines;     // indices into the lines, drawn one by one: the flagged ones in view
  std::vector<LodBundle> bundles;     // in view
  std::vector<std::size_t> stations;  // indices into the stations, drawn one by one, in view
  std::vector<LodMark> marks;         // in view
  std::size_t lines_in_bundles = 0;   // lines in view that the bundles stand for
  std::size_t lines_within_cells = 0; // lines in view whose stations share a cell (shown by its mark)
  std::size_t lines_culled = 0;       // lines wholly outside the area
  std::array<std::size_t, kMeasurementClasses> bundles_by_class{};
};

// `station_px`: each station's pixel; `own_mark`: the stations drawn one
// by one (same size, or empty for none); `lines`: as NetworkModel::lines()
// gives them. Throws std::invalid_argument for a cell that is not positive
// and finite or a line naming a station out of range.
PlanLod plan_level_of_detail(const std::vector<Eigen::Vector2d>& station_px, const std::vector<bool>& own_mark,
                             const std::vector<NetworkLine>& lines, const LodArea& area, float cell_px = kLodCell_px);

}  // namespace geoanchor::gui
