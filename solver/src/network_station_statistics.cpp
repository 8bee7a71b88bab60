// A network adjustment's results per station (network_station_statistics.hpp).

#include "network_station_statistics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/base/parallel.hpp"
#include "network_helmert.hpp"

namespace geoanchor::solver {

using geodesy::MeasurementKind;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

ErrorEllipse ellipse_of(const Eigen::Matrix2d& en) {
  // en in (east, north); azimuth clockwise from north.
  const double a = en(0, 0), b = en(1, 1), ab = en(0, 1);
  const double mean = 0.5 * (a + b), diff = 0.5 * (a - b);
  const double root = std::sqrt(diff * diff + ab * ab);
  ErrorEllipse e;
  e.semi_major_m = std::sqrt(std::max(0.0, mean + root));
  e.semi_minor_m = std::sqrt(std::max(0.0, mean - root));
  e.azimuth_rad = 0.5 * std::atan2(2.0 * ab, b - a);  // from north towards east
  if (e.azimuth_rad < 0.0) e.azimuth_rad += std::numbers::pi;
  return e;
}


}  // namespace

// ellipse_of measures from its second axis towards its first, so a local
// network's x, y go in swapped.
ErrorEllipse horizontal_ellipse(const Eigen::Matrix2d& c, geodesy::NetworkSpace space) {
  if (space == geodesy::NetworkSpace::ellipsoidal) return ellipse_of(c);
  Eigen::Matrix2d yx;
  yx << c(1, 1), c(1, 0), c(0, 1), c(0, 0);
  return ellipse_of(yx);
}

