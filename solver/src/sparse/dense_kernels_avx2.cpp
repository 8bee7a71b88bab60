// The dense kernels compiled for AVX2 with FMA (this file's compile options,
// solver/CMakeLists.txt); run only where the processor has both.
// Eigen's namespace is renamed here so that its templates, compiled with
// these instructions, never stand in for the baseline's at link time.

#if defined(__AVX2__) && defined(__FMA__)
#define Eigen geoanchor_eigen_avx2
#define GEOANCHOR_KERNEL_NAMESPACE avx2
#include "sparse/dense_kernels.inc"
#undef Eigen

#include "sparse/dense_kernels.hpp"

namespace geoanchor::solver {
extern const DenseKernels kAvx2DenseKernels{"avx2+fma", avx2::outer_product, avx2::cholesky, avx2::solve_lower_transposed_right,
                                            avx2::subtract_product, avx2::inverse_lower, avx2::transposed_gram,
    avx2::solve_lower_right, avx2::negative_symmetric_product, avx2::subtract_transposed_product};
}  // namespace geoanchor::solver
#endif
