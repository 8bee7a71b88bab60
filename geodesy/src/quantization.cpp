#include "geoanchor/geodesy/quantization.hpp"

#include <cmath>
#include <limits>

#include "geoanchor/geodesy/float32.hpp"

namespace geoanchor::geodesy {

bool is_float32_valued(double x) {
  const double f = round_to_float32(x);
  return std::fabs(x - f) <= 5e-9 * std::fabs(x) + 1e-12;
}

double float32_spacing(double x) {
  const auto f = static_cast<float>(std::fabs(round_to_float32(x)));  // exact: already a float32 value
  return static_cast<double>(std::nextafter(f, std::numeric_limits<float>::infinity()) - f);
}

}  // namespace geoanchor::geodesy
