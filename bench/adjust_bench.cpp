// The network adjustment at national scale (issue 14): generated GNSS
// networks of 10³, 10⁴ and 10⁵ stations (a jittered grid over 4° × 4°
// around 47°N 8°E, about five baselines per station, 3×3 covariances, one
// station held), adjusted with every station's covariance and every
// redundancy number (solver::adjust_network, no snooping). For each size,
// the median wall time and the peak memory of the adjustment (each run in
// its own child process, wait4's ru_maxrss), against a bare CHOLMOD
// analyze-factorize-solve of the same normal matrix (in ECEF axes: the
// adjustment's is in each station's east, north, up — the same matrix up to
// a block-diagonal rotation, the same pattern and fill) in the same run; and
// the whole `geoanchor adjust` command on the network as JSON (reading,
// adjusting, writing the stations CSV and the report). Never part of the
// test run's pass/fail.
//
//   geoanchor_adjust_bench [--sizes 1000,10000,100000] [--repetitions 3] [--command-max 10000]

#include <cholmod.h>
#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <numbers>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "bench_process.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/network.hpp"
#include "geoanchor/solver/network_adjustment.hpp"

namespace {

using namespace geoanchor;
using bench::median;
using bench::parse_sizes;
using bench::Run;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct Generated {
  geodesy::Network net;
  std::vector<Eigen::Vector3d> truth;
};

// A side × side jittered grid; baselines to the neighbours east, north,
// north-east, two east and two north (≈ 5 per station); each baseline's
// covariance 3 mm horizontal, 6 mm vertical at its first station, its
// value the truth plus that noise.
Generated make_network(std::size_t n) {
  Generated g;
  const std::size_t side = static_cast<std::size_t>(std::ceil(std::sqrt(static_cast<double>(n))));
  const double spacing_deg = 4.0 / static_cast<double>(side);
  std::mt19937_64 rng(n);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3), height(300.0, 1500.0);
  std::normal_distribution<double> unit(0.0, 1.0);
  const geodesy::GeocentricConverter conv(geodesy::Ellipsoid::grs80());
  g.net.frame = geodesy::Frame::parse("ITRF2014@2024.5", "bench");
  g.net.ellipsoid = geodesy::Ellipsoid::grs80();
  g.net.ellipsoid_stated = true;
  g.net.source_name = "generated";
  std::vector<Eigen::Matrix3d> enu_to_ecef;
  for (std::size_t i = 0; i < n; ++i) {
    const double lat = 45.0 + (static_cast<double>(i / side) + jitter(rng)) * spacing_deg;
    const double lon = 6.0 + (static_cast<double>(i % side) + jitter(rng)) * spacing_deg;
    const auto x = conv.ecef_from_geodetic({geodesy::Angle::degrees(lat), geodesy::Angle::degrees(lon), geodesy::EllipsoidalHeight{height(rng)}});
    g.truth.push_back(x.m);
    geodesy::NetworkStation s;
    s.id = "S" + std::to_string(i);
    s.position = x.m + Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * 0.05;  // a-priori 5 cm off
    if (i == 0) s.constraint.code = {'C', 'C', 'C'}, s.position = x.m;
    g.net.stations.push_back(s);
    const double la = lat * std::numbers::pi / 180.0, lo = lon * std::numbers::pi / 180.0;
    Eigen::Matrix3d r;
    r << -std::sin(lo), -std::sin(la) * std::cos(lo), std::cos(la) * std::cos(lo), std::cos(lo), -std::sin(la) * std::sin(lo),
        std::cos(la) * std::sin(lo), 0.0, std::cos(la), std::sin(la);
    enu_to_ecef.push_back(r);
  }
  const Eigen::Matrix3d enu_cov = Eigen::Vector3d(0.003 * 0.003, 0.003 * 0.003, 0.006 * 0.006).asDiagonal();
  auto add = [&](std::size_t a, std::size_t b) {
    geodesy::NetworkMeasurement m;
    m.kind = geodesy::MeasurementKind::gnss_baselines;
    m.stations = {a, b};
    const Eigen::Matrix3d c = enu_to_ecef[a] * enu_cov * enu_to_ecef[a].transpose();
    const Eigen::Matrix3d l = c.llt().matrixL();
    m.value = g.truth[b] - g.truth[a] + l * Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
    m.covariance = c;
    m.source = "baseline " + std::to_string(a) + "-" + std::to_string(b);
    g.net.measurements.push_back(std::move(m));
  };
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t row = i / side, col = i % side;
    if (col + 1 < side && i + 1 < n) add(i, i + 1);
    if (i + side < n) add(i, i + side);
    if (col + 1 < side && i + side + 1 < n) add(i, i + side + 1);
    if (col + 2 < side && i + 2 < n) add(i, i + 2);
    if (i + 2 * side < n) add(i, i + 2 * side);
    (void)row;
  }
  return g;
}

