// adjust --relative, --standard and --relative-output: which pairs, the
// relative precision's CSV, and its sections of the text and JSON reports
// (adjust.hpp, adjust_outputs.hpp).

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <numeric>
#include <sstream>
#include <unordered_map>

#include "adjust_outputs.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/csv.hpp"
#include "geoanchor/workflow/adjust.hpp"

namespace geoanchor::workflow {

using namespace adjust_detail;
using geodesy::NetworkSpace;

namespace {

// Pairs of a pairs file, resolved against the network's ids.
std::vector<std::pair<std::size_t, std::size_t>> read_pairs(const std::string& file, const geodesy::Network& net) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw Error(ErrorKind::io, "E_READ", "--relative pairs:" + file + ": cannot be read");
  io::CsvReader csv(in, file);
  const std::vector<std::string> expected = {"from", "to"};
  if (csv.header() != expected) {
    std::string got;
    for (const auto& h : csv.header()) got += (got.empty() ? "" : ",") + h;
    throw Error(ErrorKind::input, "E_PAIRS", file + ":" + std::to_string(csv.header_line()) + ": header \"" + got +
                                                 "\"; expected \"from,to\" (a pair of station ids per row, docs/commands/adjust.md)");
  }
  std::unordered_map<std::string, std::size_t> index;
  for (std::size_t s = 0; s < net.stations.size(); ++s) index.emplace(net.stations[s].id, s);
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  std::map<std::pair<std::size_t, std::size_t>, std::size_t> seen;  // pair → its line
  io::CsvRecord rec;
  while (csv.next(rec)) {
    if (rec.is_comment) continue;
    std::size_t ends[2];
    for (int k = 0; k < 2; ++k) {
      const std::string& id = rec.values[static_cast<std::size_t>(k)];
      const auto it = index.find(id);
      if (it == index.end()) {
        throw Error(ErrorKind::input, "E_PAIRS", file + ":" + std::to_string(rec.line) + ": " + expected[static_cast<std::size_t>(k)] +
                                                     " \"" + id + "\" is no station of the network");
      }
      ends[k] = it->second;
    }
    if (ends[0] == ends[1]) {
      throw Error(ErrorKind::input, "E_PAIRS", file + ":" + std::to_string(rec.line) + ": \"" + rec.values[0] +
                                                   "\" is paired with itself; a pair is two stations");
    }
    const auto key = std::make_pair(std::min(ends[0], ends[1]), std::max(ends[0], ends[1]));
    if (const auto [it, fresh] = seen.emplace(key, rec.line); !fresh) {
      throw Error(ErrorKind::input, "E_PAIRS", file + ":" + std::to_string(rec.line) + ": the pair " + rec.values[0] + "," +
                                                   rec.values[1] + " is given again (first at line " + std::to_string(it->second) + ")");
    }
    pairs.push_back({ends[0], ends[1]});
  }
  return pairs;
}

std::string mm(double m) { return format_fixed(m * 1000.0, 1); }

// v to two significant digits (ppm in the text report).
std::string two_digits(double v) {
  if (v == 0.0 || !std::isfinite(v)) return format_shortest(v);
  const int exponent = static_cast<int>(std::floor(std::log10(std::abs(v))));
  const double scale = std::pow(10.0, 1 - exponent);
  return format_fixed(std::round(v * scale) / scale, std::max(0, 1 - exponent));
}

// What the pairs' components mean in this network: a 1-D local network
// has no horizontal ellipse, a 2-D one no up.
struct Components {
  bool horizontal = true, up = true;
};
Components components(const geodesy::Network& net) {
  if (net.space == NetworkSpace::ellipsoidal) return {};
  return {net.local_dimensions >= 2, net.local_dimensions != 2};
}

std::string finite_field(double v, int decimals, const char* what) {
  if (!std::isfinite(v)) throw Error(ErrorKind::rejected, "E_RELATIVE", std::string("the relative precision's ") + what + " is not finite");
  return format_fixed(v, decimals);
}

std::string pair_name(const solver::AdjustmentResult& r, const solver::RelativePrecision& rp) {
  return r.stations[rp.from].id + " - " + r.stations[rp.to].id;
}

}  // namespace

