// The propagated uncertainty `apply` reports, from the transform file as
// `fit -o` writes it: against the Monte Carlo spread of transformed
// positions over noisy fits (independent of any Jacobian), and at the map's
// own origin for enu-origin (where only the shift can matter).

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "generated_control.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "geoanchor/solver/helmert_fit.hpp"
#include "geoanchor/workflow/fit_export.hpp"
#include "geoanchor/workflow/uncertainty.hpp"
#include "test_support.hpp"

namespace geoanchor::workflow {
namespace {

using geodesy::Angle;
using geodesy::EcefPosition;
using solver::Convention;
using solver::FitModel;
using solver::FitOptions;
using solver::FitResult;

// The file as `fit -o` writes it and `apply` reads it back.
io::TransformFile written_and_read(const FitResult& r, const geodesy::ControlSet& set, const FitOptions& o) {
  return io::parse_transform_json(io::to_json_text(transform_file_from_fit(r, set, o, {}, "test")), "fit.json");
}

// A transform file with fit-record keys added (the published WGS 72 -> WGS 84 set, EPSG:1238-like).
const char* kHelmert7 = R"({"model": "helmert7", "convention": "position_vector", "rotation_model": "small_angle",
  "source_frame": "WGS72", "target_frame": "WGS84",
  "parameters": {"tx_m": 0, "ty_m": 0, "tz_m": 4.5, "rx_arcsec": 0, "ry_arcsec": 0, "rz_arcsec": 0.554, "ds_ppm": 0.219}})";
const char* kSigmas7 = R"("sigmas": {"tx_m": 0.05, "ty_m": 0.05, "tz_m": 0.05, "rx_arcsec": 0.002, "ry_arcsec": 0.002,
                                     "rz_arcsec": 0.002, "ds_ppm": 0.005})";
std::string helmert7_with(const std::string& fit) {
  std::string s = kHelmert7;
  s.insert(s.size() - 1, ", " + fit);
  return s;
}
std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

TEST(PropagatedUncertainty, MatchesTheMonteCarloSpreadAndGrowsAwayFromTheNetwork) {
  constexpr int kTrials = 400;
  constexpr double kSpreadRelTol = 0.15;  // the sample σ of 400 trials is within ~7 % of the truth (2σ)
  const auto src = testing::region(20, 47.46, 8.55, 0.03, 41);
  const geodesy::ControlSet clean = testing::control_from_proj(
      src, "+proj=helmert +x=0.5 +y=-0.3 +z=0.8 +rx=0.12 +ry=-0.05 +rz=0.2 +s=1.2 +convention=position_vector", 0.005);
  FitOptions o;
  o.model = FitModel::helmert7;
  o.convention = Convention::position_vector;
  o.data_snooping = false;
  const geodesy::GeocentricConverter conv(geodesy::Ellipsoid::grs80());
  const EcefPosition near = conv.ecef_from_geodetic({Angle::degrees(47.46), Angle::degrees(8.55), geodesy::EllipsoidalHeight{500}});
  const EcefPosition far = conv.ecef_from_geodetic({Angle::degrees(47.9), Angle::degrees(9.3), geodesy::EllipsoidalHeight{500}});
  const FitResult base = solver::fit_helmert(clean, o);
  const io::TransformFile file = written_and_read(base, clean, o);
  const auto c_near = propagated_covariance_m2(file, near, std::nullopt, false);
  const auto c_far = propagated_covariance_m2(file, far, std::nullopt, false);
  ASSERT_TRUE(c_near && c_far);
  EXPECT_GT(c_far->trace(), 4.0 * c_near->trace());  // 60 km out vs the centre of a 3 km network

  std::mt19937_64 rng(43);
  std::normal_distribution<double> noise(0.0, 0.005 / std::sqrt(2.0));
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d sum2 = Eigen::Matrix3d::Zero();
  for (int t = 0; t < kTrials; ++t) {
    geodesy::ControlSet set = clean;
    for (auto& p : set.points) {
      p.source.m += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
      p.target.m += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    }
    const Eigen::Vector3d y = solver::apply_fit(solver::fit_helmert(set, o), far, std::nullopt).m -
                              solver::apply_fit(base, far, std::nullopt).m;
    sum += y;
    sum2 += y * y.transpose();
  }
  const Eigen::Matrix3d sample = (sum2 - sum * sum.transpose() / kTrials) / (kTrials - 1);
  EXPECT_NEAR(std::sqrt(sample.trace()), std::sqrt(c_far->trace()), kSpreadRelTol * std::sqrt(c_far->trace()));
}

// enu-origin: at the map's own origin the yaw and scale move nothing, so the
// propagated covariance is the shift's, rotated from local E, N, U into
// ECEF (same trace).
TEST(PropagatedUncertainty, AtTheMapsOriginAnEnuOriginCorrectionIsUncertainByItsShiftAlone) {
  constexpr double kRelativeTraceTol = 1e-6;  // central differences of ±σ on a map linear in the shift
  const geodesy::LocalOrigin nominal{{Angle::degrees(47.464722), Angle::degrees(8.549167), geodesy::EllipsoidalHeight{480.0}},
                                     geodesy::Ellipsoid::wgs84()};
  const geodesy::LocalTangentPlane plane(nominal);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> d(-3000.0, 3000.0), up(-20.0, 20.0);
  std::normal_distribution<double> noise(0.0, 0.01);
  geodesy::ControlSet set;
  set.source_name = "map";
  const double yaw = 20.0 / 206264.80624709636;
  for (int i = 0; i < 40; ++i) {
    const Eigen::Vector3d map(d(rng), d(rng), up(rng));
    const Eigen::Vector3d turned(std::cos(yaw) * map.x() - std::sin(yaw) * map.y() + 0.3,
                                 std::sin(yaw) * map.x() + std::cos(yaw) * map.y() - 0.2, map.z() + 0.05);
    geodesy::ControlPoint p;
    p.id = "M" + std::to_string(i);
    p.source = plane.ecef_from_enu({map, nominal});
    p.target = plane.ecef_from_enu({turned + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)), nominal});
    p.source_cov_m2 = Eigen::Matrix3d::Zero();
    p.target_cov_m2 = Eigen::Matrix3d::Identity() * 1e-4;
    p.source_as_read = p.source.m;
    p.target_as_read = p.target.m;
    set.points.push_back(p);
  }
  FitOptions o;
  o.model = FitModel::enu_origin;
  o.nominal_origin = nominal;
  const FitResult r = solver::fit_helmert(set, o);
  const io::TransformFile file = written_and_read(r, set, o);
  const auto c = propagated_covariance_m2(file, EcefPosition(plane.origin_ecef_m()), std::nullopt, false);
  ASSERT_TRUE(c.has_value());
  const double shift_trace = r.covariance.topLeftCorner(3, 3).trace();
  EXPECT_NEAR(c->trace(), shift_trace, kRelativeTraceTol * shift_trace);
}

