#pragma once
// The dense kernels of the supernodal Cholesky factorization and of its
// selected inversion, on column-major blocks given by pointer and leading
// dimension. They are compiled twice — for the x86-64 baseline and for
// AVX2 with FMA (Eigen vectorizes at compile time) — and dense_kernels()
// gives the set this processor runs. Each kernel's numbers depend on its
// operands' shapes alone, never on threads.
//
// Private to solver.

#include <cstddef>
#include <cstdint>
#include <vector>

namespace geoanchor::solver {

struct DenseKernels {
  const char* name;  // "avx2+fma" or "x86-64"
  // C (m2 × m1, leading dimension m2) = A_top_m2 A_top_m1ᵀ, where A is the
  // rows × k block at `a` (leading dimension lda) and A_top_m its first m rows.
  void (*outer_product)(const double* a, std::int64_t lda, std::int64_t m2, std::int64_t m1, std::int64_t k, double* c);
  // The Cholesky factor of the n × n block at `a` (its lower triangle read
  // and overwritten; the strict upper triangle is not touched). Returns −1,
  // or the first column whose pivot is not a positive finite number.
  std::int64_t (*cholesky)(double* a, std::int64_t lda, std::int64_t n);
  // X := X L⁻ᵀ: X is m × n at `x` (ldx), L n × n lower triangular at `l`.
  void (*solve_lower_transposed_right)(const double* l, std::int64_t ldl, std::int64_t n, double* x, std::int64_t ldx,
                                       std::int64_t m);
  // C −= A Bᵀ: C m × n (ldc), A m × k (lda), B n × k (ldb).
  void (*subtract_product)(const double* a, std::int64_t lda, const double* b, std::int64_t ldb, std::int64_t m, std::int64_t n,
                           std::int64_t k, double* c, std::int64_t ldc);
  // The selected inversion's (sparse_factor.cpp):
  // out (n × n, ldo) = L⁻¹ for L n × n lower triangular at `l`.
  void (*inverse_lower)(const double* l, std::int64_t ldl, std::int64_t n, double* out, std::int64_t ldo);
  // out (n × n, ldo) = Aᵀ A, A n × n at `a`.
  void (*transposed_gram)(const double* a, std::int64_t lda, std::int64_t n, double* out, std::int64_t ldo);
  // X := X L⁻¹: X is m × n at `x` (ldx), L n × n lower triangular at `l`.
  void (*solve_lower_right)(const double* l, std::int64_t ldl, std::int64_t n, double* x, std::int64_t ldx, std::int64_t m);
  // out (r × n, ldo) = −S B: S r × r symmetric, its lower triangle at `s`;
  // B r × n at `b`.
  void (*negative_symmetric_product)(const double* s, std::int64_t lds, std::int64_t r, const double* b, std::int64_t ldb,
                                     std::int64_t n, double* out, std::int64_t ldo);
  // C −= Aᵀ B: C m × n (ldc), A k × m (lda), B k × n (ldb).
  void (*subtract_transposed_product)(const double* a, std::int64_t lda, const double* b, std::int64_t ldb, std::int64_t m,
                                      std::int64_t n, std::int64_t k, double* c, std::int64_t ldc);
};

// Work space for the kernels, 64-byte aligned. Eigen's vector loops peel
// the elements before the first aligned address off as scalar operations;
// with FMA in the vector part and none in the scalar one the two round
// differently, so a block's numbers would depend on where a thread's work
// space happens to start. Aligned, they depend on the block's shape alone.
class KernelSpace {
 public:
  static constexpr std::size_t kAlignBytes = 64;
  // `count` doubles (the contents are not kept when it grows).
  double* take(std::size_t count) {
    constexpr std::size_t pad = kAlignBytes / sizeof(double);
    if (storage_.size() < count + pad) storage_.assign(count + pad, 0.0);
    const auto address = reinterpret_cast<std::uintptr_t>(storage_.data());
    const std::size_t skip = (kAlignBytes - address % kAlignBytes) % kAlignBytes / sizeof(double);
    return storage_.data() + skip;
  }

 private:
  std::vector<double> storage_;
};

// The AVX2+FMA set where the processor has both, else the baseline's.
const DenseKernels& dense_kernels();
// Both sets, for the tests (the AVX2 one is nullptr where it cannot run).
const DenseKernels& baseline_dense_kernels();
const DenseKernels* avx2_dense_kernels();

}  // namespace geoanchor::solver
