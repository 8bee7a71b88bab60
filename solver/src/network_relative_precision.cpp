// Relative precision between pairs of adjusted stations
// (network_relative_precision.hpp).

#include "network_relative_precision.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/parallel.hpp"
#include "network_station_statistics.hpp"
#include "statistics.hpp"

namespace geoanchor::solver {

using geodesy::MeasurementKind;

namespace {

// Radius of the sphere the ellipsoidal stations' horizontal positions are
// taken to for the grid (metres): only candidates come from it.
constexpr double kGridSphereRadius_m = 6371000.0;
// The grid's cells exceed the radius by this share and this much: the
// sphere's chord differs from the horizontal distance in the first
// station's horizon by the Earth's flattening (the normal leans up to
// 0.19° from the geocentric direction: 3.4 mm per metre of height
// difference) and curvature; the exact test follows.
constexpr double kGridMarginShare = 0.01;
constexpr double kGridMargin_m = 50.0;

// The pairs a measurement in the adjustment joins.
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
  return pairs;
}

// The horizontal distance of s2 from s1 in the horizon of s1.
double horizontal_distance(const NetworkProblem& p, std::size_t s1, std::size_t s2) {
  const Eigen::Vector3d d = p.states[s1].local_from_xyz * (p.states[s2].x - p.states[s1].x);
  return d.head<2>().norm();
}

// Every pair of used stations within p.o.relative.radius_m horizontally.
std::vector<std::pair<std::size_t, std::size_t>> radius_pairs(const NetworkProblem& p, const std::vector<std::size_t>& used) {
  const double radius = p.o.relative.radius_m;
  const double cell = radius * (1.0 + kGridMarginShare) + kGridMargin_m;
  const bool sphere = p.net.space == geodesy::NetworkSpace::ellipsoidal;
  // Each station's cell (of its point on the sphere, or its x, y).
  struct Entry {
    std::array<std::int64_t, 3> c;
    std::size_t s;
    bool operator<(const Entry& o) const { return c != o.c ? c < o.c : s < o.s; }
  };
  std::vector<Entry> grid;
  grid.reserve(used.size());
  std::vector<Eigen::Vector3d> point(p.states.size());
  for (std::size_t s : used) {
    const Eigen::Vector3d& x = p.states[s].x;
    point[s] = sphere ? Eigen::Vector3d(x.normalized() * kGridSphereRadius_m) : Eigen::Vector3d(x(0), x(1), 0.0);
    Entry e{{}, s};
    for (int k = 0; k < 3; ++k) e.c[static_cast<std::size_t>(k)] = static_cast<std::int64_t>(std::floor(point[s](k) / cell));
    grid.push_back(e);
  }
  std::sort(grid.begin(), grid.end());
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (const Entry& e : grid) {
    for (std::int64_t dx = -1; dx <= 1; ++dx) {
      for (std::int64_t dy = -1; dy <= 1; ++dy) {
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          const std::array<std::int64_t, 3> c{e.c[0] + dx, e.c[1] + dy, e.c[2] + dz};
          auto it = std::lower_bound(grid.begin(), grid.end(), Entry{c, 0});
          for (; it != grid.end() && it->c == c; ++it) {
            if (it->s <= e.s) continue;  // each pair once, from its lower index
            if (horizontal_distance(p, e.s, it->s) <= radius) pairs.push_back({e.s, it->s});
          }
        }
      }
    }
  }
  return pairs;
}

}  // namespace

double ellipse_confidence_scale(double confidence) { return std::sqrt(-2.0 * std::log(1.0 - confidence)); }
double interval_confidence_scale(double confidence) { return normal_quantile(0.5 + 0.5 * confidence); }

