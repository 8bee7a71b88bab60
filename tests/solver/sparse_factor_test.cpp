// The sparse factor the network adjustment uses (solver/src/sparse/,
// private to solver), against Eigen's dense Cholesky of the same matrix:
// solves, the selected inverse on the pattern (Takahashi on CHOLMOD's
// supernodal factor), and refactorizations that reuse the analysis (same
// pattern, new values) or must not (a new pattern). The matrices are random
// symmetric positive definite ones with a network's structure: 3×3 blocks
// per station, couplings between neighbours.

#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include <cmath>
#include <optional>
#include <random>
#include <tuple>
#include <stdexcept>
#include <utility>
#include <vector>

#include "sparse/sparse_factor.hpp"
#include "test_support.hpp"

namespace geoanchor::solver {
namespace {

constexpr double kRelative = 1e-9;  // of the largest entry of the dense inverse

struct Built {
  std::vector<SymmetricEntry> entries;
  Eigen::MatrixXd dense;
};

// `stations` stations (3 unknowns each), each pair in `joins` joined by a
// random positive semidefinite 6×6 block (drawn in the joins' order), plus
// a small diagonal: positive definite.
Built joined_matrix(int stations, const std::vector<std::pair<int, int>>& joins, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  const int n = 3 * stations;
  Built b;
  b.dense = Eigen::MatrixXd::Zero(n, n);
  for (const auto& [s, t] : joins) {
    Eigen::MatrixXd a(3, 6);
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 6; ++j) a(i, j) = unit(rng);
    }
    const Eigen::MatrixXd block = a.transpose() * a;
    const int at[2] = {3 * s, 3 * t};
    for (int p = 0; p < 2; ++p) {
      for (int q = 0; q < 2; ++q) b.dense.block(at[p], at[q], 3, 3) += block.block(3 * p, 3 * q, 3, 3);
    }
  }
  b.dense += 0.1 * Eigen::MatrixXd::Identity(n, n);
  for (int c = 0; c < n; ++c) {
    for (int r = 0; r <= c; ++r) {
      if (b.dense(r, c) != 0.0) b.entries.push_back({r, c, b.dense(r, c)});
    }
  }
  return b;
}

// A network of `stations` on a line, each joined to the next `reach`.
Built network_matrix(int stations, int reach, unsigned seed) {
  std::vector<std::pair<int, int>> joins;
  for (int s = 0; s < stations; ++s) {
    for (int t = s + 1; t <= s + reach && t < stations; ++t) joins.emplace_back(s, t);
  }
  return joined_matrix(stations, joins, seed);
}

// A network of width × height stations on a grid, each joined to its right,
// lower and lower-right neighbours: its nested-dissection ordering has
// separators of some hundred unknowns, supernodes wide enough to be cut in
// slices and panels (supernodal_cholesky.cpp).
// With `hubs`, that many more stations joined to every station: they are
// ordered last, the rows below every supernode, and a supernode of their own
// wider than a panel.
Built grid_matrix(int width, int height, unsigned seed, int hubs = 0) {
  std::vector<std::pair<int, int>> joins;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const int s = y * width + x;
      if (x + 1 < width) joins.emplace_back(s, s + 1);
      if (y + 1 < height) joins.emplace_back(s, s + width);
      if (x + 1 < width && y + 1 < height) joins.emplace_back(s, s + width + 1);
    }
  }
  for (int h = width * height; h < width * height + hubs; ++h) {
    for (int s = 0; s < h; ++s) joins.emplace_back(s, h);
  }
  return joined_matrix(width * height + hubs, joins, seed);
}

