// The weighted Helmert fit's parameters as reported (helmert_weighted_fit.hpp):
// the geometry's weakest combination, the geocentric parameters and their
// covariance, the report's parameters with names and units, and the
// warnings about them.

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>

#include "fit_common.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "helmert_weighted_fit.hpp"

namespace geoanchor::solver {

using geodesy::Angle;
using geodesy::DecimalYear;

namespace {

constexpr double kPpm = 1e6;

// The parameters' names in the report, in θ's order.
constexpr const char* kParameterNames[kMaxParams] = {"tx_m", "ty_m", "tz_m", "rx_arcsec", "ry_arcsec", "rz_arcsec", "ds_ppm",
                                                     "dtx_m_per_year", "dty_m_per_year", "dtz_m_per_year", "drx_arcsec_per_year",
                                                     "dry_arcsec_per_year", "drz_arcsec_per_year", "dds_ppm_per_year"};

// Parameter k's unit factor from solver units, in the reported convention
// (`cf`: coordinate frame, rotations of the other sign).
double unit_factor(int k, bool cf) {
  const bool rotation = (k >= 3 && k <= 5) || (k >= 10 && k <= 12);
  const bool scale = k == 6 || k == 13;
  return rotation ? (cf ? -kArcsecPerRad : kArcsecPerRad) : scale ? kPpm : 1.0;
}

}  // namespace

// --- geometry: is every parameter determined? --------------------------
// The warning for a combination of parameters determined far less
// precisely than the translation (empty: none); refused past kRefuseDilution.
std::string WeightedFit::weak_geometry(const FitPass& current) const {
  const HelmertSolution& sol = current.sol;
  const Eigen::Vector3d& cx = current.cx;
  const std::vector<MarkObservation>& obs = current.obs;
  const int u = current.u;
  const GeometryDilution gd = geometry_dilution(sol.cov_scaled, {0, 1, 2});
  if (!(gd.dilution <= kWarnDilution)) {
    const char* short_names[kMaxParams] = {"tx", "ty", "tz", "rx", "ry", "rz", "ds", "dtx", "dty", "dtz", "drx", "dry", "drz", "dds"};
    // The combination, named by its largest components, and for a
    // rotation its axis in the network's local east, north, up.
    std::string combination;
    Eigen::Vector3d axis = Eigen::Vector3d::Zero();
    for (int a = 0; a < u; ++a) {
      const int k = sol.estimated[static_cast<std::size_t>(a)];
      if (k >= 3 && k <= 5) axis(k - 3) = gd.direction(a);
      if (std::fabs(gd.direction(a)) >= 0.3) {
        combination += (combination.empty() ? "" : " ") + std::string(gd.direction(a) < 0 ? "-" : "+") +
                       fmt(std::fabs(gd.direction(a)), 2) + "·" + short_names[k];
      }
    }
    std::string where;
    if (axis.norm() > 0.5) {
      const geodesy::LocalTangentPlane plane(geodesy::LocalOrigin{
          geodesy::geodetic_from_ecef(geodesy::Ellipsoid::wgs84(), geodesy::EcefPosition(cx)), geodesy::Ellipsoid::wgs84()});
      const Eigen::Vector3d enu = plane.enu_from_ecef_rotation() * axis.normalized();
      const double azimuth = std::fmod(std::atan2(enu.x(), enu.y()) * 180.0 / M_PI + 360.0, 180.0);
      const double elevation = std::asin(std::clamp(std::fabs(enu.z()), 0.0, 1.0)) * 180.0 / M_PI;
      where = ": mostly a rotation about the axis at azimuth " + format_fixed(azimuth, 1) + "°, elevation " +
              format_fixed(elevation, 1) + "° through the marks' centroid";
    }
    const double radius_m = parameter_scale(obs).l;
    const double sigma_m = std::sqrt(gd.direction.dot(sol.cov_scaled * gd.direction));  // displacement at radius_m
    const std::string what =
        "the marks' geometry leaves a combination of parameters (" + combination + ")" + where + " determined " +
        fmt(gd.dilution, 3) + " times less precisely than the translation: σ " + fmt(sigma_m, 3) +
        " m at the network's RMS radius of " + fmt(radius_m, 4) + " m (" + fmt(sigma_m / radius_m * kArcsecPerRad, 3) +
        "″)";
    if (!(gd.dilution <= kRefuseDilution)) {
      reject("E_FIT_WEAK_GEOMETRY", what + ": the marks are (nearly) collinear or otherwise degenerate for model " +
                                         std::string(to_string(o.model)) +
                                         "; add marks off their line, or fit a translation only (--model translation3)");
    }
    return "weak geometry: " + what;
  }
  return std::string();
}

// --- geocentric parameters and covariance ----------------------------
GeocentricEstimate WeightedFit::geocentric_estimate(const FitPass& current) {
  const HelmertSolution& sol = current.sol;
  const Eigen::Vector3d& cx = current.cx;
  const Eigen::Vector3d& cy = current.cy;
  const int u = current.u;
  GeocentricEstimate estimate;
  std::array<double, kMaxParams>& g = estimate.g;
  geocentric_from_centred(sol.theta.data(), cx, cy, o.rotation_model, g.data());
  using JetU = ceres::Jet<double, kMaxParams>;
  std::array<JetU, kMaxParams> tj, gj;
  for (int k = 0; k < kMaxParams; ++k) tj[static_cast<std::size_t>(k)] = JetU(sol.theta[static_cast<std::size_t>(k)], k);
  geocentric_from_centred(tj.data(), cx, cy, o.rotation_model, gj.data());
  Eigen::MatrixXd jac(u, u);  // ∂g/∂θ' restricted to the estimated parameters
  for (int a = 0; a < u; ++a) {
    for (int b = 0; b < u; ++b) {
      jac(a, b) = gj[static_cast<std::size_t>(sol.estimated[static_cast<std::size_t>(a)])].v[sol.estimated[static_cast<std::size_t>(b)]];
    }
  }
  Eigen::MatrixXd cov = jac * sol.cov_centred * jac.transpose();
  // Molodensky-Badekas reports the translation at the pivot p:
  // T_p = T + (1 + ds) R p − p = cy + t' + (1 + ds) R (p − cx) − p.
  std::array<double, kMaxParams> reported = g;
  const bool mb = o.model == FitModel::molodensky_badekas;
  if (mb) {
    const Eigen::Vector3d pivot = o.pivot_m.value_or(cx);
    result.pivot_m = pivot;
    auto to_pivot = [&](auto const* tc, auto* out) {
      using T = std::remove_const_t<std::remove_pointer_t<decltype(tc)>>;
      for (int k = 0; k < kMaxParams; ++k) out[k] = tc[k];
      const Eigen::Matrix<T, 3, 3> r = rotation_pv(tc + 3, o.rotation_model);
      const Eigen::Matrix<T, 3, 1> rp = r * (pivot - cx).cast<T>();
      for (int k = 0; k < 3; ++k) out[k] = T(cy(k)) + tc[k] + (T(1.0) + tc[6]) * rp(k) - T(pivot(k));
    };
    to_pivot(sol.theta.data(), reported.data());
    std::array<JetU, kMaxParams> pj;
    to_pivot(tj.data(), pj.data());
    Eigen::MatrixXd jp(u, u);
    for (int a = 0; a < u; ++a) {
      for (int b = 0; b < u; ++b) {
        jp(a, b) = pj[static_cast<std::size_t>(sol.estimated[static_cast<std::size_t>(a)])].v[sol.estimated[static_cast<std::size_t>(b)]];
      }
    }
    cov = jp * sol.cov_centred * jp.transpose();
  }
  estimate.reported = reported;
  estimate.cov = cov;
  estimate.mb = mb;
  return estimate;
}

void WeightedFit::set_helmert(const std::array<double, kMaxParams>& g) {
  auto& h = result.helmert;
  h.at_reference_epoch.t_m = Eigen::Vector3d(g[0], g[1], g[2]);
  h.at_reference_epoch.rx = Angle::radians(g[3]);
  h.at_reference_epoch.ry = Angle::radians(g[4]);
  h.at_reference_epoch.rz = Angle::radians(g[5]);
  h.at_reference_epoch.ds = geodesy::ScaleDifference::unitless(g[6]);
  h.rates.dt_m_per_year = Eigen::Vector3d(g[7], g[8], g[9]);
  h.rates.drx_per_year = Angle::radians(g[10]);
  h.rates.dry_per_year = Angle::radians(g[11]);
  h.rates.drz_per_year = Angle::radians(g[12]);
  h.rates.dds_per_year = geodesy::ScaleDifference::unitless(g[13]);
  h.reference_epoch = o.reference_epoch.value_or(DecimalYear{0.0});
  result.reference_epoch = td ? o.reference_epoch : std::nullopt;
}

// --- report -------------------------------------------------------------
FitResult WeightedFit::report(const FitPass& current, GeocentricEstimate estimate) {
  const HelmertSolution& sol = current.sol;
  Eigen::MatrixXd& cov = estimate.cov;
  if (!current.geometry_warning.empty()) result.warnings.push_back(current.geometry_warning);
  if (o.scale_by_sigma0 && result.sigma0) cov *= *result.sigma0 * *result.sigma0;
  result.covariance_scaled_by_sigma0 = o.scale_by_sigma0 && result.sigma0.has_value();
  report_parameters(current, estimate);
  warn_translation_correlation(current, estimate);
  warn_implausible_magnitudes();
  add_statistics_warnings(result, options);
  result.ceres_iterations = sol.iterations;
  result.ceres_report = sol.report;
  result.rotation_model = o.rotation_model;
  return std::move(result);
}

// The covariance, correlation and parameters with their names and units, in
// the reported convention.
void WeightedFit::report_parameters(const FitPass& current, const GeocentricEstimate& estimate) {
  const HelmertSolution& sol = current.sol;
  const int u = current.u;
  const Eigen::MatrixXd& cov = estimate.cov;
  const std::array<double, kMaxParams>& reported = estimate.reported;
  const bool mb = estimate.mb;
  const bool cf = result.convention == Convention::coordinate_frame;
  const auto& names = kParameterNames;
  const auto factor = [cf](int k) { return unit_factor(k, cf); };
  Eigen::VectorXd f(u);
  for (int a = 0; a < u; ++a) f(a) = factor(sol.estimated[static_cast<std::size_t>(a)]);
  result.covariance = symmetric(f.asDiagonal() * cov * f.asDiagonal());
  result.correlation = correlation_of(result.covariance);
  result.covariance_names.clear();
  for (int a = 0; a < u; ++a) result.covariance_names.emplace_back(names[sol.estimated[static_cast<std::size_t>(a)]]);
  result.parameters.clear();
  for (int k = 0; k < (td ? 14 : 7); ++k) {
    Parameter p;
    p.name = names[k];
    p.value = reported[static_cast<std::size_t>(k)] * factor(k);
    const auto it = std::find(sol.estimated.begin(), sol.estimated.end(), k);
    p.estimated = it != sol.estimated.end();
    if (p.estimated) {
      const auto a = it - sol.estimated.begin();
      p.sigma = std::sqrt(result.covariance(a, a));
    }
    result.parameters.push_back(p);
  }
  if (mb) {
    const char* pivot_names[3] = {"px_m", "py_m", "pz_m"};
    for (int k = 0; k < 3; ++k) result.parameters.push_back(Parameter{pivot_names[k], (*result.pivot_m)(k), 0.0, false});
  }
}

void WeightedFit::warn_translation_correlation(const FitPass& current, const GeocentricEstimate& estimate) {
  const HelmertSolution& sol = current.sol;
  const int u = current.u;
  const Eigen::MatrixXd& cov = estimate.cov;
  const bool mb = estimate.mb;
  const std::string& geometry_warning = current.geometry_warning;
  const auto& names = kParameterNames;
  // Weak geometry: how much of each geocentric translation is determined by
  // the rotations and scale (multiple correlation), plus the largest
  // pairwise correlation to quote.
  std::vector<int> rs;  // positions of rotation/scale parameters in the covariance
  for (int a = 0; a < u; ++a) {
    const int k = sol.estimated[static_cast<std::size_t>(a)];
    if (k >= 3 && k <= 6) rs.push_back(a);
  }
  if (!rs.empty() && !mb) {
    double worst_multiple = 0.0, worst_pair = 0.0;
    std::string translation, pair;
    Eigen::MatrixXd s_rs(rs.size(), rs.size());
    for (std::size_t a = 0; a < rs.size(); ++a) {
      for (std::size_t b = 0; b < rs.size(); ++b) s_rs(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) = cov(rs[a], rs[b]);
    }
    const Eigen::LDLT<Eigen::MatrixXd> s_rs_ldlt(s_rs);
    for (int tix = 0; tix < 3; ++tix) {
      Eigen::VectorXd c(rs.size());
      for (std::size_t b = 0; b < rs.size(); ++b) {
        c(static_cast<Eigen::Index>(b)) = cov(tix, rs[b]);
        const double corr = std::fabs(result.correlation(tix, rs[b]));
        if (corr > worst_pair) {
          worst_pair = corr;
          pair = std::string(names[tix]) + "/" + result.covariance_names[static_cast<std::size_t>(rs[b])];
        }
      }
      const double multiple = std::sqrt(std::clamp(c.dot(s_rs_ldlt.solve(c)) / cov(tix, tix), 0.0, 1.0));
      if (multiple > worst_multiple) {
        worst_multiple = multiple;
        translation = names[tix];
      }
    }
    if (worst_multiple > 0.99) {
      result.warnings.push_back(
          "weak geometry: the multiple correlation of " + translation + " with the rotations and scale is " +
          (worst_multiple > 0.999999 ? "1 - " + fmt(1.0 - worst_multiple, 2) : fmt(worst_multiple, 6)) +
          "; largest pairwise |corr(" + pair +
          ")| = " + fmt(worst_pair, 4) +
          ". The network is small compared with its distance from the Earth's centre: " +
          (geometry_warning.empty() ? "the transform is sound, " : "") +
          "its geocentric parameters are not individually meaningful; consider --model molodensky-badekas");
    }
  }
}

// Implausible magnitudes for a datum transform (RELIABILITY #15), as
// reported (for Molodensky-Badekas: at the pivot).
void WeightedFit::warn_implausible_magnitudes() {
  geodesy::Helmert7<geodesy::PositionVector> as_reported;
  for (const auto& p : result.parameters) {
    if (p.name == "tx_m") as_reported.t_m.x() = p.value;
    if (p.name == "ty_m") as_reported.t_m.y() = p.value;
    if (p.name == "tz_m") as_reported.t_m.z() = p.value;
    if (p.name == "rx_arcsec") as_reported.rx = Angle::arcseconds(p.value);
    if (p.name == "ry_arcsec") as_reported.ry = Angle::arcseconds(p.value);
    if (p.name == "rz_arcsec") as_reported.rz = Angle::arcseconds(p.value);
    if (p.name == "ds_ppm") as_reported.ds = geodesy::ScaleDifference::ppm(p.value);
  }
  for (auto& w : geodesy::implausible_parameter_warnings(as_reported)) result.warnings.push_back(std::move(w));
}

}  // namespace geoanchor::solver
