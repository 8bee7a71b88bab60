#pragma once
// A network adjustment's results per station: coordinates, covariances
// and error ellipses (S-transformed for a free network), the joint
// covariance of every station (for SINEX), the orientations' standard
// deviations, the Helmert group's estimate, and the relative precision
// between stations that share a measurement.
//
// Private to solver.

#include <Eigen/Core>

#include <cmath>

#include "geoanchor/solver/network_adjustment.hpp"
#include "network_free_datum.hpp"
#include "network_problem.hpp"
#include "sparse/sparse_factor.hpp"

namespace geoanchor::solver {

// The horizontal ellipse (1σ) of a station's covariance in its local
// components: east, north (ellipsoidal: azimuth from north towards east) or
// x, y (local: from +x towards +y, a bearing when x is north and y east, as
// GNU Gama orients its ellipses).
ErrorEllipse horizontal_ellipse(const Eigen::Matrix2d& c, geodesy::NetworkSpace space);

// The scale of a 2-D confidence region at probability p: √χ²₂(p).
inline double confidence_scale_2d(double p) { return std::sqrt(-2.0 * std::log(1.0 - p)); }

// result.stations, covariance_stations and station_covariance_m2 (with
// AdjustOptions::joint_covariance), orientations_rad and their sigmas,
// helmert, relative; each station and pair its own, on `jobs` threads.
void station_statistics(const NetworkProblem& p, const NormalFactor& f, const InnerConstraints& inner, AdjustmentResult& result,
                        int jobs);

}  // namespace geoanchor::solver
