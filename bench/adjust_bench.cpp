// The network adjustment at national scale (issues 14 and 17): networks
// from the generator (workflow/network_generator.hpp, the same as `geoanchor
// adjust --generate N`: a jittered grid over 1000 km × 1000 km around 47°N
// 8°E, each station joined to its 4–6 nearest by baselines with 3×3
// covariances, 3 held stations, N/1000 planted 10 cm blunders, at most 10).
// For each size, each in its own child process (wall time; peak memory from
// wait4's ru_maxrss):
//  - bare: CHOLMOD analyze + factorize + solve of the same normal matrix
//    (in ECEF axes: the adjustment's is in each station's local axes, the
//    same matrix up to a block-diagonal rotation, the same pattern and fill),
//    CHOLMOD's default ordering (and, as "ND", with METIS's nested
//    dissection: the command orders the stations' graph by AMD or nested
//    dissection, whichever costs fewer flops);
//  - adjust: solver::adjust_network with every statistic and data snooping
//    removing what fails (--remove-outliers), and what it found: σ0,
//    snooping passes, the planted blunders found, other measurements
//    removed, and the truth
//    check: the share of station components within 1.96 σ (95 % expected;
//    the errors are correlated, so it wanders by a few %) and eᵀNe / dim
//    (e the errors against the truth, N the normal matrix of the kept
//    baselines: 1 ± a few ‰ when the covariances are right);
//  - pre-analysis (--preanalysis) with and without the external
//    reliability, against the bare factor-and-solve;
//  - the whole `geoanchor adjust` command on the DynaML files (read, adjust,
//    every statistic, write stations, measurements and report), as given
//    (the default: every failing measurement flagged and ranked in data
//    snooping's order, none removed; the planted blunders fail the global
//    test, so with --accept-failed-global-test: "cmd-flag") and with
//    --remove-outliers ("cmd s").
// Ratios are against the bare factor-and-solve. Never part of the test
// run's pass/fail.
//
//   geoanchor_adjust_bench [--sizes 1000,10000,100000] [--repetitions 3] [--command-max 100000] [--kernel-max 1000000] [--dense-max 2000] [--threads-max 100000]
//                          [--relative-sizes 10000,100000] [--relative-only]
//
// Relative precision (adjust --relative radius:R, issue 43): per size of
// --relative-sizes, the adjustment (no data snooping) with the connected
// pairs and with every pair within R = 2 grid spacings (the generator's
// side / √N: about 12 neighbours a station, most sharing no baseline), in
// a child each: the pairs, the seconds of the stations' part (covariances,
// ellipses, relative precision: AdjustmentTimings::stations) and of the
// whole adjustment, against the bare factor-and-solve. --relative-only
// skips the first tables.
//
// Up to --threads-max stations the adjustment runs once more on one thread:
// the speed-up of two threads is printed with the parts.
//
// Up to --dense-max stations the stations' covariances are also checked
// against a dense inverse of the normal matrix (Eigen's LLᵀ, built from the
// baselines kept): the worst difference relative to each block's largest
// entry is printed (issue 17: 1e-9 up to 2·10³ stations).

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

#include "accuracy.hpp"
#include "bench_process.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/network.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "huge_pages.hpp"
#include "geoanchor/solver/network_adjustment.hpp"
#include "geoanchor/workflow/network_generator.hpp"

