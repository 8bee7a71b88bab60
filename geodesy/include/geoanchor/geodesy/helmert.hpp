#pragma once
// Seven- and fourteen-parameter Helmert transforms between ECEF frames.
//
//   X_target = T + (1 + ds) · R · X_source
//
// Rotation convention (part of the type, never defaulted):
//   PositionVector   (EPSG 1033/1053/1037, IERS, PROJ convention=position_vector):
//     small-angle R = | 1   -rz   ry |
//                     | rz   1   -rx |
//                     | -ry  rx   1  |
//   CoordinateFrame  (EPSG 1032/1056/9607, PROJ convention=coordinate_frame):
//     R is the transpose of the above for the same (rx, ry, rz).
// So the same physical transform has its rotations negated in the other
// convention; converting is an explicit call (to_position_vector /
// to_coordinate_frame) and never happens silently.
//
// Rotation model (part of every stored transform):
//   small_angle  R = I ± skew(r), the matrix the EPSG methods define and PROJ
//                applies by default: published parameter sets must be applied
//                this way. R is not orthogonal (error ~ r²).
//   exact        the product of three finite rotations (PROJ's +exact): for
//                coordinate frame R = R3(rz)·R2(ry)·R1(rx) with
//                R1(a) = [[1,0,0],[0,cos a,sin a],[0,-sin a,cos a]], etc.; for
//                position vector its transpose. In this model negating the
//                rotations is the inverse only to first order (r²·|X|, about
//                0.15 mm for 1″ at Earth radius).
//
// Fourteen parameters: p(t) = p(t_ref) + ṗ · (t − t_ref) for each of the
// seven, evaluated at the observation epoch t of the coordinates.

#include <Eigen/Core>

#include <concepts>
#include <string>
#include <string_view>
#include <vector>

#include "geoanchor/geodesy/affine.hpp"
#include "geoanchor/geodesy/positions.hpp"
#include "geoanchor/geodesy/units.hpp"

namespace geoanchor::geodesy {

struct PositionVector {
  static constexpr std::string_view name = "position_vector";
};
struct CoordinateFrame {
  static constexpr std::string_view name = "coordinate_frame";
};
template <class C>
concept RotationConvention = std::same_as<C, PositionVector> || std::same_as<C, CoordinateFrame>;

enum class RotationModel { small_angle, exact };
std::string_view to_string(RotationModel m);

template <RotationConvention C>
struct Helmert7 {
  Eigen::Vector3d t_m = Eigen::Vector3d::Zero();
  Angle rx, ry, rz;
  ScaleDifference ds;
};

// Rates per year of the seven parameters.
template <RotationConvention C>
struct Helmert7Rates {
  Eigen::Vector3d dt_m_per_year = Eigen::Vector3d::Zero();
  Angle drx_per_year, dry_per_year, drz_per_year;
  ScaleDifference dds_per_year;
};

template <RotationConvention C>
struct Helmert14 {
  Helmert7<C> at_reference_epoch;
  Helmert7Rates<C> rates;
  DecimalYear reference_epoch;
};

// The seven parameters at `observation_epoch`.
template <RotationConvention C>
Helmert7<C> evaluate_at(const Helmert14<C>& h, DecimalYear observation_epoch) {
  const double dt = years_between(h.reference_epoch, observation_epoch);
  const auto& p = h.at_reference_epoch;
  const auto& r = h.rates;
  Helmert7<C> out;
  out.t_m = p.t_m + r.dt_m_per_year * dt;
  out.rx = p.rx + r.drx_per_year * dt;
  out.ry = p.ry + r.dry_per_year * dt;
  out.rz = p.rz + r.drz_per_year * dt;
  out.ds = p.ds + r.dds_per_year * dt;
  return out;
}

// Convention swaps: rotations (and rotation rates) negated, all else kept.
Helmert7<CoordinateFrame> to_coordinate_frame(const Helmert7<PositionVector>& h);
Helmert7<PositionVector> to_position_vector(const Helmert7<CoordinateFrame>& h);
Helmert14<CoordinateFrame> to_coordinate_frame(const Helmert14<PositionVector>& h);
Helmert14<PositionVector> to_position_vector(const Helmert14<CoordinateFrame>& h);

// R of the formula above in this transform's own convention.
Eigen::Matrix3d rotation_matrix(const Helmert7<PositionVector>& h, RotationModel model);
Eigen::Matrix3d rotation_matrix(const Helmert7<CoordinateFrame>& h, RotationModel model);

// The transform as an affine map, target_from_source.
template <RotationConvention C>
AffineMap target_from_source(const Helmert7<C>& h, RotationModel model) {
  return AffineMap((1.0 + h.ds.unitless()) * rotation_matrix(h, model), h.t_m);
}

template <RotationConvention C>
EcefPosition apply(const Helmert7<C>& h, RotationModel model, const EcefPosition& source) {
  return EcefPosition(target_from_source(h, model).apply(source.m));
}

// The exact inverse (source_from_target): the affine map inverted, not the
// parameters negated.
template <RotationConvention C>
AffineMap source_from_target(const Helmert7<C>& h, RotationModel model) {
  return target_from_source(h, model).inverse();
}

// EPSG's "reversible" reverse: every parameter negated. An approximation of
// the inverse to first order: 30 µm for GDA94 -> GDA2020, 3 cm for rotations
// of 16″. Use source_from_target for the exact inverse.
template <RotationConvention C>
Helmert7<C> negated_parameters(const Helmert7<C>& h) {
  Helmert7<C> out;
  out.t_m = -h.t_m;
  out.rx = -h.rx;
  out.ry = -h.ry;
  out.rz = -h.rz;
  out.ds = -h.ds;
  return out;
}

// Plausibility of a datum transform's parameters (RELIABILITY #15): between
// geocentric or near-geocentric frames, translations stay below a few
// hundred metres (Tokyo → JGD2000, among the largest classical shifts, is
// about 860 m), rotations below a few arc-seconds and scale differences
// below some tens of ppm. Larger values are usually a wrong unit (mas read
// as arc-seconds, ppb as ppm), a wrong convention, or local coordinates fitted
// as if geocentric. One set of limits serves `fit`, `convert` and `apply`.
inline constexpr double kPlausibleTranslation_m = 1000.0;
inline constexpr double kPlausibleRotation_arcsec = 10.0;
inline constexpr double kPlausibleScale_ppm = 100.0;
// One warning per implausible parameter, quoting its effect at the Earth's
// surface; empty when all are plausible. For a 14-parameter set pass the
// parameters at the epoch of use (evaluate_at).
template <RotationConvention C>
std::vector<std::string> implausible_parameter_warnings(const Helmert7<C>& h);
extern template std::vector<std::string> implausible_parameter_warnings(const Helmert7<PositionVector>&);
extern template std::vector<std::string> implausible_parameter_warnings(const Helmert7<CoordinateFrame>&);

}  // namespace geoanchor::geodesy
