#include "geoanchor/solver/helmert_fit.hpp"

#include <ceres/ceres.h>
#include <ceres/jet.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <numeric>
#include <functional>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "enu_origin_fit.hpp"
#include "fit_common.hpp"
#include "point_statistics.hpp"
#include "statistics.hpp"

namespace geoanchor::solver {
namespace {

using geodesy::Angle;
using geodesy::ControlPoint;
using geodesy::ControlSet;
using geodesy::DecimalYear;
using geodesy::RotationModel;

constexpr double kArcsecPerRad = 180.0 / M_PI * 3600.0;
constexpr double kPpm = 1e6;
constexpr double kCoincidentSpread_m = 1.0; // RELIABILITY #4
constexpr double kCollinearRatio = 1e-6;    // second/first singular value of the source spread

// Parameter layout of the estimation vector θ' (centroid-referenced):
//   0-2 t' (m), 3-5 r (rad), 6 ds, 7-9 ṫ' (m/yr), 10-12 ṙ (rad/yr), 13 ḋs (1/yr).
constexpr int kMaxParams = 14;

// The three elementary coordinate-frame rotations R1(rx), R2(ry), R3(rz)
// and their first (D) and second (E) derivatives in their own angle.
template <typename T>
struct Elementary {
  Eigen::Matrix<T, 3, 3> r1, r2, r3, d1, d2, d3, e1, e2, e3;
  explicit Elementary(const T* r) {
    using std::cos;
    using std::sin;
    const T ca = cos(r[0]), sa = sin(r[0]), cb = cos(r[1]), sb = sin(r[1]), cg = cos(r[2]), sg = sin(r[2]);
    const T o(0.0), i(1.0);
    r1 << i, o, o, o, ca, sa, o, -sa, ca;
    r2 << cb, o, -sb, o, i, o, sb, o, cb;
    r3 << cg, sg, o, -sg, cg, o, o, o, i;
    d1 << o, o, o, o, -sa, ca, o, -ca, -sa;
    d2 << -sb, o, -cb, o, o, o, cb, o, -sb;
    d3 << -sg, cg, o, -cg, -sg, o, o, o, o;
    e1 << o, o, o, o, -ca, -sa, o, sa, -ca;
    e2 << -cb, o, sb, o, o, o, -sb, o, -cb;
    e3 << -cg, -sg, o, sg, -cg, o, o, o, o;
  }
};

// The position-vector rotation matrix for rotations r (radians), in either model.
template <typename T>
Eigen::Matrix<T, 3, 3> rotation_pv(const T* r, RotationModel model) {
  Eigen::Matrix<T, 3, 3> m;
  if (model == RotationModel::small_angle) {
    m << T(1.0), -r[2], r[1], r[2], T(1.0), -r[0], -r[1], r[0], T(1.0);
    return m;
  }
  const Elementary<T> x(r);
  return (x.r3 * x.r2 * x.r1).transpose();  // position vector: transpose of the coordinate-frame matrix
}

// Ṙ: the derivative of the position-vector matrix along the rotation rate ṙ.
template <typename T>
Eigen::Matrix<T, 3, 3> rotation_pv_rate(const T* r, const T* rdot, RotationModel model) {
  Eigen::Matrix<T, 3, 3> m;
  if (model == RotationModel::small_angle) {
    m << T(0.0), -rdot[2], rdot[1], rdot[2], T(0.0), -rdot[0], -rdot[1], rdot[0], T(0.0);
    return m;
  }
  const Elementary<T> x(r);
  const Eigen::Matrix<T, 3, 3> cf =
      rdot[2] * x.d3 * x.r2 * x.r1 + rdot[1] * x.r3 * x.d2 * x.r1 + rdot[0] * x.r3 * x.r2 * x.d1;
  return cf.transpose();
}

// R and its derivatives with respect to rx, ry, rz.
struct RotationWithDerivatives {
  Eigen::Matrix3d r;
  std::array<Eigen::Matrix3d, 3> d;
};

RotationWithDerivatives rotation_and_derivatives(const double* rot, RotationModel model) {
  using J = ceres::Jet<double, 3>;
  const J r[3] = {J(rot[0], 0), J(rot[1], 1), J(rot[2], 2)};
  const Eigen::Matrix<J, 3, 3> m = rotation_pv(r, model);
  RotationWithDerivatives out;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      out.r(i, j) = m(i, j).a;
      for (int k = 0; k < 3; ++k) out.d[static_cast<std::size_t>(k)](i, j) = m(i, j).v[k];
    }
  }
  return out;
}

// One observation equation, ready for the solver: centred coordinates, the
// whitening matrix and the epoch offset.
struct Observation {
  Eigen::Vector3d x;   // source − source centroid
  Eigen::Vector3d y;   // target − target centroid
  Eigen::Matrix3d w;   // W with Wᵀ W = C⁻¹
  double dt = 0.0;     // years from the reference epoch
};

