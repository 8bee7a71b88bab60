#pragma once
// Networks built from a known truth for the solver's and workflow's tests:
// stations on a jittered grid around Zürich airport on GRS80, GNSS
// baselines with covariances at their first station, and terrestrial
// observations computed by GeographicLib (geocentric positions, local
// east/north/up at the instrument), with or without noise.

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <GeographicLib/Geocentric.hpp>
#include <GeographicLib/Geodesic.hpp>
#include <GeographicLib/LocalCartesian.hpp>

#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "geoanchor/geodesy/network.hpp"

namespace geoanchor::solver {
namespace {

using geodesy::MeasurementKind;
using geodesy::Network;
using geodesy::NetworkMeasurement;
using geodesy::NetworkStation;

constexpr double kArcsec = std::numbers::pi / 648000.0;

inline const GeographicLib::Geocentric& grs80() {
  static const GeographicLib::Geocentric g(6378137.0, 1.0 / 298.257222101);  // GRS 1980, EPSG:7019
  return g;
}

// Stations on a jittered grid around Zürich airport, truth on GRS80.
struct Site {
  std::vector<Eigen::Vector3d> ecef;  // truth
  std::vector<std::array<double, 3>> geodetic;  // lat, lon (deg), h (m)
};

inline Site make_site(int n, std::mt19937& rng, double spacing_m = 400.0) {
  Site s;
  std::uniform_real_distribution<double> jitter(-0.3, 0.3), height(420.0, 520.0);
  const int side = static_cast<int>(std::ceil(std::sqrt(n)));
  for (int i = 0; i < n; ++i) {
    const double e = (i % side + jitter(rng)) * spacing_m, nn = (i / side + jitter(rng)) * spacing_m;
    const double lat = 47.45 + nn / 111200.0, lon = 8.54 + e / (111200.0 * std::cos(47.45 * std::numbers::pi / 180.0));
    const double h = height(rng);
    double x = 0, y = 0, z = 0;
    grs80().Forward(lat, lon, h, x, y, z);
    s.ecef.emplace_back(x, y, z);
    s.geodetic.push_back({lat, lon, h});
  }
  return s;
}

inline Network network_of(const Site& s) {
  Network net;
  net.ellipsoid = geodesy::Ellipsoid::grs80();
  net.source_name = "test network";
  for (std::size_t i = 0; i < s.ecef.size(); ++i) {
    NetworkStation st;
    st.id = "S" + std::to_string(i);
    st.position = s.ecef[i];
    st.source = "station " + std::to_string(i);
    net.stations.push_back(st);
  }
  return net;
}

// GeographicLib's east/north/up → ECEF rotation at station `at` of the
// truth (independent of the code's axes).
inline Eigen::Matrix3d local_to_ecef(const Site& s, std::size_t at) {
  double x = 0, y = 0, z = 0;
  std::vector<double> m(9);
  grs80().Forward(s.geodetic[at][0], s.geodetic[at][1], s.geodetic[at][2], x, y, z, m);
  Eigen::Matrix3d r;
  r << m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8];
  return r;
}

// A baseline's covariance: 3 mm horizontal, 6 mm vertical at the first
// station, rotated into ECEF with GeographicLib's east/north/up matrix.
inline Eigen::Matrix3d baseline_covariance(const Site& s, std::size_t at) {
  const Eigen::Matrix3d r = local_to_ecef(s, at);
  const Eigen::Matrix3d local = Eigen::Vector3d(0.003 * 0.003, 0.003 * 0.003, 0.006 * 0.006).asDiagonal();
  return r * local * r.transpose();
}

// Draws e ~ N(0, C).
inline Eigen::VectorXd draw(const Eigen::MatrixXd& c, std::mt19937& rng) {
  std::normal_distribution<double> z;
  Eigen::VectorXd u(c.rows());
  for (Eigen::Index k = 0; k < u.size(); ++k) u(k) = z(rng);
  return Eigen::LLT<Eigen::MatrixXd>(c).matrixL() * u;
}

inline void add_baseline(Network& net, const Site& s, std::size_t i, std::size_t j, std::mt19937* rng) {
  NetworkMeasurement m;
  m.kind = MeasurementKind::gnss_baselines;
  m.stations = {i, j};
  m.covariance = baseline_covariance(s, i);
  m.value = s.ecef[j] - s.ecef[i];
  if (rng) m.value += draw(m.covariance, *rng);
  m.source = "baseline " + std::to_string(i) + "-" + std::to_string(j);
  net.measurements.push_back(m);
}

// Terrestrial observations from i to j computed by GeographicLib: the
// target's east/north/up in the local Cartesian frame at the instrument
// point (instrument height hi above i, target height ht above j, both along
// the ellipsoid normal).
struct Sighting {
  double east, north, up;
};
inline Sighting sighting(const Site& s, std::size_t i, std::size_t j, double hi, double ht) {
  const GeographicLib::LocalCartesian at(s.geodetic[i][0], s.geodetic[i][1], s.geodetic[i][2] + hi, grs80());
  Sighting g{};
  at.Forward(s.geodetic[j][0], s.geodetic[j][1], s.geodetic[j][2] + ht, g.east, g.north, g.up);
  return g;
}

inline NetworkMeasurement scalar(MeasurementKind k, std::vector<std::size_t> stations, double value, double sigma, const std::string& src) {
  NetworkMeasurement m;
  m.kind = k;
  m.stations = std::move(stations);
  m.value = Eigen::VectorXd::Constant(1, value);
  m.covariance = Eigen::MatrixXd::Constant(1, 1, sigma * sigma);
  m.source = src;
  return m;
}

// A mixed network: baselines, slope and horizontal distances, direction
// sets, zenith and vertical angles, azimuths, angles, ellipsoidal heights
// and an ellipsoid arc, all computed from the truth (noise optional).
inline Network mixed_network(const Site& s, std::mt19937* rng) {
  Network net = network_of(s);
  std::normal_distribution<double> z;
  auto noise = [&](double sigma) { return rng ? sigma * z(*rng) : 0.0; };
  const std::size_t n = s.ecef.size();
  for (std::size_t i = 0; i + 1 < n; ++i) add_baseline(net, s, i, i + 1, rng);
  for (std::size_t i = 0; i + 3 < n; i += 2) add_baseline(net, s, i, i + 3, rng);
  const double hi = 1.55, ht = 1.30;
  const double sd = 0.002, sa = 1.0 * kArcsec;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t set = net.direction_sets.size();
    net.direction_sets.push_back({i, "set at " + std::to_string(i)});
    const double orientation = 0.3 + 0.1 * static_cast<double>(i);
    for (std::size_t j : {(i + 1) % n, (i + 2) % n, (i + 5) % n}) {
      const Sighting g = sighting(s, i, j, hi, ht);
      const double horizontal = std::hypot(g.east, g.north), slope = std::hypot(horizontal, g.up);
      const double azimuth = std::atan2(g.east, g.north), zenith = std::atan2(horizontal, g.up);
      auto m = scalar(MeasurementKind::slope_distance, {i, j}, slope + noise(sd), sd, "slope");
      m.instrument_height_m = hi, m.target_height_m = ht;
      net.measurements.push_back(m);
      m = scalar(MeasurementKind::horizontal_distance, {i, j}, horizontal + noise(sd), sd, "horizontal");
      m.instrument_height_m = hi, m.target_height_m = ht;
      net.measurements.push_back(m);
      m = scalar(MeasurementKind::direction, {i, j}, azimuth - orientation + noise(sa), sa, "direction");
      m.instrument_height_m = hi, m.target_height_m = ht;
      m.set = set;
      net.measurements.push_back(m);
      m = scalar(MeasurementKind::zenith_angle, {i, j}, zenith + noise(sa), sa, "zenith");
      m.instrument_height_m = hi, m.target_height_m = ht;
      net.measurements.push_back(m);
    }
    const std::size_t a = (i + 1) % n, b = (i + 3) % n;
    const Sighting ga = sighting(s, i, a, hi, ht), gb = sighting(s, i, b, hi, ht);
    auto m = scalar(MeasurementKind::horizontal_angle, {i, a, b},
                    std::remainder(std::atan2(gb.east, gb.north) - std::atan2(ga.east, ga.north), 2 * std::numbers::pi) + noise(sa),
                    sa, "angle");
    m.instrument_height_m = hi, m.target_height_m = ht;
    net.measurements.push_back(m);
    m = scalar(MeasurementKind::vertical_angle, {i, b}, std::atan2(gb.up, std::hypot(gb.east, gb.north)) + noise(sa), sa, "vertical");
    m.instrument_height_m = hi, m.target_height_m = ht;
    net.measurements.push_back(m);
    m = scalar(MeasurementKind::azimuth, {i, b}, std::atan2(gb.east, gb.north) + noise(sa), sa, "azimuth");
    m.instrument_height_m = hi, m.target_height_m = ht;
    net.measurements.push_back(m);
    net.measurements.push_back(scalar(MeasurementKind::ellipsoidal_height, {i}, s.geodetic[i][2] + noise(0.01), 0.01, "h"));
  }
  // Ellipsoid arcs: GeographicLib's geodesic between the footpoints.
  const GeographicLib::Geodesic geodesic(6378137.0, 1.0 / 298.257222101);
  for (std::size_t i = 0; i + 2 < n; i += 3) {
    double arc = 0.0;
    geodesic.Inverse(s.geodetic[i][0], s.geodetic[i][1], s.geodetic[i + 2][0], s.geodetic[i + 2][1], arc);
    net.measurements.push_back(scalar(MeasurementKind::ellipsoid_arc, {i, i + 2}, arc + noise(sd), sd, "arc"));
  }
  return net;
}

}  // namespace
}  // namespace geoanchor::solver
