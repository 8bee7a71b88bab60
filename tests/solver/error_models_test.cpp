// Instruments' error models (issue 43 point 2): the variances
// solver::apply_error_models adds, against the same terms built here
// independently — each observation recomputed by GeographicLib (local
// Cartesian frames at the instrument point, geodesics) with the instrument
// and target points moved along their own stations' east, north and up, the
// gradients taken by central differences — and the adjustment of the
// network with error models against a dense solve of the network given
// those covariances.

#include <gtest/gtest.h>

#include <GeographicLib/Geodesic.hpp>
#include <GeographicLib/LocalCartesian.hpp>

#include <array>
#include <cmath>
#include <functional>
#include <random>

#include "accuracy.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/solver/error_models.hpp"
#include "geoanchor/solver/network_adjustment.hpp"
#include "network_builder.hpp"

namespace geoanchor::solver {
namespace {

// Central differences with a 10 cm step on sights of 200–2000 m: truncation
// (step/D)² ≈ 3e-8 of the gradients, and the evaluations' own noise
// (GeographicLib's local frames ~1 nm, its geodesics 15 nm) over the step
// ≈ 2e-7.
constexpr double kStep_m = 0.1;
constexpr double kVarianceRelativeTol = 1e-6;
constexpr double kPositionTol_m = 1e-9;

geodesy::ErrorModel instrument() {
  geodesy::ErrorModel e;
  e.name = "TS";
  e.distance_constant_m = 0.001;
  e.distance_ppm = 2.0;
  e.direction_pointing_rad = 1.0 * kArcsec;
  e.direction_reading_rad = 0.5 * kArcsec;
  e.zenith_pointing_rad = 1.5 * kArcsec;
  e.zenith_reading_rad = 1.0 * kArcsec;
  e.instrument_centring_m = 0.0008;
  e.target_centring_m = 0.0012;
  e.instrument_height_m = 0.001;
  e.target_height_m = 0.0015;
  e.gnss_horizontal_m = 0.003;
  e.gnss_horizontal_ppm = 0.5;
  e.gnss_vertical_m = 0.005;
  e.gnss_vertical_ppm = 1.0;
  return e;
}

// A point `up_m` above station i moved by `d` (east, north, up of the
// station's own horizon): latitude, longitude (deg), height (m). On the
// ellipsoid (`footpoint`), the station's footpoint moved: what an arc
// between footpoints measures.
std::array<double, 3> moved(const Site& s, std::size_t i, double up_m, const Eigen::Vector3d& d, bool footpoint) {
  const GeographicLib::LocalCartesian at(s.geodetic[i][0], s.geodetic[i][1], footpoint ? 0.0 : s.geodetic[i][2], grs80());
  std::array<double, 3> g{};
  at.Reverse(d.x(), d.y(), up_m + d.z(), g[0], g[1], g[2]);
  return g;
}

// What a terrestrial observation measures from the instrument point `a` to
// the target points, in the horizon of the instrument's station `frame`
// (it does not turn as the instrument point is moved: a sight's gradient
// with respect to a point, as error_models.hpp defines it).
double observe(MeasurementKind kind, const GeographicLib::LocalCartesian& frame, const std::array<double, 3>& a,
               const std::vector<std::array<double, 3>>& to) {
  auto local = [&](const std::array<double, 3>& b) {
    Eigen::Vector3d pa, pb;
    frame.Forward(a[0], a[1], a[2], pa.x(), pa.y(), pa.z());
    frame.Forward(b[0], b[1], b[2], pb.x(), pb.y(), pb.z());
    return Eigen::Vector3d(pb - pa);
  };
  const Eigen::Vector3d l = local(to[0]);
  const double horizontal = std::hypot(l.x(), l.y());
  switch (kind) {
    case MeasurementKind::slope_distance: return l.norm();
    case MeasurementKind::horizontal_distance: return horizontal;
    case MeasurementKind::direction:
    case MeasurementKind::azimuth: return std::atan2(l.x(), l.y());
    case MeasurementKind::zenith_angle: return std::atan2(horizontal, l.z());
    case MeasurementKind::vertical_angle: return std::atan2(l.z(), horizontal);
    case MeasurementKind::horizontal_angle: {
      const Eigen::Vector3d f = local(to[1]);
      return std::remainder(std::atan2(f.x(), f.y()) - std::atan2(l.x(), l.y()), 2.0 * std::numbers::pi);
    }
    case MeasurementKind::ellipsoid_arc: {
      const GeographicLib::Geodesic geodesic(6378137.0, 1.0 / 298.257222101);
      double arc = 0.0;
      geodesic.Inverse(a[0], a[1], to[0][0], to[0][1], arc);
      return arc;
    }
    default: ADD_FAILURE() << "no observation for kind " << geodesy::to_string(kind); return 0.0;
  }
}

// The variance the set-ups add to a terrestrial observation: each end's
// point moved along its station's east and north (centring) and up (the
// measured height), by central differences.
double setup_variance(const Site& s, const geodesy::NetworkMeasurement& m, const geodesy::ErrorModel& e) {
  const std::size_t ends = m.stations.size();
  double v = 0.0;
  for (std::size_t end = 0; end < ends; ++end) {
    const bool instrument_end = end == 0;
    const double centring = instrument_end ? e.instrument_centring_m : e.target_centring_m;
    const double height = instrument_end ? e.instrument_height_m : e.target_height_m;
    for (int axis = 0; axis < 3; ++axis) {
      const auto value = [&](double step) {
        Eigen::Vector3d d = Eigen::Vector3d::Zero();
        d(axis) = step;
        const bool arc = m.kind == MeasurementKind::ellipsoid_arc;
        const auto point = [&](std::size_t k) {
          const bool ins = k == 0;
          return moved(s, m.stations[k], ins ? m.instrument_height_m : m.target_height_m, k == end ? d : Eigen::Vector3d::Zero(), arc);
        };
        std::vector<std::array<double, 3>> targets;
        for (std::size_t k = 1; k < ends; ++k) targets.push_back(point(k));
        const std::size_t at = m.stations[0];
        const GeographicLib::LocalCartesian frame(s.geodetic[at][0], s.geodetic[at][1], s.geodetic[at][2], grs80());
        return observe(m.kind, frame, point(0), targets);
      };
      double difference = value(kStep_m) - value(-kStep_m);
      if (m.kind == MeasurementKind::direction || m.kind == MeasurementKind::azimuth || m.kind == MeasurementKind::horizontal_angle) {
        difference = std::remainder(difference, 2.0 * std::numbers::pi);  // across north
      }
      const double g = difference / (2.0 * kStep_m);
      v += (axis < 2 ? centring * centring : height * height) * g * g;
    }
  }
  return v;
}

// The constant terms of the model for a terrestrial observation.
double constant_variance(const geodesy::NetworkMeasurement& m, const geodesy::ErrorModel& e) {
  switch (m.kind) {
    case MeasurementKind::slope_distance:
    case MeasurementKind::horizontal_distance:
    case MeasurementKind::ellipsoid_arc:
      return std::pow(e.distance_constant_m, 2) + std::pow(e.distance_ppm * 1e-6 * m.value(0), 2);
    case MeasurementKind::direction:
    case MeasurementKind::azimuth: return std::pow(e.direction_pointing_rad, 2) + std::pow(e.direction_reading_rad, 2);
    case MeasurementKind::horizontal_angle: return 2.0 * (std::pow(e.direction_pointing_rad, 2) + std::pow(e.direction_reading_rad, 2));
    case MeasurementKind::zenith_angle:
    case MeasurementKind::vertical_angle: return std::pow(e.zenith_pointing_rad, 2) + std::pow(e.zenith_reading_rad, 2);
    default: return 0.0;
  }
}

// The network of mixed_network with every measurement but the heights
// under the model, and the same network with the model's covariances built
// here.
struct Pair {
  Network modelled, expected;
};

Pair networks(const Site& s, std::mt19937& rng) {
  Pair p;
  p.modelled = mixed_network(s, &rng);
  p.modelled.error_models.push_back(instrument());
  const geodesy::ErrorModel& e = p.modelled.error_models.front();
  for (auto& m : p.modelled.measurements) {
    if (m.kind != MeasurementKind::ellipsoidal_height) m.error_model = 0;
  }
  p.expected = p.modelled;
  for (auto& m : p.expected.measurements) {
    if (!m.error_model) continue;
    m.error_model.reset();
    if (m.kind == MeasurementKind::gnss_baselines) {
      const std::size_t i = m.stations[0], j = m.stations[1];
      const double length = (s.ecef[j] - s.ecef[i]).norm();
      const double h2 = std::pow(e.gnss_horizontal_m, 2) + std::pow(e.gnss_horizontal_ppm * 1e-6 * length, 2);
      const double v2 = std::pow(e.gnss_vertical_m, 2) + std::pow(e.gnss_vertical_ppm * 1e-6 * length, 2);
      const Eigen::Vector3d setup(std::pow(e.instrument_centring_m, 2), std::pow(e.instrument_centring_m, 2), std::pow(e.instrument_height_m, 2));
      const Eigen::Matrix3d ri = local_to_ecef(s, i), rj = local_to_ecef(s, j);
      m.covariance += ri * Eigen::Vector3d(h2, h2, v2).asDiagonal() * ri.transpose() + ri * setup.asDiagonal() * ri.transpose() +
                      rj * setup.asDiagonal() * rj.transpose();
    } else {
      m.covariance(0, 0) += constant_variance(m, e) + setup_variance(s, m, e);
    }
  }
  return p;
}

TEST(ErrorModels, Issue43_TheVariancesAddedAreTheGeometrysOwn) {
  std::mt19937 rng(43);
  const Site s = make_site(9, rng, 600.0);
  Pair p = networks(s, rng);
  apply_error_models(p.modelled);
  ASSERT_EQ(p.modelled.measurements.size(), p.expected.measurements.size());
  double worst = 0.0;
  std::size_t compared = 0;
  for (std::size_t k = 0; k < p.modelled.measurements.size(); ++k) {
    const auto& a = p.modelled.measurements[k];
    const auto& b = p.expected.measurements[k];
    const double relative = testing::max_abs_component(a.covariance - b.covariance) / b.covariance.norm();
    worst = testing::nan_max(worst, relative);
    EXPECT_LE(relative, kVarianceRelativeTol) << a.source << " " << geodesy::to_string(a.kind);  // NaN fails
    ++compared;
  }
  EXPECT_GT(compared, 100u);
  EXPECT_LE(worst, kVarianceRelativeTol);
}

TEST(ErrorModels, Issue43_AnAdjustmentWithErrorModelsIsADenseSolveWithTheirCovariances) {
  std::mt19937 rng(431);
  const Site s = make_site(9, rng, 600.0);
  Pair p = networks(s, rng);
  apply_error_models(p.modelled);
  for (auto* net : {&p.modelled, &p.expected}) {
    for (std::size_t i : {0u, 4u}) net->stations[i].constraint.code = {'C', 'C', 'C'};
  }
  AdjustOptions sparse;
  sparse.data_snooping = false;
  AdjustOptions dense = sparse;
  dense.dense = true;
  const AdjustmentResult a = adjust_network(p.modelled, sparse);
  const AdjustmentResult b = adjust_network(p.expected, dense);
  ASSERT_TRUE(a.converged && b.converged);
  double worst_m = 0.0;
  for (std::size_t i = 0; i < a.stations.size(); ++i) {
    worst_m = testing::nan_max(worst_m, (a.stations[i].position - b.stations[i].position).norm());
    EXPECT_LE(testing::max_abs_component(a.stations[i].covariance_m2 - b.stations[i].covariance_m2),
              kVarianceRelativeTol * b.stations[i].covariance_m2.norm())  // as the inputs' covariances agree
        << a.stations[i].id;
  }
  EXPECT_LE(worst_m, kPositionTol_m);
  EXPECT_NEAR(a.vtpv, b.vtpv, kVarianceRelativeTol * b.vtpv);
}

TEST(ErrorModels, Issue43_WhatAModelCannotGiveIsRefusedByName) {
  std::mt19937 rng(7);
  const Site s = make_site(4, rng);
  Network net = network_of(s);
  geodesy::ErrorModel e;
  e.name = "EDM";
  e.distance_constant_m = 0.001;
  net.error_models.push_back(e);
  auto level = scalar(MeasurementKind::height_difference, {0, 1}, 1.0, 0.001, "t.json: measurements[0]");
  level.error_model = 0;
  net.measurements.push_back(level);
  try {
    apply_error_models(net);
    ADD_FAILURE() << "a model with no term for a height difference was applied";
  } catch (const Error& x) {
    EXPECT_EQ(x.code(), "E_ERROR_MODEL");
    EXPECT_NE(std::string(x.what()).find("t.json: measurements[0]"), std::string::npos) << x.what();
    EXPECT_NE(std::string(x.what()).find("'EDM' has no term for this kind"), std::string::npos) << x.what();
  }
  // A set-up term needs the stations' positions.
  net.measurements.clear();
  net.error_models[0].target_centring_m = 0.001;
  net.stations[1].position_known = false;
  auto d = scalar(MeasurementKind::slope_distance, {0, 1}, 400.0, 0.001, "t.json: measurements[1]");
  d.error_model = 0;
  net.measurements.push_back(d);
  try {
    apply_error_models(net);
    ADD_FAILURE() << "a set-up term was applied without the target's position";
  } catch (const Error& x) {
    EXPECT_EQ(x.code(), "E_ERROR_MODEL");
    EXPECT_NE(std::string(x.what()).find("a-priori position of station S1"), std::string::npos) << x.what();
  }
}

}  // namespace
}  // namespace geoanchor::solver
