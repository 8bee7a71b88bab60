// The deflection of the vertical in the observation model
// (solver/src/network_model.cpp, docs/network-format.md "Deflections of the
// vertical"): at a station with deflection ξ, η, a levelled instrument
// measures in the plumb line's horizon. The expected values are the
// classical reductions, written here from their published definitions and
// computed on GeographicLib's geometry, not by geoanchor's model:
//  - ξ = Φ − φ (positive north), η = (Λ − λ) cos φ (positive east): the
//    definitions Geoscience Australia gives its AUSGeoid deflections
//    ("AUSGeoid Data Format", ga.gov.au/geodesy/ausgeoid/format.jsp);
//  - zenith distance: z_astro = z_geod − (ξ cos α + η sin α);
//  - direction: α_astro = α_geod + (ξ sin α − η cos α) cot z;
//  - astronomic azimuth (Laplace): A = α + η tan φ + (ξ sin α − η cos α) cot z;
//  - astronomic latitude and longitude: Φ = φ + ξ, Λ = λ + η / cos φ
// (Featherstone & Rüeger, "The importance of using deviations of the
// vertical for the reduction of survey data to a geocentric datum", The
// Australian Surveyor 45(2), 2000, eqs. for the zenith, direction and
// Laplace corrections). The model rotates the instrument's horizon instead
// of adding corrections: the two agree to second order in the deflection
// (ε² ≈ 1e-9 rad for 8″), far inside the tolerance below.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "geoanchor/solver/network_adjustment.hpp"
#include "network_builder.hpp"

