// The numeric supernodal Cholesky factorization, left-looking: supernode s
// gathers its columns of N, subtracts the update of every supernode below
// it whose rows reach its columns, and factors its block.

#include "sparse/supernodal_cholesky.hpp"

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <functional>
#include <limits>
#include <system_error>
#include <thread>

#include "geoanchor/base/parallel.hpp"
#include "sparse/dense_kernels.hpp"

namespace geoanchor::solver {

namespace {

std::size_t at(std::int64_t k) { return static_cast<std::size_t>(k); }

// A supernode's work is cut into pieces whose sizes depend on its shape
// alone, so that its numbers are the same on one thread or on several:
// kSliceColumns columns gathered and updated at a time, its own Cholesky
// in panels of kPanelColumns columns, the rows below a panel solved
// kSliceRows at a time.
constexpr std::int64_t kSliceColumns = 64, kPanelColumns = 128, kSliceRows = 256;

// For each supernode s, the supernodes d below it whose rows reach s's
// columns (ascending: the order their updates are subtracted in), and where
// in d's rows s's columns begin.
struct Updates {
  std::vector<std::int64_t> start, from, first_row;
};

Updates find_updates(const SupernodalLayout& l, const SupernodalTree& tree) {
  Updates u;
  u.start.assign(at(l.nsuper) + 1, 0);
  const auto each = [&](const auto& visit) {
    for (std::int64_t d = 0; d < l.nsuper; ++d) {
      const std::int64_t end = l.pi[d + 1];
      std::int64_t p = l.pi[d] + (l.super[d + 1] - l.super[d]);
      while (p < end) {
        const std::int64_t s = tree.super_of[at(l.rows[p])];
        visit(s, d, p - l.pi[d]);
        while (p < end && l.rows[p] < l.super[s + 1]) ++p;
      }
    }
  };
  each([&](std::int64_t s, std::int64_t, std::int64_t) { ++u.start[at(s) + 1]; });
  for (std::int64_t s = 0; s < l.nsuper; ++s) u.start[at(s) + 1] += u.start[at(s)];
  u.from.resize(at(u.start[at(l.nsuper)]));
  u.first_row.resize(u.from.size());
  std::vector<std::int64_t> next(u.start.begin(), u.start.end() - 1);
  each([&](std::int64_t s, std::int64_t d, std::int64_t row) {
    const std::int64_t k = next[at(s)]++;
    u.from[at(k)] = d;
    u.first_row[at(k)] = row;
  });
  return u;
}

// One supernode's numeric factorization (factor_supernodal), into `lx`.
struct SupernodeFactor {
  const SupernodalLayout& l;
  const Updates& updates;
  const DenseKernels& kernels;
  const std::int64_t* ap;
  const std::int64_t* ai;
  const double* ax;
  double* lx;

  // Supernode s, on `jobs_here` threads; returns −1 or its first failed
  // column. `map` (n entries, the caller's) is left holding s's rows'
  // positions.
  std::int64_t operator()(std::int64_t s, std::vector<std::int64_t>& map, int jobs_here) const {
    const std::int64_t nsrow = l.pi[s + 1] - l.pi[s];
    const std::int64_t* srows = l.rows + l.pi[s];
    double* ls = lx + l.px[s];
    for (std::int64_t r = 0; r < nsrow; ++r) map[at(srows[r])] = r;
    const std::int64_t* position = map.data();
    gather(s, ls, position, jobs_here);
    return factor_block(s, ls, jobs_here);
  }

