#pragma once
// What the workbench's network view shows and changes, without any window
// (issue 14 point 10): a network as `geoanchor adjust` prepared it, the
// user's choices (stations and measurements left out) and the adjustment
// that follows from them. Views draw from it; tests drive it directly.
//
// Leaving a station out sets aside every measurement that names it (a point
// cluster loses the whole cluster, as it is one measurement with one joint
// covariance); leaving a measurement out sets it aside alone. Each choice
// re-adjusts — on a worker thread for networks of `async_from_stations` or
// more, so that a window keeps drawing the last result meanwhile.

#include <Eigen/Core>

#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "geoanchor/geodesy/network.hpp"
#include "geoanchor/gui/latest_on_worker.hpp"
#include "geoanchor/solver/network_adjustment.hpp"

namespace geoanchor::gui {

// A station as the view draws it.
struct NetworkStationRow {
  std::string id;
  // Adjusted (a-priori when there is no adjustment) position on the plan:
  // east, north at the network's centroid on the ellipsoid; a local
  // network's x, y turned to east, north by its axis convention (x north,
  // y east: east = y). A levelling network (1-D) has no plan positions:
  // its stations stand on a circle of unit radius in their order
  // (NetworkModel::schematic_plan()).
  Eigen::Vector2d plan_m = Eigen::Vector2d::Zero();
  // From the a-priori weights (σ0 = 1); zero without an adjustment.
  solver::ErrorEllipse ellipse;             // 1σ; azimuth clockwise from north in the plan (local axes turned)
  solver::ErrorEllipse ellipse_confidence;  // at AdjustOptions::confidence
  Eigen::Vector3d sigma_m = Eigen::Vector3d::Zero();  // east, north, up (local: x, y, z)
  std::string constraint;        // "CCF"
  bool left_out = false;         // by the user
  bool used = false;             // in the shown adjustment
};

// How the view shows a measurement in the shown adjustment: by its
// measurement test at AdjustOptions::alpha_point (the test data snooping
// uses, AdjustedMeasurement::fails_test) and its largest |w| against
// elevated_w().
enum class MeasurementClass {
  small,       // its test passes, |w| ≤ elevated_w: bluish green, thin
  elevated,    // its test passes, |w| > elevated_w: orange, medium
  failing,     // its test fails and it was kept (flagged: the default; or at the limit, or not removable): vermillion, thick, labelled
  outlier,     // removed by data snooping (--remove-outliers): vermillion, dashed, labelled
  untestable,  // no redundancy (w undefined): black, thin, dashed
  left_out,    // not in the shown adjustment (left out by the user or ignored by its input): grey, thin, dashed
};
inline constexpr std::size_t kMeasurementClasses = 6;
const char* to_string(MeasurementClass c);  // "small", "elevated", … (the JSON keys)
// The legend's words for a class: "test passes, |w| ≤ 2.00", "test fails (kept)", …
std::string describe(MeasurementClass c, double w_critical);
// A measurement table's status for a class, short: "used", "FAILS its test", …
const char* status_text(MeasurementClass c);
// The |w| above which a measurement whose test passes is shown elevated:
// 2, or the critical value w_c when that is smaller (alpha_point > 0.0455).
double elevated_w(double w_critical);

// A measurement as the view shows it, in the network's order.
struct NetworkMeasurementRow {
  std::size_t index = 0;                 // into the network's measurements
  std::optional<std::size_t> adjusted;   // into result()->measurements; nullopt: not in the shown adjustment
  double w_max = 0.0;                    // its largest |w| (NaN: not testable or not adjusted)
  MeasurementClass shown_as = MeasurementClass::left_out;
  bool has_line = false;                 // drawn as one or more lines on the plan
};

// A line between two stations that a measurement joins (a baseline, a
// distance, a direction, an angle's two sights), drawn by its measurement's
// class.
struct NetworkLine {
  std::size_t from = 0, to = 0;  // indices into stations()
  std::size_t measurement = 0;   // into the network's measurements
  double w_max = 0.0;            // the measurement's largest |w| (NaN: not testable or not adjusted)
  MeasurementClass shown_as = MeasurementClass::left_out;
  bool used = false;             // in the shown adjustment
  bool left_out = false;         // by the user, or through a station left out
};

class NetworkModel {
 public:
  static constexpr std::size_t kDefaultAsyncFrom = 500;  // stations

  // Adjusts at once (on the worker for large networks); a refused
  // adjustment leaves result() empty and error() saying why.
  NetworkModel(geodesy::Network network, solver::AdjustOptions options, std::size_t async_from_stations = kDefaultAsyncFrom);
  ~NetworkModel();
  NetworkModel(const NetworkModel&) = delete;
  NetworkModel& operator=(const NetworkModel&) = delete;

  // The user's choices; each re-adjusts. An unknown id or index is a no-op.
  void set_station_left_out(std::string_view id, bool left_out);
  void set_measurement_left_out(std::size_t measurement, bool left_out);

  const geodesy::Network& network() const { return network_; }
  const solver::AdjustOptions& options() const { return options_; }
  // True for a levelling network, whose plan is a schematic circle.
  bool schematic_plan() const;
  const std::optional<solver::AdjustmentResult>& result() const { return result_; }
  const std::string& error() const { return error_; }
  // The shown adjustment's critical |w| (infinity without one).
  double w_critical() const { return result_ ? result_->w_critical : std::numeric_limits<double>::infinity(); }  // "E_CODE: message" of a refused adjustment
  unsigned generation() const { return generation_; }  // increments with every new result

  std::vector<NetworkStationRow> stations() const;
  std::vector<NetworkMeasurementRow> measurement_rows() const;
  std::vector<NetworkLine> lines() const;
  std::vector<std::string> stations_left_out() const;
  std::vector<std::size_t> measurements_left_out() const;
  // The user's choices as they stand now (the shown adjustment may still be
  // the previous one while a worker re-adjusts). A measurement naming a
  // station left out is out through it.
  bool station_left_out(std::size_t station) const { return station_out_.at(station); }
  bool measurement_left_out(std::size_t measurement) const { return measurement_out_.at(measurement); }
  bool measurement_out_through_station(std::size_t measurement) const;

  bool busy() const { return worker_.busy(); }
  // Takes a finished adjustment, if any, and starts the next one if the
  // choices changed meanwhile; true when the shown result changed.
  bool poll();
  void wait();

 private:
  struct Outcome {
    std::optional<solver::AdjustmentResult> result;
    std::string error;
  };
  static Outcome run(const geodesy::Network& network, const solver::AdjustOptions& options);
  geodesy::Network chosen() const;  // the network with the choices applied
  void readjust();
  void take(Outcome outcome);

  geodesy::Network network_;
  solver::AdjustOptions options_;
  std::vector<bool> station_out_, measurement_out_;
  std::optional<solver::AdjustmentResult> result_;
  std::string error_;
  unsigned generation_ = 0;
  Eigen::Vector3d plan_origin_ = Eigen::Vector3d::Zero();  // ECEF centroid (ellipsoidal)
  Eigen::Matrix3d plan_rotation_ = Eigen::Matrix3d::Identity();  // ENU from ECEF at it
  std::size_t async_from_stations_;
  LatestOnWorker<Outcome> worker_;
};

}  // namespace geoanchor::gui
