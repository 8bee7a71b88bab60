// Fit throughput: geoanchor's Ceres fit (with covariance and per-point
// statistics) for N = 10² … 10⁶ control points, 7 and 14 parameters, and the
// ratio to a closed-form linear least-squares solve of the same problem
// (normal equations of the linearised small-angle model, one shot).
// Never part of the test run's pass/fail.

#include <benchmark/benchmark.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cstdio>
#include <map>
#include <random>
#include <string>

#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/solver/helmert_fit.hpp"
#include "median_reporter.hpp"

namespace {

using namespace geoanchor;
using geodesy::Angle;

geodesy::ControlSet make_set(std::size_t n, bool time_dependent) {
  std::mt19937_64 rng(n);
  std::uniform_real_distribution<double> lat(45.0, 50.0), lon(5.0, 12.0), h(0.0, 2000.0);
  std::normal_distribution<double> noise(0.0, 0.003);
  geodesy::Helmert14<geodesy::PositionVector> truth;
  truth.at_reference_epoch.t_m = Eigen::Vector3d(0.05, 0.05, -0.07);
  truth.at_reference_epoch.rx = Angle::milliarcseconds(2.0);
  truth.at_reference_epoch.ry = Angle::milliarcseconds(14.0);
  truth.at_reference_epoch.rz = Angle::milliarcseconds(-21.0);
  truth.at_reference_epoch.ds = geodesy::ScaleDifference::ppb(2.0);
  truth.rates.dt_m_per_year = Eigen::Vector3d(0.0001, 0.0001, -0.0019);
  truth.rates.drx_per_year = Angle::milliarcseconds(0.081);
  truth.rates.dry_per_year = Angle::milliarcseconds(0.49);
  truth.rates.drz_per_year = Angle::milliarcseconds(-0.792);
  truth.reference_epoch = geodesy::DecimalYear{2015.0};
  const geodesy::GeocentricConverter conv(geodesy::Ellipsoid::grs80());
  geodesy::ControlSet set;
  set.source_name = "bench";
  set.points.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    geodesy::ControlPoint p;
    p.id = std::to_string(i);
    p.source = conv.ecef_from_geodetic({Angle::degrees(lat(rng)), Angle::degrees(lon(rng)), geodesy::EllipsoidalHeight{h(rng)}});
    const double t = time_dependent ? 2010.0 + 5.0 * static_cast<double>(i % 3) : 2015.0;
    if (time_dependent) p.epoch = geodesy::DecimalYear{t};
    p.target = geodesy::apply(geodesy::evaluate_at(truth, geodesy::DecimalYear{t}), geodesy::RotationModel::small_angle, p.source);
    p.target.m += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    p.source_cov_m2 = p.target_cov_m2 = Eigen::Matrix3d::Identity() * 0.003 * 0.003 / 2.0;
    set.points.push_back(p);
  }
  return set;
}

const geodesy::ControlSet& cached(std::size_t n, bool td) {
  static std::map<std::pair<std::size_t, bool>, geodesy::ControlSet> sets;
  auto it = sets.find({n, td});
  if (it == sets.end()) it = sets.emplace(std::make_pair(n, td), make_set(n, td)).first;
  return it->second;
}

void fit(benchmark::State& state, bool td) {
  const auto& set = cached(static_cast<std::size_t>(state.range(0)), td);
  solver::FitOptions o;
  o.model = td ? solver::FitModel::helmert14 : solver::FitModel::helmert7;
  o.convention = solver::Convention::position_vector;
  o.data_snooping = false;  // one pass: covariance and per-point statistics, no refits
  for (auto _ : state) {
    auto r = solver::fit_helmert(set, o);
    benchmark::DoNotOptimize(r.sigma0);
  }
}

// The classic one-shot linear solution: normal equations of
// y − x = T + ds·x + r × x (+ rates·dt), weights from the covariances, solved
// once by Cholesky, with the parameter covariance as its inverse.
void closed_form(benchmark::State& state, bool td) {
  const auto& set = cached(static_cast<std::size_t>(state.range(0)), td);
  const int u = td ? 14 : 7;
  for (auto _ : state) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (const auto& p : set.points) c += p.source.m;
    c /= static_cast<double>(set.points.size());
    Eigen::MatrixXd n = Eigen::MatrixXd::Zero(u, u);
    Eigen::VectorXd b = Eigen::VectorXd::Zero(u);
    Eigen::Matrix<double, 3, 14> a;
    for (const auto& p : set.points) {
      const Eigen::Vector3d x = p.source.m - c;
      const Eigen::Matrix3d w = (p.source_cov_m2 + p.target_cov_m2).inverse();
      a.setZero();
      a.block<3, 3>(0, 0).setIdentity();
      a.block<3, 3>(0, 3) << 0, x.z(), -x.y(), -x.z(), 0, x.x(), x.y(), -x.x(), 0;
      a.col(6) = x;
      if (td) a.block<3, 7>(0, 7) = (p.epoch->year - 2015.0) * a.block<3, 7>(0, 0);
      const auto au = a.leftCols(u);
      n.noalias() += au.transpose() * w * au;
      b.noalias() += au.transpose() * w * (p.target.m - p.source.m);
    }
    const Eigen::LLT<Eigen::MatrixXd> llt(n);
    Eigen::VectorXd sol = llt.solve(b);
    Eigen::MatrixXd cov = llt.solve(Eigen::MatrixXd::Identity(u, u));
    benchmark::DoNotOptimize(sol.data());
    benchmark::DoNotOptimize(cov.data());
  }
}

void fit7(benchmark::State& s) { fit(s, false); }
void fit14(benchmark::State& s) { fit(s, true); }
void closed7(benchmark::State& s) { closed_form(s, false); }
void closed14(benchmark::State& s) { closed_form(s, true); }

void print_table(const geoanchor::bench::MedianReporter& r) {
  std::printf("\n%-9s %-6s %14s %16s %8s\n", "points", "model", "fit median s", "closed-form s", "ratio");
  for (const char* m : {"7", "14"}) {
    for (int n = 100; n <= 1000000; n *= 10) {
      const std::string fit = std::string("fit") + m + "/" + std::to_string(n);
      const std::string closed = std::string("closed") + m + "/" + std::to_string(n);
      if (!r.ran(fit) && !r.ran(closed)) continue;  // both filtered out; one missing prints nan
      const double f = r.median_s(fit), c = r.median_s(closed);
      std::printf("%-9d %-6s %14.4f %16.4f %8.1f\n", n, m, f, c, f / c);
    }
  }
}

}  // namespace

#define FIT_BENCH(f) \
  BENCHMARK(f)->RangeMultiplier(10)->Range(100, 1000000)->Repetitions(3)->ReportAggregatesOnly(true)->Unit(benchmark::kMillisecond)
FIT_BENCH(fit7);
FIT_BENCH(closed7);
FIT_BENCH(fit14);
FIT_BENCH(closed14);

int main(int argc, char** argv) { return geoanchor::bench::run_and_tabulate(argc, argv, print_table); }
