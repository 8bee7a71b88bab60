// Tile throughput for `geoanchor apply`, on 10⁷ float64 points:
//   - ENU(A) -> ECEF -> Helmert -> ENU(B): geoanchor's fused path (in place)
//     and PROJ's proj_trans_generic on the equivalent pipeline, with the
//     largest difference between them in metres;
//   - the same chain ending in geodetic coordinates, against PROJ's
//     "... +inv +proj=cart" pipeline;
//   - the memory-bandwidth ceiling: an in-place pass over the same three
//     arrays (same bytes read and written as the fused path) and a plain
//     copy of them;
//   - LAS end to end (file in the page cache): read -> decode -> transform ->
//     encode -> write, one tile on one thread and two tiles on two threads;
//   - a LAS tile in a CRS PROJ moves (Lambert-93 -> LAEA Europe, as `apply
//     --to-crs` runs it: one CrsOperation per tile, proj_trans_generic over
//     each chunk) against PROJ's proj_trans_generic on the same points;
//   - LAZ (issue 15): a realistic tile of kLazPoints (scan lines, returns,
//     GPS time, RGB; tests/support/laz_records.hpp) as LAZ and as LAS:
//     LAZ -> transform -> LAZ and LAS -> transform -> LAS, one tile on one
//     thread and on two (its chunks on both), geoanchor's decompression
//     alone, and laz-perf's (npm, the LASzip codec as WebAssembly) in a
//     Node child process (tests/las-verify/laz-speed.mjs, timed inside the
//     script; the child's whole wall time printed too).
// Prints Google Benchmark's medians (≥ 5 repetitions), then a table of
// points/s and ratios. Never part of the test run's pass/fail.

#include <benchmark/benchmark.h>
#include <nlohmann/json.hpp>
#include <proj.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "geoanchor/crs/crs.hpp"
#include "geoanchor/crs/crs_operation.hpp"
#include "geoanchor/las/las.hpp"
#include "geoanchor/io/tile/point_chain.hpp"
#include "geoanchor/io/tile/tile_apply.hpp"
#include "accuracy.hpp"
#include "bench_process.hpp"
#include "laz_records.hpp"
#include "median_reporter.hpp"

namespace {

using namespace geoanchor;
namespace fs = std::filesystem;

constexpr std::size_t kPoints = 10'000'000;
constexpr std::size_t kLasPoints = 10'000'000;

const char* kHelmert = R"J({"model": "helmert7", "convention": "position_vector",
  "parameters": {"tx_m": 0.0547, "ty_m": 0.0522, "tz_m": -0.0741, "rx_arcsec": 0.00228, "ry_arcsec": 0.01404,
                 "rz_arcsec": -0.02168, "ds_ppm": 0.00212}})J";
const char* kProjChain =
    "+proj=pipeline +step +inv +proj=topocentric +ellps=GRS80 +lat_0=47.464722 +lon_0=8.549167 +h_0=480 "
    "+step +proj=helmert +x=0.0547 +y=0.0522 +z=-0.0741 +rx=0.00228 +ry=0.01404 +rz=-0.02168 +s=0.00212 "
    "+convention=position_vector ";
const std::string kProjToB = "+step +proj=topocentric +ellps=GRS80 +lat_0=47.2597 +lon_0=11.3439 +h_0=581";
const std::string kProjToGeodetic = "+step +inv +proj=cart +ellps=GRS80";

geodesy::LocalOrigin origin(double lat, double lon, double h) {
  return {{geodesy::Angle::degrees(lat), geodesy::Angle::degrees(lon), geodesy::EllipsoidalHeight{h}},
          geodesy::Ellipsoid::grs80()};
}
io::ArrayFrame enu(const geodesy::LocalOrigin& o) {
  return {io::CoordinateKind::enu, geodesy::Ellipsoid::grs80(), o, std::nullopt};
}
const io::ArrayFrame kA = enu(origin(47.464722, 8.549167, 480.0));
const io::ArrayFrame kB = enu(origin(47.2597, 11.3439, 581.0));
const io::ArrayFrame kGeodetic{io::CoordinateKind::geodetic, geodesy::Ellipsoid::grs80(), std::nullopt, std::nullopt};

