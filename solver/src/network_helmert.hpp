#pragma once
// The Helmert group of a network adjustment (AdjustOptions::helmert): the
// group's members checked and placed, its parameters estimated about the
// group's centroid (GeocentricForm), a member's computed values taken back
// into the group's datum, and the estimate in the geocentric form.
//
// Private to solver.

#include <Eigen/Core>

#include "geoanchor/solver/network_adjustment.hpp"
#include "network_model.hpp"
#include "network_problem.hpp"
#include "sparse/sparse_factor.hpp"

namespace geoanchor::solver {

// The Helmert of AdjustOptions::helmert is estimated about `pivot` (the
// group's stations' a-priori centroid c): X = c + T_c + (1 + s) R (y − c).
// Over a small group a geocentric translation is correlated with the
// rotations to 1 − 10⁻⁸, which would cost the factor its digits; about the
// centroid they are nearly independent. The model itself is the
// geocentric one (AdjustOptions::helmert): these are its parameters,
// T = c + T_c − (1 + s) R c and, with rates, Ṫ = Ṫ_c − ṡ R c + (1 + s) [c]× ṙ
// (rotations, scale and their rates are the same in both forms), and J
// their derivatives with respect to the parameters about the pivot.
struct GeocentricForm {
  Eigen::VectorXd parameters;
  Eigen::MatrixXd j;
};

GeocentricForm geocentric_form(const Eigen::VectorXd& about_pivot, const Eigen::Vector3d& c, bool rates);

// A Helmert group member's values taken back into the group's datum:
// `computed` (positions or baseline differences in the network's frame)
// becomes y = R⁻¹ (X − T) / (1 + s) (for a baseline R⁻¹ Δ / (1 + s)) with
// the geocentric parameters at the member's epoch (dt years from the
// reference epoch), d_local its derivatives through R⁻¹ / (1 + s), and
// `d_parameters` (rows × 7 or 14) ∂y / ∂(each parameter about the pivot).
void into_group_datum(Evaluation& ev, bool points, const GeocentricForm& g, bool rates, double dt,
                      Eigen::MatrixXd& d_parameters);

// The group of p.o.helmert (set): its members checked (GNSS baselines and
// point clusters only, a network on the ellipsoid, no --free), each
// measurement's place in it (p.helmert_slot), its parameters at zero and
// its pivot, the centroid of its stations' a-priori positions.
void begin_helmert_group(NetworkProblem& p);

// The estimate in the geocentric form, its covariance (from the selected
// inverse `f`) carried by J.
EstimatedHelmert estimated_helmert(const NetworkProblem& p, const NormalFactor& f);

}  // namespace geoanchor::solver
