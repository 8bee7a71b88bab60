// The selected inverse Z = N⁻¹ on the factor's pattern (Takahashi's
// equations, supernode by supernode on the threads' subtrees), its reading
// (NormalFactor::inverse, inverse_block), and the downdates that take rows
// out of the factored matrix (sparse_factor.hpp).

#include <cholmod.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <atomic>
#include <exception>
#include <functional>
#include <stdexcept>
#include <string>
#include <thread>

#include "geoanchor/base/parallel.hpp"
#include "sparse/dense_kernels.hpp"
#include "sparse/sparse_factor.hpp"
#include "sparse/sparse_factor_impl.hpp"

namespace geoanchor::solver {

namespace {

// Work space for the largest supernode, allocated once per thread (a
// fresh allocation per supernode costs more in page faults than the work).
// (Aligned: a block's numbers are the same whichever thread's space it is
// computed in, dense_kernels.hpp.)
struct Workspace {
  KernelSpace zrr_space, u_space, zrj_space, linv_space;
  double *zrr = nullptr, *u = nullptr, *zrj = nullptr, *linv = nullptr;
};

Workspace make_workspace(std::int64_t max_r, std::int64_t max_c) {
  Workspace w;
  w.zrr = w.zrr_space.take(static_cast<std::size_t>(max_r * max_r));
  w.u = w.u_space.take(static_cast<std::size_t>(max_r * max_c));
  w.zrj = w.zrj_space.take(static_cast<std::size_t>(max_r * max_c));
  w.linv = w.linv_space.take(static_cast<std::size_t>(max_c * max_c));
  return w;
}

// Supernode by supernode from the last (the root) to the first. With J
// its columns and R the rows below them, L_JJ lower triangular and L_RJ
// below it, and U = L_RJ L_JJ⁻¹, the Takahashi equations Lᵀ Z = L⁻¹ give
//   Z_RJ = −Z_RR U,   Z_JJ = L_JJ⁻ᵀ L_JJ⁻¹ − Uᵀ Z_RJ.
// R is a clique of the factor's graph, so Z_RR lies on the pattern of
// the supernodes that hold R's columns, already computed.
//
// A supernode's work is cut into slices whose sizes depend on its shape
// alone (kSliceColumns of U and Z_RJ, kSliceRows of U, kSliceGather
// columns of Z_RR), so that its numbers are the same whether the slices
// run on one thread or on `jobs` (the supernodes above the subtrees'
// split are the largest, and are done with every thread).
constexpr std::int64_t kSliceColumns = 32, kSliceRows = 256, kSliceGather = 128;

// The Takahashi step at supernode k (in the factor's layout, Z written in
// place), on `jobs_here` threads.
struct TakahashiStep {
  const SuiteSparse_long* super;
  const SuiteSparse_long* pi;
  const SuiteSparse_long* px;
  const SuiteSparse_long* rows;
  const double* lx;
  double* z;
  const std::vector<std::int64_t>& super_of;

