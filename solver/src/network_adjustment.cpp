// Least-squares adjustment of a survey network (network_adjustment.hpp).

#include "geoanchor/solver/network_adjustment.hpp"

#include <Eigen/SVD>
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>

#include "fit_common.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/base/number_text.hpp"
#include "datum_rank.hpp"
#include "network_approximate.hpp"
#include "network_model.hpp"
#include "network_snooping.hpp"
#include "point_statistics.hpp"
#include "snooping.hpp"
#include "geoanchor/base/parallel.hpp"
#include "sparse_factor.hpp"
#include "statistics.hpp"

namespace geoanchor::solver {

using geodesy::MeasurementKind;
using geodesy::NetworkSpace;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
using Index = std::int64_t;

// The stations' unknowns: per station the index of each local component's
// correction (east, north, up | x, y, z), −1 where none; per direction set
// its orientation's.
struct Layout {
  std::vector<std::array<Index, 3>> station;
  std::vector<Index> orientation;
  std::vector<Index> helmert;  // AdjustOptions::helmert's parameters (7 or 14), in HelmertGroup's order
  Index count = 0;
  // What each unknown is: the station (or set) and the component (3: an
  // orientation; 4: a Helmert parameter, `first` its index).
  std::vector<std::pair<std::size_t, int>> owner;
  bool operator==(const Layout&) const = default;
};

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

// [v]×: the matrix of v × ·.
Eigen::Matrix3d cross_matrix(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

// The Helmert of AdjustOptions::helmert is estimated about `pivot` (the
// group's stations' a-priori centroid c): X = c + T_c + (1 + s) R (y − c).
// Over a small group a geocentric translation is correlated with the
// rotations to 1 − 10⁻⁸, which would cost the factor its digits; about the
// centroid they are nearly independent. The model itself is the
// geocentric one (AdjustOptions::helmert): these are its parameters,
// T = c + T_c − (1 + s) R c and, with rates, Ṫ = Ṫ_c − ṡ R c + (1 + s) [c]× ṙ
// (rotations, scale and their rates are the same in both forms), and J
// their derivatives with respect to the parameters about the pivot.
struct GeocentricForm {
  Eigen::VectorXd parameters;
  Eigen::MatrixXd j;
};

GeocentricForm geocentric_form(const Eigen::VectorXd& about_pivot, const Eigen::Vector3d& c, bool rates) {
  const Eigen::Index n = about_pivot.size();
  const Eigen::Vector3d r = about_pivot.segment<3>(3);
  const double scale = 1.0 + about_pivot(6);
  const Eigen::Vector3d rc = (Eigen::Matrix3d::Identity() + cross_matrix(r)) * c;
  GeocentricForm g;
  g.parameters = about_pivot;
  g.parameters.head<3>() = c + about_pivot.head<3>() - scale * rc;
  g.j = Eigen::MatrixXd::Identity(n, n);
  g.j.block<3, 3>(0, 3) = scale * cross_matrix(c);  // ∂T/∂r = −(1 + s) ∂(R c)/∂r = (1 + s) [c]×
  g.j.block<3, 1>(0, 6) = -rc;
  if (rates) {
    const Eigen::Vector3d dr = about_pivot.segment<3>(10);
    const double ds = about_pivot(13);
    g.parameters.segment<3>(7) = about_pivot.segment<3>(7) - ds * rc + scale * cross_matrix(c) * dr;
    g.j.block<3, 3>(7, 3) = ds * cross_matrix(c);  // −ṡ ∂(R c)/∂r
    g.j.block<3, 1>(7, 6) = cross_matrix(c) * dr;  // ∂/∂s of (1 + s) [c]× ṙ
    g.j.block<3, 3>(7, 10) = scale * cross_matrix(c);
    g.j.block<3, 1>(7, 13) = -rc;
  }
  return g;
}

// A Helmert group member's values taken back into the group's datum:
// `computed` (positions or baseline differences in the network's frame)
// becomes y = R⁻¹ (X − T) / (1 + s) (for a baseline R⁻¹ Δ / (1 + s)) with
// the geocentric parameters at the member's epoch (dt years from the
// reference epoch), d_local its derivatives through R⁻¹ / (1 + s), and
// `d_parameters` (rows × 7 or 14) ∂y / ∂(each parameter about the pivot).
void into_group_datum(Evaluation& ev, bool points, const GeocentricForm& g, bool rates, double dt,
                      Eigen::MatrixXd& d_parameters) {
  Eigen::Matrix<double, 7, 1> q = g.parameters.head<7>();
  if (rates) q += dt * g.parameters.segment<7>(7);
  const Eigen::Vector3d t = q.head<3>(), r = q.segment<3>(3);
  const double scale = 1.0 + q(6);
  const Eigen::Matrix3d r_inv = (Eigen::Matrix3d::Identity() + cross_matrix(r)).inverse();
  const Eigen::Matrix3d a = r_inv / scale;
  const Eigen::Index rows = ev.computed.size();
  Eigen::MatrixXd d_geocentric = Eigen::MatrixXd::Zero(rows, rates ? 14 : 7);
  for (Eigen::Index k = 0; k + 2 < rows; k += 3) {
    const Eigen::Vector3d x = ev.computed.segment<3>(k);
    const Eigen::Vector3d y = a * (points ? Eigen::Vector3d(x - t) : x);
    ev.computed.segment<3>(k) = y;
    ev.d_local.middleRows(k, 3) = a * ev.d_local.middleRows(k, 3);
    Eigen::Matrix<double, 3, 7> d = Eigen::Matrix<double, 3, 7>::Zero();
    if (points) d.leftCols<3>() = -a;
    d.middleCols<3>(3) = r_inv * cross_matrix(y);  // ∂y/∂r = −R⁻¹ (∂R/∂r_i) y, ∂R/∂r_i = [e_i]×
    d.col(6) = -y / scale;
    d_geocentric.block(k, 0, 3, 7) = d;
    if (rates) d_geocentric.block(k, 7, 3, 7) = dt * d;
  }
  d_parameters = d_geocentric * g.j;
}

// The estimate in the geocentric form, its covariance carried by J.
EstimatedHelmert geocentric_helmert(const Eigen::VectorXd& about_pivot, const Eigen::MatrixXd& covariance,
                                    const Eigen::Vector3d& c, bool rates) {
  const GeocentricForm g = geocentric_form(about_pivot, c, rates);
  EstimatedHelmert h;
  h.parameters = g.parameters;
  h.covariance = g.j * covariance * g.j.transpose();
  return h;
}

// One measurement's rows, linearized: its unknowns and the whitened design
// rows over them, the whitened misclosure (observed − computed).
struct Rows {
  std::vector<Index> unknowns;
  Eigen::MatrixXd a;  // whitened, rows × unknowns.size()
  Eigen::VectorXd l;  // whitened misclosure
  Eigen::VectorXd computed;
};

struct Problem {
  const geodesy::Network& net;
  const AdjustOptions& o;
  geodesy::GeocentricConverter geocentric;
  std::vector<StationState> states;
  std::vector<double> orientations;
  Eigen::VectorXd helmert;        // AdjustOptions::helmert's parameters (SI) about helmert_pivot, p0 then the rates
  Eigen::Vector3d helmert_pivot = Eigen::Vector3d::Zero();  // the group's stations' a-priori centroid
  std::vector<int> helmert_slot;  // per measurement: its place in the group, −1 outside it
  std::vector<Eigen::MatrixXd> whitening;  // per measurement: W with Wᵀ W = C⁻¹
  std::vector<bool> active;                // measurements in the adjustment
  // Measurements removed by data snooping whose entries stay in the normal
  // matrix as zeros, so that its pattern (and CHOLMOD's analysis) is the
  // first pass's: the next pass refactors numerically only.
  std::vector<bool> pattern_only;
  std::vector<bool> station_used;
  Layout layout;
  bool aside = false;  // --free: the input's station constraints are set aside
  bool free = false;   // the datum (or what the constraints leave of it) by inner constraints
  std::vector<std::size_t> inner;          // free: the inner-constraint stations
  std::vector<std::array<bool, 3>> inner_components;  // their components in the inner constraints
  Eigen::MatrixXd defect;                  // free: the undefined datum directions over the unknowns (u × d)
  std::vector<std::size_t> anchor;         // free: the stations the defect is held at while iterating
  std::vector<std::array<bool, 3>> anchor_components;  // their components that hold it
  std::vector<std::string> defect_names;
  Eigen::MatrixXd defect_motions;          // the defect's columns over the named motions (DatumVectors::named)
  std::vector<std::string> motion_names;
  // Every sum over measurements runs in this order (canonical_order: by
  // what each is, not where it is in the input), and the direction sets'
  // orientations are numbered in set_order: the same network in a shuffled
  // file gives the same bits.
  std::vector<std::size_t> order;
  std::vector<std::size_t> set_order;

  Problem(const geodesy::Network& n, const AdjustOptions& opt) : net(n), o(opt), geocentric(n.ellipsoid) {}

  Rows linearize(std::size_t mi) const { return linearize(mi, layout); }
  // The rows over the unknowns of `l` (the layout, or the datum's probe of
  // every component).
  Rows linearize(std::size_t mi, const Layout& l) const {
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
    Rows r;
    r.computed = ev.computed;
    // The columns in the order their unknowns first come (a measurement has
    // a handful: a linear search), in a matrix as wide as they can be.
    const Eigen::Index most = static_cast<Eigen::Index>(3 * ev.stations.size()) + (ev.orientation ? 1 : 0) + d_helmert.cols();
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
    if (ev.orientation) {
      const Eigen::Index k = column(l.orientation[*m.set]);
      a.col(k).array() -= 1.0;
    }
    for (Eigen::Index j = 0; j < d_helmert.cols(); ++j) {
      const Eigen::Index k = column(l.helmert[static_cast<std::size_t>(j)]);
      a.col(k) += d_helmert.col(j);
    }
    r.a = whitening[mi] * a.leftCols(static_cast<Eigen::Index>(r.unknowns.size()));
    r.l = whitening[mi] * misclosure(m, ev.computed);
    return r;
  }

  // The constraint of station s along component c held with a sigma: its
  // whitened misclosure (a-priori − current, along the local axis) and unknown.
  struct Pseudo {
    Index unknown;
    double l;
  };
  std::vector<Pseudo> pseudo_observations() const {
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
  double pseudo_weight(Index unknown) const {
    const auto [s, c] = layout.owner[static_cast<std::size_t>(unknown)];
    for (int k = 0; k < 3; ++k) {
      if (constrained_component(net.space, k) == c) return 1.0 / net.stations[s].constraint.sigma_m[static_cast<std::size_t>(k)];
    }
    return 0.0;
  }
};

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
  return three_way(ma.ignore, mb.ignore);
}

// Direction sets by what they are: their station's name, then their
// directions in the order of their content, compared one by one (then the
// fewer first). Equal sets are interchangeable.
std::vector<std::size_t> canonical_set_order(const geodesy::Network& net) {
  std::vector<std::vector<std::size_t>> members(net.direction_sets.size());
  for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) {
    const auto& m = net.measurements[mi];
    if (m.set && *m.set < members.size()) members[*m.set].push_back(mi);
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

// Each set's place in canonical_set_order (its canonical rank).
std::vector<std::size_t> set_ranks(const std::vector<std::size_t>& set_order) {
  std::vector<std::size_t> rank(set_order.size());
  for (std::size_t k = 0; k < set_order.size(); ++k) rank[set_order[k]] = k;
  return rank;
}

// The measurements by what they are (compare_content), a direction's set
// by its canonical rank after that.
std::vector<std::size_t> canonical_order(const geodesy::Network& net, const std::vector<std::size_t>& set_order) {
  const std::vector<std::size_t> rank = set_ranks(set_order);
  const auto set_rank = [&](const geodesy::NetworkMeasurement& m) {
    return m.set && *m.set < rank.size() ? rank[*m.set] + 1 : std::size_t{0};
  };
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

// The text data snooping breaks exact ties with: what the measurement is
// (kind, stations, values, heights and covariance as exact hexadecimal,
// frame, group, a direction's set by its canonical rank `set_rank` (0 for
// none), solution type, variance scales, ignored), not where it is.
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
  key += m.ignore ? "\x1fignored" : "";
  return key;
}

// Union-find over stations joined by a measurement.
std::vector<std::size_t> components_of(const Problem& p, std::size_t& count) {
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
Layout make_layout(const Problem& p, bool all_free = false) {
  Layout l;
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
    const auto& m = net.measurements[mi];
    if (m.set && p.active[mi]) observed[*m.set] = true;
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

// The normal equations at the current state: entries of N (upper
// triangle), Aᵀ l, the number of observation rows and vᵀPv of the misclosures.
struct Normal {
  std::vector<SymmetricEntry> entries;
  Eigen::VectorXd b;
  std::size_t rows = 0;
};

// Measurements per chunk of work shared among threads (parallel.hpp).
constexpr std::size_t kMeasurementChunk = 512;

// The upper triangle of a measurement's AᵀA over its unknowns.
void push_upper(Normal& n, const std::vector<Index>& unknowns, const Eigen::MatrixXd& ata) {
  for (std::size_t i = 0; i < unknowns.size(); ++i) {
    for (std::size_t j = 0; j < unknowns.size(); ++j) {
      if (unknowns[i] > unknowns[j]) continue;
      n.entries.push_back({unknowns[i], unknowns[j], ata(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j))});
    }
  }
}

// With `matrix` false only b and the rows (the matrix is known not to have
// changed: constant_jacobian()). The measurements are linearized on `jobs`
// threads a block at a time and summed on this one in their order, so the
// entries and b do not depend on the threads.
constexpr std::size_t kAssemblyBlock = 1 << 16;
Normal assemble(const Problem& p, bool matrix = true, int jobs = 1) {
  Normal n;
  n.b = Eigen::VectorXd::Zero(p.layout.count);
  struct Contribution {
    std::vector<Index> unknowns;
    Eigen::MatrixXd ata;
    Eigen::VectorXd atl;
    std::size_t rows = 0;
  };
  std::vector<std::size_t> active;
  for (std::size_t mi : p.order) {
    if (p.active[mi]) active.push_back(mi);
  }
  if (matrix) n.entries.reserve(21 * active.size());  // a baseline's 6 unknowns: 21 entries
  std::vector<Contribution> block;
  for (std::size_t first = 0; first < active.size(); first += kAssemblyBlock) {
    const std::size_t count = std::min(kAssemblyBlock, active.size() - first);
    block.resize(count);
    for_chunks(count, kMeasurementChunk, jobs, [&](std::size_t begin, std::size_t end) {
      for (std::size_t k = begin; k < end; ++k) {
        Rows r = p.linearize(active[first + k]);
        Contribution& c = block[k];
        c.rows = static_cast<std::size_t>(r.l.size());
        c.atl = r.a.transpose() * r.l;
        if (matrix) c.ata = r.a.transpose() * r.a;
        c.unknowns = std::move(r.unknowns);
      }
    });
    for (const Contribution& c : block) {
      n.rows += c.rows;
      for (std::size_t i = 0; i < c.unknowns.size(); ++i) n.b(c.unknowns[i]) += c.atl(static_cast<Eigen::Index>(i));
      if (matrix) push_upper(n, c.unknowns, c.ata);
    }
  }
  if (matrix && !p.pattern_only.empty()) {
    for (std::size_t mi = 0; mi < p.net.measurements.size(); ++mi) {
      if (!p.pattern_only[mi] || p.active[mi]) continue;
      const auto& st = p.net.measurements[mi].stations;
      if (!std::all_of(st.begin(), st.end(), [&](std::size_t s) { return p.station_used[s]; })) continue;
      const Rows r = p.linearize(mi);
      push_upper(n, r.unknowns, Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(r.unknowns.size()), static_cast<Eigen::Index>(r.unknowns.size())));
    }
  }
  for (const auto& q : p.pseudo_observations()) {
    const double w = p.pseudo_weight(q.unknown);
    if (matrix) n.entries.push_back({q.unknown, q.unknown, w * w});
    n.b(q.unknown) += w * q.l;
    ++n.rows;
  }
  return n;
}

// Whether the normal matrix is the same at every state: every measurement
// in the adjustment is linear in the positions (GNSS baselines and points;
// the unknowns' axes are fixed, StationState::axes), no Helmert is
// estimated with them, and the datum is held by constraints (inner
// constraints move with the positions).
bool constant_jacobian(const Problem& p) {
  if (p.free || p.o.helmert) return false;
  for (std::size_t mi = 0; mi < p.net.measurements.size(); ++mi) {
    if (!p.active[mi]) continue;
    const auto k = p.net.measurements[mi].kind;
    if (k != MeasurementKind::gnss_baselines && k != MeasurementKind::gnss_points) return false;
  }
  return true;
}

// The datum parameters as motions of the unknowns, each scaled to move the
// stations by 1 m RMS: translations along X, Y, Z (x, y, z), rotations
// about X, Y, Z through the centroid (local: about the vertical), scale.
struct DatumVectors {
  Eigen::MatrixXd g;  // u × d
  std::vector<std::string> names;
  // The columns of g over the named motions (identity unless some
  // combination of them moves nothing, e.g. a rotation about the line
  // through the only two stations: such combinations are no datum).
  Eigen::MatrixXd basis;
  Eigen::MatrixXd named;  // u × (named motions): each named motion, unit RMS (g = named · basis)
};

DatumVectors datum_vectors(const Problem& p, const Layout& layout) {
  const auto& net = p.net;
  const bool ellipsoidal = net.space == NetworkSpace::ellipsoidal;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  std::size_t n = 0;
  for (std::size_t s = 0; s < net.stations.size(); ++s) {
    if (p.station_used[s]) centroid += p.states[s].x, ++n;
  }
  centroid /= static_cast<double>(std::max<std::size_t>(n, 1));
  double radius2 = 0.0;
  for (std::size_t s = 0; s < net.stations.size(); ++s) {
    if (p.station_used[s]) radius2 += (p.states[s].x - centroid).squaredNorm();
  }
  const double radius = std::max(1.0, std::sqrt(radius2 / static_cast<double>(std::max<std::size_t>(n, 1))));

  // The motions of a station's position, per parameter (in the positions' axes).
  struct Motion {
    std::string name;
    std::function<Eigen::Vector3d(const Eigen::Vector3d&)> move;
    Eigen::Vector3d rotation_axis = Eigen::Vector3d::Zero();  // for the orientations
  };
  std::vector<Motion> motions;
  const char* axis_names[] = {"X", "Y", "Z"};
  if (ellipsoidal) {
    for (int k = 0; k < 3; ++k) {
      motions.push_back({std::string("translation along ") + axis_names[k] + " (ECEF)",
                         [k](const Eigen::Vector3d&) { return Eigen::Vector3d::Unit(k); }, Eigen::Vector3d::Zero()});
    }
    for (int k = 0; k < 3; ++k) {
      motions.push_back({std::string("rotation about ") + axis_names[k] + " (ECEF, through the network's centroid)",
                         [k, centroid, radius](const Eigen::Vector3d& x) {
                           return Eigen::Vector3d(Eigen::Vector3d::Unit(k).cross(x - centroid) / radius);
                         },
                         Eigen::Vector3d::Unit(k) / radius});
    }
    motions.push_back({"scale", [centroid, radius](const Eigen::Vector3d& x) { return Eigen::Vector3d((x - centroid) / radius); },
                       Eigen::Vector3d::Zero()});
  } else {
    const char* local_names[] = {"x", "y", "z"};
    for (int k = 0; k < 3; ++k) {
      if (!estimated_component(net, k)) continue;
      motions.push_back({std::string("translation along ") + local_names[k],
                         [k](const Eigen::Vector3d&) { return Eigen::Vector3d::Unit(k); }, Eigen::Vector3d::Zero()});
    }
    if (net.local_dimensions == 3) {
      // A 3-D network turns about its horizontal axes too (slope distances
      // alone leave all three rotations free).
      for (int k = 0; k < 2; ++k) {
        motions.push_back({std::string("rotation about the ") + local_names[k] + " axis (through the network's centroid)",
                           [k, centroid, radius](const Eigen::Vector3d& x) {
                             return Eigen::Vector3d(Eigen::Vector3d::Unit(k).cross(x - centroid) / radius);
                           },
                           Eigen::Vector3d::Unit(k) / radius});
      }
    }
    if (net.local_dimensions >= 2) {
      motions.push_back({"rotation about the vertical",
                         [centroid, radius](const Eigen::Vector3d& x) {
                           return Eigen::Vector3d(Eigen::Vector3d::UnitZ().cross(x - centroid) / radius);
                         },
                         Eigen::Vector3d::UnitZ() / radius});
      motions.push_back({net.local_dimensions == 3 ? "horizontal scale" : "scale",
                         [centroid, radius](const Eigen::Vector3d& x) {
                           Eigen::Vector3d d = (x - centroid) / radius;
                           d.z() = 0.0;
                           return d;
                         },
                         Eigen::Vector3d::Zero()});
    }
    if (net.local_dimensions == 3) {
      // Angles alone keep a 3-D network's shape at any size: the uniform
      // scale is the horizontal and the vertical one together.
      motions.push_back({"vertical scale",
                         [centroid, radius](const Eigen::Vector3d& x) {
                           return Eigen::Vector3d(0.0, 0.0, (x.z() - centroid.z()) / radius);
                         },
                         Eigen::Vector3d::Zero()});
    }
  }
  DatumVectors dv;
  dv.g = Eigen::MatrixXd::Zero(layout.count, static_cast<Eigen::Index>(motions.size()));
  for (std::size_t k = 0; k < motions.size(); ++k) {
    dv.names.push_back(motions[k].name);
    // Unit RMS motion over the stations reached, whatever the layout (a
    // combination means the same motion over every layout).
    double rms2 = 0.0;
    for (std::size_t s = 0; s < net.stations.size(); ++s) {
      if (!p.station_used[s]) continue;
      Eigen::Vector3d moved = motions[k].move(p.states[s].x);
      for (int c = 0; c < 3; ++c) {
        if (!estimated_component(net, c)) moved(c) = 0.0;  // (a local network's absent axes)
      }
      rms2 += moved.squaredNorm();
    }
    const double unit = rms2 > 0.0 ? 1.0 / std::sqrt(rms2 / static_cast<double>(std::max<std::size_t>(n, 1))) : 1.0;
    for (std::size_t s = 0; s < net.stations.size(); ++s) {
      if (!p.station_used[s]) continue;
      const Eigen::Vector3d local = unit * (p.states[s].axes * motions[k].move(p.states[s].x));
      for (int c = 0; c < 3; ++c) {
        const Index u = layout.station[s][static_cast<std::size_t>(c)];
        if (u >= 0) dv.g(u, static_cast<Eigen::Index>(k)) = local(c);
      }
    }
    // The group's datum moves with the stations, so that its values stay
    // as they are: its translation, rotation and scale take up the motion
    // (to first order), the rates none of it.
    if (ellipsoidal && !layout.helmert.empty()) {
      const Eigen::Vector3d t = p.helmert_pivot + p.helmert.head<3>();  // where the pivot lies in the network's frame
      Eigen::Matrix<double, 7, 1> d = Eigen::Matrix<double, 7, 1>::Zero();
      if (k < 3) {
        d.head<3>() = Eigen::Vector3d::Unit(static_cast<int>(k));
      } else if (k < 6) {
        const Eigen::Vector3d e = Eigen::Vector3d::Unit(static_cast<int>(k) - 3);
        d.head<3>() = e.cross(t - centroid) / radius;
        d(static_cast<Eigen::Index>(k)) = 1.0 / radius;
      } else {
        d.head<3>() = (t - centroid) / radius;
        d(6) = 1.0 / radius;
      }
      for (Eigen::Index j = 0; j < 7; ++j) dv.g(layout.helmert[static_cast<std::size_t>(j)], static_cast<Eigen::Index>(k)) = unit * d(j);
    }
    // A rotation turns the bearings at a station by its component about
    // the local vertical: the set's orientation turns with them.
    if (motions[k].rotation_axis.squaredNorm() > 0.0) {
      for (std::size_t set = 0; set < net.direction_sets.size(); ++set) {
        if (layout.orientation[set] < 0) continue;
        const auto& st = p.states[net.direction_sets[set].station];
        const double about_up = motions[k].rotation_axis.dot(st.local_from_xyz.row(2).transpose());
        dv.g(layout.orientation[set], static_cast<Eigen::Index>(k)) =
            unit * (ellipsoidal ? -about_up : net.axes.bearing_sign() * about_up);
      }
    }
  }
  dv.named = dv.g;
  dv.basis = Eigen::MatrixXd::Identity(dv.g.cols(), dv.g.cols());
  if (dv.g.cols() > 0 && dv.g.rows() > 0) {
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(dv.g, Eigen::ComputeThinV);
    const Eigen::VectorXd& sv = svd.singularValues();
    Eigen::Index keep = 0;
    while (keep < sv.size() && sv(keep) > 1e-6 * sv(0)) ++keep;
    if (keep < dv.g.cols()) {
      // Unit RMS motion per column again: g·basis = U·√n.
      dv.basis = svd.matrixV().leftCols(keep) * sv.head(keep).cwiseInverse().asDiagonal() *
                 std::sqrt(static_cast<double>(std::max<std::size_t>(n, 1)));
      dv.g = dv.g * dv.basis;
    }
  }
  return dv;
}

// Names a combination over the datum parameters by its largest parts.
std::string name_combination(const Eigen::VectorXd& e, const std::vector<std::string>& names) {
  std::string what;
  for (Eigen::Index j = 0; j < e.size(); ++j) {
    if (std::fabs(e(j)) >= 0.3 * e.cwiseAbs().maxCoeff()) what += (what.empty() ? "" : " with ") + names[static_cast<std::size_t>(j)];
  }
  return what;
}

// What the measurements tell of the datum motions (the columns of g, unit
// RMS over the stations, over the unknowns of `layout`: the probe of every
// component) and what they could (datum_rank.hpp): the R factors of the
// rows A_j G_j and ‖A_j‖_F G_j, A_j a measurement's whitened rows over its
// unknowns and G_j the motions there. In the canonical order, in chunks on
// `jobs` threads folded in turn: the same bits for any order of the input
// and any number of threads.
struct DatumInformation {
  Eigen::MatrixXd measured, reference;
};

DatumInformation datum_information(const Problem& p, const Layout& layout, const Eigen::MatrixXd& g, int jobs) {
  const Eigen::Index d = g.cols();
  std::vector<std::size_t> active;
  for (std::size_t mi : p.order) {
    if (p.active[mi]) active.push_back(mi);
  }
  constexpr std::size_t kChunk = 4096;
  const std::size_t chunks = (active.size() + kChunk - 1) / kChunk;
  std::vector<RowsR> measured(chunks, RowsR(d)), reference(chunks, RowsR(d));
  for_chunks(active.size(), kChunk, jobs, [&](std::size_t begin, std::size_t end) {
    const std::size_t chunk = begin / kChunk;
    for (std::size_t k = begin; k < end; ++k) {
      const Rows r = p.linearize(active[k], layout);
      Eigen::MatrixXd gj(static_cast<Eigen::Index>(r.unknowns.size()), d);
      for (std::size_t c = 0; c < r.unknowns.size(); ++c) gj.row(static_cast<Eigen::Index>(c)) = g.row(r.unknowns[c]);
      measured[chunk].add(r.a * gj);
      reference[chunk].add(r.a.norm() * gj);
    }
  });
  RowsR all_measured(d), all_reference(d);
  for (std::size_t c = 0; c < chunks; ++c) {
    all_measured.add(measured[c]);
    all_reference.add(reference[c]);
  }
  return {all_measured.r(), all_reference.r()};
}

// The ratio (datum_rank.hpp: what a combination is told over what a
// typical station could be told at most) below which a combination of the datum motions is
// undefined: the factorization's pivots are then within a hundred roundings
// of nothing (sparse_factor's relative pivot check is the same 10⁻¹⁴).
// Rounding leaves a motion nothing measures near n·10⁻³²; a datum held by
// constraints of 100 m among millimetre baselines is near 10⁻¹⁰, by 1 km
// holds 10⁻¹², by a GNSS point of 3 m on one station 10⁻⁷: for a datum held
// at one station, the same for ten stations or a million. Below kWeakDatumRelative (a combination
// told at less than a millionth of what a typical station is told)
// it is defined, weakly, and named in a warning with the standard
// deviation it then has: a terrestrial network with no azimuth, turned
// about the vertical only by the convergence of the ellipsoid's normals,
// is near 10⁻⁸.
constexpr double kUndefinedDatumRelative = 1e-14;
constexpr double kWeakDatumRelative = 1e-6;

// How closely double precision resolves the standard deviation of a datum
// combination of this ratio in a network of n stations: the
// factorization's rounding along it grows as √n times a station's, about
// ε √n / (4 ratio) (measured: one station of 900, joined by baselines of
// millimetres, held at 1 km and 3 km, ratio 6·10⁻¹³ and 6·10⁻¹⁴: σ 0.2 % and
// 1.9 % off, this says 0.3 % and 3 %; held at 6 km the iteration no longer
// converges). Past kDatumResolution a warning says so; past
// kUnresolvedDatum the combination is undefined, as good as nothing.
double datum_resolution(double ratio, std::size_t stations) {
  return std::numeric_limits<double>::epsilon() * std::sqrt(static_cast<double>(std::max<std::size_t>(stations, 1))) / (4.0 * ratio);
}
constexpr double kDatumResolution = 1e-3;
// Above this ratio a combination is told of by the measurements, weakly,
// rather than left to their rounding (n·10⁻³² in the R factors; the
// positions' own rounding in ECEF, 10⁻⁹ m against a network's radius,
// under 10⁻²⁰ for stations 10 m apart).
constexpr double kToldOf = 1e-18;
constexpr double kUnresolvedDatum = 0.05;

// The combinations of the motions (columns over g's columns) that neither
// the measurements nor the constraints define to `below` of what a typical
// station is told (datum_rank.hpp), weakest first: a fixed component
// defines any motion that moves it; weighted constraints tell 1/σ² per
// component held. `probe` is the layout of every component (g's rows).
DatumRank undefined_datum(const Problem& p, const Layout& probe, const Eigen::MatrixXd& g, const DatumInformation& info,
                          double below) {
  const auto& net = p.net;
  const Eigen::Index d = g.cols();
  std::vector<Eigen::RowVectorXd> fixed_rows;
  RowsR weighted(d);
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(d, d);
  std::size_t stations = 0;
  for (std::size_t s = 0; s < net.stations.size(); ++s) {
    if (!p.station_used[s]) continue;
    ++stations;
    for (int c = 0; c < 3; ++c) {
      const Index u = probe.station[s][static_cast<std::size_t>(c)];
      if (u >= 0) gram.noalias() += g.row(u).transpose() * g.row(u);
    }
    if (p.aside) continue;
    const auto& con = net.stations[s].constraint;
    for (int k = 0; k < 3; ++k) {
      if (con.code[static_cast<std::size_t>(k)] != 'C') continue;
      const Index u = probe.station[s][static_cast<std::size_t>(constrained_component(net.space, k))];
      if (u < 0) continue;
      const double sigma = con.sigma_m[static_cast<std::size_t>(k)];
      if (sigma > 0.0) {
        weighted.add(Eigen::MatrixXd(g.row(u) / sigma));
      } else {
        fixed_rows.push_back(g.row(u));
      }
    }
  }
  Eigen::MatrixXd fixed(static_cast<Eigen::Index>(fixed_rows.size()), d);
  for (std::size_t k = 0; k < fixed_rows.size(); ++k) fixed.row(static_cast<Eigen::Index>(k)) = fixed_rows[k];
  return weak_combinations(fixed, gram, stations, info.measured, weighted.r(), info.reference, below);
}

// The same span, as orthogonal motions of 1 m RMS at the stations: v (vᵀ T v / n)^(−1/2), T the motions' Gram matrix
// over the probe's station unknowns.
Eigen::MatrixXd unit_motions(const Problem& p, const Layout& probe, const Eigen::MatrixXd& g, const Eigen::MatrixXd& v) {
  if (v.cols() == 0) return v;
  Eigen::MatrixXd gv = Eigen::MatrixXd::Zero(g.rows(), v.cols());
  std::size_t stations = 0;
  for (std::size_t s = 0; s < p.net.stations.size(); ++s) {
    if (!p.station_used[s]) continue;
    ++stations;
    for (int c = 0; c < 3; ++c) {
      const Index u = probe.station[s][static_cast<std::size_t>(c)];
      if (u >= 0) gv.row(u) = g.row(u) * v;
    }
  }
  const Eigen::MatrixXd t = gv.transpose() * gv / static_cast<double>(std::max<std::size_t>(stations, 1));
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> te(t);
  return v * te.operatorInverseSqrt();
}

// The defect directions over the unknowns of `stations` only (zero elsewhere).
Eigen::MatrixXd restricted(const Problem& p, const std::vector<std::size_t>& stations,
                           const std::vector<std::array<bool, 3>>& components = {}) {
  Eigen::MatrixXd e = Eigen::MatrixXd::Zero(p.defect.rows(), p.defect.cols());
  for (std::size_t k = 0; k < stations.size(); ++k) {
    const std::size_t s = stations[k];
    for (int c = 0; c < 3; ++c) {
      if (k < components.size() && !components[k][static_cast<std::size_t>(c)]) continue;
      const Index u = p.layout.station[s][static_cast<std::size_t>(c)];
      if (u >= 0) e.row(u) = p.defect.row(u);
    }
  }
  return e;
}

// A station's share of EᵀD (E: the defect D restricted to the stations
// holding it): D_sᵀ D_s over its components that take part (d × d), so
// that EᵀD over any set of stations is the sum of theirs.
Eigen::MatrixXd station_block(const Problem& p, std::size_t s, const std::array<bool, 3>& components) {
  const Eigen::Index d = p.defect.cols();
  Eigen::MatrixXd block = Eigen::MatrixXd::Zero(d, d);
  for (int c = 0; c < 3; ++c) {
    if (!components[static_cast<std::size_t>(c)]) continue;
    const Index u = p.layout.station[s][static_cast<std::size_t>(c)];
    if (u >= 0) block.noalias() += p.defect.row(u).transpose() * p.defect.row(u);
  }
  return block;
}

// The ratio of the smallest to the largest eigenvalue of EᵀD (symmetric,
// positive semi-definite): 0 when the stations leave a combination of the
// defect undefined; `weakest` gets that combination (over the defect's
// columns).
double spanning_ratio(const Eigen::MatrixXd& ed, Eigen::VectorXd* weakest = nullptr) {
  const Eigen::Index d = ed.rows();
  if (d == 0) return 1.0;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(ed);
  if (weakest) *weakest = eig.eigenvectors().col(0);
  const double top = eig.eigenvalues()(d - 1);
  return top > 0.0 ? std::max(0.0, eig.eigenvalues()(0)) / top : 0.0;
}

// Below this ratio (spanning_ratio) a set of stations does not hold the
// defect: the inner constraints over them would leave a combination free.
constexpr double kSpanningRatio = 1e-6;

// The inner-constraint stations (p.inner with p.inner_components) must
// hold every combination of the defect (EᵀD of full rank, spanning_ratio):
// else a refusal naming the combinations they leave free and why, before
// any factorization. `option`: they came from --inner-constraints (usage),
// else from the input's datum stations (input).
void check_inner_stations(const Problem& p, bool option) {
  const Eigen::Index d = p.defect.cols();
  if (d == 0) return;
  Eigen::MatrixXd ed = Eigen::MatrixXd::Zero(d, d), every_component = Eigen::MatrixXd::Zero(d, d);
  for (std::size_t k = 0; k < p.inner.size(); ++k) {
    ed += station_block(p, p.inner[k], k < p.inner_components.size() ? p.inner_components[k] : std::array<bool, 3>{true, true, true});
    every_component += station_block(p, p.inner[k], {true, true, true});
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(ed);
  const double top = eig.eigenvalues()(d - 1);
  std::vector<std::string> left;
  for (Eigen::Index k = 0; k < d; ++k) {
    if (top > 0.0 && eig.eigenvalues()(k) >= kSpanningRatio * top) continue;
    left.push_back(name_combination(p.defect_motions * eig.eigenvectors().col(k), p.motion_names));
  }
  if (left.empty()) return;
  const auto& net = p.net;
  std::string ids;
  for (std::size_t k = 0; k < p.inner.size() && k < 8; ++k) ids += (k ? ", " : "") + net.stations[p.inner[k]].id;
  if (p.inner.size() > 8) ids += ", …";
  // Why: the components left out, or the stations' places.
  std::string why;
  if (spanning_ratio(every_component) >= kSpanningRatio) {
    why = "the components of " + ids + " that take part do not hold it (with all three components of each they would)";
  } else if (p.inner.size() == 1) {
    why = "one station holds the translations only";
  } else {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (std::size_t st : p.inner) c += p.states[st].x;
    c /= static_cast<double>(p.inner.size());
    Eigen::MatrixXd spread(static_cast<Eigen::Index>(p.inner.size()), 3);
    for (std::size_t k = 0; k < p.inner.size(); ++k) spread.row(static_cast<Eigen::Index>(k)) = (p.states[p.inner[k]].x - c).transpose();
    constexpr double kOnOneLine = 1e-3;  // the second singular value of their spread against the first
    bool on_one_line = p.inner.size() == 2;
    if (!on_one_line) {
      // (≥ 3 stations: the spread's scatter matrix has 3 eigenvalues, the squares of its singular values.)
      const Eigen::Vector3d scatter = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(Eigen::Matrix3d(spread.transpose() * spread)).eigenvalues();
      on_one_line = scatter(1) < kOnOneLine * kOnOneLine * scatter(2);
    }
    if (on_one_line) {
      why = "the stations " + ids + " lie on one line: the rotation about the line through them moves none of them";
    } else {
      why = "the places of " + ids + " leave it free";
    }
  }
  std::string list;
  for (const auto& x : left) list += (list.empty() ? "" : "; ") + x;
  const std::string text = (option ? "--inner-constraints " + ids : p.net.source_name + ": the input's datum stations " + ids) +
                           ": these stations do not hold the " + list + " (" + std::to_string(left.size()) + " of the " +
                           std::to_string(d) + " combination" + (d == 1 ? "" : "s") + " the measurements leave undefined): " + why +
                           "; choose stations that span the network (for rotations and scale, three or more not on one line)";
  if (option) throw Error(ErrorKind::usage, "E_INNER_CONSTRAINTS", text);
  throw Error(ErrorKind::input, "E_DATUM_DEFECT", text);
}

// Where the defect is held while iterating (p.anchor and its components):
// few of the inner stations over which the defect's directions are
// independent: the one farthest from their centroid, then the farthest
// from it, then the one farthest off their line, then, while a
// combination is left free, the station that holds it best. A handful, so
// that holding them adds a small dense block to the normal matrix.
void choose_anchors(Problem& p) {
  const auto& set = p.inner;
  p.anchor.clear();
  p.anchor_components.clear();
  if (set.empty()) return;
  const auto components_at = [&](std::size_t k) {
    return k < p.inner_components.size() ? p.inner_components[k] : std::array<bool, 3>{true, true, true};
  };
  std::vector<Eigen::MatrixXd> blocks(set.size());
  for (std::size_t k = 0; k < set.size(); ++k) blocks[k] = station_block(p, set[k], components_at(k));
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (std::size_t s : set) centroid += p.states[s].x;
  centroid /= static_cast<double>(set.size());
  const auto farthest = [&](const std::function<double(std::size_t)>& score) {  // an index into set
    std::size_t best = 0;
    double top = -1.0;
    for (std::size_t k = 0; k < set.size(); ++k) {
      if (score(k) > top) top = score(k), best = k;
    }
    return best;
  };
  const auto x = [&](std::size_t k) { return p.states[set[k]].x; };
  const std::size_t a = farthest([&](std::size_t k) { return (x(k) - centroid).squaredNorm(); });
  const std::size_t b = farthest([&](std::size_t k) { return (x(k) - x(a)).squaredNorm(); });
  const std::size_t c = farthest([&](std::size_t k) { return (x(k) - x(a)).cross(x(b) - x(a)).squaredNorm(); });
  std::vector<bool> chosen(set.size(), false);
  const Eigen::Index d = p.defect.cols();
  Eigen::MatrixXd ed = Eigen::MatrixXd::Zero(d, d);
  const auto take = [&](std::size_t k) {
    if (chosen[k]) return;
    chosen[k] = true;
    ed += blocks[k];
  };
  Eigen::VectorXd weakest;
  for (std::size_t k : {a, b, c}) {
    take(k);
    if (spanning_ratio(ed) >= kSpanningRatio) break;
  }
  std::size_t count = static_cast<std::size_t>(std::count(chosen.begin(), chosen.end(), true));
  while (spanning_ratio(ed, &weakest) < kSpanningRatio && count < set.size()) {
    // The station that holds the weakest combination best.
    std::size_t best = set.size();
    double most = -1.0;
    for (std::size_t k = 0; k < set.size(); ++k) {
      if (chosen[k]) continue;
      const double held = weakest.dot(blocks[k] * weakest);
      if (held > most) most = held, best = k;
    }
    take(best);
    ++count;
  }
  for (std::size_t k = 0; k < set.size(); ++k) {
    if (!chosen[k]) continue;
    p.anchor.push_back(set[k]);
    p.anchor_components.push_back(components_at(k));
  }
}

// Adds w·C Cᵀ to the normal equations (C: the defect held at the anchors).
void hold_defect(const Problem& p, Normal& n) {
  if (!p.free || p.defect.cols() == 0) return;
  const Eigen::MatrixXd c = restricted(p, p.anchor, p.anchor_components);
  double trace = 0.0;
  std::size_t diagonal = 0;
  for (const auto& e : n.entries) {
    if (e.row == e.col) trace += e.value, ++diagonal;
  }
  const double w = diagonal > 0 ? trace / static_cast<double>(diagonal) : 1.0;
  std::vector<Index> rows;
  for (Index u = 0; u < c.rows(); ++u) {
    if (c.row(u).squaredNorm() > 0.0) rows.push_back(u);
  }
  for (Index a : rows) {
    for (Index b : rows) {
      if (a <= b) n.entries.push_back({a, b, w * c.row(a).dot(c.row(b))});
    }
  }
}

[[noreturn]] void singular(const Problem& p, Index column) {
  const std::string where = p.net.source_name;
  if (column < 0 || static_cast<std::size_t>(column) >= p.layout.owner.size()) {
    throw Error(ErrorKind::input, "E_NETWORK_SINGULAR",
                where + ": the normal equations are singular: some unknown is not determined by the measurements");
  }
  const auto [s, c] = p.layout.owner[static_cast<std::size_t>(column)];
  if (c == 4) {
    throw Error(ErrorKind::input, "E_NETWORK_SINGULAR",
                where + ": the Helmert parameter " + kHelmertNames[s] + " of group " + p.o.helmert->name +
                    " is not determined by its measurements (a translation needs a point cluster in the group, rates "
                    "need its measurements at two epochs or more, rotations and scale positions or baselines that span them)");
  }
  if (c == 3) {
    throw Error(ErrorKind::input, "E_NETWORK_SINGULAR",
                where + ": the orientation of the direction set at " + p.net.stations[p.net.direction_sets[s].station].id +
                    " (" + p.net.direction_sets[s].source + ") is not determined: the set needs directions to stations "
                    "whose positions the rest of the network gives");
  }
  std::size_t count = 0;
  for (std::size_t mi = 0; mi < p.net.measurements.size(); ++mi) {
    if (!p.active[mi]) continue;
    const auto& st = p.net.measurements[mi].stations;
    if (std::find(st.begin(), st.end(), s) != st.end()) ++count;
  }
  // (Reached only when the motion the matrix leaves free could not be
  // isolated: the station is where the elimination broke down, which is
  // not always what leaves it free. Said so.)
  throw Error(ErrorKind::input, "E_NETWORK_SINGULAR",
              where + ": the normal equations are singular: the elimination broke down at station " + p.net.stations[s].id + " (" +
                  p.net.stations[s].source + "), its " + component_name(p.net.space, c) + " coordinate (" +
                  std::to_string(count) + " measurement" + (count == 1 ? " reaches" : "s reach") +
                  " it), and the motion left free could not be isolated: check the measurements near it for a value that "
                  "is not finite or a distance of zero, then add measurements or constrain stations");
}

// The measurements that reach station s (their sources, at most `most`),
// and how many they are.
std::string reaching(const Problem& p, const std::vector<std::size_t>& stations, std::size_t most, std::size_t& count) {
  std::string list;
  count = 0;
  for (std::size_t mi : p.order) {
    if (!p.active[mi]) continue;
    const auto& st = p.net.measurements[mi].stations;
    if (std::none_of(st.begin(), st.end(), [&](std::size_t x) { return std::find(stations.begin(), stations.end(), x) != stations.end(); })) continue;
    if (count++ < most) list += (list.empty() ? "" : ", ") + p.net.measurements[mi].source + " (" + geodesy::to_string(p.net.measurements[mi].kind) + ")";
  }
  if (count > most) list += ", …";
  return list;
}

// A direction in a station's local components, in words: "east", "north
// and up", or a horizontal azimuth.
std::string direction_words(const Problem& p, const Eigen::Vector3d& local) {
  const Eigen::Vector3d a = local.cwiseAbs();
  const double top = a.maxCoeff();
  std::string out;
  for (int c = 0; c < 3; ++c) {
    if (a(c) >= 0.3 * top) out += std::string(out.empty() ? "" : " and ") + component_name(p.net.space, c);
  }
  return out;
}

// A station whose own block of the normal matrix (its unknowns, with the
// others held) is singular: moving it alone along the null direction
// changes no measurement, whatever the rest does. Named with the direction
// and the measurements that reach it (E_NETWORK_SINGULAR).
void check_station_blocks(const Problem& p, const Normal& n) {
  const auto& net = p.net;
  std::vector<Eigen::Matrix3d> blocks(net.stations.size(), Eigen::Matrix3d::Zero());
  for (const auto& e : n.entries) {
    const auto [s1, c1] = p.layout.owner[static_cast<std::size_t>(e.row)];
    const auto [s2, c2] = p.layout.owner[static_cast<std::size_t>(e.col)];
    if (c1 >= 3 || c2 >= 3 || s1 != s2) continue;
    blocks[s1](c1, c2) += e.value;
    if (c1 != c2) blocks[s1](c2, c1) += e.value;
  }
  // Below this share of the block's largest eigenvalue a direction is not
  // determined (one distance to a station: rank one, the rest rounding).
  constexpr double kSingularBlock = 1e-12;
  for (std::size_t s = 0; s < net.stations.size(); ++s) {
    if (!p.station_used[s]) continue;
    std::vector<int> comps;
    for (int c = 0; c < 3; ++c) {
      if (p.layout.station[s][static_cast<std::size_t>(c)] >= 0) comps.push_back(c);
    }
    if (comps.empty()) continue;
    const auto m = static_cast<Eigen::Index>(comps.size());
    Eigen::MatrixXd b(m, m);
    for (Eigen::Index i = 0; i < m; ++i) {
      for (Eigen::Index j = 0; j < m; ++j) b(i, j) = blocks[s](comps[static_cast<std::size_t>(i)], comps[static_cast<std::size_t>(j)]);
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(b);
    const double top = eig.eigenvalues()(m - 1);
    if (eig.eigenvalues()(0) >= kSingularBlock * top && top > 0.0) continue;
    Eigen::Vector3d dir = Eigen::Vector3d::Zero();
    for (Eigen::Index i = 0; i < m; ++i) dir(comps[static_cast<std::size_t>(i)]) = eig.eigenvectors()(i, 0);
    std::size_t count = 0;
    const std::string list = reaching(p, {s}, 5, count);
    throw Error(ErrorKind::input, "E_NETWORK_SINGULAR",
                net.source_name + ": station " + net.stations[s].id + " (" + net.stations[s].source + "): its position along its " +
                    direction_words(p, dir) + " is not determined by the " + std::to_string(count) + " measurement" +
                    (count == 1 ? "" : "s") + " that reach it" + (list.empty() ? "" : " (" + list + ")") +
                    "; add measurements or constrain it");
  }
}

// When the factorization fails past the datum and station checks, the
// direction the normal matrix leaves free is found and named: the matrix
// shifted by 10⁻¹⁰ of its diagonal is factored, and inverse iteration
// (three solves from a fixed start) turns any start towards its null
// direction; the stations (and orientations, Helmert parameters) that
// carry it are named with their components.
[[noreturn]] void explain_singularity(const Problem& p, const Normal& n, Index failed_column) {
  const auto& net = p.net;
  const Index u = p.layout.count;
  Eigen::VectorXd diag = Eigen::VectorXd::Zero(u);
  for (const auto& e : n.entries) {
    if (e.row == e.col) diag(e.row) += e.value;
  }
  std::vector<SymmetricEntry> shifted = n.entries;
  constexpr double kShift = 1e-10;
  for (Index k = 0; k < u; ++k) shifted.push_back({k, k, kShift * std::max(diag(k), std::numeric_limits<double>::min())});
  Index again = -1;
  std::optional<NormalFactor> f;
  try {
    f = NormalFactor::factor(u, shifted, p.o.dense ? NormalFactor::Mode::dense : NormalFactor::Mode::sparse, &again, std::nullopt,
                             p.o.memory_budget_bytes, resolve_jobs(p.o.jobs));
  } catch (const Error&) {
    f.reset();
  }
  if (!f) singular(p, failed_column);
  Eigen::VectorXd z(u);
  for (Index k = 0; k < u; ++k) z(k) = (1.0 + static_cast<double>((static_cast<std::uint64_t>(k) * 2654435761u) % 1000u) / 1000.0) /
                                      std::sqrt(std::max(diag(k), std::numeric_limits<double>::min()));
  for (int it = 0; it < 3; ++it) {
    z = f->solve(Eigen::VectorXd(diag.cwiseProduct(z)));
    z /= std::sqrt(z.dot(diag.cwiseProduct(z)));
  }
  if (!z.allFinite()) singular(p, failed_column);
  // Its share on each station (in the diagonal's metric), largest first.
  std::vector<double> share(net.stations.size(), 0.0);
  std::vector<Eigen::Vector3d> local(net.stations.size(), Eigen::Vector3d::Zero());
  std::string others;
  for (Index k = 0; k < u; ++k) {
    const auto [s, c] = p.layout.owner[static_cast<std::size_t>(k)];
    const double w = z(k) * z(k) * diag(k);
    if (c < 3) {
      share[s] += w;
      local[s](c) = z(k);
    } else if (w > 0.05) {
      others += (others.empty() ? "" : ", ") +
                (c == 3 ? "the orientation of the direction set at " + net.stations[net.direction_sets[s].station].id
                        : std::string("the Helmert parameter ") + kHelmertNames[s]);
    }
  }
  std::vector<std::size_t> involved;
  for (std::size_t s = 0; s < share.size(); ++s) {
    if (share[s] > 0.05) involved.push_back(s);
  }
  std::sort(involved.begin(), involved.end(), [&](std::size_t a, std::size_t b) { return share[a] > share[b]; });
  if (involved.empty() && others.empty()) singular(p, failed_column);
  std::string what;
  constexpr std::size_t kNamed = 6;
  for (std::size_t k = 0; k < involved.size() && k < kNamed; ++k) {
    what += (k ? ", " : "") + net.stations[involved[k]].id + " (" + direction_words(p, local[involved[k]]) + ")";
  }
  if (involved.size() > kNamed) what += " and " + std::to_string(involved.size() - kNamed) + " more";
  if (!others.empty()) what += (what.empty() ? "" : "; with ") + others;
  std::size_t count = 0;
  const std::string list = reaching(p, std::vector<std::size_t>(involved.begin(), involved.begin() + static_cast<std::ptrdiff_t>(std::min(involved.size(), kNamed))), 5, count);
  throw Error(ErrorKind::input, "E_NETWORK_SINGULAR",
              net.source_name + ": the normal equations are singular: the measurements and constraints leave a motion of " +
                  (involved.size() == 1 ? "station " : "stations ") + what +
                  " free (moving them together along it changes no measurement; " + std::to_string(count) +
                  " measurement" + (count == 1 ? " reaches" : "s reach") + " them" + (list.empty() ? "" : ": " + list) +
                  "); add measurements that tie them to the rest of the network, or constrain them");
}

// Moves the stations and orientations by the unknowns' corrections; returns
// the largest station correction (metres) and its station.
std::pair<double, std::size_t> apply_corrections(Problem& p, const Eigen::VectorXd& dx) {
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
    p.states[s] = station_state(net, p.geocentric, x);
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

NormalFactor factor_or_explain(const Problem& p, const Normal& n, std::optional<NormalFactor> previous = std::nullopt) {
  Index failed = -1;
  auto f = NormalFactor::factor(p.layout.count, n.entries, p.o.dense ? NormalFactor::Mode::dense : NormalFactor::Mode::sparse,
                                &failed, std::move(previous), p.o.memory_budget_bytes, resolve_jobs(p.o.jobs));
  if (!f) explain_singularity(p, n, failed);
  return std::move(*f);
}

ErrorEllipse ellipse_of(const Eigen::Matrix2d& en) {
  // en in (east, north); azimuth clockwise from north.
  const double a = en(0, 0), b = en(1, 1), ab = en(0, 1);
  const double mean = 0.5 * (a + b), diff = 0.5 * (a - b);
  const double root = std::sqrt(diff * diff + ab * ab);
  ErrorEllipse e;
  e.semi_major_m = std::sqrt(std::max(0.0, mean + root));
  e.semi_minor_m = std::sqrt(std::max(0.0, mean - root));
  e.azimuth_rad = 0.5 * std::atan2(2.0 * ab, b - a);  // from north towards east
  if (e.azimuth_rad < 0.0) e.azimuth_rad += std::numbers::pi;
  return e;
}

// The horizontal ellipse of a station's covariance in its local components:
// east, north (ellipsoidal: azimuth from north towards east) or x, y (local:
// from +x towards +y, a bearing when x is north and y east, as GNU Gama
// orients its ellipses). ellipse_of measures from its second axis towards
// its first, so a local network's x, y go in swapped.
ErrorEllipse horizontal_ellipse(const Eigen::Matrix2d& c, geodesy::NetworkSpace space) {
  if (space == geodesy::NetworkSpace::ellipsoidal) return ellipse_of(c);
  Eigen::Matrix2d yx;
  yx << c(1, 1), c(1, 0), c(0, 1), c(0, 0);
  return ellipse_of(yx);
}

}  // namespace

AdjustmentResult adjust_network(const geodesy::Network& network, const AdjustOptions& o) {
  if (network.stations.empty()) throw Error(ErrorKind::input, "E_NETWORK_EMPTY", network.source_name + ": no stations");
  if (std::all_of(network.measurements.begin(), network.measurements.end(), [](const auto& m) { return m.ignore; })) {
    throw Error(ErrorKind::input, "E_NETWORK_EMPTY",
                network.source_name + ": no measurement to adjust (" + std::to_string(network.measurements.size()) +
                    " read; each is ignored by its input or left out)");
  }
  std::size_t unplaced = 0;
  for (const auto& s : network.stations) unplaced += s.position_known ? 0u : 1u;
  if (unplaced > 0) {
    geodesy::Network placed = network;
    approximate_positions(placed);
    AdjustmentResult r = adjust_network(placed, o);
    r.warnings.insert(r.warnings.begin(), std::to_string(unplaced) + " station(s) had no a-priori coordinates: their "
                                          "approximate positions were computed from the measurements");
    return r;
  }
  Problem p(network, o);
  const auto& net = network;
  p.set_order = canonical_set_order(net);
  p.order = canonical_order(net, p.set_order);
  AdjustmentResult result;
  const int jobs = resolve_jobs(o.jobs);
  const std::string where = net.source_name;

  // Whitening of each measurement's covariance, on threads (each its own;
  // the first failure in the measurements' order is the one reported).
  p.whitening.resize(net.measurements.size());
  p.active.assign(net.measurements.size(), false);
  p.pattern_only.assign(net.measurements.size(), false);
  for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) p.active[mi] = !net.measurements[mi].ignore;
  for_chunks(net.measurements.size(), kMeasurementChunk, jobs, [&](std::size_t begin, std::size_t end) {
    for (std::size_t mi = begin; mi < end; ++mi) {
      const auto& m = net.measurements[mi];
      if (m.ignore) continue;
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(m.covariance, Eigen::EigenvaluesOnly);
      const double smallest = eig.eigenvalues().size() ? eig.eigenvalues()(0) : 0.0;
      const double largest = eig.eigenvalues().size() ? eig.eigenvalues().maxCoeff() : 0.0;
      if (!(smallest > 1e-15 * std::max(largest, 1e-300)) || !std::isfinite(largest)) {
        throw Error(ErrorKind::input, "E_COVARIANCE",
                    m.source + ": " + geodesy::to_string(m.kind) + ": the covariance is not positive definite (smallest "
                    "eigenvalue " + format_shortest(smallest) + ", largest " + format_shortest(largest) + ")");
      }
      const Eigen::LLT<Eigen::MatrixXd> llt(m.covariance);
      p.whitening[mi] = llt.matrixL().solve(Eigen::MatrixXd::Identity(m.covariance.rows(), m.covariance.cols()));
    }
  });
  p.free = o.free;
  p.aside = o.free;
  if (p.free) {
    std::size_t held = 0;
    for (const auto& s : net.stations) held += s.constraint.any() ? 1u : 0u;
    if (held > 0) {
      result.warnings.push_back("--free: the constraints of " + std::to_string(held) +
                                " station(s) in the input are set aside; the datum is the inner constraints'");
    }
  }

  // The state: a-priori positions; orientations from the first direction of each set.
  for (const auto& s : net.stations) p.states.push_back(station_state(net, p.geocentric, s.position));
  p.orientations.assign(net.direction_sets.size(), 0.0);
  if (o.helmert) {
    if (net.space != NetworkSpace::ellipsoidal) {
      throw Error(ErrorKind::usage, "E_OPTION", where + ": a Helmert transformation needs a network on the ellipsoid");
    }
    if (o.free) throw Error(ErrorKind::usage, "E_OPTION", "--estimate-helmert with --free: give the network's datum by constraints");
    p.helmert = Eigen::VectorXd::Zero(o.helmert->rates ? 14 : 7);
    p.helmert_slot.assign(net.measurements.size(), -1);
    for (std::size_t k = 0; k < o.helmert->measurements.size(); ++k) {
      const std::size_t mi = o.helmert->measurements[k];
      const auto kind = net.measurements.at(mi).kind;
      if (kind != geodesy::MeasurementKind::gnss_baselines && kind != geodesy::MeasurementKind::gnss_points) {
        throw Error(ErrorKind::input, "E_HELMERT_GROUP",
                    net.measurements[mi].source + ": " + geodesy::to_string(kind) + " in Helmert group " + o.helmert->name +
                        ": a datum transformation relates GNSS positions and baselines only");
      }
      p.helmert_slot[mi] = static_cast<int>(k);
    }
    std::size_t count = 0;
    std::vector<bool> seen(net.stations.size(), false);
    for (std::size_t mi : o.helmert->measurements) {
      for (std::size_t st : net.measurements[mi].stations) {
        if (seen[st]) continue;
        seen[st] = true;
        p.helmert_pivot += net.stations[st].position;
        ++count;
      }
    }
    if (count > 0) p.helmert_pivot /= static_cast<double>(count);
  }
  {
    std::vector<bool> seeded(net.direction_sets.size(), false);
    const ModelContext ctx{net, o, p.states, p.orientations};
    for (std::size_t mi : p.order) {
      const auto& m = net.measurements[mi];
      if (m.kind != MeasurementKind::direction || m.ignore || !m.set || seeded[*m.set]) continue;
      const Evaluation ev = evaluate(m, ctx);  // computed = bearing − 0
      p.orientations[*m.set] = ev.computed(0) - m.value(0);
      seeded[*m.set] = true;
    }
  }

  // Gross misclosures at the a-priori coordinates (GNU Gama's tol-abs):
  // set aside before the adjustment, each named.
  std::vector<std::string> gross_why(net.measurements.size());
  if (net.gross_misclosure_m > 0.0) {
    const ModelContext ctx{net, o, p.states, p.orientations};
    for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) {
      if (!p.active[mi]) continue;
      if (!p.helmert_slot.empty() && p.helmert_slot[mi] >= 0) continue;  // in a datum of its own, not yet known
      const auto& m = net.measurements[mi];
      Evaluation ev;
      try {
        ev = evaluate(m, ctx);
      } catch (const Error&) {
        continue;  // its geometry is judged by the adjustment
      }
      const Eigen::VectorXd w = misclosure(m, ev.computed);
      double length = 1.0;
      if (is_angular(m.kind) && m.stations.size() >= 2) {
        length = 0.0;
        for (std::size_t k = 1; k < m.stations.size(); ++k) {
          length = std::max(length, (p.states[m.stations[k]].x - p.states[m.stations[0]].x).norm());
        }
      }
      const double gross = w.cwiseAbs().maxCoeff() * length;
      if (gross > net.gross_misclosure_m) {
        p.active[mi] = false;
        gross_why[mi] = "misclosure " + fmt_m(gross) + " at the a-priori coordinates exceeds the input's tolerance " +
                        fmt_m(net.gross_misclosure_m);
        result.warnings.push_back(m.source + " (" + geodesy::to_string(m.kind) + "): set aside before the adjustment: " +
                                  gross_why[mi]);
      }
    }
  }

  // A station whose every measurement misses by more than the tolerance
  // has wrong a-priori coordinates, not only gross measurements: refused,
  // never left out of the results.
  if (net.gross_misclosure_m > 0.0) {
    std::vector<int> before(net.stations.size(), 0), after(net.stations.size(), 0);
    for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) {
      if (net.measurements[mi].ignore) continue;
      for (std::size_t st : net.measurements[mi].stations) {
        ++before[st];
        if (p.active[mi]) ++after[st];
      }
    }
    for (std::size_t st = 0; st < net.stations.size(); ++st) {
      if (before[st] > 0 && after[st] == 0) {
        throw Error(ErrorKind::input, "E_GROSS_MISCLOSURE",
                    net.stations[st].source + ": every measurement of station " + net.stations[st].id +
                        " misses by more than the input's tolerance " + fmt_m(net.gross_misclosure_m) +
                        " at its a-priori coordinates: check them (or its measurements)");
      }
    }
  }

  std::size_t removed = 0;
  const std::size_t countable = static_cast<std::size_t>(std::count(p.active.begin(), p.active.end(), true));
  FitOptions levels_of;
  levels_of.alpha_point = o.alpha_point;
  levels_of.power = o.power;
  const PointTestLevels levels = point_test_levels(levels_of);
  result.w_critical = levels.w_critical;
  result.alpha_point = o.alpha_point;
  std::vector<std::string> outlier_why = gross_why;

  const std::vector<std::string> base_warnings = result.warnings;
  std::optional<NormalFactor> last_factor;
  // Data snooping: what the last pass removed, and the unknowns it had.
  std::vector<std::size_t> removed_last_pass;
  Layout last_layout;
  std::vector<std::string> datum_warnings;  // the datum's weakly defined combinations (each pass that probes it)
  std::vector<std::size_t> rank_of(net.measurements.size(), 0);  // data snooping's order (snooping_rank)
  for (;;) {
    result.warnings = base_warnings;  // each pass states its own
    ++result.passes;
    // Stations reached by the measurements; the rest are left out.
    p.station_used.assign(net.stations.size(), false);
    for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) {
      if (!p.active[mi]) continue;
      for (std::size_t s : net.measurements[mi].stations) p.station_used[s] = true;
    }
    std::size_t components = 0;
    const auto component = components_of(p, components);
    if (components > 1) {
      std::map<std::size_t, std::vector<std::string>> members;
      for (std::size_t s = 0; s < net.stations.size(); ++s) {
        if (p.station_used[s]) members[component[s]].push_back(net.stations[s].id);
      }
      std::string list;
      for (const auto& [k, ids] : members) {
        list += (list.empty() ? "" : "; ") + std::to_string(ids.size()) + " station" + (ids.size() == 1 ? "" : "s") + " (" +
                ids.front() + (ids.size() > 1 ? ", " + ids[1] : "") + (ids.size() > 2 ? ", …" : "") + ")";
      }
      throw Error(ErrorKind::input, "E_NETWORK_DISCONNECTED",
                  where + ": the network falls into " + std::to_string(components) +
                      " parts that no measurement joins: " + list + "; adjust them separately or join them");
    }
    p.layout = make_layout(p);
    // A later pass of a GNSS network (linear, its matrix the same at every
    // state) with the same unknowns: data snooping took measurements out,
    // no station. Its datum is the last pass's (the translations, held by
    // the same constraints: the network stays whole), not probed again.
    const bool same_unknowns = result.passes > 1 && p.layout == last_layout && constant_jacobian(p);
    // A GNSS network (linear, its matrix the same at every state) that lost
    // a few measurements to data snooping and no unknown: they are taken
    // out of the last factor and its selected inverse (a downdate) instead
    // of factoring and inverting again (NormalFactor::downdate).
    bool downdated = false;
    if (!removed_last_pass.empty() && o.snooping_downdates && last_factor && same_unknowns) {
      const auto t0 = Clock::now();
      std::vector<Rows> taken;
      Eigen::Index rows = 0;
      for (std::size_t mi : removed_last_pass) {
        taken.push_back(p.linearize(mi));
        rows += taken.back().l.size();
      }
      if (last_factor->downdated_rows() + rows <= last_factor->downdate_rows_worth()) {
        Eigen::MatrixXd b = Eigen::MatrixXd::Zero(p.layout.count, rows);
        Eigen::Index column = 0;
        for (const Rows& r : taken) {
          for (Eigen::Index i = 0; i < r.a.rows(); ++i, ++column) {
            for (std::size_t k = 0; k < r.unknowns.size(); ++k) b(r.unknowns[k], column) = r.a(i, static_cast<Eigen::Index>(k));
          }
        }
        downdated = last_factor->downdate(b, jobs);
        result.passes_downdated += downdated ? 1 : 0;
      }
      result.seconds.downdate += since(t0);
    }
    removed_last_pass.clear();
    last_layout = p.layout;
    p.inner.clear();
    p.inner_components.clear();
    p.free = o.free;  // a pass may find the constraints leave a defect (datum stations)
    p.defect.resize(0, 0);
    if (p.free) {
      if (o.inner_constraint_stations.empty()) {
        for (std::size_t s = 0; s < net.stations.size(); ++s) {
          if (p.station_used[s]) p.inner.push_back(s);
        }
      } else {
        for (const auto& id : o.inner_constraint_stations) {
          const auto s = net.find(id);
          if (!s) throw Error(ErrorKind::usage, "E_OPTION", "--inner-constraints " + id + ": no station of that name in " + where);
          if (!p.station_used[*s]) {
            throw Error(ErrorKind::usage, "E_OPTION", "--inner-constraints " + id + ": the station has no measurement");
          }
          p.inner.push_back(*s);
        }
      }
    }

    // Gauss–Newton. Each factorization hands its analysis to the next (the
    // pattern is the first pass's, while the measurements snooping removes
    // keep their place as zeros).
    bool converged = false;
    double largest = 0.0;
    std::size_t largest_at = 0;
    int iteration = 0;
    for (iteration = 1; iteration <= o.max_iterations; ++iteration) {
      // A normal matrix that cannot have changed is not factored again.
      const bool same_matrix = (iteration > 1 || downdated) && last_factor && constant_jacobian(p);
      auto t0 = Clock::now();
      Normal n = assemble(p, !same_matrix, jobs);
      result.seconds.assemble += since(t0);
      if (iteration == 1 && !same_unknowns) {
        // The datum, judged against the network's own precision
        // (datum_information): what the measurements and the constraints
        // leave undefined of the translations, rotations and scale. A
        // station the measurements do not fix on its own is no datum
        // defect but a singularity, named below.
        const auto datum_t0 = Clock::now();
        const Layout probe = make_layout(p, true);
        const DatumVectors dv = datum_vectors(p, probe);
        const DatumInformation info = datum_information(p, probe, dv.g, jobs);
        const DatumRank weak = undefined_datum(p, probe, dv.g, info, kWeakDatumRelative);
        std::size_t stations = 0;
        for (std::size_t st = 0; st < net.stations.size(); ++st) stations += p.station_used[st] ? 1u : 0u;
        const auto resolution = [&](double ratio) { return datum_resolution(ratio, stations); };
        std::size_t below = 0;
        while (below < weak.ratio.size() &&
               (weak.ratio[below] < kUndefinedDatumRelative || resolution(weak.ratio[below]) > kUnresolvedDatum)) {
          ++below;
        }
        const Eigen::MatrixXd undefined =
            unit_motions(p, probe, dv.g, weak.combinations.leftCols(static_cast<Eigen::Index>(below)));
        std::vector<std::string> names;
        for (Eigen::Index k = 0; k < undefined.cols(); ++k) names.push_back(name_combination(dv.basis * undefined.col(k), dv.names));
        // (Those told of, by measurements or weighted constraints, above
        // rounding but too weakly for double precision, say so.)
        std::size_t unresolved = 0;
        for (std::size_t k = 0; k < below; ++k) unresolved += weak.ratio[k] >= kToldOf ? 1u : 0u;
        if (!p.free && undefined.cols() > 0) {
          if (!net.datum_stations.empty()) {
            // What the constraints leave undefined is held by the input's
            // own datum stations (GNU Gama's constrained points): the
            // minimum-norm solution over them, the fixed components kept.
            p.free = true;
            for (const auto& ds : net.datum_stations) {
              if (p.station_used[ds.station]) p.inner.push_back(ds.station), p.inner_components.push_back(ds.components);
            }
            if (p.inner.empty()) {
              throw Error(ErrorKind::input, "E_DATUM_DEFECT",
                          where + ": the datum is not defined and none of the input's datum stations has a measurement");
            }
          } else {
            std::string list;
            for (const auto& x : names) list += (list.empty() ? "" : "; ") + x;
            const std::string weakly = "at " + fmt(weak.ratio[below - 1], 2) +
                                       " of what a typical station is told or less, which double precision does not resolve "
                                       "in a network of " + std::to_string(stations) + " stations";
            const std::string what =
                unresolved == names.size()
                    ? "the datum is not defined to what double precision resolves: the measurements and constraints tell the " + list +
                          " only " + weakly
                    : "the datum is not defined: neither the measurements nor the constraints fix the " + list +
                          (names.size() == 1 ? "" : " (" + std::to_string(names.size()) + " combinations)") +
                          (unresolved > 0 ? "; " + std::to_string(unresolved) + " of them they tell only " + weakly : std::string());
            throw Error(ErrorKind::input, "E_DATUM_DEFECT",
                        where + ": " + what +
                            (o.helmert ? "; the Helmert of group " + o.helmert->name +
                                             " takes up the datum its measurements would give: constrain stations "
                                             "(--constrain ID=CCC[,SIGMA_M]) or add measurements in the network's frame"
                                       : "; constrain stations (--constrain ID=CCC[,SIGMA_M]) or adjust it as a free network (--free)"));
          }
        }
        p.defect_motions = dv.basis * undefined;
        p.defect = datum_vectors(p, p.layout).named * p.defect_motions;  // over the unknowns (no fixed component moves)
        p.defect_names = names;
        p.motion_names = dv.names;
        if (p.free && p.defect.cols() > 0) {
          check_inner_stations(p, net.datum_stations.empty() || o.free);
          choose_anchors(p);
        }
        // Defined by the measurements, but weakly: named, with the
        // standard deviation it then has at least. A datum held by weighted
        // constraints is the user's business, unless it is held so weakly
        // that double precision cannot resolve its standard deviation: the
        // factorization's rounding along it grows as √n times a station's
        // (measured: a 3 km hold at one of 900 stations of millimetre
        // baselines, ratio 6·10⁻¹⁴, gives its σ 1.9 % off).
        datum_warnings.clear();
        for (Eigen::Index k = static_cast<Eigen::Index>(below); k < weak.combinations.cols(); ++k) {
          const auto c = static_cast<std::size_t>(k);
          const double resolved = resolution(weak.ratio[c]);
          const bool by_measurements = weak.measured[c] >= weak.weighted[c];
          if (!by_measurements && resolved <= kDatumResolution) continue;
          const Eigen::VectorXd y = weak.combinations.col(k);
          double motion2 = 0.0;
          const Eigen::VectorXd gy = dv.g * y;
          for (std::size_t uk = 0; uk < probe.owner.size(); ++uk) {
            if (probe.owner[uk].second < 3) motion2 += gy(static_cast<Eigen::Index>(uk)) * gy(static_cast<Eigen::Index>(uk));
          }
          const double rms = std::sqrt(motion2 / static_cast<double>(std::max<std::size_t>(stations, 1)));
          const double told = weak.measured[c] + weak.weighted[c];
          const std::string sigma = fmt_m(told > 0.0 ? rms / std::sqrt(told) : std::numeric_limits<double>::infinity());
          const std::string precision =
              resolved > kDatumResolution ? "; double precision resolves that standard deviation only to about " +
                                                fmt(100.0 * resolved, 2) + " %"
                                          : std::string();
          if (by_measurements) {
            datum_warnings.push_back("the datum's " + name_combination(dv.basis * y, dv.names) +
                                     " is defined only weakly by the measurements: they tell it at " + fmt(weak.ratio[c], 2) +
                                     " of what a typical station is told; its standard deviation is at least " + sigma +
                                     " at the stations (RMS)" + precision + ": constrain stations or add measurements that fix it");
          } else {
            datum_warnings.push_back("the datum's " + name_combination(dv.basis * y, dv.names) +
                                     " is held by the weighted constraints alone, at " + fmt(weak.ratio[c], 2) +
                                     " of what a typical station is told (its standard deviation " + sigma +
                                     " at the stations, RMS)" + precision + ": hold it with smaller standard deviations");
          }
        }
        result.seconds.datum += since(datum_t0);
        check_station_blocks(p, n);
      } else if (p.free && p.defect.cols() > 0) {
        // The same combinations of the motions, at the moved positions.
        p.defect = datum_vectors(p, p.layout).named * p.defect_motions;
      }
      hold_defect(p, n);
      t0 = Clock::now();
      if (!same_matrix) last_factor = factor_or_explain(p, n, std::move(last_factor));
      result.seconds.factor += since(t0);
      t0 = Clock::now();
      const Eigen::VectorXd dx = last_factor->solve(n.b);
      result.seconds.solve += since(t0);
      if (!dx.allFinite()) explain_singularity(p, n, -1);
      const auto [moved, at] = apply_corrections(p, dx);
      largest = moved;
      largest_at = at;
      if (moved < o.convergence_m) {
        converged = true;
        break;
      }
    }
    result.iterations += std::min(iteration, o.max_iterations);
    result.largest_correction_m = largest;
    if (!converged) {
      throw Error(ErrorKind::rejected, "E_NOT_CONVERGED",
                  where + ": the adjustment did not converge in " + std::to_string(o.max_iterations) +
                      " iterations: the last moved " +
                      (largest_at < net.stations.size() ? "station " + net.stations[largest_at].id
                                                        : "the Helmert of group " + o.helmert->name + " (at the surface)") +
                      " by " + fmt_m(largest) +
                      " (threshold " + format_shortest(o.convergence_m) + " m); check the a-priori coordinates and units");
    }

    // Free network: the minimum-norm solution over the inner stations (an
    // S-transformation of the solution held at the anchors).
    Eigen::MatrixXd inner_e, inner_m;
    if (p.free && p.defect.cols() > 0) {
      inner_e = restricted(p, p.inner, p.inner_components);
      inner_m = (inner_e.transpose() * p.defect).inverse();
      Eigen::VectorXd corrections = Eigen::VectorXd::Zero(p.layout.count);
      for (std::size_t s : p.inner) {
        const Eigen::Vector3d d = p.states[s].axes * (p.states[s].x - net.stations[s].position);
        for (int c = 0; c < 3; ++c) {
          const Index u = p.layout.station[s][static_cast<std::size_t>(c)];
          if (u >= 0) corrections(u) = d(c);
        }
      }
      const Eigen::VectorXd t = -inner_m * (inner_e.transpose() * corrections);
      apply_corrections(p, p.defect * t);
    }

    // The statistics at the solution (with the last iteration's factor
    // when the matrix is the same).
    const bool same_matrix = last_factor && constant_jacobian(p);
    auto t0 = Clock::now();
    Normal n;
    if (same_matrix) {
      // Nothing to assemble: the matrix is factored, b is not needed (and a
      // GNSS network is not free: no defect to hold).
      for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) {
        if (p.active[mi]) n.rows += static_cast<std::size_t>(net.measurements[mi].value.size());
      }
      n.rows += p.pseudo_observations().size();
    } else {
      n = assemble(p, true, jobs);
      hold_defect(p, n);
    }
    result.seconds.assemble += since(t0);
    t0 = Clock::now();
    NormalFactor f = same_matrix ? std::move(*last_factor) : factor_or_explain(p, n, std::move(last_factor));
    result.seconds.factor += since(t0);
    t0 = Clock::now();
    if (!downdated) f.select_inverse(jobs);  // (a downdate updated it)
    result.seconds.select_inverse += since(t0);
    t0 = Clock::now();
    result.factor_nonzeros = f.factor_nonzeros();
    result.unknowns = static_cast<std::size_t>(p.layout.count);
    result.observations = n.rows;
    const int defect = p.free ? static_cast<int>(p.defect.cols()) : 0;
    result.dof = static_cast<int>(n.rows) - static_cast<int>(p.layout.count) + defect;

    // Per measurement, on `jobs` threads: each measurement's results are
    // its own, so they do not depend on the threads. A measurement left out
    // is tested by solves with the factor (CHOLMOD's solve is not shared
    // between threads): after the others, on this thread.
    std::vector<std::size_t> listed;  // the measurements reported (ignored ones left out)
    for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) {
      if (!net.measurements[mi].ignore) listed.push_back(mi);
    }
    std::vector<AdjustedMeasurement> measured(listed.size());
    std::vector<char> deferred(listed.size(), 0);
    const auto measure = [&](std::size_t slot, bool defer_left_out) {
      const std::size_t mi = listed[slot];
      const auto& m = net.measurements[mi];
      AdjustedMeasurement& am = measured[slot];
      const bool in = p.active[mi];
      const bool was_outlier = !in && !outlier_why[mi].empty();
      // An outlier is tested against the adjustment (its prediction) where its stations are in it.
      bool testable = in;
      if (was_outlier) {
        testable = true;
        for (std::size_t s : m.stations) testable = testable && p.station_used[s];
        if (m.set) testable = testable && p.layout.orientation[*m.set] >= 0;  // its set still has an orientation
      }
      am = AdjustedMeasurement{};
      am.index = mi;
      am.used = in;
      am.outlier = was_outlier;
      am.removed_because = outlier_why[mi];
      am.snooping_rank = rank_of[mi];
      am.observed = m.value;
      am.sigma = m.covariance.diagonal().cwiseSqrt();
      const Eigen::Index k = m.value.size();
      if (!testable) {
        am.adjusted = am.residual = am.residual_sigma = am.w = am.mdb = Eigen::VectorXd::Constant(k, kNaN);
        am.redundancy = Eigen::VectorXd::Zero(k);
        return;
      }
      const Rows r = p.linearize(mi);
      am.adjusted = r.computed;
      am.residual = -misclosure(m, r.computed);  // adjusted − observed
      // A Q Aᵀ over the measurement's unknowns, from the selected inverse.
      const std::size_t nu = r.unknowns.size();
      Eigen::MatrixXd q(static_cast<Eigen::Index>(nu), static_cast<Eigen::Index>(nu));
      bool on_pattern = in;
      if (!in) {
        // A measurement left out keeps its place in the pattern while
        // snooping reuses the analysis (Problem::pattern_only): read there.
        on_pattern = f.inverse_block(r.unknowns.data(), nu, q.data());
        if (!on_pattern && defer_left_out) {
          deferred[slot] = 1;
          return;
        }
      }
      if (!on_pattern) {
        // Its unknowns may share no other measurement (off the factor's
        // pattern): solve for its columns.
        Eigen::MatrixXd e = Eigen::MatrixXd::Zero(p.layout.count, static_cast<Eigen::Index>(nu));
        for (std::size_t a = 0; a < nu; ++a) e(r.unknowns[a], static_cast<Eigen::Index>(a)) = 1.0;
        const Eigen::MatrixXd z = f.solve(e);
        for (std::size_t a = 0; a < nu; ++a) {
          for (std::size_t b = 0; b < nu; ++b) {
            q(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) = z(r.unknowns[a], static_cast<Eigen::Index>(b));
          }
        }
        q = (0.5 * (q + q.transpose())).eval();
      }
      if (in && !f.inverse_block(r.unknowns.data(), nu, q.data())) {
        throw std::logic_error("adjust_network: a measurement's unknowns are off the factor's pattern");
      }
      const Eigen::MatrixXd aqa = r.a * q * r.a.transpose();
      const Eigen::MatrixXd qv = in ? Eigen::MatrixXd(Eigen::MatrixXd::Identity(k, k) - aqa)
                                    : Eigen::MatrixXd(Eigen::MatrixXd::Identity(k, k) + aqa);
      const ObservationTest t = test_observation(am.residual, p.whitening[mi], qv, Eigen::MatrixXd::Identity(k, k), in, 1.0,
                                                 levels.lambda0);
      am.w = t.w;
      am.redundancy = t.redundancy;
      am.mdb = t.mdb;
      am.w_max = t.w_max;
      am.statistic = t.statistic;
      am.test_dof = t.dof;
      am.p_value = t.p_value;
      am.log_p = t.log_p;
      // σ of the residual: W⁻¹ Q_v W⁻ᵀ.
      const Eigen::MatrixXd w_inv = p.whitening[mi].inverse();
      am.residual_sigma = (w_inv * qv * w_inv.transpose()).diagonal().cwiseMax(0.0).cwiseSqrt();
    };
    for_chunks(listed.size(), kMeasurementChunk, jobs, [&](std::size_t begin, std::size_t end) {
      for (std::size_t slot = begin; slot < end; ++slot) measure(slot, true);
    });
    for (std::size_t slot = 0; slot < listed.size(); ++slot) {
      if (deferred[slot]) measure(slot, false);
    }
    // vᵀPv in the canonical order.
    double vtpv = 0.0;
    {
      std::vector<std::size_t> slot_of(net.measurements.size(), listed.size());
      for (std::size_t slot = 0; slot < listed.size(); ++slot) slot_of[listed[slot]] = slot;
      for (std::size_t mi : p.order) {
        if (slot_of[mi] == listed.size()) continue;
        const auto& am = measured[slot_of[mi]];
        if (am.used) vtpv += (p.whitening[am.index] * am.residual).squaredNorm();
      }
    }
    result.measurements = std::move(measured);
    for (const auto& q : p.pseudo_observations()) vtpv += q.l * q.l;
    result.vtpv = vtpv;
    result.variance_factor = result.dof > 0 ? std::optional<double>(vtpv / result.dof) : std::nullopt;
    result.sigma0 = result.variance_factor ? std::optional<double>(std::sqrt(*result.variance_factor)) : std::nullopt;
    result.global_test = global_test(vtpv, result.dof, o.alpha, true);

