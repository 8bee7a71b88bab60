#include "adjust_command.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <future>
#include <iostream>

#include "command_input.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/workflow/adjust.hpp"
#include "geoanchor/workflow/network_generator.hpp"
#include "geoanchor/workflow/transform_checks.hpp"
#include "option_parsing.hpp"
#include "version.hpp"

namespace geoanchor::cli {

CLI::App* add_adjust_command(CLI::App& app, AdjustCommandOptions& o) {
  auto* cmd = app.add_subcommand("adjust", "Least-squares adjustment of a survey network (GNSS and terrestrial)");
  cmd->add_option("INPUT", o.inputs,
                  "Network inputs, detected from their content: geoanchor network JSON, DynaML station and measurement "
                  "files, SINEX, GNU Gama local XML; - for standard input");
  cmd->add_option("-o,--output", o.output, "Adjusted stations as a control-set CSV (with its sidecar OUT.geoanchor.json); - for standard output");
  cmd->add_option("--measurements", o.measurements, "Write the measurements with their statistics as CSV");
  cmd->add_option("--report", o.report, "Write the text report to this file (else it goes to standard output, or standard error with -o -)");
  cmd->add_flag("--json", o.json, "Print the report as JSON (schema geoanchor.adjust-report/1) on standard output");
  cmd->add_option("--sinex", o.sinex, "Write the adjusted stations with their covariance as SINEX");
  cmd->add_option("--relative", o.relative,
                  "Relative precision between: connected (stations a measurement joins; default), all (every pair), radius:R_M (every "
                  "pair within R metres horizontally), pairs:FILE (a CSV with header from,to)");
  cmd->add_option("--standard", o.standard,
                  "Judge the relative precision (and positions) against an accuracy standard: a shipped NAME (alta-nsps-2021) or a "
                  "standard's JSON FILE (docs/standards.md)");
  cmd->add_option("--relative-output", o.relative_output, "Write the relative precision of every pair (and the standard's verdicts) as CSV");
  add_network_options(cmd, o.network);
  cmd->add_option("--convention", o.convention, "--estimate-helmert: position_vector|coordinate_frame, the convention of the written transform (required)");
  cmd->add_option("--helmert-output", o.helmert_output, "--estimate-helmert: the transform file (default: STATIONS less .csv, plus .helmert.json)");
  cmd->add_flag("--preanalysis", o.preanalysis,
                "Pre-analysis: from the design at the a-priori coordinates and the a-priori errors alone (measured values "
                "optional, not used): predicted ellipses, redundancy, MDB and external reliability; no residuals");
  cmd->add_flag("--no-external-reliability", o.no_external_reliability,
                "Leave out the external reliability (a solve per measurement component: minutes at 10^5 stations)");
  cmd->add_option("--candidates", o.candidates,
                  "--preanalysis: candidate measurements (any network input format; values not used), each ranked by how much "
                  "it improves the worst station when added alone");
  cmd->add_option("--candidates-output", o.candidates_output, "--candidates: write the ranked candidates as CSV");
  cmd->add_option("--rank-by", o.rank_by, "--candidates: semi-major (the largest semi-major axis at --confidence, the default) or sigma-up");
  cmd->add_flag("--accept-failed-global-test", o.accept_failed_global_test, "Write the results even if the global test fails high");
  cmd->add_flag("--overwrite", o.overwrite, "Replace existing outputs");
  cmd->add_option("--jobs", o.jobs, "Threads for the assembly and the statistics (default: the machine's cores); the results do not depend on it")
      ->check(integer_range(1, 256));
  cmd->add_option("--max-memory", o.max_memory_gb, "GB the factor and its selected inverse may take (default: what the machine has available); above it E_MEMORY before any is taken")
      ->check(finite_positive());
  // Generated networks (planning, benchmarks): docs/commands/adjust.md#generated-networks.
  cmd->add_option("--generate", o.generate, "Write a generated GNSS network of N stations (DynaML, network JSON, truth, blunders) to --out-dir instead of adjusting")
      ->check(integer_range(0, 100000000));  // fewer than 4: the generator says why
  cmd->add_option("--out-dir", o.out_dir, "--generate: the folder for network.stn.xml, network.msr.xml, network.json, network.truth.csv, network.blunders.csv");
  cmd->add_option("--seed", o.seed, "--generate: the random seed (default 1)")->check(integer_range(0, 1LL << 62));
  cmd->add_option("--held", o.held, "--generate: stations held fixed at their true positions (default 3)")->check(integer_range(1, 100000000));
  cmd->add_option("--blunders", o.blunders, "--generate: baselines with a planted blunder (default N/1000, 1 to 10)")->check(integer_range(0, 100000000));
  cmd->add_option("--blunder", o.blunder_m, "--generate: the planted blunders' length in metres (default 0.10)")->check(finite_positive());
  cmd->add_option("--center", o.center, "--generate: the region's centre LAT,LON in degrees (default 47,8)");
  cmd->add_option("--side-km", o.side_km, "--generate: the square region's side in km (default 1000)")->check(finite_positive());
  return cmd;
}

namespace {

int run_generate(const AdjustCommandOptions& o) {
  if (!o.out_dir) throw Error(ErrorKind::usage, "E_OPTION", "--generate: give the folder for the network with --out-dir");
  if (!o.inputs.empty() || !o.output.empty() || o.measurements || o.report || o.sinex || o.json || o.relative_output || o.standard) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--generate writes a network and adjusts nothing: give no INPUT, -o, --measurements, --report, --sinex, --json, "
                "--relative-output or --standard");
  }
  workflow::NetworkGeneratorOptions g;
  g.stations = *o.generate;
  if (o.seed) g.seed = *o.seed;
  if (o.held) g.held = *o.held;
  g.blunders = o.blunders;
  if (o.blunder_m) g.blunder_m = *o.blunder_m;
  if (o.side_km) g.side_km = *o.side_km;
  if (o.center) {
    const std::vector<double> c = split_numbers(*o.center, "--center", 2, "LAT,LON in degrees");
    g.center_lat_deg = c[0];
    g.center_lon_deg = c[1];
  }
  if (!std::filesystem::is_directory(*o.out_dir)) {
    throw Error(ErrorKind::usage, "E_OUTPUT_DIR", "--out-dir " + *o.out_dir + ": not a folder");
  }
  const workflow::GeneratedNetwork net = workflow::generate_network(g);
  const auto paths = workflow::write_generated_network(net, *o.out_dir, "network", o.overwrite ? io::Overwrite::allow : io::Overwrite::refuse);
  std::cout << "generated " << net.network.stations.size() << " stations, " << net.network.measurements.size() << " baselines, "
            << g.held << " held, " << net.blunders.size() << " planted blunder" << (net.blunders.size() == 1 ? "" : "s") << " of "
            << format_shortest(g.blunder_m) << " m (seed " << g.seed << ")\n";
  for (const auto& p : paths) std::cout << "  " << p.string() << '\n';
  return 0;
}

