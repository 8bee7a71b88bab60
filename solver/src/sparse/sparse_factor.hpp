#pragma once
// The normal matrix of a least-squares problem, factored once: a sparse
// supernodal Cholesky (a fill-reducing ordering on the matrix's quotient
// graph by CHOLMOD's AMD or METIS, CHOLMOD's symbolic analysis, and
// geoanchor's own numeric factorization, supernodal_cholesky.hpp), its
// solves (CHOLMOD's, with that factor), and the entries of its inverse on
// the factor's pattern by the Takahashi equations (selected inversion,
// selected_inversion.cpp): every pair of unknowns that share a
// measurement is on that pattern, so station covariances, covariances
// between connected stations and every measurement's redundancy come from
// it without a dense inverse. A dense mode (Eigen's LLᵀ and the full
// inverse) is the tests' reference for small problems.
//
// Private to solver.

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

namespace geoanchor::solver {

// One entry of the upper triangle of a symmetric matrix (row <= col); the
// entries given for the same (row, col) are summed.
struct SymmetricEntry {
  std::int64_t row = 0, col = 0;
  double value = 0.0;
};

// A pivot L(k, k)² below this share of the matrix's own diagonal N(k, k)
// is a direction the matrix does not determine that rounding left positive:
// the factorization is taken as failed there (a station whose position its
// measurements leave free, factored early, has a pivot of a few units of
// rounding, 1e-16 of its diagonal; a datum held by weighted constraints of
// 100 m among baselines of millimetres, 1e-10 and more).
inline constexpr double kMinPivotRatio = 1e-14;

class NormalFactor {
 public:
  enum class Mode { sparse, dense };

  // Factors the n × n matrix the entries sum to (sparse: CHOLMOD's
  // analysis, the numeric factorization of supernodal_cholesky.hpp on `jobs`
  // threads, the same bits on any number). When it is not positive
  // definite, nullopt, and `failed_column` the first unknown (in the
  // caller's order) at which the factorization broke down (a pivot not
  // positive, not finite, or below kMinPivotRatio of its diagonal).
  // With `previous` (a sparse factor of a matrix of the same size), its
  // analysis (ordering and supernodal pattern) is reused when the entries
  // have the same pattern: only the numeric factorization is redone
  // (`previous` is consumed either way). Gauss–Newton iterations refactor
  // one pattern several times.
  // A fresh analysis states the memory the factor and its selected inverse
  // will need (2 × L's values, from CHOLMOD's symbolic factorization)
  // before any of it is taken: above `memory_budget_bytes` (0: what the
  // machine has available, MemAvailable, within the address-space limit)
  // it throws geoanchor::Error (rejected, E_MEMORY) naming both.
  // `jobs`: the threads the factorization runs on, and select_inverse will
  // (each has a work space of the largest supernode's size).
  static std::optional<NormalFactor> factor(std::int64_t n, const std::vector<SymmetricEntry>& entries, Mode mode,
                                            std::int64_t* failed_column, std::optional<NormalFactor> previous = std::nullopt,
                                            std::uint64_t memory_budget_bytes = 0, int jobs = 1);
  ~NormalFactor();
  NormalFactor(NormalFactor&&) noexcept;
  NormalFactor& operator=(NormalFactor&&) noexcept;
  NormalFactor(const NormalFactor&) = delete;
  NormalFactor& operator=(const NormalFactor&) = delete;

  std::int64_t size() const;
  // N⁻¹ b, and N⁻¹ B column by column.
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) const;

  // Computes the entries of N⁻¹ on the factor's pattern (sparse), or the
  // whole inverse (dense). Call once before inverse().
  // On `jobs` threads (disjoint subtrees of the supernodal elimination
  // tree); the numbers do not depend on them.
  void select_inverse(int jobs = 1);
  // Takes rows out of the factored matrix without factoring it again: the
  // matrix becomes N − B Bᵀ (B: n × r, each column a whitened observation
  // row of a measurement taken out). By Sherman–Morrison–Woodbury,
  //   (N − B Bᵀ)⁻¹ = N⁻¹ + U M⁻¹ Uᵀ,  U = N⁻¹ B,  M = I − Bᵀ N⁻¹ B
  // (M is the rows' residual cofactor: positive definite while the rows are
  // redundant), after select_inverse(): the selected inverse is updated in
  // place, on `jobs` threads (the numbers do not depend on them), and
  // solve() answers for the new matrix. The cost is r solves and r
  // multiply-adds per entry of the pattern, against a numeric
  // factorization and a selected inversion: worth it for a few rows
  // (downdate_rows_worth()). Downdates compose. Returns false, and changes
  // nothing, in dense mode or when M's smallest eigenvalue is below 1e-6
  // (the rows nearly all that determines some unknown: refactor instead).
  bool downdate(const Eigen::MatrixXd& b, int jobs = 1);
  // The most rows (all downdates since the factorization together) a
  // downdate is worth: where its solves and updates cost less than a
  // factorization and a selected inversion, and its n × r vectors take at
  // most half of what L takes.
  std::int64_t downdate_rows_worth() const;
  std::int64_t downdated_rows() const;

  // (N⁻¹)(a, b). Throws std::logic_error for an entry off the pattern (a
  // pair of unknowns that share no measurement): a caller bug.
  double inverse(std::int64_t a, std::int64_t b) const;

  // (N⁻¹)(u[a], u[b]) for every pair of the `count` unknowns at `u`, into
  // `q` (count × count, column-major): the block a measurement's
  // statistics need, found with one search of the factor's rows per
  // station pair rather than one per entry. False (q partly written) when
  // a pair is off the pattern.
  bool inverse_block(const std::int64_t* u, std::size_t count, double* q) const;

  // The blocks A_i N⁻¹ A_jᵀ between row blocks (block c: its rows `rows[c]`
  // over the unknowns `unknowns[c]`, k_c × their count), stacked (Σk × Σk,
  // symmetric); the downdates' low-rank terms included. L⁻¹ P A_cᵀ is zero
  // off the elimination tree's paths from c's unknowns to the root, so a
  // block costs a forward solve along them (a tenth of a solve and less in
  // a network of 10⁵ stations) and a pair the inner product over the
  // supernodes their paths share (sparse_paths.cpp). On `jobs` threads, the
  // same bits for any number. Dense mode: from the whole inverse.
  Eigen::MatrixXd inverse_between(const std::vector<std::vector<std::int64_t>>& unknowns, const std::vector<Eigen::MatrixXd>& rows,
                                  int jobs = 1) const;
  // Where `unknown` comes in the factor's elimination order (the tests' view
  // of the ordering; dense: the unknown itself).
  std::int64_t elimination_step(std::int64_t unknown) const;

  // The factor's size: nonzeros of L, and floating-point work of the
  // factorization (the flop count of CHOLMOD's symbolic analysis; 0 in
  // dense mode).
  std::int64_t factor_nonzeros() const;
  double factor_flops() const;

 private:
  struct Impl;
  explicit NormalFactor(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace geoanchor::solver
