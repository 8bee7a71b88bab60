#pragma once
// A console reporter that also keeps each benchmark's median (in seconds),
// so that a benchmark can print its own table of medians and ratios.

#include <benchmark/benchmark.h>

#include <limits>
#include <map>
#include <string>
#include <vector>

namespace geoanchor::bench {

class MedianReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const auto& r : runs) {
      if (r.aggregate_name == "median") {
        // Adjusted times are in the run's display unit.
        medians_s_[r.run_name.function_name + (r.run_name.args.empty() ? "" : "/" + r.run_name.args)] =
            r.GetAdjustedRealTime() / benchmark::GetTimeUnitMultiplier(r.time_unit);
      }
    }
    ConsoleReporter::ReportRuns(runs);
  }
  // Median seconds per iteration of `name` ("fit7/1000"), or NaN if it did
  // not run (filtered out): a table prints "nan" there, never a number.
  double median_s(const std::string& name) const {
    const auto it = medians_s_.find(name);
    return it == medians_s_.end() ? std::numeric_limits<double>::quiet_NaN() : it->second;
  }
  bool ran(const std::string& name) const { return medians_s_.count(name) != 0; }

 private:
  std::map<std::string, double> medians_s_;
};

// A benchmark's main: Google Benchmark's own report, then `print_table`.
template <class PrintTable>
int run_and_tabulate(int argc, char** argv, PrintTable print_table) {
  benchmark::Initialize(&argc, argv);
  MedianReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  print_table(reporter);
  benchmark::Shutdown();
  return 0;
}

}  // namespace geoanchor::bench
