// Frame time of the off-screen workbench shell (OSMesa llvmpipe, 1600×1000)
// with 10², 10³ and 10⁴ control points, per view, against the 50 ms frame
// budget of the issue; and a whole snapshot (context, fonts, three frames,
// PNG) of the bundled example. Never part of the test run's pass/fail.

#include <benchmark/benchmark.h>

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <random>
#include <string>

#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/gui/offscreen.hpp"
#include "geoanchor/io/control_csv.hpp"
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
  std::printf("whole snapshot of the bundled example (context, fonts, fit, 3 frames, PNG): %.0f ms\n",
              1e3 * r.median_s("snapshot_total"));
}

}  // namespace

int main(int argc, char** argv) {
  for (const auto& [name, v] : kViews) {
    benchmark::RegisterBenchmark(("frame_" + name).c_str(), frame, v)
        ->Arg(100)->Arg(1000)->Arg(10000)->Repetitions(5)->ReportAggregatesOnly(true)->Unit(benchmark::kMillisecond);
  }
  benchmark::RegisterBenchmark("snapshot_total", snapshot_total)->Repetitions(5)->ReportAggregatesOnly(true)->Unit(benchmark::kMillisecond);
  return bench::run_and_tabulate(argc, argv, print_table);
}
