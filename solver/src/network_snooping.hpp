#pragma once
// The whitened residuals' cofactor between measurements of a network
// adjustment, Q(i, t) = δ_it I − A_i N⁻¹ A_tᵀ (A_i a measurement's whitened
// rows over its unknowns), from the adjustment's factor, for data snooping
// (snooping.hpp): a column costs one solve with the factor (k_t right-hand
// sides), or the cofactor between a set of measurements comes all together
// (prefetch) from forward solves along the elimination tree and their inner
// products (NormalFactor::inverse_between: at 10⁵ stations, 900 columns in
// about a second where multi-column solves took 25 s).
//
// Private to solver.

#include <Eigen/Core>

#include <cstdint>
#include <vector>

#include "snooping.hpp"
#include "sparse/sparse_factor.hpp"

namespace geoanchor::solver {

class NetworkCofactors final : public CofactorSource {
 public:
  NetworkCofactors(const NormalFactor& factor, std::int64_t unknowns, int jobs = 1)
      : factor_(factor), unknowns_(unknowns), jobs_(jobs) {}
  // The next candidate: its unknowns and its whitened rows over them.
  void add(std::vector<std::int64_t> unknowns, Eigen::MatrixXd a);
  Eigen::MatrixXd column(const std::vector<std::size_t>& rows, std::size_t column) override;
  void prefetch(const std::vector<std::size_t>& candidates) override;

 private:
  // N⁻¹ A_tᵀ for the candidates `ts` (u × Σ k_t), by solves.
  Eigen::MatrixXd solved(const std::vector<std::size_t>& ts) const;
  // Q(i, t) from z = N⁻¹ A_tᵀ's columns `z_cols` of z.
  Eigen::MatrixXd block(std::size_t i, std::size_t t, const Eigen::MatrixXd& z, Eigen::Index first_col) const;

  const NormalFactor& factor_;
  std::int64_t unknowns_;
  int jobs_ = 1;
  std::vector<std::vector<std::int64_t>> candidate_unknowns_;
  std::vector<Eigen::MatrixXd> a_;
  // After prefetch: the dense cofactor over the prefetched candidates
  // (their rows stacked at offset_), −1 for the others.
  std::vector<Eigen::Index> offset_;
  Eigen::MatrixXd cached_;
};

}  // namespace geoanchor::solver
