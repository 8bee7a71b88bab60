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

// What the removals so far make of each candidate's residual and cofactor,
// and the removal of one more: over the cofactor between candidates (W
// below) or over a few parameters (a fit).
class Downdater {
 public:
  virtual ~Downdater() = default;
  // Candidate i's whitened residual and cofactor once the removals so far are out.
  virtual void current(std::size_t i, Eigen::VectorXd& v, Eigen::MatrixXd& q) = 0;
  // Takes t out, given its current residual and the Cholesky factor of its
  // current cofactor, for the candidates in `rows` (which include t).
  virtual void remove(std::size_t t, const Eigen::VectorXd& vt, const Eigen::LLT<Eigen::MatrixXd>& d,
                      const std::vector<std::size_t>& rows) = 0;
  // The candidates in play are few enough (rows) to have their cofactors together.
  virtual void few(const std::vector<std::size_t>& rows) { (void)rows; }
};

// Q(R, R) = L Lᵀ grows by one block per removal; for each candidate i in
// play, w[i] = Q(i, R) L⁻ᵀ, so that v'_i = v_i − w_i z (z = L⁻¹ v_R) and
// Q'_ii = Q_ii − w_i w_iᵀ. A removal costs the column of blocks Q(i, t)
// (the source's) and a product over the removals so far per candidate.
class CofactorDowndater final : public Downdater {
 public:
  CofactorDowndater(const std::vector<SnoopingCandidate>& candidates, CofactorSource& source)
      : candidates_(candidates), source_(source), w_(candidates.size()) {
    for (std::size_t i = 0; i < candidates.size(); ++i) w_[i].resize(candidates[i].v.size(), 0);
  }
  void current(std::size_t i, Eigen::VectorXd& v, Eigen::MatrixXd& q) override {
    v = candidates_[i].v;
    q = candidates_[i].q;
    if (w_[i].cols() > 0) {
      v.noalias() -= w_[i] * z_;
      q.noalias() -= w_[i] * w_[i].transpose();
    }
  }
  void remove(std::size_t t, const Eigen::VectorXd& vt, const Eigen::LLT<Eigen::MatrixXd>& d,
              const std::vector<std::size_t>& rows) override {
    const Eigen::MatrixXd column = source_.column(rows, t);
    // The new column of every w: (Q(i, t) − w_i w_tᵀ) L_d⁻ᵀ, L_d L_dᵀ = Q'_tt.
    const Eigen::Index kt = vt.size();
    const Eigen::MatrixXd wt = w_[t];
    Eigen::Index at = 0;
    for (std::size_t i : rows) {
      const Eigen::Index ki = candidates_[i].v.size();
      if (i != t) {
        Eigen::MatrixXd c = column.middleRows(at, ki);
        if (wt.cols() > 0) c.noalias() -= w_[i] * wt.transpose();
        const Eigen::MatrixXd added = d.matrixL().solve(c.transpose()).transpose();  // c L_d⁻ᵀ
        Eigen::MatrixXd grown(ki, w_[i].cols() + kt);
        grown << w_[i], added;
        w_[i].swap(grown);
      }
      at += ki;
    }
    z_.conservativeResize(z_.size() + kt);
    z_.tail(kt) = d.matrixL().solve(vt);
    w_[t].resize(0, 0);
  }
  void few(const std::vector<std::size_t>& rows) override { source_.prefetch(rows); }

 private:
  const std::vector<SnoopingCandidate>& candidates_;
  CofactorSource& source_;
  std::vector<Eigen::MatrixXd> w_;
  Eigen::VectorXd z_ = Eigen::VectorXd(0);
};

// A problem of few parameters: with A_i a candidate's whitened design rows
// and N⁻¹ the parameters' cofactor, Q(i, j) = δ_ij I − A_i N⁻¹ A_jᵀ. Taking
// t out updates N⁻¹ by Sherman–Morrison–Woodbury,
//   N⁻¹ ← N⁻¹ + G Q'_tt⁻¹ Gᵀ,  G = N⁻¹ A_tᵀ,
// and moves the parameters by G Q'_tt⁻¹ v'_t, so that v'_i = v_i + A_i Δx
// and Q'_ii = I − A_i N⁻¹ A_iᵀ: O(u²) a candidate, whatever the removals.
class ParameterDowndater final : public Downdater {
 public:
  ParameterDowndater(const std::vector<SnoopingCandidate>& candidates, const std::vector<Eigen::MatrixXd>& design,
                     const Eigen::MatrixXd& n_inv)
      : candidates_(candidates), a_(design), n_inv_(n_inv), dx_(Eigen::VectorXd::Zero(n_inv.rows())) {}
  void current(std::size_t i, Eigen::VectorXd& v, Eigen::MatrixXd& q) override {
    if (!moved_) {
      v = candidates_[i].v;
      q = candidates_[i].q;
      return;
    }
    v = candidates_[i].v + a_[i] * dx_;
    q = Eigen::MatrixXd::Identity(a_[i].rows(), a_[i].rows()) - a_[i] * n_inv_ * a_[i].transpose();
  }
  void remove(std::size_t t, const Eigen::VectorXd& vt, const Eigen::LLT<Eigen::MatrixXd>& d,
              const std::vector<std::size_t>& rows) override {
    (void)rows;
    const Eigen::MatrixXd g = n_inv_ * a_[t].transpose();
    dx_.noalias() += g * d.solve(vt);
    n_inv_.noalias() += g * d.solve(Eigen::MatrixXd(g.transpose()));
    moved_ = true;
  }

