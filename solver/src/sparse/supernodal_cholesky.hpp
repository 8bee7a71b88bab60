#pragma once
// The numeric supernodal Cholesky factorization N = L Lᵀ on CHOLMOD's
// symbolic analysis (its ordering, supernodes and their row patterns), on
// several threads: disjoint subtrees of the supernodal elimination tree on
// threads of their own, then the supernodes above them (the largest) one
// at a time on every thread, cut in slices of fixed size. A supernode's
// numbers depend on its shape alone, never on the threads: one thread and
// two give the same bits. CHOLMOD's own numeric factorization runs on one
// core; this one fills the same supernodal layout, so CHOLMOD's solves and
// the selected inversion read it as they read CHOLMOD's.
//
// Private to solver.

#include <cstdint>
#include <vector>

namespace geoanchor::solver {

// A supernodal factor's layout, as CHOLMOD's cholmod_factor holds it:
// supernode k has columns super[k] … super[k+1]−1 and the row indices
// rows[pi[k]] … rows[pi[k+1]−1] (its own columns first, then the rows below,
// ascending); its values are the (pi[k+1]−pi[k]) × (super[k+1]−super[k])
// column-major block from px[k].
struct SupernodalLayout {
  std::int64_t n = 0, nsuper = 0;
  const std::int64_t* super = nullptr;
  const std::int64_t* pi = nullptr;
  const std::int64_t* px = nullptr;
  const std::int64_t* rows = nullptr;
};

// The supernodal elimination tree: parent[k] (−1 for a root) and, for each
// unknown, its supernode.
struct SupernodalTree {
  std::vector<std::int64_t> parent, super_of;
  explicit SupernodalTree(const SupernodalLayout& layout);
};

// Factors the matrix whose lower triangle, in the factor's (permuted) order,
// is the compressed-column (p, i, x) — column j's rows ≥ j, in any order,
// each on the factor's pattern — into `lx` (the layout's px[nsuper] values;
// the strict upper triangle of each diagonal block is set to zero).
// Returns −1, or the first column (permuted order) whose pivot is not
// positive: the matrix is not positive definite, and `lx` is not a factor.
std::int64_t factor_supernodal(const SupernodalLayout& layout, const SupernodalTree& tree, const std::int64_t* p,
                               const std::int64_t* i, const double* x, double* lx, int jobs);

}  // namespace geoanchor::solver
