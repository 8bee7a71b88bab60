// The cofactor between a network's measurements for data snooping (network_snooping.hpp).

#include "network_snooping.hpp"

#include <algorithm>

#include "geoanchor/solver/network_adjustment.hpp"

namespace geoanchor::solver {

std::vector<std::size_t> failing_measurements(const AdjustmentResult& r) {
  std::vector<std::size_t> out;
  for (std::size_t k = 0; k < r.measurements.size(); ++k) {
    const AdjustedMeasurement& am = r.measurements[k];
    const TestStatus s = am.status(r.alpha_point);
    if (s == TestStatus::flagged || (s == TestStatus::removed && am.snooping_rank > 0)) out.push_back(k);
  }
  std::sort(out.begin(), out.end(), [&](std::size_t a, std::size_t b) {
    const AdjustedMeasurement& x = r.measurements[a];
    const AdjustedMeasurement& y = r.measurements[b];
    if ((x.snooping_rank > 0) != (y.snooping_rank > 0)) return x.snooping_rank > 0;
    if (x.snooping_rank != y.snooping_rank) return x.snooping_rank < y.snooping_rank;
    if (stronger_evidence(x.log_p, x.statistic, y.log_p, y.statistic)) return true;
    if (stronger_evidence(y.log_p, y.statistic, x.log_p, x.statistic)) return false;
    return a < b;
  });
  return out;
}

void NetworkCofactors::add(std::vector<std::int64_t> unknowns, Eigen::MatrixXd a) {
  candidate_unknowns_.push_back(std::move(unknowns));
  a_.push_back(std::move(a));
  offset_.push_back(-1);
}

Eigen::MatrixXd NetworkCofactors::solved(const std::vector<std::size_t>& ts) const {
  Eigen::Index cols = 0;
  for (std::size_t t : ts) cols += a_[t].rows();
  Eigen::MatrixXd e = Eigen::MatrixXd::Zero(unknowns_, cols);
  Eigen::Index at = 0;
  for (std::size_t t : ts) {
    for (std::size_t c = 0; c < candidate_unknowns_[t].size(); ++c) {
      e.block(candidate_unknowns_[t][c], at, 1, a_[t].rows()) = a_[t].col(static_cast<Eigen::Index>(c)).transpose();
    }
    at += a_[t].rows();
  }
  return factor_.solve(e);
}

Eigen::MatrixXd NetworkCofactors::block(std::size_t i, std::size_t t, const Eigen::MatrixXd& z, Eigen::Index first_col) const {
  const Eigen::Index ki = a_[i].rows(), kt = a_[t].rows();
  Eigen::MatrixXd zi(static_cast<Eigen::Index>(candidate_unknowns_[i].size()), kt);
  for (std::size_t c = 0; c < candidate_unknowns_[i].size(); ++c) {
    zi.row(static_cast<Eigen::Index>(c)) = z.block(candidate_unknowns_[i][c], first_col, 1, kt);
  }
  Eigen::MatrixXd q = -a_[i] * zi;
  if (i == t) q += Eigen::MatrixXd::Identity(ki, kt);
  return q;
}

Eigen::MatrixXd NetworkCofactors::column(const std::vector<std::size_t>& rows, std::size_t t) {
  const Eigen::Index kt = a_[t].rows();
  Eigen::Index total = 0;
  for (std::size_t i : rows) total += a_[i].rows();
  Eigen::MatrixXd out(total, kt);
  const bool cached = offset_[t] >= 0 && std::all_of(rows.begin(), rows.end(), [&](std::size_t i) { return offset_[i] >= 0; });
  Eigen::Index at = 0;
  if (cached) {
    for (std::size_t i : rows) {
      out.middleRows(at, a_[i].rows()) = cached_.block(offset_[i], offset_[t], a_[i].rows(), kt);
      at += a_[i].rows();
    }
    return out;
  }
  const Eigen::MatrixXd z = solved({t});
  for (std::size_t i : rows) {
    out.middleRows(at, a_[i].rows()) = block(i, t, z, 0);
    at += a_[i].rows();
  }
  return out;
}

void NetworkCofactors::prefetch(const std::vector<std::size_t>& candidates) {
  std::fill(offset_.begin(), offset_.end(), Eigen::Index{-1});
  std::vector<std::vector<std::int64_t>> unknowns;
  std::vector<Eigen::MatrixXd> rows;
  Eigen::Index total = 0;
  for (std::size_t i : candidates) {
    offset_[i] = total;
    total += a_[i].rows();
    unknowns.push_back(candidate_unknowns_[i]);
    rows.push_back(a_[i]);
  }
  cached_ = Eigen::MatrixXd::Identity(total, total) - factor_.inverse_between(unknowns, rows, jobs_);
}

}  // namespace geoanchor::solver