solver::RelativeOptions relative_options(const std::string& spec, const geodesy::Network& net) {
  solver::RelativeOptions o;
  const auto colon = spec.find(':');
  const std::string kind = spec.substr(0, colon), arg = colon == std::string::npos ? "" : spec.substr(colon + 1);
  const auto bad = [&spec](const std::string& why) {
    return Error(ErrorKind::usage, "E_OPTION", "--relative " + spec + ": " + why +
                                                   " (expected connected, all, radius:R_M or pairs:FILE)");
  };
  if (kind == "connected" && colon == std::string::npos) {
    o.pairs = solver::RelativePairs::connected;
  } else if (kind == "all" && colon == std::string::npos) {
    o.pairs = solver::RelativePairs::all;
    const std::size_t n = net.stations.size();
    const std::size_t count = n < 2 ? 0 : n * (n - 1) / 2;
    if (count > solver::kMaxAllRelativePairs) {
      throw Error(ErrorKind::usage, "E_OPTION", "--relative all: " + std::to_string(n) + " stations make " + std::to_string(count) +
                                                    " pairs, more than " + std::to_string(solver::kMaxAllRelativePairs) +
                                                    "; give --relative radius:R_M (the pairs within R metres) or pairs:FILE");
    }
  } else if (kind == "radius") {
    const std::optional<double> r = parse_finite_double(arg);
    if (!r || *r <= 0.0) throw bad("'" + arg + "' is not a radius in metres > 0");
    o.pairs = solver::RelativePairs::radius;
    o.radius_m = *r;
  } else if (kind == "pairs") {
    if (arg.empty()) throw bad("give the pairs' CSV file after pairs:");
    o.pairs = solver::RelativePairs::listed;
    o.listed = read_pairs(arg, net);
  } else {
    throw bad("unknown");
  }
  return o;
}

std::string relative_csv(const PreparedNetwork& prepared, const solver::AdjustmentResult& r, const solver::AdjustOptions& o) {
  const auto& net = prepared.network;
  const Components has = components(net);
  const AccuracyStandard* standard = prepared.standard.get();
  const std::optional<StandardVerdicts> verdicts = standard ? std::optional(judge_standard(*standard, r)) : std::nullopt;
  std::string header_line;
  {
    std::ostringstream h;
    if (standard) {
      h << "# standard " << standard->name << ": " << standard->title << "\n";
      if (standard->relative_horizontal) h << "# h_*: " << criterion_text(*standard->relative_horizontal) << "\n";
      if (standard->relative_vertical) h << "# v_*: " << criterion_text(*standard->relative_vertical) << "\n";
    }
    header_line = h.str();
  }
  std::ostringstream body;
  body << "# relative precision of to - from in the local horizon of from ("
       << (net.space == NetworkSpace::ellipsoidal ? "east, north, up; azimuth from north towards east" : "x, y, z; azimuth from +x towards +y")
       << "); pairs: " << prepared.relative_spec << "\n";
  body << "# sigmas from the a-priori weights (sigma0 = 1); ellipse_conf and up_conf at " << format_shortest(100.0 * o.confidence) << " %\n";
  if (!has.horizontal) body << "# a 1-D network: the ellipse fields are empty\n";
  if (!has.up) body << "# a 2-D network: the up fields are empty\n";
  body << header_line;
  body << "from,to,distance_m,horizontal_distance_m,sigma_distance_m,ellipse_a_m,ellipse_b_m,ellipse_azimuth_deg,ellipse_conf_a_m,"
          "ellipse_conf_b_m,sigma_up_m,up_conf_m";
  const bool h_cols = standard && standard->relative_horizontal, v_cols = standard && standard->relative_vertical;
  if (h_cols) body << ",h_achieved_m,h_allowed_m,h_margin_mm,h_verdict";
  if (v_cols) body << ",v_achieved_m,v_allowed_m,v_margin_mm,v_verdict";
  body << "\n";
  for (std::size_t k = 0; k < r.relative.size(); ++k) {
    const auto& rp = r.relative[k];
    body << csv_field(r.stations[rp.from].id) << ',' << csv_field(r.stations[rp.to].id) << ',' << finite_field(rp.distance_m, 6, "distance")
         << ',' << finite_field(rp.horizontal_distance_m, 6, "horizontal distance") << ','
         << finite_field(rp.sigma_distance_m, 6, "sigma of the distance") << ',';
    if (has.horizontal) {
      body << finite_field(rp.ellipse.semi_major_m, 6, "ellipse") << ',' << finite_field(rp.ellipse.semi_minor_m, 6, "ellipse") << ','
           << finite_field(rp.ellipse.azimuth_rad * kRadToDeg, 3, "ellipse") << ','
           << finite_field(rp.ellipse_confidence.semi_major_m, 6, "ellipse") << ','
           << finite_field(rp.ellipse_confidence.semi_minor_m, 6, "ellipse") << ',';
    } else {
      body << ",,,,,";
    }
    if (has.up) {
      body << finite_field(rp.sigma_up_m, 6, "up sigma") << ',' << finite_field(rp.up_confidence_m, 6, "up interval");
    } else {
      body << ',';
    }
    const auto verdict = [&](const std::optional<Verdict>& v) {
      body << ',' << finite_field(v->achieved_m, 6, "achieved value") << ',' << finite_field(v->allowed_m, 6, "allowed value") << ','
           << finite_field(v->margin_m() * 1000.0, 3, "margin") << ',' << (v->pass() ? "PASS" : "FAIL");
    };
    if (h_cols) verdict(verdicts->pair_horizontal[k]);
    if (v_cols) verdict(verdicts->pair_vertical[k]);
    body << "\n";
  }
  return body.str();
}

