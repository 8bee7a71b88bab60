// `geoanchor apply` as a library (apply.hpp): a run's inputs (files,
// folders, manifests, --exclude, --shard), its tiles on threads and its run
// summary; one tile's work is TileRunner's (apply_tile.hpp).
#include "geoanchor/workflow/apply.hpp"

#include <nlohmann/json.hpp>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <ctime>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <thread>

#include "apply_tile.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/base/utf8.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/base/hash.hpp"
#include "geoanchor/io/tile/tile_apply.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "geoanchor/workflow/transform_checks.hpp"
#include "geoanchor/workflow/tile_plan.hpp"
#include "map_files.hpp"

namespace geoanchor::workflow {
namespace {

namespace fs = std::filesystem;
using apply_detail::TileRunner;
using geodesy::DecimalYear;
using nlohmann::json;

constexpr char kSummarySchema[] = "geoanchor.apply-summary/1";
constexpr int kRunSummaryAttempts = 100;  // run summaries of one name: same second, same pid, other hosts

// ---------------------------------------------------------------- inputs

bool is_manifest(const fs::path& p) {
  const auto e = p.extension().string();
  return e == ".txt" || e == ".lst" || e == ".manifest";
}

bool is_tile(const fs::path& p) {
  const std::string name = p.filename().string();
  if (name.size() > 15 && name.ends_with(".geoanchor.json")) return false;
  return io::tile_format_of(p).has_value();
}

using detail::excluded_by;
using detail::is_run_summary;
using detail::kSidecarSuffix;
constexpr std::string_view kTileKinds = ".las, .laz, .copc.laz, .csv, .txt, .ply, .geojson, .osm or .xodr";
constexpr std::size_t kUnknownListed = 20;  // names in the message; the rest counted

// The inputs of a run: its tiles, in order, and the files --exclude left out.
struct Inputs {
  std::vector<fs::path> tiles;
  std::vector<std::string> excluded;
};

// Files, folders (their tiles, recursively, sorted) and manifests (one path
// per line, relative to the manifest's folder; '#' starts a comment), in
// the order given, each tile once. A folder's files that are neither tiles
// nor a tile's sidecar (nor geoanchor's run summaries and temporaries) are
// an error naming them, unless --exclude leaves them out.
Inputs expand_inputs(const std::vector<std::string>& inputs, const std::vector<std::string>& exclude) {
  Inputs r;
  std::set<std::string> seen;
  for (const auto& g : exclude) {
    if (g.empty()) throw Error(ErrorKind::usage, "E_OPTION", "--exclude '': expected a glob such as '*.xyz' or 'raw/*'");
  }
  auto add = [&](const fs::path& p, const std::string& where) {
    // A tile's path goes into its sidecar and the run summary (JSON, UTF-8
    // only); geoanchor records no name other than the file's.
    if (const auto problem = utf8_problem(p.string())) {
      throw Error(ErrorKind::input, "E_PATH_NOT_UTF8",
                  where + ": " + p.string() + ": the file name is not valid UTF-8 (" + *problem +
                      "): tile paths are recorded in the sidecars and the run summary, which hold UTF-8 only; rename "
                      "it (from Latin-1: convmv -f latin1 -t utf-8 --notest NAME)");
    }
    if (!is_tile(p)) {
      throw Error(ErrorKind::usage, "E_INPUT",
                  where + ": " + p.string() + ": not a tile; expected " + std::string(kTileKinds) +
                      " (leave it out with --exclude GLOB)");
    }
    std::error_code ec;
    if (!fs::is_regular_file(p, ec)) throw Error(ErrorKind::io, "E_READ", where + ": " + p.string() + ": no such file");
    const std::string key = fs::weakly_canonical(p, ec).string();
    if (seen.insert(key).second) r.tiles.push_back(p);
  };
  std::vector<std::string> unknown;
  for (const auto& in : inputs) {
    const fs::path p(in);
    std::error_code ec;
    if (fs::is_directory(p, ec)) {
      // Every entry, sorted; the folder's own file names, to tell a tile's sidecar.
      std::vector<fs::directory_entry> entries;
      for (const auto& e : fs::recursive_directory_iterator(p, ec)) entries.push_back(e);
      if (ec) throw Error(ErrorKind::io, "E_READ", in + ": cannot list the folder: " + ec.message());
      std::sort(entries.begin(), entries.end(), [](const auto& a, const auto& b) { return a.path() < b.path(); });
      std::set<fs::path> names;
      for (const auto& e : entries) names.insert(e.path());
      for (const auto& e : entries) {
        std::error_code e_ec;
        const bool link = e.is_symlink(e_ec);
        if (e.is_directory(e_ec) && !link) continue;  // descended into
        const fs::path& f = e.path();
        const std::string name = f.filename().string();
        if (excluded_by(exclude, f.lexically_relative(p))) {
          r.excluded.push_back(f.string());
          continue;
        }
        const bool regular = e.is_regular_file(e_ec);
        if (regular && is_tile(f)) {
          add(f, in);
          continue;
        }
        // A tile's sidecar; geoanchor's own run summaries and temporaries.
        if (regular && name.size() > kSidecarSuffix.size() && name.ends_with(kSidecarSuffix)) {
          const fs::path tile = f.parent_path() / name.substr(0, name.size() - kSidecarSuffix.size());
          if (is_tile(tile) && names.count(tile)) continue;
        }
        if (regular && is_run_summary(name)) continue;
        if (io::is_temporary_name(name)) continue;
        std::string what;
        if (e.is_directory(e_ec)) {
          what = " (a link to a folder, not followed)";
        } else if (!regular) {
          what = fs::exists(e.symlink_status(e_ec)) && !fs::exists(f, e_ec) ? " (a dangling link)" : " (not a regular file)";
        } else if (name.ends_with(kSidecarSuffix)) {
          what = " (a sidecar without its tile)";
        }
        unknown.push_back(f.string() + what);
      }
    } else if (is_manifest(p) && !excluded_by(exclude, p)) {
      std::ifstream m(p);
      if (!m) throw Error(ErrorKind::io, "E_READ", in + ": cannot open manifest");
      std::string line;
      std::size_t n = 0;
      while (std::getline(m, line)) {
        ++n;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        const auto first = line.find_first_not_of(" \t");
        if (first == std::string::npos || line[first] == '#') continue;
        const auto last = line.find_last_not_of(" \t");
        const fs::path listed(line.substr(first, last - first + 1));
        fs::path entry = listed;
        if (entry.is_relative()) entry = p.parent_path() / entry;
        if (excluded_by(exclude, listed)) {
          r.excluded.push_back(entry.string());
          continue;
        }
        add(entry, in + ":" + std::to_string(n));
      }
    } else if (excluded_by(exclude, p)) {
      r.excluded.push_back(p.string());
    } else {
      add(p, "input");
    }
  }
  if (!unknown.empty()) {
    throw Error(ErrorKind::usage, "E_INPUT_UNKNOWN",
                std::to_string(unknown.size()) + (unknown.size() == 1 ? " file" : " files") +
                    " in the input folders " + (unknown.size() == 1 ? "is" : "are") + " neither a tile (" +
                    std::string(kTileKinds) + ") nor a tile's sidecar: " + detail::name_list(unknown, kUnknownListed) +
                    "; leave them out with --exclude GLOB (e.g. --exclude '*.xyz'), or convert them; nothing was "
                    "processed");
  }
  return r;
}

// "I/N", 0-based I.
std::pair<std::size_t, std::size_t> parse_shard(const std::string& s) {
  const auto slash = s.find('/');
  auto bad = [&](const std::string& why) {
    return Error(ErrorKind::usage, "E_OPTION", "--shard " + s + ": " + why + "; expected I/N with 0 <= I < N (I is 0-based, "
                                               "as SLURM_ARRAY_TASK_ID with --array=0-<N-1> or a Kubernetes "
                                               "JOB_COMPLETION_INDEX)");
  };
  if (slash == std::string::npos) throw bad("no '/'");
  const auto i = parse_finite_double(s.substr(0, slash));
  const auto n = parse_finite_double(s.substr(slash + 1));
  if (!i || !n || *i != std::floor(*i) || *n != std::floor(*n) || *n < 1 || *i < 0) throw bad("not two integers");
  if (*i >= *n) throw bad("I is not below N");
  return {static_cast<std::size_t>(*i), static_cast<std::size_t>(*n)};
}
}  // namespace

struct ApplyRun::Impl {
  ApplyRequest request;
  std::optional<io::TransformFile> transform;
  std::string transform_sha;
  std::vector<fs::path> tiles;
  std::vector<std::string> excluded;
  std::string shard_text, summary_base, run_id;
  std::uint64_t total_bytes = 0;
};

// This run's name among others into the same folder: its start in UTC and
// its process id, e.g. 20250301T101500Z-4242.
std::string make_run_id() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  ::gmtime_r(&now, &utc);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &utc);
  return std::string(stamp) + "-" + std::to_string(::getpid());
}