namespace {

using namespace geoanchor;
using bench::median;
using bench::parse_sizes;
using bench::Run;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

using workflow::GeneratedNetwork;

GeneratedNetwork make_network(std::size_t n) {
  workflow::NetworkGeneratorOptions o;
  o.stations = n;
  o.seed = n;
  return workflow::generate_network(o);
}

// The bare baseline: N = Σ Aᵀ C⁻¹ A in ECEF (A = [−I I] per baseline), the
// held stations' rows by a weight of 1e12, analyzed, factored, solved.
// With `metis`, ordered by METIS's nested dissection instead of CHOLMOD's
// default (AMD, and METIS only when AMD's fill is high): the floor the
// command's own ordering (AMD or nested dissection, on the stations' graph)
// is to be read against too.
double bare_cholmod_seconds(const GeneratedNetwork& g, bool metis) {
  const auto& net = g.network;
  const SuiteSparse_long n = static_cast<SuiteSparse_long>(3 * net.stations.size());
  cholmod_common common;
  cholmod_l_start(&common);
  common.print = 0;
  if (metis) {
    common.nmethods = 1;
    common.method[0].ordering = CHOLMOD_METIS;
  }
  const auto t0 = Clock::now();
  cholmod_triplet* t = cholmod_l_allocate_triplet(static_cast<std::size_t>(n), static_cast<std::size_t>(n),
                                                  net.measurements.size() * 21 + 3 * net.stations.size(), 1, CHOLMOD_REAL, &common);
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
  for (std::size_t st = 0; st < net.stations.size(); ++st) {
    if (!net.stations[st].constraint.any()) continue;
    for (int r = 0; r < 3; ++r) put(static_cast<SuiteSparse_long>(3 * st) + r, static_cast<SuiteSparse_long>(3 * st) + r, 1e12);
  }
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

struct PreanalysisRun {
  double seconds = -1.0;
  solver::AdjustmentTimings parts;
};

struct KernelRun {
  double seconds = -1.0, sigma0 = 0.0, coverage = 0.0, chi2_ratio = 0.0;
  int passes = 0, downdated = 0;
  std::size_t found = 0, others_removed = 0;
  solver::AdjustmentTimings parts;
  std::int64_t factor_nonzeros = 0;
  double dense_difference = -1.0;  // worst station block against a dense inverse, relative (-1: not checked)
  double one_thread_seconds = 0.0, two_thread_seconds = 0.0;  // filled by main
  double bare_seconds = 0.0;                                   // filled by main
  PreanalysisRun preanalysis, preanalysis_no_external;          // filled by main
};

// The stations' covariance blocks against the dense inverse of the normal
// matrix built here from the baselines the adjustment kept (ECEF, held
// stations out): the worst difference relative to the block's largest
// entry. O(n³): for networks of a few thousand stations.
double dense_check(const GeneratedNetwork& g, const solver::AdjustmentResult& r) {
  std::vector<Eigen::Index> unknown(r.stations.size(), -1);
  Eigen::Index count = 0;
  for (std::size_t i = 0; i < r.stations.size(); ++i) {
    if (r.stations[i].constraint != "CCC") unknown[i] = count, count += 3;
  }
  Eigen::MatrixXd n = Eigen::MatrixXd::Zero(count, count);
  for (const auto& am : r.measurements) {
    if (!am.used) continue;
    const auto& m = g.network.measurements[am.index];
    const Eigen::Matrix3d w = m.covariance.inverse();
    const Eigen::Index ends[2] = {unknown[m.stations[0]], unknown[m.stations[1]]};
    for (int a = 0; a < 2; ++a) {
      for (int b = 0; b < 2; ++b) {
        if (ends[a] >= 0 && ends[b] >= 0) n.block<3, 3>(ends[a], ends[b]) += (a == b ? 1.0 : -1.0) * w;
      }
    }
  }
  const Eigen::MatrixXd inverse = n.llt().solve(Eigen::MatrixXd::Identity(count, count));
  double worst = 0.0;
  for (std::size_t i = 0; i < r.stations.size(); ++i) {
    if (unknown[i] < 0) continue;
    const Eigen::Matrix3d q = inverse.block<3, 3>(unknown[i], unknown[i]);
    worst = testing::nan_max(worst, testing::max_abs_component(q - r.stations[i].covariance_m2) / testing::max_abs_component(q));
  }
  return worst;
}

// What the adjustment found against the generator's truth.
void check_against_truth(const GeneratedNetwork& g, const solver::AdjustmentResult& r, KernelRun& k) {
  const geodesy::GeocentricConverter geocentric(geodesy::Ellipsoid::grs80());
  std::size_t inside = 0, components = 0;
  for (std::size_t i = 0; i < r.stations.size(); ++i) {
    const auto& s = r.stations[i];
    if (s.constraint == "CCC") continue;
    const auto at = geocentric.geodetic_from_ecef(geodesy::EcefPosition(s.position));
    const Eigen::Vector3d error = geodesy::enu_from_ecef_rotation(at.lat, at.lon) * (s.position - g.truth[i]);
    for (int c = 0; c < 3; ++c) {
      inside += std::abs(error(c)) <= 1.96 * std::sqrt(s.covariance_local_m2(c, c)) ? 1u : 0u;
      ++components;
    }
  }
  k.coverage = static_cast<double>(inside) / static_cast<double>(components);
  // eᵀ N e over the baselines kept: Σ (Δe)ᵀ C⁻¹ Δe.
  double chi2 = 0.0;
  for (const auto& am : r.measurements) {
    if (!am.used) continue;
    const auto& m = g.network.measurements[am.index];
    const Eigen::Vector3d d = (r.stations[m.stations[1]].position - g.truth[m.stations[1]]) -
                              (r.stations[m.stations[0]].position - g.truth[m.stations[0]]);
    chi2 += d.dot(m.covariance.llt().solve(d));
  }
  k.chi2_ratio = chi2 / static_cast<double>(components);
  std::vector<bool> planted(g.network.measurements.size(), false);
  for (const auto& b : g.blunders) planted[b.measurement] = true;
  for (const auto& am : r.measurements) {
    if (am.outlier) (planted[am.index] ? k.found : k.others_removed)++;
  }
  k.sigma0 = r.sigma0.value_or(0.0);
  k.passes = r.passes;
  k.downdated = r.passes_downdated;
  k.parts = r.seconds;
  k.factor_nonzeros = r.factor_nonzeros;
}

// `work` (returning a trivially copyable T) in a child process: its result
// through a pipe, its exit status and peak resident set from wait4.
template <class T, class F>
std::pair<T, Run> in_child(F work) {
  int fds[2];
  if (pipe(fds) != 0) std::exit(1);
  const pid_t pid = fork();
  if (pid == 0) {
    close(fds[0]);
    const T k = work();
    if (write(fds[1], &k, sizeof k) != static_cast<ssize_t>(sizeof k)) _exit(1);
    _exit(0);
  }
  close(fds[1]);
  T k;
  const bool read_all = read(fds[0], &k, sizeof k) == static_cast<ssize_t>(sizeof k);
  close(fds[0]);
  struct rusage usage {};
  int status = 0;
  wait4(pid, &status, 0, &usage);
  Run run;
  run.peak_mb = static_cast<double>(usage.ru_maxrss) / 1024.0;
  run.status = !read_all ? 1 : WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return {k, run};
}

// The adjustment in a child process.
std::pair<KernelRun, Run> adjust_in_child(const GeneratedNetwork& g, std::size_t dense_max, int jobs = 0) {
  auto [k, run] = in_child<KernelRun>([&] {
    KernelRun kr;
    const auto t0 = Clock::now();
    solver::AdjustOptions options;
    options.jobs = jobs;
    options.remove_outliers = true;
    options.external_reliability = false;  // its solves: the pre-analysis table
    const solver::AdjustmentResult r = solver::adjust_network(g.network, options);
    kr.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    if (!r.converged) kr.seconds = -1.0;
    check_against_truth(g, r, kr);
    if (g.network.stations.size() <= dense_max) kr.dense_difference = dense_check(g, r);
    return kr;
  });
  if (run.status != 0) k.seconds = -1.0;
  run.seconds = k.seconds;
  return {k, run};
}

// Pre-analysis (adjust --preanalysis) in a child process: its wall
// seconds and parts, with the external reliability (a solve per
// measurement component) or without.
PreanalysisRun preanalysis_in_child(const GeneratedNetwork& g, bool external) {
  auto [k, run] = in_child<PreanalysisRun>([&] {
    PreanalysisRun pr;
    const auto t0 = Clock::now();
    solver::AdjustOptions options;
    options.jobs = 2;
    options.preanalysis = true;
    options.data_snooping = false;
    options.external_reliability = external;
    const solver::AdjustmentResult r = solver::adjust_network(g.network, options);
    pr.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    pr.parts = r.seconds;
    return pr;
  });
  if (run.status != 0) k.seconds = -1.0;
  return k;
}

// The command line (the usage line at the top of this file).
struct BenchOptions {
  std::vector<std::size_t> sizes{1000, 10000, 100000};
  int repetitions = 3;
  std::size_t command_max = 100000, kernel_max = 1000000, dense_max = 2000, threads_max = 100000;
  std::vector<std::size_t> relative_sizes{10000, 100000};
  bool relative_only = false;
};

// One adjustment for the relative-precision table, in a child.
struct RelativeRun {
  double seconds = -1.0, stations_seconds = 0.0;
  std::size_t pairs = 0;
};
RelativeRun relative_in_child(const GeneratedNetwork& g, solver::RelativePairs pairs, double radius_m) {
  auto [k, run] = in_child<RelativeRun>(
      [&] {
        RelativeRun kr;
        solver::AdjustOptions options;
        options.jobs = 2;
        options.data_snooping = false;
        options.relative.pairs = pairs;
        options.relative.radius_m = radius_m;
        const auto t0 = Clock::now();
        const solver::AdjustmentResult r = solver::adjust_network(g.network, options);
        kr.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
        kr.stations_seconds = r.seconds.stations;
        kr.pairs = r.relative.size();
        return kr;
      });
  if (run.status != 0) k.seconds = -1.0;
  return k;
}

// False (after printing the usage) for an unknown flag.
bool parse_options(int argc, char** argv, BenchOptions& b) {
  // The one flag without a value, first; then flag-value pairs.
  std::vector<char*> args{argv[0]};
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--relative-only") b.relative_only = true;
    else args.push_back(argv[i]);
  }
  argc = static_cast<int>(args.size());
  argv = args.data();
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--sizes") b.sizes = parse_sizes(argv[i + 1]);
    else if (flag == "--threads-max") b.threads_max = static_cast<std::size_t>(std::atol(argv[i + 1]));
    else if (flag == "--dense-max") b.dense_max = static_cast<std::size_t>(std::atol(argv[i + 1]));
    else if (flag == "--kernel-max") b.kernel_max = static_cast<std::size_t>(std::atol(argv[i + 1]));
    else if (flag == "--repetitions") b.repetitions = std::max(1, std::atoi(argv[i + 1]));
    else if (flag == "--relative-sizes") b.relative_sizes = parse_sizes(argv[i + 1]);
    else if (flag == "--command-max") b.command_max = static_cast<std::size_t>(std::atol(argv[i + 1]));
    else {
      std::fprintf(stderr, "usage: %s [--sizes N,N...] [--repetitions R] [--command-max N] [--kernel-max N] [--dense-max N] [--threads-max N] [--relative-sizes N,N...] [--relative-only]\n", argv[0]);
      return false;
    }
  }
  return true;
}

