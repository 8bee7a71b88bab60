#pragma once
// The float32 value nearest to a double, as a double: what a coordinate
// keeps when it is stored in a 4-byte float (a PLY float property, a float32
// ECEF column). IEEE 754 round to nearest, ties to even; NaN stays NaN and
// ±infinity stays ±infinity. `v` must lie within float's range (|v| ≤
// FLT_MAX), as a value read from a float property does.
//
// A plain inline narrowing, as the PLY reader and diagnose use it. It is
// correct because the build turns GCC 12's basic-block (SLP) vectorizer off
// for every target (cmake/GeoanchorCompilerWorkarounds.cmake): that pass
// compiles double → float → double round trips stored side by side into a
// copy of the doubles ({round(x0), round(x1), round(x2)} keeps x0 and x1
// unrounded; seen in a test's Eigen::Vector3d and in another's array
// initializer, before the workaround was one out-of-line function per call
// site). tests/geodesy/float32_test.cpp fails without the flag.

namespace geoanchor::geodesy {

constexpr double round_to_float32(double v) { return static_cast<float>(v); }

}  // namespace geoanchor::geodesy
