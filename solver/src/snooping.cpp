// Iterative data snooping without refitting (snooping.hpp).

#include "snooping.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "point_statistics.hpp"

namespace geoanchor::solver {

bool stronger_evidence(double log_p_a, double statistic_a, double log_p_b, double statistic_b) {
  if (log_p_a != log_p_b) return log_p_a < log_p_b;
  return statistic_a > statistic_b;
}

namespace {

// Above this many rows in play the columns are asked for one removal at a
// time (a gross blunder's contamination: thousands of failing measurements,
// most of which pass once it is out); at or below it the source is told to
// compute them all together (one multi-column solve in a network).
constexpr Eigen::Index kPrefetchRows = 3000;

}  // namespace

SnoopingSequence snooping_sequence(const std::vector<SnoopingCandidate>& candidates, CofactorSource& source,
                                   const SnoopingLimits& limits) {
  SnoopingSequence out;
  const std::size_t n = candidates.size();
  out.passes_after.assign(n, -1);
  // The removals so far, R: Q(R, R) = L Lᵀ grows by one block per removal.
  // For each candidate i still in play, w[i] = Q(i, R) L⁻ᵀ, so that
  //   v'_i = v_i − w_i z,  z = L⁻¹ v_R,   Q'_ii = Q_ii − w_i w_iᵀ
  // are its residual and cofactor once R is out.
  std::vector<Eigen::MatrixXd> w(n);
  Eigen::VectorXd z(0);
  double omega = limits.omega;
  int dof = limits.dof;
  std::vector<std::size_t> in_play(n);
  std::iota(in_play.begin(), in_play.end(), std::size_t{0});
  for (std::size_t i = 0; i < n; ++i) w[i].resize(candidates[i].v.size(), 0);
  bool prefetched = false;

  struct Current {
    Eigen::VectorXd v;
    Eigen::MatrixXd q;
    MeasurementTest test;
  };
  std::vector<Current> current(n);
  for (;;) {
    // Every candidate in play tested as the removals so far leave it. While
    // they are many (a gross blunder's contamination) those that pass drop
    // out, what made them fail being gone; once they are few every one is
    // kept and followed, since one that passes may fail again once others
    // are out (a blunder masked by another).
    const double sigma = limits.scale_by_sigma0 ? (dof > 0 ? std::sqrt(omega / dof) : 1.0) : 1.0;
    std::vector<std::size_t> failing;
    for (std::size_t i : in_play) {
      Current& c = current[i];
      c.v = candidates[i].v;
      c.q = candidates[i].q;
      if (w[i].cols() > 0) {
        c.v.noalias() -= w[i] * z;
        c.q.noalias() -= w[i] * w[i].transpose();
      }
      c.test = measurement_test(c.v, c.q, sigma);
      if (c.test.dof > 0 && c.test.p_value < limits.alpha) {
        failing.push_back(i);
      } else if (!out.removals.empty() && out.passes_after[i] < 0) {
        out.passes_after[i] = static_cast<std::ptrdiff_t>(out.removals.size()) - 1;
      }
    }
    if (!prefetched) in_play = failing;
    if (failing.empty()) break;
    // Strongest first: ln p, statistic, then the key (what it is, not where).
    std::sort(failing.begin(), failing.end(), [&](std::size_t a, std::size_t b) {
      const MeasurementTest& ta = current[a].test;
      const MeasurementTest& tb = current[b].test;
      if (stronger_evidence(ta.log_p, ta.statistic, tb.log_p, tb.statistic)) return true;
      if (stronger_evidence(tb.log_p, tb.statistic, ta.log_p, ta.statistic)) return false;
      return candidates[a].key < candidates[b].key;
    });
    const std::size_t t = failing.front();
    const Eigen::Index kt = candidates[t].v.size();
    // Removable only when every direction of its residual is redundant: else
    // the rest would not determine all it measures. It stays, named.
    if (current[t].test.dof < kt) {
      out.not_removable.push_back(t);
      in_play.erase(std::find(in_play.begin(), in_play.end(), t));
      continue;
    }
    for (std::size_t i : failing) out.passes_after[i] = -1;  // (failing again, if it passed before)
    if (out.removals.size() + 1 > limits.max_removals) {
      out.limit_reached = true;
      out.still_failing = failing;
      break;
    }
    if (limits.may_remove && !limits.may_remove(out.removals.size() + 1, t)) {
      out.stopped_by_caller = true;
      out.still_failing = failing;
      break;
    }
    const Eigen::LLT<Eigen::MatrixXd> d(current[t].q);
    if (d.info() != Eigen::Success) {  // (its eigenvalues passed kMinRedundancy: not expected)
      out.not_removable.push_back(t);
      in_play.erase(std::find(in_play.begin(), in_play.end(), t));
      continue;
    }
    Eigen::Index rows = 0;
    for (std::size_t i : in_play) rows += candidates[i].v.size();
    if (!prefetched && rows <= kPrefetchRows) {
      source.prefetch(in_play);
      prefetched = true;
    }
    const Eigen::MatrixXd column = source.column(in_play, t);
    // The new column of every w: (Q(i, t) − w_i w_tᵀ) L_d⁻ᵀ, L_d L_dᵀ = Q'_tt.
    const Eigen::MatrixXd wt = w[t];
    const Eigen::VectorXd zt = d.matrixL().solve(current[t].v);
    Eigen::Index at = 0;
    for (std::size_t i : in_play) {
      const Eigen::Index ki = candidates[i].v.size();
      if (i != t) {
        Eigen::MatrixXd c = column.middleRows(at, ki);
        if (wt.cols() > 0) c.noalias() -= w[i] * wt.transpose();
        const Eigen::MatrixXd added = d.matrixL().solve(c.transpose()).transpose();  // c L_d⁻ᵀ
        Eigen::MatrixXd grown(ki, w[i].cols() + kt);
        grown << w[i], added;
        w[i].swap(grown);
      }
      at += ki;
    }
    z.conservativeResize(z.size() + kt);
    z.tail(kt) = zt;
    omega -= zt.squaredNorm();
    dof -= static_cast<int>(kt);
    SnoopingRemoval removal;
    removal.candidate = t;
    removal.statistic = current[t].test.statistic;
    removal.dof = current[t].test.dof;
    removal.p_value = current[t].test.p_value;
    removal.log_p = current[t].test.log_p;
    out.removals.push_back(removal);
    w[t].resize(0, 0);
    in_play.erase(std::find(in_play.begin(), in_play.end(), t));
  }
  return out;
}

}  // namespace geoanchor::solver
