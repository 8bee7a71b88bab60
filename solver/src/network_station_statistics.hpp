#pragma once
// A network adjustment's results per station: coordinates, covariances
// and error ellipses (S-transformed for a free network), the joint
// covariance of every station (for SINEX), the orientations' standard
// deviations, the Helmert group's estimate, and the relative precision
// between stations that share a measurement.
//
// Private to solver.

#include "geoanchor/solver/network_adjustment.hpp"
#include "network_free_datum.hpp"
#include "network_problem.hpp"
#include "sparse/sparse_factor.hpp"

namespace geoanchor::solver {

// result.stations, covariance_stations and station_covariance_m2 (with
// AdjustOptions::joint_covariance), orientations_rad and their sigmas,
// helmert, relative; each station and pair its own, on `jobs` threads.
void station_statistics(const NetworkProblem& p, const NormalFactor& f, const InnerConstraints& inner, AdjustmentResult& result,
                        int jobs);

}  // namespace geoanchor::solver
