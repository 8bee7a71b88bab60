#pragma once
// Control points: marks whose coordinates are known in two frames, the
// observations a datum transform is fitted to. Coordinates are ECEF in each
// frame; covariances are ECEF 3×3 in square metres.

#include <Eigen/Core>

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/positions.hpp"
#include "geoanchor/geodesy/units.hpp"

namespace geoanchor::geodesy {

struct ControlPoint {
  std::string id;
  std::size_t line = 0;  // where it was read, for messages
  EcefPosition source;
  EcefPosition target;
  Eigen::Matrix3d source_cov_m2 = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d target_cov_m2 = Eigen::Matrix3d::Zero();
  // Epoch at which the point's two coordinates are related by the transform.
  std::optional<DecimalYear> epoch;
  bool use = true;
  // Optional ECEF velocities (m/yr) in each frame at `epoch`, with their
  // covariances (m²/yr²): they observe the transform's rates.
  std::optional<Eigen::Vector3d> source_velocity_m_per_year;
  std::optional<Eigen::Vector3d> target_velocity_m_per_year;
  Eigen::Matrix3d source_velocity_cov = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d target_velocity_cov = Eigen::Matrix3d::Zero();
};

struct ControlSet {
  std::string source_name;  // file name, for messages
  std::vector<ControlPoint> points;
  std::optional<Frame> source_frame;
  std::optional<Frame> target_frame;
  // False when the file gave no sigmas: weights are then equal (1 m²) and
  // only σ0 estimated from the residuals gives them a scale.
  bool has_a_priori_sigmas = true;
};

}  // namespace geoanchor::geodesy
