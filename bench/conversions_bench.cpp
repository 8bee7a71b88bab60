// Conversion throughput: geoanchor's paths against PROJ on the same points,
// and a plain copy of the same bytes as the memory-bandwidth floor.
// Prints Google Benchmark's medians, then a table of median ns/point and the
// ratio PROJ / geoanchor. Never part of the test run's pass/fail.

#include <benchmark/benchmark.h>
#include <proj.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "geoanchor/geodesy/affine.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/helmert.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/geodesy/projection.hpp"
#include "geoanchor/io/tile/point_chain.hpp"
#include "median_reporter.hpp"

namespace {

using namespace geoanchor::geodesy;

constexpr std::size_t kPoints = 100000;

struct Data {
  std::vector<double> lon_rad, lat_rad, lon_deg, lat_deg, h, x, y, z, e, n, u;
  Data() {
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> d(-3000.0, 3000.0), lat(47.4, 47.5), lon(8.5, 8.6), hh(400, 600);
    const GeocentricConverter conv(Ellipsoid::wgs84());
    for (std::size_t i = 0; i < kPoints; ++i) {
      lat_deg.push_back(lat(rng));
      lon_deg.push_back(lon(rng));
      lat_rad.push_back(proj_torad(lat_deg.back()));
      lon_rad.push_back(proj_torad(lon_deg.back()));
      h.push_back(hh(rng));
      const auto p = conv.ecef_from_geodetic({Angle::degrees(lat_deg.back()), Angle::degrees(lon_deg.back()), EllipsoidalHeight{h.back()}});
      x.push_back(p.m.x());
      y.push_back(p.m.y());
      z.push_back(p.m.z());
      e.push_back(d(rng));
      n.push_back(d(rng));
      u.push_back(0.01 * d(rng));
    }
  }
};
const Data& data() {
  static const Data d;
  return d;
}

struct Proj {
  PJ_CONTEXT* ctx = proj_context_create();
  PJ* pj;
  explicit Proj(const char* def) : pj(proj_create(ctx, def)) {}
  ~Proj() {
    proj_destroy(pj);
    proj_context_destroy(ctx);
  }
  void run(std::vector<double>& a, std::vector<double>& b, std::vector<double>& c, PJ_DIRECTION dir) const {
    proj_trans_generic(pj, dir, a.data(), sizeof(double), a.size(), b.data(), sizeof(double), b.size(), c.data(),
                       sizeof(double), c.size(), nullptr, 0, 0);
  }
};

const LocalOrigin kArpA{{Angle::degrees(47.464722), Angle::degrees(8.549167), EllipsoidalHeight{480.0}}, Ellipsoid::wgs84()};
const LocalOrigin kArpB{{Angle::degrees(47.458), Angle::degrees(8.561), EllipsoidalHeight{470.0}}, Ellipsoid::wgs84()};

Helmert7<PositionVector> helmert() {
  Helmert7<PositionVector> h;
  h.t_m = Eigen::Vector3d(0.3, -0.2, 0.05);
  h.rx = Angle::arcseconds(0.02);
  h.ry = Angle::arcseconds(-0.01);
  h.rz = Angle::arcseconds(20.0);
  h.ds = ScaleDifference::ppm(1.5);
  return h;
}

void finish(benchmark::State& state) { state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(kPoints)); }

// PROJ over the three input columns, restored from `a0, b0, c0` untimed
// before each pass (proj_trans_generic works in place).
void run_proj(benchmark::State& state, const char* definition, const std::vector<double>& a0,
              const std::vector<double>& b0, const std::vector<double>& c0, PJ_DIRECTION direction) {
  const Proj p(definition);
  std::vector<double> a, b, c;
  for (auto _ : state) {
    state.PauseTiming();
    a = a0, b = b0, c = c0;
    state.ResumeTiming();
    p.run(a, b, c, direction);
    benchmark::DoNotOptimize(a.data());
  }
  finish(state);
}

void copy_xyz(benchmark::State& state) {
  const auto& d = data();
  std::vector<double> x(kPoints), y(kPoints), z(kPoints);
  for (auto _ : state) {
    std::memcpy(x.data(), d.x.data(), kPoints * sizeof(double));
    std::memcpy(y.data(), d.y.data(), kPoints * sizeof(double));
    std::memcpy(z.data(), d.z.data(), kPoints * sizeof(double));
    benchmark::DoNotOptimize(x.data());
    benchmark::ClobberMemory();
  }
  finish(state);
}

void ours_geodetic_to_ecef(benchmark::State& state) {
  const auto& d = data();
  const GeocentricConverter conv(Ellipsoid::wgs84());
  std::vector<double> x(kPoints), y(kPoints), z(kPoints);
  for (auto _ : state) {
    for (std::size_t i = 0; i < kPoints; ++i) {
      const auto p = conv.ecef_from_geodetic({Angle::degrees(d.lat_deg[i]), Angle::degrees(d.lon_deg[i]), EllipsoidalHeight{d.h[i]}});
      x[i] = p.m.x();
      y[i] = p.m.y();
      z[i] = p.m.z();
    }
    benchmark::DoNotOptimize(x.data());
  }
  finish(state);
}

void proj_geodetic_to_ecef(benchmark::State& state) {
  run_proj(state, "+proj=cart +ellps=WGS84", data().lon_rad, data().lat_rad, data().h, PJ_FWD);
}

