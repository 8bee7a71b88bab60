// Blocks of A N⁻¹ Aᵀ between a few row blocks, by forward solves along the
// elimination tree (sparse_factor.hpp: NormalFactor::inverse_between).
//
// With P N Pᵀ = L Lᵀ, A_i N⁻¹ A_jᵀ = Y_iᵀ Y_j, Y_c = L⁻¹ P A_cᵀ. A column
// of L has its nonzeros in rows that are ancestors of it in the elimination
// tree, so the forward solve of a right-hand side that is nonzero at a few
// unknowns stays on the paths from their supernodes to the root: Y_c is
// zero elsewhere, and the solve costs those supernodes' blocks only (in a
// generated network of 10⁵ stations, 9 % of L for one unknown's path,
// against all of L twice for a solve). The blocks between two row blocks
// are then the inner products of their Y over the supernodes their paths
// share, summed in the supernodes' order.

#include <Eigen/Cholesky>

#include <algorithm>
#include <stdexcept>

#include "geoanchor/base/parallel.hpp"
#include "sparse/sparse_factor_impl.hpp"

namespace geoanchor::solver {
namespace {

// Y of one row block: the supernodes of its paths (ascending: a child
// before its parent) and, stacked in that order, the rows of Y at their
// columns (Σ ncol × k).
struct PathSolve {
  std::vector<std::int64_t> supernodes;
  std::vector<std::int64_t> offset;  // per supernode: its first row in y
  Eigen::MatrixXd y;
};

// Candidates per chunk of work shared among threads.
constexpr std::size_t kBlocksPerChunk = 8;

}  // namespace

Eigen::MatrixXd NormalFactor::inverse_between(const std::vector<std::vector<std::int64_t>>& unknowns,
                                              const std::vector<Eigen::MatrixXd>& rows, int jobs) const {
  const Impl& m = *impl_;
  if (unknowns.size() != rows.size()) throw std::logic_error("NormalFactor::inverse_between: one unknown list per row block");
  const std::size_t count = rows.size();
  std::vector<Eigen::Index> at(count + 1, 0);
  for (std::size_t c = 0; c < count; ++c) {
    if (static_cast<std::size_t>(rows[c].cols()) != unknowns[c].size()) {
      throw std::logic_error("NormalFactor::inverse_between: a row block's columns are not its unknowns");
    }
    at[c + 1] = at[c] + rows[c].rows();
  }
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(at[count], at[count]);
  if (m.mode == Mode::dense) {
    const Eigen::MatrixXd inverse = m.llt.solve(Eigen::MatrixXd::Identity(m.n, m.n));
    for (std::size_t i = 0; i < count; ++i) {
      for (std::size_t j = 0; j < count; ++j) {
        Eigen::MatrixXd z(static_cast<Eigen::Index>(unknowns[i].size()), static_cast<Eigen::Index>(unknowns[j].size()));
        for (std::size_t a = 0; a < unknowns[i].size(); ++a) {
          for (std::size_t b = 0; b < unknowns[j].size(); ++b) {
            z(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) = inverse(unknowns[i][a], unknowns[j][b]);
          }
        }
        out.block(at[i], at[j], rows[i].rows(), rows[j].rows()) = rows[i] * z * rows[j].transpose();
      }
    }
    return out;
  }
  const cholmod_factor* f = m.factor;
  const auto* super = static_cast<const SuiteSparse_long*>(f->super);
  const auto* pi = static_cast<const SuiteSparse_long*>(f->pi);
  const auto* px = static_cast<const SuiteSparse_long*>(f->px);
  const auto* srows = static_cast<const SuiteSparse_long*>(f->s);
  const auto* lx = static_cast<const double*>(f->x);
  const auto* perm = static_cast<const SuiteSparse_long*>(f->Perm);
  const std::size_t n = static_cast<std::size_t>(m.n);
  std::vector<std::int64_t> permuted(n);  // an unknown's place in the factor's order
  for (std::size_t k = 0; k < n; ++k) permuted[static_cast<std::size_t>(perm[k])] = static_cast<std::int64_t>(k);
  const std::vector<std::int64_t>& super_of = m.tree->super_of;
  const std::vector<std::int64_t>& parent = m.tree->parent;

  // Y for every row block (each on its own: the same bits on any thread).
  std::vector<PathSolve> solves(count);
  for_chunks(count, kBlocksPerChunk, std::max(1, jobs), [&](std::size_t begin, std::size_t end) {
    std::vector<std::int64_t> local(n, -1);  // a permuted unknown's row in y, while it is on the path
    std::vector<char> seen(static_cast<std::size_t>(f->nsuper), 0);
    for (std::size_t c = begin; c < end; ++c) {
      PathSolve& s = solves[c];
      for (std::int64_t u : unknowns[c]) {
        for (std::int64_t k = super_of[static_cast<std::size_t>(permuted[static_cast<std::size_t>(u)])]; k >= 0 && !seen[static_cast<std::size_t>(k)];
             k = parent[static_cast<std::size_t>(k)]) {
          seen[static_cast<std::size_t>(k)] = 1;
          s.supernodes.push_back(k);
        }
      }
      std::sort(s.supernodes.begin(), s.supernodes.end());
      std::int64_t rows_on_path = 0;
      for (std::int64_t k : s.supernodes) {
        s.offset.push_back(rows_on_path);
        for (std::int64_t col = super[k]; col < super[k + 1]; ++col) local[static_cast<std::size_t>(col)] = rows_on_path + (col - super[k]);
        rows_on_path += super[k + 1] - super[k];
      }
      const Eigen::Index kc = rows[c].rows();
      s.y = Eigen::MatrixXd::Zero(rows_on_path, kc);
      for (std::size_t j = 0; j < unknowns[c].size(); ++j) {
        s.y.row(local[static_cast<std::size_t>(permuted[static_cast<std::size_t>(unknowns[c][j])])]) += rows[c].col(static_cast<Eigen::Index>(j)).transpose();
      }
      // The forward solve, supernode by supernode up the paths.
      Eigen::MatrixXd below;
      for (std::size_t p = 0; p < s.supernodes.size(); ++p) {
        const std::int64_t k = s.supernodes[p];
        const std::int64_t nscol = super[k + 1] - super[k], nsrow = pi[k + 1] - pi[k];
        const Eigen::Map<const Eigen::MatrixXd> lk(lx + px[k], nsrow, nscol);
        auto yk = s.y.middleRows(s.offset[p], nscol);
        lk.topRows(nscol).triangularView<Eigen::Lower>().solveInPlace(yk);
        if (nsrow == nscol) continue;
        below.noalias() = lk.bottomRows(nsrow - nscol) * yk;
        for (std::int64_t i = nscol; i < nsrow; ++i) {
          const std::int64_t row = local[static_cast<std::size_t>(srows[pi[k] + i])];
          if (row < 0) throw std::logic_error("NormalFactor::inverse_between: a row of L off its column's path");
          s.y.row(row) -= below.row(i - nscol);
        }
      }
      for (std::int64_t k : s.supernodes) {
        seen[static_cast<std::size_t>(k)] = 0;
        for (std::int64_t col = super[k]; col < super[k + 1]; ++col) local[static_cast<std::size_t>(col)] = -1;
      }
    }
  });

  // Y_iᵀ Y_j over the supernodes both paths hold, in their order.
  for_chunks(count, kBlocksPerChunk, std::max(1, jobs), [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const PathSolve& a = solves[i];
      for (std::size_t j = i; j < count; ++j) {
        const PathSolve& b = solves[j];
        Eigen::MatrixXd block = Eigen::MatrixXd::Zero(a.y.cols(), b.y.cols());
        std::size_t p = 0, q = 0;
        while (p < a.supernodes.size() && q < b.supernodes.size()) {
          if (a.supernodes[p] < b.supernodes[q]) {
            ++p;
          } else if (b.supernodes[q] < a.supernodes[p]) {
            ++q;
          } else {
            const std::int64_t k = a.supernodes[p];
            const std::int64_t nscol = super[k + 1] - super[k];
            block.noalias() += a.y.middleRows(a.offset[p], nscol).transpose() * b.y.middleRows(b.offset[q], nscol);
            ++p;
            ++q;
          }
        }
        out.block(at[i], at[j], a.y.cols(), b.y.cols()) = block;
      }
    }
  });
  // The downdates since the factorization: + (U Aᵀ)ᵀ M⁻¹ (U Aᵀ) each.
  for (const auto& up : m.updates) {
    Eigen::MatrixXd v(up.u.cols(), at[count]);
    for (std::size_t c = 0; c < count; ++c) {
      Eigen::MatrixXd uc(static_cast<Eigen::Index>(unknowns[c].size()), up.u.cols());
      for (std::size_t j = 0; j < unknowns[c].size(); ++j) uc.row(static_cast<Eigen::Index>(j)) = up.u.row(unknowns[c][j]);
      v.middleCols(at[c], rows[c].rows()) = uc.transpose() * rows[c].transpose();
    }
    const Eigen::MatrixXd term = v.transpose() * up.m.solve(v);
    out.triangularView<Eigen::Upper>() += term;
  }
  out.triangularView<Eigen::StrictlyLower>() = out.transpose();
  return out;
}

}  // namespace geoanchor::solver
