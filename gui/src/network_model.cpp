#include "geoanchor/gui/network_model.hpp"

#include <cmath>
#include <exception>
#include <limits>
#include <numbers>
#include <utility>

#include "geoanchor/geodesy/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"

namespace geoanchor::gui {

using geodesy::MeasurementKind;

NetworkModel::NetworkModel(geodesy::Network network, solver::AdjustOptions options, std::size_t async_from_stations)
    : network_(std::move(network)),
      options_(std::move(options)),
      station_out_(network_.stations.size(), false),
      measurement_out_(network_.measurements.size(), false),
      async_from_stations_(async_from_stations) {
  if (network_.space == geodesy::NetworkSpace::ellipsoidal && !network_.stations.empty()) {
    for (const auto& s : network_.stations) plan_origin_ += s.position;
    plan_origin_ /= static_cast<double>(network_.stations.size());
    const geodesy::GeocentricConverter geocentric(network_.ellipsoid);
    const auto g = geocentric.geodetic_from_ecef(geodesy::EcefPosition(plan_origin_));
    plan_rotation_ = geodesy::enu_from_ecef_rotation(g.lat, g.lon);
  }
  readjust();
}

NetworkModel::~NetworkModel() = default;

NetworkModel::Outcome NetworkModel::run(const geodesy::Network& network, const solver::AdjustOptions& options) {
  Outcome o;
  try {
    o.result = solver::adjust_network(network, options);
  } catch (const Error& e) {
    o.error = e.code() + ": " + e.what();
  }
  return o;
}

geodesy::Network NetworkModel::chosen() const {
  geodesy::Network n = network_;
  for (std::size_t mi = 0; mi < n.measurements.size(); ++mi) {
    auto& m = n.measurements[mi];
    bool out = measurement_out_[mi];
    for (std::size_t s : m.stations) out = out || station_out_[s];
    if (out) m.ignore = true;
  }
  return n;
}

void NetworkModel::readjust() {
  if (network_.stations.size() < async_from_stations_) {
    take(run(chosen(), options_));
    return;
  }
  worker_.start([network = chosen(), options = options_] { return run(network, options); });
}

void NetworkModel::take(Outcome outcome) {
  result_ = std::move(outcome.result);
  error_ = std::move(outcome.error);
  ++generation_;
}

bool NetworkModel::poll() {
  bool again = false;
  auto outcome = worker_.take_ready(again);
  if (!outcome) return false;
  take(std::move(*outcome));
  if (again) readjust();
  return true;
}

void NetworkModel::wait() {
  while (busy()) {
    worker_.wait_running();
    poll();
  }
}

void NetworkModel::set_station_left_out(std::string_view id, bool left_out) {
  const auto s = network_.find(std::string(id));
  if (!s || station_out_[*s] == left_out) return;
  station_out_[*s] = left_out;
  readjust();
}

void NetworkModel::set_measurement_left_out(std::size_t measurement, bool left_out) {
  if (measurement >= measurement_out_.size() || measurement_out_[measurement] == left_out) return;
  measurement_out_[measurement] = left_out;
  readjust();
}

std::vector<std::string> NetworkModel::stations_left_out() const {
  std::vector<std::string> out;
  for (std::size_t s = 0; s < station_out_.size(); ++s) {
    if (station_out_[s]) out.push_back(network_.stations[s].id);
  }
  return out;
}

std::vector<std::size_t> NetworkModel::measurements_left_out() const {
  std::vector<std::size_t> out;
  for (std::size_t m = 0; m < measurement_out_.size(); ++m) {
    if (measurement_out_[m]) out.push_back(m);
  }
  return out;
}

bool NetworkModel::schematic_plan() const {
  return network_.space == geodesy::NetworkSpace::local && network_.local_dimensions == 1;
}

namespace {

// East, north of a local axis direction (n, e, s or w).
Eigen::Vector2d east_north(char axis) {
  switch (axis) {
    case 'n': return {0.0, 1.0};
    case 's': return {0.0, -1.0};
    case 'e': return {1.0, 0.0};
    default: return {-1.0, 0.0};  // w
  }
}

}  // namespace

std::vector<NetworkStationRow> NetworkModel::stations() const {
  const bool ellipsoidal = network_.space == geodesy::NetworkSpace::ellipsoidal;
  const Eigen::Vector2d x_en = east_north(network_.axes.x), y_en = east_north(network_.axes.y);
  std::vector<NetworkStationRow> out;
  for (std::size_t s = 0; s < network_.stations.size(); ++s) {
    NetworkStationRow row;
    const auto& st = network_.stations[s];
    row.id = st.id;
    row.constraint = st.constraint.text();
    row.left_out = station_out_[s];
    Eigen::Vector3d x = st.position;
    if (result_ && s < result_->stations.size()) {
      const auto& a = result_->stations[s];
      row.used = a.used;
      if (a.used) {
        x = a.position;
        row.ellipse = a.ellipse;
        row.ellipse_confidence = a.ellipse_confidence;
        row.sigma_m = a.covariance_local_m2.diagonal().cwiseMax(0.0).cwiseSqrt();
      }
    }
    if (schematic_plan()) {
      const double t = 2.0 * std::numbers::pi * static_cast<double>(s) / static_cast<double>(network_.stations.size());
      row.plan_m = Eigen::Vector2d(std::sin(t), std::cos(t));
    } else if (ellipsoidal) {
      row.plan_m = (plan_rotation_ * (x - plan_origin_)).head<2>();
    } else {
      row.plan_m = x.x() * x_en + x.y() * y_en;
    }
    out.push_back(row);
  }
  return out;
}

std::vector<NetworkLine> NetworkModel::lines() const {
  // Each measurement's result, by its index in the network.
  std::vector<const solver::AdjustedMeasurement*> adjusted(network_.measurements.size(), nullptr);
  if (result_) {
    for (const auto& am : result_->measurements) {
      if (am.index < adjusted.size()) adjusted[am.index] = &am;
    }
  }
  std::vector<NetworkLine> out;
  for (std::size_t mi = 0; mi < network_.measurements.size(); ++mi) {
    const auto& m = network_.measurements[mi];
    bool out_by_choice = measurement_out_[mi];
    for (std::size_t s : m.stations) out_by_choice = out_by_choice || station_out_[s];
    const solver::AdjustedMeasurement* am = adjusted[mi];
    auto add = [&](std::size_t from, std::size_t to) {
      NetworkLine l;
      l.from = from;
      l.to = to;
      l.measurement = mi;
      l.left_out = out_by_choice;
      l.used = am && am->used;
      l.outlier = am && am->outlier;
      l.w_max = am && std::isfinite(am->w_max) ? am->w_max : std::numeric_limits<double>::quiet_NaN();
      out.push_back(l);
    };
    switch (m.kind) {
      case MeasurementKind::gnss_baselines:
        for (std::size_t k = 0; k + 1 < m.stations.size(); k += 2) add(m.stations[k], m.stations[k + 1]);
        break;
      case MeasurementKind::horizontal_angle:  // at, backsight, foresight: the two sights
        if (m.stations.size() == 3) {
          add(m.stations[0], m.stations[1]);
          add(m.stations[0], m.stations[2]);
        }
        break;
      case MeasurementKind::gnss_points:
      case MeasurementKind::ellipsoidal_height:
      case MeasurementKind::orthometric_height:
      case MeasurementKind::geodetic_latitude:
      case MeasurementKind::geodetic_longitude:
        break;  // at the stations themselves: no line
      default:
        if (m.stations.size() == 2) add(m.stations[0], m.stations[1]);
        break;
    }
  }
  return out;
}

}  // namespace geoanchor::gui