// issue 12 point 9: the propagated covariance against J Σ Jᵀ worked out by hand.
constexpr double kPropagatedCovTol_m2 = 1e-9;  // central differences of a model linear in each parameter are exact up to
                                               // float64 rounding of ECEF coordinates (9.3e-10 m) over a 2σ step
TEST(PropagatedUncertainty, Point9_PropagatedCovarianceIsJSigmaJtByHand) {
  const geodesy::EcefPosition x(4271315.696, 641096.356, 4678048.542);
  // Translation only: J = σ per axis, so Σ = D R D.
  const double s[3] = {0.01, 0.02, 0.03};
  const double r[3][3] = {{1, 0.5, -0.2}, {0.5, 1, 0.1}, {-0.2, 0.1, 1}};
  const std::string t3 = R"({"model": "translation3", "parameters": {"tx_m": 1, "ty_m": 2, "tz_m": 3},
    "sigmas": {"tx_m": 0.01, "ty_m": 0.02, "tz_m": 0.03},
    "correlation_parameters": ["tx_m", "ty_m", "tz_m"],
    "correlation": [[1, 0.5, -0.2], [0.5, 1, 0.1], [-0.2, 0.1, 1]]})";
  const auto c = propagated_covariance_m2(io::parse_transform_json(t3, "T.json"), x, std::nullopt, false);
  ASSERT_TRUE(c);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) EXPECT_NEAR((*c)(i, j), s[i] * s[j] * r[i][j], kPropagatedCovTol_m2) << i << "," << j;
  }
  // The rows and columns in another order read the same matrix.
  const std::string reordered = replace(replace(t3, R"(["tx_m", "ty_m", "tz_m"])", R"(["tz_m", "tx_m", "ty_m"])"),
                                        R"([[1, 0.5, -0.2], [0.5, 1, 0.1], [-0.2, 0.1, 1]])",
                                        R"([[1, -0.2, 0.1], [-0.2, 1, 0.5], [0.1, 0.5, 1]])");
  const auto c2 = propagated_covariance_m2(io::parse_transform_json(reordered, "T.json"), x, std::nullopt, false);
  ASSERT_TRUE(c2);
  EXPECT_LE(testing::max_abs_component((*c2) - (*c)), kPropagatedCovTol_m2);

  // Sigmas stated per parameter as published sets do, "correlation": "none":
  // position vector, small angle (EPSG 1033), X' = T + (1 + ds)(I + S(r)) X with
  // S(r) = [[0, −rz, ry], [rz, 0, −rx], [−ry, rx, 0]]; the columns of J by hand.
  const auto t7 = io::parse_transform_json(helmert7_with(std::string(kSigmas7) + R"(, "correlation": "none")"), "T.json");
  ASSERT_TRUE(t7.fit);
  EXPECT_TRUE(t7.fit->uncorrelated);
  const double k = M_PI / 648000.0, ds = 0.219e-6, rz = 0.554 * k;
  const Eigen::Vector3d p = x.m;
  Eigen::Matrix3d rot;
  rot << 1, -rz, 0, rz, 1, 0, 0, 0, 1;
  Eigen::Matrix<double, 3, 7> j;
  j.col(0) = Eigen::Vector3d(0.05, 0, 0);
  j.col(1) = Eigen::Vector3d(0, 0.05, 0);
  j.col(2) = Eigen::Vector3d(0, 0, 0.05);
  j.col(3) = (1 + ds) * Eigen::Vector3d(0, -p.z(), p.y()) * 0.002 * k;
  j.col(4) = (1 + ds) * Eigen::Vector3d(p.z(), 0, -p.x()) * 0.002 * k;
  j.col(5) = (1 + ds) * Eigen::Vector3d(-p.y(), p.x(), 0) * 0.002 * k;
  j.col(6) = rot * p * 0.005e-6;
  const Eigen::Matrix3d expected = j * j.transpose();
  const auto c7 = propagated_covariance_m2(t7, x, std::nullopt, false);
  ASSERT_TRUE(c7);
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) EXPECT_NEAR((*c7)(a, b), expected(a, b), kPropagatedCovTol_m2) << a << "," << b;
  }
  // A record built in code whose correlation misses a sigma'd parameter gives NaN, not the identity.
  io::TransformFile partial = t7;
  partial.fit->uncorrelated = false;
  const auto nan = propagated_covariance_m2(partial, x, std::nullopt, false);
  ASSERT_TRUE(nan);
  EXPECT_TRUE(std::isnan((*nan)(0, 0)));
}

}  // namespace
}  // namespace geoanchor::workflow