// The lines above the first table, and its header.
void print_table_header(int repetitions) {
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  std::printf("malloc: GLIBC_TUNABLES=%s (every process below)\n", tunables ? tunables : "(not set)");
  std::printf("generated GNSS networks (adjust --generate N --seed N); median of %d; s = wall seconds, MB = peak RSS;\n"
              "ratio = / bare CHOLMOD analyze + factor + solve of the same normal matrix (CHOLMOD's default ordering;\n"
              "ND s: the same with METIS's nested dissection)\n\n",
              repetitions);
  std::printf("%-8s %-8s | %7s %6s %6s | %7s %6s %5s | %7s %6s %5s | %7s %6s %5s | %6s %6s %9s %6s %6s\n", "stations", "baselns",
              "bare s", "MB", "ND s", "adj s", "MB", "ratio", "cmd-flag", "MB", "ratio", "cmd s", "MB", "ratio", "sigma0", "passes",
              "blunders", "cover", "eNe/n");
}

// The bare factor-and-solve's seconds, with CHOLMOD's default ordering
// and with METIS's, and the default's peak memory.
struct BareRuns {
  std::vector<double> seconds, nd_seconds;
  double peak_mb = 0.0;
};

// The bare factor-and-solve in a child too: CHOLMOD's OpenMP threads in
// this process would deadlock a child forked later (libgomp after fork).
// False when a run failed.
bool time_bare(const GeneratedNetwork& g, int repetitions, BareRuns& bare) {
  for (int rep = 0; rep < repetitions; ++rep) {
    for (const bool metis : {false, true}) {
      const auto [sec, usage] = in_child<double>([&] { return bare_cholmod_seconds(g, metis); });
      if (usage.status != 0) return false;
      if (sec < 0.0) return false;
      if (metis) {
        bare.nd_seconds.push_back(sec);
      } else {
        bare.seconds.push_back(sec);
        bare.peak_mb = std::max(bare.peak_mb, usage.peak_mb);
      }
    }
  }
  return true;
}

