#pragma once
// The residual workbench's views, drawn with Dear ImGui from a
// WorkbenchModel: the one UI code path that the GLFW window and the OSMesa
// off-screen shell both show. Call draw() between ImGui::NewFrame() and
// ImGui::Render(); the shells own the GL context and the backend.
//
// Views (names as `geoanchor snapshot --view` takes them):
//   plan        control points in ENU at the network's centroid (metres,
//               north up, equal scale, scale bar); horizontal residuals as
//               arrows exaggerated by a stated factor; the vertical residual
//               as a diverging colour with its legend; outliers as labelled
//               vermillion squares with thick arrows
//   histogram   the used points' w-tests (E, N and U), bins 0.5 wide, against
//               the standard normal scaled to the count, critical values
//               marked
//   table       id, residual E/N/U (mm), w-test, MDB, status; sortable; the
//               check box leaves a point out (refit)
//   parameters  each parameter with unit and σ, σ0, the global test and the
//               correlation matrix as a heat map
//   comparison  the same points under every applicable model
//   workbench   all of them, with the model/convention bar and Save transform…

#include <Eigen/Core>

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "geoanchor/gui/workbench_model.hpp"

namespace geoanchor::gui {

enum class View { workbench, plan, histogram, table, parameters, comparison };
inline constexpr std::array<View, 6> kAllViews{View::workbench, View::plan,       View::histogram,
                                               View::table,     View::parameters, View::comparison};
std::string_view to_string(View v);
std::optional<View> view_from_string(std::string_view name);

// The plan's points are fitted into its plotting area with this margin on
// every side: pixel = area centre + px_per_m · (e − ē, −(n − n̄)), with (ē, n̄)
// the centre of the points' bounding box and px_per_m the largest scale at
// which the box fits (spans below 1 m count as 1 m).
inline constexpr float kPlanMarginPx = 48.0f;
// Above this many marks the plan is dense: marks are small squares, arrows
// are drawn without antialiasing, and only outliers are labelled.
inline constexpr std::size_t kDensePlanMarks = 1500;
// The histogram's bins are this wide (in units of σ of the w-test).
inline constexpr double kHistogramBinWidth = 0.5;

// Where the last frame drew the plan (pixels from the top-left corner).
struct PlanGeometry {
  bool drawn = false;
  float left = 0, top = 0, right = 0, bottom = 0;  // plotting area
  Eigen::Vector2d center_en_m = Eigen::Vector2d::Zero();
  double px_per_m = 0.0;
  double arrow_exaggeration = 1.0;  // arrows are residual × this, on the plan's scale
  double scale_bar_m = 0.0;
  double du_limit_mm = 0.0;  // the colour scale runs from −this to +this
  Eigen::Vector2d pixel_of(const Eigen::Vector2d& en_m) const;
};

// Where the last frame drew the histogram, and what it counted.
struct HistogramGeometry {
  bool drawn = false;
  float left = 0, top = 0, right = 0, bottom = 0;  // plotting area; the bars stand on `bottom`
  double w_low = 0.0;                              // left edge of the first bin
  std::vector<int> counts;                         // per bin
  double w_critical = 0.0;
  float x_of(double w) const;
};

struct UiOptions {
  // Where Save transform… proposes to write, and the generator it records.
  std::string save_path;
  std::string generator;
};

class WorkbenchUi {
 public:
  WorkbenchUi(WorkbenchModel& model, UiOptions options);

  // Style, colours and fonts (DejaVu Sans with Greek, superscripts and
  // mathematical operators) for the current ImGui context, sized for a
  // display `display_height_px` tall; call before the backend builds the
  // font atlas. No ini file. Throws geoanchor::Error (io) naming a missing
  // font file and its Debian package.
  static void configure_context(float display_height_px);

  // One frame of `view` filling width × height pixels.
  void draw(View view, float width, float height);

  const PlanGeometry& plan() const { return plan_; }
  const HistogramGeometry& histogram() const { return histogram_; }
  // The last Save transform… outcome ("wrote …" or the error), for the bar.
  const std::string& status() const { return status_; }

 private:
  void refresh();
  void draw_bar();
  void draw_plan();
  void draw_histogram();
  void draw_table();
  void draw_parameters();
  void draw_comparison();
  void draw_save_popup();

  WorkbenchModel& model_;
  UiOptions options_;
  unsigned shown_generation_ = ~0u;
  std::vector<PointRow> rows_;
  std::vector<std::size_t> order_;  // table rows in the current sort order
  bool resort_ = true;
  PlanGeometry plan_;
  HistogramGeometry histogram_;
  std::string status_;
  std::array<char, 1024> save_path_{};
  bool save_overwrite_ = false;
};

}  // namespace geoanchor::gui