// The options' combinations for an adjustment (not --generate).
void check_options(const AdjustCommandOptions& o) {
  if (o.out_dir || o.seed || o.held || o.blunders || o.blunder_m || o.center || o.side_km) {
    throw Error(ErrorKind::usage, "E_OPTION", "--out-dir, --seed, --held, --blunders, --blunder, --center and --side-km go with --generate");
  }
  if (o.inputs.empty()) throw Error(ErrorKind::usage, "E_OPTION", "INPUT is required: the network's files (or --generate N --out-dir DIR)");
  if (o.output.empty()) throw Error(ErrorKind::usage, "E_OPTION", "-o STATIONS.csv is required (or - for standard output)");
  if (o.json && o.output == "-") {
    throw Error(ErrorKind::usage, "E_OPTION", "--json and -o -: both would go to standard output; give -o STATIONS.csv");
  }
  if (!o.preanalysis && (o.candidates || o.candidates_output || o.rank_by)) {
    throw Error(ErrorKind::usage, "E_OPTION", std::string(o.candidates ? "--candidates" : o.candidates_output ? "--candidates-output" : "--rank-by") +
                                                  ": only with --preanalysis (candidates are ranked by a pre-analysis of the design)");
  }
  if (!o.candidates && (o.candidates_output || o.rank_by)) {
    throw Error(ErrorKind::usage, "E_OPTION", std::string(o.candidates_output ? "--candidates-output" : "--rank-by") + ": only with --candidates FILE");
  }
  if (o.rank_by && *o.rank_by != "semi-major" && *o.rank_by != "sigma-up") {
    throw Error(ErrorKind::usage, "E_OPTION", "--rank-by " + *o.rank_by + ": expected semi-major or sigma-up");
  }
  if (!o.network.estimate_helmert && (o.convention || o.helmert_output)) {
    throw Error(ErrorKind::usage, "E_OPTION", std::string(o.convention ? "--convention" : "--helmert-output") + ": only with --estimate-helmert");
  }
}