void ours_ecef_to_geodetic(benchmark::State& state) {
  const auto& d = data();
  const GeocentricConverter conv(Ellipsoid::wgs84());
  std::vector<double> a(kPoints), b(kPoints), c(kPoints);
  for (auto _ : state) {
    for (std::size_t i = 0; i < kPoints; ++i) {
      const auto g = conv.geodetic_from_ecef(EcefPosition(d.x[i], d.y[i], d.z[i]));
      a[i] = g.lat.deg();
      b[i] = g.lon.deg();
      c[i] = g.h.m;
    }
    benchmark::DoNotOptimize(a.data());
  }
  finish(state);
}

void proj_ecef_to_geodetic(benchmark::State& state) {
  run_proj(state, "+proj=cart +ellps=WGS84", data().x, data().y, data().z, PJ_INV);
}

// ENU(ARP A) -> ECEF -> Helmert -> ECEF -> ENU(ARP B): io::PointChain, which
// fuses the chain once into one affine map. In place, as apply runs on tiles.
void ours_enu_helmert_enu(benchmark::State& state) {
  const auto& d = data();
  geoanchor::io::TransformFile t;
  t.model = geoanchor::io::TransformModel::helmert7;
  t.helmert = helmert();
  const geoanchor::io::ArrayFrame a{geoanchor::io::CoordinateKind::enu, Ellipsoid::wgs84(), kArpA, std::nullopt};
  const geoanchor::io::ArrayFrame b{geoanchor::io::CoordinateKind::enu, Ellipsoid::wgs84(), kArpB, std::nullopt};
  const geoanchor::io::PointChain chain(a, t, false, std::nullopt, b);
  std::vector<double> x = d.e, y = d.n, z = d.u;
  for (auto _ : state) {
    chain.apply(x, y, z);
    benchmark::DoNotOptimize(x.data());
  }
  finish(state);
}

void proj_enu_helmert_enu(benchmark::State& state) {
  char def[512];
  std::snprintf(def, sizeof def,
                "+proj=pipeline +step +inv +proj=topocentric +ellps=WGS84 +lat_0=%.17g +lon_0=%.17g +h_0=%.17g "
                "+step +proj=helmert +x=0.3 +y=-0.2 +z=0.05 +rx=0.02 +ry=-0.01 +rz=20 +s=1.5 "
                "+convention=position_vector +step +proj=topocentric +ellps=WGS84 +lat_0=%.17g +lon_0=%.17g +h_0=%.17g",
                kArpA.point.lat.deg(), kArpA.point.lon.deg(), kArpA.point.h.m, kArpB.point.lat.deg(),
                kArpB.point.lon.deg(), kArpB.point.h.m);
  run_proj(state, def, data().e, data().n, data().u, PJ_FWD);
}

void ours_utm(benchmark::State& state) {
  const auto& d = data();
  const TransverseMercator tm(utm_projection(Ellipsoid::wgs84(), {32, Hemisphere::north}));
  std::vector<double> a(kPoints), b(kPoints);
  for (auto _ : state) {
    for (std::size_t i = 0; i < kPoints; ++i) {
      const auto q = tm.forward({Angle::degrees(d.lat_deg[i]), Angle::degrees(d.lon_deg[i]), EllipsoidalHeight{0}});
      a[i] = q.easting_m;
      b[i] = q.northing_m;
    }
    benchmark::DoNotOptimize(a.data());
  }
  finish(state);
}

void proj_utm(benchmark::State& state) {
  run_proj(state, "+proj=utm +zone=32 +ellps=WGS84", data().lon_rad, data().lat_rad, data().h, PJ_FWD);
}

// Median ns/point and PROJ/ours ratios, after Google Benchmark's own output.
void print_table(const geoanchor::bench::MedianReporter& r) {
  auto ns_per_point = [&](const std::string& name) { return r.median_s(name) * 1e9 / static_cast<double>(kPoints); };
  std::printf("\n%-22s %14s %14s %10s\n", "median ns/point", "geoanchor", "PROJ", "PROJ/ours");
  for (const char* what : {"geodetic_to_ecef", "ecef_to_geodetic", "enu_helmert_enu", "utm"}) {
    if (!r.ran(std::string("ours_") + what) && !r.ran(std::string("proj_") + what)) continue;  // both filtered out
    const double ours = ns_per_point(std::string("ours_") + what), proj = ns_per_point(std::string("proj_") + what);
    std::printf("%-22s %14.2f %14.2f %10.2f\n", what, ours, proj, proj / ours);
  }
  std::printf("%-22s %14.2f   (plain copy of the same xyz bytes: memory floor)\n", "copy_xyz", ns_per_point("copy_xyz"));
}

}  // namespace

#define GEOANCHOR_BENCH(f) BENCHMARK(f)->Repetitions(7)->ReportAggregatesOnly(true)->Unit(benchmark::kMillisecond)
GEOANCHOR_BENCH(copy_xyz);
GEOANCHOR_BENCH(ours_geodetic_to_ecef);
GEOANCHOR_BENCH(proj_geodetic_to_ecef);
GEOANCHOR_BENCH(ours_ecef_to_geodetic);
GEOANCHOR_BENCH(proj_ecef_to_geodetic);
GEOANCHOR_BENCH(ours_enu_helmert_enu);
GEOANCHOR_BENCH(proj_enu_helmert_enu);
GEOANCHOR_BENCH(ours_utm);
GEOANCHOR_BENCH(proj_utm);

int main(int argc, char** argv) { return geoanchor::bench::run_and_tabulate(argc, argv, print_table); }