    result.seconds.measurements += since(t0);

    // Data snooping (snooping.hpp): the failing measurements in the order
    // iterative snooping removes them, each the strongest evidence once the
    // ones before it are out. Flagged and kept; with remove_outliers they
    // go, and the network is adjusted and tested again (ranks continue).
    if (o.data_snooping && result.dof > 0) {
      const auto snooping_t0 = Clock::now();
      std::vector<std::size_t> failing;  // positions in result.measurements
      std::vector<std::string> keys(result.measurements.size());
      const std::vector<std::size_t> set_rank = set_ranks(p.set_order);
      for (std::size_t k = 0; k < result.measurements.size(); ++k) {
        if (!result.measurements[k].fails_test(o.alpha_point)) continue;
        failing.push_back(k);
        const auto& m = net.measurements[result.measurements[k].index];
        keys[k] = measurement_key(net, m, m.set && *m.set < set_rank.size() ? set_rank[*m.set] + 1 : 0);
      }
      // In the order of their content, so that the cofactors' solves are
      // batched the same for any order of the input.
      std::stable_sort(failing.begin(), failing.end(), [&](std::size_t a, std::size_t b) { return keys[a] < keys[b]; });
      if (!failing.empty()) {
        NetworkCofactors cofactors(f, p.layout.count, jobs);
        std::vector<SnoopingCandidate> candidates(failing.size());
        for (std::size_t c = 0; c < failing.size(); ++c) {
          const AdjustedMeasurement& am = result.measurements[failing[c]];
          const std::size_t mi = am.index;
          Rows r = p.linearize(mi);
          const std::size_t nu = r.unknowns.size();
          Eigen::MatrixXd q(static_cast<Eigen::Index>(nu), static_cast<Eigen::Index>(nu));
          if (!f.inverse_block(r.unknowns.data(), nu, q.data())) {
            throw std::logic_error("adjust_network: a measurement's unknowns are off the factor's pattern");
          }
          const Eigen::Index k = r.a.rows();
          candidates[c].v = p.whitening[mi] * am.residual;
          candidates[c].q = Eigen::MatrixXd::Identity(k, k) - r.a * q * r.a.transpose();
          candidates[c].key = std::move(keys[failing[c]]);
          cofactors.add(std::move(r.unknowns), std::move(r.a));
        }
        const std::size_t limit = std::max<std::size_t>(
            1, static_cast<std::size_t>(std::floor(o.max_outlier_share * static_cast<double>(countable))));
        SnoopingLimits limits;
        limits.alpha = o.alpha_point;
        limits.max_removals = limit > removed ? limit - removed : 0;
        const SnoopingSequence seq = snooping_sequence(candidates, cofactors, limits);
        result.seconds.snooping += since(snooping_t0);
        const auto measurement_of = [&](std::size_t c) -> AdjustedMeasurement& { return result.measurements[failing[c]]; };
        const auto name_of = [&](const AdjustedMeasurement& am) {
          return net.measurements[am.index].source + " (" + geodesy::to_string(net.measurements[am.index].kind) + ")";
        };
        const auto describe = [&](const AdjustedMeasurement& am) {
          return "measurement test " + fmt(am.statistic, 4) + " (χ²(" + std::to_string(am.test_dof) + "), p = " +
                 fmt(am.p_value, 3) + " < " + format_shortest(o.alpha_point) + "); max |w| " + format_fixed(am.w_max, 2);
        };
        for (std::size_t k = 0; k < seq.removals.size(); ++k) {
          AdjustedMeasurement& am = measurement_of(seq.removals[k].candidate);
          am.snooping_rank = removed + k + 1;
          rank_of[am.index] = am.snooping_rank;
        }
        for (std::size_t c = 0; c < candidates.size(); ++c) {
          measurement_of(c).passes_after_rank =
              seq.passes_after[c] >= 0 ? removed + static_cast<std::size_t>(seq.passes_after[c]) + 1 : 0;
        }
        const std::string stops = "; data snooping stops there (the weaker failing measurements may fail because of it, so "
                                  "none is removed in its place)";
        for (std::size_t c : seq.not_removable) {
          const AdjustedMeasurement& am = measurement_of(c);
          result.warnings.push_back(name_of(am) + " fails its " + describe(am) +
                                    " but cannot be removed: the rest of the network does not determine all of what it measures" +
                                    stops);
        }
        for (const auto& group : seq.inseparable) {
          std::string names;
          for (std::size_t c : group) names += (names.empty() ? "" : ", ") + name_of(measurement_of(c));
          result.warnings.push_back(
              names + " fail their measurement tests and cannot be told apart: with " + name_of(measurement_of(group.front())) +
              " removed the others could no longer be tested along the direction they share (their residuals are correlated by "
              "±1 there); one of them is wrong, none is removed" + stops);
        }
        // Past the limit: with --remove-outliers the measurements up to it
        // go first (the next pass refuses, with them out), unless the
        // sequence found the failures hopeless (then it refuses now); else
        // named.
        if (seq.limit_reached && (!o.remove_outliers || seq.removals.empty() || seq.hopeless)) {
          const SnoopingTest& worst_test = seq.still_failing.front();
          const AdjustedMeasurement& worst = measurement_of(worst_test.candidate);
          const std::size_t sequenced = removed + seq.removals.size();
          const std::string why =
              "data snooping " + std::string(o.remove_outliers ? "stopped" : "would stop") + " after removing " +
              std::to_string(o.remove_outliers ? removed : sequenced) + " of " + std::to_string(countable) + " measurements" +
              (seq.hopeless ? " (" + std::to_string(seq.still_failing.size()) + " fail, more than the " +
                                  std::to_string(limit - std::min(limit, sequenced)) + " removals left under the limit, and the last " +
                                  std::to_string(kHopelessWindow) + " removals explained almost none of the others)"
                            : " (the limit is " + format_shortest(100.0 * o.max_outlier_share) + " %, --max-outlier-share)") +
              ": " + name_of(worst) + " would still fail its measurement test with those out (" + fmt(worst_test.statistic, 4) +
              ", χ²(" + std::to_string(worst_test.dof) + "), p = " + fmt(worst_test.p_value, 3) + "; as adjusted: " + describe(worst) +
              "); " + std::to_string(seq.still_failing.size()) +
              " measurements would fail then. So many failures mean the data or the model is wrong (frames, units, heights, "
              "station names), not a few blunders";
          if (o.remove_outliers) result.refused_because = why;
          result.warnings.push_back(why);
        } else if (o.remove_outliers && !seq.removals.empty()) {
          for (const SnoopingTest& x : seq.removals) {
            const AdjustedMeasurement& am = measurement_of(x.candidate);
            const std::size_t mi = am.index;
            outlier_why[mi] = "data snooping (rank " + std::to_string(am.snooping_rank) + "): " + describe(am) +
                              (x.statistic != am.statistic
                                   ? " (with the measurements removed before it: " + fmt(x.statistic, 4) + ", p = " +
                                         fmt(x.p_value, 3) + ")"
                                   : std::string());
            p.active[mi] = false;
            const auto kind = net.measurements[mi].kind;
            p.pattern_only[mi] = kind == MeasurementKind::gnss_baselines || kind == MeasurementKind::gnss_points;
            removed_last_pass.push_back(mi);
          }
          removed += seq.removals.size();
          result.removed_per_pass.push_back(seq.removals.size());
          last_factor = std::move(f);  // its analysis serves the next pass (the same pattern)
          continue;  // adjust again without them
        }
      }
    }

