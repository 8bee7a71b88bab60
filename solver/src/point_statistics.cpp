#include "point_statistics.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "fit_common.hpp"
#include "snooping.hpp"
#include "statistics.hpp"

namespace geoanchor::solver {
namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

const char* to_string(TestStatus s) {
  switch (s) {
    case TestStatus::used: return "used";
    case TestStatus::flagged: return "flagged";
    case TestStatus::removed: return "removed";
    case TestStatus::uncontrolled: return "uncontrolled";
    case TestStatus::ignored: return "ignored";
  }
  return "used";
}

namespace {

// Σ (eᵀ v)² / λ over the eigenpairs (λ, e) of q with λ ≥ kMinRedundancy.
// Where q − kMinRedundancy·I is positive definite every eigenvalue is above
// it: then vᵀ q⁻¹ v by a Cholesky factor, without the eigen decomposition
// (a million marks' point tests in a fraction of the time).
template <class Matrix, class Vector>
void controlled_quadratic_form(const Matrix& q, const Vector& vw, MeasurementTest& t) {
  const Eigen::LLT<Matrix> above(q - kMinRedundancy * Matrix::Identity(q.rows(), q.cols()));
  if (above.info() == Eigen::Success) {
    const Eigen::LLT<Matrix> all(q);
    if (all.info() == Eigen::Success) {
      t.statistic = all.matrixL().solve(vw).squaredNorm();
      t.dof = static_cast<int>(q.rows());
      return;
    }
  }
  const Eigen::SelfAdjointEigenSolver<Matrix> eig(q);
  for (Eigen::Index e = 0; e < q.rows(); ++e) {
    if (!(eig.eigenvalues()(e) >= kMinRedundancy)) continue;
    const double projection = eig.eigenvectors().col(e).dot(vw);
    t.statistic += projection * projection / eig.eigenvalues()(e);
    ++t.dof;
  }
}

}  // namespace

namespace {

// The statistic's p-value and its logarithm, once the quadratic form and
// its dimension are known.
void finish(MeasurementTest& t, double sigma_scale) {
  t.statistic /= sigma_scale * sigma_scale;
  if (t.dof > 0) {
    // (A residual that is not finite gives a statistic that is not: p = 0
    // for +inf, NaN for NaN — never passed to Boost, which throws on them.)
    const ChiSquaredTail tail = chi_squared_tail(t.dof, t.statistic);
    t.p_value = tail.p;
    t.log_p = tail.log_p;
  }
}

template <class Vector, class Matrix>
MeasurementTest measurement_test_of(const Vector& vw, const Matrix& q, double sigma_scale) {
  MeasurementTest t;
  if (vw.size() == 1) {
    if (q(0, 0) >= kMinRedundancy) {
      t.statistic = vw(0) * vw(0) / q(0, 0);
      t.dof = 1;
    }
  } else if (vw.size() == 3) {
    controlled_quadratic_form(Eigen::Matrix3d(q), Eigen::Vector3d(vw), t);
  } else {
    controlled_quadratic_form(Eigen::MatrixXd(q), Eigen::VectorXd(vw), t);
  }
  finish(t, sigma_scale);
  return t;
}

template <int K, class Vector, class Matrix>
ObservationTestOf<K> test_observation_of(const Vector& v, const Matrix& w, const Matrix& q, const Matrix& axes, bool in_fit,
                                         double sigma_scale, double lambda0) {
  ObservationTestOf<K> t;
  const Eigen::Index k = v.size();
  const Vector vw = w * v;
  const MeasurementTest m = measurement_test_of(vw, q, sigma_scale);
  t.statistic = m.statistic;
  t.dof = m.dof;
  t.p_value = m.p_value;
  t.log_p = m.log_p;

  // Redundancy numbers: the diagonal of R = Q_v P (Q_v the residuals'
  // cofactor, P = C⁻¹) along each axis; in whitened terms R = W⁻¹ Q W, whose
  // trace over all observations is the degrees of freedom.
  const Matrix r = w.partialPivLu().solve(Matrix(q * w));
  // w-tests (Baarda) for a blunder along each axis.
  const Eigen::Index n_axes = axes.rows();
  t.w.setZero(n_axes);
  t.redundancy.setZero(n_axes);
  t.mdb.setConstant(n_axes, in_fit ? 0.0 : kNaN);  // outside the fit: no detectability
  for (Eigen::Index axis = 0; axis < n_axes; ++axis) {
    const Vector b = w * axes.row(axis).transpose();  // blunder direction, whitened
    const double qb = b.dot(q * b);
    if (in_fit) {
      double along = 0.0;  // aᵀ R a
      for (Eigen::Index i = 0; i < k; ++i) {
        for (Eigen::Index j = 0; j < k; ++j) along += axes(axis, i) * r(i, j) * axes(axis, j);
      }
      t.redundancy(axis) = std::max(0.0, along);  // rounding of a zero redundancy can be negative
    }
    if (!(qb >= kMinRedundancy * b.squaredNorm())) {  // uncontrolled along this axis: no w-test
      t.w(axis) = kNaN;
      if (in_fit) t.mdb(axis) = std::numeric_limits<double>::infinity();
      continue;
    }
    t.w(axis) = b.dot(vw) / std::sqrt(qb) / sigma_scale;  // τ-test when σ0 is estimated
    if (!(std::fabs(t.w(axis)) <= t.w_max)) t.w_max = std::fabs(t.w(axis));
    if (in_fit) t.mdb(axis) = std::sqrt(lambda0) * sigma_scale / std::sqrt(qb);
  }
  return t;
}

}  // namespace

MeasurementTest measurement_test(const Eigen::VectorXd& vw, const Eigen::MatrixXd& q, double sigma_scale) {
  return measurement_test_of(vw, q, sigma_scale);
}

ObservationTest test_observation(const Eigen::VectorXd& v, const Eigen::MatrixXd& w, const Eigen::MatrixXd& q,
                                 const Eigen::MatrixXd& axes, bool in_fit, double sigma_scale, double lambda0) {
  return test_observation_of<Eigen::Dynamic>(v, w, q, axes, in_fit, sigma_scale, lambda0);
}

ObservationTestOf<3> test_observation(const Eigen::Vector3d& v, const Eigen::Matrix3d& w, const Eigen::Matrix3d& q,
                                      const Eigen::Matrix3d& axes, bool in_fit, double sigma_scale, double lambda0) {
  return test_observation_of<3>(v, w, q, axes, in_fit, sigma_scale, lambda0);
}

void test_point(const PointTestInput& in, double sigma_scale, double lambda0, PointResult& pr) {
  pr.residual_enu_m = in.enu * in.v_m;
  // C_v = W⁻¹ Q W⁻ᵀ (W whitens: Wᵀ W = C⁻¹), in E, N, U, scaled as σ is.
  const Eigen::Matrix3d w_inv = in.w.inverse();
  pr.residual_cov_enu_m2 = (sigma_scale * sigma_scale) * (in.enu * w_inv * in.q * w_inv.transpose() * in.enu.transpose());
  const ObservationTestOf<3> t = test_observation(in.v_m, in.w, in.q, in.enu, in.in_fit, sigma_scale, lambda0);
  pr.point_statistic = t.statistic;
  pr.point_dof = t.dof;
  pr.point_p_value = t.p_value;
  pr.point_log_p = t.log_p;
  pr.w_enu = t.w;
  pr.w_max = t.w_max;
  pr.redundancy_enu = t.redundancy;
  // The largest MDB over the axes (inf when one is undetectable, NaN outside the fit).
  pr.mdb_m = in.in_fit ? 0.0 : kNaN;
  for (Eigen::Index axis = 0; axis < 3 && in.in_fit; ++axis) {
    if (!(t.mdb(axis) <= pr.mdb_m)) pr.mdb_m = t.mdb(axis);
  }
}

GlobalTest global_test(double omega, int dof, double alpha, bool applicable) {
  GlobalTest g;
  g.statistic = omega;
  g.applicable = applicable && dof > 0;
  if (dof > 0) {
    g.critical_lower = chi_squared_quantile(dof, alpha / 2.0);
    g.critical_upper = chi_squared_quantile(dof, 1.0 - alpha / 2.0);
    g.passed = omega >= g.critical_lower && omega <= g.critical_upper;
  }
  return g;
}

PointTestLevels point_test_levels(const FitOptions& o) {
  PointTestLevels l;
  l.w_critical = normal_quantile(1.0 - o.alpha_point / 2.0);
  l.lambda0 = std::pow(l.w_critical + normal_quantile(o.power), 2.0);
  return l;
}

void fill_global_test(FitResult& r, double omega, int dof, double alpha, bool a_priori_sigmas) {
  r.dof = dof;
  r.sigma0 = dof > 0 ? std::optional<double>(std::sqrt(omega / dof)) : std::nullopt;
  r.global_test = global_test(omega, dof, alpha, a_priori_sigmas);
}

double sigma_scale(const FitResult& r, const FitOptions& o) { return o.scale_by_sigma0 && r.sigma0 ? *r.sigma0 : 1.0; }

Eigen::MatrixXd correlation_of(const Eigen::MatrixXd& cov) {
  Eigen::MatrixXd c = cov;
  for (Eigen::Index a = 0; a < cov.rows(); ++a) {
    for (Eigen::Index b = 0; b < cov.cols(); ++b) c(a, b) = a == b ? 1.0 : correlation_coefficient(cov(a, b), cov(a, a), cov(b, b));
  }
  return c;
}

double correlation_coefficient(double covariance, double variance_a, double variance_b) {
  const double d = std::sqrt(variance_a * variance_b);
  if (!(d > 0.0) || !std::isfinite(covariance)) return 0.0;
  // A covariance matrix's rounding can put |c| a few parts in 10⁶ past 1
  // where two components are nearly dependent; a correlation is never more.
  return std::clamp(covariance / d, -1.0, 1.0);
}

std::size_t max_snooped(std::size_t n, const FitOptions& o) {
  return std::max<std::size_t>(1, static_cast<std::size_t>(std::floor(o.max_outlier_share * static_cast<double>(n))));
}

SnoopStep snoop(FitResult& r, std::vector<std::size_t>& active, const FitOptions& o, int u, int min_points,
                const FitLinearization& lin) {
  if (!o.data_snooping || r.dof <= 0 || lin.position.empty()) return SnoopStep::none;
  const auto why_of = [&](const PointResult& pr) {
    return "point test " + fmt(pr.point_statistic, 4) + " (χ²(" + std::to_string(pr.point_dof) + "), p = " +
           fmt(pr.point_p_value, 2) + " < " + fmt(o.alpha_point) + "); max |w| " + fmt(pr.w_max) + "; residual E/N/U " +
           fmt(pr.residual_enu_m.x()) + ", " + fmt(pr.residual_enu_m.y()) + ", " + fmt(pr.residual_enu_m.z()) + " m";
  };
  // The candidates: the marks failing now (their design rows and residuals
  // as the fit stands), keyed by id (ids are unique in a control set).
  std::vector<SnoopingCandidate> candidates(lin.position.size());
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    candidates[c].v = lin.vw[c];
    candidates[c].q = Eigen::Matrix3d::Identity() - lin.a[c] * lin.n_inv * lin.a[c].transpose();
    candidates[c].key = r.points[active[lin.position[c]]].id;
  }
  // The limit counts the marks that entered the fit (not those the input
  // left out).
  std::size_t marks = 0, removed = 0;
  for (const PointResult& p : r.points) {
    marks += p.used || p.outlier ? 1u : 0u;
    removed += p.outlier ? 1u : 0u;
  }
  const std::size_t limit = max_snooped(marks, o);
  const int n = static_cast<int>(active.size());
  SnoopingLimits limits;
  limits.alpha = o.alpha_point;
  limits.max_removals = limit > removed ? limit - removed : 0;
  limits.scale_by_sigma0 = o.scale_by_sigma0 && r.sigma0.has_value();
  limits.dof = r.dof;
  limits.omega = r.sigma0 ? *r.sigma0 * *r.sigma0 * r.dof : 0.0;
  limits.may_remove = [&](std::size_t count, std::size_t) {
    const int left = n - static_cast<int>(count);
    return left >= min_points && 3 * left - u > 0;
  };
  const SnoopingSequence seq = snooping_sequence(candidates, lin.a, lin.n_inv, limits);
  const auto point_of = [&](std::size_t c) -> PointResult& { return r.points[active[lin.position[c]]]; };
  // Ranks continue those of the marks removed in earlier passes.
  for (std::size_t k = 0; k < seq.removals.size(); ++k) point_of(seq.removals[k].candidate).snooping_rank = removed + k + 1;
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    point_of(c).passes_after_rank =
        seq.passes_after[c] >= 0 ? removed + static_cast<std::size_t>(seq.passes_after[c]) + 1 : 0;
  }
  // What this pass says; kept only when it is the last (a pass that
  // removes is followed by another, which says it again with them out).
  std::vector<std::string> said;
  const std::string stops = "; data snooping stops there (the weaker failing marks may fail because of it, so none is "
                            "removed in its place)";
  for (std::size_t c : seq.not_removable) {
    said.push_back("point " + point_of(c).id + " fails the " + why_of(point_of(c)) +
                   ", but too few points remain to remove it (the other marks do not determine all the fit takes from it)" +
                   stops);
  }
  for (const auto& group : seq.inseparable) {
    std::string ids;
    for (std::size_t c : group) ids += (ids.empty() ? "" : ", ") + point_of(c).id;
    said.push_back("points " + ids + " fail their point tests and cannot be told apart: with " + point_of(group.front()).id +
                   " removed the others could no longer be tested along the direction they share (their residuals are "
                   "correlated by ±1 there); one of them is wrong, none is removed" + stops);
  }
  const auto test_text = [&](const SnoopingTest& t) {
    return "point test " + fmt(t.statistic, 4) + " (χ²(" + std::to_string(t.dof) + "), p = " + fmt(t.p_value, 2) + ")";
  };
  if (seq.stopped_by_caller && !seq.still_failing.empty()) {
    const PointResult& worst = point_of(seq.still_failing.front().candidate);
    said.push_back("point " + worst.id + " fails the " + why_of(worst) + ", but too few points remain to remove it");
  }
  // Past the limit: with --remove-outliers the marks up to it go first (the
  // next pass refuses, with them out), unless the sequence found the
  // failures hopeless (then it refuses now); else named.
  const bool refuse_now = seq.limit_reached && (!o.remove_outliers || seq.removals.empty() || seq.hopeless);
  if (refuse_now && !seq.still_failing.empty()) {
    const SnoopingTest& worst_test = seq.still_failing.front();
    const PointResult& worst = point_of(worst_test.candidate);
    const auto& g = r.global_test;
    std::string global;
    if (g.applicable) {
      global = std::string("; the global test ") + (g.passed ? "passes" : g.failed_high() ? "fails high" : "fails low") +
               " (" + fmt(g.statistic, 4) + " vs [" + fmt(g.critical_lower, 4) + ", " + fmt(g.critical_upper, 4) +
               "], σ0 = " + fmt(r.sigma0.value_or(0.0), 4) + ")";
    }
    const std::size_t sequenced = removed + seq.removals.size();
    const std::string why =
        "data snooping " + std::string(o.remove_outliers ? "stopped after removing " : "would stop after removing ") +
        std::to_string(o.remove_outliers ? removed : sequenced) + " of " + std::to_string(marks) + " marks" +
        (seq.hopeless ? " (" + std::to_string(seq.still_failing.size()) + " fail, more than the " +
                            std::to_string(limit - std::min(limit, sequenced)) + " removals left under the limit, and the last " +
                            std::to_string(kHopelessWindow) + " removals explained almost none of the others)"
                      : std::string(" (the limit is ") + fmt(100.0 * o.max_outlier_share, 3) + " %, --max-outlier-share)") +
        ": " + worst.id + " still fails its " + test_text(worst_test) + " with those out (as the fit stands: " + why_of(worst) + ")" +
        global + "; " + std::to_string(seq.still_failing.size()) +
        " marks fail then. So many failing marks mean the data or the model is wrong (frames, units, height types, quantized "
        "coordinates), not a few blunders";
    if (o.remove_outliers) r.refused_because = why;
    said.push_back(why);
    if (o.remove_outliers) {
      for (auto& w : said) r.warnings.push_back(std::move(w));
      return SnoopStep::stopped;
    }
  }
  if (!o.remove_outliers || seq.removals.empty()) {
    for (auto& w : said) r.warnings.push_back(std::move(w));
    return SnoopStep::none;
  }
  // --remove-outliers: the ranked marks go, in their order; the caller
  // fits again and tests every mark anew.
  std::vector<std::size_t> take;
  for (const SnoopingTest& x : seq.removals) {
    PointResult& pr = point_of(x.candidate);
    pr.outlier = true;
    pr.used = false;
    pr.removed_because = "data snooping (rank " + std::to_string(pr.snooping_rank) + "): " + why_of(pr) +
                         (x.statistic != pr.point_statistic
                              ? " (with the marks removed before it: point test " + fmt(x.statistic, 4) + ", p = " + fmt(x.p_value, 2) + ")"
                              : std::string());
    take.push_back(lin.position[x.candidate]);
  }
  std::sort(take.begin(), take.end());
  for (auto it = take.rbegin(); it != take.rend(); ++it) active.erase(active.begin() + static_cast<std::ptrdiff_t>(*it));
  return SnoopStep::removed;
}