struct Arrays {
  std::vector<double> e, n, u;
  Arrays() : e(kPoints), n(kPoints), u(kPoints) {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> h(-3000.0, 3000.0), v(-30.0, 80.0);
    for (std::size_t i = 0; i < kPoints; ++i) e[i] = h(rng), n[i] = h(rng), u[i] = v(rng);
  }
};
const Arrays& source() {
  static const Arrays a;
  return a;
}
// Work buffers, reused so that no iteration pays for page faults.
struct Work {
  std::vector<double> a, b, c, d, f, g;
  Work() : a(kPoints), b(kPoints), c(kPoints), d(kPoints), f(kPoints), g(kPoints) {}
  void load() {
    std::memcpy(a.data(), source().e.data(), kPoints * 8);
    std::memcpy(b.data(), source().n.data(), kPoints * 8);
    std::memcpy(c.data(), source().u.data(), kPoints * 8);
  }
};
Work& work() {
  static Work w;
  return w;
}

const io::PointChain& chain_to_b() {
  static const io::PointChain c(kA, io::parse_transform_json(kHelmert, "bench"), false, std::nullopt, kB);
  return c;
}
const io::PointChain& chain_to_geodetic() {
  static const io::PointChain c(kA, io::parse_transform_json(kHelmert, "bench"), false, std::nullopt, kGeodetic);
  return c;
}

// See tests/support/proj_reference.cpp: PROJ 9.1.1's topocentric step
// leaves the time coordinate uninitialised for the next step; zeroing the
// stack first keeps its garbage from turning a static Helmert into NaN.
[[gnu::noinline]] void scrub_stack() {
  volatile unsigned char buf[16384];
  for (std::size_t i = 0; i < sizeof buf; ++i) buf[i] = 0;
}

struct Proj {
  PJ_CONTEXT* ctx = proj_context_create();
  PJ* pj = nullptr;
  // Probe the ENU origin, and build the pipeline again should PROJ return
  // NaN for it without an error, saying so.
  explicit Proj(const std::string& def) {
    for (int attempt = 0; attempt < 10; ++attempt) {
      pj = proj_create(ctx, def.c_str());
      scrub_stack();
      PJ_COORD c = proj_trans(pj, PJ_FWD, proj_coord(0, 0, 0, 0));
      if (std::isfinite(c.xyz.x)) return;
      std::fprintf(stderr, "note: PROJ returned NaN for a valid point; pipeline rebuilt (attempt %d)\n", attempt + 1);
      proj_destroy(pj);
    }
    pj = proj_create(ctx, def.c_str());
  }
  ~Proj() {
    proj_destroy(pj);
    proj_context_destroy(ctx);
  }
  // With an explicit time of 0 for every point.
  void run(std::vector<double>& x, std::vector<double>& y, std::vector<double>& z) const {
    double t = 0.0;
    scrub_stack();
    proj_trans_generic(pj, PJ_FWD, x.data(), sizeof(double), x.size(), y.data(), sizeof(double), y.size(), z.data(),
                       sizeof(double), z.size(), &t, 0, 1);
  }
};

void set_points(benchmark::State& state, std::size_t n) {
  state.SetItemsProcessed(state.iterations() * static_cast<benchmark::IterationCount>(n));
}

// Times `transform` on the three arrays, reloaded (untimed) before each run.
template <class Transform>
void time_in_place(benchmark::State& state, Transform&& transform) {
  Work& w = work();
  for (auto _ : state) {
    state.PauseTiming();
    w.load();
    state.ResumeTiming();
    transform(w.a, w.b, w.c);
    benchmark::ClobberMemory();
  }
  set_points(state, kPoints);
}

void fused_enu_to_enu(benchmark::State& state) {
  time_in_place(state, [](auto& a, auto& b, auto& c) { chain_to_b().apply(a, b, c); });
}

void proj_enu_to_enu(benchmark::State& state) {
  static const Proj proj(std::string(kProjChain) + kProjToB);
  time_in_place(state, [](auto& a, auto& b, auto& c) { proj.run(a, b, c); });
}

void fused_enu_to_geodetic(benchmark::State& state) {
  time_in_place(state, [](auto& a, auto& b, auto& c) { chain_to_geodetic().apply(a, b, c); });
}

void proj_enu_to_geodetic(benchmark::State& state) {
  static const Proj proj(std::string(kProjChain) + kProjToGeodetic);
  time_in_place(state, [](auto& a, auto& b, auto& c) { proj.run(a, b, c); });
}