namespace geoanchor::solver {
namespace {

constexpr double kModelTol_arcsec = 1e-3;  // second-order terms of the classical corrections: ~3e-4″ at 8″

TEST(NetworkDeflection, Issue42_AnglesAreMeasuredInThePlumbLinesHorizon) {
  std::mt19937 rng(42);
  const Site s = make_site(5, rng);
  Network net = network_of(s);
  const double xi = 8.0 * kArcsec, eta = -5.0 * kArcsec;  // at station 0
  net.stations[0].geoid = geodesy::StationGeoid{47.0, {xi, eta}, "test"};
  for (std::size_t i = 1; i < 5; ++i) net.stations[i].geoid = geodesy::StationGeoid{47.0, {0.0, 0.0}, "test"};
  // Stations 1..4 held; station 0 free, placed by two baselines.
  for (std::size_t i = 1; i < 5; ++i) net.stations[i].constraint.code = {'C', 'C', 'C'};
  add_baseline(net, s, 1, 0, nullptr);
  add_baseline(net, s, 2, 0, nullptr);
  const double lat0 = s.geodetic[0][0] * std::numbers::pi / 180.0;
  net.direction_sets.push_back({0, "set at S0"});
  const double orientation = 0.3;  // the set's zero, radians
  for (std::size_t j = 1; j < 5; ++j) {
    const Sighting g = sighting(s, 0, j, 1.5, 1.2);
    const double alpha = std::atan2(g.east, g.north), z = std::atan2(std::hypot(g.east, g.north), g.up);
    const double along = xi * std::cos(alpha) + eta * std::sin(alpha), across = (xi * std::sin(alpha) - eta * std::cos(alpha)) / std::tan(z);
    NetworkMeasurement v = scalar(MeasurementKind::zenith_angle, {0, j}, z - along, 1.0 * kArcsec, "zenith " + std::to_string(j));
    v.instrument_height_m = 1.5, v.target_height_m = 1.2;
    net.measurements.push_back(v);
    double a = std::remainder(alpha + across - orientation, 2.0 * std::numbers::pi);
    if (a < 0) a += 2.0 * std::numbers::pi;
    NetworkMeasurement d = scalar(MeasurementKind::direction, {0, j}, a, 1.0 * kArcsec, "direction " + std::to_string(j));
    d.instrument_height_m = 1.5, d.target_height_m = 1.2, d.set = 0;
    net.measurements.push_back(d);
    double laplace = alpha + eta * std::tan(lat0) + across;
    if (laplace < 0) laplace += 2.0 * std::numbers::pi;
    NetworkMeasurement k = scalar(MeasurementKind::astronomic_azimuth, {0, j}, laplace, 1.0 * kArcsec, "astro azimuth " + std::to_string(j));
    k.instrument_height_m = 1.5, k.target_height_m = 1.2;
    net.measurements.push_back(k);
  }
  net.measurements.push_back(scalar(MeasurementKind::astronomic_latitude, {0}, lat0 + xi, 1.0 * kArcsec, "astro latitude"));
  net.measurements.push_back(scalar(MeasurementKind::astronomic_longitude, {0},
                                    s.geodetic[0][1] * std::numbers::pi / 180.0 + eta / std::cos(lat0), 1.0 * kArcsec, "astro longitude"));
  AdjustOptions o;
  o.data_snooping = false;
  const AdjustmentResult r = adjust_network(net, o);
  ASSERT_TRUE(r.converged);
  EXPECT_LE((r.stations[0].position - s.ecef[0]).norm(), 1e-6);  // the error-free truth
  for (const auto& m : r.measurements) {
    if (net.measurements[m.index].kind == MeasurementKind::gnss_baselines) continue;
    EXPECT_LE(std::abs(m.residual(0)) / kArcsec, kModelTol_arcsec) << net.measurements[m.index].source;  // NaN fails
  }
}


// DynAdjust's M, the arc on the geoid (its User's Guide: the MSL arc; its
// reduction include/functions/dnatemplategeodesyfuncs.hpp MSLArcDistance):
// the stations brought down their normals to the geoid (ellipsoidal height
// N), the chord between those points, and the arc of that chord on the
// sphere of radius √(ρν) + N̄ at the mean latitude. Expected here from
// GeographicLib's geocentric positions of those points.
TEST(NetworkDeflection, Issue42_AnMslArcIsTheArcOnTheGeoid) {
  std::mt19937 rng(7);
  const Site s = make_site(4, rng, 3000.0);
  Network net = network_of(s);
  const double n[4] = {47.1, 47.4, 46.8, 47.9};
  for (std::size_t i = 0; i < 4; ++i) net.stations[i].geoid = geodesy::StationGeoid{n[i], {0.0, 0.0}, "test"};
  for (std::size_t i = 1; i < 4; ++i) net.stations[i].constraint.code = {'C', 'C', 'C'};
  add_baseline(net, s, 1, 0, nullptr);
  const double a = 6378137.0, f = 1.0 / 298.257222101, e2 = f * (2.0 - f);
  for (std::size_t j = 1; j < 4; ++j) {
    double x0, y0, z0, x1, y1, z1;
    grs80().Forward(s.geodetic[0][0], s.geodetic[0][1], n[0], x0, y0, z0);
    grs80().Forward(s.geodetic[j][0], s.geodetic[j][1], n[j], x1, y1, z1);
    const double chord = std::hypot(x1 - x0, y1 - y0, z1 - z0);
    const double sl = std::sin(0.5 * (s.geodetic[0][0] + s.geodetic[j][0]) * std::numbers::pi / 180.0);
    const double rho_nu = a * std::sqrt(1.0 - e2) / (1.0 - e2 * sl * sl);  // √(ρν)
    const double r = rho_nu + 0.5 * (n[0] + n[j]);
    net.measurements.push_back(scalar(MeasurementKind::msl_arc, {0, j}, 2.0 * r * std::asin(chord / (2.0 * r)), 0.002, "msl " + std::to_string(j)));
  }
  AdjustOptions o;
  o.data_snooping = false;
  const AdjustmentResult r = adjust_network(net, o);
  ASSERT_TRUE(r.converged);
  constexpr double kArcTol_m = 1e-6;  // float64 on a few-kilometre arc
  for (const auto& m : r.measurements) EXPECT_LE(std::abs(m.residual(0)), kArcTol_m) << net.measurements[m.index].source;
  EXPECT_LE((r.stations[0].position - s.ecef[0]).norm(), 1e-6);
}

}  // namespace
}  // namespace geoanchor::solver