ApplyRun::ApplyRun(ApplyRequest request) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.request = std::move(request);
  const ApplyRequest& o = m.request;
  if (o.transform) {
    m.transform = io::read_transform_file(*o.transform);
    m.transform_sha = sha256_file_hex(*o.transform);
  }
  // The planner parses every value flag: a bad one fails before any output.
  const TilePlanner check(o, m.transform);
  Inputs inputs = expand_inputs(o.inputs, o.exclude);
  m.tiles = std::move(inputs.tiles);
  m.excluded = std::move(inputs.excluded);
  m.summary_base = std::string(detail::kRunSummaryStem);
  m.run_id = make_run_id();
  if (o.shard) {
    const auto [i, n] = parse_shard(*o.shard);
    std::vector<fs::path> mine;
    for (std::size_t k = i; k < m.tiles.size(); k += n) mine.push_back(m.tiles[k]);
    m.tiles = std::move(mine);
    m.shard_text = std::to_string(i) + "/" + std::to_string(n);
    m.summary_base = std::string(detail::kRunSummaryStem) + ".shard-" + std::to_string(i) + "-of-" + std::to_string(n);
  }
  // Two inputs must not write the same output (x.las and x.laz with
  // --format, x.laz and x.copc.laz); --format is checked against each tile.
  std::map<std::string, std::string> by_name;
  for (const auto& t : m.tiles) {
    const fs::path output = planned_output_path(o, t);
    const auto [it, fresh] = by_name.emplace(output.filename().string(), t.string());
    if (!fresh) {
      throw Error(ErrorKind::usage, "E_OUTPUT_CLASH",
                  t.string() + " and " + it->second + " would both be written to " + output.string() +
                      "; process them in separate runs");
    }
  }
  if (o.survey_metadata) (void)io::read_survey_metadata(*o.survey_metadata);  // a bad file fails before any tile
  if (m.tiles.empty() && !o.shard) throw Error(ErrorKind::usage, "E_INPUT", "no tiles to process");
  std::error_code ec;
  for (const auto& t : m.tiles) m.total_bytes += fs::file_size(t, ec);
  if (!fs::is_directory(o.out_dir, ec)) {
    // Created when missing (as mkdir -p); never a file in its place.
    if (fs::exists(o.out_dir, ec) || !fs::create_directories(o.out_dir, ec) || ec) {
      throw Error(ErrorKind::io, "E_OUTPUT_DIR",
                  "--out-dir " + o.out_dir + ": not a folder and cannot be created" +
                      (ec ? ": " + ec.message() : std::string()));
    }
  }
}

