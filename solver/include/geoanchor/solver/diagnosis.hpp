#pragma once
// `geoanchor diagnose`: which classic mistake explains a bad fit.
//
// The discrepancy is measured first: with a given transform T (a published
// set, an earlier fit) the residuals t − T(s); without one, the residuals of
// the declared model fitted to the set. Then each classic mistake is tested
// as a hypothesis, in one of two ways:
//  - correction: the data (or T) are read again as the mistake would have it
//    (latitude and longitude swapped, radians read as degrees, Web Mercator
//    read as UTM, another UTM zone or hemisphere, the other rotation
//    convention), the residuals recomputed (T applied again, or the model
//    fitted again) and compared;
//  - signature: the whole discrepancy from what the declared frames lead one
//    to expect, A = t − E(s) (E: the catalog's path between the declared
//    frames at their epoch, T when given, the identity when no frames are
//    declared), is compared with the mistake's predicted effect (the EGM96
//    undulation along the vertical; the catalog's transformation to another
//    frame; plate velocity × Δt; a rigid shift and yaw at the ENU origin).
//
// Evidence is a log10 Bayes factor against "no mistake", with the noise of
// each point (its a-priori covariances, or an assumed sigma) and Gaussian
// priors on what a hypothesis estimates (a common offset within the effect's
// own uncertainty, Δt, the origin shift and yaw), so that a hypothesis with
// free parameters pays for them (Occam factor) and trying several variants
// (zones, frames, plates) costs log10 of their number. A hypothesis
// explains the data when that evidence is decisive (≥ 2, Jeffreys), what it
// estimates is plausible (within 5σ of its prior), and what it leaves is at
// the noise level (≤ 2 × the noise RMS) or a tenth of the
// discrepancy. Scores of hypotheses that do not explain the data are capped
// just below 2. Explanations rank first, those that estimate fewer
// parameters before the others (Occam: a predicted effect that matches beats
// a fitted one that matches as well), and scores are clamped to be
// non-increasing down the ranking.

#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "geoanchor/geodesy/control_point.hpp"
#include "geoanchor/geodesy/geoid.hpp"
#include "geoanchor/solver/helmert_fit.hpp"

namespace geoanchor::solver {

enum class Hypothesis {
  convention_swap,
  lat_lon_swap,
  degrees_radians,
  height_type,
  datum_mix,
  epoch,
  web_mercator,
  utm_zone,
  float32_ecef,
  enu_origin,
};
std::string_view to_string(Hypothesis h);
inline constexpr int kHypothesisCount = 10;

// A transform that is applied, not fitted: `apply` maps a source position at
// an epoch to the target; `apply_swapped` does the same with its rotations
// read in the other convention (empty when it has no rotations).
using PointMap = std::function<geodesy::EcefPosition(const geodesy::EcefPosition&, std::optional<geodesy::DecimalYear>)>;
struct GivenTransform {
  PointMap apply;
  PointMap apply_swapped;
  std::string description;  // "T.json (helmert7, coordinate_frame)"
};

struct DiagnoseOptions {
  FitOptions fit;                           // the declared model, when no transform is given
  std::optional<GivenTransform> transform;  // applied instead of fitting
  const geodesy::GeoidGrid* geoid = nullptr;  // EGM96, for height_type (skipped when null)
  // Noise per coordinate (m, 1σ) for a set without a-priori sigmas.
  double assumed_sigma_m = 0.01;
};

// Log10 Bayes factor at which a hypothesis is decisive (Jeffreys' scale).
inline constexpr double kDecisiveLog10BayesFactor = 2.0;

struct HypothesisResult {
  Hypothesis name = Hypothesis::convention_swap;
  bool applicable = false;  // false: `effect` says why it could not be tested
  bool explains = false;
  double score = 0.0;       // log10 Bayes factor (capped below 2 unless it explains)
  double rms_before_m = 0.0;  // RMS of the 3-D discrepancy it was tested on
  double rms_after_m = 0.0;   // what is left once the mistake is undone
  // What the hypothesis estimates beyond its predicted effect (Δt: 1; origin
  // shift and yaw: 4); offsets that only absorb the effect's own uncertainty
  // are not counted.
  int estimated_parameters = 0;
  int variants_tried = 0;
  // Signature hypotheses: what they estimate lies within 5σ of its prior
  // (an offset within the effect's own uncertainty, |Δt| ≤ 50 yr, an origin
  // error ≤ 500 m), and the effect beats that offset alone decisively;
  // otherwise they cannot explain the data.
  bool plausible = true;
  std::string effect;  // what the best variant says, with its size
};

struct Diagnosis {
  bool problem_found = false;
  std::string verdict;      // one sentence
  std::string baseline;     // how the residuals were obtained
  std::string expectation;  // what E is
  double residual_rms_m = 0.0;  // of the baseline
  std::optional<double> departure_rms_m;  // of t − E(s), when E is known
  double noise_rms_m = 0.0;     // expected RMS of a 3-D discrepancy from noise alone
  bool sigmas_assumed = false;  // the set gave none: assumed_sigma_m was used
  std::optional<bool> global_test_passed;  // baseline fit with a-priori sigmas
  int points_used = 0;
  std::vector<HypothesisResult> hypotheses;  // all ten, best first
};

// Throws geoanchor::Error: `rejected` when the baseline itself cannot be
// computed (the fit refuses the set), `input` from the given transform.
Diagnosis diagnose(const geodesy::ControlSet& set, const DiagnoseOptions& options);

}  // namespace geoanchor::solver