void write_json(const Generated& g, const fs::path& path) {
  const geodesy::GeocentricConverter conv(geodesy::Ellipsoid::grs80());
  std::ofstream out(path);
  out << "{\"schema\": \"geoanchor.network/1\", \"frame\": \"ITRF2014@2024.5\", \"stations\": [\n";
  char line[512];
  for (std::size_t i = 0; i < g.net.stations.size(); ++i) {
    const auto& s = g.net.stations[i];
    std::snprintf(line, sizeof line, "%s{\"id\": \"%s\", \"x_m\": %.4f, \"y_m\": %.4f, \"z_m\": %.4f%s}\n", i ? "," : "", s.id.c_str(),
                  s.position.x(), s.position.y(), s.position.z(), s.constraint.any() ? ", \"constraint\": \"CCC\"" : "");
    out << line;
  }
  out << "], \"measurements\": [\n";
  for (std::size_t k = 0; k < g.net.measurements.size(); ++k) {
    const auto& m = g.net.measurements[k];
    const auto& c = m.covariance;
    std::snprintf(line, sizeof line,
                  "%s{\"kind\": \"gnss_baseline\", \"from\": \"S%zu\", \"to\": \"S%zu\", \"dx_m\": %.5f, \"dy_m\": %.5f, \"dz_m\": %.5f, "
                  "\"cov_m2\": [[%.6e,%.6e,%.6e],[%.6e,%.6e,%.6e],[%.6e,%.6e,%.6e]]}\n",
                  k ? "," : "", m.stations[0], m.stations[1], m.value(0), m.value(1), m.value(2), c(0, 0), c(0, 1), c(0, 2), c(0, 1),
                  c(1, 1), c(1, 2), c(0, 2), c(1, 2), c(2, 2));
    out << line;
  }
  out << "]}\n";
}

// The bare baseline: N = Σ Aᵀ C⁻¹ A in ECEF (A = [−I I] per baseline), the
// held station's rows by a weight of 1e12, analyzed, factored, solved.
double bare_cholmod_seconds(const Generated& g) {
  const auto& net = g.net;
  const SuiteSparse_long n = static_cast<SuiteSparse_long>(3 * net.stations.size());
  cholmod_common common;
  cholmod_l_start(&common);
  common.print = 0;
  const auto t0 = Clock::now();
  cholmod_triplet* t = cholmod_l_allocate_triplet(static_cast<std::size_t>(n), static_cast<std::size_t>(n),
                                                  net.measurements.size() * 21 + 3, 1, CHOLMOD_REAL, &common);
  auto* ti = static_cast<SuiteSparse_long*>(t->i);
  auto* tj = static_cast<SuiteSparse_long*>(t->j);
  auto* tx = static_cast<double*>(t->x);
  std::size_t k = 0;
  auto put = [&](SuiteSparse_long r, SuiteSparse_long c, double v) {
    if (r > c) std::swap(r, c);
    ti[k] = r, tj[k] = c, tx[k] = v, ++k;
  };
  for (const auto& m : net.measurements) {
    const Eigen::Matrix3d w = m.covariance.inverse();
    const SuiteSparse_long a = static_cast<SuiteSparse_long>(3 * m.stations[0]), b = static_cast<SuiteSparse_long>(3 * m.stations[1]);
    for (int r = 0; r < 3; ++r) {
      for (int c = r; c < 3; ++c) {
        put(a + r, a + c, w(r, c));
        put(b + r, b + c, w(r, c));
      }
      for (int c = 0; c < 3; ++c) put(a + r, b + c, -w(r, c));
    }
  }
  for (int r = 0; r < 3; ++r) put(r, r, 1e12);
  t->nnz = k;
  cholmod_sparse* a = cholmod_l_triplet_to_sparse(t, k, &common);
  cholmod_l_free_triplet(&t, &common);
  cholmod_factor* f = cholmod_l_analyze(a, &common);
  cholmod_l_factorize(a, f, &common);
  cholmod_dense* rhs = cholmod_l_ones(static_cast<std::size_t>(n), 1, CHOLMOD_REAL, &common);
  cholmod_dense* x = cholmod_l_solve(CHOLMOD_A, f, rhs, &common);
  const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  cholmod_l_free_dense(&x, &common);
  cholmod_l_free_dense(&rhs, &common);
  cholmod_l_free_factor(&f, &common);
  cholmod_l_free_sparse(&a, &common);
  cholmod_l_finish(&common);
  return seconds;
}

