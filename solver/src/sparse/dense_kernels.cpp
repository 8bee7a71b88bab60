// The dense kernels for the x86-64 baseline, and the choice of set.

#define GEOANCHOR_KERNEL_NAMESPACE baseline
#include "sparse/dense_kernels.inc"

#include "sparse/dense_kernels.hpp"

namespace geoanchor::solver {

#if defined(GEOANCHOR_HAVE_AVX2_KERNELS)
extern const DenseKernels kAvx2DenseKernels;
#endif

const DenseKernels& baseline_dense_kernels() {
  static const DenseKernels kernels{"x86-64", baseline::outer_product, baseline::cholesky, baseline::solve_lower_transposed_right,
                                    baseline::subtract_product, baseline::inverse_lower, baseline::transposed_gram,
    baseline::solve_lower_right, baseline::negative_symmetric_product, baseline::subtract_transposed_product};
  return kernels;
}

const DenseKernels* avx2_dense_kernels() {
#if defined(GEOANCHOR_HAVE_AVX2_KERNELS)
  static const bool runs = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return runs ? &kAvx2DenseKernels : nullptr;
#else
  return nullptr;
#endif
}

const DenseKernels& dense_kernels() {
  static const DenseKernels& chosen = avx2_dense_kernels() ? *avx2_dense_kernels() : baseline_dense_kernels();
  return chosen;
}

}  // namespace geoanchor::solver
