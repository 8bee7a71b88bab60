// A network adjustment's singular normal matrix, explained (network_singularity.hpp).

#include "network_singularity.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/parallel.hpp"

namespace geoanchor::solver {

namespace {

[[noreturn]] void singular(const NetworkProblem& p, Index column) {
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
std::string reaching(const NetworkProblem& p, const std::vector<std::size_t>& stations, std::size_t most, std::size_t& count) {
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
std::string direction_words(const NetworkProblem& p, const Eigen::Vector3d& local) {
  const Eigen::Vector3d a = local.cwiseAbs();
  const double top = a.maxCoeff();
  std::string out;
  for (int c = 0; c < 3; ++c) {
    if (a(c) >= 0.3 * top) out += std::string(out.empty() ? "" : " and ") + component_name(p.net.space, c);
  }
  return out;
}

}  // namespace

void check_station_blocks(const NetworkProblem& p, const NormalEquations& n) {
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

[[noreturn]] void explain_singularity(const NetworkProblem& p, const NormalEquations& n, Index failed_column) {
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

}  // namespace geoanchor::solver
