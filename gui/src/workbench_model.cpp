#include "geoanchor/gui/workbench_model.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <numbers>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/workflow/fit_checks.hpp"
#include "geoanchor/workflow/fit_export.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/io/transform/transform_file.hpp"

namespace geoanchor::gui {

WorkbenchModel::WorkbenchModel(geodesy::ControlSet control, solver::FitOptions options, std::size_t async_from_points,
                               const std::vector<std::string>& left_out)
    : control_(std::move(control)), options_(std::move(options)), async_from_points_(async_from_points) {
  // The plan: source positions in ENU at their centroid (WGS 84 normal; the
  // plan is a picture, metres to a part in 10⁶).
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : control_.points) mean += p.source.m;
  if (!control_.points.empty()) mean /= static_cast<double>(control_.points.size());
  const geodesy::GeocentricConverter wgs84(geodesy::Ellipsoid::wgs84());
  plan_origin_.point = wgs84.geodetic_from_ecef(geodesy::EcefPosition(mean));
  plan_origin_.ellipsoid = geodesy::Ellipsoid::wgs84();
  const geodesy::LocalTangentPlane plane(plan_origin_);
  for (const auto& p : control_.points) {
    plan_en_m_.push_back(plane.enu_from_ecef(p.source).enu_m.head<2>());
    use_in_file_.push_back(p.use);
  }
  for (const auto& id : left_out) {
    for (auto& p : control_.points) {
      if (p.id == id) p.use = false;
    }
  }
  refit();
}

WorkbenchModel::~WorkbenchModel() = default;  // the worker finishes first (LatestOnWorker)

void WorkbenchModel::set_left_out(std::string_view id, bool left_out) {
  bool changed = false;
  for (std::size_t i = 0; i < control_.points.size(); ++i) {
    auto& p = control_.points[i];
    if (p.id == id && use_in_file_[i] && p.use == left_out) {
      p.use = !left_out;
      changed = true;
    }
  }
  if (changed) refit();
}

void WorkbenchModel::set_model(solver::FitModel model) {
  options_.model = model;
  refit();
}

void WorkbenchModel::set_convention(solver::Convention convention) {
  options_.convention = convention;
  refit();
}

WorkbenchModel::Outcome WorkbenchModel::run_fit(const geodesy::ControlSet& control, const solver::FitOptions& options) {
  Outcome out;
  try {
    out.fit = solver::fit_helmert(control, options);
  } catch (const Error& e) {
    out.error = e.what();
  }
  try {
    out.comparison = solver::compare_models(control, options);
  } catch (const Error&) {
    // Each model's refusal is in its row; a set too small for any is shown by the fit's error.
  }
  return out;
}

void WorkbenchModel::take(Outcome outcome) {
  fit_ = std::move(outcome.fit);
  error_ = std::move(outcome.error);
  comparison_ = std::move(outcome.comparison);
  ++generation_;
}

void WorkbenchModel::refit() {
  if (control_.points.size() < async_from_points_) {
    take(run_fit(control_, options_));
    return;
  }
  worker_.start([control = control_, options = options_] { return run_fit(control, options); });
}

bool WorkbenchModel::poll() {
  bool again = false;
  auto outcome = worker_.take_ready(again);
  if (!outcome) return false;
  take(std::move(*outcome));
  if (again) refit();
  return true;
}

void WorkbenchModel::wait() {
  while (busy()) {
    worker_.wait_running();
    poll();
  }
}

std::vector<std::string> WorkbenchModel::left_out() const {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < control_.points.size(); ++i) {
    if (use_in_file_[i] && !control_.points[i].use) out.push_back(control_.points[i].id);
  }
  return out;
}