  void operator()(std::int64_t k, Workspace& w, int jobs_here) const {
    using Matrix = Eigen::MatrixXd;
    using Map = Eigen::Map<Matrix>;
    const std::int64_t nscol = super[k + 1] - super[k], nsrow = pi[k + 1] - pi[k], r = nsrow - nscol;
    const SuiteSparse_long* below = rows + pi[k] + nscol;  // R, ascending
    Map zrr(w.zrr, r, r), u(w.u, r, nscol), zrj(w.zrj, r, nscol), linv(w.linv, nscol, nscol);
    const auto slices = [&](std::int64_t count, std::int64_t size, const auto& work) {
      for_chunks(static_cast<std::size_t>(count), static_cast<std::size_t>(size), jobs_here,
                 [&](std::size_t b, std::size_t e) { work(static_cast<std::int64_t>(b), static_cast<std::int64_t>(e - b)); });
    };
    // Z_RR (its lower triangle), gathered column by column: column R[a]
    // lies in supernode t, whose rows, from R[a] on, hold R[a..] in order.
    slices(r, kSliceGather, [&](std::int64_t first, std::int64_t count) {
      for (std::int64_t a = first; a < first + count; ++a) {
        const std::int64_t c = below[a];
        const std::int64_t t = super_of[static_cast<std::size_t>(c)];
        const std::int64_t t_nsrow = pi[t + 1] - pi[t];
        const SuiteSparse_long* t_rows = rows + pi[t];
        const double* t_z = z + px[t] + (c - super[t]) * t_nsrow;
        std::int64_t q = c - super[t];  // the diagonal's row within t
        for (std::int64_t b = a; b < r; ++b) {
          while (q < t_nsrow && t_rows[q] < below[b]) ++q;
          if (q == t_nsrow || t_rows[q] != below[b]) throw std::logic_error("selected inversion: an entry off the factor's pattern");
          zrr(b, a) = t_z[q];
        }
      }
    });
    const DenseKernels& kernels = dense_kernels();
    const double* l_jj = lx + px[k];
    double* z_k = z + px[k];
    kernels.inverse_lower(l_jj, nsrow, nscol, linv.data(), nscol);      // L_JJ⁻¹
    kernels.transposed_gram(linv.data(), nscol, nscol, z_k, nsrow);     // Z_JJ = L_JJ⁻ᵀ L_JJ⁻¹
    if (r == 0) return;  // a root: nothing below
    // U L_JJ = L_RJ, row by row.
    slices(r, kSliceRows, [&](std::int64_t first, std::int64_t count) {
      for (std::int64_t c = 0; c < nscol; ++c) {
        std::copy_n(l_jj + nscol + first + c * nsrow, count, u.data() + first + c * r);
      }
      kernels.solve_lower_right(l_jj, nsrow, nscol, u.data() + first, r, count);
    });
    // Z_RJ = −Z_RR U and Z_JJ −= Uᵀ Z_RJ, a slice of columns at a time.
    slices(nscol, kSliceColumns, [&](std::int64_t first, std::int64_t count) {
      kernels.negative_symmetric_product(zrr.data(), r, r, u.data() + first * r, r, count, zrj.data() + first * r, r);
    });
    slices(nscol, kSliceColumns, [&](std::int64_t first, std::int64_t count) {
      kernels.subtract_transposed_product(u.data(), r, zrj.data() + first * r, r, nscol, count, r, z_k + first * nsrow, nsrow);
    });
    for (std::int64_t c = 0; c < nscol; ++c) std::copy_n(zrj.data() + c * r, r, z_k + nscol + c * nsrow);
  }
};

// A supernode needs only its ancestors (R's columns lie in them), so
// disjoint subtrees of the supernodal elimination tree go to threads:
// the largest subtrees are split (their roots done here first, parents
// before children) until there are enough to share out; each thread then
// does whole subtrees, each from its root down. Every supernode's numbers
// are the same whichever thread computes them.
void run_top_down(std::int64_t nsuper, const SuiteSparse_long* super, const SuiteSparse_long* pi,
                  const std::vector<std::int64_t>& parent, int jobs, const TakahashiStep& process, std::int64_t max_r,
                  std::int64_t max_c) {
  std::vector<std::vector<std::int64_t>> children(static_cast<std::size_t>(nsuper));
  std::vector<double> cost(static_cast<std::size_t>(nsuper), 0.0);
  for (std::int64_t k = 0; k < nsuper; ++k) {
    const std::int64_t nscol = super[k + 1] - super[k], r = (pi[k + 1] - pi[k]) - nscol;
    cost[static_cast<std::size_t>(k)] += static_cast<double>(nscol) * static_cast<double>((r + nscol) * (r + nscol));
    const std::int64_t up = parent[static_cast<std::size_t>(k)];
    if (up >= 0) children[static_cast<std::size_t>(up)].push_back(k);
  }
  std::vector<double> subtree = cost;  // children before parents: a child's index is lower
  for (std::int64_t k = 0; k < nsuper; ++k) {
    if (parent[static_cast<std::size_t>(k)] >= 0) subtree[static_cast<std::size_t>(parent[static_cast<std::size_t>(k)])] += subtree[static_cast<std::size_t>(k)];
  }
  const int threads = std::max(1, jobs);
  std::vector<std::int64_t> pending;  // roots of subtrees not yet done
  for (std::int64_t k = nsuper; k-- > 0;) {
    if (parent[static_cast<std::size_t>(k)] < 0) pending.push_back(k);
  }
  double total = 0.0;
  for (std::int64_t k : pending) total += subtree[static_cast<std::size_t>(k)];
  Workspace here = make_workspace(max_r, max_c);
  const auto by_cost = [&](std::int64_t a, std::int64_t b) { return subtree[static_cast<std::size_t>(a)] < subtree[static_cast<std::size_t>(b)]; };
  if (threads > 1) {
    std::make_heap(pending.begin(), pending.end(), by_cost);
    while (!pending.empty() && subtree[static_cast<std::size_t>(pending.front())] > total / (4.0 * threads)) {
      std::pop_heap(pending.begin(), pending.end(), by_cost);
      const std::int64_t k = pending.back();
      pending.pop_back();
      process(k, here, threads);  // above the split: one supernode at a time, on every thread
      for (std::int64_t c : children[static_cast<std::size_t>(k)]) {
        pending.push_back(c);
        std::push_heap(pending.begin(), pending.end(), by_cost);
      }
    }
    std::sort(pending.begin(), pending.end(), [&](std::int64_t a, std::int64_t b) { return by_cost(b, a); });
  }
  const auto do_subtree = [&](std::int64_t root, Workspace& w) {
    std::vector<std::int64_t> nodes{root};
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      for (std::int64_t c : children[static_cast<std::size_t>(nodes[i])]) nodes.push_back(c);
    }
    std::sort(nodes.begin(), nodes.end(), std::greater<>());
    for (std::int64_t k : nodes) process(k, w, 1);
  };
  std::atomic<std::size_t> next{0};
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(threads));
  const auto run = [&](int t, Workspace& w) {
    try {
      for (std::size_t i = next++; i < pending.size(); i = next++) do_subtree(pending[i], w);
    } catch (...) {
      errors[static_cast<std::size_t>(t)] = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  std::vector<Workspace> spaces;
  spaces.reserve(static_cast<std::size_t>(threads));
  for (int t = 1; t < threads && static_cast<std::size_t>(t) < pending.size(); ++t) spaces.push_back(make_workspace(max_r, max_c));
  pool.reserve(spaces.size());
  for (std::size_t t = 0; t < spaces.size(); ++t) {
    try {
      pool.emplace_back(run, static_cast<int>(t) + 1, std::ref(spaces[t]));
    } catch (...) {  // std::system_error, std::bad_alloc: never unwind past running threads
      break;  // no more threads to be had: those started and this one share the subtrees
    }
  }
  run(0, here);
  for (auto& t : pool) t.join();
  for (const auto& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

}  // namespace

std::int64_t NormalFactor::downdated_rows() const {
  std::int64_t r = 0;
  for (const auto& up : impl_->updates) r += up.u.cols();
  return r;
}

std::int64_t NormalFactor::downdate_rows_worth() const {
  const Impl& m = *impl_;
  if (m.mode == Mode::dense || m.n == 0 || m.lnz == 0) return 0;
  // A downdate of r rows: r solves (4 flops per value of L each) and 2 per
  // value and row for the selected inverse, against a factorization (its
  // flops) and a selected inversion (about twice them).
  const double by_work = 3.0 * m.flops / (6.0 * static_cast<double>(m.lnz));
  const double by_memory = static_cast<double>(m.lnz) / (2.0 * static_cast<double>(m.n));
  return static_cast<std::int64_t>(std::max(0.0, std::min(by_work, by_memory)));
}

bool NormalFactor::downdate(const Eigen::MatrixXd& b, int jobs) {
  Impl& m = *impl_;
  if (m.mode == Mode::dense || b.cols() == 0) return false;
  if (m.z.empty()) throw std::logic_error("NormalFactor::downdate: select_inverse() was not called on this factor");
  if (b.rows() != m.n) throw std::logic_error("NormalFactor::downdate: B has the wrong number of rows");
  constexpr double kMinPivot = 1e-6;
  Impl::LowRank up;
  up.u = solve(b);  // N⁻¹ B for the matrix as it is now (earlier downdates included)
  Eigen::MatrixXd cofactor = Eigen::MatrixXd::Identity(b.cols(), b.cols()) - b.transpose() * up.u;
  cofactor = (0.5 * (cofactor + cofactor.transpose())).eval();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(cofactor, Eigen::EigenvaluesOnly);
  if (!(eig.eigenvalues()(0) >= kMinPivot)) return false;
  up.m.compute(cofactor);
  if (up.m.info() != Eigen::Success) return false;
  // U M⁻¹ Uᵀ = W Wᵀ, W = U L_M⁻ᵀ: symmetric by construction. Each
  // supernode's block of Z (its rows by its columns, in the permuted
  // order) gets W_rows W_colsᵀ.
  const Eigen::MatrixXd w = up.m.matrixL().solve(up.u.transpose()).transpose();
  const cholmod_factor* f = m.factor;
  const auto* super = static_cast<const SuiteSparse_long*>(f->super);
  const auto* pi = static_cast<const SuiteSparse_long*>(f->pi);
  const auto* px = static_cast<const SuiteSparse_long*>(f->px);
  const auto* rows = static_cast<const SuiteSparse_long*>(f->s);
  const auto* perm = static_cast<const SuiteSparse_long*>(f->Perm);
  const Eigen::Index r = w.cols();
  constexpr std::size_t kSupernodesPerChunk = 64;
  for_chunks(f->nsuper, kSupernodesPerChunk, std::max(1, jobs), [&](std::size_t begin, std::size_t end) {
    Eigen::MatrixXd wr, wc;
    for (std::size_t k = begin; k < end; ++k) {
      const std::int64_t nscol = super[k + 1] - super[k], nsrow = pi[k + 1] - pi[k];
      wr.resize(nsrow, r);
      for (std::int64_t i = 0; i < nsrow; ++i) wr.row(i) = w.row(perm[rows[pi[k] + i]]);
      wc = wr.topRows(nscol);  // the supernode's own columns are its first rows
      Eigen::Map<Eigen::MatrixXd> zk(m.z.data() + px[k], nsrow, nscol);
      zk.noalias() += wr * wc.transpose();
    }
  });
  m.updates.push_back(std::move(up));
  return true;
}

void NormalFactor::select_inverse(int jobs) {
  Impl& m = *impl_;
  if (m.mode == Mode::dense) {
    m.dense_inverse = m.llt.solve(Eigen::MatrixXd::Identity(m.n, m.n));
    return;
  }
  const cholmod_factor* f = m.factor;
  if (!f->is_super || !f->is_ll) throw std::logic_error("selected inversion: the factor is not a supernodal LLᵀ");
  const std::size_t n = static_cast<std::size_t>(m.n);
  const auto nsuper = static_cast<std::int64_t>(f->nsuper);
  const auto* super = static_cast<const SuiteSparse_long*>(f->super);
  const auto* pi = static_cast<const SuiteSparse_long*>(f->pi);
  const auto* px = static_cast<const SuiteSparse_long*>(f->px);
  const auto* rows = static_cast<const SuiteSparse_long*>(f->s);
  const auto* lx = static_cast<const double*>(f->x);
  const auto* perm = static_cast<const SuiteSparse_long*>(f->Perm);
  m.inverse_permutation.assign(n, 0);
  for (std::size_t k = 0; k < n; ++k) m.inverse_permutation[static_cast<std::size_t>(perm[k])] = static_cast<std::int64_t>(k);
  const std::vector<std::int64_t>& super_of = m.tree->super_of;
  const std::vector<std::int64_t>& parent = m.tree->parent;
  for (std::int64_t k = 0; k < nsuper; ++k) {
    for (SuiteSparse_long p = pi[k] + (super[k + 1] - super[k]) + 1; p < pi[k + 1]; ++p) {
      if (rows[p - 1] >= rows[p]) throw std::logic_error("selected inversion: a supernode's rows are not ascending");
    }
  }
  m.z.resize(static_cast<std::size_t>(px[nsuper]));  // every block is written below
  std::int64_t max_r = 0, max_c = 0;
  for (std::int64_t k = 0; k < nsuper; ++k) {
    max_c = std::max<std::int64_t>(max_c, super[k + 1] - super[k]);
    max_r = std::max<std::int64_t>(max_r, (pi[k + 1] - pi[k]) - (super[k + 1] - super[k]));
  }
  const TakahashiStep process{super, pi, px, rows, lx, m.z.data(), super_of};
  run_top_down(nsuper, super, pi, parent, jobs, process, max_r, max_c);
}

double NormalFactor::inverse(std::int64_t a, std::int64_t b) const {
  const Impl& m = *impl_;
  if (m.mode == Mode::dense) return m.dense_inverse(a, b);
  if (m.z.empty()) throw std::logic_error("NormalFactor::inverse: select_inverse() was not called on this factor");
  const std::int64_t pa = m.inverse_permutation[static_cast<std::size_t>(a)];
  const std::int64_t pb = m.inverse_permutation[static_cast<std::size_t>(b)];
  const std::int64_t p = pa >= pb ? m.find(pa, pb) : m.find(pb, pa);  // the lower triangle
  if (p < 0) throw std::logic_error("NormalFactor::inverse: (" + std::to_string(a) + ", " + std::to_string(b) +
                                    ") is off the factor's pattern");
  return m.z[static_cast<std::size_t>(p)];
}

bool NormalFactor::inverse_block(const std::int64_t* u, std::size_t count, double* q) const {
  const Impl& m = *impl_;
  const auto at = [count](std::size_t a, std::size_t b) { return a + b * count; };
  if (m.mode == Mode::dense) {
    for (std::size_t a = 0; a < count; ++a) {
      for (std::size_t b = 0; b < count; ++b) q[at(a, b)] = m.dense_inverse(u[a], u[b]);
    }
    return true;
  }
  if (m.z.empty()) throw std::logic_error("NormalFactor::inverse_block: select_inverse() was not called on this factor");
  const auto* super = static_cast<const SuiteSparse_long*>(m.factor->super);
  const auto* pi = static_cast<const SuiteSparse_long*>(m.factor->pi);
  const auto* px = static_cast<const SuiteSparse_long*>(m.factor->px);
  const auto* rows = static_cast<const SuiteSparse_long*>(m.factor->s);
  // The unknowns in the factor's order: for each as a column, the later
  // ones are rows below it, found in ascending order from where the last
  // one was (a station's coordinates are consecutive rows).
  constexpr std::size_t kSmall = 16;
  std::int64_t small_permuted[kSmall];
  std::size_t small_order[kSmall];
  std::vector<std::int64_t> large_permuted;
  std::vector<std::size_t> large_order;
  std::int64_t* permuted = small_permuted;
  std::size_t* order = small_order;
  if (count > kSmall) {
    large_permuted.resize(count);
    large_order.resize(count);
    permuted = large_permuted.data();
    order = large_order.data();
  }
  for (std::size_t a = 0; a < count; ++a) {
    permuted[a] = m.inverse_permutation[static_cast<std::size_t>(u[a])];
    order[a] = a;
  }
  std::sort(order, order + count, [&](std::size_t a, std::size_t b) { return permuted[a] < permuted[b]; });
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t a = order[i];
    const std::int64_t column = permuted[a];
    const std::int64_t k = m.tree->super_of[static_cast<std::size_t>(column)];
    const std::int64_t first = super[k], last = super[k + 1], nsrow = pi[k + 1] - pi[k];
    const SuiteSparse_long* krows = rows + pi[k];
    const double* z = m.z.data() + px[k] + (column - first) * nsrow;
    std::int64_t from = last - first;  // where the search for the next row below starts
    for (std::size_t j = i; j < count; ++j) {
      const std::size_t b = order[j];
      const std::int64_t row = permuted[b];
      std::int64_t position = -1;
      if (row < last) {
        position = row - first;
      } else {
        if (from < nsrow && krows[from] == row) {
          position = from;  // a repeated unknown
        } else if (from + 1 < nsrow && krows[from + 1] == row) {
          position = from + 1;  // the next coordinate of a station
        } else {
          const SuiteSparse_long* it = std::lower_bound(krows + from, krows + nsrow, static_cast<SuiteSparse_long>(row));
          if (it == krows + nsrow || *it != row) return false;
          position = it - krows;
        }
        from = position;
      }
      q[at(a, b)] = q[at(b, a)] = z[position];
    }
  }
  return true;
}


}  // namespace geoanchor::solver
