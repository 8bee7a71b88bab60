// Must NOT compile: an ECEF position from float32 values.
#include "geoanchor/geodesy/positions.hpp"

geoanchor::geodesy::EcefPosition misuse(float x, float y, float z) { return geoanchor::geodesy::EcefPosition(x, y, z); }
