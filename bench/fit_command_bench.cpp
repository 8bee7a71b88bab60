// The whole `geoanchor fit` command against its solve (issue 12 point 13):
// for N control marks, the median wall time and the peak memory of the
// executable reading a CSV, fitting, reporting and writing the transform
// file, and the median time of solver::fit_helmert on the same set with the
// same options in this process (the solver benchmark's call). The target is
// a ratio of at most 2 at 10⁶ marks. Never part of the test run's pass/fail.
//
//   geoanchor_fit_command_bench [--sizes 100000,1000000] [--repetitions 3]
//
// GEOANCHOR_BENCH_EXE overrides the geoanchor executable measured.

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
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "bench_process.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/helmert.hpp"
#include "geoanchor/io/control/control_csv.hpp"
#include "geoanchor/solver/helmert_fit.hpp"

namespace {

using namespace geoanchor;
using bench::median;
using bench::parse_sizes;
using bench::Run;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// The solver benchmark's set (bench/fit_bench.cpp): marks over 45–50°N,
// 5–12°E, 0–2000 m; a 7-parameter truth of cm/mas size; 3 mm noise in each
// frame, 3 mm sigmas in the file.
void write_control_csv(const fs::path& path, std::size_t n) {
  std::mt19937_64 rng(n);
  std::uniform_real_distribution<double> lat(45.0, 50.0), lon(5.0, 12.0), h(0.0, 2000.0);
  std::normal_distribution<double> noise(0.0, 0.003);
  geodesy::Helmert7<geodesy::PositionVector> truth;
  truth.t_m = Eigen::Vector3d(0.05, 0.05, -0.07);
  truth.rx = geodesy::Angle::milliarcseconds(2.0);
  truth.ry = geodesy::Angle::milliarcseconds(14.0);
  truth.rz = geodesy::Angle::milliarcseconds(-21.0);
  truth.ds = geodesy::ScaleDifference::ppb(2.0);
  const geodesy::GeocentricConverter conv(geodesy::Ellipsoid::grs80());
  std::ofstream out(path);
  out << "# source_frame = ITRF2014@2024.5\n# target_frame = ETRF2000@2024.5\n"
      << "id,x_src_m,y_src_m,z_src_m,x_dst_m,y_dst_m,z_dst_m,sigma_src_m,sigma_dst_m\n";
  char line[256];
  for (std::size_t i = 0; i < n; ++i) {
    const auto src = conv.ecef_from_geodetic(
        {geodesy::Angle::degrees(lat(rng)), geodesy::Angle::degrees(lon(rng)), geodesy::EllipsoidalHeight{h(rng)}});
    const auto dst = geodesy::apply(truth, geodesy::RotationModel::small_angle, src);
    std::snprintf(line, sizeof line, "P%zu,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,0.003,0.003\n", i, src.m.x() + noise(rng),
                  src.m.y() + noise(rng), src.m.z() + noise(rng), dst.m.x() + noise(rng), dst.m.y() + noise(rng),
                  dst.m.z() + noise(rng));
    out << line;
  }
  out.close();
  // On disk before anything is timed: a user's control file is not being
  // written back while they fit it (here 96 MB at 10⁶ marks would be,
  // during the first runs).
  const int fd = out ? open(path.c_str(), O_RDONLY) : -1;
  if (fd < 0 || fsync(fd) != 0) {
    std::fprintf(stderr, "cannot write %s\n", path.c_str());
    std::exit(1);
  }
  close(fd);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::size_t> sizes{100000, 1000000};
  int repetitions = 3;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--sizes") {
      sizes = parse_sizes(argv[i + 1]);
    } else if (flag == "--repetitions") {
      repetitions = std::max(1, std::atoi(argv[i + 1]));
    } else {
      std::fprintf(stderr, "usage: %s [--sizes N,N...] [--repetitions R]\n", argv[0]);
      return 2;
    }
  }
  const char* override_exe = std::getenv("GEOANCHOR_BENCH_EXE");
  const std::string exe = override_exe ? override_exe : GEOANCHOR_EXE;
  char folder_template[] = "/tmp/geoanchor_fit_command_bench_XXXXXX";
  if (!mkdtemp(folder_template)) return 1;
  const fs::path folder = folder_template;

  std::printf("geoanchor fit (whole command: read CSV, fit, report, write the transform file) vs its solve\n"
              "(solver::fit_helmert on the same set and options), helmert7, median of %d\n\n",
              repetitions);
  std::printf("%-9s %-9s %12s %12s %7s %14s %8s\n", "marks", "outliers", "command s", "solve s", "ratio", "command peak MB",
              "removed");
  for (const std::size_t n : sizes) {
    const fs::path csv = folder / ("control_" + std::to_string(n) + ".csv");
    write_control_csv(csv, n);
    for (const bool snooping : {false, true}) {
      std::vector<std::string> args{exe, "fit", csv.string(), "--model", "helmert7", "--convention", "position_vector",
                                    "-o", (folder / "T.json").string()};
      // As given (the default: flagged and ranked, none removed; a failing
      // global test written anyway), and with --remove-outliers.
      args.push_back(snooping ? "--remove-outliers" : "--accept-failed-global-test");
      // The command's runs first, with nothing of this process's in memory,
      // then the solves, each on a set read once: neither measures the
      // other's memory churn.
      std::vector<double> command_s, solve_s;
      double peak_mb = 0.0;
      for (int k = 0; k < repetitions; ++k) {
        // Each run writes a file that does not exist yet, as a user's first
        // fit does: the previous run's 450 MB (at 10⁶ marks) are deleted
        // and everything is on disk before the clock starts, so that no run
        // pays for freeing or writing back another's output.
        fs::remove(folder / "T.json");
        sync();
        const Run r = bench::run_command(args, folder, "report.txt");
        if (r.status != 0) {
          std::fprintf(stderr, "%s exited %d; see %s\n", exe.c_str(), r.status, (folder / "stderr.txt").c_str());
          return 1;
        }
        command_s.push_back(r.seconds);
        if (!(r.peak_mb <= peak_mb)) peak_mb = r.peak_mb;
      }
      std::size_t removed = 0;
      {
        io::ControlReadOptions ro;
        const geodesy::ControlSet set = io::read_control_set(csv, ro);
        solver::FitOptions o;
        o.model = solver::FitModel::helmert7;
        o.convention = solver::Convention::position_vector;
        o.remove_outliers = snooping;
        for (int k = 0; k < repetitions; ++k) {
          const auto t0 = Clock::now();
          const solver::FitResult fit = solver::fit_helmert(set, o);
          solve_s.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
          removed = static_cast<std::size_t>(
              std::count_if(fit.points.begin(), fit.points.end(), [](const auto& p) { return p.outlier; }));
        }
      }
      const double c = median(command_s), s = median(solve_s);
      std::printf("%-9zu %-9s %12.3f %12.3f %7.2f %14.0f %8zu\n", n, snooping ? "removed" : "flagged", c, s, c / s, peak_mb, removed);
      std::fflush(stdout);
    }
    fs::remove(csv);
  }
  fs::remove_all(folder);
  std::printf("\ntarget: ratio <= 2 at 10^6 marks (issue 12 point 13, fit at scale; at 10^5 the process's start,\n"
              "read and write, about 0.1 s, are more than the 0.08 s solve)\n");
  return 0;
}
