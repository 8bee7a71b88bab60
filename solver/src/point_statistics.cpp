#include "point_statistics.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "fit_common.hpp"
#include "statistics.hpp"

namespace geoanchor::solver {
namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

ObservationTest test_observation(const Eigen::VectorXd& v, const Eigen::MatrixXd& w, const Eigen::MatrixXd& q,
                                 const Eigen::MatrixXd& axes, bool in_fit, double sigma_scale, double lambda0) {
  ObservationTest t;
  const Eigen::Index k = v.size();
  const Eigen::VectorXd vw = w * v;
  // The observation test over the redundant directions of Q (all of them
  // unless the observation alone determines some unknown).
  const Eigen::LLT<Eigen::MatrixXd> llt(q);
  if (llt.info() == Eigen::Success && llt.matrixLLT().diagonal().minCoeff() > 1e-5) {
    t.statistic = vw.dot(llt.solve(vw));
    t.dof = static_cast<int>(k);
  } else {
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> qe(q);
    for (Eigen::Index e = 0; e < k; ++e) {
      if (qe.eigenvalues()(e) > 1e-9) {
        const double proj = qe.eigenvectors().col(e).dot(vw);
        t.statistic += proj * proj / qe.eigenvalues()(e);
        ++t.dof;
      }
    }
  }
  t.statistic /= sigma_scale * sigma_scale;
  t.p_value = t.dof > 0 ? chi_squared_upper_tail(t.dof, t.statistic) : 1.0;

  // Redundancy numbers: the diagonal of R = Q_v P (Q_v the residuals'
  // cofactor, P = C⁻¹) along each axis; in whitened terms R = W⁻¹ Q W, whose
  // trace over all observations is the degrees of freedom.
  const Eigen::MatrixXd r = w.partialPivLu().solve(Eigen::MatrixXd(q * w));
  // w-tests (Baarda) for a blunder along each axis.
  const Eigen::Index n_axes = axes.rows();
  t.w = Eigen::VectorXd::Zero(n_axes);
  t.redundancy = Eigen::VectorXd::Zero(n_axes);
  t.mdb = Eigen::VectorXd::Constant(n_axes, in_fit ? 0.0 : kNaN);  // outside the fit: no detectability
  for (Eigen::Index axis = 0; axis < n_axes; ++axis) {
    const Eigen::VectorXd b = w * axes.row(axis).transpose();  // blunder direction, whitened
    const double qb = b.dot(q * b);
    if (!(qb > 1e-12 * b.squaredNorm())) {  // no redundancy along this axis: the blunder is invisible
      t.w(axis) = kNaN;
      if (in_fit) t.mdb(axis) = std::numeric_limits<double>::infinity();
      continue;
    }
    t.w(axis) = b.dot(vw) / std::sqrt(qb) / sigma_scale;  // τ-test when σ0 is estimated
    if (!(std::fabs(t.w(axis)) <= t.w_max)) t.w_max = std::fabs(t.w(axis));
    if (in_fit) {
      double along = 0.0;  // aᵀ R a
      for (Eigen::Index i = 0; i < k; ++i) {
        for (Eigen::Index j = 0; j < k; ++j) along += axes(axis, i) * r(i, j) * axes(axis, j);
      }
      t.redundancy(axis) = along;
      t.mdb(axis) = std::sqrt(lambda0) * sigma_scale / std::sqrt(qb);
    }
  }
  return t;
}

void test_point(const PointTestInput& in, double sigma_scale, double lambda0, PointResult& pr) {
  pr.residual_enu_m = in.enu * in.v_m;
  // C_v = W⁻¹ Q W⁻ᵀ (W whitens: Wᵀ W = C⁻¹), in E, N, U, scaled as σ is.
  const Eigen::Matrix3d w_inv = in.w.inverse();
  pr.residual_cov_enu_m2 = (sigma_scale * sigma_scale) * (in.enu * w_inv * in.q * w_inv.transpose() * in.enu.transpose());
  const ObservationTest t = test_observation(in.v_m, in.w, in.q, in.enu, in.in_fit, sigma_scale, lambda0);
  pr.point_statistic = t.statistic;
  pr.point_dof = t.dof;
  pr.point_p_value = t.p_value;
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

std::vector<std::size_t> snoop_selection(const std::vector<SnoopCandidate>& failing,
                                         const std::function<bool(std::size_t)>& may_take) {
  std::vector<std::size_t> take;
  double leverage = 0.0;
  for (std::size_t k = 0; k < failing.size(); ++k) {
    if (!take.empty() && (leverage + failing[k].leverage > kSnoopLeverageBudget || !may_take(take.size() + 1))) break;
    leverage += failing[k].leverage;
    take.push_back(k);
  }
  return take;
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
    for (Eigen::Index b = 0; b < cov.cols(); ++b) c(a, b) = cov(a, b) / std::sqrt(cov(a, a) * cov(b, b));
  }
  return c;
}

std::size_t max_snooped(std::size_t n, const FitOptions& o) {
  return std::max<std::size_t>(1, static_cast<std::size_t>(std::floor(o.max_outlier_share * static_cast<double>(n))));
}

SnoopStep snoop(FitResult& r, std::vector<std::size_t>& active, const FitOptions& o, int u, int min_points) {
  if (!o.data_snooping || r.dof <= 0) return SnoopStep::none;
  // The failing points, worst (smallest p-value) first.
  std::vector<std::size_t> failing;  // positions in `active`
  for (std::size_t k = 0; k < active.size(); ++k) {
    const auto& p = r.points[active[k]];
    if (p.point_dof > 0 && p.point_p_value < o.alpha_point) failing.push_back(k);
  }
  if (failing.empty()) return SnoopStep::none;
  std::stable_sort(failing.begin(), failing.end(), [&](std::size_t a, std::size_t b) {
    return r.points[active[a]].point_p_value < r.points[active[b]].point_p_value;
  });
  const auto why_of = [&](const PointResult& pr) {
    return "point test " + fmt(pr.point_statistic, 4) + " (χ²(" + std::to_string(pr.point_dof) + "), p = " +
           fmt(pr.point_p_value, 2) + " < " + fmt(o.alpha_point) + "); max |w| " + fmt(pr.w_max) + "; residual E/N/U " +
           fmt(pr.residual_enu_m.x()) + ", " + fmt(pr.residual_enu_m.y()) + ", " + fmt(pr.residual_enu_m.z()) + " m";
  };
  const PointResult& worst = r.points[active[failing.front()]];
  const int n = static_cast<int>(active.size());
  if (n - 1 < min_points || 3 * (n - 1) - u <= 0) {
    r.warnings.push_back("point " + worst.id + " fails the " + why_of(worst) + ", but too few points remain to remove it");
    return SnoopStep::stopped;
  }
  const std::size_t marks = r.points.size();
  const std::size_t removed = static_cast<std::size_t>(std::count_if(r.points.begin(), r.points.end(),
                                                                     [](const PointResult& p) { return p.outlier; }));
  const std::size_t limit = max_snooped(marks, o);
  if (removed + 1 > limit) {
    const auto& g = r.global_test;
    std::string global;
    if (g.applicable) {
      global = std::string("; the global test ") + (g.passed ? "passes" : g.failed_high() ? "fails high" : "fails low") +
               " (" + fmt(g.statistic, 4) + " vs [" + fmt(g.critical_lower, 4) + ", " + fmt(g.critical_upper, 4) +
               "], σ0 = " + fmt(r.sigma0.value_or(0.0), 4) + ")";
    }
    r.refused_because = "data snooping stopped after removing " + std::to_string(removed) + " of " + std::to_string(marks) +
                        " marks (the limit is " + fmt(100.0 * o.max_outlier_share, 3) + " %, --max-outlier-share): " +
                        worst.id + " still fails its " + why_of(worst) + global + "; " + std::to_string(failing.size()) +
                        " marks fail now. So many failing marks mean the data or the model is wrong (frames, units, "
                        "height types, quantized coordinates), not a few blunders";
    r.warnings.push_back(r.refused_because);
    return SnoopStep::stopped;
  }
  // The worst point goes; with it, further failing points while their
  // leverages (1 − mean redundancy) add up to at most kSnoopLeverageBudget:
  // then removing them together moves the parameters, and the others'
  // tests, as removing them one at a time would, to within a few per cent.
  // In a small network one point's leverage exceeds the budget, and this is
  // Baarda's one-at-a-time data snooping; in a network of 10⁵ marks the
  // chance failures at alpha_point go in a few passes instead of one each.
  std::vector<SnoopCandidate> candidates;
  for (std::size_t k : failing) {
    const PointResult& p = r.points[active[k]];
    candidates.push_back({p.point_p_value, 1.0 - p.redundancy_enu.sum() / 3.0});
  }
  std::vector<std::size_t> take = snoop_selection(candidates, [&](std::size_t count) {
    const int left = n - static_cast<int>(count);
    return removed + count <= limit && left >= min_points && 3 * left - u > 0;
  });
  for (std::size_t& k : take) k = failing[k];
  for (std::size_t k : take) {
    PointResult& pr = r.points[active[k]];
    pr.outlier = true;
    pr.used = false;
    pr.removed_because = "data snooping: " + why_of(pr);
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
