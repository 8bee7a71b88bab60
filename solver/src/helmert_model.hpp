#pragma once
// The Helmert transformation as the fit estimates it (helmert_fit.hpp):
// the centred parameter vector θ' (its layout below), the position-vector
// rotation matrix of either rotation model with its derivatives (templated
// for Ceres' automatic differentiation), one mark's observation equation
// and the geocentric parameters from the centred ones.
//
// Private to solver.

#include <ceres/jet.h>

#include <Eigen/Core>

#include <array>
#include <cmath>
#include <cstddef>

#include "geoanchor/geodesy/helmert.hpp"
#include "geoanchor/solver/helmert_fit.hpp"

namespace geoanchor::solver {

// Parameter layout of the estimation vector θ' (centroid-referenced):
//   0-2 t' (m), 3-5 r (rad), 6 ds, 7-9 ṫ' (m/yr), 10-12 ṙ (rad/yr), 13 ḋs (1/yr).
inline constexpr int kMaxParams = 14;

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
Eigen::Matrix<T, 3, 3> rotation_pv(const T* r, geodesy::RotationModel model) {
  Eigen::Matrix<T, 3, 3> m;
  if (model == geodesy::RotationModel::small_angle) {
    m << T(1.0), -r[2], r[1], r[2], T(1.0), -r[0], -r[1], r[0], T(1.0);
    return m;
  }
  const Elementary<T> x(r);
  return (x.r3 * x.r2 * x.r1).transpose();  // position vector: transpose of the coordinate-frame matrix
}

// Ṙ: the derivative of the position-vector matrix along the rotation rate ṙ.
template <typename T>
Eigen::Matrix<T, 3, 3> rotation_pv_rate(const T* r, const T* rdot, geodesy::RotationModel model) {
  Eigen::Matrix<T, 3, 3> m;
  if (model == geodesy::RotationModel::small_angle) {
    m << T(0.0), -rdot[2], rdot[1], rdot[2], T(0.0), -rdot[0], -rdot[1], rdot[0], T(0.0);
    return m;
  }
  const Elementary<T> x(r);
  const Eigen::Matrix<T, 3, 3> cf =
      rdot[2] * x.d3 * x.r2 * x.r1 + rdot[1] * x.r3 * x.d2 * x.r1 + rdot[0] * x.r3 * x.r2 * x.d1;
  return cf.transpose();
}

// R̈: the second derivative of the position-vector matrix along ṙ.
template <typename T>
Eigen::Matrix<T, 3, 3> rotation_pv_acceleration(const T* r, const T* rdot, geodesy::RotationModel model) {
  if (model == geodesy::RotationModel::small_angle) return Eigen::Matrix<T, 3, 3>::Zero();  // R is linear in r
  const Elementary<T> x(r);
  const T a = rdot[0], b = rdot[1], g = rdot[2];
  // (R3 R2 R1)'' with Ri' = ṙi Di, Ri'' = ṙi² Ei.
  const Eigen::Matrix<T, 3, 3> cf = g * g * x.e3 * x.r2 * x.r1 + b * b * x.r3 * x.e2 * x.r1 + a * a * x.r3 * x.r2 * x.e1 +
                                    T(2.0) * (g * b * x.d3 * x.d2 * x.r1 + g * a * x.d3 * x.r2 * x.d1 + b * a * x.r3 * x.d2 * x.d1);
  return cf.transpose();
}

// R and its derivatives with respect to rx, ry, rz.
struct RotationWithDerivatives {
  Eigen::Matrix3d r;
  std::array<Eigen::Matrix3d, 3> d;
};

RotationWithDerivatives rotation_and_derivatives(const double* rot, geodesy::RotationModel model);

// One observation equation, ready for the solver: centred coordinates, the
// whitening matrix and the epoch offset.
struct MarkObservation {
  Eigen::Vector3d x;   // source − source centroid
  Eigen::Vector3d y;   // target − target centroid
  Eigen::Matrix3d w;   // W with Wᵀ W = C⁻¹
  double dt = 0.0;     // years from the reference epoch
};

// A mark's velocities (helmert14): ẏ − ẋ = ṫ' + Ṁ x + (M − I) ẋ observes the
// rates. Kept apart from the positions: most fits have none, and inside
// each observation they were half of its memory.
struct MarkVelocity {
  std::size_t k = 0;  // the mark's position observation
  Eigen::Vector3d xdot = Eigen::Vector3d::Zero(), ydot = Eigen::Vector3d::Zero();
  Eigen::Matrix3d wv = Eigen::Matrix3d::Identity();  // whitening of the velocity difference
};

// Predicted centred target and its Jacobian (3 × 14) for θ'. Without time
// dependence R is the same for every point: pass it as `fixed_rotation`.
void predict_mark(const MarkObservation& o, const double* theta, geodesy::RotationModel model, bool time_dependent,
                  Eigen::Vector3d& pred, Eigen::Matrix<double, 3, kMaxParams>* jac,
                  const RotationWithDerivatives* fixed_rotation = nullptr);

inline bool has_rotation(FitModel m) {
  return m != FitModel::translation3 && m != FitModel::enu_origin && m != FitModel::site_calibration;
}
inline bool has_scale(FitModel m) {
  return m == FitModel::helmert7 || m == FitModel::helmert14 || m == FitModel::molodensky_badekas;
}
inline int min_points(FitModel m) { return m == FitModel::translation3 ? 1 : 3; }

// Geocentric (position-vector) parameters from θ' (both in solver units:
// metres, radians, unitless, per year), templated for autodiff of the
// covariance propagation.
template <typename T>
void geocentric_from_centred(const T* tc, const Eigen::Vector3d& cx, const Eigen::Vector3d& cy, geodesy::RotationModel model,
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

}  // namespace geoanchor::solver
