#pragma once
// SINEX output of adjusted station coordinates with their covariance
// (SINEX 2.02: header, FILE/REFERENCE, FILE/COMMENT, SITE/ID,
// SOLUTION/EPOCHS, SOLUTION/STATISTICS, SOLUTION/ESTIMATE,
// SOLUTION/MATRIX_ESTIMATE L COVA). The reader is network_input.hpp's.

#include <Eigen/Core>

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "geoanchor/geodesy/frame.hpp"

namespace geoanchor::io {

struct SinexSite {
  std::string id;                  // the station's name (its SINEX code when it is 4 characters or fewer)
  Eigen::Vector3d ecef_m = Eigen::Vector3d::Zero();
  double lat_deg = 0.0, lon_deg = 0.0, h_m = 0.0;  // for SITE/ID's approximate position
};

struct SinexSolution {
  explicit SinexSolution(geodesy::Frame f) : frame(std::move(f)) {}
  std::vector<SinexSite> sites;
  Eigen::MatrixXd covariance_m2;  // 3n × 3n, X Y Z per site in order
  geodesy::Frame frame;           // with its epoch: REF_EPOCH
  char technique = 'P';           // P GNSS, C combined
  int constraint_code = 2;        // 0 tight, 1 significant, 2 unconstrained
  std::size_t observations = 0, unknowns = 0;
  int dof = 0;
  double vtpv = 0.0;
  std::optional<double> variance_factor;  // none without redundancy
  std::string description, software, input;
  std::vector<std::string> comments;
};

// The SINEX text. Throws geoanchor::Error (usage) when the frame has no
// epoch, or when codes cannot be made unique; names longer than 4
// characters get codes S001, S002, … listed in FILE/COMMENT and SITE/ID.
std::string sinex_text(const SinexSolution& s);

// A decimal year as SINEX's YY:DDD:SSSSS.
std::string sinex_epoch(double decimal_year);

}  // namespace geoanchor::io
