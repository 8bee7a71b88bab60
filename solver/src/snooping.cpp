// Iterative data snooping without refitting (snooping.hpp).

#include "snooping.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "point_statistics.hpp"

namespace geoanchor::solver {

bool stronger_evidence(double log_p_a, double statistic_a, double log_p_b, double statistic_b) {
  if (statistic_a != statistic_b) return statistic_a > statistic_b;
  return log_p_a < log_p_b;
}

namespace {

// Above this many rows in play the columns are asked for one removal at a
// time (a gross blunder's contamination: thousands of failing measurements,
// most of which pass once it is out); at or below it the source is told to
// compute them all together (one multi-column solve in a network).
constexpr Eigen::Index kPrefetchRows = 3000;

// What the removals so far make of each candidate's residual and cofactor,
// and the removal of one more, prepared (to see what it would do to the
// others) before it is made: over the cofactor between candidates (W
// below) or over a few parameters (a fit).
class Downdater {
 public:
  virtual ~Downdater() = default;
  // Candidate i's whitened residual and cofactor once the removals so far are out.
  virtual void current(std::size_t i, Eigen::VectorXd& v, Eigen::MatrixXd& q) = 0;
  // Prepares t's removal, given its current residual and the Cholesky
  // factor of its current cofactor, for the candidates in `rows` (which
  // include t).
  virtual void prepare(std::size_t t, const Eigen::VectorXd& vt, const Eigen::LLT<Eigen::MatrixXd>& d,
                       const std::vector<std::size_t>& rows) = 0;
  // Candidate i's (one of the prepared rows, not t) were the prepared removal made.
  virtual void after(std::size_t i, Eigen::VectorXd& v, Eigen::MatrixXd& q) = 0;
  // Makes the prepared removal.
  virtual void commit() = 0;
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
      : candidates_(candidates), source_(source), w_(candidates.size()), added_(candidates.size()) {
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
  void prepare(std::size_t t, const Eigen::VectorXd& vt, const Eigen::LLT<Eigen::MatrixXd>& d,
               const std::vector<std::size_t>& rows) override {
    const Eigen::MatrixXd column = source_.column(rows, t);
    // The new column of every w: (Q(i, t) − w_i w_tᵀ) L_d⁻ᵀ, L_d L_dᵀ = Q'_tt.
    t_ = t;
    rows_ = rows;
    Eigen::Index at = 0;
    for (std::size_t i : rows) {
      const Eigen::Index ki = candidates_[i].v.size();
      if (i != t) {
        Eigen::MatrixXd c = column.middleRows(at, ki);
        if (w_[t].cols() > 0) c.noalias() -= w_[i] * w_[t].transpose();
        added_[i] = d.matrixL().solve(c.transpose()).transpose();  // c L_d⁻ᵀ
      }
      at += ki;
    }
    zt_ = d.matrixL().solve(vt);
  }
  void after(std::size_t i, Eigen::VectorXd& v, Eigen::MatrixXd& q) override {
    current(i, v, q);
    v.noalias() -= added_[i] * zt_;
    q.noalias() -= added_[i] * added_[i].transpose();
  }
  void commit() override {
    for (std::size_t i : rows_) {
      if (i == t_) continue;
      Eigen::MatrixXd grown(w_[i].rows(), w_[i].cols() + added_[i].cols());
      grown << w_[i], added_[i];
      w_[i].swap(grown);
      added_[i].resize(0, 0);
    }
    z_.conservativeResize(z_.size() + zt_.size());
    z_.tail(zt_.size()) = zt_;
    w_[t_].resize(0, 0);
  }
  void few(const std::vector<std::size_t>& rows) override { source_.prefetch(rows); }

 private:
  const std::vector<SnoopingCandidate>& candidates_;
  CofactorSource& source_;
  std::vector<Eigen::MatrixXd> w_;
  Eigen::VectorXd z_ = Eigen::VectorXd(0);
  // The prepared removal.
  std::size_t t_ = 0;
  std::vector<std::size_t> rows_;
  std::vector<Eigen::MatrixXd> added_;
  Eigen::VectorXd zt_;
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
    state(i, dx_, n_inv_, v, q);
  }
  void prepare(std::size_t t, const Eigen::VectorXd& vt, const Eigen::LLT<Eigen::MatrixXd>& d,
               const std::vector<std::size_t>& rows) override {
    (void)rows;
    const Eigen::MatrixXd g = n_inv_ * a_[t].transpose();
    next_dx_ = dx_ + g * d.solve(vt);
    next_n_inv_ = n_inv_ + g * d.solve(Eigen::MatrixXd(g.transpose()));
    next_n_inv_ = (0.5 * (next_n_inv_ + next_n_inv_.transpose())).eval();  // (the solvers read one triangle)
  }
  void after(std::size_t i, Eigen::VectorXd& v, Eigen::MatrixXd& q) override { state(i, next_dx_, next_n_inv_, v, q); }
  void commit() override {
    dx_.swap(next_dx_);
    n_inv_.swap(next_n_inv_);
    moved_ = true;
  }