// The worst difference between the factor's inverse on the matrix's pattern
// and the dense inverse, relative to the dense inverse's largest entry; and
// the same for a solve.
double worst_difference(const NormalFactor& f, const Built& b) {
  const Eigen::MatrixXd inverse = b.dense.llt().solve(Eigen::MatrixXd::Identity(b.dense.rows(), b.dense.cols()));
  const double scale = testing::max_abs_component(inverse);
  double worst = 0.0;
  for (const auto& e : b.entries) {
    worst = testing::nan_max(worst, std::abs(f.inverse(e.row, e.col) - inverse(e.row, e.col)) / scale);
    worst = testing::nan_max(worst, std::abs(f.inverse(e.col, e.row) - inverse(e.row, e.col)) / scale);
  }
  const Eigen::VectorXd rhs = Eigen::VectorXd::LinSpaced(b.dense.rows(), -1.0, 2.0);
  const Eigen::VectorXd x = b.dense.llt().solve(rhs);
  worst = testing::nan_max(worst, testing::max_abs_component(f.solve(rhs) - x) / testing::max_abs_component(x));
  return worst;
}

TEST(NormalFactor, SelectedInverseAndSolvesAgreeWithADenseInverse) {
  for (const auto& [stations, reach] : {std::pair{1, 1}, std::pair{2, 1}, std::pair{40, 3}, std::pair{200, 5}}) {
    SCOPED_TRACE(stations);
    const Built b = network_matrix(stations, reach, 7u + static_cast<unsigned>(stations));
    auto f = NormalFactor::factor(b.dense.rows(), b.entries, NormalFactor::Mode::sparse, nullptr);
    ASSERT_TRUE(f);
    f->select_inverse();
    EXPECT_LE(worst_difference(*f, b), kRelative);
  }
}

// Issue 17 point 3: subtrees of the elimination tree on threads give the
// same bits as one thread, and agree with the dense inverse.
TEST(NormalFactor, SelectedInversionOnThreadsGivesTheSameBits) {
  const Built b = network_matrix(600, 5, 11u);
  auto one = NormalFactor::factor(b.dense.rows(), b.entries, NormalFactor::Mode::sparse, nullptr);
  auto three = NormalFactor::factor(b.dense.rows(), b.entries, NormalFactor::Mode::sparse, nullptr);
  ASSERT_TRUE(one && three);
  one->select_inverse(1);
  three->select_inverse(3);
  for (const auto& e : b.entries) {
    ASSERT_EQ(one->inverse(e.row, e.col), three->inverse(e.row, e.col)) << e.row << ", " << e.col;
  }
  EXPECT_LE(worst_difference(*three, b), kRelative);
}

// Issue 17 point 3: the numeric factorization on threads (subtrees, then
// the separators' supernodes in slices) gives the same bits as on one, and
// the factor agrees with Eigen's dense Cholesky through its solves and
// selected inverse.
TEST(NormalFactor, Issue17_TheFactorizationOnThreadsGivesTheSameBits) {
  for (const auto& [width, height, hubs] : {std::tuple{24, 20, 0}, std::tuple{20, 16, 90}}) {
    SCOPED_TRACE(::testing::Message() << width << " × " << height << " grid, " << hubs << " hubs");
    const Built b = grid_matrix(width, height, 17u, hubs);
    const Eigen::Index n = b.dense.rows();
    auto one = NormalFactor::factor(n, b.entries, NormalFactor::Mode::sparse, nullptr, std::nullopt, 0, 1);
    auto two = NormalFactor::factor(n, b.entries, NormalFactor::Mode::sparse, nullptr, std::nullopt, 0, 2);
    auto three = NormalFactor::factor(n, b.entries, NormalFactor::Mode::sparse, nullptr, std::nullopt, 0, 3);
    ASSERT_TRUE(one && two && three);
    const Eigen::VectorXd rhs = Eigen::VectorXd::LinSpaced(n, -1.0, 2.0);
    const Eigen::VectorXd x1 = one->solve(rhs), x2 = two->solve(rhs), x3 = three->solve(rhs);
    for (Eigen::Index k = 0; k < n; ++k) {
      ASSERT_EQ(x1(k), x2(k)) << k;
      ASSERT_EQ(x1(k), x3(k)) << k;
    }
    one->select_inverse(1);
    two->select_inverse(2);
    EXPECT_LE(worst_difference(*one, b), kRelative);
    for (const auto& e : b.entries) ASSERT_EQ(one->inverse(e.row, e.col), two->inverse(e.row, e.col)) << e.row << ", " << e.col;
    // Refactored in place (the same pattern, other values), on threads.
    const Built other = grid_matrix(width, height, 18u, hubs);
    auto again = NormalFactor::factor(n, other.entries, NormalFactor::Mode::sparse, nullptr, std::move(*two), 0, 2);
    ASSERT_TRUE(again);
    const Eigen::VectorXd expected = other.dense.llt().solve(rhs);
    EXPECT_LE(testing::max_abs_component(again->solve(rhs) - expected) / testing::max_abs_component(expected), kRelative);
  }
}