GeometryDilution geometry_dilution(const Eigen::MatrixXd& scaled_cov, const std::vector<int>& translations) {
  GeometryDilution g;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(scaled_cov);
  const Eigen::Index top = scaled_cov.rows() - 1;
  double reference = 0.0;
  for (int t : translations) reference += scaled_cov(t, t) / static_cast<double>(translations.size());
  g.dilution = std::sqrt(std::max(eig.eigenvalues()(top), 0.0) / reference);
  g.direction = eig.eigenvectors().col(top);
  return g;
}

std::vector<std::size_t> failing_marks(const FitResult& r) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < r.points.size(); ++i) {
    const TestStatus s = r.points[i].status(r.alpha_point);
    if (s == TestStatus::flagged || (s == TestStatus::removed && r.points[i].snooping_rank > 0)) out.push_back(i);
  }
  std::sort(out.begin(), out.end(), [&](std::size_t a, std::size_t b) {
    const PointResult& pa = r.points[a];
    const PointResult& pb = r.points[b];
    if ((pa.snooping_rank > 0) != (pb.snooping_rank > 0)) return pa.snooping_rank > 0;
    if (pa.snooping_rank != pb.snooping_rank) return pa.snooping_rank < pb.snooping_rank;
    if (stronger_evidence(pa.point_log_p, pa.point_statistic, pb.point_log_p, pb.point_statistic)) return true;
    if (stronger_evidence(pb.point_log_p, pb.point_statistic, pa.point_log_p, pa.point_statistic)) return false;
    return pa.id < pb.id;
  });
  return out;
}