 private:
  void state(std::size_t i, const Eigen::VectorXd& dx, const Eigen::MatrixXd& n_inv, Eigen::VectorXd& v, Eigen::MatrixXd& q) const {
    v = candidates_[i].v + a_[i] * dx;
    q = Eigen::MatrixXd::Identity(a_[i].rows(), a_[i].rows()) - a_[i] * n_inv * a_[i].transpose();
  }
  const std::vector<SnoopingCandidate>& candidates_;
  const std::vector<Eigen::MatrixXd>& a_;
  Eigen::MatrixXd n_inv_;
  Eigen::VectorXd dx_;
  Eigen::MatrixXd next_n_inv_;
  Eigen::VectorXd next_dx_;
  bool moved_ = false;
};

// Whether a candidate whose whitened residual cofactor is `before` keeps
// almost none of the redundancy of one of its tested directions (those with
// eigenvalue ≥ kMinRedundancy) once it is `after`: the smallest generalized
// eigenvalue of (after, before) over them is below kInseparable, i.e. its
// residual there is correlated with the removed one's by ±1 within 10⁻⁶.
// Merely falling below kMinRedundancy (becoming untested along a direction
// it shared in part) is not enough.
bool loses_a_direction(const Eigen::MatrixXd& before, const Eigen::MatrixXd& after) {
  constexpr double kInseparable = 1e-6;
  // A quick answer first: after ⪯ before, so the generalized eigenvalues
  // of (after, before) lie in [0, 1], their product det(after)/det(before)
  // is at most the smallest, and the smallest over the tested directions is
  // at least that (a Rayleigh quotient over a subspace). Most candidates
  // barely change with one removal: no eigen decompositions for them.
  const double det_before = before.determinant();
  if (det_before > 0.0 && after.determinant() >= kInseparable * det_before) return false;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(before);
  std::vector<Eigen::Index> tested;
  for (Eigen::Index k = 0; k < before.rows(); ++k) {
    if (eig.eigenvalues()(k) >= kMinRedundancy) tested.push_back(k);
  }
  if (tested.empty()) return false;
  // In the tested directions, scaled so that `before` is the identity there.
  Eigen::MatrixXd e(before.rows(), static_cast<Eigen::Index>(tested.size()));
  for (std::size_t k = 0; k < tested.size(); ++k) {
    e.col(static_cast<Eigen::Index>(k)) = eig.eigenvectors().col(tested[k]) / std::sqrt(eig.eigenvalues()(tested[k]));
  }
  const Eigen::MatrixXd kept = e.transpose() * after * e;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> left(0.5 * (kept + kept.transpose()));
  return left.eigenvalues()(0) < kInseparable;
}

SnoopingTest as_snooping_test(std::size_t candidate, const MeasurementTest& t) {
  SnoopingTest s;
  s.candidate = candidate;
  s.statistic = t.statistic;
  s.dof = t.dof;
  s.p_value = t.p_value;
  s.log_p = t.log_p;
  return s;
}

SnoopingSequence run_sequence(const std::vector<SnoopingCandidate>& candidates, Downdater& downdater,
                              const SnoopingLimits& limits) {
  SnoopingSequence out;
  const std::size_t n = candidates.size();
  out.passes_after.assign(n, -1);
  double omega = limits.omega;
  int dof = limits.dof;
  std::vector<std::size_t> in_play(n);
  std::iota(in_play.begin(), in_play.end(), std::size_t{0});
  const auto drop = [&](std::size_t i) {
    const auto it = std::find(in_play.begin(), in_play.end(), i);
    if (it != in_play.end()) in_play.erase(it);
  };
  bool few = false;
  std::vector<int> initial_dof(n, -1);
  std::vector<std::size_t> failing_at;  // the failing count after each number of removals

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
    double sigma = 1.0;
    if (limits.scale_by_sigma0) {
      if (!(dof > 0 && omega > 0.0)) break;  // no σ̂0 left to test by
      sigma = std::sqrt(omega / dof);
    }
    std::vector<std::size_t> failing;
    for (std::size_t i : in_play) {
      Current& c = current[i];
      downdater.current(i, c.v, c.q);
      c.test = measurement_test(c.v, c.q, sigma);
      if (initial_dof[i] < 0) initial_dof[i] = c.test.dof;
      if (c.test.dof > 0 && c.test.p_value < limits.alpha) {
        failing.push_back(i);
        out.passes_after[i] = -1;  // (failing again, if it passed before)
      } else if (!out.removals.empty() && out.passes_after[i] < 0 && c.test.dof == initial_dof[i] &&
                 std::isfinite(c.test.statistic)) {
        // Explained by the removals so far; not when it passes only because
        // fewer of its directions can be tested.
        out.passes_after[i] = static_cast<std::ptrdiff_t>(out.removals.size()) - 1;
      }
    }
    if (!few) in_play = failing;
    if (failing.empty()) break;
    // Strongest first: the statistic, ln p, then the key (what it is, not where).
    const auto stronger = [&](std::size_t a, std::size_t b) {
      const MeasurementTest& ta = current[a].test;
      const MeasurementTest& tb = current[b].test;
      if (stronger_evidence(ta.log_p, ta.statistic, tb.log_p, tb.statistic)) return true;
      if (stronger_evidence(tb.log_p, tb.statistic, ta.log_p, ta.statistic)) return false;
      return candidates[a].key < candidates[b].key;
    };
    std::stable_sort(failing.begin(), failing.end(), stronger);
    const std::size_t made = out.removals.size();
    const auto stop = [&](bool& flag) {
      flag = true;
      for (std::size_t i : failing) out.still_failing.push_back(as_snooping_test(i, current[i].test));
    };
    failing_at.push_back(failing.size());
    if (made >= kHopelessWindow && failing.size() > limits.max_removals - std::min(made, limits.max_removals) &&
        failing_at[made - kHopelessWindow] <= failing.size() + 2 * kHopelessWindow) {
      out.hopeless = true;
      stop(out.limit_reached);
      break;
    }
    // The strongest goes, if it can. If it cannot, the sequence ends
    // there: it may be what makes the weaker ones fail, and removing them
    // in its place would take good measurements out.
    const std::size_t t = failing.front();
    const Eigen::Index kt = candidates[t].v.size();
    // Removable only when every direction of its residual is redundant:
    // else the rest would not determine all it measures. It stays, named.
    const Eigen::LLT<Eigen::MatrixXd> d(current[t].q);
    if (current[t].test.dof < kt || d.info() != Eigen::Success) {
      out.not_removable.push_back(t);
      out.stopped_at = static_cast<std::ptrdiff_t>(t);
      break;
    }
    if (made + 1 > limits.max_removals) {
      stop(out.limit_reached);
      break;
    }
    if (limits.may_remove && !limits.may_remove(made + 1, t)) {
      stop(out.stopped_by_caller);
      break;
    }
    Eigen::Index rows = 0;
    for (std::size_t i : in_play) rows += candidates[i].v.size();
    if (!few && rows <= kPrefetchRows) {
      downdater.few(in_play);
      few = true;
    }
    downdater.prepare(t, current[t].v, d, in_play);
    // A failing candidate that would lose (nearly) all the redundancy of
    // one of its tested directions with t out cannot be told from t: their
    // residuals are correlated by ±1 along it. Neither is removed, and the
    // sequence ends.
    std::vector<std::size_t> group{t};
    for (std::size_t j : failing) {
      if (j == t) continue;
      Eigen::VectorXd v;
      Eigen::MatrixXd q;
      downdater.after(j, v, q);
      if (loses_a_direction(current[j].q, q)) group.push_back(j);
    }
    if (group.size() > 1) {
      out.inseparable.push_back(std::move(group));
      out.stopped_at = static_cast<std::ptrdiff_t>(t);
      break;
    }
    downdater.commit();
    omega = std::max(0.0, omega - d.matrixL().solve(current[t].v).squaredNorm());
    dof -= static_cast<int>(kt);
    out.removals.push_back(as_snooping_test(t, current[t].test));
    drop(t);
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