// The block a measurement's statistics read: every pair of its unknowns,
// in any order and with repeats, as inverse() gives each entry; false for
// unknowns that share no measurement (off the pattern). Dense: the inverse.
TEST(NormalFactor, Issue17_AnInverseBlockIsItsEntries) {
  const Built b = grid_matrix(20, 16, 29u);
  const auto n = static_cast<std::int64_t>(b.dense.rows());
  auto f = NormalFactor::factor(n, b.entries, NormalFactor::Mode::sparse, nullptr);
  auto dense = NormalFactor::factor(n, b.entries, NormalFactor::Mode::dense, nullptr);
  ASSERT_TRUE(f && dense);
  f->select_inverse();
  dense->select_inverse();
  const auto station = [](std::int64_t s) { return std::vector<std::int64_t>{3 * s, 3 * s + 1, 3 * s + 2}; };
  const auto join = [](std::vector<std::int64_t> a, const std::vector<std::int64_t>& c) {
    a.insert(a.end(), c.begin(), c.end());
    return a;
  };
  const std::vector<std::vector<std::int64_t>> sets{
      station(0), join(station(5), station(6)), join(station(47), station(26)), join(station(100), station(120)),
      {3 * 50 + 2, 3 * 71, 3 * 50 + 2, 3 * 71 + 1, 3 * 51},  // out of order, one repeated, three joined stations
      join(station(221), join(station(200), station(201)))};
  for (const auto& u : sets) {
    SCOPED_TRACE(u.size());
    std::vector<double> q(u.size() * u.size(), std::nan("")), dq = q;
    ASSERT_TRUE(f->inverse_block(u.data(), u.size(), q.data()));
    ASSERT_TRUE(dense->inverse_block(u.data(), u.size(), dq.data()));
    const Eigen::MatrixXd inverse = b.dense.llt().solve(Eigen::MatrixXd::Identity(n, n));
    for (std::size_t a = 0; a < u.size(); ++a) {
      for (std::size_t c = 0; c < u.size(); ++c) {
        EXPECT_EQ(q[a + c * u.size()], f->inverse(u[a], u[c])) << a << ", " << c;
        EXPECT_NEAR(dq[a + c * u.size()], inverse(u[a], u[c]), kRelative * testing::max_abs_component(inverse));
      }
    }
  }
  // Stations 0 and 319 (opposite corners) share no measurement.
  const auto far = join(station(0), station(319));
  std::vector<double> q(far.size() * far.size());
  EXPECT_FALSE(f->inverse_block(far.data(), far.size(), q.data()));
}

// A matrix positive definite but for one unknown u (its diagonal lowered
// below its Schur complement): every pivot before u's, in any order, is a
// leading minor without u, so the factorization fails at u and nowhere
// else — the column named, on one thread or on two, wherever u lies in
// the elimination tree. A NaN on the diagonal fails where it is.
TEST(NormalFactor, Issue17_TheFailedColumnIsTheUnknownThatBreaksIt) {
  const Built b = grid_matrix(30, 24, 23u);
  const auto n = static_cast<std::int64_t>(b.dense.rows());
  for (const std::int64_t u : {std::int64_t{0}, std::int64_t{7}, n / 2 + 1, std::int64_t{3 * 15 + 2}, n - 1}) {
    for (const bool nan : {false, true}) {
      SCOPED_TRACE(::testing::Message() << "unknown " << u << (nan ? ", NaN" : ""));
      Built bad = b;
      for (auto& e : bad.entries) {
        if (e.row == u && e.col == u) e.value = nan ? std::nan("") : -1.0;
      }
      for (const int jobs : {1, 2}) {
        std::int64_t failed = -1;
        EXPECT_FALSE(NormalFactor::factor(n, bad.entries, NormalFactor::Mode::sparse, &failed, std::nullopt, 0, jobs));
        EXPECT_EQ(failed, u) << jobs << " threads";
      }
    }
  }
}

