#pragma once
// NormalFactor's state (sparse_factor.hpp), for the files that implement
// it: sparse_factor.cpp (ordering, factorization, solves),
// selected_inversion.cpp (selected inversion, downdates) and
// sparse_paths.cpp (solves along the elimination tree).
//
// Private to solver.

#include <cholmod.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <algorithm>
#include <cstdint>
#include <optional>
#include <vector>

#include "sparse/sparse_factor.hpp"
#include "sparse/supernodal_cholesky.hpp"

namespace geoanchor::solver {

struct NormalFactor::Impl {
  Mode mode = Mode::sparse;
  std::int64_t n = 0;
  // sparse
  cholmod_common common{};
  bool started = false;
  cholmod_factor* factor = nullptr;
  // The selected inverse Z = N⁻¹ in the permuted order of the supernodal
  // factor, on its pattern and in its layout: supernode k's columns
  // super[k] … super[k+1]−1 hold the rows of its pattern, L->s[pi[k] …
  // pi[k+1]) (its own columns first, then the rows below, ascending), and
  // `z` holds Z at those rows and columns, column-major from px[k] as L->x
  // holds L (the diagonal block whole).
  std::vector<std::int64_t> inverse_permutation;
  // The supernodal elimination tree of the analysis (each unknown's
  // supernode, each supernode's parent).
  std::optional<SupernodalTree> tree;
  // The pattern the analysis was made for (column pointers, row indices).
  std::vector<SuiteSparse_long> pattern_p, pattern_i;
  std::vector<double> z;
  // Rows taken out since the factorization (downdate): N⁻¹ is the factor's
  // L⁻ᵀ L⁻¹ plus, for each downdate s in turn, U_s M_s⁻¹ U_sᵀ.
  struct LowRank {
    Eigen::MatrixXd u;               // n × r_s, in the caller's order
    Eigen::LLT<Eigen::MatrixXd> m;   // r_s × r_s
  };
  std::vector<LowRank> updates;
  // dense
  Eigen::MatrixXd dense;
  Eigen::LLT<Eigen::MatrixXd> llt;
  Eigen::MatrixXd dense_inverse;
  std::int64_t lnz = 0;
  double flops = 0.0;

  ~Impl() {
    if (factor) cholmod_l_free_factor(&factor, &common);
    if (started) cholmod_l_finish(&common);
  }
  // Position in `z` of Z(row, column) for row >= column in the permuted
  // order; -1 when off the pattern.
  std::int64_t find(std::int64_t row, std::int64_t column) const {
    const auto* super = static_cast<const SuiteSparse_long*>(factor->super);
    const auto* pi = static_cast<const SuiteSparse_long*>(factor->pi);
    const auto* px = static_cast<const SuiteSparse_long*>(factor->px);
    const auto* rows = static_cast<const SuiteSparse_long*>(factor->s);
    const std::int64_t k = tree->super_of[static_cast<std::size_t>(column)];
    const std::int64_t nscol = super[k + 1] - super[k], nsrow = pi[k + 1] - pi[k];
    const std::int64_t j = column - super[k];
    std::int64_t i = -1;
    if (row < super[k + 1]) {
      i = row - super[k];
    } else {
      const SuiteSparse_long* first = rows + pi[k] + nscol;
      const SuiteSparse_long* last = rows + pi[k + 1];
      const SuiteSparse_long* it = std::lower_bound(first, last, static_cast<SuiteSparse_long>(row));
      if (it == last || *it != row) return -1;
      i = it - (rows + pi[k]);
    }
    return px[k] + i + j * nsrow;
  }
};

}  // namespace geoanchor::solver
