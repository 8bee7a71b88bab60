#pragma once
// Iterative data snooping (Baarda), in one implementation for fit and
// adjust: the order in which the failing measurements (or marks) would be
// removed one at a time, each time the one with the strongest evidence
// against it, every other test recomputed without the ones before it.
//
// Nothing is refitted here. Removing measurements R from a least-squares
// adjustment changes the whitened residuals and their cofactor exactly as
//   v' = v − Q(·,R) Q(R,R)⁻¹ v_R,   Q' = Q − Q(·,R) Q(R,R)⁻¹ Q(R,·)
// (Q = I − A N⁻¹ Aᵀ, the whitened residuals' cofactor): the projector onto
// the residual space loses the directions of R (Sherman–Morrison–Woodbury
// in the space of the residuals). So the sequence needs only each
// candidate's residual and cofactor and, for each removal t, the column of
// blocks Q(i, t) between it and the candidates still in play, which the
// caller's CofactorSource gives (fit: from the parameters' cofactor; adjust:
// one solve with the network's factor per removal, or one multi-column
// solve for all candidates). Q(R,R) is kept as its Cholesky factor, grown
// one removal at a time, so that a removal costs the column and a product
// over the removals so far.
//
// Evidence: a test's statistic S = vᵀQ⁺v (the χ² quantity; w² for one
// dimension), then the natural logarithm of its p-value (computed without
// underflow), then the candidates' keys (their content, never their place
// in the input), so that the order of the input changes nothing. Under one
// blunder b, every other measurement's S from b's bias is at most b's,
// whatever the two dimensions (Q is a projector, so Q_bb ⪰ Q_bi Q_ii⁻¹ Q_ib):
// a gross blunder is removed before any measurement it contaminates, and
// once it is out their tests are computed without it. (ln p would not do
// across dimensions: a 1-D measurement at 0.95 of a 3-D blunder's S has the
// smaller p.) When the strongest candidate cannot be removed (some
// direction of it has no redundancy, or it cannot be told from another) the
// sequence ends there: the weaker ones may fail because of it.
//
// Private to solver.

#include <Eigen/Core>

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace geoanchor::solver {

// A measurement that fails its test as the adjustment stands.
struct SnoopingCandidate {
  Eigen::VectorXd v;  // whitened residual (k components)
  Eigen::MatrixXd q;  // whitened residual cofactor (k × k): Q(i, i)
  std::string key;    // breaks exact ties in evidence: what it is (kind, stations, values), not where it is
};

// The whitened residuals' cofactor between candidates, of the adjustment
// as it stands (before any removal of the sequence).
class CofactorSource {
 public:
  virtual ~CofactorSource() = default;
  // The blocks Q(i, column) for every candidate i of `rows`, stacked in
  // that order (Σ k_i rows × k_column columns). `rows` may include `column`
  // itself (its block is Q(column, column)).
  virtual Eigen::MatrixXd column(const std::vector<std::size_t>& rows, std::size_t column) = 0;
  // A hint: the columns of these candidates will be asked for with (a
  // subset of) them as rows; a source whose columns cost a solve each does
  // them together.
  virtual void prefetch(const std::vector<std::size_t>& candidates) { (void)candidates; }
};

struct SnoopingLimits {
  double alpha = 0.001;  // a candidate fails while its test's p-value is below it
  // The most removals (max_outlier_share); past it limit_reached.
  std::size_t max_removals = 0;
  // τ-tests (σ0 estimated: fit --scale-by-sigma0): the residuals scaled by
  // √(Ω/dof) as Ω and dof fall with each removal (once either reaches 0
  // there is no σ̂0 left to test by: the sequence ends); else σ0 = 1.
  bool scale_by_sigma0 = false;
  double omega = 0.0;
  int dof = 0;
  // Whether the (count)th removal, of `candidate`, may be made (a fit keeps
  // its fewest points); false stops the sequence (stopped_by_caller).
  std::function<bool(std::size_t count, std::size_t candidate)> may_remove;
};

// A candidate's test at one step of the sequence (after the removals
// before it).
struct SnoopingTest {
  std::size_t candidate = 0;  // index into the candidates
  double statistic = 0.0;
  int dof = 0;
  double p_value = 1.0;
  double log_p = 0.0;
};

struct SnoopingSequence {
  // In the order they would be made, each with its test when it was made.
  std::vector<SnoopingTest> removals;
  // Failing, but not removable: some direction of its residual has no
  // redundancy once the earlier ones are out (the rest would not determine
  // all it measures). At most one: the sequence ends there.
  std::vector<std::size_t> not_removable;
  // Failing candidates that cannot be told apart: removing the first would
  // take the redundancy of the others (their residuals correlated by
  // ±1 along it), so that they would pass because they could no longer be
  // tested. One of them is wrong; none is removed, and the sequence ends
  // there. At most one group.
  std::vector<std::vector<std::size_t>> inseparable;
  // The candidate (the strongest failing then) at which the sequence ended
  // because it could not be removed (not_removable or inseparable): the
  // weaker ones may fail because of it, so none of them is removed in its
  // place; −1 when it did not end so.
  std::ptrdiff_t stopped_at = -1;
  // The candidates that still fail, with their tests, when the sequence
  // stopped at max_removals (limit_reached) or by may_remove
  // (stopped_by_caller); strongest first.
  std::vector<SnoopingTest> still_failing;
  bool limit_reached = false;
  // limit_reached before max_removals: more candidates fail than removals
  // remain, and the last kHopelessWindow removals explained almost none of
  // the others (each took only itself out of the failing): the signature of
  // a wrong model or frame, not of blunders, which the remaining removals
  // could not finish. Stopped there rather than ranking thousands.
  bool hopeless = false;
  bool stopped_by_caller = false;
  // Per candidate: the removal (index into `removals`) after which it no
  // longer fails, its failure explained by the ones removed before, tested
  // over as many directions as at the start; −1 for the removed and those
  // that fail to the end.
  std::vector<std::ptrdiff_t> passes_after;
};

// The window of the hopeless stop (SnoopingSequence::hopeless): over this
// many consecutive removals the failing count fell by at most twice as
// many.
inline constexpr std::size_t kHopelessWindow = 10;

SnoopingSequence snooping_sequence(const std::vector<SnoopingCandidate>& candidates, CofactorSource& source,
                                   const SnoopingLimits& limits);

// The same for a problem of few parameters (a fit): each candidate's
// whitened design rows over them (`design`, k_i × u; Q(i, j) = δ_ij I −
// A_i N⁻¹ A_jᵀ) and their cofactor N⁻¹ (u × u). Each removal updates N⁻¹
// and the parameters (Sherman–Morrison–Woodbury): O(u²) a candidate, so a
// set of 10⁶ marks with a thousand failing by chance ranks them in
// milliseconds, where the cofactors between them would grow with the
// square of their number.
SnoopingSequence snooping_sequence(const std::vector<SnoopingCandidate>& candidates, const std::vector<Eigen::MatrixXd>& design,
                                   const Eigen::MatrixXd& n_inv, const SnoopingLimits& limits);

// Whether evidence (ln p, statistic) `a` is stronger than `b` (the larger
// statistic; equal: the smaller ln p). Neither when both are equal.
bool stronger_evidence(double log_p_a, double statistic_a, double log_p_b, double statistic_b);

}  // namespace geoanchor::solver
