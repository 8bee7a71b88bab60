// The Helmert transformation as the fit estimates it (helmert_model.hpp).

#include "helmert_model.hpp"

namespace geoanchor::solver {

using geodesy::RotationModel;

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

void predict_mark(const MarkObservation& o, const double* theta, RotationModel model, bool time_dependent,
                  Eigen::Vector3d& pred, Eigen::Matrix<double, 3, kMaxParams>* jac,
                  const RotationWithDerivatives* fixed_rotation) {
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

}  // namespace geoanchor::solver
