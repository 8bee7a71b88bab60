#include "geoanchor/geodesy/helmert.hpp"

#include <cmath>
#include <cstdio>

namespace geoanchor::geodesy {

std::string_view to_string(RotationModel m) { return m == RotationModel::small_angle ? "small_angle" : "exact"; }

namespace {

template <RotationConvention To, RotationConvention From>
Helmert7<To> swap_convention(const Helmert7<From>& h) {
  Helmert7<To> out;
  out.t_m = h.t_m;
  out.rx = -h.rx;
  out.ry = -h.ry;
  out.rz = -h.rz;
  out.ds = h.ds;
  return out;
}

template <RotationConvention To, RotationConvention From>
Helmert14<To> swap_convention(const Helmert14<From>& h) {
  Helmert14<To> out;
  out.at_reference_epoch = swap_convention<To>(h.at_reference_epoch);
  out.rates.dt_m_per_year = h.rates.dt_m_per_year;
  out.rates.drx_per_year = -h.rates.drx_per_year;
  out.rates.dry_per_year = -h.rates.dry_per_year;
  out.rates.drz_per_year = -h.rates.drz_per_year;
  out.rates.dds_per_year = h.rates.dds_per_year;
  out.reference_epoch = h.reference_epoch;
  return out;
}

// The coordinate-frame matrix for rotations (rx, ry, rz) in radians.
Eigen::Matrix3d coordinate_frame_matrix(double rx, double ry, double rz, RotationModel model) {
  Eigen::Matrix3d r;
  if (model == RotationModel::small_angle) {
    r << 1.0, rz, -ry,  //
        -rz, 1.0, rx,   //
        ry, -rx, 1.0;
    return r;
  }
  // R3(rz) · R2(ry) · R1(rx), each a rotation of the axes (coordinate frame).
  const double ca = std::cos(rx), sa = std::sin(rx);
  const double cb = std::cos(ry), sb = std::sin(ry);
  const double cg = std::cos(rz), sg = std::sin(rz);
  Eigen::Matrix3d r1, r2, r3;
  r1 << 1, 0, 0, 0, ca, sa, 0, -sa, ca;
  r2 << cb, 0, -sb, 0, 1, 0, sb, 0, cb;
  r3 << cg, sg, 0, -sg, cg, 0, 0, 0, 1;
  return r3 * r2 * r1;
}

}  // namespace

Helmert7<CoordinateFrame> to_coordinate_frame(const Helmert7<PositionVector>& h) {
  return swap_convention<CoordinateFrame>(h);
}
Helmert7<PositionVector> to_position_vector(const Helmert7<CoordinateFrame>& h) {
  return swap_convention<PositionVector>(h);
}
Helmert14<CoordinateFrame> to_coordinate_frame(const Helmert14<PositionVector>& h) {
  return swap_convention<CoordinateFrame>(h);
}
Helmert14<PositionVector> to_position_vector(const Helmert14<CoordinateFrame>& h) {
  return swap_convention<PositionVector>(h);
}

Eigen::Matrix3d rotation_matrix(const Helmert7<CoordinateFrame>& h, RotationModel model) {
  return coordinate_frame_matrix(h.rx.rad(), h.ry.rad(), h.rz.rad(), model);
}

Eigen::Matrix3d rotation_matrix(const Helmert7<PositionVector>& h, RotationModel model) {
  // Position vector: the transpose of the coordinate-frame matrix built from
  // the same numbers (PROJ's definition, in both rotation models).
  return coordinate_frame_matrix(h.rx.rad(), h.ry.rad(), h.rz.rad(), model).transpose();
}

}  // namespace geoanchor::geodesy

namespace geoanchor::geodesy {
namespace {

// A parameter's effect at the Earth's surface (mean radius 6 371 km).
constexpr double kEarthRadius_m = 6371000.0;

std::string three_digits(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}

}  // namespace

template <RotationConvention C>
std::vector<std::string> implausible_parameter_warnings(const Helmert7<C>& h) {
  std::vector<std::string> out;
  const char* axes[3] = {"tx", "ty", "tz"};
  for (int k = 0; k < 3; ++k) {
    const double t = h.t_m(k);
    if (!(std::fabs(t) <= kPlausibleTranslation_m)) {
      out.push_back(std::string(axes[k]) + " = " + three_digits(t) + " m is implausible for a datum transform (> " +
                    three_digits(kPlausibleTranslation_m) +
                    " m): check the units (mm read as m?) and that both frames are geocentric");
    }
  }
  const Angle r[3] = {h.rx, h.ry, h.rz};
  const char* rot[3] = {"rx", "ry", "rz"};
  for (int k = 0; k < 3; ++k) {
    const double a = r[k].arcsec();
    if (!(std::fabs(a) <= kPlausibleRotation_arcsec)) {
      out.push_back(std::string(rot[k]) + " = " + three_digits(a) + "″ is implausible for a datum transform (> " +
                    three_digits(kPlausibleRotation_arcsec) + "″, " +
                    three_digits(std::fabs(r[k].rad()) * kEarthRadius_m) +
                    " m at the Earth's surface): check the convention and the units (mas read as arc-seconds?)");
    }
  }
  const double s = h.ds.ppm();
  if (!(std::fabs(s) <= kPlausibleScale_ppm)) {
    out.push_back("ds = " + three_digits(s) + " ppm is implausible for a datum transform (> " +
                  three_digits(kPlausibleScale_ppm) + " ppm, " + three_digits(std::fabs(h.ds.unitless()) * kEarthRadius_m) +
                  " m at the Earth's surface): check the units (ppb read as ppm?)");
  }
  return out;
}

template std::vector<std::string> implausible_parameter_warnings(const Helmert7<PositionVector>&);
template std::vector<std::string> implausible_parameter_warnings(const Helmert7<CoordinateFrame>&);

}  // namespace geoanchor::geodesy