// A mark's velocities (helmert14): ẏ − ẋ = ṫ' + Ṁ x + (M − I) ẋ observes the
// rates. Kept apart from the positions: most fits have none, and inside
// each observation they were half of its memory.
struct VelocityObservation {
  std::size_t k = 0;  // the mark's position observation
  Eigen::Vector3d xdot = Eigen::Vector3d::Zero(), ydot = Eigen::Vector3d::Zero();
  Eigen::Matrix3d wv = Eigen::Matrix3d::Identity();  // whitening of the velocity difference
};

// Predicted centred target and its Jacobian (3 × 14) for θ'. Without time
// dependence R is the same for every point: pass it as `fixed_rotation`.
void predict(const Observation& o, const double* theta, RotationModel model, bool time_dependent,
             Eigen::Vector3d& pred, Eigen::Matrix<double, 3, kMaxParams>* jac,
             const RotationWithDerivatives* fixed_rotation = nullptr) {
  double r[3], s = theta[6];
  Eigen::Vector3d t(theta[0], theta[1], theta[2]);
  for (int k = 0; k < 3; ++k) r[k] = theta[3 + k];
  if (time_dependent) {
    t += o.dt * Eigen::Vector3d(theta[7], theta[8], theta[9]);
    for (int k = 0; k < 3; ++k) r[k] += o.dt * theta[10 + k];
    s += o.dt * theta[13];
  }
  const RotationWithDerivatives rot =
      fixed_rotation && !time_dependent ? *fixed_rotation : rotation_and_derivatives(r, model);
  const Eigen::Vector3d rx = rot.r * o.x;
  pred = t + (1.0 + s) * rx;
  if (!jac) return;
  jac->setZero();
  jac->block<3, 3>(0, 0).setIdentity();
  for (int k = 0; k < 3; ++k) jac->col(3 + k) = (1.0 + s) * (rot.d[static_cast<std::size_t>(k)] * o.x);
  jac->col(6) = rx;
  if (time_dependent) {
    jac->block<3, 7>(0, 7) = o.dt * jac->block<3, 7>(0, 0);
  }
}

bool has_rotation(FitModel m) {
  return m != FitModel::translation3 && m != FitModel::enu_origin && m != FitModel::site_calibration;
}
bool has_scale(FitModel m) {
  return m == FitModel::helmert7 || m == FitModel::helmert14 || m == FitModel::molodensky_badekas;
}
int min_points(FitModel m) { return m == FitModel::translation3 ? 1 : 3; }

// Geocentric (position-vector) parameters from θ' (both in solver units:
// metres, radians, unitless, per year), templated for autodiff of the
// covariance propagation.
template <typename T>
void geocentric_from_centred(const T* tc, const Eigen::Vector3d& cx, const Eigen::Vector3d& cy, RotationModel model,
                             T* out) {
  for (int k = 0; k < kMaxParams; ++k) out[k] = tc[k];
  const Eigen::Matrix<T, 3, 3> r = rotation_pv(tc + 3, model);
  const Eigen::Matrix<T, 3, 1> cxt = cx.cast<T>();
  const Eigen::Matrix<T, 3, 1> rc = r * cxt;
  for (int k = 0; k < 3; ++k) out[k] = T(cy(k)) + tc[k] - (T(1.0) + tc[6]) * rc(k);
  // Rates: the time derivative of the above at the reference epoch,
  // d/dt [(1+s) R c] = ṡ R c + (1+s) Ṙ c with Ṙ the derivative of R along ṙ.
  const Eigen::Matrix<T, 3, 3> rdot = rotation_pv_rate(tc + 3, tc + 10, model);
  const Eigen::Matrix<T, 3, 1> rdc = rdot * cxt;
  for (int k = 0; k < 3; ++k) out[7 + k] = tc[7 + k] - (tc[13] * rc(k) + (T(1.0) + tc[6]) * rdc(k));
}

struct Solution {
  std::array<double, kMaxParams> theta{};  // centred, solver units
  Eigen::MatrixXd cov_centred;             // over `estimated` indices, a-priori σ0 = 1
  Eigen::MatrixXd cov_scaled;              // the same in the scaled units (every column metres at the RMS radius)
  std::vector<int> estimated;              // indices into θ
  int iterations = 0;
  std::string report;
};

// Parameters are solved in scaled units so that every Jacobian column has
// the size of a displacement in metres: rotations and scale times the
// network's RMS radius L, rates times the RMS epoch spread D as well.
// ceres::Covariance does no column scaling of its own, and unscaled
// radians-per-year columns would make a sound 14-parameter problem look
// rank-deficient.
struct Scales {
  double l = 1.0, d = 1.0;
  std::array<double, kMaxParams> param{};
};

Scales parameter_scale(const std::vector<Observation>& obs) {
  double l2 = 0.0, d2 = 0.0;
  for (const auto& o : obs) {
    l2 += o.x.squaredNorm();
    d2 += o.dt * o.dt;
  }
  Scales s;
  s.l = std::max(1.0, std::sqrt(l2 / static_cast<double>(obs.size())));
  s.d = std::max(1.0, std::sqrt(d2 / static_cast<double>(obs.size())));
  const double l = s.l, d = s.d;
  s.param = {1, 1, 1, l, l, l, l, d, d, d, l * d, l * d, l * d, l * d};  // NOLINT
  return s;
}