namespace {

// Per station its position, covariance (in the position's axes and the
// local ones) and error ellipses.
void adjusted_stations(const NetworkProblem& p, const DatumCofactors& cofactors, AdjustmentResult& result, int jobs) {
  const auto& net = p.net;
  const auto& o = p.o;
  const double confidence_scale = confidence_scale_2d(o.confidence);
  // Each station its own (on threads).
  result.stations.assign(net.stations.size(), AdjustedStation{});
  for_chunks(net.stations.size(), kMeasurementChunk, jobs, [&](std::size_t begin, std::size_t end) {
    for (std::size_t s = begin; s < end; ++s) {
      AdjustedStation& as = result.stations[s];
      as.id = net.stations[s].id;
      as.position = p.states[s].x;
      as.a_priori = net.stations[s].position;
      as.constraint = p.aside ? "FFF" : net.stations[s].constraint.text();
      as.used = p.station_used[s];
      if (as.used) {
        // between() is along the unknowns' axes; the local ones are those at the adjusted position.
        const Eigen::Matrix3d& axes = p.states[s].axes;
        const Eigen::Matrix3d& local = p.states[s].local_from_xyz;
        as.covariance_m2 = axes.transpose() * cofactors.between(s, s) * axes;
        as.covariance_local_m2 = local * as.covariance_m2 * local.transpose();
        as.ellipse = horizontal_ellipse(as.covariance_local_m2.topLeftCorner<2, 2>(), net.space);
        as.ellipse_confidence = as.ellipse;
        as.ellipse_confidence.semi_major_m *= confidence_scale;
        as.ellipse_confidence.semi_minor_m *= confidence_scale;
      }
    }
  });
}

// The joint covariance of every station in the adjustment
// (AdjustOptions::joint_covariance), refused above
// kMaxJointCovarianceStations.
void joint_covariance(const NetworkProblem& p, const DatumCofactors& cofactors, AdjustmentResult& result) {
  const auto& net = p.net;
  const std::string where = net.source_name;
  result.covariance_stations.clear();
  for (std::size_t s = 0; s < net.stations.size(); ++s) {
    if (p.station_used[s]) result.covariance_stations.push_back(s);
  }
  const std::size_t m = result.covariance_stations.size();
  if (m > kMaxJointCovarianceStations) {
    throw Error(ErrorKind::usage, "E_JOINT_COVARIANCE",
                where + ": the joint covariance of " + std::to_string(m) + " stations (" +
                    format_shortest(72.0 * static_cast<double>(m) * static_cast<double>(m) / 1e9) +
                    " GB) is more than geoanchor writes (at most " + std::to_string(kMaxJointCovarianceStations) +
                    " stations); the stations CSV carries each station's covariance");
  }
  // Z E_s: the columns of N⁻¹ for every station unknown.
  Eigen::MatrixXd sel = Eigen::MatrixXd::Zero(p.layout.count, static_cast<Eigen::Index>(3 * m));
  for (std::size_t i = 0; i < m; ++i) {
    for (int c = 0; c < 3; ++c) {
      const Index u = p.layout.station[result.covariance_stations[i]][static_cast<std::size_t>(c)];
      if (u >= 0) sel(u, static_cast<Eigen::Index>(3 * i) + c) = 1.0;
    }
  }
  const Eigen::MatrixXd q = cofactors.selected(sel);  // local axes
  // To ECEF (ellipsoidal) per station block: Rᵢᵀ Q Rⱼ.
  result.station_covariance_m2.resize(static_cast<Eigen::Index>(3 * m), static_cast<Eigen::Index>(3 * m));
  for (std::size_t i = 0; i < m; ++i) {
    const Eigen::Matrix3d ri = p.states[result.covariance_stations[i]].axes;
    for (std::size_t j = 0; j < m; ++j) {
      const Eigen::Matrix3d rj = p.states[result.covariance_stations[j]].axes;
      result.station_covariance_m2.block<3, 3>(static_cast<Eigen::Index>(3 * i), static_cast<Eigen::Index>(3 * j)) =
          ri.transpose() * q.block<3, 3>(static_cast<Eigen::Index>(3 * i), static_cast<Eigen::Index>(3 * j)) * rj;
    }
  }
}

// The pairs of stations a measurement in the adjustment joins, each once,
// in order.
std::vector<std::pair<std::size_t, std::size_t>> joined_pairs(const NetworkProblem& p) {
  const auto& net = p.net;
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) {
    if (!p.active[mi]) continue;
    // The stations a measurement joins: a baseline's ends, a terrestrial
    // observation's stations (an observation set's each on its own; not a
    // point cluster's points, which it positions each on its own).
    for (const auto& m : geodesy::parts_of(net.measurements[mi])) {
      const auto& st = m.stations;
      if (m.kind == MeasurementKind::gnss_points) continue;
      for (std::size_t a = 0; a < st.size(); ++a) {
        for (std::size_t b = a + 1; b < st.size(); ++b) {
          if (m.kind == MeasurementKind::gnss_baselines && !(a % 2 == 0 && b == a + 1)) continue;
          if (st[a] != st[b]) pairs.push_back({std::min(st[a], st[b]), std::max(st[a], st[b])});
        }
      }
    }
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

// Relative precision between stations that share a measurement.
void relative_precision(const NetworkProblem& p, const DatumCofactors& cofactors, AdjustmentResult& result, int jobs) {
  const auto& net = p.net;
  const std::vector<std::pair<std::size_t, std::size_t>> pairs = joined_pairs(p);
  result.relative.assign(pairs.size(), RelativePrecision{});
  for_chunks(pairs.size(), kMeasurementChunk, jobs, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const auto [s1, s2] = pairs[k];
      // In the axes of the first station; a local network's axes are one.
      const Eigen::Matrix3d a1 = p.states[s1].axes, a2 = p.states[s2].axes, r1 = p.states[s1].local_from_xyz;
      const Eigen::Matrix3d c11 = a1.transpose() * cofactors.between(s1, s1) * a1, c22 = a2.transpose() * cofactors.between(s2, s2) * a2;
      const Eigen::Matrix3d c12 = a1.transpose() * cofactors.between(s1, s2) * a2;
      const Eigen::Matrix3d diff = r1 * (c11 + c22 - c12 - c12.transpose()) * r1.transpose();
      RelativePrecision rp;
      rp.from = s1;
      rp.to = s2;
      const Eigen::Vector3d dxyz = p.states[s2].x - p.states[s1].x;
      rp.distance_m = dxyz.norm();
      const Eigen::Vector3d unit_local = r1 * dxyz / std::max(rp.distance_m, 1e-12);
      rp.sigma_distance_m = std::sqrt(std::max(0.0, unit_local.dot(diff * unit_local)));
      rp.ellipse = horizontal_ellipse(diff.topLeftCorner<2, 2>(), net.space);
      result.relative[k] = rp;
    }
  });
}

}  // namespace

void station_statistics(const NetworkProblem& p, const NormalFactor& f, const InnerConstraints& inner, AdjustmentResult& result,
                        int jobs) {
  // Stations: coordinates and covariances (S-transformed for a free network).
  const DatumCofactors cofactors(p, f, inner);
  adjusted_stations(p, cofactors, result, jobs);
  if (p.o.joint_covariance) joint_covariance(p, cofactors, result);
  result.orientations_rad = p.orientations;
  result.orientation_sigmas_rad.clear();
  for (std::size_t k = 0; k < p.orientations.size(); ++k) {
    const Index u = p.layout.orientation[k];
    result.orientation_sigmas_rad.push_back(u >= 0 ? std::sqrt(std::max(0.0, f.inverse(u, u))) : kNaN);
  }
  if (!p.layout.helmert.empty()) result.helmert = estimated_helmert(p, f);
  relative_precision(p, cofactors, result, jobs);
}

}  // namespace geoanchor::solver