// The ceiling for an in-place pass: the same three arrays read and written.
void stream_in_place(benchmark::State& state) {
  time_in_place(state, [](std::vector<double>& a, std::vector<double>& b, std::vector<double>& c) {
    for (std::size_t i = 0; i < kPoints; ++i) {
      a[i] = a[i] * 1.0000001 + 0.5;
      b[i] = b[i] * 1.0000001 + 0.5;
      c[i] = c[i] * 1.0000001 + 0.5;
    }
  });
}

// A plain copy of the same bytes into other (already touched) buffers.
void stream_copy(benchmark::State& state) {
  Work& w = work();
  w.load();
  std::fill(w.d.begin(), w.d.end(), 0.0);
  std::fill(w.f.begin(), w.f.end(), 0.0);
  std::fill(w.g.begin(), w.g.end(), 0.0);
  for (auto _ : state) {
    std::memcpy(w.d.data(), w.a.data(), kPoints * 8);
    std::memcpy(w.f.data(), w.b.data(), kPoints * 8);
    std::memcpy(w.g.data(), w.c.data(), kPoints * 8);
    benchmark::ClobberMemory();
  }
  set_points(state, kPoints);
}

// ---------------------------------------------------------------- LAS

// A folder of this run's own (mkdtemp: two runs at once, e.g. from two
// worktrees, must not write each other's tiles), removed at exit.
fs::path las_dir() {
  struct Folder {
    fs::path p;
    Folder() {
      std::string templ = (fs::temp_directory_path() / "geoanchor_apply_bench_XXXXXX").string();
      if (::mkdtemp(templ.data()) == nullptr) throw std::runtime_error("cannot create a folder from " + templ);
      p = templ;
    }
    ~Folder() {
      std::error_code ignored;
      fs::remove_all(p, ignored);
    }
  };
  static const Folder d;
  return d.p;
}

// A LAS 1.4 point format 6 tile of kLasPoints, ±3 km around `offset`
// horizontally, 1 mm steps, made once.
fs::path make_tile(const std::string& name, const std::array<double, 3>& offset, unsigned seed) {
  const fs::path p = las_dir() / (name + ".las");
  if (fs::exists(p) && fs::file_size(p) == 375 + kLasPoints * 30) return p;
  io::LasHeader h;
  h.point_format = 6;
  h.record_length = 30;
  h.global_encoding = 1;
  h.offset = offset;
  std::ofstream out(p, std::ios::binary);
  io::LasWriter w(out, h, {}, {}, p.string());
  std::vector<std::uint8_t> rec(30 * 65536);
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::int32_t> hq(-3000000, 3000000), vq(-30000, 80000);
  std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (std::size_t done = 0; done < kLasPoints;) {
    const std::size_t n = std::min<std::size_t>(65536, kLasPoints - done);
    for (std::size_t i = 0; i < n; ++i) {
      const std::int32_t q[3] = {hq(rng), hq(rng), vq(rng)};
      std::memcpy(&rec[i * 30], q, 12);
      for (std::size_t b = 12; b < 30; ++b) rec[i * 30 + b] = static_cast<std::uint8_t>(i + b);
      for (std::size_t k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], q[k] * 0.001 + offset[k]);
        hi[k] = std::max(hi[k], q[k] * 0.001 + offset[k]);
      }
    }
    w.write_records(rec.data(), n);
    done += n;
  }
  std::array<std::uint64_t, 15> by_return{};
  by_return[0] = kLasPoints;
  w.finish(by_return, lo, hi);
  return p;
}

// In ENU at A.
fs::path las_tile(int k) { return make_tile("tile" + std::to_string(k), {0.0, 0.0, 0.0}, static_cast<unsigned>(k)); }

void las_tile_to(int k, const fs::path& out_path) {
  std::ofstream out(out_path, std::ios::binary);
  io::TileApplyOptions o{kA, kB, std::nullopt, "WKT", 1 << 16, {}};
  io::apply_las_tile(las_tile(k), out, out_path.string(), chain_to_b(), o);
}

// Each run writes a new file, as apply does (a temporary renamed into
// place): removing the previous output is not timed.
void remove_outputs() {
  fs::remove(las_dir() / "out0.las");
  fs::remove(las_dir() / "out1.las");
}

void las_end_to_end(benchmark::State& state) {
  las_tile(0);
  for (auto _ : state) {
    state.PauseTiming();
    remove_outputs();
    state.ResumeTiming();
    las_tile_to(0, las_dir() / "out0.las");
  }
  set_points(state, kLasPoints);
}

