#pragma once

#include "geoanchor/solver/helmert_fit.hpp"

namespace geoanchor::solver {

// The enu-origin model (see FitModel). Called by fit_helmert.
FitResult fit_enu_origin(const geodesy::ControlSet& control, const FitOptions& options);

// The site-calibration model (see FitModel). Called by fit_helmert.
FitResult fit_site_calibration(const geodesy::ControlSet& control, const FitOptions& options);

}  // namespace geoanchor::solver
