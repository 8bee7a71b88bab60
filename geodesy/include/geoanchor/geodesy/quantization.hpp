#pragma once
// Whether numbers as read carry the trace of a float32 store: coordinates
// written from a 4-byte float (an exporter's float32 ECEF column, a PLY
// float property) are quantized to the float32 spacing at their magnitude,
// 0.5 m for ECEF values between 2²² and 2²³ m (4.2–8.4 Mm): far coarser than
// any survey. Integer metres at ECEF magnitudes are float32 values too, and
// just as coarse.

namespace geoanchor::geodesy {

// Whether `x`, as decimal text read back, is a float32 value: within the
// rounding of 9 significant digits (what float32's shortest round trip needs)
// of the nearest float32.
bool is_float32_valued(double x);

// The spacing of float32 values at |x| (the step to the next float32 away
// from zero), in x's units.
double float32_spacing(double x);

}  // namespace geoanchor::geodesy
