#pragma once
// An affine map y = L x + t between two Cartesian frames, in metres.
//
// ENU <-> ECEF at a fixed origin and a Helmert transform at a fixed epoch are
// all affine, so a chain of them is composed once into one AffineMap and then
// applied per point. Composition and inversion are carried out in long double
// and rounded once, so a fused chain is at least as accurate as applying its
// steps one after the other in double.

#include <Eigen/Core>

namespace geoanchor::geodesy {

class AffineMap {
 public:
  static AffineMap identity();
  AffineMap(const Eigen::Matrix3d& linear, const Eigen::Vector3d& translation_m)
      : linear_(linear), translation_m_(translation_m) {}

  Eigen::Vector3d apply(const Eigen::Vector3d& x_m) const { return linear_ * x_m + translation_m_; }
  const Eigen::Matrix3d& linear() const { return linear_; }
  const Eigen::Vector3d& translation_m() const { return translation_m_; }

  // The exact inverse x = L^-1 (y - t); all NaN if L is singular.
  AffineMap inverse() const;

 private:
  Eigen::Matrix3d linear_;
  Eigen::Vector3d translation_m_;
};

// c_from_a = c_from_b ∘ b_from_a: apply b_from_a first.
AffineMap compose(const AffineMap& c_from_b, const AffineMap& b_from_a);

}  // namespace geoanchor::geodesy
