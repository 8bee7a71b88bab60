#pragma once
// A free network's datum (or what the constraints leave of it, held by the
// input's datum stations): the inner-constraint stations, checked to hold
// every combination of the defect; the few anchors that hold it while
// iterating; and the S-transformation to the minimum-norm solution over the
// inner stations, of the solution and of its cofactors.
//
// Private to solver.

#include <Eigen/Core>

#include <cstddef>
#include <vector>

#include "network_normal_equations.hpp"
#include "network_problem.hpp"
#include "sparse/sparse_factor.hpp"

namespace geoanchor::solver {

// A pass's inner constraints as the options give them: p.free from
// --free, and then the inner-constraint stations (--inner-constraints, or
// every station reached); the defect is left for define_datum
// (network_datum.hpp) to find.
void begin_inner_constraints(NetworkProblem& p);

// The inner-constraint stations (p.inner with p.inner_components) must
// hold every combination of the defect (EᵀD of full rank, spanning_ratio):
// else a refusal naming the combinations they leave free and why, before
// any factorization. `option`: they came from --inner-constraints (usage),
// else from the input's datum stations (input).
void check_inner_stations(const NetworkProblem& p, bool option);

// Where the defect is held while iterating (p.anchor and its components):
// few of the inner stations over which the defect's directions are
// independent: the one farthest from their centroid, then the farthest
// from it, then the one farthest off their line, then, while a
// combination is left free, the station that holds it best. A handful, so
// that holding them adds a small dense block to the normal matrix.
void choose_anchors(NetworkProblem& p);

// Adds w·C Cᵀ to the normal equations (C: the defect held at the anchors).
void hold_defect(const NetworkProblem& p, NormalEquations& n);

// The inner constraints of the solution: E, the defect D restricted to the
// inner stations, and M = (EᵀD)⁻¹ (both empty unless a free network has a
// defect).
struct InnerConstraints {
  Eigen::MatrixXd e, m;
};

// Free network: the minimum-norm solution over the inner stations (an
// S-transformation of the solution held at the anchors).
InnerConstraints to_minimum_norm(NetworkProblem& p);

// The cofactors of the station unknowns at the solution (from the factor's
// selected inverse Z = N⁻¹), S-transformed for a free network: S Z Sᵀ,
// S = I − D M Eᵀ.
class DatumCofactors {
 public:
  DatumCofactors(const NetworkProblem& p, const NormalFactor& f, const InnerConstraints& inner);
  // The 3 × 3 block between stations s1 and s2, along their unknowns' axes
  // (zero for a component that is no unknown).
  Eigen::Matrix3d between(std::size_t s1, std::size_t s2) const;
  // The joint cofactor of station s with each of `others` (6 × 6 each:
  // s's 3 components then the other's, along their unknowns' axes; zero
  // for a component that is no unknown), S-transformed as between(). A
  // pair on the factor's pattern (sharing a measurement, or joined by
  // fill) from the selected inverse; the others' cross cofactors from one
  // NormalFactor::inverse_between over s and them (forward solves along
  // the elimination tree, never a dense inverse): one path solve per
  // station rather than two per pair.
  std::vector<Eigen::Matrix<double, 6, 6>> with_each(std::size_t s, const std::vector<std::size_t>& others) const;
  // The cofactor over the unknowns `sel` selects (u × k, a 1 per column),
  // by solves for every column of N⁻¹ they need (k × k, symmetric).
  Eigen::MatrixXd selected(const Eigen::MatrixXd& sel) const;

 private:
  const NetworkProblem& p_;
  const NormalFactor& f_;
  const InnerConstraints& inner_;
  bool transformed_ = false;
  Eigen::MatrixXd ze_, eze_;  // Z E (u × d) and Eᵀ Z E
};

}  // namespace geoanchor::solver
