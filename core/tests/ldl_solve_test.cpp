// Row-major backward passes with a simplicial LDLᵀ factor (src/recovery/ldl_solve.h): on a unit
// lower L of d x d blocks, stored as CHOLMOD stores a simplicial factor, the block-wise pass
// (supernodes where a block's columns share their rows below it, column by column elsewhere)
// equals a dense solve Lᵀ X = Y, for every width the recovery uses, and takes exactly the
// blocks of supernode pattern as supernodes.
#include "../src/recovery/ldl_solve.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <random>
#include <vector>

namespace nav::core::detail {
namespace {

/// A unit lower L (n = blocks·d) with dense diagonal blocks and, below each block, rows shared
/// by all of its columns, in CHOLMOD's simplicial storage (column j: D_j first, then its rows
/// in increasing order; columns placed with gaps, as after modifications).
struct BlockFactor {
  int n = 0;
  std::vector<int> p, nz, row;
  std::vector<double> value;
  Eigen::MatrixXd dense;  // the same unit lower L
  SimplicialLdl ldl() const { return {n, p.data(), nz.data(), row.data(), value.data()}; }
};

/// Block `odd_block`'s column `odd_column` gets one off-block row fewer than its block's other
/// columns (a pattern of its own); any other block is a supernode.
BlockFactor make_factor(int blocks, int d, int odd_block, int odd_column, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  std::bernoulli_distribution coupled(0.3);
  BlockFactor f;
  f.n = blocks * d;
  f.dense = Eigen::MatrixXd::Identity(f.n, f.n);
  for (int b = 0; b < blocks; ++b) {
    std::vector<int> below;
    for (int other = b + 1; other < blocks; ++other) {
      if (!coupled(rng)) continue;
      for (int i = 0; i < d; ++i) below.push_back(other * d + i);
    }
    for (int c = 0; c < d; ++c) {
      const int j = b * d + c;
      f.p.push_back(static_cast<int>(f.row.size()));
      f.row.push_back(j);
      f.value.push_back(1.0 + std::abs(normal(rng)));  // D_j: not read by the backward pass
      std::vector<int> rows;
      for (int i = j + 1; i < (b + 1) * d; ++i) rows.push_back(i);
      rows.insert(rows.end(), below.begin(), below.end());
      if (b == odd_block && c == odd_column && !below.empty()) rows.pop_back();
      for (int i : rows) {
        f.row.push_back(i);
        f.value.push_back(0.3 * normal(rng));
        f.dense(i, j) = f.value.back();
      }
      f.nz.push_back(1 + static_cast<int>(rows.size()));
      for (int gap = 0; gap < 3; ++gap) {  // room CHOLMOD leaves for growth, never read
        f.row.push_back(-1);
        f.value.push_back(1e300);
      }
    }
  }
  return f;
}

/// Y (n x columns) stored by rows of `width` doubles, the added columns zero.
std::vector<double> by_rows(const Eigen::MatrixXd& Y, int width) {
  std::vector<double> rows(static_cast<size_t>(Y.rows()) * static_cast<size_t>(width), 0.0);
  for (Eigen::Index i = 0; i < Y.rows(); ++i)
    for (Eigen::Index c = 0; c < Y.cols(); ++c) rows[static_cast<size_t>(i * width + c)] = Y(i, c);
  return rows;
}

double max_error(const std::vector<double>& rows, const Eigen::MatrixXd& expected, int width) {
  double worst = 0.0;
  for (Eigen::Index i = 0; i < expected.rows(); ++i)
    for (Eigen::Index c = 0; c < expected.cols(); ++c)
      worst = std::max(worst, std::abs(rows[static_cast<size_t>(i * width + c)] - expected(i, c)));
  return worst;
}

TEST(LdlSolve, BlockwiseBackwardPassEqualsADenseSolveAndTakesTheSupernodeBlocks) {
  for (const int d : {6, 12}) {
    for (const int columns : {4, 12, 13, 16, 20}) {
      const int blocks = 23, odd_block = 7;
      const BlockFactor f = make_factor(blocks, d, odd_block, d / 2, 17U + d + columns);
      const Eigen::MatrixXd Y = Eigen::MatrixXd::Random(f.n, columns);
      const Eigen::MatrixXd expected =
          f.dense.transpose().triangularView<Eigen::UnitUpper>().solve(Y);
      const int width = ldl_width(columns);
      std::vector<double> blockwise = by_rows(Y, width), by_column = by_rows(Y, width);
      const int supernodes = ldl_backward_blocks(f.ldl(), d, blockwise.data(), width);
      ldl_backward(f.ldl(), by_column.data(), width);
      SCOPED_TRACE(testing::Message() << "d " << d << ", " << columns << " columns");
      EXPECT_LT(max_error(blockwise, expected, width), 1e-9);
      EXPECT_LT(max_error(by_column, expected, width), 1e-9);
      // Every block but the odd one (the last block has no rows below it: a supernode too).
      EXPECT_EQ(supernodes, blocks - 1);
    }
  }
}

TEST(LdlSolve, BlockSizesThatDoNotDivideTheFactorFallBackToColumns) {
  const BlockFactor f = make_factor(5, 6, -1, 0, 3U);
  const Eigen::MatrixXd Y = Eigen::MatrixXd::Random(f.n, 8);
  const Eigen::MatrixXd expected = f.dense.transpose().triangularView<Eigen::UnitUpper>().solve(Y);
  std::vector<double> rows = by_rows(Y, 8);
  EXPECT_EQ(ldl_backward_blocks(f.ldl(), 7, rows.data(), 8), 0);  // 30 rows are not 7-blocks
  EXPECT_LT(max_error(rows, expected, 8), 1e-9);
  rows = by_rows(Y, 8);
  EXPECT_EQ(ldl_backward_blocks(f.ldl(), 6, rows.data(), 8), 5);
  EXPECT_LT(max_error(rows, expected, 8), 1e-9);
}

}  // namespace
}  // namespace nav::core::detail