// The whole command, on the DynaML files as written: seconds, peak MB and
// ratio to the bare factor-and-solve, as given ([0]) and with
// --remove-outliers ([1]); "-" above --command-max. False when a run failed.
bool time_command(const GeneratedNetwork& g, std::size_t n, const BenchOptions& b, const fs::path& folder, double bare,
                  std::string (&command)[2][3]) {
  for (auto& c : command) c[0] = c[1] = c[2] = "-";
  if (n <= b.command_max) {
    for (const auto& e : fs::directory_iterator(folder)) fs::remove(e.path());
    workflow::write_generated_network(g, folder, "network", io::Overwrite::allow);
    for (int snooping = 0; snooping < 2; ++snooping) {
      std::vector<double> cmd_s;
      double cmd_peak = 0.0;
      for (int rep = 0; rep < b.repetitions; ++rep) {
        std::vector<std::string> args{GEOANCHOR_EXE, "adjust", (folder / "network.stn.xml").string(), (folder / "network.msr.xml").string(),
                                      "-o", (folder / "st.csv").string(), "--measurements", (folder / "m.csv").string(), "--report",
                                      (folder / "report.txt").string(), "--overwrite"};
        // As given the planted blunders fail the global test: written anyway.
        if (!snooping) args.insert(args.end(), {"--accept-failed-global-test"});
        if (snooping) args.push_back("--remove-outliers");
        const Run r = bench::run_command(args, folder);
        if (r.status != 0) {
          std::fprintf(stderr, "geoanchor adjust exited %d; see %s\n", r.status, (folder / "stderr.txt").c_str());
          return false;
        }
        cmd_s.push_back(r.seconds);
        cmd_peak = std::max(cmd_peak, r.peak_mb);
      }
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.2f", median(cmd_s));
      command[snooping][0] = buf;
      std::snprintf(buf, sizeof buf, "%.0f", cmd_peak);
      command[snooping][1] = buf;
      std::snprintf(buf, sizeof buf, "%.2f", median(cmd_s) / bare);
      command[snooping][2] = buf;
    }
  }
  return true;
}