void las_end_to_end_two_jobs(benchmark::State& state) {
  las_tile(0);
  las_tile(1);
  for (auto _ : state) {
    state.PauseTiming();
    remove_outputs();
    state.ResumeTiming();
    std::thread t([] { las_tile_to(1, las_dir() / "out1.las"); });
    las_tile_to(0, las_dir() / "out0.las");
    t.join();
  }
  set_points(state, 2 * kLasPoints);
}

// ---------------------------------------------------------------- LAS through PROJ

constexpr char kLambert93[] = "EPSG:2154";
constexpr char kLaea[] = "EPSG:3035";

// In Lambert-93 (promoted to 3-D), around Paris.
constexpr std::array<double, 3> kParisLambert93{652000.0, 6862000.0, 0.0};
constexpr unsigned kLambertSeed = 7;
fs::path lambert_tile() { return make_tile("lambert93", kParisLambert93, kLambertSeed); }

void las_crs_end_to_end(benchmark::State& state) {
  const fs::path in = lambert_tile();
  const io::Crs src = io::Crs::parse(kLambert93, "bench").promoted_to_3d("bench");
  const io::Crs dst = io::Crs::parse(kLaea, "bench").promoted_to_3d("bench");
  for (auto _ : state) {
    state.PauseTiming();
    fs::remove(las_dir() / "out_crs.las");
    state.ResumeTiming();
    io::CrsOperation op(src, dst, "bench");  // per tile, as apply makes it
    io::TileApplyOptions o{io::ArrayFrame{}, io::ArrayFrame{}, std::nullopt, "WKT", 1 << 16, {}};
    o.crs_before = &op;
    o.chain_used = false;
    o.file_in = io::TileCrsAxes{};
    o.file_out = io::TileCrsAxes{};
    const io::PointChain identity(io::ArrayFrame{}, std::nullopt, false, std::nullopt, io::ArrayFrame{});
    std::ofstream out(las_dir() / "out_crs.las", std::ios::binary);
    io::apply_las_tile(in, out, (las_dir() / "out_crs.las").string(), identity, o);
  }
  set_points(state, kLasPoints);
}

// PROJ alone on the same points: decoded arrays through proj_trans_generic.
void proj_crs_kernel(benchmark::State& state) {
  PJ_CONTEXT* ctx = proj_context_create();
  PJ* raw = proj_create_crs_to_crs(ctx, kLambert93, kLaea, nullptr);
  PJ* op = proj_normalize_for_visualization(ctx, raw);
  std::vector<double> x(kLasPoints), y(kLasPoints), z(kLasPoints);
  std::mt19937_64 rng(kLambertSeed);
  std::uniform_int_distribution<std::int32_t> hq(-3000000, 3000000), vq(-30000, 80000);
  for (std::size_t i = 0; i < kLasPoints; ++i) {
    x[i] = hq(rng) * 0.001 + kParisLambert93[0];
    y[i] = hq(rng) * 0.001 + kParisLambert93[1];
    z[i] = vq(rng) * 0.001;
  }
  for (auto _ : state) {
    state.PauseTiming();
    std::vector<double> a = x, b = y, c = z;
    state.ResumeTiming();
    proj_trans_generic(op, PJ_FWD, a.data(), 8, kLasPoints, b.data(), 8, kLasPoints, c.data(), 8, kLasPoints, nullptr, 0, 0);
    benchmark::DoNotOptimize(a.data());
  }
  proj_destroy(op);
  proj_destroy(raw);
  proj_context_destroy(ctx);
  set_points(state, kLasPoints);
}

// ---------------------------------------------------------------- LAZ

constexpr std::size_t kLazPoints = 3'000'000;
const fs::path kLasVerify = fs::path(__FILE__).parent_path().parent_path() / "tests" / "las-verify";

