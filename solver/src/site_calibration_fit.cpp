// The site-calibration model: controller-style localization.

#include <ceres/ceres.h>

#include <Eigen/Cholesky>
#include <cmath>

#include "enu_origin_fit.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "fit_common.hpp"
#include "point_statistics.hpp"
#include "statistics.hpp"

namespace geoanchor::solver {
namespace {

using geodesy::Angle;

constexpr int kParams = 7;  // tE, tN, a, b, c, slope_n, slope_e
constexpr double kArcsecPerRad = 180.0 / M_PI * 3600.0;

struct SiteObs {
  Eigen::Vector3d local;  // e, n, u
  Eigen::Vector3d grid;   // E, N, h of the target
  Eigen::Matrix3d w;      // whitening in (grid E, grid N, up)
};

// W (observed − predicted) in (grid E, grid N, h).
struct SiteCost {
  SiteObs obs;
  double e0, n0;
  template <typename T>
  bool operator()(const T* p, T* residual) const {
    const T e(obs.local.x()), n(obs.local.y()), u(obs.local.z());
    const Eigen::Matrix<T, 3, 1> pred(p[0] + p[2] * e - p[3] * n, p[1] + p[3] * e + p[2] * n,
                                      u + p[4] + p[5] * (n - T(n0)) + p[6] * (e - T(e0)));
    const Eigen::Matrix<T, 3, 1> r = obs.w.cast<T>() * (obs.grid.cast<T>() - pred);
    for (int k = 0; k < 3; ++k) residual[k] = r(k);
    return true;
  }
};

// The grid: TM with k0 = 1 at the targets' mean latitude and longitude
// (unless the options give one).
geodesy::ProjectionDef site_grid(const geodesy::ControlSet& control, const FitOptions& o,
                                 const geodesy::GeocentricConverter& geocentric, const std::vector<std::size_t>& active) {
  const geodesy::Ellipsoid& e = o.nominal_origin->ellipsoid;
  geodesy::ProjectionDef grid;
  if (o.site_grid) {
    grid = *o.site_grid;
  } else {
    double lat = 0.0, lon = 0.0;
    for (std::size_t i : active) {
      const auto g = geocentric.geodetic_from_ecef(control.points[i].target);
      lat += g.lat.deg();
      lon += g.lon.deg();
    }
    grid.ellipsoid = e;
    grid.tm.lat0 = Angle::degrees(lat / static_cast<double>(active.size()));
    grid.tm.lon0 = Angle::degrees(lon / static_cast<double>(active.size()));
    grid.tm.k0 = 1.0;
  }
  return grid;
}

// Per point: local e, n, u; the target on the grid; covariances in
// (grid E, grid N, up). The grid axes differ from local east/north by the
// meridian convergence γ ≈ (λ − λ0) sin φ (a few hundredths of a degree on
// a site), applied to the target covariance.
struct SiteObserver {
  const geodesy::ControlSet& control;
  const geodesy::LocalTangentPlane& plane;
  const geodesy::GeocentricConverter& geocentric;
  const geodesy::TransverseMercator& tm;
  const geodesy::ProjectionDef& grid;

