// InformationMatrix against a dense reference: random symmetric block updates, clear, swap,
// multiply, to_sparse, pair counting. Sizes are tiny so a dense comparison is exact.
#include "nav/core/filter/information_matrix.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <random>

namespace nav::core {
namespace {

Eigen::MatrixXd random_block(std::mt19937& rng, int d) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::MatrixXd m(d, d);
  for (int r = 0; r < d; ++r)
    for (int c = 0; c < d; ++c) m(r, c) = n(rng);
  return m;
}

void add_dense(Eigen::MatrixXd& D, int d, int i, int j, const Eigen::MatrixXd& m) {
  if (i == j) {
    D.block(i * d, i * d, d, d) += 0.5 * (m + m.transpose());
  } else {
    D.block(i * d, j * d, d, d) += m;
    D.block(j * d, i * d, d, d) += m.transpose();
  }
}

class InformationMatrixTest : public ::testing::TestWithParam<int> {};

TEST_P(InformationMatrixTest, RandomUpdatesMatchDense) {
  const int d = GetParam();
  const int n = 7;
  std::mt19937 rng(42);
  InformationMatrix L(d);
  for (int k = 0; k < n; ++k) EXPECT_EQ(L.add_block(), k);
  EXPECT_EQ(L.num_blocks(), n);
  EXPECT_EQ(L.dim(), n * d);
  Eigen::MatrixXd D = Eigen::MatrixXd::Zero(n * d, n * d);
  std::uniform_int_distribution<int> pick(0, n - 1);
  for (int t = 0; t < 40; ++t) {
    const int i = pick(rng), j = pick(rng);
    const Eigen::MatrixXd m = random_block(rng, d);
    L.add_to_block(i, j, m);
    add_dense(D, d, i, j, m);
  }
  EXPECT_LT((L.to_dense() - D).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((Eigen::MatrixXd(L.to_sparse()) - D).cwiseAbs().maxCoeff(), 1e-12);

  // Pairs and neighbours agree with the dense pattern.
  size_t pairs = 0;
  for (int i = 0; i < n; ++i) {
    std::vector<int> nb = L.neighbours(i);
    std::sort(nb.begin(), nb.end());
    std::vector<int> expected;
    for (int j = 0; j < n; ++j) {
      if (j != i && D.block(i * d, j * d, d, d).cwiseAbs().maxCoeff() > 0) expected.push_back(j);
      if (j > i && D.block(i * d, j * d, d, d).cwiseAbs().maxCoeff() > 0) ++pairs;
    }
    EXPECT_EQ(nb, expected) << "row " << i;
    EXPECT_EQ(L.num_neighbours(i), static_cast<int>(expected.size()));
    for (int j = 0; j < n; ++j) {
      EXPECT_EQ(L.block(i, j), D.block(i * d, j * d, d, d)) << i << "," << j;
    }
  }
  EXPECT_EQ(L.num_off_diagonal_pairs(), pairs);

  // Multiply with several right-hand sides.
  Eigen::MatrixXd X = Eigen::MatrixXd::Random(n * d, 3), Y(n * d, 3);
  L.multiply(X, Y);
  EXPECT_LT((Y - D * X).cwiseAbs().maxCoeff(), 1e-10);
}

TEST_P(InformationMatrixTest, ClearRowRemovesRowAndColumn) {
  const int d = GetParam();
  const int n = 5;
  std::mt19937 rng(7);
  InformationMatrix L(d);
  Eigen::MatrixXd D = Eigen::MatrixXd::Zero(n * d, n * d);
  for (int k = 0; k < n; ++k) L.add_block();
  for (int i = 0; i < n; ++i) {
    for (int j = i; j < n; ++j) {
      const Eigen::MatrixXd m = random_block(rng, d);
      L.add_to_block(i, j, m);
      add_dense(D, d, i, j, m);
    }
  }
  EXPECT_EQ(L.num_off_diagonal_pairs(), 10u);
  L.clear_row(2);
  D.middleRows(2 * d, d).setZero();
  D.middleCols(2 * d, d).setZero();
  EXPECT_EQ(L.to_dense(), D);
  EXPECT_EQ(L.num_off_diagonal_pairs(), 6u);
  EXPECT_TRUE(L.neighbours(2).empty());
  EXPECT_EQ(L.find_block(1, 2), nullptr);
}

TEST_P(InformationMatrixTest, SwapRowsIsSymmetricPermutation) {
  const int d = GetParam();
  const int n = 6;
  std::mt19937 rng(3);
  InformationMatrix L(d);
  Eigen::MatrixXd D = Eigen::MatrixXd::Zero(n * d, n * d);
  for (int k = 0; k < n; ++k) L.add_block();
  const int links[][2] = {{0, 0}, {0, 1}, {1, 1}, {1, 2}, {0, 4}, {4, 5}, {2, 5}, {3, 3}, {1, 4}};
  for (const auto& l : links) {
    const Eigen::MatrixXd m = random_block(rng, d);
    L.add_to_block(l[0], l[1], m);
    add_dense(D, d, l[0], l[1], m);
  }
  const size_t pairs = L.num_off_diagonal_pairs();
  L.swap_rows(1, 4);
  Eigen::VectorXi perm(n * d);  // new index -> old index
  for (int b = 0; b < n; ++b) {
    const int old = b == 1 ? 4 : (b == 4 ? 1 : b);
    for (int r = 0; r < d; ++r) perm[b * d + r] = old * d + r;
  }
  Eigen::MatrixXd P(n * d, n * d);
  for (int r = 0; r < n * d; ++r)
    for (int c = 0; c < n * d; ++c) P(r, c) = D(perm[r], perm[c]);
  EXPECT_EQ(L.to_dense(), P);
  EXPECT_EQ(L.num_off_diagonal_pairs(), pairs);
  // Swap with an empty row moves the row out (how the filter keeps a delayed state).
  const int fresh = L.add_block();
  L.swap_rows(0, fresh);
  EXPECT_TRUE(L.neighbours(0).empty());
  EXPECT_EQ(L.diagonal_block(0).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(L.diagonal_block(fresh), P.block(0, 0, d, d));
}

TEST_P(InformationMatrixTest, EmptyMatrixAndZeroBlocks) {
  const int d = GetParam();
  InformationMatrix L(d);
  EXPECT_EQ(L.num_blocks(), 0);
  EXPECT_EQ(L.to_sparse().rows(), 0);
  L.add_block();
  L.add_block();
  EXPECT_EQ(L.block(0, 1), Eigen::MatrixXd::Zero(d, d));
  EXPECT_EQ(L.find_block(0, 1), nullptr);
  EXPECT_EQ(L.num_off_diagonal_pairs(), 0u);
}

INSTANTIATE_TEST_SUITE_P(BlockSizes, InformationMatrixTest, ::testing::Values(6, 12));

TEST(InformationMatrix, RejectsBadBlockSize) {
  EXPECT_THROW(InformationMatrix(0), std::invalid_argument);
  EXPECT_THROW(InformationMatrix(13), std::invalid_argument);
}

}  // namespace
}  // namespace nav::core
