// The weighted Helmert fit's passes (helmert_weighted_fit.hpp): the marks
// checked, observed and weighted, the solution, residuals, tests and
// variance components.

#include "helmert_weighted_fit.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

#include "fit_common.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "statistics.hpp"

namespace geoanchor::solver {

using geodesy::DecimalYear;

namespace {

constexpr double kCoincidentSpread_m = 1.0; // RELIABILITY #4
constexpr double kCollinearRatio = 1e-6;    // second/first singular value of the source spread

// The whitened residual's cofactor I ∓ A N⁻¹ Aᵀ: − in the fit, + for a
// point tested against it (a prediction).
Eigen::Matrix3d cofactor(const PointJacobian& a, const NormalMatrix& n_inv, double sign) {
  return Eigen::Matrix3d(Eigen::Matrix3d::Identity() + sign * (a * n_inv * a.transpose()));
}

}  // namespace

WeightedFit::WeightedFit(const geodesy::ControlSet& control_set, const FitOptions& given)
    : control(control_set),
      options(given),
      o(given),
      td(given.model == FitModel::helmert14),
      axes(control_set.points.size()),
      have_axes(control_set.points.size(), false),
      geocentric(geodesy::Ellipsoid::wgs84()) {
  if (has_rotation(o.model) && !o.convention) {
    throw Error(ErrorKind::usage, "E_CONVENTION_MISSING",
                "--convention: required for model " + std::string(to_string(o.model)) +
                    ": position_vector or coordinate_frame (the sign of every rotation depends on it; never assumed)");
  }
  result.model = o.model;
  result.convention = o.convention.value_or(Convention::position_vector);
  result.rotation_model = o.rotation_model;
  note_missing_sigmas(result, o, control);
  active = init_points(result, control, o);

  levels = point_test_levels(o);
  result.w_critical = levels.w_critical;

  if (o.vce && !control.has_a_priori_sigmas) {
    throw Error(ErrorKind::usage, "E_OPTION", "--vce: needs a-priori sigmas in both frames (sigma_src_m, sigma_dst_m or covariances)");
  }
}

const Eigen::Matrix3d& WeightedFit::local_axes(std::size_t i) {
  if (!have_axes[i]) {
    const geodesy::GeodeticPosition at = geocentric.geodetic_from_ecef(control.points[i].target);
    axes[i] = geodesy::enu_from_ecef_rotation(at.lat, at.lon);
    have_axes[i] = true;
  }
  return axes[i];
}

Eigen::Matrix3d WeightedFit::whitening(const geodesy::ControlPoint& p, const Eigen::Matrix3d& j) const {
  Eigen::Matrix3d c = f_dst * p.target_cov_m2 + f_src * (j * p.source_cov_m2 * j.transpose());
  if (!control.has_a_priori_sigmas) c = Eigen::Matrix3d::Identity();
  const Eigen::LLT<Eigen::Matrix3d> llt(c);
  if (llt.info() != Eigen::Success) {
    throw Error(ErrorKind::input, "E_SIGMA",
                control.source_name + ":" + std::to_string(p.line) + ": id=" + p.id +
                    ": combined covariance is not positive definite (zero sigmas in both frames?)");
  }
  return Eigen::Matrix3d(llt.matrixL().solve(Eigen::Matrix3d::Identity()));  // L⁻¹: (L⁻¹)ᵀ L⁻¹ = C⁻¹
}

Eigen::Matrix3d WeightedFit::linear_part(const std::array<double, kMaxParams>& th, double dt) const {
  double r[3];
  double s = th[6];
  for (int k = 0; k < 3; ++k) r[k] = th[static_cast<std::size_t>(3 + k)] + (td ? dt * th[static_cast<std::size_t>(10 + k)] : 0.0);
  if (td) s += dt * th[13];
  return Eigen::Matrix3d((1.0 + s) * rotation_pv(r, o.rotation_model));
}

PointJacobian WeightedFit::design(const FitPass& current, const MarkObservation& ob) const {
  const HelmertSolution& sol = current.sol;
  Eigen::Vector3d pred;
  Eigen::Matrix<double, 3, kMaxParams> jfull;
  predict_mark(ob, sol.theta.data(), o.rotation_model, td, pred, &jfull, &current.final_rotation);
  PointJacobian a(3, current.u);
  for (int c = 0; c < current.u; ++c) a.col(c) = ob.w * jfull.col(sol.estimated[static_cast<std::size_t>(c)]);
  return a;
}

// Refuses an ill-posed problem: too few marks, helmert14 without epochs or
// rates to see, sources that coincide or lie on one line; the centroids.
void WeightedFit::check_marks(FitPass& current) {
  current.n = static_cast<int>(active.size());
  const int n = current.n;
  Eigen::Vector3d& cx = current.cx;
  Eigen::Vector3d& cy = current.cy;
  // --- refuse ill-posed problems -------------------------------------
  if (n < min_points(o.model)) {
    reject("E_FIT_TOO_FEW_POINTS", "model " + std::string(to_string(o.model)) + ": need >= " +
                                       std::to_string(min_points(o.model)) + " non-collinear points, got " +
                                       std::to_string(n));
  }
  for (std::size_t i : active) {
    cx += control.points[i].source.m;
    cy += control.points[i].target.m;
  }
  cx /= n;
  cy /= n;
  if (td) check_epochs(current);
  if (has_rotation(o.model)) check_spread(current);
}

// helmert14: every mark has an epoch, and the epochs (or velocities) show
// the rates; the reference epoch, when not given, is the marks' mean.
void WeightedFit::check_epochs(const FitPass& current) {
  const int n = current.n;
  const std::string unit = td ? "point-epochs" : "points";
  double lo = 1e300, hi = -1e300, sum = 0.0;
  for (std::size_t i : active) {
    const auto& p = control.points[i];
    if (!p.epoch) {
      throw Error(ErrorKind::input, "E_EPOCH_MISSING",
                  control.source_name + ":" + std::to_string(p.line) + ": id=" + p.id +
                      ": no epoch; helmert14 relates each point's coordinates at its own epoch (epoch column)");
    }
    lo = std::min(lo, p.epoch->year);
    hi = std::max(hi, p.epoch->year);
    sum += p.epoch->year;
  }
  const bool velocities = std::any_of(active.begin(), active.end(), [&](std::size_t i) {
    return control.points[i].velocities != nullptr;
  });
  if (!(hi > lo) && !velocities) {
    reject("E_FIT_ONE_EPOCH", "model helmert14: all " + std::to_string(n) + " " + unit + " are at epoch " +
                                  format_shortest(lo) +
                                  "; rates need observations at >= 2 epochs, or velocities in both frames (use "
                                  "helmert7 for one epoch)");
  }
  if (!o.reference_epoch) o.reference_epoch = DecimalYear{sum / n};
  const auto with_velocity = std::count_if(active.begin(), active.end(), [&](std::size_t i) {
    return control.points[i].velocities != nullptr;
  });
  if (3 * (n + with_velocity) < 14) {
    reject("E_FIT_TOO_FEW_POINTS", "model helmert14: 14 parameters need >= 14 observations (5 point-epochs), got " +
                                       std::to_string(3 * (n + with_velocity)));
  }
}

// Rotations need sources spread over more than a line.
void WeightedFit::check_spread(const FitPass& current) const {
  const int n = current.n;
  const Eigen::Vector3d& cx = current.cx;
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (std::size_t i : active) {
    const Eigen::Vector3d d = control.points[i].source.m - cx;
    scatter += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
  const double s1 = std::sqrt(std::max(eig.eigenvalues()(2), 0.0) / n);
  const double s2 = std::sqrt(std::max(eig.eigenvalues()(1), 0.0) / n);
  if (s1 < kCoincidentSpread_m) {
    reject("E_FIT_COINCIDENT", "the " + std::to_string(n) + " source points lie within " + fmt(s1) +
                                   " m of each other (RMS spread): only a translation is observable; use --model "
                                   "translation3 or add points at least " + fmt(kCoincidentSpread_m) + " m apart");
  }
  if (s2 / s1 < kCollinearRatio) {
    const Eigen::Vector3d axis = eig.eigenvectors().col(2);
    const geodesy::LocalTangentPlane plane(geodesy::LocalOrigin{
        geodesy::geodetic_from_ecef(geodesy::Ellipsoid::wgs84(), geodesy::EcefPosition(cx)), geodesy::Ellipsoid::wgs84()});
    const Eigen::Vector3d enu = plane.enu_from_ecef_rotation() * axis;
    const double azimuth = std::fmod(std::atan2(enu.x(), enu.y()) * 180.0 / M_PI + 360.0, 180.0);
    reject("E_FIT_COLLINEAR", "the source points are collinear (singular-value ratio " + fmt(s2 / s1) +
                                  " < " + fmt(kCollinearRatio) +
                                  "): the rotation about their line (azimuth " + fmt(azimuth, 4) +
                                  "°) is not observable; add a point off the line");
  }
}

// --- observations ----------------------------------------------------
void WeightedFit::observe(FitPass& current) const {
  const Eigen::Vector3d& cx = current.cx;
  const Eigen::Vector3d& cy = current.cy;
  std::vector<MarkObservation>& obs = current.obs;
  std::vector<MarkVelocity>& velocities = current.velocities;
  obs.reserve(active.size());
  for (std::size_t i : active) {
    const auto& p = control.points[i];
    MarkObservation ob;
    ob.x = p.source.m - cx;
    ob.y = p.target.m - cy;
    ob.w = whitening(p, Eigen::Matrix3d::Identity());
    ob.dt = td ? p.epoch->year - o.reference_epoch->year : 0.0;
    if (td && p.velocities) {
      const Eigen::LLT<Eigen::Matrix3d> vllt(p.velocities->source_cov + p.velocities->target_cov);
      if (vllt.info() == Eigen::Success) {
        MarkVelocity& ov = velocities.emplace_back();
        ov.k = obs.size();
        ov.xdot = p.velocities->source_m_per_year;
        ov.ydot = p.velocities->target_m_per_year;
        ov.wv = vllt.matrixL().solve(Eigen::Matrix3d::Identity());
      }
    }
    obs.push_back(ob);
  }
}

// The solution, re-weighted with the estimate's J until it settles.
void WeightedFit::solve_weighted(FitPass& current) const {
  std::vector<MarkObservation>& obs = current.obs;
  const std::vector<MarkVelocity>& velocities = current.velocities;
  HelmertSolution& sol = current.sol;
  sol = solve_helmert(obs, velocities, o, td);
  // Re-weight with J from the estimate until it settles (the source
  // covariance turned and scaled as the transform turns and scales it).
  constexpr int kMaxWeightPasses = 5;
  constexpr double kWeightChange = 1e-12;  // relative change of J between passes
  if (control.has_a_priori_sigmas) {
    // J depends on a mark's epoch alone (helmert14): one for every mark
    // in the other models.
    std::vector<Eigen::Matrix3d> used(td ? obs.size() : 1, Eigen::Matrix3d::Identity());
    for (int pass = 0; pass < kMaxWeightPasses; ++pass) {
      double change = 0.0;
      for (std::size_t k = 0; k < used.size(); ++k) {
        const Eigen::Matrix3d j = linear_part(sol.theta, obs[k].dt);
        const double d = (j - used[k]).cwiseAbs().maxCoeff();
        if (!(d <= change)) change = d;
        used[k] = j;
      }
      if (change <= kWeightChange) break;
      for (std::size_t k = 0; k < obs.size(); ++k) obs[k].w = whitening(control.points[active[k]], used[td ? k : 0]);
      sol = solve_helmert(obs, velocities, o, td);
    }
  }
  current.u = static_cast<int>(sol.estimated.size());
  current.dof = 3 * current.n - current.u;  // plus the velocity observations, below
}

void WeightedFit::residuals(FitPass& current) {
  const std::vector<MarkObservation>& obs = current.obs;
  const std::vector<MarkVelocity>& velocities = current.velocities;
  const HelmertSolution& sol = current.sol;
  std::vector<Eigen::Vector3d>& v = current.v;
  std::vector<Eigen::Vector3d>& vw = current.vw;
  int& dof = current.dof;
  // --- residuals from the geocentric parameters, whitened statistics ----
  // The reported residuals come from the very parameters that are written,
  // so that applying the file reproduces them.
  double omega = 0.0;
  v.resize(active.size());
  vw.resize(active.size());
  for (std::size_t k = 0; k < active.size(); ++k) {
    const auto& p = control.points[active[k]];
    const geodesy::EcefPosition pred = apply_fit(result, p.source, td ? p.epoch : std::nullopt);
    v[k] = p.target.m - pred.m;
    vw[k] = obs[k].w * v[k];
    omega += vw[k].squaredNorm();
  }
  // Velocity residuals (helmert14): from the centred parameters' M(Δt).
  int velocity_observations = 0;
  if (td) {
    const double* th = sol.theta.data();
    double r0[3] = {th[3], th[4], th[5]}, rd[3] = {th[10], th[11], th[12]};
    const Eigen::Matrix3d rot = rotation_pv(r0, o.rotation_model);
    const Eigen::Matrix3d rdot = rotation_pv_rate(r0, rd, o.rotation_model);
    const Eigen::Matrix3d racc = rotation_pv_acceleration(r0, rd, o.rotation_model);
    const Eigen::Matrix3d m0 = (1.0 + th[6]) * rot - Eigen::Matrix3d::Identity();
    const Eigen::Matrix3d m1 = th[13] * rot + (1.0 + th[6]) * rdot;
    const Eigen::Matrix3d m2 = th[13] * rdot + 0.5 * (1.0 + th[6]) * racc;
    const Eigen::Vector3d tdot(th[7], th[8], th[9]);
    for (const MarkVelocity& ov : velocities) {
      const MarkObservation& ob = obs[ov.k];
      const double t = ob.dt;
      const Eigen::Vector3d pred = tdot + (m1 + 2.0 * t * m2) * ob.x + (m0 + t * m1 + t * t * m2) * ov.xdot;
      omega += (ov.wv * (ov.ydot - ov.xdot - pred)).squaredNorm();
      ++velocity_observations;
    }
  }
  dof += 3 * velocity_observations;
  fill_global_test(result, omega, dof, o.alpha, control.has_a_priori_sigmas);
  current.tau = sigma_scale(result, o);
}

void WeightedFit::test_marks(FitPass& current) {
  const std::vector<MarkObservation>& obs = current.obs;
  const HelmertSolution& sol = current.sol;
  // Per point: w-tests along local E, N, U; redundancy; MDB.
  current.n_inv = sol.cov_centred;  // (ĀᵀĀ)⁻¹ over the estimated parameters
  current.final_rotation = rotation_and_derivatives(sol.theta.data() + 3, o.rotation_model);
  const NormalMatrix& n_inv = current.n_inv;
  std::vector<Eigen::Matrix3d>& qvs = current.qvs;
  qvs.resize(o.vce ? active.size() : 0);
  FitLinearization& lin = current.lin;
  lin.n_inv = n_inv;
  for (std::size_t k = 0; k < active.size(); ++k) {
    const PointJacobian a = design(current, obs[k]);
    const Eigen::Matrix3d qv = cofactor(a, n_inv, -1.0);
    if (o.vce) qvs[k] = qv;
    PointResult& pr = result.points[active[k]];
    pr.used = true;
    test_point(PointTestInput{current.v[k], obs[k].w, qv, local_axes(active[k]), true}, current.tau, levels.lambda0, pr);
    if (pr.point_dof > 0 && pr.point_p_value < o.alpha_point) lin.add(k, a, current.vw[k]);
  }
}

bool WeightedFit::next_variance_components(const FitPass& current) {
  const std::vector<MarkObservation>& obs = current.obs;
  const HelmertSolution& sol = current.sol;
  // --- variance components (--vce) -----------------------------------------
  // θ_k ← θ_k · (vᵀ P Q_k P v) / tr(P Q_k P Q_vv), Q_k the group's current
  // covariance (the source's as J C Jᵀ, as the weights hold it); with one
  // group this is θ ← θ σ̂0².
  double num_src = 0.0, num_dst = 0.0, den_src = 0.0, den_dst = 0.0;
  double s11 = 0.0, s12 = 0.0, s22 = 0.0;  // the VCE normal matrix: Σ tr(B_k B_l), B_k = Q_k P Q_vv P
  for (std::size_t k = 0; k < active.size(); ++k) {
    const auto& p = control.points[active[k]];
    const Eigen::Matrix3d pqp = obs[k].w.transpose() * current.qvs[k] * obs[k].w;
    const Eigen::Vector3d pv = obs[k].w.transpose() * current.vw[k];
    // The source group's covariance as the weights carry it: turned and
    // scaled by J of the estimate, as in whitening().
    const Eigen::Matrix3d j = linear_part(sol.theta, obs[k].dt);
    const Eigen::Matrix3d q_src = f_src * (j * p.source_cov_m2 * j.transpose()), q_dst = f_dst * p.target_cov_m2;
    num_src += pv.dot(q_src * pv);
    num_dst += pv.dot(q_dst * pv);
    den_src += (q_src * pqp).trace();
    den_dst += (q_dst * pqp).trace();
    const Eigen::Matrix3d b_src = q_src * pqp, b_dst = q_dst * pqp;
    s11 += (b_src * b_src).trace();
    s12 += (b_src * b_dst).trace();
    s22 += (b_dst * b_dst).trace();
  }
  // Source and target errors enter each residual the same way; they can
  // be told apart only where their covariances differ in pattern.
  const double rho = s12 / std::sqrt(s11 * s22);
  if (!(std::fabs(rho) < 0.99)) {
    reject("E_VCE_INSEPARABLE",
           "--vce: the source and target covariances have nearly the same pattern at every point (correlation of "
           "the two variance estimates " + fmt(rho, 5) +
               "), so only their sum is estimable: σ0² = " + fmt(result.sigma0.value_or(0.0) * result.sigma0.value_or(0.0), 4) +
               " already estimates it. Separate components need sigmas that differ between points or axes");
  }
  const double new_src = den_src > 0.0 ? f_src * num_src / den_src : f_src;
  const double new_dst = den_dst > 0.0 ? f_dst * num_dst / den_dst : f_dst;
  const bool converged = std::fabs(new_src - f_src) <= kVceTolerance * f_src && std::fabs(new_dst - f_dst) <= kVceTolerance * f_dst;
  f_src = new_src;
  f_dst = new_dst;
  result.variance_factors = std::make_pair(f_src, f_dst);
  if (!converged && ++vce_iterations < kMaxVceIterations) return true;
  if (!converged) result.warnings.push_back("variance components did not converge in " + std::to_string(kMaxVceIterations) + " iterations");
  return false;
}

void WeightedFit::test_marks_outside(const FitPass& current) {
  const Eigen::Vector3d& cx = current.cx;
  const Eigen::Vector3d& cy = current.cy;
  const HelmertSolution& sol = current.sol;
  // --- points outside the final fit: tested against it ---------------------
  // Their residuals come from the final parameters, and their tests are
  // prediction tests (Q = I + A N⁻¹ Aᵀ): a removed blunder shows at full size.
  std::vector<bool> in_fit(control.points.size(), false);
  for (std::size_t i : active) in_fit[i] = true;
  for (std::size_t i = 0; i < control.points.size(); ++i) {
    if (in_fit[i]) continue;
    const auto& p = control.points[i];
    if (td && !p.epoch) continue;
    MarkObservation ob;
    ob.x = p.source.m - cx;
    ob.y = p.target.m - cy;
    ob.dt = td ? p.epoch->year - o.reference_epoch->year : 0.0;
    ob.w = whitening(p, linear_part(sol.theta, ob.dt));
    const Eigen::Vector3d vi = p.target.m - apply_fit(result, p.source, td ? p.epoch : std::nullopt).m;
    const Eigen::Matrix3d q = cofactor(design(current, ob), current.n_inv, +1.0);
    test_point(PointTestInput{vi, ob.w, q, local_axes(i), false}, current.tau, levels.lambda0, result.points[i]);
  }
}

}  // namespace geoanchor::solver
