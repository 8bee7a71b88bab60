// Pre-analysis candidates (network_candidates.hpp).

#include "network_candidates.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <map>

#include "geoanchor/base/error.hpp"
#include "network_model.hpp"
#include "network_station_statistics.hpp"

namespace geoanchor::solver {

namespace {

// One candidate's whitened rows over the design's unknowns, with a new
// direction set's orientation projected out: B = (I − O (OᵀO)⁻¹ Oᵀ) W A.
struct CandidateRows {
  std::vector<Index> unknowns;
  Eigen::MatrixXd b;  // rows × unknowns.size()
};

std::string where_of(const geodesy::NetworkMeasurement& m) { return m.source + " (" + geodesy::to_string(m.kind) + ")"; }

CandidateRows candidate_rows(const NetworkProblem& p, const std::vector<std::size_t>& members) {
  const auto& net = p.net;
  const auto& candidates = p.o.candidates;
  const ModelContext ctx{net, p.o, p.states, p.orientations};
  std::vector<Index> unknowns;
  std::vector<std::size_t> new_sets;
  auto column_of = [](std::vector<Index>& list, Index u) {
    const auto at = std::find(list.begin(), list.end(), u);
    if (at != list.end()) return static_cast<Eigen::Index>(at - list.begin());
    list.push_back(u);
    return static_cast<Eigen::Index>(list.size() - 1);
  };
  struct Part {
    Evaluation ev;
    Eigen::MatrixXd w;
  };
  std::vector<Part> parts;
  Eigen::Index rows = 0;
  for (std::size_t c : members) {
    const auto& m = candidates[c];
    for (std::size_t s : m.stations) {
      if (s >= net.stations.size() || !p.station_used[s]) {
        throw Error(ErrorKind::input, "E_CANDIDATE_STATION",
                    where_of(m) + ": candidate at station " + (s < net.stations.size() ? net.stations[s].id : std::to_string(s)) +
                        ", which no measurement of the design reaches: a candidate joins stations of the design");
      }
    }
    const Eigen::LLT<Eigen::MatrixXd> llt(m.covariance);
    if (m.covariance.rows() != m.value.size() || llt.info() != Eigen::Success) {
      throw Error(ErrorKind::input, "E_COVARIANCE", where_of(m) + ": candidate: the covariance is not positive definite");
    }
    Part part{evaluate(m, ctx), llt.matrixL().solve(Eigen::MatrixXd::Identity(m.covariance.rows(), m.covariance.cols()))};
    rows += part.ev.computed.size();
    parts.push_back(std::move(part));
  }
  // Columns: the design's unknowns; the new sets' orientations apart (O).
  std::vector<std::vector<std::pair<Eigen::Index, double>>> entries(static_cast<std::size_t>(rows));
  std::vector<std::pair<Eigen::Index, std::size_t>> nuisance;  // (row, new set slot)
  Eigen::Index row0 = 0;
  for (const Part& part : parts) {
    const Evaluation& ev = part.ev;
    std::vector<Index> cols;
    Eigen::MatrixXd design = Eigen::MatrixXd::Zero(ev.computed.size(), static_cast<Eigen::Index>(3 * ev.stations.size() + ev.orientation.size()));
    for (std::size_t s = 0; s < ev.stations.size(); ++s) {
      for (int c = 0; c < 3; ++c) {
        const Index u = p.layout.station[ev.stations[s]][static_cast<std::size_t>(c)];
        if (u < 0) continue;
        const Eigen::Index k = column_of(cols, u);
        design.col(k) += ev.d_local.col(static_cast<Eigen::Index>(3 * s + static_cast<std::size_t>(c)));
      }
    }
    std::vector<std::pair<Eigen::Index, std::size_t>> own_nuisance;
    for (const auto& [row, set] : ev.orientation) {
      const Index u = set < p.layout.orientation.size() ? p.layout.orientation[set] : -1;
      if (u >= 0) {
        design(row, column_of(cols, u)) -= 1.0;
      } else {
        const auto at = std::find(new_sets.begin(), new_sets.end(), set);
        const std::size_t slot = at == new_sets.end() ? (new_sets.push_back(set), new_sets.size() - 1) : static_cast<std::size_t>(at - new_sets.begin());
        own_nuisance.push_back({row, slot});
      }
    }
    const Eigen::MatrixXd wa = part.w * design.leftCols(static_cast<Eigen::Index>(cols.size()));
    for (Eigen::Index i = 0; i < wa.rows(); ++i) {
      for (Eigen::Index k = 0; k < wa.cols(); ++k) {
        if (wa(i, k) != 0.0) entries[static_cast<std::size_t>(row0 + i)].push_back({column_of(unknowns, cols[static_cast<std::size_t>(k)]), wa(i, k)});
      }
    }
    for (const auto& [row, slot] : own_nuisance) nuisance.push_back({row0 + row, slot});
    row0 += wa.rows();
  }
  Eigen::MatrixXd bx = Eigen::MatrixXd::Zero(rows, static_cast<Eigen::Index>(unknowns.size()));
  for (std::size_t i = 0; i < entries.size(); ++i) {
    for (const auto& [k, v] : entries[i]) bx(static_cast<Eigen::Index>(i), k) += v;
  }
  if (!new_sets.empty()) {
    // O: the whitened orientation columns (each part's W times −1 at its direction rows).
    Eigen::MatrixXd o = Eigen::MatrixXd::Zero(rows, static_cast<Eigen::Index>(new_sets.size()));
    Eigen::Index r0 = 0;
    std::size_t n = 0;
    for (const Part& part : parts) {
      const Eigen::Index k = part.ev.computed.size();
      Eigen::MatrixXd raw = Eigen::MatrixXd::Zero(k, o.cols());
      for (; n < nuisance.size() && nuisance[n].first < r0 + k; ++n) raw(nuisance[n].first - r0, static_cast<Eigen::Index>(nuisance[n].second)) = -1.0;
      o.middleRows(r0, k) = part.w * raw;
      r0 += k;
    }
    const Eigen::MatrixXd oto = o.transpose() * o;
    bx -= o * oto.ldlt().solve(o.transpose() * bx);
  }
  return CandidateRows{std::move(unknowns), std::move(bx)};
}

}  // namespace

CriterionValue built_in_criterion(const AdjustmentResult& design, const CovarianceUpdate* update, CandidateRanking ranking,
                                  double confidence, geodesy::NetworkSpace space) {
  const double scale = ellipse_confidence_scale(confidence);
  CriterionValue worst;
  bool first = true;
  for (std::size_t s = 0; s < design.stations.size(); ++s) {
    const AdjustedStation& st = design.stations[s];
    if (!st.used) continue;
    const Eigen::Matrix3d q = update ? update->updated(s, st.covariance_local_m2) : st.covariance_local_m2;
    const double v = ranking == CandidateRanking::sigma_up ? std::sqrt(std::max(0.0, q(2, 2)))
                                                           : scale * horizontal_ellipse(q.topLeftCorner<2, 2>(), space).semi_major_m;
    if (first || !(v <= worst.value)) {  // NaN-propagating
      worst = CriterionValue{v, s, s};
      first = false;
    }
  }
  return worst;
}

void rank_candidates(const NetworkProblem& p, const NormalFactor& f, const InnerConstraints& inner, AdjustmentResult& result) {
  const auto& o = p.o;
  const CandidateCriterion criterion = o.candidate_criterion ? o.candidate_criterion : CandidateCriterion([&](const AdjustmentResult& d, const CovarianceUpdate* u) {
    return built_in_criterion(d, u, o.candidate_ranking, o.confidence, p.net.space);
  });
  result.design_worst = criterion(result, nullptr);
  // The candidates: one each, a new direction set's directions together.
  std::vector<std::vector<std::size_t>> groups;
  std::map<std::size_t, std::size_t> group_of_set;
  for (std::size_t c = 0; c < o.candidates.size(); ++c) {
    const auto& m = o.candidates[c];
    const bool new_set = m.set && (*m.set >= p.layout.orientation.size() || p.layout.orientation[*m.set] < 0);
    if (new_set) {
      const auto [at, inserted] = group_of_set.try_emplace(*m.set, groups.size());
      if (inserted) groups.emplace_back();
      groups[at->second].push_back(c);
    } else {
      groups.push_back({c});
    }
  }
  const bool transform = inner.e.size() > 0;
  for (const auto& members : groups) {
    const CandidateRows rows = candidate_rows(p, members);
    const Eigen::Index k = rows.b.rows();
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(p.layout.count, k);
    for (std::size_t j = 0; j < rows.unknowns.size(); ++j) rhs.row(rows.unknowns[j]) = rows.b.col(static_cast<Eigen::Index>(j)).transpose();
    Eigen::MatrixXd x = f.solve(rhs);  // N⁻¹ Bᵀ
    if (transform) x -= p.defect * (inner.m * (inner.e.transpose() * x));
    Eigen::MatrixXd m = Eigen::MatrixXd::Identity(k, k);
    for (std::size_t j = 0; j < rows.unknowns.size(); ++j) m += rows.b.col(static_cast<Eigen::Index>(j)) * x.row(rows.unknowns[j]);
    m = (0.5 * (m + m.transpose())).eval();
    CovarianceUpdate update;
    update.m_inverse = m.ldlt().solve(Eigen::MatrixXd::Identity(k, k));
    update.station.resize(p.net.stations.size());
    for (std::size_t s = 0; s < p.net.stations.size(); ++s) {
      if (!p.station_used[s]) continue;
      Eigen::MatrixXd u = Eigen::MatrixXd::Zero(3, k);
      for (int c = 0; c < 3; ++c) {
        const Index at = p.layout.station[s][static_cast<std::size_t>(c)];
        if (at >= 0) u.row(c) = x.row(at);
      }
      // From the unknowns' axes to the local ones (AdjustedStation::covariance_local_m2).
      const Eigen::Matrix3d to_local = p.states[s].local_from_xyz * p.states[s].axes.transpose();
      update.station[s] = to_local * u;
    }
    RankedCandidate ranked;
    ranked.measurements = members;
    ranked.worst = criterion(result, &update);
    ranked.improvement = result.design_worst.value - ranked.worst.value;
    result.candidates.push_back(std::move(ranked));
  }
  std::stable_sort(result.candidates.begin(), result.candidates.end(),
                   [](const RankedCandidate& a, const RankedCandidate& b) { return a.worst.value < b.worst.value; });
}

}  // namespace geoanchor::solver
