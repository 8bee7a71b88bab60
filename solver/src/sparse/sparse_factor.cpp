// CHOLMOD's sparse Cholesky and the Takahashi equations on its factor.

#include "sparse/sparse_factor.hpp"

#include <cholmod.h>
#include <sys/resource.h>
#include <unistd.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <atomic>
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

#include "geoanchor/geodesy/error.hpp"
#include "geoanchor/geodesy/parallel.hpp"
#include "sparse/dense_kernels.hpp"
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
    impl->dense = Eigen::MatrixXd::Zero(n, n);
    for (const auto& e : entries) {
      impl->dense(e.row, e.col) += e.value;
      if (e.row != e.col) impl->dense(e.col, e.row) += e.value;
    }
    impl->llt.compute(impl->dense);
    std::int64_t negligible = -1;
    if (impl->llt.info() == Eigen::Success) {
      for (std::int64_t k = 0; k < n && negligible < 0; ++k) {
        const double d = impl->llt.matrixLLT()(k, k);
        if (!(d * d >= kMinPivotRatio * impl->dense(k, k))) negligible = k;
      }
    }
    if (negligible >= 0) {
      if (failed_column) *failed_column = negligible;
      return std::nullopt;
    }
    if (impl->llt.info() != Eigen::Success) {
      // The first column whose pivot is not positive.
      Eigen::MatrixXd a = impl->dense;
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
      return std::nullopt;
    }
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
    std::vector<SuiteSparse_long> ordering = quotient_ordering(a, c, jobs);
    c->nmethods = 1;
    c->method[0].ordering = CHOLMOD_GIVEN;
    impl->factor = cholmod_l_analyze_p(a, ordering.data(), nullptr, 0, c);
    if (!impl->factor) throw std::bad_alloc();
    // L's values and the selected inverse's, the same size, and a
    // supernode's work space per thread (select_inverse) and CHOLMOD's for
    // the factorization (about the largest supernode's update block).
    const auto* lsuper = static_cast<const SuiteSparse_long*>(impl->factor->super);
    const auto* lpi = static_cast<const SuiteSparse_long*>(impl->factor->pi);
    double block = 0.0;
    for (std::size_t k = 0; impl->factor->is_super && k < impl->factor->nsuper; ++k) {
      const double cols = static_cast<double>(lsuper[k + 1] - lsuper[k]), rows_below = static_cast<double>(lpi[k + 1] - lpi[k]) - cols;
      block = std::max(block, rows_below * rows_below + 2.0 * rows_below * cols + cols * cols);
    }
    // The factorization's own: N's lower triangle in the factor's order
    // (an index and a value per entry), a row map per thread.
    const double threads = static_cast<double>(std::max(1, jobs));
    const double need = 8.0 * (2.0 * static_cast<double>(impl->factor->xsize) + (1.0 + threads) * block) +
                        16.0 * static_cast<double>(ap[n]) + 8.0 * (threads + 2.0) * static_cast<double>(n);
    const std::uint64_t budget = memory_budget_bytes ? memory_budget_bytes : available_memory_bytes();
    if (budget > 0 && need > static_cast<double>(budget)) {
      const double values = static_cast<double>(impl->factor->xsize);
      throw Error(ErrorKind::rejected, "E_MEMORY",
                  "the normal matrix of " + std::to_string(n) + " unknowns: its Cholesky factor holds " +
                      std::to_string(static_cast<long long>(values)) + " values (CHOLMOD's analysis), so the factor and its "
                      "selected inverse need " + gigabytes(need) + ", and " + gigabytes(static_cast<double>(budget)) +
                      (memory_budget_bytes ? " are allowed (--max-memory)" : " are available") +
                      "; nothing was factored. Split the network (docs/scale.md) or run it where more memory is free");
    }
    impl->tree.reset();
  }  // else: the same ordering and supernodes, refactored in place
  cholmod_factor* f = impl->factor;
  if (!f->is_super) throw std::logic_error("NormalFactor: CHOLMOD's analysis is not supernodal");
  if (f->xtype == CHOLMOD_PATTERN && !cholmod_l_change_factor(CHOLMOD_REAL, 1, 1, 1, 1, f, c)) throw std::bad_alloc();  // L's values: allocated, not set
  const auto* perm = static_cast<const SuiteSparse_long*>(f->Perm);
  // N's lower triangle in the factor's order, compressed by column.
  std::vector<std::int64_t> lower_p(static_cast<std::size_t>(n) + 1, 0), lower_i(static_cast<std::size_t>(ap[n])),
      position(static_cast<std::size_t>(n));
  std::vector<double> lower_x(static_cast<std::size_t>(ap[n]));
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

  // Supernode by supernode from the last (the root) to the first. With J
  // its columns and R the rows below them, L_JJ lower triangular and L_RJ
  // below it, and U = L_RJ L_JJ⁻¹, the Takahashi equations Lᵀ Z = L⁻¹ give
  //   Z_RJ = −Z_RR U,   Z_JJ = L_JJ⁻ᵀ L_JJ⁻¹ − Uᵀ Z_RJ.
  // R is a clique of the factor's graph, so Z_RR lies on the pattern of
  // the supernodes that hold R's columns, already computed.
  using Matrix = Eigen::MatrixXd;
  using Map = Eigen::Map<Matrix>;
  // Work space for the largest supernode, allocated once per thread (a
  // fresh allocation per supernode costs more in page faults than the work).
  std::int64_t max_r = 0, max_c = 0;
  for (std::int64_t k = 0; k < nsuper; ++k) {
    max_c = std::max<std::int64_t>(max_c, super[k + 1] - super[k]);
    max_r = std::max<std::int64_t>(max_r, (pi[k + 1] - pi[k]) - (super[k + 1] - super[k]));
  }
  // (Aligned: a block's numbers are the same whichever thread's space it is
  // computed in, dense_kernels.hpp.)
  struct Workspace {
    KernelSpace zrr_space, u_space, zrj_space, linv_space;
    double *zrr = nullptr, *u = nullptr, *zrj = nullptr, *linv = nullptr;
  };
  const auto workspace = [&] {
    Workspace w;
    w.zrr = w.zrr_space.take(static_cast<std::size_t>(max_r * max_r));
    w.u = w.u_space.take(static_cast<std::size_t>(max_r * max_c));
    w.zrj = w.zrj_space.take(static_cast<std::size_t>(max_r * max_c));
    w.linv = w.linv_space.take(static_cast<std::size_t>(max_c * max_c));
    return w;
  };

  // A supernode's work is cut into slices whose sizes depend on its shape
  // alone (kSliceColumns of U and Z_RJ, kSliceRows of U, kSliceGather
  // columns of Z_RR), so that its numbers are the same whether the slices
  // run on one thread or on `jobs` (the supernodes above the subtrees'
  // split are the largest, and are done with every thread).
  constexpr std::int64_t kSliceColumns = 32, kSliceRows = 256, kSliceGather = 128;
  const auto process = [&](std::int64_t k, Workspace& w, int jobs_here) {
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
        const double* t_z = m.z.data() + px[t] + (c - super[t]) * t_nsrow;
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
    double* z_k = m.z.data() + px[k];
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
  };

  // A supernode needs only its ancestors (R's columns lie in them), so
  // disjoint subtrees of the supernodal elimination tree go to threads:
  // the largest subtrees are split (their roots done here first, parents
  // before children) until there are enough to share out; each thread then
  // does whole subtrees, each from its root down. Every supernode's numbers
  // are the same whichever thread computes them.
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
  Workspace here = workspace();
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
  for (int t = 1; t < threads && static_cast<std::size_t>(t) < pending.size(); ++t) spaces.push_back(workspace());
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