 private:
  const std::vector<SnoopingCandidate>& candidates_;
  const std::vector<Eigen::MatrixXd>& a_;
  Eigen::MatrixXd n_inv_;
  Eigen::VectorXd dx_;
  bool moved_ = false;
};

SnoopingSequence run_sequence(const std::vector<SnoopingCandidate>& candidates, Downdater& downdater,
                              const SnoopingLimits& limits) {
  SnoopingSequence out;
  const std::size_t n = candidates.size();
  out.passes_after.assign(n, -1);
  double omega = limits.omega;
  int dof = limits.dof;
  std::vector<std::size_t> in_play(n);
  std::iota(in_play.begin(), in_play.end(), std::size_t{0});
  bool few = false;

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
      downdater.current(i, c.v, c.q);
      c.test = measurement_test(c.v, c.q, sigma);
      if (c.test.dof > 0 && c.test.p_value < limits.alpha) {
        failing.push_back(i);
      } else if (!out.removals.empty() && out.passes_after[i] < 0) {
        out.passes_after[i] = static_cast<std::ptrdiff_t>(out.removals.size()) - 1;
      }
    }
    if (!few) in_play = failing;
    if (failing.empty()) break;
    // Strongest first: ln p, statistic, then the key (what it is, not where).
    const auto stronger = [&](std::size_t a, std::size_t b) {
      const MeasurementTest& ta = current[a].test;
      const MeasurementTest& tb = current[b].test;
      if (stronger_evidence(ta.log_p, ta.statistic, tb.log_p, tb.statistic)) return true;
      if (stronger_evidence(tb.log_p, tb.statistic, ta.log_p, ta.statistic)) return false;
      return candidates[a].key < candidates[b].key;
    };
    const std::size_t t = *std::min_element(failing.begin(), failing.end(), stronger);
    const Eigen::Index kt = candidates[t].v.size();
    // Removable only when every direction of its residual is redundant: else
    // the rest would not determine all it measures. It stays, named.
    if (current[t].test.dof < kt) {
      out.not_removable.push_back(t);
      in_play.erase(std::find(in_play.begin(), in_play.end(), t));
      continue;
    }
    for (std::size_t i : failing) out.passes_after[i] = -1;  // (failing again, if it passed before)
    const auto stop = [&](bool& flag) {
      flag = true;
      std::sort(failing.begin(), failing.end(), stronger);
      out.still_failing = failing;
    };
    if (out.removals.size() + 1 > limits.max_removals) {
      stop(out.limit_reached);
      break;
    }
    if (limits.may_remove && !limits.may_remove(out.removals.size() + 1, t)) {
      stop(out.stopped_by_caller);
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
    if (!few && rows <= kPrefetchRows) {
      downdater.few(in_play);
      few = true;
    }
    downdater.remove(t, current[t].v, d, in_play);
    omega -= d.matrixL().solve(current[t].v).squaredNorm();
    dof -= static_cast<int>(kt);
    SnoopingRemoval removal;
    removal.candidate = t;
    removal.statistic = current[t].test.statistic;
    removal.dof = current[t].test.dof;
    removal.p_value = current[t].test.p_value;
    removal.log_p = current[t].test.log_p;
    out.removals.push_back(removal);
    in_play.erase(std::find(in_play.begin(), in_play.end(), t));
  }
  return out;
}

}  // namespace

SnoopingSequence snooping_sequence(const std::vector<SnoopingCandidate>& candidates, CofactorSource& source,
                                   const SnoopingLimits& limits) {
  CofactorDowndater downdater(candidates, source);
  return run_sequence(candidates, downdater, limits);
}

SnoopingSequence snooping_sequence(const std::vector<SnoopingCandidate>& candidates, const std::vector<Eigen::MatrixXd>& design,
                                   const Eigen::MatrixXd& n_inv, const SnoopingLimits& limits) {
  ParameterDowndater downdater(candidates, design, n_inv);
  return run_sequence(candidates, downdater, limits);
}

}  // namespace geoanchor::solver
