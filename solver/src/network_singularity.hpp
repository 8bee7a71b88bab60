#pragma once
// A network adjustment's normal matrix that is singular, explained: a
// station its measurements do not fix on its own, or the motion of
// stations (orientations, Helmert parameters) the matrix leaves free,
// named with the measurements that reach them (E_NETWORK_SINGULAR).
//
// Private to solver.

#include "network_normal_equations.hpp"
#include "network_problem.hpp"

namespace geoanchor::solver {

// A station whose own block of the normal matrix (its unknowns, with the
// others held) is singular: moving it alone along the null direction
// changes no measurement, whatever the rest does. Named with the direction
// and the measurements that reach it (E_NETWORK_SINGULAR).
void check_station_blocks(const NetworkProblem& p, const NormalEquations& n);

// When the factorization fails past the datum and station checks, the
// direction the normal matrix leaves free is found and named: the matrix
// shifted by 10⁻¹⁰ of its diagonal is factored, and inverse iteration
// (three solves from a fixed start) turns any start towards its null
// direction; the stations (and orientations, Helmert parameters) that
// carry it are named with their components.
[[noreturn]] void explain_singularity(const NetworkProblem& p, const NormalEquations& n, Index failed_column);

}  // namespace geoanchor::solver