ApplyRun::~ApplyRun() = default;

std::size_t ApplyRun::tile_count() const { return impl_->tiles.size(); }
std::uint64_t ApplyRun::total_bytes() const { return impl_->total_bytes; }

ApplyResult ApplyRun::run(ApplyProgress& progress, const std::function<void(const TileOutcome&)>& on_tile) {
  const Impl& m = *impl_;
  const ApplyRequest& o = m.request;
  const TilePlanner planner(o, m.transform);
  const auto& tiles = m.tiles;
  ApplyResult result;
  // Tiles at once, and each one's share of the threads for its chunks.
  result.jobs = std::max(1u, std::min<unsigned>(o.jobs, static_cast<unsigned>(std::max<std::size_t>(tiles.size(), 1))));
  const TileRunner runner(o, planner, m.transform, m.transform_sha, progress, std::max(1u, o.jobs / result.jobs));
  result.excluded = m.excluded;

  // Temporaries a killed run left in the output folder, before any tile.
  for (const auto& t : io::remove_stale_temporaries(o.out_dir)) result.stale_temporaries_removed.push_back(t.string());
  const auto start = std::chrono::steady_clock::now();
  result.tiles.resize(tiles.size());
  std::atomic<std::size_t> next{0};
  std::mutex report;
  auto worker = [&] {
    for (std::size_t k; (k = next++) < tiles.size();) {
      result.tiles[k] = runner.run(tiles[k]);
      if (on_tile) {
        const std::lock_guard<std::mutex> lock(report);
        on_tile(result.tiles[k]);
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned j = 1; j < result.jobs; ++j) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // The run summary, written beside the outputs.
  json summary;
  summary["schema"] = kSummarySchema;
  summary["tool"] = o.tool;
  summary["command"] = o.command;
  summary["shard"] = o.shard ? json(m.shard_text) : json(nullptr);
  summary["transform"] = o.transform ? json(*o.transform) : json(nullptr);
  summary["transform_sha256"] = o.transform ? json(m.transform_sha) : json(nullptr);
  json list = json::array();
  for (const auto& r : result.tiles) {
    json t = {{"input", r.input}, {"output", r.output}, {"status", r.status}, {"points", r.points},
              {"seconds", r.seconds}, {"warnings", r.warnings}};
    if (r.status == "failed") {
      t["error"] = r.error;
      t["error_code"] = r.error_code;
      ++result.failed;
      if (result.exit_code == 0) result.exit_code = r.exit_code;
    } else if (r.status == "skipped") {
      ++result.skipped;
    } else {
      ++result.done;
      result.processed += r.points;
    }
    result.points += r.points;
    list.push_back(t);
  }
  summary["tiles"] = list;
  // The transform's implausible parameters, once for the run: a 14-parameter
  // set at the first and last epoch of the tiles done.
  if (m.transform) {
    std::optional<EpochSpan> span;
    for (const auto& r : result.tiles) {
      if (r.status != "done" || !r.transform_epochs_year) continue;
      const auto [first, last] = *r.transform_epochs_year;
      if (!span) span = EpochSpan{DecimalYear{first}, DecimalYear{last}};
      if (first < span->first.year) span->first = DecimalYear{first};
      if (last > span->last.year) span->last = DecimalYear{last};
    }
    result.warnings = implausible_transform_warnings(*m.transform, *o.transform, span);
  }
  summary["warnings"] = result.warnings;
  summary["tiles_done"] = result.done;
  summary["tiles_skipped"] = result.skipped;
  summary["tiles_failed"] = result.failed;
  summary["points"] = result.points;
  summary["seconds"] = result.seconds;
  summary["points_per_second"] = result.seconds > 0 ? static_cast<double>(result.processed) / result.seconds : 0.0;
  summary["jobs"] = result.jobs;
  summary["stale_temporaries_removed"] = result.stale_temporaries_removed;
  summary["excluded"] = result.excluded;
  // This run's summary under its own name, never replaced (published with
  // RENAME_NOREPLACE; a name another host took in the same second gets a
  // suffix), then the same text as the latest run's summary under the
  // name scripts read.
  const fs::path dir(o.out_dir);
  result.summary_path = dir / (m.summary_base + ".json");
  for (int attempt = 1;; ++attempt) {
    result.run_id = m.run_id + (attempt == 1 ? std::string() : "-" + std::to_string(attempt));
    result.run_summary_path = dir / (m.summary_base + "." + result.run_id + ".json");
    summary["run_id"] = result.run_id;
    summary["run_summary"] = result.run_summary_path.filename().string();
    result.summary_json = summary.dump(2) + "\n";
    try {
      io::AtomicOutputFile run_file(result.run_summary_path, io::Overwrite::refuse);
      run_file.stream() << result.summary_json;
      run_file.commit();
      break;
    } catch (const Error& e) {
      if (e.code() != "E_OUTPUT_EXISTS" || attempt >= kRunSummaryAttempts) throw;
    }
  }
  io::AtomicOutputFile summary_file(result.summary_path, io::Overwrite::allow);
  summary_file.stream() << result.summary_json;
  summary_file.commit();
  return result;
}

}  // namespace geoanchor::workflow