// The adjustment in a child process: its seconds through a pipe, its peak
// resident set from wait4.
Run adjust_in_child(const Generated& g) {
  int fds[2];
  if (pipe(fds) != 0) std::exit(1);
  const pid_t pid = fork();
  if (pid == 0) {
    close(fds[0]);
    solver::AdjustOptions o;
    o.data_snooping = false;
    const auto t0 = Clock::now();
    const solver::AdjustmentResult r = solver::adjust_network(g.net, o);
    double s = std::chrono::duration<double>(Clock::now() - t0).count();
    if (!r.converged) s = -1.0;
    if (write(fds[1], &s, sizeof s) != static_cast<ssize_t>(sizeof s)) _exit(1);
    _exit(0);
  }
  close(fds[1]);
  Run run;
  double s = -1.0;
  if (read(fds[0], &s, sizeof s) != static_cast<ssize_t>(sizeof s)) s = -1.0;
  close(fds[0]);
  struct rusage usage {};
  int status = 0;
  wait4(pid, &status, 0, &usage);
  run.seconds = s;
  run.peak_mb = static_cast<double>(usage.ru_maxrss) / 1024.0;
  run.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return run;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::size_t> sizes{1000, 10000, 100000};
  int repetitions = 3;
  std::size_t command_max = 10000;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--sizes") sizes = parse_sizes(argv[i + 1]);
    else if (flag == "--repetitions") repetitions = std::max(1, std::atoi(argv[i + 1]));
    else if (flag == "--command-max") command_max = static_cast<std::size_t>(std::atol(argv[i + 1]));
    else {
      std::fprintf(stderr, "usage: %s [--sizes N,N...] [--repetitions R] [--command-max N]\n", argv[0]);
      return 2;
    }
  }
  char folder_template[] = "/tmp/geoanchor_adjust_bench_XXXXXX";
  if (!mkdtemp(folder_template)) return 1;
  const fs::path folder = folder_template;
  std::printf("network adjustment (stations' covariances and every redundancy number, no snooping) vs a bare CHOLMOD\n"
              "analyze + factor + solve of the same normal matrix; median of %d; peak = the child's maximum RSS\n\n",
              repetitions);
  std::printf("%-9s %-10s %12s %12s %8s %10s %12s %12s\n", "stations", "baselines", "adjust s", "cholmod s", "ratio", "peak MB",
              "command s", "cmd peak MB");
  for (const std::size_t n : sizes) {
    const Generated g = make_network(n);
    std::vector<double> adjust_s, bare_s;
    double peak = 0.0;
    for (int k = 0; k < repetitions; ++k) {
      const Run r = adjust_in_child(g);
      if (r.status != 0 || r.seconds < 0.0) {
        std::fprintf(stderr, "the adjustment of %zu stations failed (status %d)\n", n, r.status);
        return 1;
      }
      adjust_s.push_back(r.seconds);
      peak = std::max(peak, r.peak_mb);
    }
    // The bare factor-and-solve in a child too: CHOLMOD's OpenMP threads in
    // this process would deadlock a child forked later (libgomp after fork).
    for (int k = 0; k < repetitions; ++k) {
      int fds[2];
      if (pipe(fds) != 0) return 1;
      const pid_t pid = fork();
      if (pid == 0) {
        close(fds[0]);
        const double sec = bare_cholmod_seconds(g);
        if (write(fds[1], &sec, sizeof sec) != static_cast<ssize_t>(sizeof sec)) _exit(1);
        _exit(0);
      }
      close(fds[1]);
      double sec = -1.0;
      if (read(fds[0], &sec, sizeof sec) != static_cast<ssize_t>(sizeof sec)) sec = -1.0;
      close(fds[0]);
      int status = 0;
      waitpid(pid, &status, 0);
      if (sec < 0.0) return 1;
      bare_s.push_back(sec);
    }
    std::string command_text = "-", command_peak = "-";
    if (n <= command_max) {
      const fs::path json = folder / ("net_" + std::to_string(n) + ".json");
      write_json(g, json);
      std::vector<double> cmd_s;
      double cmd_peak = 0.0;
      for (int k = 0; k < repetitions; ++k) {
        fs::remove(folder / "st.csv");
        fs::remove(folder / "st.csv.geoanchor.json");
        const Run r = bench::run_command({GEOANCHOR_EXE, "adjust", json.string(), "-o", (folder / "st.csv").string(), "--no-snooping",
                                   "--report", (folder / "report.txt").string(), "--overwrite"},
                                  folder);
        if (r.status != 0) {
          std::fprintf(stderr, "geoanchor adjust exited %d; see %s\n", r.status, (folder / "stderr.txt").c_str());
          return 1;
        }
        cmd_s.push_back(r.seconds);
        cmd_peak = std::max(cmd_peak, r.peak_mb);
      }
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.3f", median(cmd_s));
      command_text = buf;
      std::snprintf(buf, sizeof buf, "%.0f", cmd_peak);
      command_peak = buf;
    }
    const double a = median(adjust_s), b = median(bare_s);
    std::printf("%-9zu %-10zu %12.3f %12.3f %8.2f %10.0f %12s %12s\n", n, g.net.measurements.size(), a, b, a / b, peak,
                command_text.c_str(), command_peak.c_str());
    std::fflush(stdout);
  }
  fs::remove_all(folder);
  return 0;
}
