// Variance components of a network adjustment (AdjustOptions::
// variance_components, adjust --vce): network_vce.hpp.

#include "network_vce.hpp"

#include <Eigen/Cholesky>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "geoanchor/base/number_text.hpp"

namespace geoanchor::solver {
namespace {

using geodesy::MeasurementKind;
using Groups = AdjustOptions::VarianceGroups;

// The class of a terrestrial or GNSS observation, for --vce kind.
const char* kind_class(MeasurementKind k) {
  switch (k) {
    case MeasurementKind::gnss_baselines:
    case MeasurementKind::gnss_points: return "GNSS";
    case MeasurementKind::slope_distance:
    case MeasurementKind::horizontal_distance:
    case MeasurementKind::ellipsoid_arc:
    case MeasurementKind::chord_distance:
    case MeasurementKind::msl_arc: return "distances";
    case MeasurementKind::direction:
    case MeasurementKind::horizontal_angle: return "directions and horizontal angles";
    case MeasurementKind::zenith_angle:
    case MeasurementKind::vertical_angle: return "zenith and vertical angles";
    case MeasurementKind::azimuth:
    case MeasurementKind::astronomic_azimuth: return "azimuths";
    case MeasurementKind::height_difference: return "levelled height differences";
    case MeasurementKind::ellipsoidal_height:
    case MeasurementKind::orthometric_height: return "heights";
    case MeasurementKind::geodetic_latitude:
    case MeasurementKind::geodetic_longitude:
    case MeasurementKind::astronomic_latitude:
    case MeasurementKind::astronomic_longitude: return "latitudes and longitudes";
    case MeasurementKind::observation_set: return "observation sets";
  }
  return "other";
}

std::string group_of(const geodesy::Network& net, const geodesy::NetworkMeasurement& m, Groups by) {
  switch (by) {
    case Groups::kind: {
      if (m.kind != MeasurementKind::observation_set) return kind_class(m.kind);
      // A set of one class is that class; a mixed one its own group.
      const std::string first = kind_class(m.parts.front().kind);
      for (const auto& part : m.parts) {
        if (kind_class(part.kind) != first) return "observation sets";
      }
      return first;
    }
    case Groups::group: return m.group.empty() ? "(no group)" : m.group;
    case Groups::model: return m.error_model ? net.error_models[*m.error_model].name : "(no error model)";
    case Groups::none: break;
  }
  return "";
}

}  // namespace

AdjustmentResult adjust_with_variance_components(const geodesy::Network& network, const AdjustOptions& options,
                                                 const std::function<AdjustmentResult(const geodesy::Network&, const AdjustOptions&)>& adjust) {
  // The groups, in the order their first measurement comes.
  std::vector<std::string> names;
  std::map<std::string, std::size_t> index;
  std::vector<std::size_t> group(network.measurements.size(), 0);
  for (std::size_t mi = 0; mi < network.measurements.size(); ++mi) {
    const std::string name = group_of(network, network.measurements[mi], options.variance_components);
    const auto [it, added] = index.emplace(name, names.size());
    if (added) names.push_back(name);
    group[mi] = it->second;
  }
  std::vector<double> factor(names.size(), 1.0);
  std::vector<VarianceComponent> components(names.size());
  AdjustOptions estimation = options;
  estimation.variance_components = Groups::none;
  estimation.data_snooping = false;
  estimation.remove_outliers = false;
  // What the estimation does not read is left to the final adjustment:
  // external reliability (a solve per component) and the relative
  // precision of the pairs asked for.
  estimation.external_reliability = false;
  estimation.relative = RelativeOptions{};
  geodesy::Network scaled = network;
  int iterations = 0;
  bool converged = false;
  while (!converged && iterations < kMaxVceIterations) {
    ++iterations;
    for (std::size_t mi = 0; mi < scaled.measurements.size(); ++mi) {
      scaled.measurements[mi].covariance = network.measurements[mi].covariance * factor[group[mi]];
    }
    const AdjustmentResult r = adjust(scaled, estimation);
    // Per group: Ω_k = Σ vᵢᵀ Σᵢ⁻¹ vᵢ and r_k = Σ redundancy, over the
    // measurements in the adjustment.
    std::vector<double> omega(names.size(), 0.0), redundancy(names.size(), 0.0);
    std::vector<std::size_t> count(names.size(), 0);
    for (const auto& am : r.measurements) {
      if (!am.used) continue;
      const std::size_t k = group[am.index];
      const Eigen::LLT<Eigen::MatrixXd> llt(scaled.measurements[am.index].covariance);
      omega[k] += am.residual.dot(llt.solve(am.residual));
      redundancy[k] += am.redundancy.sum();
      ++count[k];
    }
    converged = true;
    for (std::size_t k = 0; k < names.size(); ++k) {
      VarianceComponent& c = components[k];
      c.name = names[k];
      c.measurements = count[k];
      c.redundancy = redundancy[k];
      c.estimated = redundancy[k] >= kMinVceRedundancy;
      if (!c.estimated) continue;
      const double update = omega[k] / redundancy[k];  // θ_k ← θ_k · Ω_k / r_k
      converged = converged && std::fabs(update - 1.0) <= kVceTolerance;
      factor[k] *= update;
    }
  }
  for (std::size_t mi = 0; mi < scaled.measurements.size(); ++mi) {
    scaled.measurements[mi].covariance = network.measurements[mi].covariance * factor[group[mi]];
  }
  AdjustOptions final_options = options;
  final_options.variance_components = Groups::none;
  AdjustmentResult result = adjust(scaled, final_options);
  for (std::size_t k = 0; k < names.size(); ++k) {
    VarianceComponent& c = components[k];
    c.factor = factor[k];
    c.sigma = c.estimated ? factor[k] * std::sqrt(2.0 / c.redundancy) : 0.0;
  }
  result.variance_components = components;
  result.vce_iterations = iterations;
  if (!converged) {
    result.warnings.push_back("variance components did not converge in " + std::to_string(kMaxVceIterations) +
                              " adjustments; the factors of the last are used");
  }
  for (const auto& c : components) {
    if (!c.estimated && c.measurements > 0) {
      result.warnings.push_back("variance component '" + c.name + "' not estimated: its redundancy " +
                                format_fixed(c.redundancy, 2) + " is below " + format_shortest(kMinVceRedundancy) +
                                "; its factor is kept at 1");
    }
  }
  return result;
}

}  // namespace geoanchor::solver