// Two such unknowns far apart (opposite corners of the grid: different
// subtrees of the elimination tree, one on each thread): the factorization
// fails at the one eliminated first — the order read from a factor of the
// same pattern — on one thread, two or three.
TEST(NormalFactor, Issue17_OfTwoUnknownsThatBreakItTheFirstEliminatedIsNamed) {
  const Built b = grid_matrix(30, 24, 31u);
  const auto n = static_cast<std::int64_t>(b.dense.rows());
  auto good = NormalFactor::factor(n, b.entries, NormalFactor::Mode::sparse, nullptr);
  ASSERT_TRUE(good);
  for (const auto& [u1, u2] : {std::pair<std::int64_t, std::int64_t>{1, n - 2}, std::pair<std::int64_t, std::int64_t>{3 * 29, 3 * (30 * 23) + 2},
                               std::pair<std::int64_t, std::int64_t>{3 * 375, 4}}) {
    const std::int64_t expected = good->elimination_step(u1) < good->elimination_step(u2) ? u1 : u2;
    Built bad = b;
    for (auto& e : bad.entries) {
      if ((e.row == u1 && e.col == u1) || (e.row == u2 && e.col == u2)) e.value = -1.0;
    }
    for (const int jobs : {1, 2, 3}) {
      std::int64_t failed = -1;
      EXPECT_FALSE(NormalFactor::factor(n, bad.entries, NormalFactor::Mode::sparse, &failed, std::nullopt, 0, jobs));
      EXPECT_EQ(failed, expected) << u1 << " and " << u2 << ", " << jobs << " threads";
    }
  }
}

// Issue 17 point 5: rows taken out of a factored matrix (data snooping's
// removed measurements) by Sherman–Morrison–Woodbury, against the dense
// inverse of the matrix without them: the selected inverse on the whole
// pattern and the solves; twice in a row (downdates compose); on threads
// with the same bits; and refused, with nothing changed, where the rows
// were all that determined an unknown.
TEST(NormalFactor, Issue17_ADowndateIsTheInverseOfTheMatrixWithoutTheRows) {
  const Built b = network_matrix(300, 4, 21u);
  const Eigen::Index n = b.dense.rows();
  std::mt19937 rng(5u);
  std::normal_distribution<double> unit(0.0, 1.0);
  // Rows of a measurement between two stations: whitened, 3 rows over their
  // 6 unknowns, small enough to leave the matrix positive definite.
  const auto rows_between = [&](int s, int t) {
    Eigen::MatrixXd rows = Eigen::MatrixXd::Zero(n, 3);
    for (int c = 0; c < 3; ++c) {
      for (int k = 0; k < 3; ++k) {
        rows(3 * s + k, c) = 0.3 * unit(rng);
        rows(3 * t + k, c) = 0.3 * unit(rng);
      }
    }
    return rows;
  };
  // The rows must be in the matrix to be taken out: add them, then factor.
  Eigen::MatrixXd first(n, 6), second(n, 3);
  first << rows_between(10, 12), rows_between(150, 151);
  second << rows_between(290, 293);
  Built with = b;
  with.dense += first * first.transpose() + second * second.transpose();
  with.entries.clear();
  for (Eigen::Index c = 0; c < n; ++c) {
    for (Eigen::Index r = 0; r <= c; ++r) {
      if (with.dense(r, c) != 0.0 || b.dense(r, c) != 0.0) with.entries.push_back({r, c, with.dense(r, c)});
    }
  }
  auto one = NormalFactor::factor(n, with.entries, NormalFactor::Mode::sparse, nullptr);
  auto two = NormalFactor::factor(n, with.entries, NormalFactor::Mode::sparse, nullptr);
  ASSERT_TRUE(one && two);
  one->select_inverse(1);
  two->select_inverse(2);
  EXPECT_LE(worst_difference(*one, with), kRelative);
  ASSERT_TRUE(one->downdate(first, 1));
  ASSERT_TRUE(two->downdate(first, 2));
  Built without_first = with;
  without_first.dense -= first * first.transpose();
  EXPECT_LE(worst_difference(*one, without_first), kRelative);
  ASSERT_TRUE(one->downdate(second, 1));
  ASSERT_TRUE(two->downdate(second, 2));
  Built without_both = without_first;
  without_both.dense -= second * second.transpose();
  EXPECT_LE(worst_difference(*one, without_both), kRelative);
  EXPECT_EQ(one->downdated_rows(), 9);
  for (const auto& e : with.entries) ASSERT_EQ(one->inverse(e.row, e.col), two->inverse(e.row, e.col)) << e.row << ", " << e.col;
  // A station held only by the rows: its unknowns' weight is all theirs.
  Eigen::MatrixXd all = Eigen::MatrixXd::Zero(n, 3);
  const Eigen::LLT<Eigen::MatrixXd> block(without_both.dense.block(3 * 100, 3 * 100, 3, 3));
  ASSERT_EQ(block.info(), Eigen::Success);
  all.block(3 * 100, 0, 3, 3) = block.matrixL();
  EXPECT_FALSE(one->downdate(all, 1));
  EXPECT_LE(worst_difference(*one, without_both), kRelative);  // nothing changed
  EXPECT_EQ(one->downdated_rows(), 9);
  // A dense factor (the tests' reference) is never downdated.
  auto dense = NormalFactor::factor(n, with.entries, NormalFactor::Mode::dense, nullptr);
  ASSERT_TRUE(dense);
  dense->select_inverse();
  EXPECT_FALSE(dense->downdate(first));
  // A refactorization starts from no downdate.
  auto again = NormalFactor::factor(n, with.entries, NormalFactor::Mode::sparse, nullptr, std::move(*one));
  ASSERT_TRUE(again);
  again->select_inverse();
  EXPECT_EQ(again->downdated_rows(), 0);
  EXPECT_LE(worst_difference(*again, with), kRelative);
}

