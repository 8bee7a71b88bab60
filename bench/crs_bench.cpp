// Issue 13 point 8: chains through PROJ against PROJ's own throughput on the
// same operation, and the whole `geoanchor convert --crs --to-crs` command
// against PROJ's cs2cs on the same rows and a plain copy of the same bytes.
//
//  kernel:  io::CrsOperation::transform over 10^6 points, in the 4096-row
//           batches convert uses, vs proj_trans_generic over the whole
//           arrays with proj_create_crs_to_crs (normalised for
//           visualisation) on the same pair: median of 7, ratio.
//  command: geoanchor convert IN.csv --crs A --to-crs B -o OUT.csv vs
//           cs2cs A B < IN.txt > OUT.txt (the same points, PROJ's text
//           format) vs cat IN.csv > COPY: median wall time of 3.
// Never part of the test run's pass/fail.

#include <fcntl.h>
#include <proj.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "geoanchor/crs/crs.hpp"
#include "geoanchor/crs/crs_operation.hpp"

extern char** environ;

namespace {

namespace fs = std::filesystem;

constexpr std::size_t kPoints = 1000000;
constexpr std::size_t kBatch = 4096;  // convert's batch (io/src/control/crs_csv.cpp)
constexpr int kKernelRepeats = 11;
constexpr int kCommandRepeats = 3;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

template <class F>
double seconds(F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct Pair {
  const char* from;
  const char* to;
  const char* from_columns;  // CSV header of the input's coordinates, in the order written
  bool lonlat_first_in_file;  // false: lat, lon (geoanchor's order); true: easting, northing
  const char* what;
};

// Points inside both CRSs' areas of use (the smaller of the two boxes), in
// the source CRS's coordinates, visualisation order.
void make_points(const char* crs, const char* other_crs, std::vector<double>& a, std::vector<double>& b) {
  PJ_CONTEXT* ctx = proj_context_create();
  PJ* c = proj_create(ctx, crs);
  PJ* other = proj_create(ctx, other_crs);
  double w = 0, s = 0, e = 0, n = 0, w2 = 0, s2 = 0, e2 = 0, n2 = 0;
  proj_get_area_of_use(ctx, c, &w, &s, &e, &n, nullptr);
  proj_get_area_of_use(ctx, other, &w2, &s2, &e2, &n2, nullptr);
  if ((e2 - w2) * (n2 - s2) < (e - w) * (n - s)) w = w2, s = s2, e = e2, n = n2;
  proj_destroy(other);
  const char* opts[] = {"ALLOW_BALLPARK=YES", nullptr};
  PJ* geog = proj_create(ctx, "OGC:CRS84");
  PJ* raw = proj_create_crs_to_crs_from_pj(ctx, geog, c, nullptr, opts);
  PJ* op = proj_normalize_for_visualization(ctx, raw);
  std::mt19937_64 rng(42);
  const double dw = 0.2 * (e - w), dn = 0.2 * (n - s);
  std::uniform_real_distribution<double> lon(w + dw, e - dw), lat(s + dn, n - dn);
  a.resize(kPoints);
  b.resize(kPoints);
  for (std::size_t i = 0; i < kPoints; ++i) {
    a[i] = lon(rng);
    b[i] = lat(rng);
  }
  proj_trans_generic(op, PJ_FWD, a.data(), sizeof(double), kPoints, b.data(), sizeof(double), kPoints, nullptr, 0, 0,
                     nullptr, 0, 0);
  proj_destroy(op);
  proj_destroy(raw);
  proj_destroy(geog);
  proj_destroy(c);
  proj_context_destroy(ctx);
}

double run_command(const std::vector<std::string>& args, const std::string& in, const std::string& out) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (!in.empty()) posix_spawn_file_actions_addopen(&actions, 0, in.c_str(), O_RDONLY, 0);
  if (!out.empty()) posix_spawn_file_actions_addopen(&actions, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  int status = 0;
  const double s = seconds([&] {
    if (posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), environ) != 0) {
      std::fprintf(stderr, "cannot run %s\n", argv[0]);
      std::exit(1);
    }
    waitpid(pid, &status, 0);
  });
  posix_spawn_file_actions_destroy(&actions);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::fprintf(stderr, "%s exited with %d\n", argv[0], WEXITSTATUS(status));
    std::exit(1);
  }
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string exe = argc > 1 ? argv[1] : GEOANCHOR_EXE;
  const std::vector<Pair> pairs = {
      {"EPSG:4326", "EPSG:32632", "lat_deg,lon_deg", false, "WGS 84 -> UTM 32N (one conversion)"},
      {"EPSG:2236", "EPSG:4269", "easting_ftus,northing_ftus", true, "Florida East ftUS -> NAD83 (inverse TM, feet)"},
      {"EPSG:2154", "EPSG:3035", "easting_m,northing_m", true, "Lambert-93 -> LAEA Europe (projected to projected)"},
      {"EPSG:4283", "EPSG:7844", "lat_deg,lon_deg", false, "GDA94 -> GDA2020 (Helmert; 5 candidates, chosen per point)"},
  };
  std::printf("geoanchor CRS operations through PROJ %s, %zu points\n\n", proj_info().version, kPoints);
  std::printf("%-58s %12s %12s %8s\n", "kernel (medians of 11, in turn)", "PROJ ns/pt", "geoanchor", "ratio");
  for (const auto& p : pairs) {
    std::vector<double> a0, b0;
    make_points(p.from, p.to, a0, b0);
    // PROJ alone.
    PJ_CONTEXT* ctx = proj_context_create();
    PJ* src = proj_create(ctx, p.from);
    PJ* dst = proj_create(ctx, p.to);
    PJ* raw = proj_create_crs_to_crs_from_pj(ctx, src, dst, nullptr, nullptr);
    PJ* op = proj_normalize_for_visualization(ctx, raw);
    std::vector<double> proj_s, ours_s, ratios;
    // geoanchor, as convert drives it.
    const auto from = geoanchor::io::Crs::parse(p.from, "bench");
    const auto to = geoanchor::io::Crs::parse(p.to, "bench");
    geoanchor::io::CrsOperation ours(from, to, "bench");
    // PROJ and geoanchor in turn, so that a slower moment of the machine
    // falls on both: the ratio is the median of each pair's.
    for (int r = 0; r < kKernelRepeats; ++r) {
      std::vector<double> a = a0, b = b0;
      proj_s.push_back(seconds([&] {
        proj_trans_generic(op, PJ_FWD, a.data(), sizeof(double), kPoints, b.data(), sizeof(double), kPoints, nullptr, 0,
                           0, nullptr, 0, 0);
      }));
      a = a0, b = b0;
      ours_s.push_back(seconds([&] {
        for (std::size_t i = 0; i < kPoints; i += kBatch) {
          const std::size_t n = std::min(kBatch, kPoints - i);
          ours.transform(a.data() + i, b.data() + i, nullptr, n, [](std::size_t k) { return std::to_string(k); });
        }
      }));
      ratios.push_back(ours_s.back() / proj_s.back());
    }
    const double ps = median(proj_s), os = median(ours_s);
    std::printf("%-58s %12.1f %12.1f %8.2f\n", p.what, ps / kPoints * 1e9, os / kPoints * 1e9, median(ratios));
    proj_destroy(op);
    proj_destroy(raw);
    proj_destroy(dst);
    proj_destroy(src);
    proj_context_destroy(ctx);
  }

  // The whole command on a 10^6-row file.
  const fs::path dir = fs::temp_directory_path() / ("geoanchor_crs_bench_" + std::to_string(getpid()));
  fs::create_directories(dir);
  std::printf("\n%-58s %10s %10s %10s %8s %8s\n", "command (median of 3, s)", "geoanchor", "cs2cs", "cat", "vs cs2cs",
              "vs cat");
  for (const auto& p : pairs) {
    std::vector<double> a, b;
    make_points(p.from, p.to, a, b);
    const std::string csv = (dir / "in.csv").string(), txt = (dir / "in.txt").string();
    {
      std::ofstream c(csv), t(txt);
      c << "id," << p.from_columns << "\n";
      char line[128];
      for (std::size_t i = 0; i < kPoints; ++i) {
        // The file holds (lat, lon) or (easting, northing); cs2cs reads the CRS's own axis order.
        const double first = p.lonlat_first_in_file ? a[i] : b[i], second = p.lonlat_first_in_file ? b[i] : a[i];
        std::snprintf(line, sizeof line, "P%zu,%.10f,%.10f\n", i, first, second);
        c << line;
        std::snprintf(line, sizeof line, "%.10f %.10f\n", first, second);
        t << line;
      }
    }
    std::vector<double> g, c2, cp;
    for (int r = 0; r < kCommandRepeats; ++r) {
      fs::remove(dir / "out.csv");
      fs::remove(dir / "out.csv.geoanchor.json");
      g.push_back(run_command({exe, "convert", csv, "--crs", p.from, "--to-crs", p.to, "-o", (dir / "out.csv").string()},
                              "", ""));
      c2.push_back(run_command({"cs2cs", "-f", "%.10f", p.from, p.to}, txt, (dir / "out.txt").string()));
      cp.push_back(run_command({"cat", csv}, "", (dir / "copy.csv").string()));
    }
    const double gs = median(g), cs = median(c2), ks = median(cp);
    std::printf("%-58s %10.3f %10.3f %10.3f %8.2f %8.1f\n", p.what, gs, cs, ks, gs / cs, gs / ks);
  }
  fs::remove_all(dir);
  std::printf("\nratio = geoanchor / reference (lower is faster); the kernel's target is <= 1.10 (issue 13 point 8)\n");
  return 0;
}