void add_statistics_warnings(FitResult& r, const FitOptions& o) {
  if (r.dof <= 0) {
    r.warnings.push_back("no redundancy (dof = " + std::to_string(r.dof) +
                         "): σ0, the global test and the point tests are undefined; the residuals are zero by "
                         "construction and prove nothing");
  } else if (r.dof <= 5) {
    r.warnings.push_back("low redundancy (dof = " + std::to_string(r.dof) +
                         "): the global test and the w-tests have little power");
  }
  const auto& g = r.global_test;
  const std::size_t removed = static_cast<std::size_t>(
      std::count_if(r.points.begin(), r.points.end(), [](const PointResult& p) { return p.outlier; }));
  int k = 0;  // the point tests' degrees of freedom (3 for a 3-D mark)
  for (const auto& p : r.points) k = std::max(k, p.point_dof);
  std::string chance;
  if (removed > 0 && k > 0 && o.data_snooping) {
    // A mark of pure noise fails its χ²(k) point test with probability
    // alpha_point; removing every mark above the critical value c takes away
    // the share P(χ²(k+2) > c) of the expected sum of squares (the identity
    // E[X·1(X > c)] = k·P(χ²(k+2) > c) for X ~ χ²(k)).
    const double c = chi_squared_quantile(k, 1.0 - o.alpha_point);
    const double share = chi_squared_upper_tail(k + 2, c);
    const double sigma0_after = std::sqrt((1.0 - share) / (1.0 - o.alpha_point));
    chance = "data snooping removed " + std::to_string(removed) + " of " + std::to_string(r.points.size()) +
             " marks; at alpha_point = " + fmt(o.alpha_point) + " about " +
             fmt(o.alpha_point * static_cast<double>(r.points.size()), 3) +
             " of them fail by chance alone with no blunder at all, and removing those lowers σ0 to about " +
             fmt(sigma0_after, 4) + " of its true value";
    r.warnings.push_back(chance);
  }
  // Flagged marks: failing and kept (the default).
  std::size_t flagged = 0, ranked = 0, explained = 0;
  const PointResult* first = nullptr;
  for (const auto& p : r.points) {
    if (p.status(o.alpha_point) != TestStatus::flagged) continue;
    ++flagged;
    ranked += p.snooping_rank > 0 ? 1u : 0u;
    explained += p.passes_after_rank > 0 ? 1u : 0u;
    if (p.snooping_rank > 0 && (!first || p.snooping_rank < first->snooping_rank)) first = &p;
  }
  if (flagged > 0) {
    r.warnings.push_back(std::to_string(flagged) + " of " + std::to_string(r.points.size()) + " marks fail their point test at alpha_point = " +
                         fmt(o.alpha_point) + " and are flagged, none removed" +
                         (first ? "; data snooping would remove " + std::to_string(ranked) + " (" + first->id +
                                      " first; --remove-outliers removes them in the order of their snooping rank)"
                                : std::string()) +
                         (explained > 0 ? "; " + std::to_string(explained) + " pass once those before them are removed" : std::string()) +
                         "; about " + fmt(o.alpha_point * static_cast<double>(r.points.size()), 3) +
                         " of the marks fail by chance alone with no blunder at all");
  }
  if (g.applicable && !g.passed) {
    r.warnings.push_back(std::string("global test ") +
                         (g.failed_high() ? "FAILED high: residuals are larger than the a-priori sigmas allow"
                                                         : "low: residuals are smaller than the a-priori sigmas suggest "
                                                           "(sigmas too pessimistic?)") +
                         " (σ0 = " + fmt(r.sigma0.value_or(0.0), 4) + ")" +
                         (!chance.empty() && g.statistic < g.critical_lower
                              ? "; with this many degrees of freedom the chance removals alone can explain it (see "
                                "the data snooping warning)"
                              : ""));
  }
}

}  // namespace geoanchor::solver