// Issue 39 (data snooping's cofactors): the blocks A_i N⁻¹ A_jᵀ from
// forward solves along the elimination tree equal those of the dense
// inverse, for row blocks near and far apart on a grid (separators of some
// hundred unknowns), before and after a downdate, on one thread and two
// (the same bits), and in dense mode.
TEST(NormalFactor, Issue39_BlocksOfTheInverseBetweenRowBlocksAreTheDenseInverses) {
  const Built b = grid_matrix(20, 16, 11u, 2);
  const Eigen::Index n = b.dense.rows();
  std::mt19937 rng(3u);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::vector<std::vector<std::int64_t>> unknowns;
  std::vector<Eigen::MatrixXd> rows;
  for (const auto& [s, t, k] : std::vector<std::tuple<int, int, int>>{{0, 1, 3}, {5, 300, 3}, {319, 318, 1}, {150, 151, 3}, {320, 10, 2}, {77, 77, 3}}) {
    std::vector<std::int64_t> u;
    for (int c = 0; c < 3; ++c) u.push_back(3 * s + c);
    if (t != s) {
      for (int c = 0; c < 3; ++c) u.push_back(3 * t + c);
    }
    Eigen::MatrixXd a(k, static_cast<Eigen::Index>(u.size()));
    for (Eigen::Index i = 0; i < a.size(); ++i) a.data()[i] = unit(rng);
    unknowns.push_back(u);
    rows.push_back(a);
  }
  const auto dense_blocks = [&](const Eigen::MatrixXd& matrix) {
    const Eigen::MatrixXd inverse = matrix.llt().solve(Eigen::MatrixXd::Identity(n, n));
    Eigen::Index total = 0;
    for (const auto& a : rows) total += a.rows();
    Eigen::MatrixXd stacked = Eigen::MatrixXd::Zero(total, n);
    Eigen::Index at = 0;
    for (std::size_t c = 0; c < rows.size(); ++c) {
      for (std::size_t j = 0; j < unknowns[c].size(); ++j) stacked.block(at, unknowns[c][j], rows[c].rows(), 1) = rows[c].col(static_cast<Eigen::Index>(j));
      at += rows[c].rows();
    }
    return Eigen::MatrixXd(stacked * inverse * stacked.transpose());
  };
  const auto worst = [](const Eigen::MatrixXd& ours, const Eigen::MatrixXd& reference) {
    return testing::max_abs_component(Eigen::MatrixXd(ours - reference)) / testing::max_abs_component(reference);
  };
  auto one = NormalFactor::factor(n, b.entries, NormalFactor::Mode::sparse, nullptr);
  auto two = NormalFactor::factor(n, b.entries, NormalFactor::Mode::sparse, nullptr);
  ASSERT_TRUE(one && two);
  const Eigen::MatrixXd reference = dense_blocks(b.dense);
  const Eigen::MatrixXd ours = one->inverse_between(unknowns, rows, 1);
  EXPECT_LE(worst(ours, reference), kRelative);
  const Eigen::MatrixXd on_two = two->inverse_between(unknowns, rows, 2);
  EXPECT_EQ(testing::max_abs_component(Eigen::MatrixXd(on_two - ours)), 0.0);
  // After a downdate (rows of a measurement between stations 200 and 201).
  one->select_inverse();
  Eigen::MatrixXd gone = Eigen::MatrixXd::Zero(n, 3);
  for (Eigen::Index c = 0; c < 3; ++c) {
    for (Eigen::Index k = 0; k < 3; ++k) {
      gone(3 * 200 + k, c) = 0.2 * unit(rng);
      gone(3 * 201 + k, c) = 0.2 * unit(rng);
    }
  }
  ASSERT_TRUE(one->downdate(gone));
  EXPECT_LE(worst(one->inverse_between(unknowns, rows, 1), dense_blocks(b.dense - gone * gone.transpose())), kRelative);
  auto dense = NormalFactor::factor(n, b.entries, NormalFactor::Mode::dense, nullptr);
  ASSERT_TRUE(dense);
  EXPECT_LE(worst(dense->inverse_between(unknowns, rows), reference), kRelative);
}