// One size: the adjustment (on two threads, and on one), the bare
// factor-and-solve and the command, printed as a row of the first table;
// the adjustment's numbers added to `kernels`. False when a run failed.
bool measure_size(std::size_t n, const BenchOptions& b, const fs::path& folder,
                  std::vector<std::pair<std::size_t, KernelRun>>& kernels) {
  const GeneratedNetwork g = make_network(n);
  std::vector<double> adjust_s;
  double peak = 0.0;
  KernelRun k;
  for (int rep = 0; rep < (n <= b.kernel_max ? b.repetitions : 0); ++rep) {
    const auto [kr, r] = adjust_in_child(g, b.dense_max, 2);
    if (r.status != 0 || r.seconds < 0.0) {
      std::fprintf(stderr, "the adjustment of %zu stations failed (status %d)\n", n, r.status);
      return false;
    }
    k = kr;
    adjust_s.push_back(r.seconds);
    peak = std::max(peak, r.peak_mb);
  }
  // The same on one thread: the speed-up of --jobs 2 (the results are
  // the same bits, tests/workflow/network_generator_test.cpp).
  double one_thread = 0.0;
  if (n <= b.kernel_max && n <= b.threads_max) {
    const auto [k1, r1] = adjust_in_child(g, 0, 1);
    if (r1.status != 0 || r1.seconds < 0.0) return false;
    one_thread = r1.seconds;
  }
  BareRuns bare_runs;
  if (!time_bare(g, b.repetitions, bare_runs)) return false;
  const double bare = median(bare_runs.seconds), bare_nd = median(bare_runs.nd_seconds);
  std::string command[2][3];
  if (!time_command(g, n, b, folder, bare, command)) return false;
  const double a = adjust_s.empty() ? 0.0 : median(adjust_s);
  char blunders[32];
  std::snprintf(blunders, sizeof blunders, "%zu/%zu+%zu", k.found, g.blunders.size(), k.others_removed);
  std::printf("%-8zu %-8zu | %7.2f %6.0f %6.2f | %7.2f %6.0f %5.2f | %7s %6s %5s | %7s %6s %5s | %6.4f %6d %9s %6.4f %6.4f\n", n,
              g.network.measurements.size(), bare, bare_runs.peak_mb, bare_nd, a, peak, a / bare, command[0][0].c_str(),
              command[0][1].c_str(), command[0][2].c_str(), command[1][0].c_str(), command[1][1].c_str(), command[1][2].c_str(),
              k.sigma0, k.passes, blunders, k.coverage, k.chi2_ratio);
  std::fflush(stdout);
  k.one_thread_seconds = one_thread;
  k.two_thread_seconds = a;
  k.bare_seconds = bare;
  if (n <= b.kernel_max) {
    k.preanalysis = preanalysis_in_child(g, true);
    k.preanalysis_no_external = preanalysis_in_child(g, false);
    if (k.preanalysis.seconds < 0.0 || k.preanalysis_no_external.seconds < 0.0) return false;
  }
  kernels.push_back({n, k});
  return true;
}

