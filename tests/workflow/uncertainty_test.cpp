// The propagated uncertainty `apply` reports, from the transform file as
// `fit -o` writes it: against the Monte Carlo spread of transformed
// positions over noisy fits (independent of any Jacobian), and at the map's
// own origin for enu-origin (where only the shift can matter).

#include <gtest/gtest.h>

#include <random>

#include "generated_control.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/io/transform_file.hpp"
#include "geoanchor/solver/helmert_fit.hpp"
#include "geoanchor/workflow/fit_export.hpp"
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
  const auto c_near = io::propagated_covariance_m2(file, near, std::nullopt, false);
  const auto c_far = io::propagated_covariance_m2(file, far, std::nullopt, false);
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
  const auto c = io::propagated_covariance_m2(file, EcefPosition(plane.origin_ecef_m()), std::nullopt, false);
  ASSERT_TRUE(c.has_value());
  const double shift_trace = r.covariance.topLeftCorner(3, 3).trace();
  EXPECT_NEAR(c->trace(), shift_trace, kRelativeTraceTol * shift_trace);
}

}  // namespace
}  // namespace geoanchor::workflow
