// Data snooping's one implementation (solver/src/snooping.hpp) against
// references it does not use: the logarithm of a χ² tail against Boost's
// long-double evaluation (which does not underflow until 10⁻⁴⁹³¹), and the
// order of removals against a least-squares problem refitted from scratch
// after each removal (a dense solve of its own here).

#include <gtest/gtest.h>

#include <boost/math/distributions/chi_squared.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <random>

#include "point_statistics.hpp"
#include "snooping.hpp"
#include "statistics.hpp"
#include "test_support.hpp"

namespace geoanchor::solver {
namespace {

// ln p of a χ² tail in double against long double: 1e-12 relative is a few
// hundred units of double's rounding in the continued fraction's terms.
constexpr double kLogTailRelative = 1e-12;

TEST(Snooping, Issue39_TheLogOfAChiSquaredTailDoesNotUnderflow) {
  testing::WorstCase worst;
  for (const int dof : {1, 2, 3, 6, 30, 300}) {
    for (const double x : {0.5, 3.0, 10.8, 50.0, 700.0, 1500.0, 5000.0, 3.0e4, 1.0e6}) {
      const long double reference =
          std::log(boost::math::cdf(boost::math::complement(boost::math::chi_squared_distribution<long double>(dof), static_cast<long double>(x))));
      const double ours = chi_squared_log_upper_tail(dof, x);
      // Where long double underflows too (p below 10⁻⁴⁹³¹), the tail's
      // asymptotic series: Q(a, y) = y^(a−1) e^(−y) / Γ(a) · Σ_k
      // (a−1)(a−2)…(a−k) / y^k, y = x/2, a = dof/2 (terms summed while they
      // shrink; y ≥ 15000 here, so a few suffice).
      double expected = static_cast<double>(reference);
      if (!std::isfinite(expected)) {
        const double a = 0.5 * dof, y = 0.5 * x;
        double sum = 1.0, term = 1.0;
        for (int k = 1; k < 60; ++k) {
          term *= (a - k) / y;
          if (std::abs(term) < 1e-18) break;
          sum += term;
        }
        expected = -y + (a - 1.0) * std::log(y) - std::lgamma(a) + std::log(sum);
      }
      worst.add(std::abs(ours - expected) / std::max(1.0, std::abs(expected)));
    }
  }
  EXPECT_WORST_WITHIN(worst, kLogTailRelative);
  // Monotone past the point where the p-value itself is 0 in double.
  EXPECT_EQ(chi_squared_upper_tail(1, 2000.0), 0.0);
  EXPECT_LT(chi_squared_log_upper_tail(1, 2001.0), chi_squared_log_upper_tail(1, 2000.0));
  EXPECT_TRUE(std::isnan(chi_squared_log_upper_tail(3, std::numeric_limits<double>::quiet_NaN())));
}

// A gross 3-D blunder and a 1-D measurement it contaminates: the blunder's
// statistic S = vᵀQ⁺v bounds every other measurement's S from its bias
// (Q is a projector: Q_bb ⪰ Q_bi Q_ii⁻¹ Q_ib), whatever their dimensions,
// so ranking by S puts the blunder first. ln p would not: at S_b = 100 (χ²(3),
// ln p = −47.9) a 1-D measurement at S = 95 has ln p = −50.0. Where p
// underflows (S = 4·10¹⁰) S still ranks.
TEST(Snooping, Issue39_EvidenceRanksAGrossBlunderBeforeWhatItContaminates) {
  const double blunder = chi_squared_log_upper_tail(3, 100.0);
  const double contaminated = chi_squared_log_upper_tail(1, 95.0);
  ASSERT_LT(contaminated, blunder);  // (what ln p alone would rank first)
  EXPECT_TRUE(stronger_evidence(blunder, 100.0, contaminated, 95.0));
  EXPECT_FALSE(stronger_evidence(contaminated, 95.0, blunder, 100.0));
  EXPECT_TRUE(stronger_evidence(chi_squared_log_upper_tail(3, 4.0e10), 4.0e10, chi_squared_log_upper_tail(1, 0.99 * 4.0e10),
                                0.99 * 4.0e10));
  // Equal statistics: the smaller ln p (the larger dimension's is the larger p).
  EXPECT_TRUE(stronger_evidence(-6.0, 12.0, -5.0, 12.0));
  EXPECT_FALSE(stronger_evidence(-5.0, 11.0, -5.0, 11.0));
}

// A linear least-squares problem of m observations in groups (1-D and 3-D
// measurements), whitened: rows A, observations l.
struct Problem {
  Eigen::MatrixXd a;
  Eigen::VectorXd l;
  std::vector<std::vector<Eigen::Index>> rows;  // each measurement's rows
};

Problem make_problem(std::mt19937& rng, int measurements, int unknowns) {
  std::normal_distribution<double> z;
  Problem p;
  std::vector<Eigen::Index> sizes;
  Eigen::Index total = 0;
  for (int k = 0; k < measurements; ++k) sizes.push_back(k % 4 == 0 ? 3 : 1), total += sizes.back();
  p.a.resize(total, unknowns);
  p.l.resize(total);
  for (Eigen::Index r = 0; r < total; ++r) {
    for (int c = 0; c < unknowns; ++c) p.a(r, c) = z(rng);
    p.l(r) = z(rng);
  }
  Eigen::Index at = 0;
  for (Eigen::Index k : sizes) {
    std::vector<Eigen::Index> rows;
    for (Eigen::Index r = 0; r < k; ++r) rows.push_back(at + r);
    p.rows.push_back(rows);
    at += k;
  }
  return p;
}

// The residuals and their cofactor of the problem without the measurements
// `out`, solved densely from scratch.
struct Solved {
  Eigen::VectorXd v;
  Eigen::MatrixXd q;
};
Solved solve_without(const Problem& p, const std::vector<bool>& out) {
  std::vector<Eigen::Index> keep;
  for (std::size_t k = 0; k < p.rows.size(); ++k) {
    if (!out[k]) keep.insert(keep.end(), p.rows[k].begin(), p.rows[k].end());
  }
  Eigen::MatrixXd a(static_cast<Eigen::Index>(keep.size()), p.a.cols());
  Eigen::VectorXd l(a.rows());
  for (std::size_t r = 0; r < keep.size(); ++r) a.row(static_cast<Eigen::Index>(r)) = p.a.row(keep[r]), l(static_cast<Eigen::Index>(r)) = p.l(keep[r]);
  const Eigen::MatrixXd n_inv = (a.transpose() * a).inverse();
  Solved s;
  s.v = Eigen::VectorXd::Zero(p.l.size());
  s.q = Eigen::MatrixXd::Zero(p.l.size(), p.l.size());
  const Eigen::VectorXd x = n_inv * a.transpose() * l;
  const Eigen::MatrixXd q = Eigen::MatrixXd::Identity(a.rows(), a.rows()) - a * n_inv * a.transpose();
  for (std::size_t r = 0; r < keep.size(); ++r) {
    s.v(keep[r]) = l(static_cast<Eigen::Index>(r)) - a.row(static_cast<Eigen::Index>(r)).dot(x);
    for (std::size_t c = 0; c < keep.size(); ++c) s.q(keep[r], keep[c]) = q(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c));
  }
  return s;
}

Eigen::VectorXd part(const Eigen::VectorXd& v, const std::vector<Eigen::Index>& rows) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(rows.size()));
  for (std::size_t r = 0; r < rows.size(); ++r) out(static_cast<Eigen::Index>(r)) = v(rows[r]);
  return out;
}
Eigen::MatrixXd part(const Eigen::MatrixXd& q, const std::vector<Eigen::Index>& rows, const std::vector<Eigen::Index>& cols) {
  Eigen::MatrixXd out(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(cols.size()));
  for (std::size_t r = 0; r < rows.size(); ++r) {
    for (std::size_t c = 0; c < cols.size(); ++c) out(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = q(rows[r], cols[c]);
  }
  return out;
}

class DenseCofactors final : public CofactorSource {
 public:
  DenseCofactors(const Problem& p, const Solved& s, const std::vector<std::size_t>& candidate_of) : p_(p), s_(s), of_(candidate_of) {}
  Eigen::MatrixXd column(const std::vector<std::size_t>& rows, std::size_t t) override {
    Eigen::Index total = 0;
    for (std::size_t i : rows) total += static_cast<Eigen::Index>(p_.rows[of_[i]].size());
    Eigen::MatrixXd out(total, static_cast<Eigen::Index>(p_.rows[of_[t]].size()));
    Eigen::Index at = 0;
    for (std::size_t i : rows) {
      const auto& ri = p_.rows[of_[i]];
      out.middleRows(at, static_cast<Eigen::Index>(ri.size())) = part(s_.q, ri, p_.rows[of_[t]]);
      at += static_cast<Eigen::Index>(ri.size());
    }
    return out;
  }

 private:
  const Problem& p_;
  const Solved& s_;
  const std::vector<std::size_t>& of_;
};

// The measurements of `p` that fail their test at `alpha` as `s` leaves
// them: the candidates (keyed m<index>), their measurement indices and
// their whitened design rows.
struct Failing {
  std::vector<SnoopingCandidate> candidates;
  std::vector<std::size_t> of;
  std::vector<Eigen::MatrixXd> design;
};
Failing failing_of(const Problem& p, const Solved& s, double alpha) {
  Failing f;
  for (std::size_t k = 0; k < p.rows.size(); ++k) {
    const Eigen::VectorXd v = part(s.v, p.rows[k]);
    const Eigen::MatrixXd q = part(s.q, p.rows[k], p.rows[k]);
    const MeasurementTest t = measurement_test(v, q, 1.0);
    if (!(t.dof > 0 && t.p_value < alpha)) continue;
    f.candidates.push_back({v, q, "m" + std::to_string(k)});
    f.of.push_back(k);
    Eigen::MatrixXd a(static_cast<Eigen::Index>(p.rows[k].size()), p.a.cols());
    for (std::size_t r = 0; r < p.rows[k].size(); ++r) a.row(static_cast<Eigen::Index>(r)) = p.a.row(p.rows[k][r]);
    f.design.push_back(a);
  }
  return f;
}

// Iterative data snooping done the long way: refit without the removed
// measurements, test every one, remove the strongest failing, again.
std::vector<std::size_t> refitted_order(const Problem& p, double alpha) {
  std::vector<bool> out(p.rows.size(), false);
  std::vector<std::size_t> order;
  for (;;) {
    const Solved s = solve_without(p, out);
    std::ptrdiff_t best = -1;
    MeasurementTest best_test;
    for (std::size_t k = 0; k < p.rows.size(); ++k) {
      if (out[k]) continue;
      const MeasurementTest t = measurement_test(part(s.v, p.rows[k]), part(s.q, p.rows[k], p.rows[k]), 1.0);
      if (!(t.dof > 0 && t.p_value < alpha)) continue;
      if (best < 0 || stronger_evidence(t.log_p, t.statistic, best_test.log_p, best_test.statistic)) best = static_cast<std::ptrdiff_t>(k), best_test = t;
    }
    if (best < 0) return order;
    order.push_back(static_cast<std::size_t>(best));
    out[static_cast<std::size_t>(best)] = true;
  }
}

// The sequence without refitting is iterative snooping: the same
// measurements in the same order as refitting after every removal (both
// ways of computing it: over the cofactors between candidates, as a network
// does, and over the parameters, as a fit does), here
// with three planted blunders of different sizes among 1-D and 3-D
// measurements, over many draws.
TEST(Snooping, Issue39_TheSequenceIsIterativeSnoopingRefittedAfterEachRemoval) {
  constexpr double kAlpha = 0.001;
  std::mt19937 rng(39);
  int compared = 0, with_several = 0;
  for (int trial = 0; trial < 40; ++trial) {
    Problem p = make_problem(rng, 60, 6);
    // Blunders: 50, 8 and 6 units on measurements 3, 4, 17 (rows of theirs).
    p.l(p.rows[3][0]) += 50.0;
    p.l(p.rows[4][0]) += 8.0;
    p.l(p.rows[17].back()) -= 6.0;
    const Solved s = solve_without(p, std::vector<bool>(p.rows.size(), false));
    const Failing failing = failing_of(p, s, kAlpha);
    const std::vector<SnoopingCandidate>& candidates = failing.candidates;
    const std::vector<std::size_t>& candidate_of = failing.of;
    const std::vector<Eigen::MatrixXd>& design = failing.design;
    DenseCofactors source(p, s, candidate_of);
    SnoopingLimits limits;
    limits.alpha = kAlpha;
    limits.max_removals = p.rows.size();
    const SnoopingSequence seq = snooping_sequence(candidates, source, limits);
    std::vector<std::size_t> ours;
    for (const auto& r : seq.removals) ours.push_back(candidate_of[r.candidate]);
    // The same order over the parameters (a fit's way): design rows and N⁻¹.
    const SnoopingSequence by_parameters = snooping_sequence(candidates, design, (p.a.transpose() * p.a).inverse(), limits);
    std::vector<std::size_t> theirs;
    for (const auto& r : by_parameters.removals) theirs.push_back(candidate_of[r.candidate]);
    EXPECT_EQ(theirs, ours) << "trial " << trial;
    // The long way may remove one the sequence never had (a measurement
    // that fails only once others are out, not failing at the start): the
    // sequence is its prefix of the measurements failing at the start.
    const std::vector<std::size_t> reference = refitted_order(p, kAlpha);
    std::vector<std::size_t> from_start;
    bool cut = false;
    for (std::size_t k : reference) {
      if (std::find(candidate_of.begin(), candidate_of.end(), k) == candidate_of.end()) {
        cut = true;
        break;
      }
      from_start.push_back(k);
    }
    if (cut) {
      ASSERT_GE(ours.size(), from_start.size()) << "trial " << trial;
      EXPECT_EQ(std::vector<std::size_t>(ours.begin(), ours.begin() + static_cast<std::ptrdiff_t>(from_start.size())), from_start)
          << "trial " << trial;
    } else {
      EXPECT_EQ(ours, from_start) << "trial " << trial;
    }
    ASSERT_FALSE(ours.empty());
    EXPECT_EQ(ours.front(), 3u) << "the largest blunder goes first";
    ++compared;
    with_several += ours.size() > 1 ? 1 : 0;
  }
  EXPECT_EQ(compared, 40);
  EXPECT_GT(with_several, 20);
}

// The order does not depend on the order of the candidates: the same
// measurements removed in the same order when they come shuffled.
TEST(Snooping, Issue39_ShuffledCandidatesGiveTheSameSequence) {
  std::mt19937 rng(7);
  Problem p = make_problem(rng, 50, 5);
  p.l(p.rows[8][1]) += 30.0;
  p.l(p.rows[9][0]) += 9.0;
  const Solved s = solve_without(p, std::vector<bool>(p.rows.size(), false));
  std::vector<std::size_t> failing;
  for (std::size_t k = 0; k < p.rows.size(); ++k) {
    const MeasurementTest t = measurement_test(part(s.v, p.rows[k]), part(s.q, p.rows[k], p.rows[k]), 1.0);
    if (t.dof > 0 && t.p_value < 0.001) failing.push_back(k);
  }
  ASSERT_GE(failing.size(), 2u);
  std::vector<std::string> reference;
  for (int shuffle = 0; shuffle < 6; ++shuffle) {
    std::vector<std::size_t> candidate_of = failing;
    std::shuffle(candidate_of.begin(), candidate_of.end(), rng);
    std::vector<SnoopingCandidate> candidates;
    for (std::size_t k : candidate_of) candidates.push_back({part(s.v, p.rows[k]), part(s.q, p.rows[k], p.rows[k]), "m" + std::to_string(k)});
    DenseCofactors source(p, s, candidate_of);
    SnoopingLimits limits;
    limits.max_removals = 100;
    const SnoopingSequence seq = snooping_sequence(candidates, source, limits);
    std::vector<std::string> keys;
    for (const auto& r : seq.removals) keys.push_back(candidates[r.candidate].key);
    if (shuffle == 0) reference = keys;
    EXPECT_EQ(keys, reference);
  }
  EXPECT_FALSE(reference.empty());
}

// One rule for a test's dimension: the eigenvalues of the whitened
// residual cofactor at or above kMinRedundancy; below it a direction is
// not tested (a redundancy of 1e-10 would give |w| of a few units from
// rounding), and a measurement with none is uncontrolled.
TEST(Snooping, Issue39_ATestCountsOnlyTheDirectionsWithRedundancy) {
  Eigen::MatrixXd q = Eigen::MatrixXd::Zero(3, 3);
  q(0, 0) = 0.5;
  q(1, 1) = 1e-10;
  q(2, 2) = 0.9 * kMinRedundancy;
  Eigen::VectorXd v(3);
  v << 1.0, 2.6e-5, 0.01;
  const MeasurementTest t = measurement_test(v, q, 1.0);
  EXPECT_EQ(t.dof, 1);
  EXPECT_DOUBLE_EQ(t.statistic, 2.0);  // 1² / 0.5
  const ObservationTest o = test_observation(v, Eigen::MatrixXd::Identity(3, 3), q, Eigen::MatrixXd::Identity(3, 3), true, 1.0, 17.07);
  EXPECT_TRUE(std::isfinite(o.w(0)));
  EXPECT_TRUE(std::isnan(o.w(1)));
  EXPECT_TRUE(std::isnan(o.w(2)));
  EXPECT_TRUE(std::isinf(o.mdb(1)));
  const MeasurementTest none = measurement_test(Eigen::VectorXd::Constant(1, 3.0), Eigen::MatrixXd::Constant(1, 1, 1e-10), 1.0);
  EXPECT_EQ(none.dof, 0);
  EXPECT_EQ(none.p_value, 1.0);
}

// Two measurements that are each other's only check (one unknown measured
// twice, nothing else on it) fail alike when one is a blunder: their
// residuals are correlated by −1, and removing either would leave the other
// untested. Neither is removed, on both paths; they are named together, and
// the sequence ends there: a weaker blunder elsewhere stays flagged.
TEST(Snooping, Issue39_MeasurementsThatCannotBeToldApartAreNotRemoved) {
  std::mt19937 rng(3);
  std::normal_distribution<double> z;
  Problem p;
  constexpr int kOthers = 12;
  p.a = Eigen::MatrixXd::Zero(2 + kOthers, 2);
  p.l.resize(2 + kOthers);
  p.a(0, 0) = 1.0;
  p.a(1, 0) = 1.0;
  for (int r = 2; r < 2 + kOthers; ++r) p.a(r, 1) = 1.0 + 0.1 * r;
  for (Eigen::Index r = 0; r < p.l.size(); ++r) p.l(r) = z(rng);
  for (Eigen::Index r = 0; r < p.l.size(); ++r) p.rows.push_back({r});
  p.l(0) += 20.0;
  p.l(5) += 7.0;  // a weaker blunder elsewhere: not removed in the pair's place
  const Solved s = solve_without(p, std::vector<bool>(p.rows.size(), false));
  const Failing failing = failing_of(p, s, 0.001);
  const std::vector<SnoopingCandidate>& candidates = failing.candidates;
  const std::vector<std::size_t>& candidate_of = failing.of;
  const std::vector<Eigen::MatrixXd>& design = failing.design;
  ASSERT_EQ(candidate_of, (std::vector<std::size_t>{0, 1, 5}));
  SnoopingLimits limits;
  limits.max_removals = 5;
  DenseCofactors source(p, s, candidate_of);
  for (const SnoopingSequence& seq :
       {snooping_sequence(candidates, source, limits), snooping_sequence(candidates, design, (p.a.transpose() * p.a).inverse(), limits)}) {
    EXPECT_TRUE(seq.removals.empty());
    ASSERT_EQ(seq.inseparable.size(), 1u);
    std::vector<std::size_t> group = seq.inseparable.front();
    std::sort(group.begin(), group.end());
    EXPECT_EQ(group, (std::vector<std::size_t>{0, 1}));
    EXPECT_GE(seq.stopped_at, 0);
    EXPECT_EQ(seq.passes_after, (std::vector<std::ptrdiff_t>{-1, -1, -1}));
  }
}

// A measurement that shares part of a blunder's redundancy is not
// inseparable from it: one precise observation of an unknown (redundancy
// 1.1·10⁻³, just above the tested level) and four of unit weight, one of
// them 30σ wrong. Removing the blunder leaves the precise one below the
// tested level (correlation −0.5, not ±1): it becomes untested, and the
// blunder is removed, first and alone.
TEST(Snooping, Issue39_APartialShareOfRedundancyIsNotInseparable) {
  std::mt19937 rng(1);
  std::normal_distribution<double> z;
  Problem p;
  p.a.resize(5, 1);
  p.a << std::sqrt(3500.0), 1.0, 1.0, 1.0, 1.0;
  p.l.resize(5);
  for (Eigen::Index r = 0; r < 5; ++r) {
    p.l(r) = 0.3 * z(rng);
    p.rows.push_back({r});
  }
  p.l(1) += 30.0;
  const Solved s = solve_without(p, std::vector<bool>(p.rows.size(), false));
  const Failing failing = failing_of(p, s, 0.001);
  const std::vector<SnoopingCandidate>& candidates = failing.candidates;
  const std::vector<std::size_t>& candidate_of = failing.of;
  const std::vector<Eigen::MatrixXd>& design = failing.design;
  ASSERT_NE(std::find(candidate_of.begin(), candidate_of.end(), 0u), candidate_of.end());  // the precise one fails too
  SnoopingLimits limits;
  limits.max_removals = 2;
  DenseCofactors source(p, s, candidate_of);
  for (const SnoopingSequence& seq :
       {snooping_sequence(candidates, source, limits), snooping_sequence(candidates, design, (p.a.transpose() * p.a).inverse(), limits)}) {
    EXPECT_TRUE(seq.inseparable.empty());
    ASSERT_EQ(seq.removals.size(), 1u);
    EXPECT_EQ(candidate_of[seq.removals.front().candidate], 1u);
  }
}

// Past the limit the sequence says how the ones still failing test with
// the removals made: the statistic of a refit without them.
TEST(Snooping, Issue39_TheLimitReportsTheTestsAsTheRemovalsLeaveThem) {
  constexpr double kStatisticRelative = 1e-9;
  std::mt19937 rng(11);
  Problem p = make_problem(rng, 60, 6);
  p.l(p.rows[3][0]) += 50.0;
  p.l(p.rows[4][0]) += 12.0;
  p.l(p.rows[17].back()) -= 10.0;
  const Solved s = solve_without(p, std::vector<bool>(p.rows.size(), false));
  const Failing failing = failing_of(p, s, 0.001);
  const std::vector<SnoopingCandidate>& candidates = failing.candidates;
  const std::vector<std::size_t>& candidate_of = failing.of;
  DenseCofactors source(p, s, candidate_of);
  SnoopingLimits limits;
  limits.max_removals = 1;
  const SnoopingSequence seq = snooping_sequence(candidates, source, limits);
  ASSERT_EQ(seq.removals.size(), 1u);
  ASSERT_TRUE(seq.limit_reached);
  EXPECT_FALSE(seq.hopeless);
  ASSERT_FALSE(seq.still_failing.empty());
  std::vector<bool> out(p.rows.size(), false);
  out[candidate_of[seq.removals.front().candidate]] = true;
  const Solved after = solve_without(p, out);
  for (const SnoopingTest& t : seq.still_failing) {
    const auto& rows = p.rows[candidate_of[t.candidate]];
    const MeasurementTest reference = measurement_test(part(after.v, rows), part(after.q, rows, rows), 1.0);
    EXPECT_NEAR(t.statistic, reference.statistic, kStatisticRelative * reference.statistic) << candidates[t.candidate].key;
    EXPECT_LT(t.p_value, 0.001);
  }
}

// A model error, not blunders: a sign-dependent offset the linear model
// cannot absorb makes a third of the measurements fail, and each removal
// takes only itself out of the failing. Once the failing outnumber the
// removals left and ten removals explained none of the others, the
// sequence stops (hopeless) instead of ranking them all.
TEST(Snooping, Issue39_FailuresNoRemovalExplainsStopTheSequenceEarly) {
  std::mt19937 rng(5);
  std::normal_distribution<double> z;
  Problem p;
  constexpr int kMeasurements = 400;
  p.a.resize(kMeasurements, 3);
  p.l.resize(kMeasurements);
  for (int r = 0; r < kMeasurements; ++r) {
    for (int c = 0; c < 3; ++c) p.a(r, c) = z(rng);
    p.l(r) = z(rng) + (p.a(r, 0) > 0.3 ? 8.0 : 0.0);
    p.rows.push_back({r});
  }
  const Solved s = solve_without(p, std::vector<bool>(p.rows.size(), false));
  const Failing failing = failing_of(p, s, 0.001);
  const std::vector<SnoopingCandidate>& candidates = failing.candidates;
  const std::vector<Eigen::MatrixXd>& design = failing.design;
  ASSERT_GT(candidates.size(), 60u);
  SnoopingLimits limits;
  limits.max_removals = kMeasurements / 20;  // 5 %
  const SnoopingSequence seq = snooping_sequence(candidates, design, (p.a.transpose() * p.a).inverse(), limits);
  EXPECT_TRUE(seq.hopeless);
  EXPECT_TRUE(seq.limit_reached);
  EXPECT_EQ(seq.removals.size(), kHopelessWindow);
  EXPECT_GT(seq.still_failing.size(), limits.max_removals - kHopelessWindow);
}

// τ-tests with nothing left to scale by (Ω = 0) test nothing; a residual
// that is not finite gives a test that says so, and never reaches Boost
// (which throws on it).
TEST(Snooping, Issue39_DegenerateTestsNeitherThrowNorInventNumbers) {
  const Eigen::MatrixXd q = Eigen::MatrixXd::Identity(1, 1) * 0.5;
  const MeasurementTest inf = measurement_test(Eigen::VectorXd::Constant(1, std::numeric_limits<double>::infinity()), q, 1.0);
  EXPECT_EQ(inf.p_value, 0.0);
  EXPECT_EQ(inf.log_p, -std::numeric_limits<double>::infinity());
  const MeasurementTest nan = measurement_test(Eigen::VectorXd::Constant(1, std::numeric_limits<double>::quiet_NaN()), q, 1.0);
  EXPECT_TRUE(std::isnan(nan.p_value));
  EXPECT_TRUE(std::isnan(nan.log_p));
  // Two failing candidates whose residuals make up all of Ω: once the
  // first is out Ω is 0 (to rounding, never below), and the second is not
  // tested by a σ̂0 of 0 (0/0) — the sequence ends with one removal.
  std::vector<SnoopingCandidate> candidates{{Eigen::VectorXd::Constant(1, 40.0), q, "a"},
                                            {Eigen::VectorXd::Constant(1, 0.0), q, "b"}};
  std::vector<Eigen::MatrixXd> design{Eigen::MatrixXd::Constant(1, 1, std::sqrt(0.5)), Eigen::MatrixXd::Constant(1, 1, 0.0)};
  SnoopingLimits limits;
  limits.max_removals = 5;
  limits.scale_by_sigma0 = true;
  limits.omega = 40.0 * 40.0 / 0.5;  // = a's share, ‖L⁻¹ v‖²
  limits.dof = 3;
  limits.alpha = 0.5;  // (at σ̂0 = √(Ω/dof) a's τ-test fails at this level)
  const SnoopingSequence seq = snooping_sequence(candidates, design, Eigen::MatrixXd::Identity(1, 1), limits);
  ASSERT_EQ(seq.removals.size(), 1u);
  EXPECT_EQ(seq.removals.front().candidate, 0u);
  EXPECT_TRUE(std::isfinite(seq.removals.front().statistic));
  EXPECT_FALSE(seq.limit_reached);
  limits.omega = 0.0;  // nothing to scale by from the start: nothing tested
  EXPECT_TRUE(snooping_sequence(candidates, design, Eigen::MatrixXd::Identity(1, 1), limits).removals.empty());
}

// ln Γ at half-whole arguments (no std::lgamma: it writes a global) is
// checked through the tail's continued fraction against Boost's long
// double at dof where the fraction is used (p below 1e-280).
TEST(Snooping, Issue39_TheContinuedFractionsGammaIsExactAtEveryDof) {
  testing::WorstCase worst;
  for (int dof = 1; dof <= 41; ++dof) {
    const double x = 1400.0 + 10.0 * dof;
    const long double reference =
        std::log(boost::math::cdf(boost::math::complement(boost::math::chi_squared_distribution<long double>(dof), static_cast<long double>(x))));
    worst.add(std::abs(chi_squared_log_upper_tail(dof, x) - static_cast<double>(reference)) / std::abs(static_cast<double>(reference)));
  }
  EXPECT_WORST_WITHIN(worst, kLogTailRelative);
}

}  // namespace
}  // namespace geoanchor::solver
