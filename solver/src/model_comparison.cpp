#include "geoanchor/solver/model_comparison.hpp"

#include <algorithm>
#include <cmath>

#include "geoanchor/base/error.hpp"

namespace geoanchor::solver {

std::vector<ModelComparison> compare_models(const geodesy::ControlSet& set, const FitOptions& base) {
  std::vector<FitModel> models = {FitModel::translation3};
  if (base.convention) {
    models.push_back(FitModel::helmert6);
    models.push_back(FitModel::helmert7);
    models.push_back(FitModel::molodensky_badekas);
    bool epochs = !set.points.empty();
    double lo = 1e300, hi = -1e300;
    for (const auto& p : set.points) {
      if (!p.epoch) {
        epochs = false;
        break;
      }
      lo = std::min(lo, p.epoch->year);
      hi = std::max(hi, p.epoch->year);
    }
    if (epochs && hi > lo) models.push_back(FitModel::helmert14);
  }
  if (base.nominal_origin) {
    models.push_back(FitModel::enu_origin);
    models.push_back(FitModel::site_calibration);
  }
  std::vector<ModelComparison> out;
  for (FitModel m : models) {
    ModelComparison c;
    c.model = m;
    FitOptions fo = base;
    fo.model = m;
    fo.data_snooping = false;
    if (m == FitModel::helmert14) fo.reference_epoch.reset();
    try {
      c.fit = fit_helmert(set, fo);
    } catch (const Error& e) {
      c.refused = e.what();
      out.push_back(std::move(c));
      continue;
    }
    const FitResult& r = *c.fit;
    for (const auto& p : r.parameters) c.parameters += p.estimated ? 1 : 0;
    for (const auto& p : r.points) {
      if (p.used) c.max_w = std::max(c.max_w, p.w_max);
    }
    const int obs = r.dof + c.parameters;
    c.aic = set.has_a_priori_sigmas ? r.global_test.statistic + 2.0 * c.parameters
                                    : obs * std::log(r.global_test.statistic / obs) + 2.0 * c.parameters;
    if (m == FitModel::molodensky_badekas) {
      c.note = "helmert7 about the pivot (" + std::string(base.pivot_m ? "given" : "the centroid of the used points") +
               "): the same residuals, σ0, global test and AIC as helmert7, other parameters (its translation is "
               "nearly uncorrelated with the rotations and scale)";
    }
    out.push_back(std::move(c));
  }
  return out;
}

std::vector<FitModel> lowest_aic(const std::vector<ModelComparison>& rows) {
  const ModelComparison* best = nullptr;
  for (const auto& c : rows) {
    if (c.fit && (!best || c.aic < best->aic)) best = &c;
  }
  std::vector<FitModel> out;
  for (const auto& c : rows) {
    if (c.fit && std::fabs(c.aic - best->aic) <= kAicTie) out.push_back(c.model);
  }
  return out;
}

}  // namespace geoanchor::solver
