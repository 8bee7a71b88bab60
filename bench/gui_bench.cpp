// Frame time of the off-screen workbench shell (OSMesa llvmpipe, 1600×1000)
// with 10², 10³ and 10⁴ control points, per view, against the 50 ms frame
// budget of the issue; the network view (issue 17 point 6) on generated
// networks of 10³, 10⁴ and 10⁵ stations, whole, zoomed in ×16, and while
// the view changes every frame (level of detail recomputed); and a whole
// snapshot (context, fonts, three frames, PNG) of the bundled example.
// Never part of the test run's pass/fail.

#include <benchmark/benchmark.h>

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <random>
#include <string>

#include <imgui.h>

#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/gui/offscreen.hpp"
#include "geoanchor/io/control/control_csv.hpp"
#include "geoanchor/workflow/network_generator.hpp"
#include "median_reporter.hpp"

namespace {

using namespace geoanchor;
using geodesy::Angle;
constexpr int kWidth_px = 1600, kHeight_px = 1000;
constexpr double kFrameBudget_ms = 50.0;

// n marks over an airport-sized area (3 km), known in two frames related by
// a small Helmert, 3 mm noise, one blunder in a hundred.
geodesy::ControlSet make_set(std::size_t n) {
  std::mt19937_64 rng(n);
  std::uniform_real_distribution<double> lat(47.45, 47.48), lon(8.52, 8.58), h(400.0, 450.0), u(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.003);
  geodesy::Helmert7<geodesy::PositionVector> truth;
  truth.t_m = Eigen::Vector3d(0.05, 0.05, -0.07);
  truth.rx = Angle::milliarcseconds(2.0);
  truth.ry = Angle::milliarcseconds(14.0);
  truth.rz = Angle::milliarcseconds(-21.0);
  truth.ds = geodesy::ScaleDifference::ppb(2.0);
  const geodesy::GeocentricConverter conv(geodesy::Ellipsoid::grs80());
  geodesy::ControlSet set;
  set.source_name = "bench";
  for (std::size_t i = 0; i < n; ++i) {
    geodesy::ControlPoint p;
    p.id = "M" + std::to_string(i);
    p.source = conv.ecef_from_geodetic({Angle::degrees(lat(rng)), Angle::degrees(lon(rng)), geodesy::EllipsoidalHeight{h(rng)}});
    p.target = geodesy::apply(truth, geodesy::RotationModel::small_angle, p.source);
    p.target.m += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    if (u(rng) < 0.01) p.target.m.x() += 0.1;
    p.source_cov_m2 = p.target_cov_m2 = Eigen::Matrix3d::Identity() * 0.003 * 0.003 / 2.0;
    set.points.push_back(p);
  }
  return set;
}

struct Scene {
  std::unique_ptr<gui::WorkbenchModel> model;
  std::unique_ptr<gui::WorkbenchUi> ui;
};

gui::OffscreenRenderer& renderer() {
  static gui::OffscreenRenderer r(kWidth_px, kHeight_px);
  return r;
}

Scene& scene(std::size_t n) {
  static std::map<std::size_t, Scene> scenes;
  auto it = scenes.find(n);
  if (it == scenes.end()) {
    solver::FitOptions o;
    o.model = solver::FitModel::helmert7;
    o.convention = solver::Convention::position_vector;
    Scene s;
    s.model = std::make_unique<gui::WorkbenchModel>(make_set(n), o);
    s.model->wait();
    s.ui = std::make_unique<gui::WorkbenchUi>(*s.model, gui::UiOptions{});
    it = scenes.emplace(n, std::move(s)).first;
  }
  return it->second;
}

void frame(benchmark::State& state, gui::View view) {
  Scene& s = scene(static_cast<std::size_t>(state.range(0)));
  renderer().render(*s.ui, view);  // settle
  for (auto _ : state) renderer().render_frame(*s.ui, view);
}

struct NetworkScene {
  std::unique_ptr<gui::NetworkModel> model;
  std::unique_ptr<gui::NetworkUi> ui;
  Eigen::Vector2d centre_m = Eigen::Vector2d::Zero();
};

// A generated network (bench/adjust_bench's generator), adjusted without
// data snooping (its planted blunders are drawn as failing: one by one,
// labelled), kept for every benchmark of its size.
NetworkScene& network_scene(std::size_t n) {
  static std::map<std::size_t, NetworkScene> scenes;
  auto it = scenes.find(n);
  if (it == scenes.end()) {
    workflow::NetworkGeneratorOptions g;
    g.stations = n;
    solver::AdjustOptions o;
    o.data_snooping = false;
    NetworkScene s;
    s.model = std::make_unique<gui::NetworkModel>(workflow::generate_network(g).network, o);
    s.model->wait();
    s.ui = std::make_unique<gui::NetworkUi>(*s.model);
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(1e300), hi = -lo;
    for (const auto& r : s.model->stations()) lo = lo.cwiseMin(r.plan_m), hi = hi.cwiseMax(r.plan_m);
    s.centre_m = 0.5 * (lo + hi);
    it = scenes.emplace(n, std::move(s)).first;
  }
  return it->second;
}

enum class NetworkFrame { whole, zoomed, moving };

void network_frame(benchmark::State& state, NetworkFrame kind) {
  NetworkScene& s = network_scene(static_cast<std::size_t>(state.range(0)));
  if (!s.model->result()) {
    state.SkipWithError(s.model->error().c_str());
    return;
  }
  if (kind == NetworkFrame::zoomed) s.ui->set_plan_view(16.0, s.centre_m);
  else s.ui->reset_plan_view();
  renderer().render(*s.ui);  // settle
  int k = 0;
  for (auto _ : state) {
    // A view that moves by a metre each frame: nothing can be reused.
    if (kind == NetworkFrame::moving) s.ui->set_plan_view(1.0, s.centre_m + Eigen::Vector2d(++k % 2, 0.0));
    renderer().render_frame(*s.ui);
  }
  state.counters["in_view"] = static_cast<double>(s.ui->plan().stations_in_view);
  // What the rasterizer gets: llvmpipe's time goes with the triangles.
  state.counters["triangles"] = static_cast<double>(ImGui::GetDrawData()->TotalIdxCount / 3);
  s.ui->reset_plan_view();
}

void snapshot_total(benchmark::State& state) {
  const auto set = io::read_control_set(std::string(GEOANCHOR_FIXTURES_DIR) + "/airport_control.csv", io::ControlReadOptions{});
  // A name of this run's own (mkstemps): two runs at once must not share one.
  std::string templ = (std::filesystem::temp_directory_path() / "geoanchor_gui_bench_XXXXXX.png").string();
  const int fd = ::mkstemps(templ.data(), 4);
  if (fd < 0) {
    state.SkipWithError(("cannot create " + templ).c_str());
    return;
  }
  ::close(fd);
  const std::filesystem::path out = templ;
  for (auto _ : state) {
    solver::FitOptions o;
    o.model = solver::FitModel::helmert7;
    o.convention = solver::Convention::position_vector;
    gui::WorkbenchModel model(set, o);
    gui::OffscreenRenderer r(kWidth_px, kHeight_px);
    gui::WorkbenchUi ui(model, {});
    gui::write_png(r.render(ui, gui::View::workbench), out, true);
  }
  std::filesystem::remove(out);
}

const std::map<std::string, gui::View> kViews{{"workbench", gui::View::workbench},
                                              {"plan", gui::View::plan},
                                              {"table", gui::View::table},
                                              {"histogram", gui::View::histogram}};

void print_table(const bench::MedianReporter& r) {
  std::printf("\nframe time, %dx%d, OSMesa llvmpipe (median ms; budget %.0f ms)\n", kWidth_px, kHeight_px, kFrameBudget_ms);
  std::printf("%-10s %10s %10s %10s %16s\n", "view", "100 pts", "1000 pts", "10000 pts", "10⁴ / budget");
  for (const auto& [name, v] : kViews) {
    (void)v;
    double ms[3];
    for (int k = 0; k < 3; ++k) ms[k] = 1e3 * r.median_s("frame_" + name + "/" + std::to_string(k == 0 ? 100 : k == 1 ? 1000 : 10000));
    std::printf("%-10s %10.2f %10.2f %10.2f %16.2f\n", name.c_str(), ms[0], ms[1], ms[2], ms[2] / kFrameBudget_ms);
  }
  std::printf("\nnetwork view, frame time, %dx%d, OSMesa llvmpipe (median ms; budget %.0f ms)\n", kWidth_px, kHeight_px, kFrameBudget_ms);
  std::printf("%-44s %10s %10s %10s %16s\n", "view", "10³ stns", "10⁴ stns", "10⁵ stns", "10⁵ / budget");
  for (const char* name : {"whole network", "zoomed ×16", "view moving every frame (no reuse)"}) {
    const std::string key = std::string(name) == "whole network" ? "network_whole" : std::string(name) == "zoomed ×16" ? "network_zoomed" : "network_moving";
    double ms[3];
    for (int k = 0; k < 3; ++k) ms[k] = 1e3 * r.median_s(key + "/" + std::to_string(k == 0 ? 1000 : k == 1 ? 10000 : 100000));
    std::printf("%-44s %10.2f %10.2f %10.2f %16.2f\n", name, ms[0], ms[1], ms[2], ms[2] / kFrameBudget_ms);
  }
  std::printf("whole snapshot of the bundled example (context, fonts, fit, 3 frames, PNG): %.0f ms\n",
              1e3 * r.median_s("snapshot_total"));
}

}  // namespace

int main(int argc, char** argv) {
  for (const auto& [name, v] : kViews) {
    benchmark::RegisterBenchmark(("frame_" + name).c_str(), frame, v)
        ->Arg(100)->Arg(1000)->Arg(10000)->Repetitions(5)->ReportAggregatesOnly(true)->Unit(benchmark::kMillisecond);
  }
  for (const auto& [name, kind] : {std::pair{"network_whole", NetworkFrame::whole}, std::pair{"network_zoomed", NetworkFrame::zoomed},
                                   std::pair{"network_moving", NetworkFrame::moving}}) {
    benchmark::RegisterBenchmark(name, network_frame, kind)
        ->Arg(1000)->Arg(10000)->Arg(100000)->Repetitions(5)->ReportAggregatesOnly(true)->Unit(benchmark::kMillisecond);
  }
  benchmark::RegisterBenchmark("snapshot_total", snapshot_total)->Repetitions(5)->ReportAggregatesOnly(true)->Unit(benchmark::kMillisecond);
  return bench::run_and_tabulate(argc, argv, print_table);
}
