// The Helmert fit's least squares (helmert_reduced.hpp).

#include "helmert_reduced.hpp"

#include <ceres/ceres.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

#include "fit_common.hpp"

namespace geoanchor::solver {

using geodesy::RotationModel;

ParameterScales parameter_scale(const std::vector<MarkObservation>& obs) {
  double l2 = 0.0, d2 = 0.0;
  for (const auto& o : obs) {
    l2 += o.x.squaredNorm();
    d2 += o.dt * o.dt;
  }
  ParameterScales s;
  s.l = std::max(1.0, std::sqrt(l2 / static_cast<double>(obs.size())));
  s.d = std::max(1.0, std::sqrt(d2 / static_cast<double>(obs.size())));
  const double l = s.l, d = s.d;
  s.param = {1, 1, 1, l, l, l, l, d, d, d, l * d, l * d, l * d, l * d};  // NOLINT
  return s;
}

namespace {

// The normal equations reduced to sufficient statistics. Each whitened
// residual W(y − t − M x) is linear in z = (t', ṫ', M0 − I, M1, M2), where
// M(Δt) = (1 + ds(Δt)) R(r(Δt)) = M0 + M1 Δt + M2 Δt² (exact for the small-
// angle model; for the exact model the omitted third-order term is
// (ṙ Δt)³ ~ 1e-21). So Σ‖r_i‖² = ‖U (ẑ(θ) − ẑ*)‖² + const with Ĥ = UᵀU.
// Ceres solves that 12- (or 33-) residual problem, which has the very same
// minimiser and the very same JᵀJ as the 3n-residual one.
template <int K>  // basis functions per point: 4 (t, x) or 11 (with epochs)
struct Reduced {
  static constexpr int kDim = 3 * K;
  // A square root of Ĥ over its non-null directions: Ĥ = Uᵀ U with U of
  // rank × kDim rows. z itself may be under-determined (one epoch with
  // velocities, or exactly two epochs, fix only combinations of M0, M1, M2);
  // the 14 parameters behind it need not be, and Ceres judges those.
  Eigen::Matrix<double, Eigen::Dynamic, kDim> u;
  Eigen::Matrix<double, kDim, 1> z_star;  // a solution of Ĥ z = ĝ
};

template <int K>
std::array<double, static_cast<std::size_t>(K)> basis(const MarkObservation& o, const ParameterScales& sc) {
  std::array<double, static_cast<std::size_t>(K)> phi{};
  const Eigen::Vector3d x = o.x / sc.l;
  if constexpr (K == 4) {
    phi = {1.0, x(0), x(1), x(2)};
  } else {
    const double t = o.dt / sc.d;
    phi = {1.0, t, x(0), x(1), x(2), t * x(0), t * x(1), t * x(2), t * t * x(0), t * t * x(1), t * t * x(2)};
  }
  return phi;
}

template <int K>
Reduced<K> reduce(const std::vector<MarkObservation>& obs, const std::vector<MarkVelocity>& velocities,
                  const ParameterScales& sc) {
  constexpr int kDim = 3 * K;
  Eigen::Matrix<double, kDim, kDim> h = Eigen::Matrix<double, kDim, kDim>::Zero();
  Eigen::Matrix<double, kDim, 1> g = Eigen::Matrix<double, kDim, 1>::Zero();
  for (const MarkObservation& o : obs) {
    const Eigen::Matrix3d p = o.w.transpose() * o.w;
    const Eigen::Vector3d py = p * (o.y - o.x);  // target of (M − I) x: the coordinate differences
    const auto phi = basis<K>(o, sc);
    for (int a = 0; a < K; ++a) {
      g.template segment<3>(3 * a) += phi[static_cast<std::size_t>(a)] * py;
      for (int b = a; b < K; ++b) {
        h.template block<3, 3>(3 * a, 3 * b) += (phi[static_cast<std::size_t>(a)] * phi[static_cast<std::size_t>(b)]) * p;
      }
    }
  }
  if constexpr (K == 11) {
    // Velocity rows: ẏ − ẋ = ṫ' + (M1 + 2 M2 Δt) x + ((M0 − I) + M1 Δt + M2 Δt²) ẋ.
    for (const MarkVelocity& ov : velocities) {
      const MarkObservation& o = obs[ov.k];
      const Eigen::Matrix3d p = ov.wv.transpose() * ov.wv;
      const Eigen::Vector3d py = p * (ov.ydot - ov.xdot);
      const double t = o.dt, l = sc.l, d = sc.d;
      std::array<double, 11> psi{};
      psi[1] = 1.0 / d;
      for (int c = 0; c < 3; ++c) {
        psi[static_cast<std::size_t>(2 + c)] = ov.xdot(c) / l;
        psi[static_cast<std::size_t>(5 + c)] = (o.x(c) + t * ov.xdot(c)) / (l * d);
        psi[static_cast<std::size_t>(8 + c)] = (2.0 * t * o.x(c) + t * t * ov.xdot(c)) / (l * d * d);
      }
      for (int a = 0; a < K; ++a) {
        g.template segment<3>(3 * a) += psi[static_cast<std::size_t>(a)] * py;
        for (int b = a; b < K; ++b) {
          h.template block<3, 3>(3 * a, 3 * b) += (psi[static_cast<std::size_t>(a)] * psi[static_cast<std::size_t>(b)]) * p;
        }
      }
    }
  }
  for (int a = 0; a < K; ++a) {
    for (int b = 0; b < a; ++b) h.template block<3, 3>(3 * a, 3 * b) = h.template block<3, 3>(3 * b, 3 * a).transpose();
  }
  Reduced<K> r;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, kDim, kDim>> eig(h);
  const auto& ev = eig.eigenvalues();
  const double floor = 1e-13 * ev.maxCoeff();
  int rank = 0;
  for (int i = 0; i < kDim; ++i) rank += ev(i) > floor ? 1 : 0;
  if (rank == 0) {
    reject("E_FIT_COVARIANCE", "the normal equations are empty: no observation constrains the transform");
  }
  r.u.resize(rank, kDim);
  r.z_star.setZero();
  int row = 0;
  for (int i = 0; i < kDim; ++i) {
    if (!(ev(i) > floor)) continue;
    const auto v = eig.eigenvectors().col(i);
    r.u.row(row++) = std::sqrt(ev(i)) * v.transpose();
    r.z_star += (v.dot(g) / ev(i)) * v;
  }
  return r;
}

// ẑ(θ) for the scaled parameter blocks, as Ceres sees them.
template <int K>
struct ReducedCost {
  const Reduced<K>* reduced;
  ParameterScales scales;
  RotationModel model;

