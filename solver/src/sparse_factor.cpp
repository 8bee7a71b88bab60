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
  // The selected inverse Z = N⁻¹ in the permuted order of the simplicial
  // LDLᵀ factor, on its pattern: column j holds rows `rows[col[j]..col[j+1])`
  // (the diagonal first, then rows > j ascending) and their values `z`.
  std::vector<std::int64_t> col, rows, inverse_permutation;
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
  // Position of Z(row, column) for row >= column in the permuted order; -1 when off the pattern.
  std::int64_t find(std::int64_t row, std::int64_t column) const {
    const std::int64_t begin = col[static_cast<std::size_t>(column)], end = col[static_cast<std::size_t>(column) + 1];
    if (row == column) return begin;
    const auto first = rows.begin() + begin + 1, last = rows.begin() + end;
    const auto it = std::lower_bound(first, last, row);
    return it != last && *it == row ? static_cast<std::int64_t>(it - rows.begin()) : -1;
  }
};

NormalFactor::NormalFactor(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
NormalFactor::~NormalFactor() = default;
NormalFactor::NormalFactor(NormalFactor&&) noexcept = default;
NormalFactor& NormalFactor::operator=(NormalFactor&&) noexcept = default;

std::optional<NormalFactor> NormalFactor::factor(std::int64_t n, const std::vector<SymmetricEntry>& entries, Mode mode,
                                                 std::int64_t* failed_column) {
  auto impl = std::make_unique<Impl>();
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
  cholmod_l_start(c);
  impl->started = true;
  c->print = 0;
  c->error_handler = nullptr;
  c->final_ll = 1;  // keep LLᵀ: the solves are the same, the selected inversion converts a copy
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
  impl->factor = cholmod_l_analyze(a, c);
  if (!impl->factor) {
    cholmod_l_free_sparse(&a, c);
    throw std::bad_alloc();
  }
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
  cholmod_common* c = &m.common;
  // A simplicial LDLᵀ copy of the factor: L unit lower triangular with D on
  // its diagonal entries, N(P, P) = L D Lᵀ.
  cholmod_factor* s = cholmod_l_copy_factor(m.factor, c);
  if (!s) throw std::bad_alloc();
  if (!cholmod_l_change_factor(CHOLMOD_REAL, 0, 0, 1, 1, s, c)) {
    cholmod_l_free_factor(&s, c);
    throw std::bad_alloc();
  }
  const std::size_t n = static_cast<std::size_t>(m.n);
  const auto* lp = static_cast<const SuiteSparse_long*>(s->p);
  const auto* li = static_cast<const SuiteSparse_long*>(s->i);
  const auto* lx = static_cast<const double*>(s->x);
  const auto* lnz = static_cast<const SuiteSparse_long*>(s->nz);
  const auto* perm = static_cast<const SuiteSparse_long*>(s->Perm);
  m.inverse_permutation.assign(n, 0);
  for (std::size_t k = 0; k < n; ++k) m.inverse_permutation[static_cast<std::size_t>(perm[k])] = static_cast<std::int64_t>(k);
  // The pattern, each column's rows below the diagonal sorted, with L's values.
  m.col.assign(n + 1, 0);
  for (std::size_t j = 0; j < n; ++j) m.col[j + 1] = m.col[j] + lnz[j];
  m.rows.assign(static_cast<std::size_t>(m.col[n]), 0);
  std::vector<double> l(m.rows.size(), 0.0), d(n, 0.0);
  std::vector<std::pair<std::int64_t, double>> below;
  for (std::size_t j = 0; j < n; ++j) {
    const SuiteSparse_long p0 = lp[j];
    d[j] = lx[p0];  // the first entry of a simplicial column is its diagonal
    below.clear();
    for (SuiteSparse_long p = p0 + 1; p < p0 + lnz[j]; ++p) below.emplace_back(li[p], lx[p]);
    std::sort(below.begin(), below.end());
    const std::size_t at = static_cast<std::size_t>(m.col[j]);
    m.rows[at] = static_cast<std::int64_t>(j);
    for (std::size_t k = 0; k < below.size(); ++k) {
      m.rows[at + 1 + k] = below[k].first;
      l[at + 1 + k] = below[k].second;
    }
  }
  cholmod_l_free_factor(&s, c);
  // Takahashi: Z = D⁻¹L⁻¹ + (I − Lᵀ) Z, from the last column to the first;
  // every Z(k, i) it needs has k and i in one column's pattern, which the
  // elimination tree closes under.
  m.z.assign(m.rows.size(), 0.0);
  // For column j with the rows r_1 < … < r_k below its diagonal:
  // Z(r_a, j) = −Σ_b L(r_b, j) Z(r_b, r_a). Each pair a < b reads
  // Z(r_b, r_a) once, from column r_a (whose pattern holds r_b: the
  // elimination tree closes it), by a merge of two sorted row lists, and
  // adds it to both sums; Z(r_a, r_a) is column r_a's first entry.
  std::vector<double> sum;
  for (std::size_t jj = n; jj-- > 0;) {
    const std::int64_t begin = m.col[jj] + 1, end = m.col[jj + 1];
    const std::size_t k = static_cast<std::size_t>(end - begin);
    sum.assign(k, 0.0);
    for (std::size_t a = 0; a < k; ++a) {
      const std::int64_t ra = m.rows[static_cast<std::size_t>(begin) + a];
      const double la = l[static_cast<std::size_t>(begin) + a];
      std::int64_t q = m.col[static_cast<std::size_t>(ra)];
      const std::int64_t q_end = m.col[static_cast<std::size_t>(ra) + 1];
      sum[a] += la * m.z[static_cast<std::size_t>(q)];  // Z(r_a, r_a)
      ++q;
      for (std::size_t b = a + 1; b < k; ++b) {
        const std::int64_t rb = m.rows[static_cast<std::size_t>(begin) + b];
        while (q < q_end && m.rows[static_cast<std::size_t>(q)] < rb) ++q;
        if (q == q_end || m.rows[static_cast<std::size_t>(q)] != rb) {
          throw std::logic_error("selected inversion: an entry off the factor's pattern");
        }
        const double w = m.z[static_cast<std::size_t>(q)];  // Z(r_b, r_a)
        sum[a] += l[static_cast<std::size_t>(begin) + b] * w;
        sum[b] += la * w;
      }
    }
    double diagonal = 1.0 / d[jj];
    for (std::size_t a = 0; a < k; ++a) {
      m.z[static_cast<std::size_t>(begin) + a] = -sum[a];
      diagonal += l[static_cast<std::size_t>(begin) + a] * sum[a];
    }
    m.z[static_cast<std::size_t>(m.col[jj])] = diagonal;
  }
}

double NormalFactor::inverse(std::int64_t a, std::int64_t b) const {
  const Impl& m = *impl_;
  if (m.mode == Mode::dense) return m.dense_inverse(a, b);
  const std::int64_t pa = m.inverse_permutation[static_cast<std::size_t>(a)];
  const std::int64_t pb = m.inverse_permutation[static_cast<std::size_t>(b)];
  const std::int64_t p = pa >= pb ? m.find(pa, pb) : m.find(pb, pa);
  if (p < 0) throw std::logic_error("NormalFactor::inverse: (" + std::to_string(a) + ", " + std::to_string(b) +
                                    ") is off the factor's pattern");
  return m.z[static_cast<std::size_t>(p)];
}

std::int64_t NormalFactor::factor_nonzeros() const { return impl_->lnz; }
double NormalFactor::factor_flops() const { return impl_->flops; }

}  // namespace geoanchor::solver
