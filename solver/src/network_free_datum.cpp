// A free network's datum: inner constraints and the S-transformation
// (network_free_datum.hpp).

#include "network_free_datum.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>

#include <algorithm>
#include <functional>
#include <string>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "network_datum.hpp"

namespace geoanchor::solver {

namespace {

// The defect directions over the unknowns of `stations` only (zero elsewhere).
Eigen::MatrixXd restricted(const NetworkProblem& p, const std::vector<std::size_t>& stations,
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
Eigen::MatrixXd station_block(const NetworkProblem& p, std::size_t s, const std::array<bool, 3>& components) {
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

}  // namespace

void begin_inner_constraints(NetworkProblem& p) {
  const auto& net = p.net;
  const auto& o = p.o;
  const std::string where = net.source_name;
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
}

void check_inner_stations(const NetworkProblem& p, bool option) {
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

void choose_anchors(NetworkProblem& p) {
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

void hold_defect(const NetworkProblem& p, NormalEquations& n) {
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

InnerConstraints to_minimum_norm(NetworkProblem& p) {
  const auto& net = p.net;
  InnerConstraints inner;
  if (!(p.free && p.defect.cols() > 0)) return inner;
  Eigen::MatrixXd& inner_e = inner.e;
  Eigen::MatrixXd& inner_m = inner.m;
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
  return inner;
}

DatumCofactors::DatumCofactors(const NetworkProblem& p, const NormalFactor& f, const InnerConstraints& inner)
    : p_(p), f_(f), inner_(inner), transformed_(p.free && p.defect.cols() > 0) {
  if (transformed_) {
    ze_ = f.solve(Eigen::MatrixXd(inner.e));
    eze_ = inner.e.transpose() * ze_;
  }
}

Eigen::Matrix3d DatumCofactors::between(std::size_t s1, std::size_t s2) const {
  const NetworkProblem& p = p_;
  Eigen::Matrix3d q = Eigen::Matrix3d::Zero();
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      const Index ua = p.layout.station[s1][static_cast<std::size_t>(a)], ub = p.layout.station[s2][static_cast<std::size_t>(b)];
      if (ua < 0 || ub < 0) continue;
      double v = f_.inverse(ua, ub);
      if (transformed_) {
        // S Z Sᵀ, S = I − D M Eᵀ.
        const Eigen::RowVectorXd da = p.defect.row(ua) * inner_.m, db = p.defect.row(ub) * inner_.m;
        v += -da.dot(ze_.row(ub)) - ze_.row(ua).dot(db) + da * eze_ * db.transpose();
      }
      q(a, b) = v;
    }
  }
  return q;
}

std::vector<Eigen::Matrix<double, 6, 6>> DatumCofactors::with_each(std::size_t s, const std::vector<std::size_t>& others) const {
  const NetworkProblem& p = p_;
  // A station's unknowns and their components.
  struct Unknowns {
    std::vector<std::int64_t> u;
    std::vector<int> component;
  };
  const auto unknowns_of = [&p](std::size_t st) {
    Unknowns x;
    for (int c = 0; c < 3; ++c) {
      const Index uc = p.layout.station[st][static_cast<std::size_t>(c)];
      if (uc >= 0) x.u.push_back(uc), x.component.push_back(c);
    }
    return x;
  };
  const Unknowns first = unknowns_of(s);
  const auto k1 = static_cast<Eigen::Index>(first.u.size());
  std::vector<Eigen::Matrix<double, 6, 6>> out(others.size(), Eigen::Matrix<double, 6, 6>::Zero());
  // Per pair: its unknowns (s's, then the other's) and their cofactor.
  std::vector<std::vector<std::int64_t>> pair_u(others.size());
  std::vector<std::vector<Eigen::Index>> pair_at(others.size());
  std::vector<Eigen::MatrixXd> z(others.size());
  std::vector<std::size_t> off;  // pairs off the pattern
  for (std::size_t k = 0; k < others.size(); ++k) {
    const Unknowns second = unknowns_of(others[k]);
    pair_u[k] = first.u;
    for (std::size_t a = 0; a < first.u.size(); ++a) pair_at[k].push_back(first.component[a]);
    for (std::size_t a = 0; a < second.u.size(); ++a) pair_u[k].push_back(second.u[a]), pair_at[k].push_back(3 + second.component[a]);
    const auto n = static_cast<Eigen::Index>(pair_u[k].size());
    z[k].resize(n, n);
    if (n > 0 && !f_.inverse_block(pair_u[k].data(), pair_u[k].size(), z[k].data())) off.push_back(k);
  }
  if (!off.empty()) {
    // One solve along the tree per station: s first, then each other off the pattern.
    std::vector<std::vector<std::int64_t>> blocks{first.u};
    std::vector<Eigen::MatrixXd> rows{Eigen::MatrixXd::Identity(k1, k1)};
    for (const std::size_t k : off) {
      blocks.emplace_back(pair_u[k].begin() + k1, pair_u[k].end());
      const auto k2 = static_cast<Eigen::Index>(blocks.back().size());
      rows.push_back(Eigen::MatrixXd::Identity(k2, k2));
    }
    const Eigen::MatrixXd all = f_.inverse_between(blocks, rows);
    Eigen::Index at = k1;
    for (const std::size_t k : off) {
      const auto k2 = static_cast<Eigen::Index>(pair_u[k].size()) - k1;
      z[k].topLeftCorner(k1, k1) = all.topLeftCorner(k1, k1);
      z[k].topRightCorner(k1, k2) = all.block(0, at, k1, k2);
      z[k].bottomLeftCorner(k2, k1) = all.block(at, 0, k2, k1);
      z[k].bottomRightCorner(k2, k2) = all.block(at, at, k2, k2);
      at += k2;
    }
  }
  for (std::size_t k = 0; k < others.size(); ++k) {
    const auto n = static_cast<Eigen::Index>(pair_u[k].size());
    if (transformed_ && n > 0) {
      // S Z Sᵀ over these unknowns, S = I − D M Eᵀ.
      Eigen::MatrixXd dm(n, inner_.m.cols()), zes(n, ze_.cols());
      for (Eigen::Index a = 0; a < n; ++a) {
        dm.row(a) = p.defect.row(pair_u[k][static_cast<std::size_t>(a)]) * inner_.m;
        zes.row(a) = ze_.row(pair_u[k][static_cast<std::size_t>(a)]);
      }
      z[k] += -dm * zes.transpose() - zes * dm.transpose() + dm * eze_ * dm.transpose();
    }
    for (Eigen::Index a = 0; a < n; ++a) {
      for (Eigen::Index b = 0; b < n; ++b) out[k](pair_at[k][static_cast<std::size_t>(a)], pair_at[k][static_cast<std::size_t>(b)]) = z[k](a, b);
    }
  }
  return out;
}

Eigen::MatrixXd DatumCofactors::selected(const Eigen::MatrixXd& sel) const {
  const Eigen::MatrixXd z = f_.solve(sel);
  Eigen::MatrixXd q = sel.transpose() * z;  // local axes
  if (transformed_) {
    const Eigen::MatrixXd dm = sel.transpose() * (p_.defect * inner_.m);  // (3m × d)
    const Eigen::MatrixXd zes = sel.transpose() * ze_;                   // (3m × d)
    q += -dm * zes.transpose() - zes * dm.transpose() + dm * eze_ * dm.transpose();
  }
  q = (0.5 * (q + q.transpose())).eval();
  return q;
}

}  // namespace geoanchor::solver
