#pragma once
// A network written as DynAdjust's DynaML (a station file and a measurement
// file) and as geoanchor's network JSON (docs/network-format.md): the
// formats `geoanchor adjust` reads, so that what is written reads back to
// the same network. Used by the network generator (workflow/
// network_generator.hpp).
//
// What these writers hold: a network on the ellipsoid with a frame and its
// epoch; stations with a-priori ECEF positions, either free (FFF) or held
// (CCC, fixed); GNSS baselines one at a time (DynaML type G) with their 3×3
// covariance. Anything else is refused by name (E_NETWORK_WRITE) before a
// byte is written, never written approximately. Numbers are written in the
// shortest text that reads back to the same double.

#include <ostream>

#include "geoanchor/geodesy/network.hpp"

namespace geoanchor::io {

// Throws geoanchor::Error (usage, E_NETWORK_WRITE) naming the station or
// measurement these formats cannot hold.
void check_writable_network(const geodesy::Network& network);

// `referenceframe` and `epoch` (dd.mm.yyyy) on the root; stations of Type
// XYZ. The epoch must be a whole day.
void write_dynaml_stations(const geodesy::Network& network, std::ostream& out);
void write_dynaml_measurements(const geodesy::Network& network, std::ostream& out);

// "geoanchor.network/1": stations x_m y_m z_m, baselines with cov_m2.
void write_network_json(const geodesy::Network& network, std::ostream& out);

}  // namespace geoanchor::io