// The estimated Helmert's transform file.
std::optional<std::string> helmert_output_path(const AdjustCommandOptions& o) {
  std::optional<std::string> helmert_path;
  if (o.network.estimate_helmert) {
    if (o.helmert_output) {
      helmert_path = *o.helmert_output;
    } else if (o.output == "-") {
      throw Error(ErrorKind::usage, "E_OPTION", "--estimate-helmert with -o -: give the transform file's path with --helmert-output");
    } else {
      const std::filesystem::path out(o.output);
      helmert_path = (out.parent_path() / (out.extension() == ".csv" ? out.stem() : out.filename())).string() + ".helmert.json";
    }
  }
  return helmert_path;
}

// Every output its own file (the stations' sidecar included).
void refuse_shared_paths(const AdjustCommandOptions& o, const std::optional<std::string>& helmert_path) {
  std::vector<std::pair<std::string, std::string>> outputs;
  if (o.output != "-") outputs.push_back({"-o", o.output}), outputs.push_back({"-o's sidecar", o.output + ".geoanchor.json"});
  if (o.measurements) outputs.push_back({"--measurements", *o.measurements});
  if (o.report) outputs.push_back({"--report", *o.report});
  if (o.sinex) outputs.push_back({"--sinex", *o.sinex});
  if (o.relative_output) outputs.push_back({"--relative-output", *o.relative_output});
  if (o.candidates_output) outputs.push_back({"--candidates-output", *o.candidates_output});
  if (helmert_path) outputs.push_back({"--estimate-helmert's transform file", *helmert_path});
  for (std::size_t a = 0; a < outputs.size(); ++a) {
    for (std::size_t b = a + 1; b < outputs.size(); ++b) {
      std::error_code ec;
      const bool same = outputs[a].second == outputs[b].second ||
                        std::filesystem::weakly_canonical(outputs[a].second, ec) == std::filesystem::weakly_canonical(outputs[b].second, ec);
      if (same) {
        throw Error(ErrorKind::usage, "E_OPTION", outputs[a].first + " and " + outputs[b].first + " name the same file " +
                                                      outputs[b].second + "; give each output its own");
      }
    }
    for (const auto& in : o.inputs) {
      std::error_code ec;
      if (in != "-" && std::filesystem::weakly_canonical(in, ec) == std::filesystem::weakly_canonical(outputs[a].second, ec)) {
        throw Error(ErrorKind::usage, "E_OPTION", outputs[a].first + " " + outputs[a].second + " is an input");
      }
    }
  }
}

// The outputs, claimed before the adjustment: a path that cannot be
// written fails first.
struct AdjustOutputs {
  AdjustOutputs(const AdjustCommandOptions& o, const std::optional<std::string>& helmert_path)
      : overwrite(o.overwrite ? io::Overwrite::allow : io::Overwrite::refuse), stations(o.output, overwrite) {
    if (o.measurements) measurements = std::make_unique<io::AtomicOutputFile>(*o.measurements, overwrite);
    if (o.report) report = std::make_unique<io::AtomicOutputFile>(*o.report, overwrite);
    if (o.sinex) sinex = std::make_unique<io::AtomicOutputFile>(*o.sinex, overwrite);
    if (o.relative_output) relative = std::make_unique<io::AtomicOutputFile>(*o.relative_output, overwrite);
    if (helmert_path) helmert = std::make_unique<io::AtomicOutputFile>(*helmert_path, overwrite);
    if (o.candidates_output) candidates = std::make_unique<io::AtomicOutputFile>(*o.candidates_output, overwrite);
  }
  const io::Overwrite overwrite;
  io::DataOutput stations;
  std::unique_ptr<io::AtomicOutputFile> measurements, report;
  std::unique_ptr<io::AtomicOutputFile> sinex, helmert, relative, candidates;
};

