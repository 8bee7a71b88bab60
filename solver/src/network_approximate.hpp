#pragma once
// Approximate positions for the stations of a local network whose input
// gives no coordinates (private to solver).

#include "geoanchor/geodesy/network.hpp"

namespace geoanchor::solver {

// Places every station without a-priori coordinates from the measurements
// (observed points, vectors, levelled heights, and a bearing with a length
// from a placed station), repeatedly until all are placed. Throws
// geoanchor::Error (input, E_STATION_UNDEFINED) naming the stations it
// cannot place, or any such station of a network on the ellipsoid.
void approximate_positions(geodesy::Network& net);

}  // namespace geoanchor::solver