std::vector<std::pair<std::size_t, std::size_t>> relative_pairs(const NetworkProblem& p) {
  const RelativeOptions& o = p.o.relative;
  std::vector<std::size_t> used;
  for (std::size_t s = 0; s < p.station_used.size(); ++s) {
    if (p.station_used[s]) used.push_back(s);
  }
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  switch (o.pairs) {
    case RelativePairs::connected:
      pairs = joined_pairs(p);
      break;
    case RelativePairs::all: {
      const std::size_t m = used.size();
      const std::size_t count = m < 2 ? 0 : m * (m - 1) / 2;
      if (count > kMaxAllRelativePairs) {
        throw Error(ErrorKind::usage, "E_OPTION",
                    "--relative all: " + std::to_string(m) + " stations make " + std::to_string(count) + " pairs, more than " +
                        std::to_string(kMaxAllRelativePairs) + "; give --relative radius:R_M (the pairs within R metres) or pairs:FILE");
      }
      pairs.reserve(count);
      for (std::size_t a = 0; a < m; ++a) {
        for (std::size_t b = a + 1; b < m; ++b) pairs.push_back({used[a], used[b]});
      }
      break;
    }
    case RelativePairs::radius:
      pairs = radius_pairs(p, used);
      break;
    case RelativePairs::listed:
      for (const auto& [a, b] : o.listed) {
        // A station no measurement reaches has no precision: left out (the
        // report's stations leave it out too).
        if (a != b && p.station_used[a] && p.station_used[b]) pairs.push_back({std::min(a, b), std::max(a, b)});
      }
      break;
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

void relative_precision(const NetworkProblem& p, const DatumCofactors& cofactors, AdjustmentResult& result, int jobs) {
  const auto& net = p.net;
  const std::vector<std::pair<std::size_t, std::size_t>> pairs = relative_pairs(p);
  const double confidence_scale = ellipse_confidence_scale(p.o.confidence);
  const double up_scale = interval_confidence_scale(p.o.confidence);
  result.relative.assign(pairs.size(), RelativePrecision{});
  // The pairs by their first station (they are sorted): [group[g], group[g + 1]).
  std::vector<std::size_t> group;
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    if (k == 0 || pairs[k].first != pairs[k - 1].first) group.push_back(k);
  }
  group.push_back(pairs.size());
  constexpr std::size_t kStationsPerChunk = 16;
  for_chunks(group.size() - 1, kStationsPerChunk, jobs, [&](std::size_t begin, std::size_t end) {
    for (std::size_t g = begin; g < end; ++g) {
      const std::size_t s1 = pairs[group[g]].first;
      std::vector<std::size_t> others;
      for (std::size_t k = group[g]; k < group[g + 1]; ++k) others.push_back(pairs[k].second);
      const std::vector<Eigen::Matrix<double, 6, 6>> q = cofactors.with_each(s1, others);
      for (std::size_t i = 0; i < others.size(); ++i) {
        const std::size_t s2 = others[i];
        // The pair's joint cofactor along the unknowns' axes, to ECEF (a
        // local network's axes are one), then the difference in the horizon of s1.
        const Eigen::Matrix3d a1 = p.states[s1].axes, a2 = p.states[s2].axes, r1 = p.states[s1].local_from_xyz;
        const Eigen::Matrix3d c11 = a1.transpose() * q[i].topLeftCorner<3, 3>() * a1;
        const Eigen::Matrix3d c22 = a2.transpose() * q[i].bottomRightCorner<3, 3>() * a2;
        const Eigen::Matrix3d c12 = a1.transpose() * q[i].topRightCorner<3, 3>() * a2;
        const Eigen::Matrix3d diff = r1 * (c11 + c22 - c12 - c12.transpose()) * r1.transpose();
        RelativePrecision rp;
        rp.from = s1;
        rp.to = s2;
        const Eigen::Vector3d dxyz = p.states[s2].x - p.states[s1].x;
        rp.distance_m = dxyz.norm();
        rp.horizontal_distance_m = (r1 * dxyz).head<2>().norm();
        const Eigen::Vector3d unit_local = r1 * dxyz / std::max(rp.distance_m, 1e-12);
        rp.sigma_distance_m = std::sqrt(std::max(0.0, unit_local.dot(diff * unit_local)));
        rp.covariance_local_m2 = diff;
        rp.ellipse = horizontal_ellipse(diff.topLeftCorner<2, 2>(), net.space);
        rp.ellipse_confidence = rp.ellipse;
        rp.ellipse_confidence.semi_major_m *= confidence_scale;
        rp.ellipse_confidence.semi_minor_m *= confidence_scale;
        rp.sigma_up_m = std::sqrt(std::max(0.0, diff(2, 2)));
        rp.up_confidence_m = up_scale * rp.sigma_up_m;
        result.relative[group[g] + i] = rp;
      }
    }
  });
}

}  // namespace geoanchor::solver
