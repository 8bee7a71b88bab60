// The enu-origin model: a map's ENU frame re-anchored on surveyed marks.

#include <ceres/ceres.h>

#include <Eigen/Cholesky>
#include <cmath>

#include "enu_origin_fit.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "fit_common.hpp"
#include "point_statistics.hpp"
#include "statistics.hpp"

namespace geoanchor::solver {
namespace {

using geodesy::Angle;

constexpr double kArcsecPerRad = 180.0 / M_PI * 3600.0;

// What every residual needs of the nominal origin.
struct Nominal {
  double lat_rad, lon_rad;
  double meridian_radius_m;   // M + h
  double normal_radius_m;     // (N + h), times cos(lat) for longitudes
  Eigen::Matrix3d enu_from_ecef;
  double l_m;                 // RMS radius of the map points: parameter scale
};

// ENU rotation (rows E, N, U) at a latitude and longitude in radians.
template <typename T>
Eigen::Matrix<T, 3, 3> enu_rotation(const T& lat, const T& lon) {
  using std::cos;
  using std::sin;
  const T sp = sin(lat), cp = cos(lat), sl = sin(lon), cl = cos(lon);
  Eigen::Matrix<T, 3, 3> r;
  r << -sl, cl, T(0.0), -sp * cl, -sp * sl, cp, cp * cl, cp * sl, sp;
  return r;
}

// W (target − O − model) for one point; parameters: shift (m), yaw·L, ds·L.
struct EnuOriginCost {
  Eigen::Vector3d enu;         // map coordinates at the nominal origin
  Eigen::Vector3d target_rel;  // target ECEF − nominal origin ECEF
  Eigen::Matrix3d w;
  const Nominal* nominal;

