// The network adjustment's problem (network_problem.hpp): the layout of its
// unknowns, each measurement's linearized rows, the constraints held with a
// standard deviation, and the corrections that move the state.

#include "network_problem.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "geoanchor/base/number_text.hpp"
#include "network_helmert.hpp"

namespace geoanchor::solver {

using geodesy::NetworkSpace;

const char* component_name(NetworkSpace space, int c) {
  static const char* ellipsoidal[] = {"east", "north", "up"};
  static const char* local[] = {"x", "y", "z"};
  return space == NetworkSpace::ellipsoidal ? ellipsoidal[c] : local[c];
}

// The local component a constraint letter holds: latitude, longitude,
// height are north, east, up; a local network's x, y, z are themselves.
int constrained_component(NetworkSpace space, int k) {
  if (space == NetworkSpace::local) return k;
  return k == 0 ? 1 : k == 1 ? 0 : 2;
}

// Whether a local network estimates component c.
bool estimated_component(const geodesy::Network& net, int c) {
  if (net.space == NetworkSpace::ellipsoidal || net.local_dimensions == 3) return true;
  return net.local_dimensions == 2 ? c < 2 : c == 2;
}

std::string fmt_m(double v) { return format_fixed(v, 4) + " m"; }

const char* const kHelmertNames[14] = {"tx", "ty", "tz", "rx", "ry", "rz", "ds", "dtx", "dty", "dtz", "drx", "dry", "drz", "dds"};

MeasurementRows NetworkProblem::linearize(std::size_t mi, const UnknownLayout& l) const {
  const auto& m = net.measurements[mi];
  const ModelContext ctx{net, o, states, orientations};
  Evaluation ev = evaluate(m, ctx);
  Eigen::MatrixXd d_helmert;
  const int member = helmert_slot.empty() ? -1 : helmert_slot[mi];
  if (member >= 0) {
    const HelmertGroup& g = *o.helmert;
    into_group_datum(ev, m.kind == geodesy::MeasurementKind::gnss_points, geocentric_form(helmert, helmert_pivot, g.rates), g.rates,
                     g.rates ? g.epochs[static_cast<std::size_t>(member)] - g.reference_epoch : 0.0, d_helmert);
  }
  MeasurementRows r;
  r.computed = ev.computed;
  // The columns in the order their unknowns first come (a measurement has
  // a handful: a linear search), in a matrix as wide as they can be.
  const Eigen::Index most =
      static_cast<Eigen::Index>(3 * ev.stations.size() + ev.orientation.size()) + d_helmert.cols();
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(ev.computed.size(), most);
  r.unknowns.reserve(static_cast<std::size_t>(most));
  auto column = [&](Index unknown) {
    for (std::size_t k = 0; k < r.unknowns.size(); ++k) {
      if (r.unknowns[k] == unknown) return static_cast<Eigen::Index>(k);
    }
    r.unknowns.push_back(unknown);
    return static_cast<Eigen::Index>(r.unknowns.size() - 1);
  };
  for (std::size_t s = 0; s < ev.stations.size(); ++s) {
    for (int c = 0; c < 3; ++c) {
      const Index u = l.station[ev.stations[s]][static_cast<std::size_t>(c)];
      if (u < 0) continue;
      const Eigen::Index k = column(u);
      a.col(k) += ev.d_local.col(static_cast<Eigen::Index>(3 * s + static_cast<std::size_t>(c)));
    }
  }
  for (const auto& [row, set] : ev.orientation) {
    const Eigen::Index k = column(l.orientation[set]);
    a(row, k) -= 1.0;
  }
  for (Eigen::Index j = 0; j < d_helmert.cols(); ++j) {
    const Eigen::Index k = column(l.helmert[static_cast<std::size_t>(j)]);
    a.col(k) += d_helmert.col(j);
  }
  r.a = whitening[mi] * a.leftCols(static_cast<Eigen::Index>(r.unknowns.size()));
  r.l = whitening[mi] * misclosure(m, ev.computed);
  return r;
}

std::vector<NetworkProblem::Pseudo> NetworkProblem::pseudo_observations() const {
  std::vector<Pseudo> out;
  if (aside) return out;
  for (std::size_t s = 0; s < net.stations.size(); ++s) {
    if (!station_used[s]) continue;
    const auto& con = net.stations[s].constraint;
    for (int k = 0; k < 3; ++k) {
      if (con.code[static_cast<std::size_t>(k)] != 'C' || con.sigma_m[static_cast<std::size_t>(k)] <= 0.0) continue;
      const int c = constrained_component(net.space, k);
      const Eigen::Vector3d d = states[s].axes * (net.stations[s].position - states[s].x);
      out.push_back({layout.station[s][static_cast<std::size_t>(c)], d(c) / con.sigma_m[static_cast<std::size_t>(k)]});
    }
  }
  return out;
}

double NetworkProblem::pseudo_weight(Index unknown) const {
  const auto [s, c] = layout.owner[static_cast<std::size_t>(unknown)];
  for (int k = 0; k < 3; ++k) {
    if (constrained_component(net.space, k) == c) return 1.0 / net.stations[s].constraint.sigma_m[static_cast<std::size_t>(k)];
  }
  return 0.0;
}

// Union-find over stations joined by a measurement.
std::vector<std::size_t> components_of(const NetworkProblem& p, std::size_t& count) {
  std::vector<std::size_t> parent(p.net.stations.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::size_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (std::size_t mi = 0; mi < p.net.measurements.size(); ++mi) {
    if (!p.active[mi]) continue;
    const auto& st = p.net.measurements[mi].stations;
    for (std::size_t k = 1; k < st.size(); ++k) parent[find(st[k])] = find(st[0]);
  }
  // Components numbered in the order of their first station.
  constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
  std::vector<std::size_t> id(parent.size(), kNone);
  std::vector<std::size_t> out(parent.size(), 0);
  count = 0;
  for (std::size_t s = 0; s < parent.size(); ++s) {
    if (!p.station_used[s]) continue;
    std::size_t& c = id[find(s)];
    if (c == kNone) c = count++;
    out[s] = c;
  }
  return out;
}

// The unknowns: with `all_free` every component of every station reached
// (the datum's probe: what the measurements alone determine), else those
// the constraints leave.
UnknownLayout make_layout(const NetworkProblem& p, bool all_free) {
  UnknownLayout l;
  const auto& net = p.net;
  l.station.assign(net.stations.size(), {-1, -1, -1});
  for (std::size_t s = 0; s < net.stations.size(); ++s) {
    if (!p.station_used[s]) continue;
    for (int c = 0; c < 3; ++c) {
      if (!estimated_component(net, c)) continue;
      bool fixed = false;
      if (!p.aside && !all_free) {
        for (int k = 0; k < 3; ++k) {
          const auto& con = net.stations[s].constraint;
          fixed = fixed || (constrained_component(net.space, k) == c && con.code[static_cast<std::size_t>(k)] == 'C' &&
                            con.sigma_m[static_cast<std::size_t>(k)] <= 0.0);
        }
      }
      if (fixed) continue;
      l.station[s][static_cast<std::size_t>(c)] = l.count++;
      l.owner.emplace_back(s, c);
    }
  }
  // One orientation per direction set that has a direction in the
  // adjustment (a set whose directions are all left out, ignored or
  // removed as outliers has none to determine it).
  std::vector<bool> observed(net.direction_sets.size(), false);
  for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) {
    if (!p.active[mi]) continue;
    for (const auto& part : geodesy::parts_of(net.measurements[mi])) {
      if (part.set) observed[*part.set] = true;
    }
  }
  l.orientation.assign(net.direction_sets.size(), -1);
  for (std::size_t k : p.set_order) {
    if (!observed[k]) continue;
    l.orientation[k] = l.count++;
    l.owner.emplace_back(k, 3);
  }
  if (p.o.helmert) {
    for (std::size_t k = 0; k < (p.o.helmert->rates ? 14u : 7u); ++k) {
      l.helmert.push_back(l.count++);
      l.owner.emplace_back(k, 4);
    }
  }
  return l;
}

// Moves the stations and orientations by the unknowns' corrections; returns
// the largest station correction (metres) and its station.
std::pair<double, std::size_t> apply_corrections(NetworkProblem& p, const Eigen::VectorXd& dx) {
  double largest = 0.0;
  std::size_t at = 0;
  const auto& net = p.net;
  for (std::size_t s = 0; s < net.stations.size(); ++s) {
    if (!p.station_used[s]) continue;
    Eigen::Vector3d local = Eigen::Vector3d::Zero();
    for (int c = 0; c < 3; ++c) {
      const Index u = p.layout.station[s][static_cast<std::size_t>(c)];
      if (u >= 0) local(c) = dx(u);
    }
    if (local.norm() > largest) largest = local.norm(), at = s;
    Eigen::Vector3d x = p.states[s].x + p.states[s].axes.transpose() * local;
    if (net.space == NetworkSpace::ellipsoidal && !p.aside && net.stations[s].constraint.any()) {
      // Components held fixed stay at their a-priori geodetic values.
      const auto& con = net.stations[s].constraint;
      auto g = p.geocentric.geodetic_from_ecef(geodesy::EcefPosition(x.x(), x.y(), x.z()));
      const auto a = p.geocentric.geodetic_from_ecef(geodesy::EcefPosition(net.stations[s].position.x(), net.stations[s].position.y(),
                                                                           net.stations[s].position.z()));
      bool changed = false;
      if (con.code[0] == 'C' && con.sigma_m[0] <= 0.0) g.lat = a.lat, changed = true;
      if (con.code[1] == 'C' && con.sigma_m[1] <= 0.0) g.lon = a.lon, changed = true;
      if (con.code[2] == 'C' && con.sigma_m[2] <= 0.0) g.h = a.h, changed = true;
      if (changed) x = p.geocentric.ecef_from_geodetic(g).m;
    }
    const Eigen::Matrix3d axes = p.states[s].axes;
    p.states[s] = station_state(net, p.geocentric, x, s, p.o.geoid);
    p.states[s].axes = axes;
  }
  for (std::size_t k = 0; k < p.orientations.size(); ++k) {
    if (p.layout.orientation[k] >= 0) p.orientations[k] += dx(p.layout.orientation[k]);
  }
  // A Helmert parameter's correction counts by how far it moves a point
  // of the Earth's surface (a rate's over a year).
  for (std::size_t k = 0; k < p.layout.helmert.size(); ++k) {
    const double d = dx(p.layout.helmert[k]);
    p.helmert(static_cast<Eigen::Index>(k)) += d;
    const double moved = k % 7 < 3 ? std::abs(d) : std::abs(d) * net.ellipsoid.a_m();
    if (moved > largest) largest = moved, at = net.stations.size();
  }
  return {largest, at};
}

}  // namespace geoanchor::solver
