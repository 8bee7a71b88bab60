// The dense kernels of the supernodal factorization (solver/src/
// dense_kernels, private to solver), each set this processor runs (the
// x86-64 baseline, and AVX2+FMA where it has both), against plain loops
// over the textbook definitions, on blocks inside larger arrays (leading
// dimension above the rows) with odd sizes that leave vector remainders.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <tuple>
#include <vector>

#include "sparse/dense_kernels.hpp"
#include "test_support.hpp"

namespace geoanchor::solver {
namespace {

constexpr double kRelative = 1e-13;  // of the largest entry: a few ulps of sums of up to 150 products

std::vector<const DenseKernels*> sets() {
  std::vector<const DenseKernels*> all{&baseline_dense_kernels()};
  if (avx2_dense_kernels()) all.push_back(avx2_dense_kernels());
  return all;
}

std::vector<double> random_values(std::size_t count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> v(count);
  for (double& x : v) x = u(rng);
  return v;
}

TEST(DenseKernels, TheChosenSetIsOneOfThem) {
  const DenseKernels& chosen = dense_kernels();
  EXPECT_TRUE(&chosen == &baseline_dense_kernels() || &chosen == avx2_dense_kernels()) << chosen.name;
}

TEST(DenseKernels, OuterProductAndSubtractProduct) {
  for (const DenseKernels* k : sets()) {
    SCOPED_TRACE(k->name);
    for (const auto& [m2, m1, depth] : {std::tuple{1, 1, 1}, std::tuple{7, 3, 5}, std::tuple{131, 37, 149}, std::tuple{64, 64, 3}}) {
      const std::int64_t lda = m2 + 5;
      const std::vector<double> a = random_values(static_cast<std::size_t>(lda * depth), 3u);
      std::vector<double> c(static_cast<std::size_t>(m2 * m1), 7.0);
      k->outer_product(a.data(), lda, m2, m1, depth, c.data());
      double worst = 0.0;
      for (int j = 0; j < m1; ++j) {
        for (int i = 0; i < m2; ++i) {
          double sum = 0.0;
          for (int q = 0; q < depth; ++q) sum += a[static_cast<std::size_t>(i + q * lda)] * a[static_cast<std::size_t>(j + q * lda)];
          worst = testing::nan_max(worst, std::abs(c[static_cast<std::size_t>(i + j * m2)] - sum) / depth);
        }
      }
      EXPECT_LE(worst, kRelative) << m2 << " × " << m1 << " × " << depth;
      // C −= A Bᵀ with C inside a larger array.
      const std::int64_t ldb = m1 + 2, ldc = m2 + 3;
      const std::vector<double> b = random_values(static_cast<std::size_t>(ldb * depth), 4u);
      std::vector<double> out = random_values(static_cast<std::size_t>(ldc * m1), 5u), before = out;
      k->subtract_product(a.data(), lda, b.data(), ldb, m2, m1, depth, out.data(), ldc);
      worst = 0.0;
      for (int j = 0; j < m1; ++j) {
        for (int i = 0; i < ldc; ++i) {
          double expected = before[static_cast<std::size_t>(i + j * ldc)];
          if (i < m2) {
            for (int q = 0; q < depth; ++q) expected -= a[static_cast<std::size_t>(i + q * lda)] * b[static_cast<std::size_t>(j + q * ldb)];
          }
          worst = testing::nan_max(worst, std::abs(out[static_cast<std::size_t>(i + j * ldc)] - expected) / depth);
        }
      }
      EXPECT_LE(worst, kRelative) << "subtract " << m2 << " × " << m1 << " × " << depth;
    }
  }
}

TEST(DenseKernels, CholeskyAndTriangularSolve) {
  for (const DenseKernels* k : sets()) {
    SCOPED_TRACE(k->name);
    for (const int n : {1, 5, 67, 150}) {
      const int ld = n + 4;
      // A = G Gᵀ + n I, positive definite; its upper triangle holds 99s
      // that must be neither read nor written.
      const std::vector<double> g = random_values(static_cast<std::size_t>(n * n), 9u);
      std::vector<double> a(static_cast<std::size_t>(ld * n), 99.0), reference(static_cast<std::size_t>(n * n), 0.0);
      for (int j = 0; j < n; ++j) {
        for (int i = j; i < n; ++i) {
          double sum = i == j ? n : 0.0;
          for (int q = 0; q < n; ++q) sum += g[static_cast<std::size_t>(i + q * n)] * g[static_cast<std::size_t>(j + q * n)];
          a[static_cast<std::size_t>(i + j * ld)] = sum;
          reference[static_cast<std::size_t>(i + j * n)] = sum;
        }
      }
      // The textbook Cholesky–Banachiewicz on the reference.
      for (int j = 0; j < n; ++j) {
        for (int i = j; i < n; ++i) {
          double sum = reference[static_cast<std::size_t>(i + j * n)];
          for (int q = 0; q < j; ++q) sum -= reference[static_cast<std::size_t>(i + q * n)] * reference[static_cast<std::size_t>(j + q * n)];
          reference[static_cast<std::size_t>(i + j * n)] = i == j ? std::sqrt(sum) : sum / reference[static_cast<std::size_t>(j + j * n)];
        }
      }
      ASSERT_EQ(k->cholesky(a.data(), ld, n), -1) << n;
      double worst = 0.0;
      for (int j = 0; j < n; ++j) {
        for (int i = 0; i < ld; ++i) {
          const double got = a[static_cast<std::size_t>(i + j * ld)];
          if (i < j || i >= n) {
            EXPECT_EQ(got, 99.0) << i << ", " << j;
          } else {
            worst = testing::nan_max(worst, std::abs(got - reference[static_cast<std::size_t>(i + j * n)]));
          }
        }
      }
      EXPECT_LE(worst, kRelative * n) << n;
      // X L⁻ᵀ: multiplied back by Lᵀ it gives X.
      const int m = 2 * n + 3, ldx = m + 1;
      const std::vector<double> x = random_values(static_cast<std::size_t>(ldx * n), 11u);
      std::vector<double> solved = x;
      k->solve_lower_transposed_right(a.data(), ld, n, solved.data(), ldx, m);
      worst = 0.0;
      for (int i = 0; i < m; ++i) {
        for (int j = 0; j < n; ++j) {
          double back = 0.0;  // (Y Lᵀ)(i, j) = Σ_q Y(i, q) L(j, q)
          for (int q = 0; q <= j; ++q) back += solved[static_cast<std::size_t>(i + q * ldx)] * a[static_cast<std::size_t>(j + q * ld)];
          worst = testing::nan_max(worst, std::abs(back - x[static_cast<std::size_t>(i + j * ldx)]));
        }
      }
      EXPECT_LE(worst, kRelative * n) << "solve " << n;
    }
  }
}

// The selected inversion's kernels.
TEST(DenseKernels, InverseGramSymmetricAndTransposedProducts) {
  for (const DenseKernels* k : sets()) {
    SCOPED_TRACE(k->name);
    for (const int n : {1, 6, 45, 133}) {
      // L lower triangular with a dominant diagonal, inside a larger array.
      const int ld = n + 3;
      std::vector<double> l = random_values(static_cast<std::size_t>(ld * n), 13u);
      for (int j = 0; j < n; ++j) l[static_cast<std::size_t>(j + j * ld)] = 2.0 + std::abs(l[static_cast<std::size_t>(j + j * ld)]);
      const auto at = [&](int i, int j) { return i < j ? 0.0 : l[static_cast<std::size_t>(i + j * ld)]; };
      std::vector<double> inverse(static_cast<std::size_t>(n * n));
      k->inverse_lower(l.data(), ld, n, inverse.data(), n);
      double worst = 0.0;
      for (int i = 0; i < n; ++i) {  // L L⁻¹ = I
        for (int j = 0; j < n; ++j) {
          double sum = 0.0;
          for (int q = 0; q < n; ++q) sum += at(i, q) * inverse[static_cast<std::size_t>(q + j * n)];
          worst = testing::nan_max(worst, std::abs(sum - (i == j ? 1.0 : 0.0)));
        }
      }
      EXPECT_LE(worst, kRelative * n) << "inverse " << n;
      std::vector<double> gram(static_cast<std::size_t>((n + 2) * n), 5.0);
      k->transposed_gram(l.data(), ld, n, gram.data(), n + 2);
      worst = 0.0;
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          double sum = 0.0;
          for (int q = 0; q < n; ++q) sum += l[static_cast<std::size_t>(q + i * ld)] * l[static_cast<std::size_t>(q + j * ld)];
          worst = testing::nan_max(worst, std::abs(gram[static_cast<std::size_t>(i + j * (n + 2))] - sum) / n);
        }
      }
      EXPECT_LE(worst, kRelative) << "gram " << n;
      // X L⁻¹: multiplied back by L it gives X.
      const int m = n + 7, ldx = m + 2;
      const std::vector<double> x = random_values(static_cast<std::size_t>(ldx * n), 15u);
      std::vector<double> solved = x;
      k->solve_lower_right(l.data(), ld, n, solved.data(), ldx, m);
      worst = 0.0;
      for (int i = 0; i < m; ++i) {
        for (int j = 0; j < n; ++j) {
          double back = 0.0;
          for (int q = j; q < n; ++q) back += solved[static_cast<std::size_t>(i + q * ldx)] * at(q, j);
          worst = testing::nan_max(worst, std::abs(back - x[static_cast<std::size_t>(i + j * ldx)]));
        }
      }
      EXPECT_LE(worst, kRelative * n) << "solve right " << n;
      // −S B with S's lower triangle (its upper one holds values that must
      // not be read), and C −= Aᵀ B.
      const int r = n + 4, cols = n % 7 + 2;
      std::vector<double> sym = random_values(static_cast<std::size_t>(r * r), 17u);
      const std::vector<double> b = random_values(static_cast<std::size_t>(r * cols), 19u);
      std::vector<double> product(static_cast<std::size_t>(r * cols));
      k->negative_symmetric_product(sym.data(), r, r, b.data(), r, cols, product.data(), r);
      worst = 0.0;
      for (int i = 0; i < r; ++i) {
        for (int j = 0; j < cols; ++j) {
          double sum = 0.0;
          for (int q = 0; q < r; ++q) sum -= sym[static_cast<std::size_t>(std::max(i, q) + std::min(i, q) * r)] * b[static_cast<std::size_t>(q + j * r)];
          worst = testing::nan_max(worst, std::abs(product[static_cast<std::size_t>(i + j * r)] - sum) / r);
        }
      }
      EXPECT_LE(worst, kRelative) << "symmetric " << n;
      std::vector<double> c = random_values(static_cast<std::size_t>((cols + 1) * cols), 21u), before = c;
      const std::vector<double> a = random_values(static_cast<std::size_t>(r * cols), 23u);
      k->subtract_transposed_product(a.data(), r, b.data(), r, cols, cols, r, c.data(), cols + 1);
      worst = 0.0;
      for (int i = 0; i <= cols; ++i) {
        for (int j = 0; j < cols; ++j) {
          double expected = before[static_cast<std::size_t>(i + j * (cols + 1))];
          if (i < cols) {
            for (int q = 0; q < r; ++q) expected -= a[static_cast<std::size_t>(q + i * r)] * b[static_cast<std::size_t>(q + j * r)];
          }
          worst = testing::nan_max(worst, std::abs(c[static_cast<std::size_t>(i + j * (cols + 1))] - expected) / r);
        }
      }
      EXPECT_LE(worst, kRelative) << "transposed product " << n;
    }
  }
}

TEST(DenseKernels, CholeskyNamesTheFirstColumnThatIsNotPositiveDefinite) {
  for (const DenseKernels* k : sets()) {
    SCOPED_TRACE(k->name);
    constexpr int n = 40;
    for (const int bad : {0, 17, 39}) {
      for (const double value : {-1.0, std::nan("")}) {
        std::vector<double> a(static_cast<std::size_t>(n * n), 0.0);
        for (int j = 0; j < n; ++j) a[static_cast<std::size_t>(j + j * n)] = 4.0;
        for (int j = 0; j + 1 < n; ++j) a[static_cast<std::size_t>(j + 1 + j * n)] = 1.0;
        a[static_cast<std::size_t>(bad + bad * n)] = value;
        EXPECT_EQ(k->cholesky(a.data(), n, n), bad) << bad << " " << value;
      }
    }
  }
}

}  // namespace
}  // namespace geoanchor::solver
