// Must NOT compile: a coordinate-frame parameter set applied where a
// position-vector set is required, without to_position_vector().
#include "geoanchor/geodesy/helmert.hpp"

using namespace geoanchor::geodesy;

EcefPosition apply_pv(const Helmert7<PositionVector>& h, const EcefPosition& p) {
  return apply(h, RotationModel::small_angle, p);
}

EcefPosition misuse(const Helmert7<CoordinateFrame>& published_cf, const EcefPosition& p) {
  return apply_pv(published_cf, p);
}
