// Accuracy standards: reading and verdicts (accuracy_standard.hpp).

#include "geoanchor/workflow/accuracy_standard.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/json_input.hpp"

namespace geoanchor::workflow {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kSchema = "geoanchor.accuracy-standard/1";

[[noreturn]] void refuse(const std::string& source, const std::string& key, const std::string& what) {
  throw Error(ErrorKind::input, "E_STANDARD", source + ": " + key + ": " + what);
}

std::string value_text(const json& v) { return v.dump(); }

const json& member(const json& object, const char* key, const std::string& source, const std::string& path) {
  const auto it = object.find(key);
  if (it == object.end()) refuse(source, path + key, "missing (docs/standards.md lists the fields)");
  return *it;
}

std::string string_member(const json& object, const char* key, const std::string& source, const std::string& path) {
  const json& v = member(object, key, source, path);
  if (!v.is_string() || v.get<std::string>().empty()) refuse(source, path + key, value_text(v) + " is not a text");
  return v.get<std::string>();
}

// A finite number in [lo, hi] (open at the ends `open_lo`, `open_hi`).
double number_member(const json& object, const char* key, const std::string& source, const std::string& path, double lo, double hi,
                     bool open_lo, bool open_hi, const char* expected) {
  const json& v = member(object, key, source, path);
  if (!v.is_number()) refuse(source, path + key, value_text(v) + " is not a number (expected " + expected + ")");
  const double x = v.get<double>();
  const bool inside = std::isfinite(x) && (open_lo ? x > lo : x >= lo) && (open_hi ? x < hi : x <= hi);
  if (!inside) refuse(source, path + key, value_text(v) + " is not " + expected);
  return x;
}

void only_keys(const json& object, std::initializer_list<const char*> keys, const std::string& source, const std::string& path) {
  for (const auto& [k, v] : object.items()) {
    if (std::none_of(keys.begin(), keys.end(), [&](const char* a) { return k == a; })) {
      std::string known;
      for (const char* a : keys) known += (known.empty() ? "" : ", ") + std::string(a);
      refuse(source, path + k, "unknown key (value " + value_text(v) + "; expected one of " + known + ")");
    }
  }
}

const char* const kCriteria[] = {"relative_horizontal", "relative_vertical", "positional_horizontal", "positional_vertical"};
// The quantity each criterion measures.
const StandardQuantity kCriterionQuantity[] = {StandardQuantity::relative_ellipse_semi_major, StandardQuantity::relative_up,
                                               StandardQuantity::ellipse_semi_major, StandardQuantity::up};

StandardCriterion parse_criterion(const json& c, std::size_t which, const std::string& source) {
  const std::string path = std::string("criteria.") + kCriteria[which] + ".";
  if (!c.is_object()) refuse(source, path.substr(0, path.size() - 1), value_text(c) + " is not an object");
  const bool relative = which < 2;
  if (relative) {
    only_keys(c, {"quantity", "definition", "confidence", "constant_m", "ppm", "distance"}, source, path);
  } else {
    only_keys(c, {"quantity", "definition", "confidence", "constant_m"}, source, path);
  }
  StandardCriterion k;
  const std::string quantity = string_member(c, "quantity", source, path);
  k.quantity = kCriterionQuantity[which];
  if (quantity != quantity_key(k.quantity)) {
    refuse(source, path + "quantity", "\"" + quantity + "\" (expected \"" + quantity_key(k.quantity) + "\" for " + kCriteria[which] + ")");
  }
  k.definition = string_member(c, "definition", source, path);
  k.confidence = number_member(c, "confidence", source, path, 0.0, 1.0, true, true, "a probability in (0, 1)");
  k.constant_m = number_member(c, "constant_m", source, path, 0.0, 1e6, false, false, "metres in [0, 1e6]");
  if (relative) {
    k.ppm = number_member(c, "ppm", source, path, 0.0, 1e6, false, false, "parts per million in [0, 1e6]");
    const std::string d = string_member(c, "distance", source, path);
    if (d == "spatial") {
      k.distance = StandardDistance::spatial;
    } else if (d == "horizontal") {
      k.distance = StandardDistance::horizontal;
    } else {
      refuse(source, path + "distance", "\"" + d + "\" (expected \"spatial\" or \"horizontal\")");
    }
  }
  return k;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(ErrorKind::io, "E_READ", path.string() + ": cannot open the standard: " + std::strerror(errno));
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The achieved value of a criterion for a pair or a station.
double achieved(const StandardCriterion& c, double semi_major_1sigma_m, double sigma_up_m) {
  switch (c.quantity) {
    case StandardQuantity::relative_ellipse_semi_major:
    case StandardQuantity::ellipse_semi_major:
      return solver::ellipse_confidence_scale(c.confidence) * semi_major_1sigma_m;
    case StandardQuantity::relative_up:
    case StandardQuantity::up:
      return solver::interval_confidence_scale(c.confidence) * sigma_up_m;
  }
  return 0.0;
}

}  // namespace

const char* quantity_key(StandardQuantity q) {
  switch (q) {
    case StandardQuantity::relative_ellipse_semi_major: return "relative_ellipse_semi_major";
    case StandardQuantity::relative_up: return "relative_up";
    case StandardQuantity::ellipse_semi_major: return "ellipse_semi_major";
    case StandardQuantity::up: return "up";
  }
  return "?";
}

std::string criterion_text(const StandardCriterion& c) {
  const std::string conf = format_shortest(100.0 * c.confidence) + " %";
  std::string q;
  switch (c.quantity) {
    case StandardQuantity::relative_ellipse_semi_major: q = "semi-major axis of the " + conf + " relative error ellipse"; break;
    case StandardQuantity::relative_up: q = "half-width of the " + conf + " interval of the up difference"; break;
    case StandardQuantity::ellipse_semi_major: q = "semi-major axis of the station's " + conf + " error ellipse"; break;
    case StandardQuantity::up: q = "half-width of the station's " + conf + " up interval"; break;
  }
  std::string t = q + " <= " + format_shortest(c.constant_m * 1000.0) + " mm";
  const bool relative = c.quantity == StandardQuantity::relative_ellipse_semi_major || c.quantity == StandardQuantity::relative_up;
  if (relative && c.ppm > 0.0) {
    t += " + " + format_shortest(c.ppm) + " ppm of the " + (c.distance == StandardDistance::spatial ? "spatial" : "horizontal") + " distance";
  }
  return t;
}

AccuracyStandard parse_standard(std::string_view text, const std::string& source) {
  json j;
  try {
    j = io::parse_json_strict<json>(text, source);
  } catch (const Error& e) {
    throw Error(ErrorKind::input, "E_STANDARD", std::string(e.what()));
  }
  if (!j.is_object()) refuse(source, "(document)", "not a JSON object");
  only_keys(j, {"schema", "name", "title", "source", "criteria"}, source, "");
  const std::string schema = string_member(j, "schema", source, "");
  if (schema != kSchema) refuse(source, "schema", "\"" + schema + "\" (expected \"" + kSchema + "\")");
  AccuracyStandard s;
  s.file = source;
  s.name = string_member(j, "name", source, "");
  s.title = string_member(j, "title", source, "");
  s.source = string_member(j, "source", source, "");
  const json& criteria = member(j, "criteria", source, "");
  if (!criteria.is_object()) refuse(source, "criteria", value_text(criteria) + " is not an object");
  only_keys(criteria, {kCriteria[0], kCriteria[1], kCriteria[2], kCriteria[3]}, source, "criteria.");
  std::optional<StandardCriterion>* slots[] = {&s.relative_horizontal, &s.relative_vertical, &s.positional_horizontal,
                                               &s.positional_vertical};
  for (std::size_t k = 0; k < 4; ++k) {
    if (const auto it = criteria.find(kCriteria[k]); it != criteria.end()) *slots[k] = parse_criterion(*it, k, source);
  }
  if (criteria.empty()) refuse(source, "criteria", "{} holds no criterion (expected at least one of relative_horizontal, "
                                                   "relative_vertical, positional_horizontal, positional_vertical)");
  return s;
}

fs::path standards_folder() {
  std::vector<fs::path> tried;
  if (const char* d = std::getenv("GEOANCHOR_DATA_DIR"); d && *d) tried.push_back(fs::path(d) / "standards");
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) tried.push_back(exe.parent_path().parent_path() / "share" / "geoanchor" / "standards");
  tried.push_back(fs::path(GEOANCHOR_SOURCE_DATA_DIR) / "standards");
  std::string looked;
  for (const auto& p : tried) {
    if (fs::is_directory(p, ec)) return p;
    looked += (looked.empty() ? "" : ", ") + p.string();
  }
  throw Error(ErrorKind::io, "E_READ", "the accuracy standards shipped with geoanchor are not in " + looked +
                                           " (set GEOANCHOR_DATA_DIR to the folder that holds standards/)");
}