namespace adjust_detail {

void relative_report_text(std::ostream& out, const PreparedNetwork& prepared, const solver::AdjustmentResult& r,
                          const solver::AdjustOptions& o) {
  const Components has = components(prepared.network);
  const std::string conf = format_shortest(100.0 * o.confidence) + " %";
  out << "\nRelative precision (" << prepared.relative_spec << ": " << r.relative.size() << " pair" << (r.relative.size() == 1 ? "" : "s")
      << "; from the a-priori weights, sigma0 = 1; in the horizon of the first station)\n";
  const AccuracyStandard* standard = prepared.standard.get();
  const std::optional<StandardVerdicts> v = standard ? std::optional(judge_standard(*standard, r)) : std::nullopt;
  // The worst pairs: by the standard's margin, else by the relative ellipse at the confidence.
  std::vector<std::size_t> order(r.relative.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  const auto key = [&](std::size_t k) {
    if (v && v->pair_horizontal[k]) return -v->pair_horizontal[k]->margin_m();
    if (v && v->pair_vertical[k]) return -v->pair_vertical[k]->margin_m();
    return has.horizontal ? r.relative[k].ellipse_confidence.semi_major_m : r.relative[k].up_confidence_m;
  };
  constexpr std::size_t kShown = 10;
  const std::size_t shown = std::min(kShown, order.size());
  std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(shown), order.end(),
                    [&](std::size_t a, std::size_t b) { return key(a) != key(b) ? key(a) > key(b) : a < b; });
  if (shown > 0) out << "  the " << shown << " worst, in mm at " << conf << ":\n";
  for (std::size_t i = 0; i < shown; ++i) {
    const auto& rp = r.relative[order[i]];
    out << "    " << pair_name(r, rp) << ": " << format_fixed(rp.distance_m, 3) << " m";
    if (has.horizontal) {
      out << ", ellipse a " << mm(rp.ellipse_confidence.semi_major_m) << " b " << mm(rp.ellipse_confidence.semi_minor_m) << " ("
          << two_digits(rp.ellipse_confidence.semi_major_m / std::max(rp.distance_m, 1e-9) * 1e6) << " ppm)";
    }
    if (has.up) out << ", up " << mm(rp.up_confidence_m);
    out << ", sigma distance " << mm(rp.sigma_distance_m);
    if (v && v->pair_horizontal[order[i]]) {
      const Verdict& x = *v->pair_horizontal[order[i]];
      out << "; " << (x.pass() ? "PASS" : "FAIL") << " margin " << mm(x.margin_m());
    }
    out << "\n";
  }
  if (!v) return;
  out << "\nStandard " << standard->name << ": " << standard->title << "\n";
  out << "  source: " << standard->source << "\n";
  if (standard->relative_horizontal) out << "  pairs: " << criterion_text(*standard->relative_horizontal) << "\n";
  if (standard->relative_vertical) out << "  pairs, up: " << criterion_text(*standard->relative_vertical) << "\n";
  if (standard->positional_horizontal) out << "  stations: " << criterion_text(*standard->positional_horizontal) << "\n";
  if (standard->positional_vertical) out << "  stations, up: " << criterion_text(*standard->positional_vertical) << "\n";
  out << "  (judged at the standard's confidence, whatever --confidence is)\n";
  out << "  " << v->pass << " PASS, " << v->fail << " FAIL";
  if (v->worst) {
    const std::string where = v->worst_kind == "pair" ? pair_name(r, r.relative[v->worst_index]) : r.stations[v->worst_index].id;
    out << "; worst margin " << mm(v->worst->margin_m()) << " mm (" << v->worst_criterion << ", " << where << ": achieved "
        << mm(v->worst->achieved_m) << " mm, allowed " << mm(v->worst->allowed_m) << " mm)";
  }
  out << "\n";
}

void relative_report_document(nlohmann::ordered_json& j, const PreparedNetwork& prepared, const solver::AdjustmentResult& r,
                              const solver::AdjustOptions& o, bool full) {
  using nlohmann::ordered_json;
  const Components has = components(prepared.network);
  const AccuracyStandard* standard = prepared.standard.get();
  const std::optional<StandardVerdicts> v = standard ? std::optional(judge_standard(*standard, r)) : std::nullopt;
  auto num = [](double x) { return std::isfinite(x) ? ordered_json(x) : ordered_json(nullptr); };
  auto verdict = [&](const std::optional<Verdict>& x) {
    return ordered_json{{"achieved_m", num(x->achieved_m)},
                        {"allowed_m", num(x->allowed_m)},
                        {"margin_mm", num(x->margin_m() * 1000.0)},
                        {"verdict", x->pass() ? "PASS" : "FAIL"}};
  };
  j["relative_pairs"] = {{"pairs", prepared.relative_spec}, {"count", r.relative.size()}, {"confidence", o.confidence}};
  if (full) {
    ordered_json pairs = ordered_json::array();
    for (std::size_t k = 0; k < r.relative.size(); ++k) {
      const auto& rp = r.relative[k];
      ordered_json x = {{"from", r.stations[rp.from].id},
                        {"to", r.stations[rp.to].id},
                        {"distance_m", num(rp.distance_m)},
                        {"horizontal_distance_m", num(rp.horizontal_distance_m)},
                        {"sigma_distance_m", num(rp.sigma_distance_m)}};
      if (has.horizontal) {
        x["ellipse"] = {{"a_m", num(rp.ellipse.semi_major_m)},
                        {"b_m", num(rp.ellipse.semi_minor_m)},
                        {"azimuth_deg", num(rp.ellipse.azimuth_rad * kRadToDeg)}};
        x["ellipse_confidence"] = {{"a_m", num(rp.ellipse_confidence.semi_major_m)},
                                   {"b_m", num(rp.ellipse_confidence.semi_minor_m)},
                                   {"confidence", o.confidence}};
      }
      if (has.up) {
        x["sigma_up_m"] = num(rp.sigma_up_m);
        x["up_confidence_m"] = num(rp.up_confidence_m);
      }
      if (v) {
        ordered_json s = ordered_json::object();
        if (v->pair_horizontal[k]) s["relative_horizontal"] = verdict(v->pair_horizontal[k]);
        if (v->pair_vertical[k]) s["relative_vertical"] = verdict(v->pair_vertical[k]);
        x["standard"] = std::move(s);
      }
      pairs.push_back(std::move(x));
    }
    j["relative"] = std::move(pairs);
  }
  if (!v) return;
  ordered_json criteria = ordered_json::object();
  const auto criterion = [&](const char* name, const std::optional<StandardCriterion>& c) {
    if (!c) return;
    ordered_json x = {{"quantity", quantity_key(c->quantity)}, {"confidence", c->confidence}, {"constant_m", c->constant_m}};
    if (c->quantity == StandardQuantity::relative_ellipse_semi_major || c->quantity == StandardQuantity::relative_up) {
      x["ppm"] = c->ppm;
      x["distance"] = c->distance == StandardDistance::spatial ? "spatial" : "horizontal";
    }
    x["in_words"] = criterion_text(*c);
    x["definition"] = c->definition;
    criteria[name] = std::move(x);
  };
  criterion("relative_horizontal", standard->relative_horizontal);
  criterion("relative_vertical", standard->relative_vertical);
  criterion("positional_horizontal", standard->positional_horizontal);
  criterion("positional_vertical", standard->positional_vertical);
  ordered_json s = {{"name", standard->name}, {"title", standard->title}, {"source", standard->source}, {"file", standard->file},
                    {"criteria", std::move(criteria)}, {"pass", v->pass}, {"fail", v->fail}};
  if (v->worst) {
    ordered_json w = {{"criterion", v->worst_criterion}, {"margin_mm", num(v->worst->margin_m() * 1000.0)},
                      {"achieved_m", num(v->worst->achieved_m)}, {"allowed_m", num(v->worst->allowed_m)}};
    if (v->worst_kind == "pair") {
      w["from"] = r.stations[r.relative[v->worst_index].from].id;
      w["to"] = r.stations[r.relative[v->worst_index].to].id;
    } else {
      w["station"] = r.stations[v->worst_index].id;
    }
    s["worst"] = std::move(w);
  } else {
    s["worst"] = nullptr;
  }
  if (full && (standard->positional_horizontal || standard->positional_vertical)) {
    ordered_json st = ordered_json::array();
    for (std::size_t i = 0; i < r.stations.size(); ++i) {
      if (!v->station_horizontal[i] && !v->station_vertical[i]) continue;
      ordered_json x = {{"id", r.stations[i].id}};
      if (v->station_horizontal[i]) x["positional_horizontal"] = verdict(v->station_horizontal[i]);
      if (v->station_vertical[i]) x["positional_vertical"] = verdict(v->station_vertical[i]);
      st.push_back(std::move(x));
    }
    s["stations"] = std::move(st);
  }
  j["standard"] = std::move(s);
}

}  // namespace adjust_detail

}  // namespace geoanchor::workflow