  template <typename T>
  bool operator()(const T* shift, const T* yaw_scaled, const T* ds_scaled, T* residual) const {
    const T yaw = yaw_scaled[0] / nominal->l_m, ds = ds_scaled[0] / nominal->l_m;
    const Eigen::Matrix<T, 3, 1> sh(shift[0], shift[1], shift[2]);
    // The corrected origin: shifted in the nominal ENU frame; its own ENU
    // rotation from its latitude and longitude (first order in the shift:
    // the second-order error is (shift / R)² ≈ 1e-12 rad for metres).
    const T lat = T(nominal->lat_rad) + shift[1] / T(nominal->meridian_radius_m);
    const T lon = T(nominal->lon_rad) + shift[0] / (T(nominal->normal_radius_m) * T(std::cos(nominal->lat_rad)));
    const Eigen::Matrix<T, 3, 3> corrected = enu_rotation(lat, lon);
    using std::cos;
    using std::sin;
    const T c = cos(yaw), s = sin(yaw);
    const Eigen::Matrix<T, 3, 1> map(T(enu(0)), T(enu(1)), T(enu(2)));
    const Eigen::Matrix<T, 3, 1> turned((c * map(0) - s * map(1)) * (T(1.0) + ds),
                                        (s * map(0) + c * map(1)) * (T(1.0) + ds), map(2) * (T(1.0) + ds));
    const Eigen::Matrix<T, 3, 1> model = nominal->enu_from_ecef.transpose().cast<T>() * sh + corrected.transpose() * turned;
    const Eigen::Matrix<T, 3, 1> r = w.cast<T>() * (target_rel.cast<T>() - model);
    for (int k = 0; k < 3; ++k) residual[k] = r(k);
    return true;
  }
};

// Per point: map ENU, target relative to the nominal origin, whitening of
// C_target + J C_source Jᵀ with J the linear part of the correction (the
// identity before the first solve; the yaw turns the map's covariance).
struct Obs {
  Eigen::Vector3d enu, target_rel;
  Eigen::Matrix3d w;
};

Eigen::Matrix3d whitening(const geodesy::ControlSet& control, const geodesy::ControlPoint& p, const Eigen::Matrix3d& j) {
  const Eigen::Matrix3d c = control.has_a_priori_sigmas ? Eigen::Matrix3d(p.target_cov_m2 + j * p.source_cov_m2 * j.transpose())
                                                        : Eigen::Matrix3d::Identity();
  const Eigen::LLT<Eigen::Matrix3d> llt(c);
  if (llt.info() != Eigen::Success) {
    throw Error(ErrorKind::input, "E_SIGMA", control.source_name + ":" + std::to_string(p.line) + ": id=" + p.id +
                                                 ": combined covariance is not positive definite");
  }
  return Eigen::Matrix3d(llt.matrixL().solve(Eigen::Matrix3d::Identity()));
}

// The nominal origin's radii and axes.
Nominal nominal_at(const geodesy::LocalOrigin& origin, const geodesy::LocalTangentPlane& plane) {
  const geodesy::Ellipsoid& e = origin.ellipsoid;
  Nominal nominal;
  nominal.lat_rad = origin.point.lat.rad();
  nominal.lon_rad = origin.point.lon.rad();
  const double sphi = std::sin(nominal.lat_rad);
  const double w2 = 1.0 - e.e2() * sphi * sphi;
  nominal.meridian_radius_m = e.a_m() * (1.0 - e.e2()) / (w2 * std::sqrt(w2)) + origin.point.h.m;
  nominal.normal_radius_m = e.a_m() / std::sqrt(w2) + origin.point.h.m;
  nominal.enu_from_ecef = plane.enu_from_ecef_rotation();
  return nominal;
}

// The correction as solved: shift (m), yaw·L and ds·L (the Ceres problem
// holds these blocks), its problem and the solver's summary. The blocks lie
// in memory in this order, yaw and ds below shift: ceres::Covariance takes
// the parameter blocks in the order of their addresses, and the
// covariance's last bits follow that order.
struct EnuOriginSolution {
  double yaw[1] = {0}, ds[1] = {0}, shift[3] = {0, 0, 0};
  std::unique_ptr<ceres::Problem> problem;
  std::vector<const double*> blocks;
  ceres::Solver::Summary summary;
};

// Solves over the marks in use, with weights from J of the estimate until J
// settles (`weights_j`: the J the weights were made with, carried between
// passes of the fit).
void solve_enu_origin(EnuOriginSolution& s, std::vector<Obs>& all, const std::vector<std::size_t>& active,
                      const geodesy::ControlSet& control, const FitOptions& o, const Nominal& nominal,
                      Eigen::Matrix3d& weights_j) {
  constexpr int kMaxWeightPasses = 5;
  constexpr double kWeightChange = 1e-12;  // change of J between passes
  for (int pass = 0; pass < kMaxWeightPasses; ++pass) {
    s.problem = std::make_unique<ceres::Problem>();
    for (std::size_t i : active) {
      s.problem->AddResidualBlock(new ceres::AutoDiffCostFunction<EnuOriginCost, 3, 3, 1, 1>(
                                      new EnuOriginCost{all[i].enu, all[i].target_rel, all[i].w, &nominal}),
                                  nullptr, s.shift, s.yaw, s.ds);
    }
    s.blocks = {s.shift};
    if (o.enu_yaw) {
      s.blocks.push_back(s.yaw);
    } else {
      s.problem->SetParameterBlockConstant(s.yaw);
    }
    if (o.enu_scale) {
      s.blocks.push_back(s.ds);
    } else {
      s.problem->SetParameterBlockConstant(s.ds);
    }
    s.summary = solve_tightly(*s.problem, ceres::DENSE_QR, o.max_solver_iterations);
    if (!control.has_a_priori_sigmas) break;
    const Eigen::Matrix3d j = geodesy::enu_origin_correction(*o.nominal_origin, Eigen::Vector3d(s.shift[0], s.shift[1], s.shift[2]),
                                                             Angle::radians(s.yaw[0] / nominal.l_m),
                                                             geodesy::ScaleDifference::unitless(s.ds[0] / nominal.l_m))
                                  .linear();
    if ((j - weights_j).cwiseAbs().maxCoeff() <= kWeightChange) break;
    weights_j = j;
    for (std::size_t i = 0; i < control.points.size(); ++i) all[i].w = whitening(control, control.points[i], weights_j);
  }
}

// Parameters in their reporting units, covariance likewise; the corrected
// origin with sigmas from the shift's.
void report_enu_origin(FitResult& result, const FitOptions& o, const Nominal& nominal, const Eigen::MatrixXd& cov_scaled,
                       const EnuOriginSolution& s, const geodesy::GeodeticPosition& corrected, double yaw_rad,
                       double ds_unitless) {
  const int u = static_cast<int>(cov_scaled.rows());
  const double* shift = s.shift;
  Eigen::MatrixXd cov = cov_scaled;
  if (o.scale_by_sigma0 && result.sigma0) cov *= *result.sigma0 * *result.sigma0;
  result.covariance_scaled_by_sigma0 = o.scale_by_sigma0 && result.sigma0.has_value();
  std::vector<double> factor = {1.0, 1.0, 1.0};
  result.covariance_names = {"shift_e_m", "shift_n_m", "shift_u_m"};
  if (o.enu_yaw) {
    factor.push_back(kArcsecPerRad / nominal.l_m);
    result.covariance_names.emplace_back("yaw_arcsec");
  }
  if (o.enu_scale) {
    factor.push_back(1e6 / nominal.l_m);
    result.covariance_names.emplace_back("ds_ppm");
  }
  const Eigen::VectorXd f = Eigen::Map<Eigen::VectorXd>(factor.data(), u);
  result.covariance = symmetric(f.asDiagonal() * cov * f.asDiagonal());
  result.correlation = correlation_of(result.covariance);
  auto sigma_of = [&](const std::string& name) {
    for (int a = 0; a < u; ++a) {
      if (result.covariance_names[static_cast<std::size_t>(a)] == name) return std::sqrt(result.covariance(a, a));
    }
    return 0.0;
  };
  result.parameters = {
      Parameter{"shift_e_m", shift[0], sigma_of("shift_e_m"), true},
      Parameter{"shift_n_m", shift[1], sigma_of("shift_n_m"), true},
      Parameter{"shift_u_m", shift[2], sigma_of("shift_u_m"), true},
      Parameter{"yaw_arcsec", yaw_rad * kArcsecPerRad, sigma_of("yaw_arcsec"), o.enu_yaw},
      Parameter{"ds_ppm", ds_unitless * 1e6, sigma_of("ds_ppm"), o.enu_scale},
      // The corrected origin, with sigmas from the shift's (E, N, U -> degrees, degrees, metres).
      Parameter{"origin_lat_deg", corrected.lat.deg(), sigma_of("shift_n_m") / nominal.meridian_radius_m * 180.0 / M_PI, false},
      Parameter{"origin_lon_deg", corrected.lon.deg(),
                sigma_of("shift_e_m") / (nominal.normal_radius_m * std::cos(nominal.lat_rad)) * 180.0 / M_PI, false},
      Parameter{"origin_h_m", corrected.h.m, sigma_of("shift_u_m"), false},
  };
}

}  // namespace

FitResult fit_enu_origin(const geodesy::ControlSet& control, const FitOptions& options) {
  FitOptions o = options;
  if (!o.nominal_origin) {
    throw Error(ErrorKind::usage, "E_ORIGIN_MISSING",
                "--origin: the enu-origin model needs the nominal origin LAT,LON,H of the map's ENU coordinates");
  }
  FitResult result;
  result.model = FitModel::enu_origin;
  result.rotation_model = geodesy::RotationModel::exact;
  result.nominal_origin = o.nominal_origin;
  note_missing_sigmas(result, o, control);
  const geodesy::LocalTangentPlane plane(*o.nominal_origin);
  Nominal nominal = nominal_at(*o.nominal_origin, plane);

  std::vector<std::size_t> active = init_points(result, control, o);
  const int u = 3 + (o.enu_yaw ? 1 : 0) + (o.enu_scale ? 1 : 0);
  const PointTestLevels levels = point_test_levels(o);
  result.w_critical = levels.w_critical;
  const geodesy::GeocentricConverter geocentric(geodesy::Ellipsoid::wgs84());

  std::vector<Obs> all(control.points.size());
  for (std::size_t i = 0; i < control.points.size(); ++i) {
    const auto& p = control.points[i];
    all[i] = Obs{plane.enu_from_ecef(p.source).enu_m, p.target.m - plane.origin_ecef_m(), whitening(control, p, Eigen::Matrix3d::Identity())};
  }
  Eigen::Matrix3d weights_j = Eigen::Matrix3d::Identity();  // the J the weights were made with

  while (true) {
    const int n = static_cast<int>(active.size());
    const int need = o.enu_yaw || o.enu_scale ? 2 : 1;
    if (n < need) {
      reject("E_FIT_TOO_FEW_POINTS", "model enu-origin: need >= " + std::to_string(need) + " points, got " + std::to_string(n));
    }
    double l2 = 0.0;
    for (std::size_t i : active) l2 += all[i].enu.head<2>().squaredNorm();
    nominal.l_m = std::sqrt(l2 / n);
    if ((o.enu_yaw || o.enu_scale) && nominal.l_m < 1.0) {
      reject("E_FIT_COINCIDENT", "the map points lie within " + fmt(nominal.l_m) +
                                     " m of the origin horizontally: yaw and scale are not observable; use --fix-yaw");
    }
    EnuOriginSolution solution;
    solve_enu_origin(solution, all, active, control, o, nominal, weights_j);
    double* shift = solution.shift;
    double* yaw = solution.yaw;
    double* ds = solution.ds;
    const Eigen::MatrixXd cov_scaled = covariance_or_reject(*solution.problem, solution.blocks, u);
    // Every estimated parameter moves the points by metres at the map's RMS
    // radius (yaw and scale are solved times L): the geometry check applies as is.
    const GeometryDilution gd = geometry_dilution(cov_scaled, {0, 1, 2});
    if (!(gd.dilution <= kRefuseDilution)) {
      reject("E_FIT_WEAK_GEOMETRY", "the map points' geometry leaves the " +
                                        std::string(o.enu_scale ? "yaw and scale" : "yaw") + " determined " +
                                        fmt(gd.dilution, 3) +
                                        " times less precisely than the shift; use --fix-yaw "
                                        "or add points farther from the line through the others");
    }

    // The correction as an ECEF map, and the corrected origin.
    const double yaw_rad = yaw[0] / nominal.l_m, ds_unitless = ds[0] / nominal.l_m;
    const Eigen::Vector3d shift_m(shift[0], shift[1], shift[2]);
    result.ecef_map = geodesy::enu_origin_correction(*o.nominal_origin, shift_m, Angle::radians(yaw_rad),
                                                     geodesy::ScaleDifference::unitless(ds_unitless));
    result.corrected_origin = geodesy::corrected_origin(*o.nominal_origin, shift_m);
    const geodesy::GeodeticPosition corrected = result.corrected_origin->point;

    // Residuals and statistics, from the reported map.
    double omega = 0.0;
    std::vector<Eigen::Vector3d> v(active.size());
    for (std::size_t k = 0; k < active.size(); ++k) {
      const auto& p = control.points[active[k]];
      v[k] = p.target.m - result.ecef_map->apply(p.source.m);
      omega += (all[active[k]].w * v[k]).squaredNorm();
    }
    const int dof = 3 * n - u;
    fill_global_test(result, omega, dof, o.alpha, control.has_a_priori_sigmas);
    const double scale = sigma_scale(result, o);

    // Whitened Jacobians in the scaled parameters (A N⁻¹ Aᵀ is invariant).
    std::vector<double*> pblocks = {shift, yaw, ds};
    FitLinearization lin;  // the failing marks, for data snooping
    lin.n_inv = cov_scaled;
    auto tests = [&](std::size_t i, const Eigen::Vector3d& vi, bool in_fit, std::size_t position) {
      EnuOriginCost cost{all[i].enu, all[i].target_rel, all[i].w, &nominal};
      ceres::AutoDiffCostFunction<EnuOriginCost, 3, 3, 1, 1> f(new EnuOriginCost(cost));
      double res[3] = {}, j0[9] = {}, j1[3] = {}, j2[3] = {};
      double* jac[3] = {j0, j1, j2};
      f.Evaluate(pblocks.data(), res, jac);
      Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, 5> a(3, u);
      int c = 0;
      for (int k = 0; k < 3; ++k) a.col(c++) = Eigen::Vector3d(j0[k], j0[3 + k], j0[6 + k]);
      if (o.enu_yaw) a.col(c++) = Eigen::Vector3d(j1[0], j1[1], j1[2]);
      if (o.enu_scale) a.col(c++) = Eigen::Vector3d(j2[0], j2[1], j2[2]);
      const Eigen::Matrix3d q = Eigen::Matrix3d::Identity() + (in_fit ? -1.0 : 1.0) * a * cov_scaled * a.transpose();
      const geodesy::GeodeticPosition at = geocentric.geodetic_from_ecef(control.points[i].target);
      PointResult& pr = result.points[i];
      test_point(PointTestInput{vi, all[i].w, q, geodesy::enu_from_ecef_rotation(at.lat, at.lon), in_fit}, scale,
                 levels.lambda0, pr);
      if (in_fit && pr.point_dof > 0 && pr.point_p_value < o.alpha_point) lin.add(position, a, all[i].w * vi);
    };
    for (std::size_t k = 0; k < active.size(); ++k) {
      tests(active[k], v[k], true, k);
      result.points[active[k]].used = true;
    }
    if (snoop(result, active, o, u, o.enu_yaw || o.enu_scale ? 2 : 1, lin) == SnoopStep::removed) continue;
    std::vector<bool> in_fit(control.points.size(), false);
    for (std::size_t i : active) in_fit[i] = true;
    for (std::size_t i = 0; i < control.points.size(); ++i) {
      if (!in_fit[i]) tests(i, control.points[i].target.m - result.ecef_map->apply(control.points[i].source.m), false, 0);
    }

    report_enu_origin(result, o, nominal, cov_scaled, solution, corrected, yaw_rad, ds_unitless);
    if (!(gd.dilution <= kWarnDilution)) {
      result.warnings.push_back("weak geometry: the map points determine the " +
                                std::string(o.enu_scale ? "yaw and scale" : "yaw") + " " + fmt(gd.dilution, 3) +
                                " times less precisely than the shift");
    }
    add_statistics_warnings(result, options);
    result.ceres_iterations = static_cast<int>(solution.summary.iterations.size());
    result.ceres_report = solution.summary.BriefReport();
    return result;
  }
}

}  // namespace geoanchor::solver
