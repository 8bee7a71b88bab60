// CHOLMOD's sparse Cholesky and the Takahashi equations on its factor.

#include "sparse_factor.hpp"

#include <cholmod.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

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
  std::vector<std::int64_t> inverse_permutation, super_of;
  // The pattern the analysis was made for (column pointers, row indices).
  std::vector<SuiteSparse_long> pattern_p, pattern_i;
  std::vector<double> z;
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
    const std::int64_t k = super_of[static_cast<std::size_t>(column)];
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

NormalFactor::NormalFactor(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
NormalFactor::~NormalFactor() = default;
NormalFactor::NormalFactor(NormalFactor&&) noexcept = default;
NormalFactor& NormalFactor::operator=(NormalFactor&&) noexcept = default;

std::optional<NormalFactor> NormalFactor::factor(std::int64_t n, const std::vector<SymmetricEntry>& entries, Mode mode,
                                                 std::int64_t* failed_column, std::optional<NormalFactor> previous) {
  // (A moved-from factor has no Impl: no previous.)
  const bool reuse = previous && previous->impl_ && mode == Mode::sparse && previous->impl_->mode == Mode::sparse &&
                     previous->impl_->n == n && previous->impl_->factor;
  auto impl = reuse ? std::move(previous->impl_) : std::make_unique<Impl>();
  previous.reset();
  if (reuse) {  // what the last factor gave no longer holds
    impl->z.clear();
    impl->super_of.clear();
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
    impl->factor = cholmod_l_analyze(a, c);
    if (!impl->factor) {
      cholmod_l_free_sparse(&a, c);
      throw std::bad_alloc();
    }
  }  // else: the same ordering and supernodes, refactored in place
  cholmod_l_factorize(a, impl->factor, c);
  cholmod_l_free_sparse(&a, c);
  if (c->status == CHOLMOD_OUT_OF_MEMORY) throw std::bad_alloc();
  if (c->status == CHOLMOD_NOT_POSDEF || impl->factor->minor < impl->factor->n) {
    const auto* perm = static_cast<const SuiteSparse_long*>(impl->factor->Perm);
    if (failed_column && impl->factor->minor < impl->factor->n) *failed_column = perm[impl->factor->minor];
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
  return out;
}

void NormalFactor::select_inverse() {
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
  m.super_of.assign(n, 0);
  for (std::int64_t k = 0; k < nsuper; ++k) {
    for (SuiteSparse_long j = super[k]; j < super[k + 1]; ++j) m.super_of[static_cast<std::size_t>(j)] = k;
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
  using ConstMap = Eigen::Map<const Matrix>;
  using Map = Eigen::Map<Matrix>;
  // Work space for the largest supernode, allocated once (a fresh
  // allocation per supernode costs more in page faults than the work).
  std::int64_t max_r = 0, max_c = 0;
  for (std::int64_t k = 0; k < nsuper; ++k) {
    max_c = std::max<std::int64_t>(max_c, super[k + 1] - super[k]);
    max_r = std::max<std::int64_t>(max_r, (pi[k + 1] - pi[k]) - (super[k + 1] - super[k]));
  }
  std::vector<double> zrr_space(static_cast<std::size_t>(max_r * max_r)), u_space(static_cast<std::size_t>(max_r * max_c)),
      zrj_space(static_cast<std::size_t>(max_r * max_c)), linv_space(static_cast<std::size_t>(max_c * max_c));
  for (std::int64_t k = nsuper; k-- > 0;) {
    const std::int64_t nscol = super[k + 1] - super[k], nsrow = pi[k + 1] - pi[k], r = nsrow - nscol;
    const ConstMap lk(lx + px[k], nsrow, nscol);
    const auto ljj = lk.topRows(nscol).triangularView<Eigen::Lower>();
    const SuiteSparse_long* below = rows + pi[k] + nscol;  // R, ascending
    Map zrr(zrr_space.data(), r, r), u(u_space.data(), r, nscol), zrj(zrj_space.data(), r, nscol),
        linv(linv_space.data(), nscol, nscol);
    // Z_RR (its lower triangle), gathered column by column: column R[a]
    // lies in supernode t, whose rows, from R[a] on, hold R[a..] in order.
    for (std::int64_t a = 0; a < r; ++a) {
      const std::int64_t c = below[a];
      const std::int64_t t = m.super_of[static_cast<std::size_t>(c)];
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
    linv.setIdentity();
    ljj.solveInPlace(linv);  // L_JJ⁻¹
    Eigen::Map<Matrix> zk(m.z.data() + px[k], nsrow, nscol);
    zk.topRows(nscol).noalias() = linv.transpose() * linv;
    if (r == 0) continue;  // a root: nothing below (Eigen's blocked kernels want no empty operand)
    u = lk.bottomRows(r);
    ljj.solveInPlace<Eigen::OnTheRight>(u);  // U L_JJ = L_RJ
    zrj.noalias() = -(zrr.selfadjointView<Eigen::Lower>() * u);
    zk.topRows(nscol).noalias() -= u.transpose() * zrj;
    zk.bottomRows(r) = zrj;
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

std::optional<double> NormalFactor::inverse_on_pattern(std::int64_t a, std::int64_t b) const {
  const Impl& m = *impl_;
  if (m.mode == Mode::dense) return m.dense_inverse(a, b);
  if (m.z.empty()) throw std::logic_error("NormalFactor::inverse: select_inverse() was not called on this factor");
  const std::int64_t pa = m.inverse_permutation[static_cast<std::size_t>(a)];
  const std::int64_t pb = m.inverse_permutation[static_cast<std::size_t>(b)];
  const std::int64_t p = pa >= pb ? m.find(pa, pb) : m.find(pb, pa);
  if (p < 0) return std::nullopt;
  return m.z[static_cast<std::size_t>(p)];
}

std::int64_t NormalFactor::factor_nonzeros() const { return impl_->lnz; }
double NormalFactor::factor_flops() const { return impl_->flops; }

}  // namespace geoanchor::solver
