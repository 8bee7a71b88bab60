#include "geoanchor/geodesy/float32.hpp"

namespace geoanchor::geodesy {

[[gnu::noinline]] double round_to_float32(double v) { return static_cast<float>(v); }

}  // namespace geoanchor::geodesy