// The report, shown whether or not the results are written, with the
// warnings of the reading and of the adjustment.
void show_report(const AdjustCommandOptions& o, const AdjustOutputs& outputs, const workflow::PreparedNetwork& prepared,
                 const solver::AdjustmentResult& r, const solver::AdjustOptions& so, const std::string& text) {
  // (The whole report only for --json: the sidecar holds its summary.)
  const nlohmann::ordered_json report_document =
      o.json ? workflow::report_document(prepared, r, so, workflow::ReportDetail::full) : nlohmann::ordered_json();
  // The report is shown whether or not the results are written.
  std::ostream& shown = outputs.stations.is_standard_output() || o.json ? std::cerr : std::cout;
  if (!outputs.report) shown << text;
  if (o.json) std::cout << report_document.dump(2) << "\n";
  for (const auto& n : prepared.notes) {
    if (n.rfind("warning: ", 0) == 0) std::cerr << "geoanchor: " << n << '\n';
  }
  for (const auto& w : r.warnings) std::cerr << "geoanchor: warning: " << w << '\n';
}

// Whether the results are refused (data snooping's limit, or a global test
// that fails high without --accept-failed-global-test); then the error is
// printed and nothing is written.
bool refuse_results(const AdjustCommandOptions& o, const workflow::PreparedNetwork& prepared, const solver::AdjustmentResult& r) {
  const auto& g = r.global_test;
  if (!r.refused_because.empty()) {
    std::cerr << "geoanchor: error[E_ADJUST_SNOOPING_LIMIT]: " << r.refused_because << "; nothing written\n";
    return true;
  }
  if (g.failed_high() && !o.accept_failed_global_test) {
    // The flagged measurements first, in the order data snooping would remove them.
    const std::vector<std::size_t> failing = solver::failing_measurements(r);
    std::string flagged;
    constexpr std::size_t kNamed = 10;
    for (std::size_t k = 0; k < failing.size() && k < kNamed; ++k) {
      const auto& am = r.measurements[failing[k]];
      const auto& m = prepared.network.measurements[am.index];
      flagged += (k ? ", " : "") + m.source + " (" + geodesy::to_string(m.kind) + ", |w| " + format_fixed(am.w_max, 2) +
                 (am.snooping_rank > 0 ? ", snooping rank " + std::to_string(am.snooping_rank) : std::string()) + ")";
    }
    if (failing.size() > kNamed) flagged += " and " + std::to_string(failing.size() - kNamed) + " more";
    std::string worst;
    double w = 0.0;
    for (const auto& am : r.measurements) {
      if (am.used && std::isfinite(am.w_max) && am.w_max > w) w = am.w_max, worst = prepared.network.measurements[am.index].source;
    }
    std::cerr << "geoanchor: error[E_ADJUST_GLOBAL_TEST]: "
              << (failing.empty() ? std::string()
                                  : std::to_string(failing.size()) + " measurement" + (failing.size() == 1 ? " fails its" : "s fail their") +
                                        " test (flagged): " + flagged + "; ")
              << "the global test fails high (" << format_fixed(g.statistic, 3) << " > " << format_fixed(g.critical_upper, 3)
              << ", variance factor " << format_fixed(r.variance_factor.value_or(0.0), 4)
              << "): the measurements disagree more than their standard deviations allow"
              << (failing.empty() && !worst.empty() ? "; the largest |w| is " + worst + " (" + format_fixed(w, 2) + ")" : std::string())
              << "; nothing written (--remove-outliers removes the flagged measurements in that order and adjusts again; "
                 "--accept-failed-global-test writes the results as they are)\n";
    return true;
  }
  return false;
}

// The estimated Helmert's transform file, its implausible parameters
// printed and recorded.
std::string helmert_file_text(const AdjustCommandOptions& o, const workflow::PreparedNetwork& prepared,
                              const solver::AdjustmentResult& r, const solver::AdjustOptions& so, const std::string& helmert_path) {
  std::string cmd;
  for (const auto& a : o.argv) cmd += (cmd.empty() ? "" : " ") + a;
  io::TransformFile file = workflow::helmert_transform_file(prepared, r, so, "geoanchor " GEOANCHOR_VERSION ": " + cmd);
  // Parameters past the plausibility limits (RELIABILITY 15): printed and recorded.
  std::optional<workflow::EpochSpan> span;
  if (prepared.helmert->rates) {
    const auto [lo, hi] = std::minmax_element(prepared.helmert->epochs.begin(), prepared.helmert->epochs.end());
    span = workflow::EpochSpan{geodesy::DecimalYear{*lo}, geodesy::DecimalYear{*hi}};
  }
  for (const auto& w : workflow::implausible_transform_warnings(file, helmert_path, span)) {
    std::cerr << "geoanchor: warning: " << w << '\n';
    file.fit->warnings.push_back(w);
  }
  return io::to_json_text(file);
}

