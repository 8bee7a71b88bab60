#pragma once
// `geoanchor adjust` as a library (docs/commands/adjust.md): the inputs
// read into one network, brought to the adjustment's frame and epoch
// through the frame catalog, the command line's constraints applied; the
// adjustment (solver/network_adjustment.hpp); and what it becomes on disk:
// the adjusted stations as a control set CSV with its sidecar, the
// measurements with their statistics, the report as text and JSON.

#include <optional>
#include <string>
#include <vector>

#include "geoanchor/geodesy/network.hpp"
#include "geoanchor/solver/network_adjustment.hpp"

namespace geoanchor::workflow {

struct AdjustRequest {
  std::vector<std::string> inputs;      // files, or "-"
  std::optional<std::string> frame;     // --frame NAME[@EPOCH]
  std::optional<std::string> sinex_frame;  // --sinex-frame NAME: the frame of SINEX inputs
  std::vector<std::string> constrain;   // --constrain ID=CCC[,SIGMA_M]
  solver::AdjustOptions options;
};

struct PreparedNetwork {
  geodesy::Network network;
  std::vector<std::string> notes;  // what was done to it (frame changes, constraints), for the report
};

// Throws geoanchor::Error: reading (io::read_network), a --frame or
// measurement frame the catalog cannot reach (naming the measurement), a
// change of epoch in a dynamic frame (which needs velocities: refused
// naming the measurement), an ellipsoidal network without a frame, a
// --constrain that names no station or is malformed.
PreparedNetwork prepare_network(const AdjustRequest& request);

// The adjusted stations as CSV: a network on the ellipsoid
//   id,x_m,y_m,z_m,lat_deg,lon_deg,h_m,sigma_e_m,sigma_n_m,sigma_u_m,
//   corr_en,corr_eu,corr_nu,ellipse_a_m,ellipse_b_m,ellipse_azimuth_deg,
//   ellipse_conf_a_m,ellipse_conf_b_m,constraint
// with "# frame = …" above the header; a local network its own axes
// (x_m, y_m, z_m as present, sigma_x_m, …). Sigmas from the a-priori
// weights (σ0 = 1). Stations no measurement reaches are left out.
std::string stations_csv(const geodesy::Network& net, const solver::AdjustmentResult& r, const solver::AdjustOptions& o);

// One row per measurement component with its statistics.
// The adjusted stations and their joint covariance as SINEX 2.02 (the
// adjustment run with AdjustOptions::joint_covariance). Throws
// geoanchor::Error (usage) for a local network or a frame without epoch.
std::string stations_sinex(const PreparedNetwork& prepared, const solver::AdjustmentResult& r, const std::string& software);

std::string measurements_csv(const geodesy::Network& net, const solver::AdjustmentResult& r);

// The report as text, and as JSON (schema geoanchor.adjust-report/1).
std::string report_text(const PreparedNetwork& prepared, const solver::AdjustmentResult& r, const solver::AdjustOptions& o);
std::string report_json(const PreparedNetwork& prepared, const solver::AdjustmentResult& r, const solver::AdjustOptions& o);

}  // namespace geoanchor::workflow