  SiteObs operator()(std::size_t i, const Eigen::Matrix2d& similarity) const {
    const auto& p = control.points[i];
    SiteObs ob;
    ob.local = plane.enu_from_ecef(p.source).enu_m;
    const geodesy::GeodeticPosition g = geocentric.geodetic_from_ecef(p.target);
    const geodesy::ProjectedPosition q = tm.forward(g);
    ob.grid = Eigen::Vector3d(q.easting_m, q.northing_m, g.h.m);
    const double gamma = (g.lon - grid.tm.lon0).rad() * std::sin(g.lat.rad());
    Eigen::Matrix3d to_grid = Eigen::Matrix3d::Identity();
    to_grid.topLeftCorner<2, 2>() << std::cos(gamma), -std::sin(gamma), std::sin(gamma), std::cos(gamma);
    const Eigen::Matrix3d r_target = to_grid * geodesy::enu_from_ecef_rotation(g.lat, g.lon);
    Eigen::Matrix3d j = Eigen::Matrix3d::Identity();  // how source errors reach the grid
    j.topLeftCorner<2, 2>() = similarity;
    const Eigen::Matrix3d r_source = j * plane.enu_from_ecef_rotation();
    Eigen::Matrix3d c = r_target * p.target_cov_m2 * r_target.transpose() + r_source * p.source_cov_m2 * r_source.transpose();
    if (!control.has_a_priori_sigmas) c = Eigen::Matrix3d::Identity();
    const Eigen::LLT<Eigen::Matrix3d> llt(c);
    if (llt.info() != Eigen::Success) {
      throw Error(ErrorKind::input, "E_SIGMA", control.source_name + ":" + std::to_string(p.line) + ": id=" + p.id +
                                                   ": combined covariance is not positive definite");
    }
    ob.w = llt.matrixL().solve(Eigen::Matrix3d::Identity());
    return ob;
  }
};

// The site points' centroid in plan and their scatter about it; refused
// when they are collinear or coincident in plan.
struct PlanCentroid {
  double e0 = 0.0, n0 = 0.0;
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
};

PlanCentroid plan_centroid(const geodesy::ControlSet& control, const geodesy::LocalTangentPlane& plane,
                           const std::vector<std::size_t>& active) {
  const int n = static_cast<int>(active.size());
  PlanCentroid pc;
  double& e0 = pc.e0;
  double& n0 = pc.n0;
  Eigen::Matrix2d& scatter = pc.scatter;
  for (std::size_t i : active) {
    const Eigen::Vector3d l = plane.enu_from_ecef(control.points[i].source).enu_m;
    e0 += l.x();
    n0 += l.y();
  }
  e0 /= n;
  n0 /= n;
  for (std::size_t i : active) {
    const Eigen::Vector2d d = plane.enu_from_ecef(control.points[i].source).enu_m.head<2>() - Eigen::Vector2d(e0, n0);
    scatter += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter);
  if (!(eig.eigenvalues()(0) > 1e-12 * eig.eigenvalues()(1)) || eig.eigenvalues()(1) < 1.0) {
    reject("E_FIT_COLLINEAR", "the site points are collinear or coincident in plan (singular-value ratio " +
                                  std::to_string(std::sqrt(std::max(0.0, eig.eigenvalues()(0)) / eig.eigenvalues()(1))) +
                                  "): the rotation, scale and cross-tilt are not observable; add a point off the line");
  }
  return pc;
}

// The fit over the marks in use, twice: the source covariance reaches the
// grid through the fitted similarity (`similarity`, `obs`: the second
// pass's); the parameters' covariance.
Eigen::Matrix<double, kParams, kParams> solve_site(const SiteObserver& observation, const std::vector<std::size_t>& active,
                                                   const PlanCentroid& pc, const FitOptions& o, FitResult& result,
                                                   std::array<double, kParams>& params, Eigen::Matrix2d& similarity,
                                                   std::vector<SiteObs>& obs) {
  const double e0 = pc.e0, n0 = pc.n0;
  ceres::Problem::Options po;
  std::unique_ptr<ceres::Problem> problem;
  for (int pass = 0; pass < 2; ++pass) {
    obs.clear();
    for (std::size_t i : active) obs.push_back(observation(i, similarity));
    problem = std::make_unique<ceres::Problem>(po);
    params = {0, 0, 1, 0, 0, 0, 0};
    for (const auto& ob : obs) {
      problem->AddResidualBlock(new ceres::AutoDiffCostFunction<SiteCost, 3, kParams>(new SiteCost{ob, e0, n0}), nullptr,
                                params.data());
    }
    const ceres::Solver::Summary summary = solve_tightly(*problem, ceres::DENSE_QR, o.max_solver_iterations);
    result.ceres_iterations = static_cast<int>(summary.iterations.size());
    result.ceres_report = summary.BriefReport();
    similarity << params[2], -params[3], params[3], params[2];
  }
  return covariance_or_reject(*problem, std::vector<const double*>{params.data()}, kParams);
}

// The geometry check, with a, b and the slopes times the plan's RMS
// radius (then each parameter moves points by metres there): refused past
// kRefuseDilution; the warning past kWarnDilution (else empty).
std::string site_geometry(const Eigen::Matrix2d& scatter, int n, const Eigen::Matrix<double, kParams, kParams>& cov7) {
  const double radius_m = std::sqrt(scatter.trace() / n);
  Eigen::Matrix<double, kParams, 1> sc;
  sc << 1.0, 1.0, radius_m, radius_m, 1.0, radius_m, radius_m;
  const GeometryDilution gd = geometry_dilution(sc.asDiagonal() * cov7 * sc.asDiagonal(), {0, 1, 4});
  if (!(gd.dilution <= kRefuseDilution)) {
    reject("E_FIT_WEAK_GEOMETRY", "the site points' geometry leaves the rotation, scale or cross-tilt determined " +
                                      fmt(gd.dilution, 3) +
                                      " times less precisely than the shifts: they are "
                                      "(nearly) collinear in plan; add a point off their line");
  }
  if (!(gd.dilution <= kWarnDilution)) {
    return "weak geometry: the site points determine the rotation, scale and tilts " + fmt(gd.dilution, 3) +
           " times less precisely than the shifts";
  }
  return std::string();
}

// Reported parameters: (a, b) as rotation and scale; tilts in ppm (mm/km).
void report_site(FitResult& result, const FitOptions& o, const geodesy::SiteCalibrationParams& sp,
                 const std::array<double, kParams>& params, const Eigen::Matrix<double, kParams, kParams>& cov7,
                 const PlanCentroid& pc, const geodesy::ProjectionDef& grid) {
  const double a = params[2], b = params[3], k2 = a * a + b * b, k = std::sqrt(k2);
  const double e0 = pc.e0, n0 = pc.n0;
  Eigen::Matrix<double, kParams, kParams> jr = Eigen::Matrix<double, kParams, kParams>::Identity();
  jr(2, 2) = -b / k2 * kArcsecPerRad;
  jr(2, 3) = a / k2 * kArcsecPerRad;
  jr(3, 2) = a / k * 1e6;
  jr(3, 3) = b / k * 1e6;
  jr(5, 5) = jr(6, 6) = 1e6;
  Eigen::MatrixXd cov = jr * cov7 * jr.transpose();
  if (o.scale_by_sigma0 && result.sigma0) cov *= *result.sigma0 * *result.sigma0;
  result.covariance_scaled_by_sigma0 = o.scale_by_sigma0 && result.sigma0.has_value();
  result.covariance = symmetric(cov);
  result.correlation = correlation_of(cov);
  result.covariance_names = {"shift_e_m", "shift_n_m", "rotation_arcsec", "scale_ppm", "vertical_shift_m", "slope_n_ppm",
                             "slope_e_ppm"};
  const double values[kParams] = {sp.shift_e_m, sp.shift_n_m, sp.rotation.arcsec(), sp.scale.ppm(), sp.vertical_shift_m,
                                  sp.slope_n * 1e6, sp.slope_e * 1e6};
  result.parameters.clear();
  for (int m = 0; m < kParams; ++m) {
    result.parameters.push_back(Parameter{result.covariance_names[static_cast<std::size_t>(m)], values[m], std::sqrt(cov(m, m)), true});
  }
  result.parameters.push_back(Parameter{"centroid_e_m", e0, 0.0, false});
  result.parameters.push_back(Parameter{"centroid_n_m", n0, 0.0, false});
  result.parameters.push_back(Parameter{"grid_lat0_deg", grid.tm.lat0.deg(), 0.0, false});
  result.parameters.push_back(Parameter{"grid_lon0_deg", grid.tm.lon0.deg(), 0.0, false});
}

}  // namespace

FitResult fit_site_calibration(const geodesy::ControlSet& control, const FitOptions& options) {
  FitOptions o = options;
  if (!o.nominal_origin) {
    throw Error(ErrorKind::usage, "E_ORIGIN_MISSING",
                "--origin: site-calibration reads the site's local coordinates as e_src_m,n_src_m,u_src_m at an origin; "
                "give it (any fixed LAT,LON,H: only the local numbers matter)");
  }
  FitResult result;
  result.model = FitModel::site_calibration;
  result.nominal_origin = o.nominal_origin;
  note_missing_sigmas(result, o, control);
  const geodesy::Ellipsoid& e = o.nominal_origin->ellipsoid;
  const geodesy::LocalTangentPlane plane(*o.nominal_origin);
  const geodesy::GeocentricConverter geocentric(e);

  std::vector<std::size_t> active = init_points(result, control, o);
  if (active.size() < 3) {
    reject("E_FIT_TOO_FEW_POINTS", "model site-calibration: need >= 3 non-collinear points, got " + std::to_string(active.size()));
  }
  const geodesy::ProjectionDef grid = site_grid(control, o, geocentric, active);
  const geodesy::TransverseMercator tm(grid);

  const PointTestLevels levels = point_test_levels(o);
  result.w_critical = levels.w_critical;
  const SiteObserver observation{control, plane, geocentric, tm, grid};

  std::array<double, kParams> params{};
  std::string geometry_warning;
  while (true) {
    const int n = static_cast<int>(active.size());
    const PlanCentroid pc = plan_centroid(control, plane, active);
    const double e0 = pc.e0, n0 = pc.n0;
    Eigen::Matrix2d similarity = Eigen::Matrix2d::Identity();
    std::vector<SiteObs> obs;
    const Eigen::Matrix<double, kParams, kParams> cov7 = solve_site(observation, active, pc, o, result, params, similarity, obs);
    geometry_warning = site_geometry(pc.scatter, n, cov7);

    geodesy::SiteCalibrationParams sp;
    sp.shift_e_m = params[0];
    sp.shift_n_m = params[1];
    const double a = params[2], b = params[3], k2 = a * a + b * b, k = std::sqrt(k2);
    sp.rotation = Angle::radians(std::atan2(b, a));
    sp.scale = geodesy::ScaleDifference::unitless(k - 1.0);
    sp.vertical_shift_m = params[4];
    sp.slope_n = params[5];
    sp.slope_e = params[6];
    sp.centroid_e_m = e0;
    sp.centroid_n_m = n0;
    result.site_calibration.emplace(*o.nominal_origin, grid, sp);

    // Residuals (grid E, grid N, up), statistics, snooping.
    double omega = 0.0;
    std::vector<Eigen::Vector3d> v(active.size());
    for (std::size_t m = 0; m < active.size(); ++m) {
      v[m] = obs[m].grid - result.site_calibration->grid_from_local(obs[m].local);
      omega += (obs[m].w * v[m]).squaredNorm();
    }
    const int dof = 3 * n - kParams;
    fill_global_test(result, omega, dof, o.alpha, control.has_a_priori_sigmas);
    const double scale = sigma_scale(result, o);
    FitLinearization lin;  // the failing marks, for data snooping
    lin.n_inv = cov7;
    auto tests = [&](const SiteObs& ob, const Eigen::Vector3d& vi, bool in_fit, PointResult& pr, std::size_t position) {
      ceres::AutoDiffCostFunction<SiteCost, 3, kParams> f(new SiteCost{ob, e0, n0});
      double res[3] = {}, jac[3 * kParams] = {};
      double* jacs[1] = {jac};
      const double* ps[1] = {params.data()};
      f.Evaluate(ps, res, jacs);
      const Eigen::Map<Eigen::Matrix<double, 3, kParams, Eigen::RowMajor>> aw(jac);
      const Eigen::Matrix3d q = Eigen::Matrix3d::Identity() + (in_fit ? -1.0 : 1.0) * aw * cov7 * aw.transpose();
      test_point(PointTestInput{vi, ob.w, q, Eigen::Matrix3d::Identity(), in_fit}, scale, levels.lambda0, pr);
      if (in_fit && pr.point_dof > 0 && pr.point_p_value < o.alpha_point) lin.add(position, aw, ob.w * vi);
    };
    for (std::size_t m = 0; m < active.size(); ++m) {
      result.points[active[m]].used = true;
      tests(obs[m], v[m], true, result.points[active[m]], m);
    }
    if (snoop(result, active, o, kParams, 3, lin) == SnoopStep::removed) continue;
    std::vector<bool> in_fit(control.points.size(), false);
    for (std::size_t i : active) in_fit[i] = true;
    for (std::size_t i = 0; i < control.points.size(); ++i) {
      if (in_fit[i]) continue;
      const SiteObs ob = observation(i, similarity);
      tests(ob, ob.grid - result.site_calibration->grid_from_local(ob.local), false, result.points[i], 0);
    }
    report_site(result, o, sp, params, cov7, pc, grid);
    if (!geometry_warning.empty()) result.warnings.push_back(geometry_warning);
    add_statistics_warnings(result, options);
    return result;
  }
}

}  // namespace geoanchor::solver