std::vector<std::string> standard_names() {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(standards_folder())) {
    if (e.path().extension() == ".json") names.push_back(e.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

AccuracyStandard load_standard(const std::string& name_or_file) {
  const bool path = name_or_file.find('/') != std::string::npos ||
                    (name_or_file.size() > 5 && name_or_file.compare(name_or_file.size() - 5, 5, ".json") == 0);
  if (path) return parse_standard(read_text(name_or_file), name_or_file);
  const std::vector<std::string> names = standard_names();
  if (std::find(names.begin(), names.end(), name_or_file) == names.end()) {
    std::string list;
    for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
    throw Error(ErrorKind::usage, "E_OPTION", "--standard " + name_or_file + ": no such standard (shipped: " + list +
                                                  "; or give a standard's JSON file, docs/standards.md)");
  }
  const fs::path file = standards_folder() / (name_or_file + ".json");
  AccuracyStandard s = parse_standard(read_text(file), file.string());
  if (s.name != name_or_file) refuse(file.string(), "name", "\"" + s.name + "\" (expected \"" + name_or_file + "\", the file's name)");
  return s;
}

StandardVerdicts judge_standard(const AccuracyStandard& standard, const solver::AdjustmentResult& r) {
  StandardVerdicts v;
  const auto take = [&v](const Verdict& x, const char* kind, const char* criterion, std::size_t index) {
    (x.pass() ? v.pass : v.fail) += 1;
    if (!v.worst || x.margin_m() < v.worst->margin_m()) {
      v.worst = x;
      v.worst_kind = kind;
      v.worst_criterion = criterion;
      v.worst_index = index;
    }
  };
  v.pair_horizontal.assign(r.relative.size(), std::nullopt);
  v.pair_vertical.assign(r.relative.size(), std::nullopt);
  for (std::size_t k = 0; k < r.relative.size(); ++k) {
    const solver::RelativePrecision& rp = r.relative[k];
    const auto judge = [&](const StandardCriterion& c) {
      const double d = c.distance == StandardDistance::spatial ? rp.distance_m : rp.horizontal_distance_m;
      return Verdict{achieved(c, rp.ellipse.semi_major_m, rp.sigma_up_m), c.constant_m + c.ppm * 1e-6 * d};
    };
    if (standard.relative_horizontal) take(*(v.pair_horizontal[k] = judge(*standard.relative_horizontal)), "pair", kCriteria[0], k);
    if (standard.relative_vertical) take(*(v.pair_vertical[k] = judge(*standard.relative_vertical)), "pair", kCriteria[1], k);
  }
  v.station_horizontal.assign(r.stations.size(), std::nullopt);
  v.station_vertical.assign(r.stations.size(), std::nullopt);
  for (std::size_t s = 0; s < r.stations.size(); ++s) {
    const solver::AdjustedStation& st = r.stations[s];
    if (!st.used) continue;
    const double sigma_up = std::sqrt(std::max(0.0, st.covariance_local_m2(2, 2)));
    const auto judge = [&](const StandardCriterion& c) { return Verdict{achieved(c, st.ellipse.semi_major_m, sigma_up), c.constant_m}; };
    if (standard.positional_horizontal) take(*(v.station_horizontal[s] = judge(*standard.positional_horizontal)), "station", kCriteria[2], s);
    if (standard.positional_vertical) take(*(v.station_vertical[s] = judge(*standard.positional_vertical)), "station", kCriteria[3], s);
  }
  return v;
}

}  // namespace geoanchor::workflow