  // Its columns of N, less the updates from below, a slice at a time.
  void gather(std::int64_t s, double* ls, const std::int64_t* position, int jobs_here) const {
    const std::int64_t k1 = l.super[s], nscol = l.super[s + 1] - k1, nsrow = l.pi[s + 1] - l.pi[s];
    const std::int64_t slices = (nscol + kSliceColumns - 1) / kSliceColumns;
    for_chunks(at(slices), 1, jobs_here, [&](std::size_t first, std::size_t last) {
      thread_local KernelSpace space;  // (aligned: the same bits on any thread)
      for (auto slice = static_cast<std::int64_t>(first); slice < static_cast<std::int64_t>(last); ++slice) {
        const std::int64_t c0 = slice * kSliceColumns, c1 = std::min(nscol, c0 + kSliceColumns);
        std::fill(ls + c0 * nsrow, ls + c1 * nsrow, 0.0);
        for (std::int64_t c = c0; c < c1; ++c) {
          double* column = ls + c * nsrow;
          for (std::int64_t q = ap[k1 + c]; q < ap[k1 + c + 1]; ++q) column[position[ai[q]]] += ax[q];
        }
        for (std::int64_t e = updates.start[at(s)]; e < updates.start[at(s) + 1]; ++e) {
          const std::int64_t d = updates.from[at(e)];
          const std::int64_t dnscol = l.super[d + 1] - l.super[d], dnsrow = l.pi[d + 1] - l.pi[d];
          const std::int64_t* drows = l.rows + l.pi[d];
          const std::int64_t q1 = std::lower_bound(drows + updates.first_row[at(e)], drows + dnsrow, k1 + c0) - drows;
          const std::int64_t q2 = std::lower_bound(drows + q1, drows + dnsrow, k1 + c1) - drows;
          if (q1 == q2) continue;
          const std::int64_t m1 = q2 - q1, m2 = dnsrow - q1;
          double* product = space.take(at(m1 * m2));
          kernels.outer_product(lx + l.px[d] + q1, dnsrow, m2, m1, dnscol, product);
          // Column jj of the product is s's column drows[q1 + jj]; its rows
          // from jj on are on or below the diagonal.
          for (std::int64_t jj = 0; jj < m1; ++jj) {
            double* column = ls + (drows[q1 + jj] - k1) * nsrow;
            const double* from = product + jj * m2;
            for (std::int64_t ii = jj; ii < m2; ++ii) column[position[drows[q1 + ii]]] -= from[ii];
          }
        }
      }
    });
  }

