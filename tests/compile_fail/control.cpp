// Must compile: the same code as the misuse cases, written correctly. Keeps
// the compile-fail tests honest (a wrong include path would also "fail").
#include "geoanchor/geodesy/helmert.hpp"
#include "geoanchor/geodesy/positions.hpp"

using namespace geoanchor::geodesy;

EcefPosition apply_pv(const Helmert7<PositionVector>& h, const EcefPosition& p) {
  return apply(h, RotationModel::small_angle, p);
}

EcefPosition correct(const Helmert7<CoordinateFrame>& published_cf, const EcefPosition& p) {
  return apply_pv(to_position_vector(published_cf), p);
}

EcefPosition from_double(double x, double y, double z) { return EcefPosition(x, y, z); }