// The second and third tables: the adjustment's parts per size, and the
// speed-up of two threads; then the legend.
void print_parts(const std::vector<std::pair<std::size_t, KernelRun>>& kernels) {
  std::printf("\nthe adjustment's parts (seconds over every pass; solver::AdjustmentTimings; passes: all, and those downdated)\n"
              "%-8s %10s %7s %9s %9s %9s %9s %9s %9s %9s %9s %9s %9s %12s\n",
              "stations", "nnz(L)", "passes", "assemble", "factor", "solve", "sel.inv", "downdate", "per-meas", "datum", "snooping",
              "stations", "external", "vs dense");
  // (then, per size, the adjustment on one thread and the speed-up of two)
  for (const auto& [n, k] : kernels) {
    char dense[32] = "-";
    if (k.dense_difference >= 0.0 || std::isnan(k.dense_difference)) std::snprintf(dense, sizeof dense, "%.1e", k.dense_difference);
    char passes[16];
    std::snprintf(passes, sizeof passes, "%d/%d", k.passes, k.downdated);
    std::printf("%-8zu %10.3g %7s %9.2f %9.2f %9.2f %9.2f %9.2f %9.2f %9.2f %9.2f %9.2f %9.2f %12s\n", n,
                static_cast<double>(k.factor_nonzeros), passes, k.parts.assemble, k.parts.factor, k.parts.solve,
                k.parts.select_inverse, k.parts.downdate, k.parts.measurements, k.parts.datum, k.parts.snooping, k.parts.stations,
                k.parts.external, dense);
  }
  std::printf("\n%-8s %12s %12s %9s\n", "stations", "1 thread s", "2 threads s", "speed-up");
  for (const auto& [n, k] : kernels) {
    if (k.one_thread_seconds > 0.0) {
      std::printf("%-8zu %12.2f %12.2f %9.2f\n", n, k.one_thread_seconds, k.two_thread_seconds, k.one_thread_seconds / k.two_thread_seconds);
    }
  }
  std::printf("\npre-analysis (--preanalysis, 2 threads): seconds, and against the bare factor-and-solve; the external "
              "reliability's share (a solve per measurement component)\n%-8s %10s %8s %12s %8s %10s %8s\n",
              "stations", "no ext. s", "x bare", "with ext. s", "x bare", "external s", "factor s");
  for (const auto& [n, k] : kernels) {
    if (k.preanalysis.seconds < 0.0) continue;
    std::printf("%-8zu %10.2f %8.2f %12.2f %8.2f %10.2f %8.2f\n", n, k.preanalysis_no_external.seconds,
                k.preanalysis_no_external.seconds / k.bare_seconds, k.preanalysis.seconds, k.preanalysis.seconds / k.bare_seconds,
                k.preanalysis.parts.external, k.preanalysis.parts.factor);
  }
  std::printf("\nblunders: planted found / planted + other measurements removed (alpha 0.001 removes about 0.1 %% of good ones)\n"
              "cover: station components within 1.96 sigma of the truth; eNe/n: e'Ne / n over the free stations' components\n");
}