  // Its own Cholesky, a panel at a time (right-looking within it); −1 or
  // its first failed column.
  std::int64_t factor_block(std::int64_t s, double* ls, int jobs_here) const {
    const std::int64_t k1 = l.super[s], nscol = l.super[s + 1] - k1, nsrow = l.pi[s + 1] - l.pi[s];
    for (std::int64_t c0 = 0; c0 < nscol; c0 += kPanelColumns) {
      const std::int64_t c1 = std::min(nscol, c0 + kPanelColumns), width = c1 - c0;
      double* diagonal = ls + c0 + c0 * nsrow;
      const std::int64_t failed = kernels.cholesky(diagonal, nsrow, width);
      if (failed >= 0) return k1 + c0 + failed;
      const std::int64_t below = nsrow - c1;
      for_chunks(at((below + kSliceRows - 1) / kSliceRows), 1, jobs_here, [&](std::size_t first, std::size_t last) {
        for (auto slice = static_cast<std::int64_t>(first); slice < static_cast<std::int64_t>(last); ++slice) {
          const std::int64_t r0 = c1 + slice * kSliceRows;
          kernels.solve_lower_transposed_right(diagonal, nsrow, width, ls + r0 + c0 * nsrow, nsrow, std::min(kSliceRows, nsrow - r0));
        }
      });
      const std::int64_t trailing = (nscol - c1 + kPanelColumns - 1) / kPanelColumns;
      for_chunks(at(trailing), 1, jobs_here, [&](std::size_t first, std::size_t last) {
        for (auto t = static_cast<std::int64_t>(first); t < static_cast<std::int64_t>(last); ++t) {
          const std::int64_t d0 = c1 + t * kPanelColumns, d1 = std::min(nscol, d0 + kPanelColumns);
          kernels.subtract_product(ls + d0 + c0 * nsrow, nsrow, ls + d0 + c0 * nsrow, nsrow, nsrow - d0, d1 - d0, width,
                                   ls + d0 + d0 * nsrow, nsrow);
        }
      });
    }
    for (std::int64_t c = 1; c < nscol; ++c) std::fill(ls + c * nsrow, ls + c * nsrow + c, 0.0);
    return -1;
  }
};

// A supernode needs only the supernodes below it, so disjoint subtrees of
// the supernodal elimination tree go to threads: the largest subtrees are
// split until there are enough to share out; their roots, and every
// supernode above them, are done afterwards, in order, on every thread.
struct SubtreeSplit {
  std::vector<std::vector<std::int64_t>> children;
  std::vector<std::int64_t> pending;  // roots of the subtrees, largest first
  std::vector<std::int64_t> top;      // the supernodes above them, ascending
};

SubtreeSplit split_subtrees(const SupernodalLayout& l, const SupernodalTree& tree, int threads) {
  SubtreeSplit split;
  std::vector<std::vector<std::int64_t>>& children = split.children;
  children.resize(at(l.nsuper));
  std::vector<double> subtree(at(l.nsuper), 0.0);
  std::vector<std::int64_t>& pending = split.pending;  // roots of subtrees
  for (std::int64_t k = 0; k < l.nsuper; ++k) {  // children before parents: a child's index is lower
    const auto nscol = static_cast<double>(l.super[k + 1] - l.super[k]), nsrow = static_cast<double>(l.pi[k + 1] - l.pi[k]);
    subtree[at(k)] += nscol * nsrow * nsrow;
    const std::int64_t up = tree.parent[at(k)];
    if (up >= 0) {
      subtree[at(up)] += subtree[at(k)];
      children[at(up)].push_back(k);
    } else {
      pending.push_back(k);
    }
  }
  double total = 0.0;
  for (const std::int64_t k : pending) total += subtree[at(k)];
  std::vector<std::int64_t>& top = split.top;  // supernodes above the subtrees
  const auto by_cost = [&](std::int64_t a, std::int64_t b) { return subtree[at(a)] < subtree[at(b)]; };
  if (threads > 1) {
    std::make_heap(pending.begin(), pending.end(), by_cost);
    while (!pending.empty() && subtree[at(pending.front())] > total / (4.0 * threads)) {
      std::pop_heap(pending.begin(), pending.end(), by_cost);
      top.push_back(pending.back());
      pending.pop_back();
      for (const std::int64_t c : children[at(top.back())]) {
        pending.push_back(c);
        std::push_heap(pending.begin(), pending.end(), by_cost);
      }
    }
    std::sort(pending.begin(), pending.end(), [&](std::int64_t a, std::int64_t b) { return by_cost(b, a); });
    std::sort(top.begin(), top.end());
  }
  return split;
}

}  // namespace

SupernodalTree::SupernodalTree(const SupernodalLayout& l) : parent(at(l.nsuper), -1), super_of(at(l.n), 0) {
  for (std::int64_t k = 0; k < l.nsuper; ++k) {
    for (std::int64_t j = l.super[k]; j < l.super[k + 1]; ++j) super_of[at(j)] = k;
  }
  for (std::int64_t k = 0; k < l.nsuper; ++k) {
    const std::int64_t nscol = l.super[k + 1] - l.super[k];
    if (l.pi[k + 1] - l.pi[k] > nscol) parent[at(k)] = super_of[at(l.rows[l.pi[k] + nscol])];
  }
}

std::int64_t factor_supernodal(const SupernodalLayout& l, const SupernodalTree& tree, const std::int64_t* ap,
                               const std::int64_t* ai, const double* ax, double* lx, int jobs) {
  if (l.nsuper == 0) return -1;
  const DenseKernels& kernels = dense_kernels();
  const Updates updates = find_updates(l, tree);
  const SupernodeFactor process{l, updates, kernels, ap, ai, ax, lx};
  const int threads = std::max(1, jobs);
  const SubtreeSplit split = split_subtrees(l, tree, threads);
  const std::vector<std::vector<std::int64_t>>& children = split.children;
  const std::vector<std::int64_t>& pending = split.pending;
  const std::vector<std::int64_t>& top = split.top;
  // Each subtree stops at its first failed column; the others go on, so
  // that the first failed column of all is the one a single thread finds.
  constexpr std::int64_t kNone = std::numeric_limits<std::int64_t>::max();
  std::vector<std::int64_t> failed(at(threads), kNone);
  std::vector<std::exception_ptr> errors(at(threads));
  std::atomic<std::size_t> next{0};
  const auto run = [&](int t) {
    try {
      std::vector<std::int64_t> map(at(l.n), 0), nodes;
      for (std::size_t i = next++; i < pending.size(); i = next++) {
        nodes.assign(1, pending[i]);
        for (std::size_t j = 0; j < nodes.size(); ++j) {
          for (const std::int64_t c : children[at(nodes[j])]) nodes.push_back(c);
        }
        std::sort(nodes.begin(), nodes.end());
        for (const std::int64_t k : nodes) {
          const std::int64_t f = process(k, map, 1);
          if (f >= 0) {
            failed[at(t)] = std::min(failed[at(t)], f);
            break;
          }
        }
      }
    } catch (...) {
      errors[at(t)] = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(at(threads));
  for (int t = 1; t < threads && at(t) < pending.size(); ++t) {
    try {
      pool.emplace_back(run, t);
    } catch (...) {
      break;  // no more threads to be had (std::system_error, std::bad_alloc): those started and this one share the subtrees
    }
  }
  run(0);
  for (auto& t : pool) t.join();
  for (const auto& e : errors) {
    if (e) std::rethrow_exception(e);
  }
  std::int64_t first_failed = *std::min_element(failed.begin(), failed.end());
  if (!top.empty()) {
    std::vector<std::int64_t> map(at(l.n), 0);
    for (const std::int64_t k : top) {
      if (l.super[k] >= first_failed) break;  // a single thread would have stopped before it
      const std::int64_t f = process(k, map, threads);
      if (f >= 0) {
        first_failed = f;
        break;
      }
    }
  }
  return first_failed == kNone ? -1 : first_failed;
}

}  // namespace geoanchor::solver
