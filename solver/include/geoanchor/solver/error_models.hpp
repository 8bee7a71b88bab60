#pragma once
// Instruments' error models (geodesy::ErrorModel) added to the
// measurements' covariances from the network's geometry: the a-priori
// positions of the stations, the instrument's horizon (the ellipsoid's
// normal at the instrument; a local network's x, y plane and z).
//
// Per observation, in quadrature with its own standard deviation (one
// observation's terms: no correlation between the observations of one
// set-up; docs/network-format.md "Error models" states each term):
//  - distance D (slope, horizontal, ellipsoid arc, chord, MSL arc):
//    c² + (ppm·D)²;
//  - direction, azimuth: pointing² + reading²; horizontal angle: twice
//    that (two pointings, two readings);
//  - zenith and vertical angles: their own pointing² + reading²;
//  - the set-up, for each of these: the observation's gradient g with
//    respect to the instrument point (and the target point) taken into
//    that station's own horizon, σ_centring² (g_e² + g_n²) + σ_height² g_u²:
//    to first order the classical terms (a direction (σ_ci² + σ_ct²)/D²,
//    a horizontal angle's instrument σ_ci² D₃²/(D₁² D₂²), a zenith angle's
//    heights σ_h² sin²z/S², a slope distance's centring σ_c² sin²z);
//  - GNSS baselines: in the horizon at the first station diag(σ_H², σ_H²,
//    σ_V²), σ_H² = c_H² + (ppm_H·L)², σ_V² likewise, plus each end's
//    set-up (the instrument's centring and height errors: both ends are an
//    antenna's set-up); GNSS points: the constants and the set-up.
// Levelled height differences and heights: none of these terms applies.

#include "geoanchor/geodesy/network.hpp"

namespace geoanchor::solver {

// Adds each measurement's error model to its covariance, once (adjust's
// preparation calls it). Throws geoanchor::Error (input,
// E_ERROR_MODEL) naming the measurement for a model whose terms need a
// station without a-priori position, or a kind no term of the model
// applies to.
void apply_error_models(geodesy::Network& net);

}  // namespace geoanchor::solver
