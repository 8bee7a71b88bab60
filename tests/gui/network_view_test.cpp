// The network view drawn off-screen (issue 14 point 10): stations where the
// plan's documented mapping puts them, a planted blunder's line drawn and
// labelled as an outlier (and as failing with data snooping off), every
// text fitting its room on the bundled networks at the documented sizes,
// and clicks that leave a station or a measurement out and re-adjust.
//
// Independent of the code under test: the blunder is planted here (5 cm on
// one slope distance of the bundled airport network, whose sigmas are a
// few millimetres: far beyond its MDB); the critical |w| of a two-sided
// test at α = 0.001 is the normal quantile 3.2905 (tables); the mapping
// from plan metres to pixels is the documented rule (network_ui.hpp,
// workbench_ui.hpp), recomputed here; the stations' plan metres are
// NetworkModel's, tested against the generator's layout in
// network_model_test.cpp.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "geoanchor/gui/network_ui.hpp"
#include "geoanchor/gui/offscreen.hpp"
#include "geoanchor/gui/palette.hpp"
#include "geoanchor/workflow/adjust.hpp"
#include "geoanchor/workflow/network_generator.hpp"

namespace geoanchor::gui {
namespace {

using geodesy::MeasurementKind;

const std::string kFixtures = GEOANCHOR_FIXTURES_DIR;
constexpr double kMappingTol_px = 0.01;   // the rule in double against the drawn float vertices
constexpr int kColourTol = 3;             // per 8-bit channel, for antialiased blends at a line's centre
constexpr double kWCritical = 3.2905;     // two-sided normal quantile at α = 0.001
constexpr double kWCriticalTol = 1e-4;
constexpr double kBlunder_m = 0.05;

geodesy::Network network_of(std::vector<std::string> inputs) {
  workflow::AdjustRequest request;
  request.inputs = std::move(inputs);
  return workflow::prepare_network(request).network;
}

geodesy::Network airport() { return network_of({kFixtures + "/airport_network/lszh_network.json"}); }

bool near(Rgb a, Rgb b, int tol = kColourTol) {
  return std::abs(a.r - b.r) <= tol && std::abs(a.g - b.g) <= tol && std::abs(a.b - b.b) <= tol;
}

int count_near(const RgbImage& image, int cx, int cy, int radius, Rgb c) {
  int n = 0;
  for (int y = std::max(0, cy - radius); y <= std::min(image.height - 1, cy + radius); ++y) {
    for (int x = std::max(0, cx - radius); x <= std::min(image.width - 1, cx + radius); ++x) n += near(image.at(x, y), c) ? 1 : 0;
  }
  return n;
}

// The documented mapping: the stations' bounding box centred in the
// plotting area at the largest scale that keeps kPlanMarginPx free.
Eigen::Vector2d expected_pixel(const NetworkGeometry& g, const std::vector<NetworkStationRow>& rows, const Eigen::Vector2d& p) {
  Eigen::Vector2d lo = rows.front().plan_m, hi = lo;
  for (const auto& r : rows) lo = lo.cwiseMin(r.plan_m), hi = hi.cwiseMax(r.plan_m);
  const Eigen::Vector2d span = (hi - lo).cwiseMax(1.0), c = 0.5 * (lo + hi);
  const double s = std::min((g.right - g.left - 2.0 * kPlanMarginPx) / span.x(), (g.bottom - g.top - 2.0 * kPlanMarginPx) / span.y());
  return Eigen::Vector2d(0.5 * (g.left + g.right), 0.5 * (g.top + g.bottom)) + s * Eigen::Vector2d(p.x() - c.x(), -(p.y() - c.y()));
}

std::size_t planted_distance(const geodesy::Network& net) {
  // The traverse's first slope distance.
  for (std::size_t i = 0; i < net.measurements.size(); ++i) {
    if (net.measurements[i].kind == MeasurementKind::slope_distance) return i;
  }
  return net.measurements.size();
}

std::string clipped(const std::vector<ClippedText>& list) {
  std::string s;
  for (const auto& c : list) s += c.where + ": \"" + c.text + "\" needs " + std::to_string(c.needed_px) + " px, has " + std::to_string(c.available_px) + "\n";
  return s;
}

TEST(NetworkView, StationsSitWhereTheDocumentedMappingPutsThem) {
  NetworkModel model(airport(), solver::AdjustOptions{});
  ASSERT_TRUE(model.result()) << model.error();
  NetworkUi ui(model);
  OffscreenRenderer renderer(1600, 1000);
  const RgbImage image = renderer.render(ui);
  const NetworkGeometry& g = ui.plan();
  ASSERT_TRUE(g.drawn);
  const auto rows = model.stations();
  for (const auto& r : rows) {
    const Eigen::Vector2d expected = expected_pixel(g, rows, r.plan_m);
    EXPECT_LE((g.pixel_of(r.plan_m) - expected).norm(), kMappingTol_px) << r.id;
    // A free station is a filled ink disc: its centre pixel is ink.
    if (r.constraint.find('C') == std::string::npos) {
      EXPECT_GE(count_near(image, static_cast<int>(std::lround(expected.x())), static_cast<int>(std::lround(expected.y())), 1, palette::kInk),
                5)
          << r.id;
    }
  }
  EXPECT_EQ(g.ellipses_drawn, rows.size());
  EXPECT_GE(g.ellipse_exaggeration, 1.0);
  // The scale is written where the ellipses are explained.
  const std::string factor = "× " + std::to_string(static_cast<long long>(g.ellipse_exaggeration));
  EXPECT_TRUE(std::any_of(ui.drawn_text().begin(), ui.drawn_text().end(),
                          [&](const DrawnText& t) { return t.where == "network: caption" && t.text.find(factor) != std::string::npos; }))
      << factor;
}

TEST(NetworkView, APlantedBlunderIsDrawnAndLabelledAsAnOutlier) {
  geodesy::Network net = airport();
  const std::size_t planted = planted_distance(net);
  ASSERT_LT(planted, net.measurements.size());
  net.measurements[planted].value(0) += kBlunder_m;
  solver::AdjustOptions removing;
  removing.remove_outliers = true;  // (by default it is flagged, and drawn as failing)
  NetworkModel model(net, removing);
  ASSERT_TRUE(model.result()) << model.error();
  EXPECT_NEAR(model.result()->w_critical, kWCritical, kWCriticalTol);
  NetworkUi ui(model);
  OffscreenRenderer renderer(1600, 1000);
  const RgbImage image = renderer.render(ui);
  const NetworkGeometry& g = ui.plan();
  EXPECT_EQ(g.lines_by_class[static_cast<std::size_t>(MeasurementClass::outlier)], 1u);
  EXPECT_EQ(g.lines_by_class[static_cast<std::size_t>(MeasurementClass::failing)], 0u);
  // The legend counts measurements: one outlier, and every measurement in one class.
  EXPECT_EQ(g.measurements_by_class[static_cast<std::size_t>(MeasurementClass::outlier)], 1u);
  std::size_t counted = 0;
  for (std::size_t n : g.measurements_by_class) counted += n;
  EXPECT_EQ(counted, net.measurements.size());
  ASSERT_EQ(g.labelled_measurements.size(), 1u);
  EXPECT_EQ(g.labelled_measurements.front(), planted);
  const std::string name = NetworkUi::measurement_name(planted) + " outlier";
  EXPECT_TRUE(std::any_of(ui.drawn_text().begin(), ui.drawn_text().end(), [&](const DrawnText& t) {
    return t.where == "network: measurement label" && t.text.starts_with(name);
  })) << name;
  // The dashed vermillion line: along the middle half of the segment, most
  // samples have vermillion within 2 px (the dashes' gaps are shorter
  // than their dashes).
  const auto rows = model.stations();
  const auto& m = net.measurements[planted];
  const Eigen::Vector2d a = g.pixel_of(rows[m.stations[0]].plan_m), b = g.pixel_of(rows[m.stations[1]].plan_m);
  int hits = 0, samples = 0;
  for (double t = 0.25; t <= 0.75; t += 0.01, ++samples) {
    const Eigen::Vector2d p = a + t * (b - a);
    hits += count_near(image, static_cast<int>(std::lround(p.x())), static_cast<int>(std::lround(p.y())), 2, palette::kOutlier) > 0 ? 1 : 0;
  }
  EXPECT_GE(hits, samples / 2) << hits << " of " << samples;
}

TEST(NetworkView, WithoutSnoopingTheBlunderIsKeptAndDrawnAsFailing) {
  geodesy::Network net = airport();
  const std::size_t planted = planted_distance(net);
  net.measurements[planted].value(0) += kBlunder_m;
  solver::AdjustOptions o;
  o.data_snooping = false;
  NetworkModel model(net, o);
  ASSERT_TRUE(model.result()) << model.error();
  NetworkUi ui(model);
  OffscreenRenderer renderer(1600, 1000);
  renderer.render(ui);
  const NetworkGeometry& g = ui.plan();
  EXPECT_EQ(g.lines_by_class[static_cast<std::size_t>(MeasurementClass::outlier)], 0u);
  EXPECT_GE(g.lines_by_class[static_cast<std::size_t>(MeasurementClass::failing)], 1u);
  EXPECT_EQ(model.measurement_rows().at(planted).shown_as, MeasurementClass::failing);
  EXPECT_NE(std::find(g.labelled_measurements.begin(), g.labelled_measurements.end(), planted), g.labelled_measurements.end());
}

TEST(NetworkView, EveryTextFitsOnTheBundledNetworksAtTheDocumentedSizes) {
  const std::string n = kFixtures + "/networks";
  const std::vector<std::vector<std::string>> inputs{
      {kFixtures + "/airport_network/lszh_network.json"},
      {n + "/dynadjust/gnss-networkstn.xml", n + "/dynadjust/gnss-networkmsr.xml"},
      {n + "/gama/stroner-levelling-a.gkf"},
      {n + "/gama/tst-tetrahedron-1.gkf"}};
  for (const auto& in : inputs) {
    NetworkModel model(network_of(in), solver::AdjustOptions{});
    NetworkUi ui(model);
    for (const auto& [w, h] : {std::pair{kMinimumWidth_px, kMinimumHeight_px}, std::pair{1600, 1000}}) {
      OffscreenRenderer renderer(w, h);
      renderer.render(ui);
      EXPECT_TRUE(ui.clipped_text().empty()) << in.front() << " at " << w << "x" << h << ":\n" << clipped(ui.clipped_text());
      EXPECT_GT(ui.drawn_text().size(), 20u);
    }
  }
}

TEST(NetworkView, ALevellingNetworkIsASchematicWithoutEllipses) {
  NetworkModel model(network_of({kFixtures + "/networks/gama/stroner-levelling-a.gkf"}), solver::AdjustOptions{});
  ASSERT_TRUE(model.result()) << model.error();
  NetworkUi ui(model);
  OffscreenRenderer renderer(1600, 1000);
  renderer.render(ui);
  EXPECT_TRUE(ui.plan().schematic);
  EXPECT_EQ(ui.plan().ellipses_drawn, 0u);
}

TEST(NetworkView, AClickOnAStationLeavesItOutAndASecondTakesItBack) {
  NetworkModel model(airport(), solver::AdjustOptions{});
  ASSERT_TRUE(model.result()) << model.error();
  const int dof = model.result()->dof;
  NetworkUi ui(model);
  OffscreenRenderer renderer(1600, 1000);
  renderer.render(ui);
  const auto rows = model.stations();
  const auto p05 = std::find_if(rows.begin(), rows.end(), [](const auto& r) { return r.id == "P05"; });
  ASSERT_NE(p05, rows.end());
  const Eigen::Vector2d p = ui.plan().pixel_of(p05->plan_m);
  const auto draw = [&](float w, float h) { ui.draw(w, h); };
  // Hovering names it.
  renderer.render(ui, std::array<float, 2>{static_cast<float>(p.x()), static_cast<float>(p.y())});
  EXPECT_EQ(ui.plan().hovered, "P05");
  renderer.click(draw, static_cast<float>(p.x()), static_cast<float>(p.y()));
  model.wait();
  EXPECT_EQ(model.stations_left_out(), std::vector<std::string>{"P05"});
  ASSERT_TRUE(model.result()) << model.error();
  EXPECT_LT(model.result()->dof, dof);
  renderer.render(ui);
  const Eigen::Vector2d q = ui.plan().pixel_of(model.stations()[static_cast<std::size_t>(p05 - rows.begin())].plan_m);
  renderer.click(draw, static_cast<float>(q.x()), static_cast<float>(q.y()));
  model.wait();
  EXPECT_TRUE(model.stations_left_out().empty());
  ASSERT_TRUE(model.result());
  EXPECT_EQ(model.result()->dof, dof);
}

TEST(NetworkView, TheMeasurementTablesCheckBoxLeavesAMeasurementOut) {
  NetworkModel model(airport(), solver::AdjustOptions{});
  ASSERT_TRUE(model.result()) << model.error();
  NetworkUi ui(model);
  OffscreenRenderer renderer(1600, 1000);
  renderer.render(ui);
  const NetworkTableGeometry t = ui.measurement_table();
  ASSERT_TRUE(t.drawn);
  ASSERT_GT(t.shown, 0u);
  ASSERT_GT(t.shown, 1u);
  // The second row in view: the airport network's first is its reference
  // stations' point cluster, which has no line; the second is a baseline.
  const std::size_t row = t.first + 1;
  const float x = t.left + 0.5f * t.row_height_px, y = t.first_row_top + 1.5f * t.row_height_px;
  renderer.click([&](float w, float h) { ui.draw(w, h); }, x, y);
  model.wait();
  EXPECT_EQ(model.measurements_left_out(), std::vector<std::size_t>{row});
  renderer.render(ui);
  const auto lines = model.lines();
  const auto of_row = std::count_if(lines.begin(), lines.end(), [&](const NetworkLine& l) { return l.measurement == row; });
  EXPECT_GT(of_row, 0);
  EXPECT_EQ(ui.plan().lines_by_class[static_cast<std::size_t>(MeasurementClass::left_out)], static_cast<std::size_t>(of_row));
}

// Issue 17 point 6: a network too dense to draw station by station. The
// generator plants blunders far beyond their MDB (10 cm on baselines of a
// few millimetres); data snooping finds them (solver tests), and the view
// must show each one on its own, labelled, however dense the rest.
TEST(NetworkView, ADenseNetworkIsDrawnByCellsWithEveryOutlierOnItsOwnAndZoomingInShowsEachStation) {
  constexpr std::size_t kStations = 3000;  // twice kDenseNetworkStations
  constexpr double kPointerTol_px = 0.01;  // double arithmetic against float pixels
  constexpr double kZoomTol = 1e-12;
  constexpr double kCentreTol_m = 1e-6;     // on a plan of 100 km
  workflow::NetworkGeneratorOptions o;
  o.stations = kStations;
  o.side_km = 100.0;
  o.seed = 7;
  const workflow::GeneratedNetwork generated = workflow::generate_network(o);
  ASSERT_FALSE(generated.blunders.empty());
  solver::AdjustOptions removing;
  removing.remove_outliers = true;
  NetworkModel model(generated.network, removing);
  model.wait();
  ASSERT_TRUE(model.result()) << model.error();
  NetworkUi ui(model);
  OffscreenRenderer renderer(1600, 1000);
  const RgbImage image = renderer.render(ui);
  const NetworkGeometry& g = ui.plan();
  ASSERT_TRUE(g.drawn);
  EXPECT_TRUE(g.aggregated);
  EXPECT_EQ(g.stations_in_view, kStations);
  EXPECT_EQ(g.ellipses_drawn, 0u);
  EXPECT_GT(g.marks_drawn, 0u);
  EXPECT_EQ(g.stations_drawn, o.held);  // the held stations' triangles
  EXPECT_FALSE(std::any_of(ui.drawn_text().begin(), ui.drawn_text().end(), [](const DrawnText& t) { return t.where == "network: id"; }));
  // Every line is drawn, bundled or inside a cell's mark.
  std::size_t one_by_one = 0;
  for (std::size_t n : g.lines_by_class) one_by_one += n;
  EXPECT_EQ(one_by_one + g.lines_bundled + g.lines_within_cells, model.lines().size());
  // Each planted blunder: an outlier line of its own, labelled, vermillion along its middle.
  const auto rows = model.stations();
  const auto measurements = model.measurement_rows();
  for (const auto& b : generated.blunders) {
    EXPECT_EQ(measurements.at(b.measurement).shown_as, MeasurementClass::outlier) << NetworkUi::measurement_name(b.measurement);
    EXPECT_NE(std::find(g.labelled_measurements.begin(), g.labelled_measurements.end(), b.measurement), g.labelled_measurements.end())
        << NetworkUi::measurement_name(b.measurement);
  }
  std::size_t outliers = 0;
  for (const auto& m : measurements) outliers += m.shown_as == MeasurementClass::outlier ? 1u : 0u;
  EXPECT_EQ(g.lines_by_class[static_cast<std::size_t>(MeasurementClass::outlier)], outliers);
  EXPECT_EQ(g.rings_drawn, outliers);  // a baseline is a few pixels long here: each outlier ringed
  const auto& first = generated.network.measurements[generated.blunders.front().measurement];
  const Eigen::Vector2d a = g.pixel_of(rows[first.stations[0]].plan_m), b = g.pixel_of(rows[first.stations[1]].plan_m);
  const Eigen::Vector2d mid = 0.5 * (a + b);
  EXPECT_GT(count_near(image, static_cast<int>(std::lround(mid.x())), static_cast<int>(std::lround(mid.y())), 3, palette::kOutlier), 0);

  // Zoom in about the blunder: the point under the pointer stays there,
  // and once no more than kDenseNetworkStations are in view each station
  // and line is drawn again, with the ids where there is room.
  const Eigen::Vector2d mid_m = 0.5 * (rows[first.stations[0]].plan_m + rows[first.stations[1]].plan_m);
  const auto draw = [&](float w, float h) { ui.draw(w, h); };
  // ImGui floors the pointer to whole pixels.
  const float mx = std::floor(static_cast<float>(mid.x())), my = std::floor(static_cast<float>(mid.y()));
  renderer.wheel(draw, mx, my, 8.0f);  // × 1.25⁸ ≈ 6
  // The frame that took the wheel, drawn before the zoom: the documented
  // rule gives the plan point under the pointer and the centre that keeps
  // it there at 1.25⁸ × the scale.
  const NetworkGeometry before = ui.plan();
  const double zoom = std::pow(1.25, 8.0);
  const Eigen::Vector2d c_px(0.5 * (before.left + before.right), 0.5 * (before.top + before.bottom));
  const Eigen::Vector2d under = before.center_m + Eigen::Vector2d((mx - c_px.x()) / before.px_per_m, -(my - c_px.y()) / before.px_per_m);
  const double zoomed = before.px_per_m * zoom;
  const Eigen::Vector2d centre = under - Eigen::Vector2d((mx - c_px.x()) / zoomed, -(my - c_px.y()) / zoomed);
  renderer.render(ui);
  const NetworkGeometry& z = ui.plan();
  EXPECT_NEAR(z.zoom, zoom, kZoomTol);
  EXPECT_LE((z.center_m - centre).norm(), kCentreTol_m);
  EXPECT_FALSE(z.aggregated);
  EXPECT_LT(z.stations_in_view, kDenseNetworkStations);
  EXPECT_EQ(z.stations_drawn, z.stations_in_view);
  std::size_t ids = 0;
  for (const auto& t : ui.drawn_text()) ids += t.where == "network: id" ? 1u : 0u;
  EXPECT_EQ(ids + z.unlabelled.size(), z.stations_in_view);
  EXPECT_GT(ids, 0u);
  EXPECT_NE(std::find(z.labelled_measurements.begin(), z.labelled_measurements.end(), generated.blunders.front().measurement),
            z.labelled_measurements.end());
  EXPECT_TRUE(clipped(ui.clipped_text()).empty()) << clipped(ui.clipped_text());

  // A view set by hand, and back to the whole network.
  ui.set_plan_view(2.0, mid_m);
  renderer.render(ui);
  EXPECT_LE((ui.plan().pixel_of(mid_m) - Eigen::Vector2d(0.5 * (ui.plan().left + ui.plan().right), 0.5 * (ui.plan().top + ui.plan().bottom))).norm(),
            kPointerTol_px);
  ui.reset_plan_view();
  renderer.render(ui);
  EXPECT_EQ(ui.plan().zoom, 1.0);
  EXPECT_EQ(ui.plan().stations_in_view, kStations);
  EXPECT_THROW(ui.set_plan_view(0.5, mid_m), std::invalid_argument);
  EXPECT_THROW(ui.set_plan_view(std::numeric_limits<double>::quiet_NaN(), mid_m), std::invalid_argument);
}

}  // namespace
}  // namespace geoanchor::gui
