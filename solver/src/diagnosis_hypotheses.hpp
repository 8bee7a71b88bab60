#pragma once
// The diagnosis's hypotheses (diagnosis.hpp), one function each: the
// corrections re-read the data as the mistake would have it and compare the
// residuals with the baseline's (diagnosis_corrections.cpp); the signatures
// test the discrepancy from the expectation for the mistake's predicted
// pattern (diagnosis_signatures.cpp).
//
// Private to solver.

#include "diagnosis_engine.hpp"

namespace geoanchor::solver::diagnosis_detail {

// Corrections, against the baseline residuals `base`.
HypothesisResult lat_lon_swap(const Engine& e, const Vectors& base);
HypothesisResult degrees_radians(const Engine& e, const Vectors& base);
HypothesisResult web_mercator(const Engine& e, const Vectors& base);
HypothesisResult utm_zone(const Engine& e, const Vectors& base);
HypothesisResult convention_swap_correction(const Engine& e, const Vectors& base);
HypothesisResult float32_ecef(const Engine& e, const Vectors& base);

// Signatures, on the expectation's discrepancy (`rms_base`: the baseline's
// residual RMS, for a hypothesis that does not apply).
HypothesisResult height_type(const Engine& e, const Expectation& x, double rms_base);
HypothesisResult epoch_hypothesis(const Engine& e, const Expectation& x, double rms_base);
HypothesisResult enu_origin(const Engine& e, const Expectation& x, double rms_base);
HypothesisResult datum_mix(const Engine& e, const Expectation& x, double rms_base);
HypothesisResult convention_swap_signature(const Engine& e, const Expectation& x, double rms_base);

}  // namespace geoanchor::solver::diagnosis_detail