// The same realistic tile (point format 7, ENU at A) as LAS and as LAZ
// (chunks of 50 000 points, as LASzip writes them), made once.
struct RealisticTile {
  fs::path las, laz;
  std::uint64_t las_bytes = 0, laz_bytes = 0;
};
const RealisticTile& realistic_tile() {
  static const RealisticTile t = [] {
    RealisticTile r{las_dir() / "realistic.las", las_dir() / "realistic.laz"};
    const auto records = testing::make_records(7, 0, kLazPoints, testing::Content::realistic, 17);
    io::LasHeader h;
    h.point_format = 7;
    h.record_length = 36;
    h.global_encoding = 1;
    h.offset = {-1000.0, -2000.0, -400.0};  // the generator's scan lines start near (1000, 2000, 480) m
    std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    testing::widen_record_bounds(records.data(), kLazPoints, 36, h.offset, lo, hi);
    for (const bool laz : {false, true}) {
      std::ofstream out(laz ? r.laz : r.las, std::ios::binary | std::ios::trunc);
      io::LasWriter w(out, h, {}, {}, "bench", {laz, io::kLazDefaultChunkPoints});
      w.write_records(records.data(), kLazPoints);
      std::array<std::uint64_t, 15> by_return{};
      by_return[0] = kLazPoints;
      w.finish(by_return, lo, hi);
    }
    r.las_bytes = fs::file_size(r.las);
    r.laz_bytes = fs::file_size(r.laz);
    return r;
  }();
  return t;
}

// One tile through ENU(A) -> Helmert -> ENU(B) on `threads`, written as `f`.
void realistic_to(const fs::path& in, io::TileFormat f, unsigned threads) {
  const fs::path out_path = las_dir() / (f == io::TileFormat::laz ? "out_realistic.laz" : "out_realistic.las");
  fs::remove(out_path);
  std::ofstream out(out_path, std::ios::binary);
  io::TileApplyOptions o{kA, kB, std::nullopt, "WKT", 1 << 16, {}};
  o.las_output = f;
  o.threads = threads;
  io::apply_las_tile(in, out, out_path.string(), chain_to_b(), o);
}

// LAZ -> transform -> LAZ on state.range(0) threads.
void laz_end_to_end(benchmark::State& state) {
  const auto& t = realistic_tile();
  for (auto _ : state) realistic_to(t.laz, io::TileFormat::laz, static_cast<unsigned>(state.range(0)));
  set_points(state, kLazPoints);
}

// LAS -> transform -> LAS on the same tile.
void las_realistic_end_to_end(benchmark::State& state) {
  const auto& t = realistic_tile();
  for (auto _ : state) realistic_to(t.las, io::TileFormat::las, static_cast<unsigned>(state.range(0)));
  set_points(state, kLazPoints);
}

// Decompression alone, every chunk on this thread.
void laz_decode_only(benchmark::State& state) {
  const auto& t = realistic_tile();
  std::vector<std::uint8_t> records;
  for (auto _ : state) {
    const io::LasReader r(t.laz);
    for (std::size_t i = 0; i < r.chunk_count(); ++i) r.decode_chunk(i, records);
    benchmark::DoNotOptimize(records.data());
  }
  set_points(state, kLazPoints);
}

// node on the PATH, or empty.
std::string find_node() {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/bin";
  for (std::size_t at = 0; at <= dirs.size();) {
    const std::size_t colon = std::min(dirs.find(':', at), dirs.size());
    const fs::path candidate = fs::path(dirs.substr(at, colon - at)) / "node";
    if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
    at = colon + 1;
  }
  return "";
}

// laz-perf's decompression of the same file in a Node child process: the
// time its script measures around the decoding loop (manual time), and the
// child's whole wall time (start-up included) kept for the table.
std::vector<double> laz_perf_wall_s;
void laz_perf_decode(benchmark::State& state) {
  const auto& t = realistic_tile();
  const std::string node = find_node();
  if (node.empty() || !fs::exists(kLasVerify / "node_modules" / "laz-perf")) {
    state.SkipWithError("node or laz-perf missing: run npm ci --prefix tests/las-verify");
    return;
  }
  for (auto _ : state) {
    const bench::Run run = bench::run_command({node, (kLasVerify / "laz-speed.mjs").string(), t.laz.string(), "1"},
                                              las_dir(), "laz_perf.json");
    std::ifstream in(las_dir() / "laz_perf.json");
    nlohmann::json report;
    try {
      report = nlohmann::json::parse(in);
    } catch (const nlohmann::json::exception&) {
      state.SkipWithError("laz-speed.mjs printed no JSON");
      return;
    }
    if (run.status != 0 || report.value("count", 0) != static_cast<int>(kLazPoints)) {
      state.SkipWithError("laz-perf did not read the tile");
      return;
    }
    state.SetIterationTime(report["seconds"][0].get<double>());
    laz_perf_wall_s.push_back(run.seconds);
  }
  set_points(state, kLazPoints);
}