  template <typename T>
  bool operator()(T const* const* p, T* residuals) const {
    constexpr bool td = K == 11;
    const auto& sp = scales.param;
    T t[3], r[3], ds, dt[3], dr[3], dds;
    for (int k = 0; k < 3; ++k) {
      t[k] = p[0][k] / sp[static_cast<std::size_t>(k)];
      r[k] = p[1][k] / sp[static_cast<std::size_t>(3 + k)];
    }
    ds = p[2][0] / sp[6];
    if constexpr (td) {
      for (int k = 0; k < 3; ++k) {
        dt[k] = p[3][k] / sp[static_cast<std::size_t>(7 + k)];
        dr[k] = p[4][k] / sp[static_cast<std::size_t>(10 + k)];
      }
      dds = p[5][0] / sp[13];
    }
    const Eigen::Matrix<T, 3, 3> rot = rotation_pv(r, model);
    Eigen::Matrix<T, 3, 3> m0 = (T(1.0) + ds) * rot - Eigen::Matrix<T, 3, 3>::Identity();
    Eigen::Matrix<T, Reduced<K>::kDim, 1> z;
    const T l(scales.l), d(scales.d);
    for (int k = 0; k < 3; ++k) z(k) = t[k];
    if constexpr (!td) {
      for (int c = 0; c < 3; ++c) z.template segment<3>(3 + 3 * c) = l * m0.col(c);
    } else {
      const Eigen::Matrix<T, 3, 3> rdot = rotation_pv_rate(r, dr, model);
      const Eigen::Matrix<T, 3, 3> racc = rotation_pv_acceleration(r, dr, model);
      const Eigen::Matrix<T, 3, 3> m1 = dds * rot + (T(1.0) + ds) * rdot;
      const Eigen::Matrix<T, 3, 3> m2 = dds * rdot + (T(0.5) * (T(1.0) + ds)) * racc;
      for (int k = 0; k < 3; ++k) z(3 + k) = d * dt[k];
      for (int c = 0; c < 3; ++c) {
        z.template segment<3>(6 + 3 * c) = l * m0.col(c);
        z.template segment<3>(15 + 3 * c) = (l * d) * m1.col(c);
        z.template segment<3>(24 + 3 * c) = (l * d * d) * m2.col(c);
      }
    }
    const Eigen::Matrix<T, Reduced<K>::kDim, 1> diff = z - reduced->z_star.template cast<T>();
    Eigen::Map<Eigen::Matrix<T, Eigen::Dynamic, 1>> out(residuals, reduced->u.rows());
    out = reduced->u.template cast<T>() * diff;
    return true;
  }
};

template <int K>
HelmertSolution solve_reduced(const std::vector<MarkObservation>& obs, const std::vector<MarkVelocity>& velocities,
                       const FitOptions& o) {
  constexpr bool td = K == 11;
  HelmertSolution sol;
  const ParameterScales scales = parameter_scale(obs);
  const Reduced<K> reduced = reduce<K>(obs, velocities, scales);
  std::array<double, kMaxParams> scaled{};  // what Ceres sees
  double* t = scaled.data();
  double* r = t + 3;
  double* s = t + 6;
  double* dt = t + 7;
  double* dr = t + 10;
  double* ds = t + 13;
  ceres::Problem problem;
  auto* cost = new ceres::DynamicAutoDiffCostFunction<ReducedCost<K>, 8>(new ReducedCost<K>{&reduced, scales, o.rotation_model});
  for (int size : td ? std::vector<int>{3, 3, 1, 3, 3, 1} : std::vector<int>{3, 3, 1}) cost->AddParameterBlock(size);
  cost->SetNumResiduals(static_cast<int>(reduced.u.rows()));
  if constexpr (td) {
    problem.AddResidualBlock(cost, nullptr, {t, r, s, dt, dr, ds});
  } else {
    problem.AddResidualBlock(cost, nullptr, {t, r, s});
  }
  std::vector<const double*> blocks = {t};
  sol.estimated = {0, 1, 2};
  if (has_rotation(o.model)) {
    blocks.push_back(r);
    sol.estimated.insert(sol.estimated.end(), {3, 4, 5});
  } else {
    problem.SetParameterBlockConstant(r);
  }
  if (has_scale(o.model)) {
    blocks.push_back(s);
    sol.estimated.push_back(6);
  } else {
    problem.SetParameterBlockConstant(s);
  }
  if (td) {
    blocks.insert(blocks.end(), {dt, dr, ds});
    for (int k = 7; k < 14; ++k) sol.estimated.push_back(k);
  }

  const ceres::Solver::Summary summary = solve_tightly(problem, ceres::DENSE_QR, o.max_solver_iterations);
  sol.iterations = static_cast<int>(summary.iterations.size());
  sol.report = summary.BriefReport();
  const int u = static_cast<int>(sol.estimated.size());
  const Eigen::MatrixXd c = covariance_or_reject(problem, blocks, u);
  sol.cov_scaled = c;
  sol.cov_centred = c;
  for (int a = 0; a < u; ++a) {
    for (int b = 0; b < u; ++b) {
      sol.cov_centred(a, b) /= scales.param[static_cast<std::size_t>(sol.estimated[static_cast<std::size_t>(a)])] *
                               scales.param[static_cast<std::size_t>(sol.estimated[static_cast<std::size_t>(b)])];
    }
  }
  for (int k = 0; k < kMaxParams; ++k) {
    sol.theta[static_cast<std::size_t>(k)] = scaled[static_cast<std::size_t>(k)] / scales.param[static_cast<std::size_t>(k)];
  }
  return sol;
}

}  // namespace

HelmertSolution solve_helmert(const std::vector<MarkObservation>& obs, const std::vector<MarkVelocity>& velocities,
                              const FitOptions& o, bool td) {
  return td ? solve_reduced<11>(obs, velocities, o) : solve_reduced<4>(obs, {}, o);
}

}  // namespace geoanchor::solver
