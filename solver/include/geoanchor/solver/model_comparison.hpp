#pragma once
// The same control points under every model the data allow, side by side:
// what `geoanchor fit --compare` prints and the workbench's comparison panel
// shows.

#include <optional>
#include <string>
#include <vector>

#include "geoanchor/geodesy/control_point.hpp"
#include "geoanchor/solver/helmert_fit.hpp"

namespace geoanchor::solver {

struct ModelComparison {
  FitModel model = FitModel::helmert7;
  std::optional<FitResult> fit;  // empty when the model was refused
  std::string refused;           // why, when it was
  int parameters = 0;            // estimated
  double max_w = 0.0;            // largest |w| over the used points
  // AIC = −2 ln L + 2u: Ω + 2u with a-priori sigmas, else
  // n ln(Ω / n) + 2u from the estimated variance (n observations).
  double aic = 0.0;
};

// translation3 always; helmert6 and helmert7 when `base` has a convention;
// helmert14 when every point has an epoch and they differ; enu-origin and
// site-calibration when `base` has a nominal origin. Data snooping is off,
// so that every model sees the same points and the AIC compares like with
// like.
std::vector<ModelComparison> compare_models(const geodesy::ControlSet& set, const FitOptions& base);

}  // namespace geoanchor::solver
