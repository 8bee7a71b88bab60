#pragma once
// What the residual workbench shows and changes, without any window: the
// control set, the user's choices (model, convention, points left out) and
// the fit that follows from them. Both GUI shells (GLFW window, OSMesa
// snapshot) draw from this; tests drive it directly.

#include <Eigen/Core>

#include <future>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "geoanchor/geodesy/control_point.hpp"
#include "geoanchor/geodesy/positions.hpp"
#include "geoanchor/gui/latest_on_worker.hpp"
#include "geoanchor/solver/helmert_fit.hpp"
#include "geoanchor/solver/model_comparison.hpp"

namespace geoanchor::gui {

// One row of the point table.
struct PointRow {
  std::string id;
  Eigen::Vector2d plan_en_m = Eigen::Vector2d::Zero();         // source position, ENU at the network's centroid
  Eigen::Vector3d residual_enu_mm = Eigen::Vector3d::Zero();  // target − transformed source
  double w_test = 0.0;                                         // of largest magnitude, signed
  double mdb_mm = 0.0;
  bool used = true;           // entered the final fit
  bool outlier = false;       // removed by data snooping
  bool left_out = false;      // the user left it out
  std::string note;           // why it was not used
  // The covariance of the horizontal residual (E, N, m²) under the fit: the
  // a-posteriori residual covariance Q_v = C − A Σθ Aᵀ of a mark in the fit,
  // C + A Σθ Aᵀ of a mark tested against it (outliers, marks not used); C the
  // mark's a-priori covariance as the solver weights it (target + J source
  // Jᵀ, × the --vce factors, ÷ a robust weight), both × σ0² when the fit's
  // covariance is. See residual_covariance_en_m2().
  Eigen::Matrix2d residual_cov_en_m2 = Eigen::Matrix2d::Constant(std::numeric_limits<double>::quiet_NaN());
};

// The covariance of `point`'s horizontal residual (local E, N, m²) under
// `fit`, as PointRow::residual_cov_en_m2 says: the solver's own
// (solver::PointResult::residual_cov_enu_m2, what its point tests use); for
// site-calibration in grid E, N. NaN for an index outside the set.
Eigen::Matrix2d residual_covariance_en_m2(const solver::FitResult& fit, const geodesy::ControlSet& control, std::size_t index);

// The half-axes (a ≥ b, metres) and the azimuth of a (radians east of
// north) of the ellipse { x : xᵀ Q⁻¹ x ≤ k² } of a 2 × 2 covariance Q (E, N,
// m²); NaN when Q is not a finite positive semi-definite matrix.
struct Ellipse {
  double a_m = 0.0, b_m = 0.0, azimuth_rad = 0.0;
};
Ellipse confidence_ellipse(const Eigen::Matrix2d& cov_en_m2, double k);
// k for a two-dimensional normal at probability p: sqrt(χ²₂(p)) = sqrt(−2 ln(1 − p)).
double chi2_2d_factor(double p);

// The fit's warnings as a report or view shows them: advice to switch to
// the model that was fitted ("consider --model molodensky-badekas" on a
// molodensky-badekas fit) is dropped from the warning that carries it, so
// that no report advises the model it is about.
std::vector<std::string> shown_warnings(const solver::FitResult& fit);

// One parameter with its unit and σ, as the solver reports it.
struct ParameterRow {
  std::string name;  // tx_m, rx_arcsec, ds_ppm, ...
  double value = 0.0;
  double sigma = 0.0;
};

class WorkbenchModel {
 public:
  // Sets with at least this many points refit on a worker thread, so that
  // a window keeps drawing the last fit meanwhile.
  static constexpr std::size_t kDefaultAsyncFrom = 2000;

  // Fits at once (on the worker for large sets); a refused fit leaves fit()
  // empty and error() saying why. `left_out`: ids the user left out before
  // (e.g. recorded in a transform file); unknown ids are ignored.
  WorkbenchModel(geodesy::ControlSet control, solver::FitOptions options,
                 std::size_t async_from_points = kDefaultAsyncFrom, const std::vector<std::string>& left_out = {});
  ~WorkbenchModel();
  WorkbenchModel(const WorkbenchModel&) = delete;
  WorkbenchModel& operator=(const WorkbenchModel&) = delete;

  // The user's choices; each refits (on the worker thread for large sets:
  // the shown fit changes when poll() takes the result).
  void set_left_out(std::string_view id, bool left_out);  // no-op for an unknown id
  void set_model(solver::FitModel model);
  void set_convention(solver::Convention convention);

  const solver::FitOptions& options() const { return options_; }
  const geodesy::ControlSet& control() const { return control_; }
  const std::optional<solver::FitResult>& fit() const { return fit_; }
  const std::string& error() const { return error_; }
  // Increments with every refit, so that views can tell a new result.
  unsigned generation() const { return generation_; }

  std::vector<PointRow> rows() const;
  std::vector<ParameterRow> parameters() const;
  // The same points (those not left out) under every applicable model, for
  // the comparison panel: what `geoanchor fit --compare` prints. Computed
  // with each refit (on the worker thread for large sets).
  const std::vector<solver::ModelComparison>& comparison() const { return comparison_; }
  // The ids the user left out (control points with use = 0 in the file are
  // not among them).
  std::vector<std::string> left_out() const;
  // The shown fit as the transform file `geoanchor fit -o` writes, the left-out
  // points noted as such. Throws geoanchor::Error (rejected) without a fit,
  // (io) when the file cannot be written or exists and overwrite is false.
  void save_transform(const std::string& path, bool overwrite, const std::string& generator) const;
  // The network's centroid, origin of the plan view.
  const geodesy::LocalOrigin& plan_origin() const { return plan_origin_; }

  // A refit is running or waiting to run.
  bool busy() const { return worker_.busy(); }
  // Takes a finished refit, if any, and starts the next one if the choices
  // changed meanwhile; true when the shown fit changed. Call once a frame.
  bool poll();
  // Until the fit shown is the one for the current choices.
  void wait();

 private:
  struct Outcome {
    std::optional<solver::FitResult> fit;
    std::string error;
    std::vector<solver::ModelComparison> comparison;
  };
  static Outcome run_fit(const geodesy::ControlSet& control, const solver::FitOptions& options);
  void refit();
  void take(Outcome outcome);
  geodesy::ControlSet control_;
  solver::FitOptions options_;
  std::vector<bool> use_in_file_;  // the control set's own use flags
  std::optional<solver::FitResult> fit_;
  std::vector<solver::ModelComparison> comparison_;
  std::string error_;
  unsigned generation_ = 0;
  geodesy::LocalOrigin plan_origin_;
  std::vector<Eigen::Vector2d> plan_en_m_;
  std::size_t async_from_points_;
  LatestOnWorker<Outcome> worker_;
};

}  // namespace geoanchor::gui
