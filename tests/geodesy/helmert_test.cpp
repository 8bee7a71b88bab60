// Helmert transforms against PROJ (+proj=helmert) and the IOGP worked examples.

#include <gtest/gtest.h>

#include <random>
#include <type_traits>

#include "geoanchor/geodesy/helmert.hpp"
#include "proj_reference.hpp"
#include "test_support.hpp"

namespace geoanchor::geodesy {
namespace {

using testing::IsNearVector;
using testing::ProjPipeline;

constexpr double kVsProjTol_m = 1e-6;          // issue acceptance
constexpr double kRoundTripTol_m = 1e-8;       // float64 spacing at Earth radius is 9.3e-10 m
// Per axis: GN 7-2 prints the 7-parameter example's input and its result rounded to
// the centimetre, so up to 5 mm of input rounding plus 5 mm of output rounding.
constexpr double kCentimetreExampleTol_m = 0.01;
constexpr double kMillimetreExampleTol_m = 0.0005; // GN 7-2 gives the time-dependent result to the millimetre
constexpr double kComposeTol_m = 1e-8;
constexpr double kPublishedParameterTol_m = 0.000005;   // GN 7-2 lists tX' to 0.01 mm
constexpr double kPublishedRotationTol_rad = 5e-13;     // GN 7-2 lists rX' to 1e-12 rad
constexpr double kLinearityTol = 1e-12;        // metres or arc-seconds: float64 noise on values of order 100

// A convention mix-up does not compile: a coordinate-frame set is not a
// position-vector set and does not convert into one implicitly.
static_assert(!std::is_convertible_v<Helmert7<CoordinateFrame>, Helmert7<PositionVector>>);
static_assert(!std::is_convertible_v<Helmert7<PositionVector>, Helmert7<CoordinateFrame>>);
static_assert(!std::is_convertible_v<Helmert14<CoordinateFrame>, Helmert14<PositionVector>>);
EcefPosition apply_position_vector(const Helmert7<PositionVector>& h, const EcefPosition& p) {
  return apply(h, RotationModel::small_angle, p);
}
static_assert(std::is_invocable_v<decltype(&apply_position_vector), Helmert7<PositionVector>, EcefPosition>);
static_assert(!std::is_invocable_v<decltype(&apply_position_vector), Helmert7<CoordinateFrame>, EcefPosition>);
// ... and the explicit conversion call is what makes it possible.
static_assert(std::is_invocable_v<decltype(&apply_position_vector),
                                  decltype(to_position_vector(std::declval<Helmert7<CoordinateFrame>>())), EcefPosition>);

// Float32 ECEF does not compile.
static_assert(!std::is_constructible_v<EcefPosition, float, float, float>);
static_assert(!std::is_constructible_v<EcefPosition, Eigen::Vector3f>);
static_assert(std::is_constructible_v<EcefPosition, double, double, double>);

Helmert7<PositionVector> wgs72_to_wgs84_pv() {
  // IOGP GN 7-2, EPSG method 1033 example (WGS 72 -> WGS 84): tz = +4.5 m,
  // rz = +0.554″, ds = +0.219 ppm, position vector.
  Helmert7<PositionVector> h;
  h.t_m = Eigen::Vector3d(0.0, 0.0, 4.5);
  h.rz = Angle::arcseconds(0.554);
  h.ds = ScaleDifference::ppm(0.219);
  return h;
}

// GN 7-2 prints each coordinate rounded to the centimetre: compare per axis.
void expect_published_cm(const Eigen::Vector3d& out) {
  EXPECT_NEAR(out.x(), 3657660.78, kCentimetreExampleTol_m);
  EXPECT_NEAR(out.y(), 255778.43, kCentimetreExampleTol_m);
  EXPECT_NEAR(out.z(), 5201387.75, kCentimetreExampleTol_m);
}

TEST(Helmert, IogpPositionVectorExample) {
  // Source (3657660.66, 255768.55, 5201382.11) -> (3657660.78, 255778.43, 5201387.75).
  const EcefPosition out = apply(wgs72_to_wgs84_pv(), RotationModel::small_angle, EcefPosition(3657660.66, 255768.55, 5201382.11));
  expect_published_cm(out.m);
}

TEST(Helmert, IogpCoordinateFrameExample) {
  // IOGP GN 7-2, EPSG method 1032 example: the same WGS 72 -> WGS 84 with
  // rz = -0.554″ in the coordinate-frame convention gives the same result.
  Helmert7<CoordinateFrame> h;
  h.t_m = Eigen::Vector3d(0.0, 0.0, 4.5);
  h.rz = Angle::arcseconds(-0.554);
  h.ds = ScaleDifference::ppm(0.219);
  const EcefPosition out = apply(h, RotationModel::small_angle, EcefPosition(3657660.66, 255768.55, 5201382.11));
  expect_published_cm(out.m);
}

Helmert14<PositionVector> itrf2008_to_gda94() {
  // IOGP GN 7-2, EPSG method 1053 example: ITRF2008 -> GDA94, reference
  // epoch 1994.00, position vector (Dawson & Woods 2010 parameters).
  Helmert14<PositionVector> h;
  h.at_reference_epoch.t_m = Eigen::Vector3d(-0.08468, -0.01942, 0.03201);
  h.at_reference_epoch.rx = Angle::milliarcseconds(0.4254);
  h.at_reference_epoch.ry = Angle::milliarcseconds(-2.2578);
  h.at_reference_epoch.rz = Angle::milliarcseconds(-2.4015);
  h.at_reference_epoch.ds = ScaleDifference::ppb(9.71);
  h.rates.dt_m_per_year = Eigen::Vector3d(0.00142, 0.00134, 0.00090);
  h.rates.drx_per_year = Angle::milliarcseconds(-1.5461);
  h.rates.dry_per_year = Angle::milliarcseconds(-1.1820);
  h.rates.drz_per_year = Angle::milliarcseconds(-1.1551);
  h.rates.dds_per_year = ScaleDifference::ppb(0.109);
  h.reference_epoch = DecimalYear{1994.0};
  return h;
}

TEST(Helmert, IogpTimeDependentExampleAtEpoch2013_9) {
  // Source (-3789470.710, 4841770.404, -1690893.952) at 2013.90 ->
  // GDA94 (-3789470.004, 4841770.686, -1690895.108).
  const Eigen::Vector3d src(-3789470.710, 4841770.404, -1690893.952);
  const Eigen::Vector3d expected(-3789470.004, 4841770.686, -1690895.108);
  const auto pv = evaluate_at(itrf2008_to_gda94(), DecimalYear{2013.90});
  EXPECT_THAT(apply(pv, RotationModel::small_angle, EcefPosition(src)).m, IsNearVector(expected, kMillimetreExampleTol_m));
  // The same set in the coordinate-frame convention (EPSG method 1056) gives the same point.
  const auto cf = evaluate_at(to_coordinate_frame(itrf2008_to_gda94()), DecimalYear{2013.90});
  EXPECT_THAT(apply(cf, RotationModel::small_angle, EcefPosition(src)).m, IsNearVector(expected, kMillimetreExampleTol_m));
  // GN 7-2 also lists the parameters at 2013.90: tX = -0.05642 m, rX = -1.471021e-7 rad (position vector).
  EXPECT_NEAR(pv.t_m.x(), -0.05642, kPublishedParameterTol_m);
  EXPECT_NEAR(pv.rx.rad(), -1.471021e-7, kPublishedRotationTol_rad);
}

std::string proj_helmert(const Helmert14<PositionVector>& h, std::string_view convention, bool exact) {
  // PROJ takes rotations in arc-seconds and scale in ppm, in the convention named.
  const double sign = convention == "coordinate_frame" ? -1.0 : 1.0;
  const auto& p = h.at_reference_epoch;
  const auto& r = h.rates;
  char buf[1024];
  std::snprintf(buf, sizeof buf,
                "+proj=helmert +x=%.17g +y=%.17g +z=%.17g +rx=%.17g +ry=%.17g +rz=%.17g +s=%.17g +dx=%.17g +dy=%.17g "
                "+dz=%.17g +drx=%.17g +dry=%.17g +drz=%.17g +ds=%.17g +t_epoch=%.17g +convention=%s%s",
                p.t_m.x(), p.t_m.y(), p.t_m.z(), sign * p.rx.arcsec(), sign * p.ry.arcsec(), sign * p.rz.arcsec(),
                p.ds.ppm(), r.dt_m_per_year.x(), r.dt_m_per_year.y(), r.dt_m_per_year.z(), sign * r.drx_per_year.arcsec(),
                sign * r.dry_per_year.arcsec(), sign * r.drz_per_year.arcsec(), r.dds_per_year.ppm(),
                h.reference_epoch.year, std::string(convention).c_str(), exact ? " +exact" : "");
  return buf;
}

Helmert14<PositionVector> random_helmert14(std::mt19937_64& rng, double rotation_scale_arcsec) {
  std::normal_distribution<double> t(0.0, 100.0), r(0.0, rotation_scale_arcsec), s(0.0, 5.0), dt(0.0, 0.01),
      dr(0.0, 0.001), ds(0.0, 0.01);
  Helmert14<PositionVector> h;
  h.at_reference_epoch.t_m = Eigen::Vector3d(t(rng), t(rng), t(rng));
  h.at_reference_epoch.rx = Angle::arcseconds(r(rng));
  h.at_reference_epoch.ry = Angle::arcseconds(r(rng));
  h.at_reference_epoch.rz = Angle::arcseconds(r(rng));
  h.at_reference_epoch.ds = ScaleDifference::ppm(s(rng));
  h.rates.dt_m_per_year = Eigen::Vector3d(dt(rng), dt(rng), dt(rng));
  h.rates.drx_per_year = Angle::arcseconds(dr(rng));
  h.rates.dry_per_year = Angle::arcseconds(dr(rng));
  h.rates.drz_per_year = Angle::arcseconds(dr(rng));
  h.rates.dds_per_year = ScaleDifference::ppm(ds(rng));
  h.reference_epoch = DecimalYear{2010.0};
  return h;
}

struct Case {
  const char* convention;
  RotationModel model;
};

class HelmertVsProj : public ::testing::TestWithParam<Case> {};

TEST_P(HelmertVsProj, FourteenParametersAgreeAtSeveralEpochs) {
  const Case c = GetParam();
  std::mt19937_64 rng(42);
  const auto points = testing::worldwide_points(10000, -1000.0, 10000.0, 29);
  const double epochs[] = {1994.0, 2010.0, 2013.9, 2024.5, 2031.25};
  testing::WorstCase worst_m;
  for (int set = 0; set < 20; ++set) {
    // Rotations up to tens of arc-seconds: enough for the exact and small-angle forms to differ by metres.
    const auto pv = random_helmert14(rng, set < 10 ? 1.0 : 20.0);
    const ProjPipeline ref(proj_helmert(pv, c.convention, c.model == RotationModel::exact));
    for (double epoch : epochs) {
      const DecimalYear t{epoch};
      const AffineMap map = std::string_view(c.convention) == "position_vector"
                                ? target_from_source(evaluate_at(pv, t), c.model)
                                : target_from_source(evaluate_at(to_coordinate_frame(pv), t), c.model);
      for (std::size_t i = static_cast<std::size_t>(set); i < points.size(); i += 20) {
        const auto& g = points[i];
        const double cl = std::cos(g.lat.rad());
        const Eigen::Vector3d x(6378137.0 * cl * std::cos(g.lon.rad()), 6378137.0 * cl * std::sin(g.lon.rad()),
                                6356752.0 * std::sin(g.lat.rad()));
        worst_m.add((map.apply(x) - ref.forward(x, epoch)).norm());
        ASSERT_THAT(map.apply(x), IsNearVector(ref.forward(x, epoch), kVsProjTol_m))
            << proj_helmert(pv, c.convention, c.model == RotationModel::exact) << " at " << epoch;
      }
    }
  }
  EXPECT_WORST_WITHIN(worst_m, kVsProjTol_m);
  RecordProperty("worst_helmert_difference_m", testing::scientific(worst_m.value()));
}

TEST_P(HelmertVsProj, ExactInverseRoundTripsTo1e8m) {
  const Case c = GetParam();
  std::mt19937_64 rng(43);
  for (int set = 0; set < 50; ++set) {
    const auto pv = evaluate_at(random_helmert14(rng, 20.0), DecimalYear{2020.0});
    const AffineMap fwd = std::string_view(c.convention) == "position_vector" ? target_from_source(pv, c.model)
                                                                             : target_from_source(to_coordinate_frame(pv), c.model);
    const AffineMap inv = std::string_view(c.convention) == "position_vector" ? source_from_target(pv, c.model)
                                                                             : source_from_target(to_coordinate_frame(pv), c.model);
    for (const auto& g : testing::worldwide_points(200, -1000.0, 1.0e5, static_cast<unsigned>(set))) {
      const Eigen::Vector3d x(6378137.0 * std::cos(g.lat.rad()) * std::cos(g.lon.rad()),
                              6378137.0 * std::cos(g.lat.rad()) * std::sin(g.lon.rad()), 6356752.0 * std::sin(g.lat.rad()));
      ASSERT_THAT(inv.apply(fwd.apply(x)), IsNearVector(x, kRoundTripTol_m));
    }
  }
}

INSTANTIATE_TEST_SUITE_P(ConventionsAndModels, HelmertVsProj,
                         ::testing::Values(Case{"position_vector", RotationModel::small_angle},
                                           Case{"coordinate_frame", RotationModel::small_angle},
                                           Case{"position_vector", RotationModel::exact},
                                           Case{"coordinate_frame", RotationModel::exact}));

TEST(Helmert, ConventionSwapNegatesRotationsOnly) {
  std::mt19937_64 rng(7);
  const auto pv14 = random_helmert14(rng, 5.0);
  const auto cf14 = to_coordinate_frame(pv14);
  EXPECT_EQ(cf14.at_reference_epoch.t_m, pv14.at_reference_epoch.t_m);
  EXPECT_EQ(cf14.at_reference_epoch.ds, pv14.at_reference_epoch.ds);
  EXPECT_EQ(cf14.at_reference_epoch.rx, -pv14.at_reference_epoch.rx);
  EXPECT_EQ(cf14.rates.drz_per_year, -pv14.rates.drz_per_year);
  EXPECT_EQ(cf14.rates.dt_m_per_year, pv14.rates.dt_m_per_year);
  EXPECT_EQ(cf14.reference_epoch, pv14.reference_epoch);
  // In the small-angle model both describe the very same matrix.
  const auto pv = evaluate_at(pv14, DecimalYear{2015.0});
  const auto cf = evaluate_at(cf14, DecimalYear{2015.0});
  EXPECT_EQ(rotation_matrix(pv, RotationModel::small_angle), rotation_matrix(cf, RotationModel::small_angle));
  const auto back = to_position_vector(cf14);
  EXPECT_EQ(back.at_reference_epoch.ry, pv14.at_reference_epoch.ry);
}

// (r² + s·r)·|X| for r = 1″ (4.8e-6 rad), s = 1 ppm, |X| = 6.4e6 m: between 10 µm and 1 mm.
constexpr double kSecondOrderFloor_m = 1e-5;
constexpr double kSecondOrderCeiling_m = 1e-3;

TEST(Helmert, NegatedParametersAreOnlyAnApproximateInverse) {
  // GN 7-2's "reversible" reverse. With 1″ rotations and 1 ppm scale at Earth
  // radius the second-order error is below 1 mm but far above float64 noise.
  Helmert7<PositionVector> h;
  h.t_m = Eigen::Vector3d(100.0, -50.0, 25.0);
  h.rx = Angle::arcseconds(1.0);
  h.ry = Angle::arcseconds(-1.0);
  h.rz = Angle::arcseconds(1.0);
  h.ds = ScaleDifference::ppm(1.0);
  const Eigen::Vector3d x(4270803.44, 640437.85, 4678617.58);
  const Eigen::Vector3d y = apply(h, RotationModel::small_angle, EcefPosition(x)).m;
  const double approx_error_m = (apply(negated_parameters(h), RotationModel::small_angle, EcefPosition(y)).m - x).norm();
  const double exact_error_m = (source_from_target(h, RotationModel::small_angle).apply(y) - x).norm();
  EXPECT_GT(approx_error_m, kSecondOrderFloor_m);
  EXPECT_LT(approx_error_m, kSecondOrderCeiling_m);
  EXPECT_LT(exact_error_m, kRoundTripTol_m);
}

TEST(Helmert, CompositionEqualsApplyingInTurn) {
  std::mt19937_64 rng(8);
  const auto a = evaluate_at(random_helmert14(rng, 10.0), DecimalYear{2020.0});
  const auto b = to_coordinate_frame(evaluate_at(random_helmert14(rng, 10.0), DecimalYear{2020.0}));
  const AffineMap c_from_a = compose(target_from_source(b, RotationModel::exact), target_from_source(a, RotationModel::small_angle));
  const Eigen::Vector3d x(-3789470.710, 4841770.404, -1690893.952);
  const Eigen::Vector3d in_turn = apply(b, RotationModel::exact, apply(a, RotationModel::small_angle, EcefPosition(x))).m;
  EXPECT_THAT(c_from_a.apply(x), IsNearVector(in_turn, kComposeTol_m));
}

TEST(Helmert, FourteenParametersAreLinearInTimeAndEqualTheSevenAtTheReferenceEpoch) {
  std::mt19937_64 rng(9);
  const auto h = random_helmert14(rng, 1.0);
  const auto at_ref = evaluate_at(h, h.reference_epoch);
  EXPECT_EQ(at_ref.t_m, h.at_reference_epoch.t_m);
  EXPECT_EQ(at_ref.rz, h.at_reference_epoch.rz);
  const auto a = evaluate_at(h, DecimalYear{2000.0}), b = evaluate_at(h, DecimalYear{2010.0}),
             c = evaluate_at(h, DecimalYear{2020.0});
  EXPECT_NEAR((a.t_m + c.t_m - 2.0 * b.t_m).norm(), 0.0, kLinearityTol);
  EXPECT_NEAR(a.rx.arcsec() + c.rx.arcsec() - 2.0 * b.rx.arcsec(), 0.0, kLinearityTol);
}

}  // namespace
}  // namespace geoanchor::geodesy
