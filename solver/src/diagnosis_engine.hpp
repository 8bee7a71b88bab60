#pragma once
// What the diagnosis's hypotheses (diagnosis.hpp) work on: the used points
// and their noise, the residuals of a model or of the declared model
// fitted again (Engine), the discrepancy from what the declared frames lead
// one to expect (Expectation), and the helpers they share.
//
// Private to solver.

#include <Eigen/Core>

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "geoanchor/geodesy/affine.hpp"
#include "geoanchor/geodesy/control_point.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/solver/diagnosis.hpp"

namespace geoanchor::solver::diagnosis_detail {

using Vectors = std::vector<Eigen::Vector3d>;

inline constexpr double kLn10 = 2.302585092994046;

std::string fmt(double v, int decimals);
std::string role_name(bool source);
double rms(const Vectors& v);
double chi2(const Vectors& r, const std::vector<double>& sigma);
// A point's epoch, else the target frame's, else the source frame's.
std::optional<geodesy::DecimalYear> epoch_of(const geodesy::ControlSet& set, const geodesy::ControlPoint& p);

// The discrepancies of the used points under a model: given transform
// (optionally another map) or the declared model fitted again.
struct Engine {
  const geodesy::ControlSet& set;
  const DiagnoseOptions& options;
  std::vector<std::size_t> used;
  std::vector<double> sigma;  // per used point, m (1σ per coordinate)
  double noise_rms = 0.0;
  geodesy::GeocentricConverter source_geocentric, target_geocentric;  // each frame's ellipsoid

  Engine(const geodesy::ControlSet& s, const DiagnoseOptions& o);

  FitOptions fit_options() const;

  // Residuals t − model(s) of the used points; nullopt when the model cannot
  // be evaluated on `s` (a refused fit, a non-finite position).
  std::optional<Vectors> residuals(const geodesy::ControlSet& s, const PointMap* map) const;

  std::optional<Vectors> baseline_residuals(const geodesy::ControlSet& s) const;
};

// The discrepancy from what the declared frames (or the given transform) lead
// one to expect, per used point.
struct Expectation {
  std::optional<Vectors> discrepancy;  // t − E(s)
  std::string description;
  std::optional<geodesy::AffineMap> map;  // E as one affine map when it is a catalog path at one epoch
  std::optional<geodesy::DecimalYear> epoch;
};

Expectation expectation(const Engine& e);

// A hypothesis that does not apply here, and why.
HypothesisResult not_applicable(Hypothesis name, double rms_base, std::string why);

}  // namespace geoanchor::solver::diagnosis_detail