#define GEOANCHOR_BENCH(f) \
  BENCHMARK(f)->Repetitions(5)->ReportAggregatesOnly(true)->Unit(benchmark::kMillisecond)->UseRealTime()
GEOANCHOR_BENCH(fused_enu_to_enu);
GEOANCHOR_BENCH(proj_enu_to_enu)->Iterations(1);
GEOANCHOR_BENCH(fused_enu_to_geodetic);
GEOANCHOR_BENCH(proj_enu_to_geodetic)->Iterations(1);
GEOANCHOR_BENCH(stream_in_place);
GEOANCHOR_BENCH(stream_copy);
GEOANCHOR_BENCH(las_end_to_end)->Iterations(1);
GEOANCHOR_BENCH(las_end_to_end_two_jobs)->Iterations(1);
GEOANCHOR_BENCH(las_crs_end_to_end)->Iterations(1);
GEOANCHOR_BENCH(proj_crs_kernel)->Iterations(1);
GEOANCHOR_BENCH(laz_end_to_end)->Arg(1)->Arg(2)->Iterations(1);
GEOANCHOR_BENCH(las_realistic_end_to_end)->Arg(1)->Arg(2)->Iterations(1);
GEOANCHOR_BENCH(laz_decode_only)->Iterations(1);
BENCHMARK(laz_perf_decode)->Repetitions(5)->ReportAggregatesOnly(true)->Unit(benchmark::kMillisecond)->UseManualTime()->Iterations(1);

// The largest difference between the fused path and PROJ on one chain.
double max_difference_m(const io::PointChain& chain, const std::string& proj_def, bool geodetic) {
  Work& w = work();
  w.load();
  chain.apply(w.a, w.b, w.c);
  std::vector<double> x = source().e, y = source().n, z = source().u;
  Proj(proj_def).run(x, y, z);
  // NaN on either side is reported as NaN, never dropped (tests/support/accuracy.hpp).
  geoanchor::testing::WorstCase worst;
  constexpr double kMetresPerRadian = 6378137.0;
  for (std::size_t i = 0; i < kPoints; ++i) {
    if (geodetic) {  // ours: lat, lon (degrees); PROJ's: lon, lat (radians)
      worst.add(std::abs(proj_torad(w.a[i]) - y[i]) * kMetresPerRadian, i);
      worst.add(std::abs(proj_torad(w.b[i]) - x[i]) * kMetresPerRadian, i);
    } else {
      worst.add(std::abs(w.a[i] - x[i]), i);
      worst.add(std::abs(w.b[i] - y[i]), i);
    }
    worst.add(std::abs(w.c[i] - z[i]), i);
  }
  if (worst.nan_count() > 0) std::printf("  geoanchor vs PROJ: %s\n", worst.describe().c_str());
  return worst.value();
}

