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
  // What a reader must know to read the row, or empty: for
  // molodensky-badekas, that it is helmert7 about a pivot (same residuals,
  // σ0, global test and AIC; other parameters).
  std::string note;
};

// translation3 always; helmert6, helmert7 and molodensky-badekas when `base`
// has a convention (molodensky-badekas about `base.pivot_m`, else the
// centroid); helmert14 when every point has an epoch and they differ; enu-origin and
// site-calibration when `base` has a nominal origin. Data snooping is off,
// so that every model sees the same points and the AIC compares like with
// like.
std::vector<ModelComparison> compare_models(const geodesy::ControlSet& set, const FitOptions& base);

// The models at the lowest AIC, in the comparison's order: more than one
// when they tie (helmert7 and molodensky-badekas always do: one is the
// other's reparametrisation). Ties are AICs within kAicTie of each other,
// far below any difference that carries evidence (~2) and far above the
// solver's rounding. Empty when every model was refused.
inline constexpr double kAicTie = 1e-6;
std::vector<FitModel> lowest_aic(const std::vector<ModelComparison>& rows);

}  // namespace geoanchor::solver