// The relative-precision table (the usage at the top of this file).
bool measure_relative(const BenchOptions& b) {
  if (b.relative_sizes.empty()) return true;
  std::printf("\nrelative precision, --relative radius:R (R = 2 grid spacings), against connected pairs; s = wall seconds;\n"
              "stations s = the stations' part (covariances, ellipses, relative precision); ratio = / bare factor-and-solve\n"
              "%-8s %8s %9s | %10s %10s | %9s %10s %10s | %8s %8s\n",
              "stations", "R m", "bare s", "conn pairs", "stations s", "R pairs", "stations s", "adjust s", "R part/b", "adj/bare");
  for (const std::size_t n : b.relative_sizes) {
    const GeneratedNetwork g = make_network(n);
    const workflow::NetworkGeneratorOptions defaults;
    const double radius_m = 2.0 * defaults.side_km * 1000.0 / std::sqrt(static_cast<double>(n));
    BareRuns bare_runs;
    if (!time_bare(g, 1, bare_runs)) return false;
    const double bare = median(bare_runs.seconds);
    const RelativeRun connected = relative_in_child(g, solver::RelativePairs::connected, 0.0);
    const RelativeRun radius = relative_in_child(g, solver::RelativePairs::radius, radius_m);
    if (connected.seconds < 0.0 || radius.seconds < 0.0) {
      std::fprintf(stderr, "the adjustment of %zu stations with relative precision failed\n", n);
      return false;
    }
    std::printf("%-8zu %8.0f %9.2f | %10zu %10.2f | %9zu %10.2f %10.2f | %8.2f %8.2f\n", n, radius_m, bare, connected.pairs,
                connected.stations_seconds, radius.pairs, radius.stations_seconds, radius.seconds,
                (radius.stations_seconds - connected.stations_seconds) / bare, radius.seconds / bare);
    std::fflush(stdout);
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  // The bare factor-and-solve and the adjustment in the same memory setting
  // as the command (which starts itself with huge pages for malloc: the
  // floor is not to be measured with 4 kB page faults the command avoids).
  cli::restart_with_huge_pages(argv);
  BenchOptions b;
  if (!parse_options(argc, argv, b)) return 2;
  char folder_template[] = "/tmp/geoanchor_adjust_bench_XXXXXX";
  if (!mkdtemp(folder_template)) return 1;
  const fs::path folder = folder_template;
  if (!b.relative_only) {
    print_table_header(b.repetitions);
    std::vector<std::pair<std::size_t, KernelRun>> kernels;
    for (const std::size_t n : b.sizes) {
      if (!measure_size(n, b, folder, kernels)) return 1;
    }
    print_parts(kernels);
  }
  if (!measure_relative(b)) return 1;
  fs::remove_all(folder);
  return 0;
}