void print_table(const bench::MedianReporter& r) {
  // NaN (printed as "nan", never a plausible number) for a benchmark that did not run.
  auto mpts = [&](const char* name, std::size_t n) {
    const double s = r.median_s(name);
    return s > 0 ? static_cast<double>(n) / s / 1e6 : std::nan("");
  };
  const double fused = mpts("fused_enu_to_enu", kPoints), proj = mpts("proj_enu_to_enu", kPoints);
  const double fused_geo = mpts("fused_enu_to_geodetic", kPoints), proj_geo = mpts("proj_enu_to_geodetic", kPoints);
  const double in_place = mpts("stream_in_place", kPoints), copy = mpts("stream_copy", kPoints);
  const double las1 = mpts("las_end_to_end", kLasPoints), las2 = mpts("las_end_to_end_two_jobs", 2 * kLasPoints);
  const double las_crs = mpts("las_crs_end_to_end", kLasPoints), proj_crs = mpts("proj_crs_kernel", kLasPoints);
  std::printf("\n%zu float64 points, medians, million points per second\n", kPoints);
  std::printf("  %-52s %10s %10s\n", "path", "M pts/s", "ratio");
  std::printf("  %-52s %10.1f\n", "ENU(A)->ECEF->Helmert->ENU(B), PROJ proj_trans_generic", proj);
  std::printf("  %-52s %10.1f %9.1fx PROJ\n", "ENU(A)->ECEF->Helmert->ENU(B), geoanchor fused", fused, fused / proj);
  std::printf("  %-52s %10.1f %9.2f of in-place ceiling\n", "", fused, fused / in_place);
  std::printf("  %-52s %10.1f\n", "same chain to geodetic, PROJ (+inv +proj=cart)", proj_geo);
  std::printf("  %-52s %10.1f %9.1fx PROJ\n", "same chain to geodetic, geoanchor", fused_geo, fused_geo / proj_geo);
  std::printf("  %-52s %10.1f\n", "ceiling: in-place pass over the same arrays", in_place);
  std::printf("  %-52s %10.1f\n", "ceiling: plain copy of the same bytes", copy);
  std::printf("  %-52s %10.1f\n", "LAS read->transform->write, 1 tile, 1 thread", las1);
  std::printf("  %-52s %10.1f %9.2fx one job\n", "LAS read->transform->write, 2 tiles, 2 threads", las2, las2 / las1);
  std::printf("  %-52s %10.1f\n", "Lambert-93 -> LAEA, PROJ proj_trans_generic (kernel)", proj_crs);
  std::printf("  %-52s %10.1f %9.2fx PROJ kernel\n", "Lambert-93 -> LAEA, LAS tile through apply's PROJ stage", las_crs,
              las_crs / proj_crs);
  const double laz1 = mpts("laz_end_to_end/1", kLazPoints), laz2 = mpts("laz_end_to_end/2", kLazPoints);
  const double lasr1 = mpts("las_realistic_end_to_end/1", kLazPoints), lasr2 = mpts("las_realistic_end_to_end/2", kLazPoints);
  const double decode = mpts("laz_decode_only", kLazPoints), lazperf = mpts("laz_perf_decode", kLazPoints);
  std::printf("\n%zu-point realistic tile (format 7): LAS %.1f MB, LAZ %.1f MB (%.1f %%)\n", kLazPoints,
              static_cast<double>(realistic_tile().las_bytes) / 1e6, static_cast<double>(realistic_tile().laz_bytes) / 1e6,
              100.0 * static_cast<double>(realistic_tile().laz_bytes) / static_cast<double>(realistic_tile().las_bytes));
  std::printf("  %-52s %10s %10s\n", "path", "M pts/s", "ratio");
  std::printf("  %-52s %10.2f\n", "LAS read->transform->write, 1 thread", lasr1);
  std::printf("  %-52s %10.2f %9.2fx one thread\n", "LAS read->transform->write, 2 threads", lasr2, lasr2 / lasr1);
  std::printf("  %-52s %10.2f %9.2fx LAS\n", "LAZ read->transform->write, 1 thread", laz1, laz1 / lasr1);
  std::printf("  %-52s %10.2f %9.2fx one thread\n", "LAZ read->transform->write, 2 threads", laz2, laz2 / laz1);
  std::printf("  %-52s %10.2f %9.2fx LAS (2 threads each)\n", "", laz2, laz2 / lasr2);
  std::printf("  %-52s %10.2f\n", "LAZ decompression alone (geoanchor, 1 thread)", decode);
  std::printf("  %-52s %10.2f %9.2fx geoanchor's\n", "LAZ decompression, laz-perf (WebAssembly, Node)", lazperf,
              lazperf / decode);
  std::printf("  %-52s %10s %9.2fx laz-perf decoding\n", "LAZ->transform->LAZ, 1 thread", "", laz1 / lazperf);
  std::printf("  %-52s %10s %9.2fx laz-perf decoding\n", "LAZ->transform->LAZ, 2 threads", "", laz2 / lazperf);
  if (!laz_perf_wall_s.empty()) {
    std::printf("  laz-perf child process, whole wall time (Node start-up, WebAssembly, file read): median %.2f s\n",
                bench::median(laz_perf_wall_s));
  }
  const double diff_enu = max_difference_m(chain_to_b(), std::string(kProjChain) + kProjToB, false);
  const double diff_geodetic = max_difference_m(chain_to_geodetic(), std::string(kProjChain) + kProjToGeodetic, true);
  std::printf("  max |geoanchor - PROJ|: ENU(B) %.2e m, geodetic %.2e m\n", diff_enu, diff_geodetic);
}

}  // namespace

int main(int argc, char** argv) { return geoanchor::bench::run_and_tabulate(argc, argv, print_table); }
