// The canonical order of a network's measurements (network_canonical_order.hpp).

#include "network_canonical_order.hpp"

#include <algorithm>
#include <charconv>
#include <numeric>

namespace geoanchor::solver {

namespace {

// Measurement a before b by what it is, apart from its direction set:
// kind, stations (by name), values, instrument and target heights,
// covariance, then frame, group, solution, variance scales and whether it
// is ignored; < 0, 0 (equal content: such twins are interchangeable), > 0.
int compare_content(const geodesy::Network& net, const geodesy::NetworkMeasurement& ma, const geodesy::NetworkMeasurement& mb) {
  const auto three_way = [](auto x, auto y) { return x < y ? -1 : y < x ? 1 : 0; };
  if (ma.kind != mb.kind) return three_way(ma.kind, mb.kind);
  if (ma.stations.size() != mb.stations.size()) return three_way(ma.stations.size(), mb.stations.size());
  for (std::size_t k = 0; k < ma.stations.size(); ++k) {
    const int c = net.stations[ma.stations[k]].id.compare(net.stations[mb.stations[k]].id);
    if (c != 0) return c < 0 ? -1 : 1;
  }
  if (ma.value.size() != mb.value.size()) return three_way(ma.value.size(), mb.value.size());
  for (Eigen::Index k = 0; k < ma.value.size(); ++k) {
    if (ma.value(k) != mb.value(k)) return three_way(ma.value(k), mb.value(k));
  }
  if (ma.instrument_height_m != mb.instrument_height_m) return three_way(ma.instrument_height_m, mb.instrument_height_m);
  if (ma.target_height_m != mb.target_height_m) return three_way(ma.target_height_m, mb.target_height_m);
  if (ma.covariance.size() != mb.covariance.size()) return three_way(ma.covariance.size(), mb.covariance.size());
  for (Eigen::Index k = 0; k < ma.covariance.size(); ++k) {
    if (ma.covariance(k) != mb.covariance(k)) return three_way(ma.covariance(k), mb.covariance(k));
  }
  if (ma.frame != mb.frame) {
    if (ma.frame.has_value() != mb.frame.has_value()) return ma.frame.has_value() ? 1 : -1;
    const int c = ma.frame->to_string().compare(mb.frame->to_string());
    if (c != 0) return c < 0 ? -1 : 1;
  }
  if (const int c = ma.group.compare(mb.group); c != 0) return c < 0 ? -1 : 1;
  if (ma.solution != mb.solution) return three_way(ma.solution, mb.solution);
  for (int k = 0; k < 3; ++k) {
    if (ma.local_variance_scale(k) != mb.local_variance_scale(k)) return three_way(ma.local_variance_scale(k), mb.local_variance_scale(k));
  }
  // An observation set's parts: their stations and values are the set's
  // (above), their kinds and heights here.
  if (ma.parts.size() != mb.parts.size()) return three_way(ma.parts.size(), mb.parts.size());
  for (std::size_t k = 0; k < ma.parts.size(); ++k) {
    const auto& pa = ma.parts[k];
    const auto& pb = mb.parts[k];
    if (pa.kind != pb.kind) return three_way(pa.kind, pb.kind);
    if (pa.instrument_height_m != pb.instrument_height_m) return three_way(pa.instrument_height_m, pb.instrument_height_m);
    if (pa.target_height_m != pb.target_height_m) return three_way(pa.target_height_m, pb.target_height_m);
  }
  return three_way(ma.ignore, mb.ignore);
}

}  // namespace

std::vector<std::size_t> canonical_set_order(const geodesy::Network& net) {
  std::vector<std::vector<std::size_t>> members(net.direction_sets.size());
  for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) {
    for (const auto& part : geodesy::parts_of(net.measurements[mi])) {
      if (part.set && *part.set < members.size()) members[*part.set].push_back(mi);
    }
  }
  for (auto& list : members) {
    std::stable_sort(list.begin(), list.end(), [&](std::size_t a, std::size_t b) {
      return compare_content(net, net.measurements[a], net.measurements[b]) < 0;
    });
  }
  std::vector<std::size_t> sets(net.direction_sets.size());
  std::iota(sets.begin(), sets.end(), std::size_t{0});
  std::stable_sort(sets.begin(), sets.end(), [&](std::size_t a, std::size_t b) {
    const int c = net.stations[net.direction_sets[a].station].id.compare(net.stations[net.direction_sets[b].station].id);
    if (c != 0) return c < 0;
    const auto& la = members[a];
    const auto& lb = members[b];
    for (std::size_t k = 0; k < la.size() && k < lb.size(); ++k) {
      const int d = compare_content(net, net.measurements[la[k]], net.measurements[lb[k]]);
      if (d != 0) return d < 0;
    }
    return la.size() < lb.size();
  });
  return sets;
}

std::vector<std::size_t> set_ranks(const std::vector<std::size_t>& set_order) {
  std::vector<std::size_t> rank(set_order.size());
  for (std::size_t k = 0; k < set_order.size(); ++k) rank[set_order[k]] = k;
  return rank;
}

std::size_t direction_set_rank(const geodesy::NetworkMeasurement& m, const std::vector<std::size_t>& ranks) {
  for (const auto& part : geodesy::parts_of(m)) {
    if (part.set && *part.set < ranks.size()) return ranks[*part.set] + 1;
  }
  return 0;
}

std::vector<std::size_t> canonical_order(const geodesy::Network& net, const std::vector<std::size_t>& set_order) {
  const std::vector<std::size_t> rank = set_ranks(set_order);
  const auto set_rank = [&](const geodesy::NetworkMeasurement& m) { return direction_set_rank(m, rank); };
  std::vector<std::size_t> order(net.measurements.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const auto& ma = net.measurements[a];
    const auto& mb = net.measurements[b];
    const int c = compare_content(net, ma, mb);
    return c != 0 ? c < 0 : set_rank(ma) < set_rank(mb);
  });
  return order;
}

std::string measurement_key(const geodesy::Network& net, const geodesy::NetworkMeasurement& m, std::size_t set_rank) {
  std::string key = geodesy::to_string(m.kind);
  for (std::size_t s : m.stations) key += "\x1f" + net.stations[s].id;
  char buf[40];
  const auto add = [&](double x) {
    const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, x, std::chars_format::hex);
    key += '\x1f';
    key.append(buf, ec == std::errc() ? end : buf);
  };
  for (Eigen::Index k = 0; k < m.value.size(); ++k) add(m.value(k));
  add(m.instrument_height_m);
  add(m.target_height_m);
  for (Eigen::Index k = 0; k < m.covariance.size(); ++k) add(m.covariance(k));
  key += "\x1f" + (m.frame ? m.frame->to_string() : std::string()) + "\x1f" + m.group + "\x1f" + std::to_string(set_rank);
  key += "\x1f" + (m.solution ? std::to_string(static_cast<int>(*m.solution)) : std::string());
  for (int k = 0; k < 3; ++k) add(m.local_variance_scale(k));
  for (const auto& part : m.parts) {
    key += "\x1f" + std::string(geodesy::to_string(part.kind));
    add(part.instrument_height_m);
    add(part.target_height_m);
  }
  key += m.ignore ? "\x1fignored" : "";
  return key;
}

}  // namespace geoanchor::solver
