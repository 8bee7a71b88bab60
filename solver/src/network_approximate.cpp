// Approximate positions for the stations of a local network that the
// input gives no coordinates (GNU Gama's adjusted points without x, y):
// found from the measurements, station by station, until every one is
// placed (network_approximate.hpp).

#include "network_approximate.hpp"

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "geoanchor/base/error.hpp"

namespace geoanchor::solver {

namespace {

using geodesy::MeasurementKind;

}  // namespace

void approximate_positions(geodesy::Network& net) {
  std::vector<bool> known(net.stations.size());
  std::size_t missing = 0;
  for (std::size_t s = 0; s < net.stations.size(); ++s) {
    known[s] = net.stations[s].position_known;
    missing += known[s] ? 0u : 1u;
  }
  if (missing == 0) return;
  if (net.space != geodesy::NetworkSpace::local) {
    for (std::size_t s = 0; s < net.stations.size(); ++s) {
      if (known[s]) continue;
      throw Error(ErrorKind::input, "E_STATION_UNDEFINED",
                  net.stations[s].source + ": station " + net.stations[s].id +
                      " has no a-priori coordinates; a network on the ellipsoid needs them for every station");
    }
  }
  const double sign = net.axes.bearing_sign();
  // Every observation by itself (an observation set's parts too).
  std::vector<const geodesy::NetworkMeasurement*> observations;
  for (const auto& m : net.measurements) {
    if (m.ignore) continue;
    for (const auto& part : geodesy::parts_of(m)) observations.push_back(&part);
  }
  auto place = [&](std::size_t s, const Eigen::Vector3d& x) {
    net.stations[s].position = x;
    known[s] = true;
    --missing;
  };

  bool progress = true;
  while (missing > 0 && progress) {
    progress = false;
    // Orientations of the direction sets whose instrument and one target are placed.
    std::vector<std::optional<double>> orientation(net.direction_sets.size());
    for (const auto* observation : observations) {
      const auto& m = *observation;
      if (m.kind != MeasurementKind::direction || !m.set || orientation[*m.set]) continue;
      const std::size_t a = m.stations[0], b = m.stations[1];
      if (!known[a] || !known[b]) continue;
      const Eigen::Vector3d d = net.stations[b].position - net.stations[a].position;
      if (d.head<2>().norm() == 0.0) continue;
      orientation[*m.set] = sign * std::atan2(d.y(), d.x()) - m.value(0);
    }
    for (const auto* observation : observations) {
      const auto& m = *observation;
      switch (m.kind) {
        case MeasurementKind::gnss_points:
          for (std::size_t k = 0; k < m.stations.size(); ++k) {
            if (!known[m.stations[k]]) place(m.stations[k], m.value.segment<3>(static_cast<Eigen::Index>(3 * k))), progress = true;
          }
          break;
        case MeasurementKind::gnss_baselines:
          for (std::size_t k = 0; k + 1 < m.stations.size(); k += 2) {
            const std::size_t a = m.stations[k], b = m.stations[k + 1];
            const Eigen::Vector3d d = m.value.segment<3>(static_cast<Eigen::Index>(3 * (k / 2)));
            if (known[a] && !known[b]) place(b, net.stations[a].position + d), progress = true;
            else if (known[b] && !known[a]) place(a, net.stations[b].position - d), progress = true;
          }
          break;
        case MeasurementKind::height_difference:
          if (net.local_dimensions == 1) {
            const std::size_t a = m.stations[0], b = m.stations[1];
            if (known[a] && !known[b]) place(b, Eigen::Vector3d(0, 0, net.stations[a].position.z() + m.value(0))), progress = true;
            else if (known[b] && !known[a]) place(a, Eigen::Vector3d(0, 0, net.stations[b].position.z() - m.value(0))), progress = true;
          }
          break;
        default: break;
      }
    }
    if (net.local_dimensions == 1) continue;
    // Polar: a bearing (an oriented direction, or an azimuth) and a length
    // from a placed instrument.
    for (const auto* observation : observations) {
      const auto& m = *observation;
      if ((m.kind != MeasurementKind::direction && m.kind != MeasurementKind::azimuth)) continue;
      const std::size_t a = m.stations[0], b = m.stations[1];
      if (!known[a] || known[b]) continue;
      double bearing = m.value(0);
      if (m.kind == MeasurementKind::direction) {
        if (!m.set || !orientation[*m.set]) continue;
        bearing += *orientation[*m.set];
      }
      std::optional<double> horizontal, slope, zenith, rise;
      for (const auto* other : observations) {
        const auto& n = *other;
        if (n.stations.size() < 2) continue;
        const bool forward = n.stations[0] == a && n.stations[1] == b;
        const bool backward = n.stations[0] == b && n.stations[1] == a;
        if (!forward && !backward) continue;
        if (n.kind == MeasurementKind::horizontal_distance) horizontal = n.value(0);
        if (n.kind == MeasurementKind::slope_distance) slope = n.value(0);
        if (n.kind == MeasurementKind::zenith_angle && forward) zenith = n.value(0);
        if (n.kind == MeasurementKind::height_difference) rise = forward ? n.value(0) : -n.value(0);
      }
      if (!horizontal && slope) horizontal = zenith ? *slope * std::sin(*zenith) : *slope;
      if (!horizontal) continue;
      if (!rise && slope && zenith) rise = *slope * std::cos(*zenith);
      const double angle = sign * bearing;  // from +x towards +y
      const Eigen::Vector3d& from = net.stations[a].position;
      place(b, Eigen::Vector3d(from.x() + *horizontal * std::cos(angle), from.y() + *horizontal * std::sin(angle),
                               from.z() + rise.value_or(0.0)));
      progress = true;
    }
  }
  if (missing > 0) {
    std::string list;
    std::size_t shown = 0;
    for (std::size_t s = 0; s < net.stations.size(); ++s) {
      if (known[s]) continue;
      if (shown++ < 5) list += (list.empty() ? "" : ", ") + net.stations[s].id + " (" + net.stations[s].source + ")";
    }
    throw Error(ErrorKind::input, "E_STATION_UNDEFINED",
                net.source_name + ": " + std::to_string(missing) + " station(s) have no a-priori coordinates and the "
                "measurements do not place them (a vector, an observed point, or a bearing and a length from a placed "
                "station): " + list + (missing > 5 ? ", …" : "") + "; give their approximate coordinates");
  }
  for (auto& s : net.stations) s.position_known = true;
}

}  // namespace geoanchor::solver
