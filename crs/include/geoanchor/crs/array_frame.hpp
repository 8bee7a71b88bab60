#pragma once
// What kind of coordinates an array holds and in which frame: the kind,
// the ellipsoid, and the ENU/NED origin or the projection.

#include <optional>

#include "geoanchor/geodesy/ellipsoid.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/geodesy/projection.hpp"

namespace geoanchor::io {

enum class CoordinateKind { geodetic, ecef, enu, ned, projected };

// The frame of a coordinate array (no utm_zone columns here: a tile has one
// projection).
struct ArrayFrame {
  CoordinateKind kind = CoordinateKind::ecef;
  geodesy::Ellipsoid ellipsoid = geodesy::Ellipsoid::wgs84();
  std::optional<geodesy::LocalOrigin> origin;        // enu, ned
  std::optional<geodesy::ProjectionDef> projection;  // projected
};

}  // namespace geoanchor::io
