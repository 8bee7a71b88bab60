#include "geoanchor/gui/network_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <numbers>
#include <utility>

#include "geoanchor/base/error.hpp"
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
    if (measurement_out_[mi] || measurement_out_through_station(mi)) m.ignore = true;
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

bool NetworkModel::measurement_out_through_station(std::size_t measurement) const {
  for (std::size_t s : network_.measurements.at(measurement).stations) {
    if (station_out_[s]) return true;
  }
  return false;
}

const char* to_string(MeasurementClass c) {
  switch (c) {
    case MeasurementClass::small: return "small";
    case MeasurementClass::elevated: return "elevated";
    case MeasurementClass::failing: return "failing";
    case MeasurementClass::outlier: return "outlier";
    case MeasurementClass::untestable: return "untestable";
    case MeasurementClass::left_out: return "left_out";
  }
  return "?";
}

const char* status_text(MeasurementClass c) {
  switch (c) {
    case MeasurementClass::small: return "used";
    case MeasurementClass::elevated: return "used";  // the |w| column is orange
    case MeasurementClass::failing: return "FAILS its test";
    case MeasurementClass::outlier: return "OUTLIER (removed)";
    case MeasurementClass::untestable: return "used (no redundancy)";
    case MeasurementClass::left_out: return "not adjusted";
  }
  return "?";
}

double elevated_w(double w_critical) { return std::isfinite(w_critical) ? std::min(2.0, w_critical) : 2.0; }

std::string describe(MeasurementClass c, double w_critical) {
  char w[32];
  std::snprintf(w, sizeof w, "%.2f", elevated_w(w_critical));
  switch (c) {
    case MeasurementClass::small: return std::string("test passes, |w| ≤ ") + w;
    case MeasurementClass::elevated: return std::string("test passes, |w| > ") + w;
    case MeasurementClass::failing: return "test fails (kept)";
    case MeasurementClass::outlier: return "outlier (removed)";
    case MeasurementClass::untestable: return "no redundancy";
    case MeasurementClass::left_out: return "left out / not adjusted";
  }
  return "?";
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
    if (!ellipsoidal && !schematic_plan()) {
      // The solver's azimuth runs from +x towards +y; the plan is drawn east,
      // north, so the major axis is turned by the axes as the positions are.
      const Eigen::Vector2d d = std::cos(row.ellipse.azimuth_rad) * x_en + std::sin(row.ellipse.azimuth_rad) * y_en;
      double az = std::atan2(d.x(), d.y());
      if (az < 0.0) az += std::numbers::pi;
      if (az >= std::numbers::pi) az -= std::numbers::pi;
      row.ellipse.azimuth_rad = az;
      row.ellipse_confidence.azimuth_rad = az;
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

namespace {

// The station pairs a measurement is drawn between, or none (a point, a
// height: at the stations themselves).
std::vector<std::pair<std::size_t, std::size_t>> line_ends(const geodesy::NetworkMeasurement& m) {
  std::vector<std::pair<std::size_t, std::size_t>> out;
  const auto add = [&](std::size_t from, std::size_t to) { out.emplace_back(from, to); };
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
    case MeasurementKind::observation_set:  // each observation's
      for (const auto& part : m.parts) {
        const auto ends = line_ends(part);
        out.insert(out.end(), ends.begin(), ends.end());
      }
      break;
    case MeasurementKind::gnss_points:
    case MeasurementKind::ellipsoidal_height:
    case MeasurementKind::orthometric_height:
    case MeasurementKind::geodetic_latitude:
    case MeasurementKind::geodetic_longitude:
    case MeasurementKind::astronomic_latitude:
    case MeasurementKind::astronomic_longitude:
      break;  // at the stations themselves: no line
    default:
      if (m.stations.size() == 2) add(m.stations[0], m.stations[1]);
      break;
  }
  return out;
}

}  // namespace

std::vector<NetworkMeasurementRow> NetworkModel::measurement_rows() const {
  std::vector<NetworkMeasurementRow> out(network_.measurements.size());
  for (std::size_t mi = 0; mi < out.size(); ++mi) {
    out[mi].index = mi;
    out[mi].w_max = std::numeric_limits<double>::quiet_NaN();
    out[mi].has_line = !line_ends(network_.measurements[mi]).empty();
  }
  if (!result_) return out;
  for (std::size_t k = 0; k < result_->measurements.size(); ++k) {
    const auto& am = result_->measurements[k];
    if (am.index >= out.size()) continue;
    NetworkMeasurementRow& row = out[am.index];
    row.adjusted = k;
    if (std::isfinite(am.w_max)) row.w_max = am.w_max;
    row.shown_as = am.outlier                           ? MeasurementClass::outlier
                   : !am.used                           ? MeasurementClass::left_out
                   : am.test_dof <= 0 || !std::isfinite(am.w_max) ? MeasurementClass::untestable
                   : am.fails_test(options_.alpha_point) ? MeasurementClass::failing
                   : am.w_max > elevated_w(result_->w_critical) ? MeasurementClass::elevated
                                                                 : MeasurementClass::small;
  }
  return out;
}

std::vector<NetworkLine> NetworkModel::lines() const {
  const std::vector<NetworkMeasurementRow> rows = measurement_rows();
  std::vector<NetworkLine> out;
  for (const auto& row : rows) {
    for (const auto& [from, to] : line_ends(network_.measurements[row.index])) {
      NetworkLine l;
      l.from = from;
      l.to = to;
      l.measurement = row.index;
      l.w_max = row.w_max;
      l.shown_as = row.shown_as;
      l.used = row.adjusted && result_->measurements[*row.adjusted].used;
      l.left_out = measurement_out_[row.index] || measurement_out_through_station(row.index);
      out.push_back(l);
    }
  }
  return out;
}

}  // namespace geoanchor::gui