TEST(NormalFactor, ARefactorizationReusesTheAnalysisOnlyForTheSamePattern) {
  const Built first = network_matrix(60, 3, 1u);
  auto f = NormalFactor::factor(first.dense.rows(), first.entries, NormalFactor::Mode::sparse, nullptr);
  ASSERT_TRUE(f);
  // The same pattern, other values: the new matrix's inverse, not the old one's.
  const Built same = network_matrix(60, 3, 2u);
  ASSERT_EQ(same.entries.size(), first.entries.size());
  auto g = NormalFactor::factor(same.dense.rows(), same.entries, NormalFactor::Mode::sparse, nullptr, std::move(f));
  ASSERT_TRUE(g);
  g->select_inverse();
  EXPECT_LE(worst_difference(*g, same), kRelative);
  // A wider pattern (each station joined to 5 neighbours): analysed afresh.
  const Built wider = network_matrix(60, 5, 3u);
  auto h = NormalFactor::factor(wider.dense.rows(), wider.entries, NormalFactor::Mode::sparse, nullptr, std::move(g));
  ASSERT_TRUE(h);
  h->select_inverse();
  EXPECT_LE(worst_difference(*h, wider), kRelative);
  // A matrix that is not positive definite is refused, naming a column.
  Built bad = network_matrix(60, 3, 4u);
  for (auto& e : bad.entries) {
    if (e.row == 10 && e.col == 10) e.value = -1.0;
  }
  std::int64_t failed = -1;
  EXPECT_FALSE(NormalFactor::factor(bad.dense.rows(), bad.entries, NormalFactor::Mode::sparse, &failed, std::move(h)));
  EXPECT_GE(failed, 0);
  // A factor already handed on is no previous one: analysed afresh.
  auto again = NormalFactor::factor(first.dense.rows(), first.entries, NormalFactor::Mode::sparse, nullptr, std::move(h));
  ASSERT_TRUE(again);
  EXPECT_THROW((void)again->inverse(0, 0), std::logic_error);  // before select_inverse()
  again->select_inverse();
  EXPECT_LE(worst_difference(*again, first), kRelative);
}

}  // namespace
}  // namespace geoanchor::solver
