// STAR*NET data files: geodetic positions (P, PH) and GPS vectors (G1,
// G2, G3) — their values (network_starnet.hpp; docs/network-format.md).
//
// The vector lines as the STAR*NET-PRO V6 supplement's GPS data types and
// the vector files other programs write for it describe them: G1 From-To
// ΔX ΔY ΔZ (geocentric, metres, To − From), G2 the three variances (or,
// under .GPS WEIGHT StdErrCorrelation, the standard errors) of ΔX ΔY ΔZ,
// G3 the covariances XY XZ YZ (or the correlations).

#include <Eigen/Eigenvalues>

#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "geoanchor/base/number_text.hpp"
#include "network/network_builder.hpp"
#include "network/network_starnet.hpp"

namespace geoanchor::io::detail::starnet {
namespace {

using geodesy::MeasurementKind;

std::string text(const std::vector<std::string_view>& w) {
  std::string out;
  for (const auto t : w) out += (out.empty() ? "" : " ") + std::string(t);
  return out;
}

// DDD-MM-SS.s under .UNITS DMS; gons are refused (the supplement writes
// positions in DMS).
double geodetic_angle(std::string_view w, const Settings& s, const std::string& where, const std::string& what,
                      std::vector<std::string>& warnings) {
  if (!s.gons) {
    fail(where, what + " " + std::string(w) + " before any .UNITS DMS: STAR*NET takes the angular unit from its project options, "
                       "which the data file does not hold");
  }
  if (*s.gons) fail(where, what + " " + std::string(w) + ": geoanchor reads geodetic positions in DMS (.UNITS DMS), not gons");
  const std::string t(w);
  if (t.find('-', t[0] == '-' ? 1 : 0) == std::string::npos) {
    fail(where, what + " '" + t + "': expected degrees-minutes-seconds DDD-MM-SS.s");
  }
  return dms_text_to_rad(t, where + ": " + what, warnings);
}

}  // namespace

double latitude_rad(std::string_view w, const Settings& s, const std::string& where, std::vector<std::string>& warnings) {
  const double v = geodetic_angle(w, s, where, "latitude", warnings);
  check_angle_range(MeasurementKind::geodetic_latitude, v, std::string(w), AngleUnit::dms_text, where + ": latitude");
  return v;
}

double longitude_rad(std::string_view w, const Settings& s, const std::string& where, std::vector<std::string>& warnings) {
  if (!s.positive_west) {
    fail(where, "longitude " + std::string(w) + " before any .LONGITUDE PositiveWest|NegativeWest: the sign of STAR*NET "
                "longitudes is a project option the data file does not hold");
  }
  const double v = geodetic_angle(w, s, where, "longitude", warnings);
  const double east = *s.positive_west ? -v : v;
  check_angle_range(MeasurementKind::geodetic_longitude, east, std::string(w), AngleUnit::dms_text, where + ": longitude (east)");
  return east;
}

Eigen::Vector3d gps_delta(const std::vector<std::string_view>& w, const Settings& s, const std::string& where) {
  if (w.size() != 5) fail(where, "G1 '" + text(w) + "': expected From-To ΔX ΔY ΔZ (metres)");
  if (!s.metres_per_unit || *s.metres_per_unit != 1.0) {
    fail(where, "G1: GPS vectors are read in metres; give .UNITS Meters before them (the linear unit now is " +
                    (s.metres_per_unit ? s.linear_unit : std::string("the project's")) + ")");
  }
  Eigen::Vector3d d;
  for (int k = 0; k < 3; ++k) d(k) = length_m(w[2 + static_cast<std::size_t>(k)], s, where, std::string("G1 Δ") + "XYZ"[k]);
  return d;
}

Eigen::Matrix3d gps_covariance(const std::vector<std::string_view>& g2, const std::string& g2_where,
                               const std::vector<std::string_view>& g3, const std::string& g3_where, const Settings& s) {
  if (!s.gps_covariance) {
    fail(g2_where, "G2 before any .GPS WEIGHT Covariance|StdErrCorrelation: whether G2 and G3 hold variances and covariances "
                   "or standard errors and correlations is a project option the data file does not hold");
  }
  const bool cov = *s.gps_covariance;
  if (g2.size() != 4) {
    fail(g2_where, "G2 '" + text(g2) + "': expected the three " + (cov ? "variances (m²)" : "standard errors (m)") + " of ΔX ΔY ΔZ");
  }
  if (g3.size() != 4) {
    fail(g3_where, "G3 '" + text(g3) + "': expected the three " + (cov ? "covariances (m²)" : "correlations") + " XY XZ YZ");
  }
  std::array<double, 3> diag{}, off{};
  for (std::size_t k = 0; k < 3; ++k) {
    const auto v = parse_finite_double(g2[1 + k]);
    if (!v || !(*v > 0.0)) {
      fail(g2_where, "G2 " + std::string("XYZ").substr(k, 1) + " '" + std::string(g2[1 + k]) + "': expected a " +
                         (cov ? "variance" : "standard error") + " > 0");
    }
    diag[k] = cov ? *v : *v * *v;
    const auto c = parse_finite_double(g3[1 + k]);
    static constexpr const char* kPair[] = {"XY", "XZ", "YZ"};
    if (!c || (!cov && std::abs(*c) > 1.0)) {
      fail(g3_where, std::string("G3 ") + kPair[k] + " '" + std::string(g3[1 + k]) + "': expected a " +
                         (cov ? "covariance (m²)" : "correlation in [-1, 1]"));
    }
    off[k] = *c;
  }
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  for (int k = 0; k < 3; ++k) m(k, k) = diag[static_cast<std::size_t>(k)];
  const std::array<std::pair<int, int>, 3> pairs = {{{0, 1}, {0, 2}, {1, 2}}};
  for (std::size_t k = 0; k < 3; ++k) {
    const auto [i, j] = pairs[k];
    const double v = cov ? off[k] : off[k] * std::sqrt(diag[static_cast<std::size_t>(i)] * diag[static_cast<std::size_t>(j)]);
    m(i, j) = m(j, i) = v;
  }
  const double smallest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(m, Eigen::EigenvaluesOnly).eigenvalues()(0);
  if (!(smallest > 0.0)) {
    fail(g3_where, "the covariance of G2 (" + g2_where + ") and G3 is not positive definite (smallest eigenvalue " +
                       std::to_string(smallest) + " m²)");
  }
  return m;
}

}  // namespace geoanchor::io::detail::starnet
