#pragma once
// A network adjustment's results per station: coordinates, covariances
// and error ellipses (S-transformed for a free network), the joint
// covariance of every station (for SINEX), the orientations' standard
// deviations, the Helmert group's estimate, and the relative precision
// between the pairs of AdjustOptions::relative
// (network_relative_precision.hpp).
//
// Private to solver.

#include <Eigen/Core>

#include <cmath>

#include "geoanchor/solver/network_adjustment.hpp"
#include "network_free_datum.hpp"
#include "network_problem.hpp"
#include "sparse/sparse_factor.hpp"

namespace geoanchor::solver {

// The horizontal ellipse (1σ) of a 2 × 2 covariance in local components:
// east, north (ellipsoidal: azimuth from north towards east) or x, y
// (local: from +x towards +y).
ErrorEllipse horizontal_ellipse(const Eigen::Matrix2d& c, geodesy::NetworkSpace space);

// result.stations, covariance_stations and station_covariance_m2 (with
// AdjustOptions::joint_covariance), orientations_rad and their sigmas,
// helmert, relative; each station and pair its own, on `jobs` threads.
void station_statistics(const NetworkProblem& p, const NormalFactor& f, const InnerConstraints& inner, AdjustmentResult& result,
                        int jobs);

}  // namespace geoanchor::solver
