#pragma once
// The float32 value nearest to a double, as a double: what a coordinate
// keeps when it is stored in a 4-byte float (a PLY float property, a float32
// ECEF column).
//
// Defined out of line on purpose: GCC 12.2's SLP vectorizer was seen to drop
// double → float → double round trips written inline, once inside a loop
// (a float32 PLY read more precisely than the file says) and once in an
// array initializer (a float32 test corruption left two of three values
// untouched).

namespace geoanchor::geodesy {

double round_to_float32(double v);

}  // namespace geoanchor::geodesy
