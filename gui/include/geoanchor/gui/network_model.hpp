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
  solver::ErrorEllipse ellipse;             // 1σ
  solver::ErrorEllipse ellipse_confidence;  // at AdjustOptions::confidence
  Eigen::Vector3d sigma_m = Eigen::Vector3d::Zero();  // east, north, up (local: x, y, z)
  std::string constraint;        // "CCF"
  bool left_out = false;         // by the user
  bool used = false;             // in the shown adjustment
};

// A line between two stations that a measurement joins (a baseline, a
// distance, a direction, an angle's two sights), coloured by its w-test.
struct NetworkLine {
  std::size_t from = 0, to = 0;  // indices into stations()
  std::size_t measurement = 0;   // into the network's measurements
  double w_max = 0.0;            // the measurement's largest |w| (NaN: not testable or not adjusted)
  bool outlier = false;          // removed by data snooping
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
  const std::string& error() const { return error_; }  // "E_CODE: message" of a refused adjustment
  unsigned generation() const { return generation_; }  // increments with every new result

  std::vector<NetworkStationRow> stations() const;
  std::vector<NetworkLine> lines() const;
  std::vector<std::string> stations_left_out() const;
  std::vector<std::size_t> measurements_left_out() const;

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