    t0 = Clock::now();
    // Stations: coordinates and covariances (S-transformed for a free network).
    const std::size_t d = static_cast<std::size_t>(p.defect.cols());
    Eigen::MatrixXd ze, eze;  // Z E (u × d) and Eᵀ Z E
    if (p.free && d > 0) {
      ze = f.solve(Eigen::MatrixXd(inner_e));
      eze = inner_e.transpose() * ze;
    }
    auto q_block = [&](std::size_t s1, std::size_t s2) {
      Eigen::Matrix3d q = Eigen::Matrix3d::Zero();
      for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
          const Index ua = p.layout.station[s1][static_cast<std::size_t>(a)], ub = p.layout.station[s2][static_cast<std::size_t>(b)];
          if (ua < 0 || ub < 0) continue;
          double v = f.inverse(ua, ub);
          if (p.free && d > 0) {
            // S Z Sᵀ, S = I − D M Eᵀ.
            const Eigen::RowVectorXd da = p.defect.row(ua) * inner_m, db = p.defect.row(ub) * inner_m;
            v += -da.dot(ze.row(ub)) - ze.row(ua).dot(db) + da * eze * db.transpose();
          }
          q(a, b) = v;
        }
      }
      return q;
    };
    const double confidence_scale = std::sqrt(-2.0 * std::log(1.0 - o.confidence));  // √χ²₂(p)
    // Each station its own (on threads).
    result.stations.assign(net.stations.size(), AdjustedStation{});
    for_chunks(net.stations.size(), kMeasurementChunk, jobs, [&](std::size_t begin, std::size_t end) {
      for (std::size_t s = begin; s < end; ++s) {
        AdjustedStation& as = result.stations[s];
        as.id = net.stations[s].id;
        as.position = p.states[s].x;
        as.a_priori = net.stations[s].position;
        as.constraint = p.aside ? "FFF" : net.stations[s].constraint.text();
        as.used = p.station_used[s];
        if (as.used) {
          // q_block is along the unknowns' axes; the local ones are those at the adjusted position.
          const Eigen::Matrix3d& axes = p.states[s].axes;
          const Eigen::Matrix3d& local = p.states[s].local_from_xyz;
          as.covariance_m2 = axes.transpose() * q_block(s, s) * axes;
          as.covariance_local_m2 = local * as.covariance_m2 * local.transpose();
          as.ellipse = horizontal_ellipse(as.covariance_local_m2.topLeftCorner<2, 2>(), net.space);
          as.ellipse_confidence = as.ellipse;
          as.ellipse_confidence.semi_major_m *= confidence_scale;
          as.ellipse_confidence.semi_minor_m *= confidence_scale;
        }
      }
    });
    if (o.joint_covariance) {
      result.covariance_stations.clear();
      for (std::size_t s = 0; s < net.stations.size(); ++s) {
        if (p.station_used[s]) result.covariance_stations.push_back(s);
      }
      const std::size_t m = result.covariance_stations.size();
      if (m > kMaxJointCovarianceStations) {
        throw Error(ErrorKind::usage, "E_JOINT_COVARIANCE",
                    where + ": the joint covariance of " + std::to_string(m) + " stations (" +
                        format_shortest(72.0 * static_cast<double>(m) * static_cast<double>(m) / 1e9) +
                        " GB) is more than geoanchor writes (at most " + std::to_string(kMaxJointCovarianceStations) +
                        " stations); the stations CSV carries each station's covariance");
      }
      // Z E_s: the columns of N⁻¹ for every station unknown.
      Eigen::MatrixXd sel = Eigen::MatrixXd::Zero(p.layout.count, static_cast<Eigen::Index>(3 * m));
      for (std::size_t i = 0; i < m; ++i) {
        for (int c = 0; c < 3; ++c) {
          const Index u = p.layout.station[result.covariance_stations[i]][static_cast<std::size_t>(c)];
          if (u >= 0) sel(u, static_cast<Eigen::Index>(3 * i) + c) = 1.0;
        }
      }
      const Eigen::MatrixXd z = f.solve(sel);
      Eigen::MatrixXd q = sel.transpose() * z;  // local axes
      if (p.free && d > 0) {
        const Eigen::MatrixXd dm = sel.transpose() * (p.defect * inner_m);  // (3m × d)
        const Eigen::MatrixXd zes = sel.transpose() * ze;                  // (3m × d)
        q += -dm * zes.transpose() - zes * dm.transpose() + dm * eze * dm.transpose();
      }
      q = (0.5 * (q + q.transpose())).eval();
      // To ECEF (ellipsoidal) per station block: Rᵢᵀ Q Rⱼ.
      result.station_covariance_m2.resize(static_cast<Eigen::Index>(3 * m), static_cast<Eigen::Index>(3 * m));
      for (std::size_t i = 0; i < m; ++i) {
        const Eigen::Matrix3d ri = p.states[result.covariance_stations[i]].axes;
        for (std::size_t j = 0; j < m; ++j) {
          const Eigen::Matrix3d rj = p.states[result.covariance_stations[j]].axes;
          result.station_covariance_m2.block<3, 3>(static_cast<Eigen::Index>(3 * i), static_cast<Eigen::Index>(3 * j)) =
              ri.transpose() * q.block<3, 3>(static_cast<Eigen::Index>(3 * i), static_cast<Eigen::Index>(3 * j)) * rj;
        }
      }
    }
    result.orientations_rad = p.orientations;
    result.orientation_sigmas_rad.clear();
    for (std::size_t k = 0; k < p.orientations.size(); ++k) {
      const Index u = p.layout.orientation[k];
      result.orientation_sigmas_rad.push_back(u >= 0 ? std::sqrt(std::max(0.0, f.inverse(u, u))) : kNaN);
    }
    if (!p.layout.helmert.empty()) {
      const auto n_par = static_cast<Eigen::Index>(p.layout.helmert.size());
      Eigen::MatrixXd covariance(n_par, n_par);
      for (Eigen::Index i = 0; i < n_par; ++i) {
        for (Eigen::Index j = 0; j < n_par; ++j) {
          covariance(i, j) = f.inverse(p.layout.helmert[static_cast<std::size_t>(i)], p.layout.helmert[static_cast<std::size_t>(j)]);
        }
      }
      result.helmert = geocentric_helmert(p.helmert, covariance, p.helmert_pivot, o.helmert->rates);
    }
    // Relative precision between stations that share a measurement.
    std::vector<std::pair<std::size_t, std::size_t>> pairs;
    for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) {
      if (!p.active[mi]) continue;
      // The stations a measurement joins: a baseline's ends, a terrestrial
      // measurement's stations (not a point cluster's points, which it
      // positions each on its own).
      const auto& m = net.measurements[mi];
      const auto& st = m.stations;
      if (m.kind == MeasurementKind::gnss_points) continue;
      for (std::size_t a = 0; a < st.size(); ++a) {
        for (std::size_t b = a + 1; b < st.size(); ++b) {
          if (m.kind == MeasurementKind::gnss_baselines && !(a % 2 == 0 && b == a + 1)) continue;
          if (st[a] != st[b]) pairs.push_back({std::min(st[a], st[b]), std::max(st[a], st[b])});
        }
      }
    }
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    result.relative.assign(pairs.size(), RelativePrecision{});
    for_chunks(pairs.size(), kMeasurementChunk, jobs, [&](std::size_t begin, std::size_t end) {
      for (std::size_t k = begin; k < end; ++k) {
        const auto [s1, s2] = pairs[k];
        // In the axes of the first station; a local network's axes are one.
        const Eigen::Matrix3d a1 = p.states[s1].axes, a2 = p.states[s2].axes, r1 = p.states[s1].local_from_xyz;
        const Eigen::Matrix3d c11 = a1.transpose() * q_block(s1, s1) * a1, c22 = a2.transpose() * q_block(s2, s2) * a2;
        const Eigen::Matrix3d c12 = a1.transpose() * q_block(s1, s2) * a2;
        const Eigen::Matrix3d diff = r1 * (c11 + c22 - c12 - c12.transpose()) * r1.transpose();
        RelativePrecision rp;
        rp.from = s1;
        rp.to = s2;
        const Eigen::Vector3d dxyz = p.states[s2].x - p.states[s1].x;
        rp.distance_m = dxyz.norm();
        const Eigen::Vector3d unit_local = r1 * dxyz / std::max(rp.distance_m, 1e-12);
        rp.sigma_distance_m = std::sqrt(std::max(0.0, unit_local.dot(diff * unit_local)));
        rp.ellipse = horizontal_ellipse(diff.topLeftCorner<2, 2>(), net.space);
        result.relative[k] = rp;
      }
    });
    result.seconds.stations += since(t0);

    // The datum in words.
    std::size_t fixed = 0, weighted = 0;
    for (std::size_t s = 0; s < net.stations.size(); ++s) {
      if (!p.station_used[s] || p.aside) continue;
      const auto& con = net.stations[s].constraint;
      for (int k = 0; k < 3; ++k) {
        if (con.code[static_cast<std::size_t>(k)] != 'C') continue;
        (con.sigma_m[static_cast<std::size_t>(k)] > 0.0 ? weighted : fixed) += 1;
      }
    }
    result.datum_by_minimum_norm = p.free && d > 0;
    result.datum_defect = p.defect_names;
    if (p.free && d > 0 && !p.aside) {
      std::string list;
      for (const auto& x : p.defect_names) list += (list.empty() ? "" : "; ") + x;
      result.datum = std::to_string(fixed) + " coordinate component" + (fixed == 1 ? "" : "s") + " fixed, " +
                     std::to_string(weighted) + " held with a standard deviation; what they leave undefined (" + list +
                     ") held by the minimum-norm correction of the input's " + std::to_string(p.inner.size()) +
                     " datum station" + (p.inner.size() == 1 ? "" : "s");
    } else if (p.free && d > 0) {
      std::string list;
      for (const auto& x : p.defect_names) list += (list.empty() ? "" : "; ") + x;
      result.datum = "free network: " + list + " held by inner constraints over " + std::to_string(p.inner.size()) + " station" +
                     (p.inner.size() == 1 ? "" : "s");
    } else {
      result.datum = std::to_string(fixed) + " coordinate component" + (fixed == 1 ? "" : "s") + " fixed, " +
                     std::to_string(weighted) + " held with a standard deviation" +
                     (p.free ? " (free network: the measurements define the datum)" : "");
    }
    for (std::size_t s = 0; s < net.stations.size(); ++s) {
      if (!p.station_used[s]) {
        result.warnings.push_back("station " + net.stations[s].id + " (" + net.stations[s].source +
                                  ") is reached by no measurement in the adjustment: left out");
      }
    }
    result.warnings.insert(result.warnings.end(), datum_warnings.begin(), datum_warnings.end());
    if (result.dof <= 0) {
      result.warnings.push_back("no redundancy (dof = " + std::to_string(result.dof) +
                                "): σ0, the global test and the measurement tests are undefined");
    } else if (result.dof <= 5) {
      result.warnings.push_back("low redundancy (dof = " + std::to_string(result.dof) +
                                "): the global test and the w-tests have little power");
    }
    const auto& g = result.global_test;
    if (g.applicable && !g.passed) {
      result.warnings.push_back(std::string("global test ") +
                                (g.failed_high() ? "FAILED high: the residuals are larger than the a-priori "
                                                                  "standard deviations allow"
                                                                : "low: the residuals are smaller than the a-priori standard "
                                                                  "deviations suggest (too pessimistic?)") +
                                " (variance factor " + format_shortest(result.variance_factor.value_or(kNaN)) + ")");
    }
    result.converged = true;
    return result;
  }
}

}  // namespace geoanchor::solver
