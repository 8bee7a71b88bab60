// The normal matrix's sparse Cholesky factor (sparse_factor.hpp): a
// fill-reducing ordering of its quotient graph (CHOLMOD's AMD or METIS,
// whichever costs fewer flops), CHOLMOD's supernodal symbolic analysis on
// it, the numeric factorization of supernodal_cholesky.hpp into CHOLMOD's
// factor, and CHOLMOD's solves with it. The selected inverse and the
// downdates are selected_inversion.cpp's.

#include "sparse/sparse_factor.hpp"

#include <cholmod.h>
#include <sys/resource.h>
#include <unistd.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <exception>
#include <functional>
#include <system_error>
#include <thread>
#include <type_traits>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <stdexcept>
#include <string>

#include "geoanchor/base/error.hpp"
#include "sparse/sparse_factor_impl.hpp"
#include "sparse/supernodal_cholesky.hpp"

namespace geoanchor::solver {

static_assert(std::is_same_v<SuiteSparse_long, std::int64_t>, "CHOLMOD's long integers are the layout's");

NormalFactor::NormalFactor(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
NormalFactor::~NormalFactor() = default;
NormalFactor::NormalFactor(NormalFactor&&) noexcept = default;
NormalFactor& NormalFactor::operator=(NormalFactor&&) noexcept = default;

namespace {

// Bytes this process may still take: the machine's MemAvailable, within
// what is left of a cgroup v2 limit (a container's) and of the
// address-space limit (ulimit -v). 0: unknown.
std::uint64_t available_memory_bytes() {
  std::uint64_t available = 0;
  if (std::FILE* f = std::fopen("/proc/meminfo", "r")) {
    char line[256];
    while (std::fgets(line, sizeof line, f)) {
      unsigned long long kb = 0;
      if (std::sscanf(line, "MemAvailable: %llu kB", &kb) == 1) available = kb * 1024ull;
    }
    std::fclose(f);
  }
  // A cgroup v2 limit (a container's): what is left of it.
  const auto read_number = [](const char* path) -> std::optional<std::uint64_t> {
    std::FILE* f = std::fopen(path, "r");
    if (!f) return std::nullopt;
    unsigned long long v = 0;
    const bool ok = std::fscanf(f, "%llu", &v) == 1;  // "max" reads as no number: no limit
    std::fclose(f);
    return ok ? std::optional<std::uint64_t>(v) : std::nullopt;
  };
  if (const auto max = read_number("/sys/fs/cgroup/memory.max")) {
    const std::uint64_t current = read_number("/sys/fs/cgroup/memory.current").value_or(0);
    const std::uint64_t left = *max > current ? *max - current : 0;
    available = available == 0 ? left : std::min(available, left);
  }
  struct rlimit limit {};
  if (getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY) {
    unsigned long long pages = 0;
    std::uint64_t mapped = 0;
    if (std::FILE* f = std::fopen("/proc/self/statm", "r")) {
      if (std::fscanf(f, "%llu", &pages) == 1) mapped = pages * static_cast<std::uint64_t>(sysconf(_SC_PAGESIZE));
      std::fclose(f);
    }
    const std::uint64_t left = limit.rlim_cur > mapped ? limit.rlim_cur - mapped : 0;
    available = available == 0 ? left : std::min(available, left);
  }
  return available;
}

// Frees a CHOLMOD matrix on every way out, a std::bad_alloc included.
struct FreeSparse {
  cholmod_sparse*& p;
  cholmod_common* c;
  ~FreeSparse() {
    if (p) cholmod_l_free_sparse(&p, c);
  }
};

// A fill-reducing ordering of the symmetric matrix `a` (its upper triangle,
// CSC with sorted rows), found on its quotient graph: consecutive unknowns
// with the same closed neighbourhood (a station's three coordinates, say)
// are one node, ordered together, so the ordering works on a graph a ninth
// the size of the scalar one. Both AMD and METIS's nested dissection order
// that graph, and the one whose factor costs fewer flops (CHOLMOD's count
// on the quotient graph) is taken: nested dissection wins on large networks
// spread over a region (about a third fewer flops at 10⁵ stations), AMD on
// small and chain-like ones. Throws std::bad_alloc when CHOLMOD could not
// order it.
std::vector<SuiteSparse_long> quotient_ordering(const cholmod_sparse* a, cholmod_common* c, int jobs) {
  const auto n = static_cast<SuiteSparse_long>(a->ncol);
  const auto* ap = static_cast<const SuiteSparse_long*>(a->p);
  const auto* ai = static_cast<const SuiteSparse_long*>(a->i);
  // The lower triangle's pattern (a's transpose): column j's rows ≥ j.
  cholmod_sparse* lower = cholmod_l_transpose(const_cast<cholmod_sparse*>(a), 0, c);
  if (!lower) throw std::bad_alloc();
  const FreeSparse free_lower{lower, c};
  const auto* lp = static_cast<const SuiteSparse_long*>(lower->p);
  const auto* li = static_cast<const SuiteSparse_long*>(lower->i);
  // Whether unknowns j and j + 1 have the same closed neighbourhood
  // (adj ∪ self): both sorted sequences merged, each without duplicates.
  const auto closed = [&](SuiteSparse_long j, std::vector<SuiteSparse_long>& out) {
    out.clear();
    for (SuiteSparse_long q = ap[j]; q < ap[j + 1]; ++q) {
      if (ai[q] < j) out.push_back(ai[q]);
    }
    out.push_back(j);
    for (SuiteSparse_long q = lp[j]; q < lp[j + 1]; ++q) {
      if (li[q] > j) out.push_back(li[q]);
    }
  };
  std::vector<SuiteSparse_long> group_of(static_cast<std::size_t>(n)), first;  // first[g]: g's first unknown
  std::vector<SuiteSparse_long> previous, current;
  SuiteSparse_long groups = 0;
  for (SuiteSparse_long j = 0; j < n; ++j) {
    closed(j, current);
    if (j == 0 || current != previous) {
      first.push_back(j);
      ++groups;
    }
    group_of[static_cast<std::size_t>(j)] = groups - 1;
    std::swap(previous, current);
  }
  cholmod_l_free_sparse(&lower, c);
  first.push_back(n);
  const auto start = [&](SuiteSparse_long g) { return first[static_cast<std::size_t>(g)]; };
  // The quotient graph's upper triangle: group g's column holds the groups
  // of its first unknown's rows ≤ it (every member has the same ones).
  std::size_t nz = 0;
  for (SuiteSparse_long g = 0; g < groups; ++g) nz += static_cast<std::size_t>(ap[start(g) + 1] - ap[start(g)]) + 1;
  cholmod_sparse* q = cholmod_l_allocate_sparse(static_cast<std::size_t>(groups), static_cast<std::size_t>(groups), nz, 1, 1, 1,
                                                CHOLMOD_PATTERN, c);
  if (!q) throw std::bad_alloc();
  const FreeSparse free_q{q, c};
  auto* qp = static_cast<SuiteSparse_long*>(q->p);
  auto* qi = static_cast<SuiteSparse_long*>(q->i);
  SuiteSparse_long k = 0;
  for (SuiteSparse_long g = 0; g < groups; ++g) {
    qp[g] = k;
    const SuiteSparse_long j = start(g);
    for (SuiteSparse_long r = ap[j]; r < ap[j + 1]; ++r) {
      const SuiteSparse_long h = group_of[static_cast<std::size_t>(ai[r])];
      if (h <= g && (k == qp[g] || qi[k - 1] != h)) qi[k++] = h;
    }
    if (k == qp[g] || qi[k - 1] != g) qi[k++] = g;
  }
  qp[groups] = k;
  // Order it both ways (a simplicial analysis: the ordering and the
  // factor's column counts, no supernodes), side by side on two threads
  // where `jobs` allows (each with a CHOLMOD workspace of its own; only
  // METIS draws random numbers), and keep the cheaper.
  struct Ordered {
    std::vector<SuiteSparse_long> perm;
    double flops = 0.0;
    std::exception_ptr error;
  };
  const auto order = [&](int ordering, cholmod_sparse* graph, Ordered& out) {
    try {
      cholmod_common own{};
      cholmod_l_start(&own);
      own.print = 0;
      own.error_handler = nullptr;
      own.supernodal = CHOLMOD_SIMPLICIAL;
      own.nmethods = 1;
      own.method[0].ordering = ordering;
      cholmod_factor* symbolic = cholmod_l_analyze(graph, &own);
      if (symbolic) {  // (else out of memory: the other ordering stands)
        const auto* perm = static_cast<const SuiteSparse_long*>(symbolic->Perm);
        try {
          out.perm.assign(perm, perm + groups);
          out.flops = own.fl;
        } catch (...) {
          out.error = std::current_exception();
        }
        cholmod_l_free_factor(&symbolic, &own);
      }
      cholmod_l_finish(&own);
    } catch (...) {
      out.error = std::current_exception();
    }
  };
  Ordered amd, metis;
  std::thread beside;
  cholmod_sparse* copy = jobs > 1 ? cholmod_l_copy_sparse(q, c) : nullptr;  // the other thread's own
  const FreeSparse free_copy{copy, c};
  if (copy) {
    try {
      beside = std::thread(order, CHOLMOD_METIS, copy, std::ref(metis));
    } catch (...) {  // std::system_error, std::bad_alloc
      // no thread to be had: both here, one after the other
    }
  }
  order(CHOLMOD_AMD, q, amd);
  if (beside.joinable()) {
    beside.join();
  } else {
    order(CHOLMOD_METIS, q, metis);
  }
  if (amd.error) std::rethrow_exception(amd.error);
  if (metis.error) std::rethrow_exception(metis.error);
  cholmod_l_free_sparse(&q, c);
  const std::vector<SuiteSparse_long>& best =
      amd.perm.empty() || (!metis.perm.empty() && metis.flops < amd.flops) ? metis.perm : amd.perm;
  if (best.empty() && groups > 0) throw std::bad_alloc();
  // Each group's unknowns in their own order, the groups in the ordering's.
  std::vector<SuiteSparse_long> perm;
  perm.reserve(static_cast<std::size_t>(n));
  for (const SuiteSparse_long g : best) {
    for (SuiteSparse_long j = start(g); j < start(g + 1); ++j) perm.push_back(j);
  }
  return perm;
}

std::string gigabytes(double bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f GB", bytes / 1e9);
  return text;
}

// The first column (in the factor's order) whose pivot L(k, k)² is below
// kMinPivotRatio of N's own diagonal there, or −1.
std::int64_t first_negligible_pivot(const SupernodalLayout& layout, const double* x, const std::vector<double>& diagonal) {
  for (std::int64_t s = 0; s < layout.nsuper; ++s) {
    const std::int64_t first = layout.super[s], width = layout.super[s + 1] - first;
    const std::int64_t rows = layout.pi[s + 1] - layout.pi[s];
    for (std::int64_t c = 0; c < width; ++c) {
      const double d = x[layout.px[s] + c * rows + c];
      if (!(d * d >= kMinPivotRatio * diagonal[static_cast<std::size_t>(first + c)])) return first + c;
    }
  }
  return -1;
}

// The dense mode (the tests' reference): Eigen's LLᵀ of the whole matrix
// into `llt`; false, with the first column at which it broke down, when
// the matrix is not positive definite or a pivot is negligible.
bool factor_dense(std::int64_t n, const std::vector<SymmetricEntry>& entries, Eigen::MatrixXd& dense,
                  Eigen::LLT<Eigen::MatrixXd>& llt, std::int64_t* failed_column) {
  dense = Eigen::MatrixXd::Zero(n, n);
  for (const auto& e : entries) {
    dense(e.row, e.col) += e.value;
    if (e.row != e.col) dense(e.col, e.row) += e.value;
  }
  llt.compute(dense);
  std::int64_t negligible = -1;
  if (llt.info() == Eigen::Success) {
    for (std::int64_t k = 0; k < n && negligible < 0; ++k) {
      const double d = llt.matrixLLT()(k, k);
      if (!(d * d >= kMinPivotRatio * dense(k, k))) negligible = k;
    }
  }
  if (negligible >= 0) {
    if (failed_column) *failed_column = negligible;
    return false;
  }
  if (llt.info() != Eigen::Success) {
    // The first column whose pivot is not positive.
    Eigen::MatrixXd a = dense;
    for (std::int64_t k = 0; k < n; ++k) {
      if (!(a(k, k) > 0.0)) {
        if (failed_column) *failed_column = k;
        break;
      }
      const double p = std::sqrt(a(k, k));
      a.col(k).tail(n - k - 1) /= p;
      a.bottomRightCorner(n - k - 1, n - k - 1).noalias() -=
          a.col(k).tail(n - k - 1) * a.col(k).tail(n - k - 1).transpose();
    }
    return false;
  }
  return true;
}

// The matrix the entries sum to, as CHOLMOD's compressed columns (its upper
// triangle, rows sorted); the caller frees it.
cholmod_sparse* upper_triangle(std::int64_t n, const std::vector<SymmetricEntry>& entries, cholmod_common* c) {
  cholmod_triplet* t = cholmod_l_allocate_triplet(static_cast<std::size_t>(n), static_cast<std::size_t>(n), entries.size(),
                                                  1, CHOLMOD_REAL, c);
  if (!t) throw std::bad_alloc();
  auto* ti = static_cast<SuiteSparse_long*>(t->i);
  auto* tj = static_cast<SuiteSparse_long*>(t->j);
  auto* tx = static_cast<double*>(t->x);
  for (std::size_t k = 0; k < entries.size(); ++k) {
    ti[k] = entries[k].row;
    tj[k] = entries[k].col;
    tx[k] = entries[k].value;
  }
  t->nnz = entries.size();
  cholmod_sparse* a = cholmod_l_triplet_to_sparse(t, entries.size(), c);
  cholmod_l_free_triplet(&t, c);
  if (!a) throw std::bad_alloc();
  return a;
}

// A fresh analysis of `a`'s pattern: the quotient graph's ordering
// (quotient_ordering), CHOLMOD's supernodal symbolic factorization on it
// into `factor`, and the memory the factor and its selected inverse will
// take, refused (E_MEMORY) past the budget before any of it is taken.
void analyze_pattern(const cholmod_sparse* a, std::int64_t n, cholmod_common* c, std::uint64_t memory_budget_bytes, int jobs,
                     cholmod_factor*& factor) {
  const auto* ap = static_cast<const SuiteSparse_long*>(a->p);
  std::vector<SuiteSparse_long> ordering = quotient_ordering(a, c, jobs);
  c->nmethods = 1;
  c->method[0].ordering = CHOLMOD_GIVEN;
  factor = cholmod_l_analyze_p(const_cast<cholmod_sparse*>(a), ordering.data(), nullptr, 0, c);
  if (!factor) throw std::bad_alloc();
  // L's values and the selected inverse's, the same size, and a
  // supernode's work space per thread (select_inverse) and CHOLMOD's for
  // the factorization (about the largest supernode's update block).
  const auto* lsuper = static_cast<const SuiteSparse_long*>(factor->super);
  const auto* lpi = static_cast<const SuiteSparse_long*>(factor->pi);
  double block = 0.0;
  for (std::size_t k = 0; factor->is_super && k < factor->nsuper; ++k) {
    const double cols = static_cast<double>(lsuper[k + 1] - lsuper[k]), rows_below = static_cast<double>(lpi[k + 1] - lpi[k]) - cols;
    block = std::max(block, rows_below * rows_below + 2.0 * rows_below * cols + cols * cols);
  }
  // The factorization's own: N's lower triangle in the factor's order
  // (an index and a value per entry), a row map per thread.
  const double threads = static_cast<double>(std::max(1, jobs));
  const double need = 8.0 * (2.0 * static_cast<double>(factor->xsize) + (1.0 + threads) * block) +
                      16.0 * static_cast<double>(ap[n]) + 8.0 * (threads + 2.0) * static_cast<double>(n);
  const std::uint64_t budget = memory_budget_bytes ? memory_budget_bytes : available_memory_bytes();
  if (budget > 0 && need > static_cast<double>(budget)) {
    const double values = static_cast<double>(factor->xsize);
    throw Error(ErrorKind::rejected, "E_MEMORY",
                "the normal matrix of " + std::to_string(n) + " unknowns: its Cholesky factor holds " +
                    std::to_string(static_cast<long long>(values)) + " values (CHOLMOD's analysis), so the factor and its "
                    "selected inverse need " + gigabytes(need) + ", and " + gigabytes(static_cast<double>(budget)) +
                    (memory_budget_bytes ? " are allowed (--max-memory)" : " are available") +
                    "; nothing was factored. Split the network (docs/scale.md) or run it where more memory is free");
  }
}

// N's lower triangle in the factor's order (`perm`), compressed by column.
struct LowerTriangle {
  std::vector<std::int64_t> p, i;
  std::vector<double> x;
};

LowerTriangle permuted_lower(const cholmod_sparse* a, std::int64_t n, const SuiteSparse_long* perm) {
  const auto* ap = static_cast<const SuiteSparse_long*>(a->p);
  const auto* ai = static_cast<const SuiteSparse_long*>(a->i);
  LowerTriangle lower;
  std::vector<std::int64_t>& lower_p = lower.p;
  std::vector<std::int64_t>& lower_i = lower.i;
  std::vector<double>& lower_x = lower.x;
  lower_p.assign(static_cast<std::size_t>(n) + 1, 0);
  lower_i.resize(static_cast<std::size_t>(ap[n]));
  lower_x.resize(static_cast<std::size_t>(ap[n]));
  std::vector<std::int64_t> position(static_cast<std::size_t>(n));
  for (std::int64_t k = 0; k < n; ++k) position[static_cast<std::size_t>(perm[k])] = k;
  const auto* ax = static_cast<const double*>(a->x);
  for (std::int64_t j = 0; j < n; ++j) {
    for (SuiteSparse_long q = ap[j]; q < ap[j + 1]; ++q) {
      ++lower_p[static_cast<std::size_t>(std::min(position[static_cast<std::size_t>(ai[q])], position[static_cast<std::size_t>(j)])) + 1];
    }
  }
  for (std::int64_t j = 0; j < n; ++j) lower_p[static_cast<std::size_t>(j) + 1] += lower_p[static_cast<std::size_t>(j)];
  {
    std::vector<std::int64_t> next(lower_p.begin(), lower_p.end() - 1);
    for (std::int64_t j = 0; j < n; ++j) {
      for (SuiteSparse_long q = ap[j]; q < ap[j + 1]; ++q) {
        const std::int64_t r = position[static_cast<std::size_t>(ai[q])], s = position[static_cast<std::size_t>(j)];
        const std::int64_t k = next[static_cast<std::size_t>(std::min(r, s))]++;
        lower_i[static_cast<std::size_t>(k)] = std::max(r, s);
        lower_x[static_cast<std::size_t>(k)] = ax[q];
      }
    }
  }
  return lower;
}

}  // namespace

std::optional<NormalFactor> NormalFactor::factor(std::int64_t n, const std::vector<SymmetricEntry>& entries, Mode mode,
                                                 std::int64_t* failed_column, std::optional<NormalFactor> previous,
                                                 std::uint64_t memory_budget_bytes, int jobs) {
  // (A moved-from factor has no Impl: no previous.)
  const bool reuse = previous && previous->impl_ && mode == Mode::sparse && previous->impl_->mode == Mode::sparse &&
                     previous->impl_->n == n && previous->impl_->factor;
  auto impl = reuse ? std::move(previous->impl_) : std::make_unique<Impl>();
  previous.reset();
  if (reuse) {  // what the last factor gave no longer holds
    impl->z.clear();
    impl->updates.clear();
    impl->inverse_permutation.clear();
  }
  impl->mode = mode;
  impl->n = n;
  if (failed_column) *failed_column = -1;
  if (mode == Mode::dense) {
    if (!factor_dense(n, entries, impl->dense, impl->llt, failed_column)) return std::nullopt;
    impl->lnz = n * (n + 1) / 2;
    return NormalFactor(std::move(impl));
  }

  cholmod_common* c = &impl->common;
  if (!impl->started) cholmod_l_start(c);
  impl->started = true;
  c->print = 0;
  c->error_handler = nullptr;
  c->final_ll = 1;                      // LLᵀ, which the selected inversion works on
  c->supernodal = CHOLMOD_SUPERNODAL;   // dense blocks for the selected inversion, at every size
  cholmod_sparse* a = upper_triangle(n, entries, c);
  const FreeSparse free_a{a, c};
  const auto* ap = static_cast<const SuiteSparse_long*>(a->p);
  const auto* ai = static_cast<const SuiteSparse_long*>(a->i);
  const bool same_pattern = impl->factor && impl->pattern_p.size() == static_cast<std::size_t>(n) + 1 &&
                            std::equal(ap, ap + n + 1, impl->pattern_p.begin()) &&
                            impl->pattern_i.size() == static_cast<std::size_t>(ap[n]) &&
                            std::equal(ai, ai + ap[n], impl->pattern_i.begin());
  if (!same_pattern) {
    if (impl->factor) cholmod_l_free_factor(&impl->factor, c);
    impl->pattern_p.assign(ap, ap + n + 1);
    impl->pattern_i.assign(ai, ai + ap[n]);
    analyze_pattern(a, n, c, memory_budget_bytes, jobs, impl->factor);
    impl->tree.reset();
  }  // else: the same ordering and supernodes, refactored in place
  cholmod_factor* f = impl->factor;
  if (!f->is_super) throw std::logic_error("NormalFactor: CHOLMOD's analysis is not supernodal");
  if (f->xtype == CHOLMOD_PATTERN && !cholmod_l_change_factor(CHOLMOD_REAL, 1, 1, 1, 1, f, c)) throw std::bad_alloc();  // L's values: allocated, not set
  const auto* perm = static_cast<const SuiteSparse_long*>(f->Perm);
  const LowerTriangle lower = permuted_lower(a, n, perm);
  const std::vector<std::int64_t>& lower_p = lower.p;
  const std::vector<std::int64_t>& lower_i = lower.i;
  const std::vector<double>& lower_x = lower.x;
  cholmod_l_free_sparse(&a, c);  // (before the factorization's work space is taken)
  const SupernodalLayout layout{n, static_cast<std::int64_t>(f->nsuper), static_cast<const std::int64_t*>(f->super),
                                static_cast<const std::int64_t*>(f->pi), static_cast<const std::int64_t*>(f->px),
                                static_cast<const std::int64_t*>(f->s)};
  if (!impl->tree) impl->tree.emplace(layout);
  // N's diagonal in the factor's order (each column's entries start at its diagonal).
  std::vector<double> diagonal(static_cast<std::size_t>(n), 0.0);
  for (std::int64_t j = 0; j < n; ++j) {
    for (std::int64_t q = lower_p[static_cast<std::size_t>(j)]; q < lower_p[static_cast<std::size_t>(j) + 1]; ++q) {
      if (lower_i[static_cast<std::size_t>(q)] == j) diagonal[static_cast<std::size_t>(j)] += lower_x[static_cast<std::size_t>(q)];
    }
  }
  std::int64_t failed = factor_supernodal(layout, *impl->tree, lower_p.data(), lower_i.data(), lower_x.data(),
                                          static_cast<double*>(f->x), std::max(1, jobs));
  if (failed < 0) failed = first_negligible_pivot(layout, static_cast<const double*>(f->x), diagonal);
  if (failed >= 0) {
    if (failed_column) *failed_column = perm[failed];
    return std::nullopt;
  }
  impl->lnz = static_cast<std::int64_t>(c->lnz);
  impl->flops = c->fl;
  return NormalFactor(std::move(impl));
}

std::int64_t NormalFactor::size() const { return impl_->n; }

Eigen::VectorXd NormalFactor::solve(const Eigen::VectorXd& b) const {
  Eigen::MatrixXd m = b;
  return solve(m).col(0);
}

Eigen::MatrixXd NormalFactor::solve(const Eigen::MatrixXd& b) const {
  if (impl_->mode == Mode::dense) return impl_->llt.solve(b);
  cholmod_common* c = &impl_->common;
  cholmod_dense* rhs = cholmod_l_allocate_dense(static_cast<std::size_t>(b.rows()), static_cast<std::size_t>(b.cols()),
                                                static_cast<std::size_t>(b.rows()), CHOLMOD_REAL, c);
  if (!rhs) throw std::bad_alloc();
  std::copy(b.data(), b.data() + b.size(), static_cast<double*>(rhs->x));
  cholmod_dense* x = cholmod_l_solve(CHOLMOD_A, impl_->factor, rhs, c);
  cholmod_l_free_dense(&rhs, c);
  if (!x) throw std::bad_alloc();
  Eigen::MatrixXd out(b.rows(), b.cols());
  std::copy(static_cast<const double*>(x->x), static_cast<const double*>(x->x) + out.size(), out.data());
  cholmod_l_free_dense(&x, c);
  for (const auto& up : impl_->updates) out.noalias() += up.u * up.m.solve(up.u.transpose() * b);
  return out;
}

std::int64_t NormalFactor::elimination_step(std::int64_t unknown) const {
  const Impl& m = *impl_;
  if (m.mode == Mode::dense) return unknown;
  const auto* perm = static_cast<const SuiteSparse_long*>(m.factor->Perm);
  const auto* found = std::find(perm, perm + m.n, static_cast<SuiteSparse_long>(unknown));
  if (found == perm + m.n) throw std::logic_error("NormalFactor::elimination_step: no unknown " + std::to_string(unknown));
  return found - perm;
}

std::int64_t NormalFactor::factor_nonzeros() const { return impl_->lnz; }
double NormalFactor::factor_flops() const { return impl_->flops; }

}  // namespace geoanchor::solver
