#pragma once
// The residual workbench's views, drawn with Dear ImGui from a
// WorkbenchModel: the one UI code path that the GLFW window and the OSMesa
// off-screen shell both show. Call draw() between ImGui::NewFrame() and
// ImGui::Render(); the shells own the GL context and the backend.
//
// Views (names as `geoanchor snapshot --view` takes them):
//   plan        control points in ENU at the network's centroid (metres,
//               north up, equal scale, scale bar); horizontal residuals as
//               arrows exaggerated by a stated factor, each mark's 95 %
//               residual ellipse at the same factor; the vertical residual
//               as a diverging colour with its legend; every mark labelled
//               with its id where there is room (listed under the plan
//               where there is none); outliers as labelled vermillion
//               squares with thick arrows; the mark under the mouse in a
//               tooltip
//   histogram   the used points' w-tests (E, N and U), bins 0.5 wide, against
//               the standard normal scaled to the count, critical values
//               marked
//   table       id, residual E/N/U (mm), w-test, MDB, status; sortable; the
//               check box leaves a point out (refit); a line under it says
//               which marks are in view
//   parameters  each parameter with unit and σ, σ0, the global test and the
//               correlation matrix as a heat map labelled with the
//               parameters' names
//   comparison  the same points under every applicable model
//   workbench   all of them, with the model/convention bar and Save transform…
//
// No text is clipped or shortened: each caption, label and header is
// checked against the room it is drawn in, and what does not fit is
// wrapped, moved, or replaced by a sentence saying where to find it;
// clipped_text() lists any that still does not fit (the tests require none
// at the documented sizes).

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

// The smallest frame (pixels) at which every view's text fits: `snapshot`,
// `report` and the window refuse a smaller --size.
inline constexpr int kMinimumWidth_px = 1280, kMinimumHeight_px = 800;

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

// The plan's residual ellipses: the region a mark's horizontal residual
// falls in with this probability if the model and the sigmas are right.
inline constexpr double kEllipseProbability = 0.95;

// A mark's id as the plan drew it: its box (pixels) and whether a leader
// line joins it to a mark it could not sit beside.
struct PlanLabel {
  std::string id;
  float x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  Eigen::Vector2d mark_px = Eigen::Vector2d::Zero();
  bool leader = false;
  std::optional<std::size_t> measurement;  // the network view's measurement labels: its index (id is "#12")
};

// Where the last frame drew the plan (pixels from the top-left corner).
struct PlanGeometry {
  bool drawn = false;
  float left = 0, top = 0, right = 0, bottom = 0;  // plotting area
  Eigen::Vector2d center_en_m = Eigen::Vector2d::Zero();
  double px_per_m = 0.0;
  double arrow_exaggeration = 1.0;  // arrows are residual × this, on the plan's scale
  double scale_bar_m = 0.0;
  double du_limit_mm = 0.0;  // the colour scale runs from −this to +this
  // Residual ellipses at kEllipseProbability: k = sqrt(χ²₂(p)) times the
  // residual covariance's square root, at arrow_exaggeration; none on a dense
  // plan.
  double ellipse_k = 0.0;
  std::size_t ellipses_drawn = 0;
  std::vector<PlanLabel> labels;        // every mark whose id is on the plan
  std::vector<std::string> unlabelled;  // marks with no room for their id: listed under the plan
  std::string hovered;                  // the mark under the mouse (its tooltip is shown), or empty
  Eigen::Vector2d pixel_of(const Eigen::Vector2d& en_m) const;
};

// What the last frame's point table held: the rows wholly in view, in
// order. `first` is the sorted position of the first of them.
struct TableGeometry {
  bool drawn = false;
  std::size_t total = 0;
  std::size_t first = 0;
  std::vector<std::string> shown_ids;
  std::vector<bool> shown_use;  // each shown row's "use" box: ticked (a mark the fit uses)
  std::string sorted_by;  // e.g. "id ▲"
  float left = 0, right = 0, rows_top = 0, rows_bottom = 0;  // the rows' area (pixels)
  float row_height_px = 0;
};

// A piece of text a view drew that does not fit in the room it was drawn in.
struct ClippedText {
  std::string text;
  std::string where;  // view and element: "plan: caption", "comparison: header"
  float needed_px = 0.0f, available_px = 0.0f;
  bool vertical = false;  // it runs out at the bottom rather than the side
};

// A piece of text a view drew, and its box (pixels; a table header, checked
// by its width only, has the box 0 … its width × 0).
struct DrawnText {
  std::string text, where;
  float x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

// Collects, for one frame, the texts drawn and those that did not fit.
struct TextAudit {
  std::vector<DrawnText> drawn;
  std::vector<ClippedText> clipped;
  // The text's box [x0, x1] × [y0, y1] against the room [cx0, cx1] × [cy0, cy1]
  // (pixels; half a pixel of slack for rounding). `vertical` false: only the
  // width counts (a table's rows scroll).
  void check(std::string_view text, std::string_view where, float x0, float y0, float x1, float y1, float cx0, float cy0,
             float cx1, float cy1, bool vertical = true);
  void check_width(std::string_view text, std::string_view where, float needed_px, float available_px);
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
  const TableGeometry& table() const { return table_; }
  // The texts of the last frame (captions, labels, headers, cells) and
  // those of them that did not fit.
  const std::vector<DrawnText>& drawn_text() const { return audit_.drawn; }
  const std::vector<ClippedText>& clipped_text() const { return audit_.clipped; }
  // The table starts at the mark at this sorted position (0: the top), for
  // the report's pages; the rows before it are not drawn.
  void set_table_start(std::size_t sorted_position) { table_start_ = sorted_position; }
  // The last Save transform… outcome ("wrote …" or the error), for the bar.
  const std::string& status() const { return status_; }

 private:
  void refresh();
  void draw_bar();
  void draw_plan();
  // The steps of draw_plan (plan_view.cpp), in the order it takes them,
  // sharing one frame's PlanFrame.
  struct PlanFrame;
  void begin_plan(PlanFrame& f);
  void measure_plan(PlanFrame& f);
  void layout_plan(PlanFrame& f);
  void settle_plan_scale(PlanFrame& f);
  void place_plan_labels(PlanFrame& f);
  void write_plan_caption(PlanFrame& f);
  void draw_plan_ellipses(PlanFrame& f);
  void draw_plan_marks(const PlanFrame& f);
  void draw_plan_labels(const PlanFrame& f);
  void draw_plan_footer(const PlanFrame& f);
  void draw_plan_legend(const PlanFrame& f);
  void plan_pointer(const PlanFrame& f);
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
  TableGeometry table_;
  TextAudit audit_;
  std::size_t table_start_ = 0;
  // The plan's layout (scale, factor, labels, caption) for the shown fit and
  // the plan's room: recomputed only when either changes.
  struct PlanLayout {
    unsigned generation = ~0u;
    float x = 0, y = 0, w = 0, h = 0, font = 0;
    PlanGeometry geometry;
    std::string caption;
  };
  PlanLayout plan_layout_;
  float bar_height_px_ = 0.0f;  // measured in the last frame (0: not yet)
  bool composite_ = false;      // drawing the workbench's panels (not one view)
  std::string status_;
  std::array<char, 1024> save_path_{};
  bool save_overwrite_ = false;
};

}  // namespace geoanchor::gui
