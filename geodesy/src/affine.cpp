#include "geoanchor/geodesy/affine.hpp"

#include <Eigen/LU>
#include <cmath>
#include <limits>

namespace geoanchor::geodesy {
namespace {
using Matrix3l = Eigen::Matrix<long double, 3, 3>;
using Vector3l = Eigen::Matrix<long double, 3, 1>;
}  // namespace

AffineMap AffineMap::identity() { return AffineMap(Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero()); }

AffineMap AffineMap::inverse() const {
  const Matrix3l l = linear_.cast<long double>();
  const long double det = l.determinant();
  if (!(std::fabs(det) > 0.0L) || !std::isfinite(static_cast<double>(det))) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return AffineMap(Eigen::Matrix3d::Constant(nan), Eigen::Vector3d::Constant(nan));
  }
  const Matrix3l inv = l.inverse();
  const Vector3l t = -(inv * translation_m_.cast<long double>());
  return AffineMap(inv.cast<double>(), t.cast<double>());
}

AffineMap compose(const AffineMap& c_from_b, const AffineMap& b_from_a) {
  const Matrix3l l2 = c_from_b.linear().cast<long double>();
  const Matrix3l l = l2 * b_from_a.linear().cast<long double>();
  const Vector3l t = l2 * b_from_a.translation_m().cast<long double>() + c_from_b.translation_m().cast<long double>();
  return AffineMap(l.cast<double>(), t.cast<double>());
}

}  // namespace geoanchor::geodesy