// R̈: the second derivative of the position-vector matrix along ṙ.
template <typename T>
Eigen::Matrix<T, 3, 3> rotation_pv_acceleration(const T* r, const T* rdot, RotationModel model) {
  if (model == RotationModel::small_angle) return Eigen::Matrix<T, 3, 3>::Zero();  // R is linear in r
  const Elementary<T> x(r);
  const T a = rdot[0], b = rdot[1], g = rdot[2];
  // (R3 R2 R1)'' with Ri' = ṙi Di, Ri'' = ṙi² Ei.
  const Eigen::Matrix<T, 3, 3> cf = g * g * x.e3 * x.r2 * x.r1 + b * b * x.r3 * x.e2 * x.r1 + a * a * x.r3 * x.r2 * x.e1 +
                                    T(2.0) * (g * b * x.d3 * x.d2 * x.r1 + g * a * x.d3 * x.r2 * x.d1 + b * a * x.r3 * x.d2 * x.d1);
  return cf.transpose();
}

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
std::array<double, static_cast<std::size_t>(K)> basis(const Observation& o, const Scales& sc) {
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
Reduced<K> reduce(const std::vector<Observation>& obs, const std::vector<VelocityObservation>& velocities,
                  const Scales& sc) {
  constexpr int kDim = 3 * K;
  Eigen::Matrix<double, kDim, kDim> h = Eigen::Matrix<double, kDim, kDim>::Zero();
  Eigen::Matrix<double, kDim, 1> g = Eigen::Matrix<double, kDim, 1>::Zero();
  for (const Observation& o : obs) {
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
    for (const VelocityObservation& ov : velocities) {
      const Observation& o = obs[ov.k];
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
  Scales scales;
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
Solution solve_reduced(const std::vector<Observation>& obs, const std::vector<VelocityObservation>& velocities,
                       const FitOptions& o) {
  constexpr bool td = K == 11;
  Solution sol;
  const Scales scales = parameter_scale(obs);
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

Solution solve(const std::vector<Observation>& obs, const std::vector<VelocityObservation>& velocities,
               const FitOptions& o, bool td) {
  return td ? solve_reduced<11>(obs, velocities, o) : solve_reduced<4>(obs, {}, o);
}

}  // namespace

std::string_view to_string(FitModel m) {
  switch (m) {
    case FitModel::translation3: return "translation3";
    case FitModel::helmert6: return "helmert6";
    case FitModel::helmert7: return "helmert7";
    case FitModel::helmert14: return "helmert14";
    case FitModel::molodensky_badekas: return "molodensky-badekas";
    case FitModel::enu_origin: return "enu-origin";
    case FitModel::site_calibration: return "site-calibration";
  }
  return "?";
}

geodesy::EcefPosition apply_fit(const FitResult& fit, const geodesy::EcefPosition& source,
                                std::optional<DecimalYear> epoch) {
  if (fit.ecef_map) return geodesy::EcefPosition(fit.ecef_map->apply(source.m));
  if (fit.site_calibration) return fit.site_calibration->target_from_source(source);
  const DecimalYear t = fit.model == FitModel::helmert14 ? epoch.value() : fit.helmert.reference_epoch;
  return geodesy::apply(geodesy::evaluate_at(fit.helmert, t), fit.rotation_model, source);
}

namespace {

// The fit of `control` as its covariances stand (the GNSS solution types'
// sigma factors already applied by fit_helmert).
FitResult fit_weighted(const ControlSet& control, const FitOptions& options);

// Iteratively reweighted least squares for a robust loss.
FitResult fit_robust(const ControlSet& control, const FitOptions& options) {
  constexpr int kMaxIterations = 50;
  constexpr double kWeightTolerance = 1e-6;
  FitOptions o = options;
  o.robust = FitOptions::Robust::none;
  o.data_snooping = false;
  std::vector<double> weight(control.points.size(), 1.0);
  FitResult r;
  for (int it = 1; it <= kMaxIterations; ++it) {
    ControlSet weighted = control;
    for (std::size_t i = 0; i < weighted.points.size(); ++i) {
      weighted.points[i].source_cov_m2 /= weight[i];
      weighted.points[i].target_cov_m2 /= weight[i];
    }
    if (!control.has_a_priori_sigmas) weighted.has_a_priori_sigmas = false;
    r = fit_weighted(weighted, o);
    double change = 0.0;
    for (std::size_t i = 0; i < r.points.size(); ++i) {
      const auto& p = r.points[i];
      if (!p.used || p.point_dof == 0) continue;
      // The point test T was computed with covariance C / w, so T = w · vᵀC⁻¹v:
      // the standardized residual under the stated covariance is sqrt(T / (dof · w)).
      const double e = std::sqrt(p.point_statistic / (p.point_dof * weight[i]));
      const double k = options.robust_k;
      const double w = options.robust == FitOptions::Robust::huber ? (e <= k ? 1.0 : k / e) : 1.0 / (1.0 + (e / k) * (e / k));
      change = std::max(change, std::fabs(w - weight[i]));
      weight[i] = std::max(w, 1e-6);
    }
    r.robust_iterations = it;
    if (change < kWeightTolerance) break;
  }
  for (std::size_t i = 0; i < r.points.size(); ++i) r.points[i].robust_weight = weight[i];
  r.warnings.push_back(std::string(options.robust == FitOptions::Robust::huber ? "Huber" : "Cauchy") + " robust loss (k = " +
                       fmt(options.robust_k) + ", " + std::to_string(r.robust_iterations) +
                       " reweighting passes): for exploration; sigmas and tests assume the final weights were known");
  return r;
}

FitResult fit_weighted(const ControlSet& control, const FitOptions& options) {
  if (options.robust != FitOptions::Robust::none) return fit_robust(control, options);
  if (options.model == FitModel::enu_origin || options.model == FitModel::site_calibration) {
    if (options.vce) {
      throw Error(ErrorKind::usage, "E_OPTION", "--vce: not available for the " + std::string(to_string(options.model)) +
                                                    " model yet");
    }
    return options.model == FitModel::enu_origin ? fit_enu_origin(control, options) : fit_site_calibration(control, options);
  }
  FitOptions o = options;
  const bool td = o.model == FitModel::helmert14;
  if (has_rotation(o.model) && !o.convention) {
    throw Error(ErrorKind::usage, "E_CONVENTION_MISSING",
                "--convention: required for model " + std::string(to_string(o.model)) +
                    ": position_vector or coordinate_frame (the sign of every rotation depends on it; never assumed)");
  }
  FitResult result;
  result.model = o.model;
  result.convention = o.convention.value_or(Convention::position_vector);
  result.rotation_model = o.rotation_model;
  note_missing_sigmas(result, o, control);
  std::vector<std::size_t> active = init_points(result, control, o);

  const PointTestLevels levels = point_test_levels(o);
  result.w_critical = levels.w_critical;

  // Variance factors of the source and target covariances (--vce).
  double f_src = 1.0, f_dst = 1.0;
  int vce_iterations = 0;
  constexpr int kMaxVceIterations = 50;
  constexpr double kVceTolerance = 1e-5;
  if (o.vce && !control.has_a_priori_sigmas) {
    throw Error(ErrorKind::usage, "E_OPTION", "--vce: needs a-priori sigmas in both frames (sigma_src_m, sigma_dst_m or covariances)");
  }

  // Each mark's local east, north, up (rows, in ECEF) at its target
  // position: the axes of its residuals and w-tests, the same in every pass.
  std::vector<Eigen::Matrix3d> axes(control.points.size());
  std::vector<bool> have_axes(control.points.size(), false);
  const geodesy::GeocentricConverter geocentric(geodesy::Ellipsoid::wgs84());
  auto local_axes = [&](std::size_t i) -> const Eigen::Matrix3d& {
    if (!have_axes[i]) {
      const geodesy::GeodeticPosition at = geocentric.geodetic_from_ecef(control.points[i].target);
      axes[i] = geodesy::enu_from_ecef_rotation(at.lat, at.lon);
      have_axes[i] = true;
    }
    return axes[i];
  };

  while (true) {
    const int n = static_cast<int>(active.size());
    // --- refuse ill-posed problems -------------------------------------
    const std::string unit = td ? "point-epochs" : "points";
    if (n < min_points(o.model)) {
      reject("E_FIT_TOO_FEW_POINTS", "model " + std::string(to_string(o.model)) + ": need >= " +
                                         std::to_string(min_points(o.model)) + " non-collinear points, got " +
                                         std::to_string(n));
    }
    Eigen::Vector3d cx = Eigen::Vector3d::Zero(), cy = Eigen::Vector3d::Zero();
    for (std::size_t i : active) {
      cx += control.points[i].source.m;
      cy += control.points[i].target.m;
    }
    cx /= n;
    cy /= n;
    if (td) {
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
    if (has_rotation(o.model)) {
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
    // Weights from C_target + J C_source Jᵀ, J = (1 + ds(t)) R(r(t)) of the
    // current estimate (the identity before the first solve).
    auto whitening = [&](const geodesy::ControlPoint& p, const Eigen::Matrix3d& j) {
      Eigen::Matrix3d c = f_dst * p.target_cov_m2 + f_src * (j * p.source_cov_m2 * j.transpose());
      if (!control.has_a_priori_sigmas) c = Eigen::Matrix3d::Identity();
      const Eigen::LLT<Eigen::Matrix3d> llt(c);
      if (llt.info() != Eigen::Success) {
        throw Error(ErrorKind::input, "E_SIGMA",
                    control.source_name + ":" + std::to_string(p.line) + ": id=" + p.id +
                        ": combined covariance is not positive definite (zero sigmas in both frames?)");
      }
      return Eigen::Matrix3d(llt.matrixL().solve(Eigen::Matrix3d::Identity()));  // L⁻¹: (L⁻¹)ᵀ L⁻¹ = C⁻¹
    };
    // J at θ for an epoch offset dt.
    auto linear_part = [&](const std::array<double, kMaxParams>& th, double dt) {
      double r[3];
      double s = th[6];
      for (int k = 0; k < 3; ++k) r[k] = th[static_cast<std::size_t>(3 + k)] + (td ? dt * th[static_cast<std::size_t>(10 + k)] : 0.0);
      if (td) s += dt * th[13];
      return Eigen::Matrix3d((1.0 + s) * rotation_pv(r, o.rotation_model));
    };
    std::vector<Observation> obs;
    std::vector<VelocityObservation> velocities;
    obs.reserve(active.size());
    for (std::size_t i : active) {
      const auto& p = control.points[i];
      Observation ob;
      ob.x = p.source.m - cx;
      ob.y = p.target.m - cy;
      ob.w = whitening(p, Eigen::Matrix3d::Identity());
      ob.dt = td ? p.epoch->year - o.reference_epoch->year : 0.0;
      if (td && p.velocities) {
        const Eigen::LLT<Eigen::Matrix3d> vllt(p.velocities->source_cov + p.velocities->target_cov);
        if (vllt.info() == Eigen::Success) {
          VelocityObservation& ov = velocities.emplace_back();
          ov.k = obs.size();
          ov.xdot = p.velocities->source_m_per_year;
          ov.ydot = p.velocities->target_m_per_year;
          ov.wv = vllt.matrixL().solve(Eigen::Matrix3d::Identity());
        }
      }
      obs.push_back(ob);
    }

    Solution sol = solve(obs, velocities, o, td);
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
        sol = solve(obs, velocities, o, td);
      }
    }
    const int u = static_cast<int>(sol.estimated.size());
    int dof = 3 * n - u;  // plus the velocity observations, below

    // --- geometry: is every parameter determined? --------------------------
    std::string geometry_warning;
    {
      const GeometryDilution gd = geometry_dilution(sol.cov_scaled, {0, 1, 2});
      if (!(gd.dilution <= kWarnDilution)) {
        const char* short_names[kMaxParams] = {"tx", "ty", "tz", "rx", "ry", "rz", "ds", "dtx", "dty", "dtz", "drx", "dry", "drz", "dds"};
        // The combination, named by its largest components, and for a
        // rotation its axis in the network's local east, north, up.
        std::string combination;
        Eigen::Vector3d axis = Eigen::Vector3d::Zero();
        for (int a = 0; a < u; ++a) {
          const int k = sol.estimated[static_cast<std::size_t>(a)];
          if (k >= 3 && k <= 5) axis(k - 3) = gd.direction(a);
          if (std::fabs(gd.direction(a)) >= 0.3) {
            combination += (combination.empty() ? "" : " ") + std::string(gd.direction(a) < 0 ? "-" : "+") +
                           fmt(std::fabs(gd.direction(a)), 2) + "·" + short_names[k];
          }
        }
        std::string where;
        if (axis.norm() > 0.5) {
          const geodesy::LocalTangentPlane plane(geodesy::LocalOrigin{
              geodesy::geodetic_from_ecef(geodesy::Ellipsoid::wgs84(), geodesy::EcefPosition(cx)), geodesy::Ellipsoid::wgs84()});
          const Eigen::Vector3d enu = plane.enu_from_ecef_rotation() * axis.normalized();
          const double azimuth = std::fmod(std::atan2(enu.x(), enu.y()) * 180.0 / M_PI + 360.0, 180.0);
          const double elevation = std::asin(std::clamp(std::fabs(enu.z()), 0.0, 1.0)) * 180.0 / M_PI;
          where = ": mostly a rotation about the axis at azimuth " + format_fixed(azimuth, 1) + "°, elevation " +
                  format_fixed(elevation, 1) + "° through the marks' centroid";
        }
        const double radius_m = parameter_scale(obs).l;
        const double sigma_m = std::sqrt(gd.direction.dot(sol.cov_scaled * gd.direction));  // displacement at radius_m
        const std::string what =
            "the marks' geometry leaves a combination of parameters (" + combination + ")" + where + " determined " +
            fmt(gd.dilution, 3) + " times less precisely than the translation: σ " + fmt(sigma_m, 3) +
            " m at the network's RMS radius of " + fmt(radius_m, 4) + " m (" + fmt(sigma_m / radius_m * kArcsecPerRad, 3) +
            "″)";
        if (!(gd.dilution <= kRefuseDilution)) {
          reject("E_FIT_WEAK_GEOMETRY", what + ": the marks are (nearly) collinear or otherwise degenerate for model " +
                                             std::string(to_string(o.model)) +
                                             "; add marks off their line, or fit a translation only (--model translation3)");
        }
        geometry_warning = "weak geometry: " + what;
      }
    }

    // --- geocentric parameters and covariance ----------------------------
    std::array<double, kMaxParams> g{};
    geocentric_from_centred(sol.theta.data(), cx, cy, o.rotation_model, g.data());
    using JetU = ceres::Jet<double, kMaxParams>;
    std::array<JetU, kMaxParams> tj, gj;
    for (int k = 0; k < kMaxParams; ++k) tj[static_cast<std::size_t>(k)] = JetU(sol.theta[static_cast<std::size_t>(k)], k);
    geocentric_from_centred(tj.data(), cx, cy, o.rotation_model, gj.data());
    Eigen::MatrixXd jac(u, u);  // ∂g/∂θ' restricted to the estimated parameters
    for (int a = 0; a < u; ++a) {
      for (int b = 0; b < u; ++b) {
        jac(a, b) = gj[static_cast<std::size_t>(sol.estimated[static_cast<std::size_t>(a)])].v[sol.estimated[static_cast<std::size_t>(b)]];
      }
    }
    Eigen::MatrixXd cov = jac * sol.cov_centred * jac.transpose();
    // Molodensky-Badekas reports the translation at the pivot p:
    // T_p = T + (1 + ds) R p − p = cy + t' + (1 + ds) R (p − cx) − p.
    std::array<double, kMaxParams> reported = g;
    const bool mb = o.model == FitModel::molodensky_badekas;
    if (mb) {
      const Eigen::Vector3d pivot = o.pivot_m.value_or(cx);
      result.pivot_m = pivot;
      auto to_pivot = [&](auto const* tc, auto* out) {
        using T = std::remove_const_t<std::remove_pointer_t<decltype(tc)>>;
        for (int k = 0; k < kMaxParams; ++k) out[k] = tc[k];
        const Eigen::Matrix<T, 3, 3> r = rotation_pv(tc + 3, o.rotation_model);
        const Eigen::Matrix<T, 3, 1> rp = r * (pivot - cx).cast<T>();
        for (int k = 0; k < 3; ++k) out[k] = T(cy(k)) + tc[k] + (T(1.0) + tc[6]) * rp(k) - T(pivot(k));
      };
      to_pivot(sol.theta.data(), reported.data());
      std::array<JetU, kMaxParams> pj;
      to_pivot(tj.data(), pj.data());
      Eigen::MatrixXd jp(u, u);
      for (int a = 0; a < u; ++a) {
        for (int b = 0; b < u; ++b) {
          jp(a, b) = pj[static_cast<std::size_t>(sol.estimated[static_cast<std::size_t>(a)])].v[sol.estimated[static_cast<std::size_t>(b)]];
        }
      }
      cov = jp * sol.cov_centred * jp.transpose();
    }

    auto& h = result.helmert;
    h.at_reference_epoch.t_m = Eigen::Vector3d(g[0], g[1], g[2]);
    h.at_reference_epoch.rx = Angle::radians(g[3]);
    h.at_reference_epoch.ry = Angle::radians(g[4]);
    h.at_reference_epoch.rz = Angle::radians(g[5]);
    h.at_reference_epoch.ds = geodesy::ScaleDifference::unitless(g[6]);
    h.rates.dt_m_per_year = Eigen::Vector3d(g[7], g[8], g[9]);
    h.rates.drx_per_year = Angle::radians(g[10]);
    h.rates.dry_per_year = Angle::radians(g[11]);
    h.rates.drz_per_year = Angle::radians(g[12]);
    h.rates.dds_per_year = geodesy::ScaleDifference::unitless(g[13]);
    h.reference_epoch = o.reference_epoch.value_or(DecimalYear{0.0});
    result.reference_epoch = td ? o.reference_epoch : std::nullopt;

    // --- residuals from the geocentric parameters, whitened statistics ----
    // The reported residuals come from the very parameters that are written,
    // so that applying the file reproduces them.
    double omega = 0.0;
    std::vector<Eigen::Vector3d> v(active.size()), vw(active.size());
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
      for (const VelocityObservation& ov : velocities) {
        const Observation& ob = obs[ov.k];
        const double t = ob.dt;
        const Eigen::Vector3d pred = tdot + (m1 + 2.0 * t * m2) * ob.x + (m0 + t * m1 + t * t * m2) * ov.xdot;
        omega += (ov.wv * (ov.ydot - ov.xdot - pred)).squaredNorm();
        ++velocity_observations;
      }
    }
    dof += 3 * velocity_observations;
    fill_global_test(result, omega, dof, o.alpha, control.has_a_priori_sigmas);
    const double tau = sigma_scale(result, o);

    // Per point: w-tests along local E, N, U; redundancy; MDB.
    using NormalMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxParams, kMaxParams>;
    const NormalMatrix n_inv = sol.cov_centred;  // (ĀᵀĀ)⁻¹ over the estimated parameters
    const RotationWithDerivatives final_rotation = rotation_and_derivatives(sol.theta.data() + 3, o.rotation_model);
    using PointJacobian = Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, kMaxParams>;
    // The whitened residual's cofactor I ∓ A N⁻¹ Aᵀ: − in the fit, + for a
    // point tested against it (a prediction).
    // The whitened design rows of a point over the estimated parameters.
    auto design = [&](const Observation& ob) {
      Eigen::Vector3d pred;
      Eigen::Matrix<double, 3, kMaxParams> jfull;
      predict(ob, sol.theta.data(), o.rotation_model, td, pred, &jfull, &final_rotation);
      PointJacobian a(3, u);
      for (int c = 0; c < u; ++c) a.col(c) = ob.w * jfull.col(sol.estimated[static_cast<std::size_t>(c)]);
      return a;
    };
    auto cofactor = [&](const PointJacobian& a, double sign) {
      return Eigen::Matrix3d(Eigen::Matrix3d::Identity() + sign * (a * n_inv * a.transpose()));
    };
    std::vector<Eigen::Matrix3d> qvs(o.vce ? active.size() : 0);  // whitened Q_vv per point, kept for --vce
    FitLinearization lin;  // the failing marks, for data snooping
    lin.n_inv = n_inv;
    for (std::size_t k = 0; k < active.size(); ++k) {
      const PointJacobian a = design(obs[k]);
      const Eigen::Matrix3d qv = cofactor(a, -1.0);
      if (o.vce) qvs[k] = qv;
      PointResult& pr = result.points[active[k]];
      pr.used = true;
      test_point(PointTestInput{v[k], obs[k].w, qv, local_axes(active[k]), true}, tau, levels.lambda0, pr);
      if (pr.point_dof > 0 && pr.point_p_value < o.alpha_point) lin.add(k, a, vw[k]);
    }

    // --- variance components (--vce) -----------------------------------------
    // θ_k ← θ_k · (vᵀ P Q_k P v) / tr(P Q_k P Q_vv), Q_k the group's current
    // covariance (the source's as J C Jᵀ, as the weights hold it); with one
    // group this is θ ← θ σ̂0².
    if (o.vce && dof > 0) {
      double num_src = 0.0, num_dst = 0.0, den_src = 0.0, den_dst = 0.0;
      double s11 = 0.0, s12 = 0.0, s22 = 0.0;  // the VCE normal matrix: Σ tr(B_k B_l), B_k = Q_k P Q_vv P
      for (std::size_t k = 0; k < active.size(); ++k) {
        const auto& p = control.points[active[k]];
        const Eigen::Matrix3d pqp = obs[k].w.transpose() * qvs[k] * obs[k].w;
        const Eigen::Vector3d pv = obs[k].w.transpose() * vw[k];
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
      if (!converged && ++vce_iterations < kMaxVceIterations) continue;
      if (!converged) result.warnings.push_back("variance components did not converge in " + std::to_string(kMaxVceIterations) + " iterations");
    }

    // --- data snooping ------------------------------------------------------
    if (snoop(result, active, o, u, min_points(o.model), lin) == SnoopStep::removed) continue;

    // --- points outside the final fit: tested against it ---------------------
    // Their residuals come from the final parameters, and their tests are
    // prediction tests (Q = I + A N⁻¹ Aᵀ): a removed blunder shows at full size.
    std::vector<bool> in_fit(control.points.size(), false);
    for (std::size_t i : active) in_fit[i] = true;
    for (std::size_t i = 0; i < control.points.size(); ++i) {
      if (in_fit[i]) continue;
      const auto& p = control.points[i];
      if (td && !p.epoch) continue;
      Observation ob;
      ob.x = p.source.m - cx;
      ob.y = p.target.m - cy;
      ob.dt = td ? p.epoch->year - o.reference_epoch->year : 0.0;
      ob.w = whitening(p, linear_part(sol.theta, ob.dt));
      const Eigen::Vector3d vi = p.target.m - apply_fit(result, p.source, td ? p.epoch : std::nullopt).m;
      const Eigen::Matrix3d q = cofactor(design(ob), +1.0);
      test_point(PointTestInput{vi, ob.w, q, local_axes(i), false}, tau, levels.lambda0, result.points[i]);
    }

    // --- report -------------------------------------------------------------
    if (!geometry_warning.empty()) result.warnings.push_back(geometry_warning);
    if (o.scale_by_sigma0 && result.sigma0) cov *= *result.sigma0 * *result.sigma0;
    result.covariance_scaled_by_sigma0 = o.scale_by_sigma0 && result.sigma0.has_value();

    // Names and unit factors, in the reported convention.
    const bool cf = result.convention == Convention::coordinate_frame;
    const char* names[kMaxParams] = {"tx_m", "ty_m", "tz_m", "rx_arcsec", "ry_arcsec", "rz_arcsec", "ds_ppm",
                                     "dtx_m_per_year", "dty_m_per_year", "dtz_m_per_year", "drx_arcsec_per_year",
                                     "dry_arcsec_per_year", "drz_arcsec_per_year", "dds_ppm_per_year"};
    auto factor = [&](int k) {
      const bool rotation = (k >= 3 && k <= 5) || (k >= 10 && k <= 12);
      const bool scale = k == 6 || k == 13;
      return rotation ? (cf ? -kArcsecPerRad : kArcsecPerRad) : scale ? kPpm : 1.0;
    };
    Eigen::VectorXd f(u);
    for (int a = 0; a < u; ++a) f(a) = factor(sol.estimated[static_cast<std::size_t>(a)]);
    result.covariance = symmetric(f.asDiagonal() * cov * f.asDiagonal());
    result.correlation = correlation_of(result.covariance);
    result.covariance_names.clear();
    for (int a = 0; a < u; ++a) result.covariance_names.emplace_back(names[sol.estimated[static_cast<std::size_t>(a)]]);
    result.parameters.clear();
    for (int k = 0; k < (td ? 14 : 7); ++k) {
      Parameter p;
      p.name = names[k];
      p.value = reported[static_cast<std::size_t>(k)] * factor(k);
      const auto it = std::find(sol.estimated.begin(), sol.estimated.end(), k);
      p.estimated = it != sol.estimated.end();
      if (p.estimated) {
        const auto a = it - sol.estimated.begin();
        p.sigma = std::sqrt(result.covariance(a, a));
      }
      result.parameters.push_back(p);
    }
    if (mb) {
      const char* pivot_names[3] = {"px_m", "py_m", "pz_m"};
      for (int k = 0; k < 3; ++k) result.parameters.push_back(Parameter{pivot_names[k], (*result.pivot_m)(k), 0.0, false});
    }
    // Weak geometry: how much of each geocentric translation is determined by
    // the rotations and scale (multiple correlation), plus the largest
    // pairwise correlation to quote.
    std::vector<int> rs;  // positions of rotation/scale parameters in the covariance
    for (int a = 0; a < u; ++a) {
      const int k = sol.estimated[static_cast<std::size_t>(a)];
      if (k >= 3 && k <= 6) rs.push_back(a);
    }
    if (!rs.empty() && !mb) {
      double worst_multiple = 0.0, worst_pair = 0.0;
      std::string translation, pair;
      Eigen::MatrixXd s_rs(rs.size(), rs.size());
      for (std::size_t a = 0; a < rs.size(); ++a) {
        for (std::size_t b = 0; b < rs.size(); ++b) s_rs(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) = cov(rs[a], rs[b]);
      }
      const Eigen::LDLT<Eigen::MatrixXd> s_rs_ldlt(s_rs);
      for (int tix = 0; tix < 3; ++tix) {
        Eigen::VectorXd c(rs.size());
        for (std::size_t b = 0; b < rs.size(); ++b) {
          c(static_cast<Eigen::Index>(b)) = cov(tix, rs[b]);
          const double corr = std::fabs(result.correlation(tix, rs[b]));
          if (corr > worst_pair) {
            worst_pair = corr;
            pair = std::string(names[tix]) + "/" + result.covariance_names[static_cast<std::size_t>(rs[b])];
          }
        }
        const double multiple = std::sqrt(std::clamp(c.dot(s_rs_ldlt.solve(c)) / cov(tix, tix), 0.0, 1.0));
        if (multiple > worst_multiple) {
          worst_multiple = multiple;
          translation = names[tix];
        }
      }
      if (worst_multiple > 0.99) {
        result.warnings.push_back(
            "weak geometry: the multiple correlation of " + translation + " with the rotations and scale is " +
            (worst_multiple > 0.999999 ? "1 - " + fmt(1.0 - worst_multiple, 2) : fmt(worst_multiple, 6)) +
            "; largest pairwise |corr(" + pair +
            ")| = " + fmt(worst_pair, 4) +
            ". The network is small compared with its distance from the Earth's centre: " +
            (geometry_warning.empty() ? "the transform is sound, " : "") +
            "its geocentric parameters are not individually meaningful; consider --model molodensky-badekas");
      }
    }
    // Implausible magnitudes for a datum transform (RELIABILITY #15), as
    // reported (for Molodensky-Badekas: at the pivot).
    {
      geodesy::Helmert7<geodesy::PositionVector> as_reported;
      for (const auto& p : result.parameters) {
        if (p.name == "tx_m") as_reported.t_m.x() = p.value;
        if (p.name == "ty_m") as_reported.t_m.y() = p.value;
        if (p.name == "tz_m") as_reported.t_m.z() = p.value;
        if (p.name == "rx_arcsec") as_reported.rx = Angle::arcseconds(p.value);
        if (p.name == "ry_arcsec") as_reported.ry = Angle::arcseconds(p.value);
        if (p.name == "rz_arcsec") as_reported.rz = Angle::arcseconds(p.value);
        if (p.name == "ds_ppm") as_reported.ds = geodesy::ScaleDifference::ppm(p.value);
      }
      for (auto& w : geodesy::implausible_parameter_warnings(as_reported)) result.warnings.push_back(std::move(w));
    }
    add_statistics_warnings(result, options);
    result.ceres_iterations = sol.iterations;
    result.ceres_report = sol.report;
    result.rotation_model = o.rotation_model;
    return result;
  }
}

}  // namespace

FitResult fit_helmert(const ControlSet& control, const FitOptions& options) {
  // GNSS solution types weighted on request: float and worse enter with
  // their covariances scaled by the class's factor squared (geodesy::
  // solution_sigma_factor); excluded classes are left out by init_points.
  bool scaled = false;
  if (options.solutions == geodesy::SolutionPolicy::weight && control.has_solutions) {
    for (const auto& p : control.points) {
      scaled = scaled || (p.solution && geodesy::sigma_factor_under(*p.solution, options.solutions) != 1.0);
    }
  }
  if (!scaled) return fit_weighted(control, options);
  if (!control.has_a_priori_sigmas) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--solution-weighting: " + control.source_name +
                    " gives no a-priori sigmas, which the GNSS solution types' factors would scale; give sigma_src_m/"
                    "sigma_dst_m (or covariances), or leave float and worse out (the default)");
  }
  ControlSet weighted = control;
  for (auto& p : weighted.points) {
    if (!p.solution) continue;
    const double f = geodesy::sigma_factor_under(*p.solution, options.solutions);
    p.source_cov_m2 *= f * f;
    p.target_cov_m2 *= f * f;
  }
  return fit_weighted(weighted, options);
}


}  // namespace geoanchor::solver