void WorkbenchModel::save_transform(const std::string& path, bool overwrite, const std::string& generator) const {
  if (!fit_) {
    throw Error(ErrorKind::rejected, "E_FIT_NONE", path + ": no transform to save: " + (error_.empty() ? "no fit" : error_));
  }
  // The same refusals as `geoanchor fit` (the window has no
  // --accept-failed-global-test: a failing fit is explored, not saved).
  if (const auto refusal = workflow::fit_refusal(*fit_, control_.source_name, false)) {
    throw Error(ErrorKind::rejected, refusal->code, refusal->message);
  }
  io::AtomicOutputFile out(path, overwrite ? io::Overwrite::allow : io::Overwrite::refuse);
  out.stream() << io::to_json_text(workflow::transform_file_from_fit(*fit_, control_, options_, left_out(), generator));
  out.commit();
}

Eigen::Matrix2d residual_covariance_en_m2(const solver::FitResult& fit, const geodesy::ControlSet& control, std::size_t index) {
  // The solver's own: the covariance its point tests use (one implementation).
  if (index >= control.points.size() || index >= fit.points.size()) {
    return Eigen::Matrix2d::Constant(std::numeric_limits<double>::quiet_NaN());
  }
  return fit.points[index].residual_cov_enu_m2.topLeftCorner<2, 2>();
}

Ellipse confidence_ellipse(const Eigen::Matrix2d& cov_en_m2, double k) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (!cov_en_m2.allFinite() || !(k >= 0.0)) return {nan, nan, nan};
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(0.5 * (cov_en_m2 + cov_en_m2.transpose()));
  const Eigen::Vector2d lambda = es.eigenvalues();  // ascending
  // A residual covariance is positive semi-definite; allow rounding below zero.
  const double scale = std::max(std::abs(lambda(1)), 1e-300);
  if (!(lambda(0) >= -1e-9 * scale)) return {nan, nan, nan};
  const Eigen::Vector2d major = es.eigenvectors().col(1);  // (E, N)
  double azimuth = std::atan2(major.x(), major.y());
  if (azimuth < 0.0) azimuth += std::numbers::pi;
  if (azimuth >= std::numbers::pi) azimuth -= std::numbers::pi;
  return {k * std::sqrt(std::max(lambda(1), 0.0)), k * std::sqrt(std::max(lambda(0), 0.0)), azimuth};
}

double chi2_2d_factor(double p) { return std::sqrt(-2.0 * std::log1p(-p)); }

std::vector<std::string> shown_warnings(const solver::FitResult& fit) {
  const std::string advice = "; consider --model " + std::string(solver::to_string(fit.model));
  std::vector<std::string> out;
  for (std::string w : fit.warnings) {
    for (auto at = w.find(advice); at != std::string::npos; at = w.find(advice)) {
      const auto end = at + advice.size();
      // Only the whole advice: "--model helmert7" is not "--model helmert7x".
      if (end < w.size() && (std::isalnum(static_cast<unsigned char>(w[end])) || w[end] == '-' || w[end] == '_')) break;
      w.erase(at, advice.size());
    }
    out.push_back(std::move(w));
  }
  return out;
}

std::vector<PointRow> WorkbenchModel::rows() const {
  std::vector<PointRow> out;
  for (std::size_t i = 0; i < control_.points.size(); ++i) {
    PointRow r;
    r.id = control_.points[i].id;
    r.plan_en_m = plan_en_m_[i];
    r.left_out = !control_.points[i].use;
    if (fit_ && i < fit_->points.size()) {
      const auto& p = fit_->points[i];
      r.residual_enu_mm = 1000.0 * p.residual_enu_m;
      Eigen::Index worst = 0;
      p.w_enu.cwiseAbs().maxCoeff(&worst);
      r.w_test = p.w_enu(worst);
      r.mdb_mm = 1000.0 * p.mdb_m;
      r.used = p.used;
      r.outlier = p.outlier;
      r.note = p.removed_because;
      r.residual_cov_en_m2 = residual_covariance_en_m2(*fit_, control_, i);
    } else {
      r.used = false;
    }
    out.push_back(r);
  }
  return out;
}

std::vector<ParameterRow> WorkbenchModel::parameters() const {
  std::vector<ParameterRow> out;
  if (!fit_) return out;
  for (const auto& p : fit_->parameters) {
    if (p.estimated) out.push_back({p.name, p.value, p.sigma});
  }
  return out;
}

}  // namespace geoanchor::gui