// Every output's text, written and published as one group.
void write_outputs(const AdjustCommandOptions& o, AdjustOutputs& outputs, const workflow::PreparedNetwork& prepared,
                   const solver::AdjustmentResult& r, const solver::AdjustOptions& so,
                   const std::optional<std::string>& helmert_path, const std::string& text) {
  io::DataOutput& stations = outputs.stations;
  // The sidecar's text (the report's summary and the inputs' hashes: a
  // second's reading of 200 MB at 10⁵ stations) is made on a thread of its
  // own while the other outputs are formatted.
  std::future<std::string> sidecar_text;
  if (!stations.is_standard_output()) {
    sidecar_text = std::async(std::launch::async, [&] {
      return workflow::stations_sidecar_text(prepared, r, so, o.argv, o.inputs, GEOANCHOR_VERSION);
    });
  }
  // Every output's text before any is written: a refusal leaves none.
  const std::string sinex_text = outputs.sinex ? workflow::stations_sinex(prepared, r, std::string("geoanchor ") + GEOANCHOR_VERSION) : "";
  std::string helmert_text;
  if (outputs.helmert) helmert_text = helmert_file_text(o, prepared, r, so, *helmert_path);
  stations.stream() << workflow::stations_csv(prepared.network, r, so);
  const std::string measurements_text = outputs.measurements ? workflow::measurements_csv(prepared.network, r, o.jobs) : std::string();
  const std::string relative_text = outputs.relative ? workflow::relative_csv(prepared, r, so) : std::string();
  if (sidecar_text.valid()) stations.sidecar() << sidecar_text.get() << "\n";
  // One group (RELIABILITY 41): every output written before any is
  // published, the stations' CSV last; a failure leaves none of them.
  std::vector<io::AtomicOutputFile*> group;
  if (outputs.sinex) {
    outputs.sinex->stream() << sinex_text;
    group.push_back(outputs.sinex.get());
  }
  if (outputs.helmert) {
    outputs.helmert->stream() << helmert_text;
    group.push_back(outputs.helmert.get());
  }
  if (outputs.candidates) {
    outputs.candidates->stream() << workflow::candidates_csv(prepared, r, so);
    group.push_back(outputs.candidates.get());
  }
  if (outputs.measurements) {
    outputs.measurements->stream() << measurements_text;
    group.push_back(outputs.measurements.get());
  }
  if (outputs.relative) {
    outputs.relative->stream() << relative_text;
    group.push_back(outputs.relative.get());
  }
  if (outputs.report) {
    outputs.report->stream() << text;
    group.push_back(outputs.report.get());
  }
  // Standard output first: a report that could not be printed leaves no file.
  if (o.json) io::finish_standard_output("the report (--json)");
  stations.commit_with(group, "the adjusted stations");
}

}  // namespace

int run_adjust(const AdjustCommandOptions& o) {
  if (o.generate) return run_generate(o);
  check_options(o);
  const std::optional<std::string> helmert_path = helmert_output_path(o);
  workflow::AdjustRequest request = network_request(o.inputs, o.network, o.convention);
  auto& so = request.options;
  so.joint_covariance = o.sinex.has_value();
  so.preanalysis = o.preanalysis;
  so.external_reliability = !o.no_external_reliability;
  if (o.preanalysis) so.data_snooping = false;  // nothing to snoop: no residuals
  request.candidates = o.candidates;
  if (o.rank_by == "sigma-up") so.candidate_ranking = solver::CandidateRanking::sigma_up;
  so.jobs = o.jobs;
  request.relative = o.relative;
  request.standard = o.standard;
  if (o.max_memory_gb) so.memory_budget_bytes = static_cast<std::uint64_t>(std::max(1.0, *o.max_memory_gb * 1e9));
  refuse_shared_paths(o, helmert_path);
  AdjustOutputs outputs(o, helmert_path);

  const workflow::PreparedNetwork prepared = workflow::prepare_network(request);
  so.helmert = prepared.helmert;
  so.refraction_k = prepared.refraction_k;
  so.relative = prepared.relative;
  so.candidates = prepared.candidates;
  const solver::AdjustmentResult r = solver::adjust_network(prepared.network, so);
  const std::string text = workflow::report_text(prepared, r, so);
  show_report(o, outputs, prepared, r, so, text);
  if (refuse_results(o, prepared, r)) return exit_code(ErrorKind::rejected);
  write_outputs(o, outputs, prepared, r, so, helmert_path, text);
  return 0;
}

}  // namespace geoanchor::cli
