#pragma once
// Decimal degrees written as sexagesimal text DDD-MM-SS.ssssss (rounded to
// a micro-arc-second), as the tests write STAR*NET and network JSON angles
// from one truth. Non-negative input.

#include <cmath>
#include <cstdio>
#include <string>

namespace geoanchor::testing {

inline std::string dms_micro_text(double deg) {
  long micro = std::lround(deg * 3600.0 * 1e6);  // micro-arc-seconds
  const long d = micro / 3600000000L;
  micro -= d * 3600000000L;
  const long m = micro / 60000000L;
  micro -= m * 60000000L;
  char buf[64];
  std::snprintf(buf, sizeof buf, "%ld-%02ld-%09.6f", d, m, static_cast<double>(micro) * 1e-6);
  return buf;
}

}  // namespace geoanchor::testing
