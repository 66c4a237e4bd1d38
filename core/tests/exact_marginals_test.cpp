// Exact marginals by supernodal selected inversion against a dense inverse
// (recovery/exact_marginals.h).

#include "nav/core/recovery/exact_marginals.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "nav/core/posegraph/g2o.h"
#include "nav/testing/data.h"
#include "nav/testing/numeric_jacobian.h"

namespace nav::core {
namespace {

using nav::testing::max_abs_diff;

/// Random block-sparse SPD matrix: a chain plus `extra` random links between blocks, each
/// link a random d x d coupling; diagonal dominance is added per block.
Eigen::SparseMatrix<double> random_block_spd(int num_blocks, int d, int extra, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  std::uniform_int_distribution<int> pick(0, num_blocks - 1);
  std::set<std::pair<int, int>> links;
  for (int b = 1; b < num_blocks; ++b) links.insert({b - 1, b});
  for (int k = 0; k < extra; ++k) {
    const int a = pick(rng), b = pick(rng);
    if (a != b) links.insert({std::min(a, b), std::max(a, b)});
  }
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(num_blocks * d, num_blocks * d);
  for (const auto& [a, b] : links) {
    // A "measurement" between a and b: H = [A -B], adds H^T H (PSD, couples a and b).
    Eigen::MatrixXd H(d, 2 * d);
    for (int i = 0; i < H.size(); ++i) H.data()[i] = normal(rng);
    const Eigen::MatrixXd M = H.transpose() * H;
    dense.block(a * d, a * d, d, d) += M.topLeftCorner(d, d);
    dense.block(b * d, b * d, d, d) += M.bottomRightCorner(d, d);
    dense.block(a * d, b * d, d, d) += M.topRightCorner(d, d);
    dense.block(b * d, a * d, d, d) += M.bottomLeftCorner(d, d);
  }
  dense.diagonal().array() += 0.5;  // prior on every state: SPD
  return dense.sparseView();
}

Eigen::MatrixXd dense_inverse(const Eigen::SparseMatrix<double>& A) {
  const Eigen::MatrixXd dense(A);
  return dense.llt().solve(Eigen::MatrixXd::Identity(dense.rows(), dense.cols()));
}

/// Checks every diagonal block and every in-pattern entry of Lambda's pattern.
void expect_matches_dense(const Eigen::SparseMatrix<double>& A, int d, MarginalsOrdering ordering,
                          double rel_tol, MarginalsKernel kernel = MarginalsKernel::kAuto) {
  const ExactMarginals em = ExactMarginals::compute(A, d, ordering, kernel);
  const Eigen::MatrixXd S = dense_inverse(A);
  const double scale = S.cwiseAbs().maxCoeff();
  ASSERT_EQ(em.num_blocks(), A.rows() / d);
  for (int b = 0; b < em.num_blocks(); ++b) {
    const Eigen::MatrixXd expected = S.block(b * d, b * d, d, d);
    EXPECT_LE(max_abs_diff(em.marginal(b), expected), rel_tol * scale) << "block " << b;
  }
  // Every nonzero of Lambda is in the pattern of L, so entry() must return it.
  for (int j = 0; j < A.outerSize(); ++j) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, j); it; ++it) {
      EXPECT_NEAR(em.entry(it.row(), j), S(it.row(), j), rel_tol * scale)
          << "(" << it.row() << ", " << j << ")";
    }
  }
}

TEST(ExactMarginals, TwoByTwoByHand) {
  // Lambda = [[2 1]; [1 2]] -> Sigma = 1/3 [[2 -1]; [-1 2]].
  Eigen::SparseMatrix<double> A(2, 2);
  A.insert(0, 0) = 2.0;
  A.insert(0, 1) = 1.0;
  A.insert(1, 0) = 1.0;
  A.insert(1, 1) = 2.0;
  const ExactMarginals em = ExactMarginals::compute(A, 1);
  EXPECT_NEAR(em.marginal(0)(0, 0), 2.0 / 3.0, 1e-15);
  EXPECT_NEAR(em.marginal(1)(0, 0), 2.0 / 3.0, 1e-15);
  const Eigen::MatrixXd J = em.joint(0, 1);
  EXPECT_NEAR(J(0, 1), -1.0 / 3.0, 1e-15);
  EXPECT_NEAR(J(1, 0), -1.0 / 3.0, 1e-15);
}

TEST(ExactMarginals, RandomSparseMatchesDenseInverse) {
  struct Case {
    int blocks, d, extra;
  };
  for (const Case c : {Case{1, 6, 0}, Case{10, 1, 5}, Case{40, 3, 30}, Case{60, 6, 40},
                       Case{30, 12, 25}, Case{80, 2, 200}}) {
    SCOPED_TRACE(::testing::Message()
                 << c.blocks << " blocks of " << c.d << ", " << c.extra << " extra links");
    const auto A = random_block_spd(c.blocks, c.d, c.extra, 17u + c.blocks);
    expect_matches_dense(A, c.d, MarginalsOrdering::kBlockAmd, 1e-10);
    expect_matches_dense(A, c.d, MarginalsOrdering::kCholmodAuto, 1e-10);
    expect_matches_dense(A, c.d, MarginalsOrdering::kBlockMetis, 1e-10);
    expect_matches_dense(A, c.d, MarginalsOrdering::kBlockAmd, 1e-10, MarginalsKernel::kBaseline);
  }
}

TEST(ExactMarginals, BlockColumnIsTheBlocksColumnsOfTheDenseInverse) {
  const auto A = random_block_spd(30, 12, 25, 5u);
  const Eigen::MatrixXd inverse = Eigen::MatrixXd(A).inverse();
  const ExactMarginals em = ExactMarginals::compute(A, 12);
  for (const int b : {0, 7, 29}) {
    const Eigen::MatrixXd column = em.block_column(b);
    ASSERT_EQ(column.rows(), A.rows());
    ASSERT_EQ(column.cols(), 12);
    EXPECT_LT((column - inverse.middleCols(12 * b, 12)).norm(), 1e-10 * inverse.norm())
        << "block " << b;
  }
  EXPECT_THROW(em.block_column(30), std::out_of_range);
}

TEST(ExactMarginals, SolveMatchesDenseSolveForEveryKernelAndOrdering) {
  // The supernodal triangular solves (and the forward half's quadratic form) against a dense
  // LLT, on strided views (as the factor preconditioner passes them) and for 1, 13 (the
  // recovery's [η | E_r]) and 40 columns.
  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  for (const int blocks : {1, 25, 120}) {
    const auto A = random_block_spd(blocks, 6, 2 * blocks, 91u + blocks);
    const Eigen::MatrixXd dense(A);
    const Eigen::LLT<Eigen::MatrixXd> llt(dense);
    for (const int m : {1, 13, 40}) {
      Eigen::MatrixXd B_storage(A.rows() + 3, m + 2);
      for (Eigen::Index i = 0; i < B_storage.size(); ++i) B_storage.data()[i] = normal(rng);
      const auto B = B_storage.block(2, 1, A.rows(), m);
      const Eigen::MatrixXd expected = llt.solve(Eigen::MatrixXd(B));
      for (const auto ordering : {MarginalsOrdering::kBlockAmd, MarginalsOrdering::kBlockMetis}) {
        for (const auto kernel : {MarginalsKernel::kAuto, MarginalsKernel::kBaseline}) {
          const ExactMarginals em = ExactMarginals::compute(A, 6, ordering, kernel);
          Eigen::MatrixXd X_storage = Eigen::MatrixXd::Constant(A.rows() + 1, m + 1, 7.0);
          auto X = X_storage.block(1, 0, A.rows(), m);
          em.solve(B, X);
          EXPECT_LE(max_abs_diff(X, expected), 1e-10 * expected.cwiseAbs().maxCoeff())
              << blocks << " blocks, " << m << " columns";
          em.solve(B, X);  // workspace reused
          EXPECT_LE(max_abs_diff(X, expected), 1e-10 * expected.cwiseAbs().maxCoeff());
          // The forward half alone: Bᵀ Λ⁻¹ B.
          const Eigen::MatrixXd form = Eigen::MatrixXd(B).transpose() * expected;
          EXPECT_LE(max_abs_diff(em.quadratic_form(B), form), 1e-10 * form.cwiseAbs().maxCoeff())
              << blocks << " blocks, " << m << " columns";
          EXPECT_EQ(X_storage(0, 0), 7.0) << "wrote outside the view";
          EXPECT_EQ(X_storage(1, m), 7.0) << "wrote outside the view";
        }
      }
    }
  }
}

TEST(ExactMarginals, DenseMatrixIsOneLargeSupernode) {
  // A fully dense 150 x 150 SPD matrix: one supernode, so the recursive triangular inverse
  // and Gram kernels run through several levels (150 -> 75 -> 37 -> 18).
  std::mt19937 rng(23);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd M(150, 150);
  for (int k = 0; k < M.size(); ++k) M.data()[k] = normal(rng);
  const Eigen::MatrixXd A = M * M.transpose() + 10.0 * Eigen::MatrixXd::Identity(150, 150);
  expect_matches_dense(A.sparseView(), 5, MarginalsOrdering::kBlockAmd, 1e-11);
  expect_matches_dense(A.sparseView(), 5, MarginalsOrdering::kBlockAmd, 1e-11,
                       MarginalsKernel::kBaseline);
}

TEST(ExactMarginals, AutoKernelUsesAvx2FmaWhenTheCpuHasIt) {
  const std::string name = auto_marginals_kernel_name();
#if defined(__x86_64__)
  __builtin_cpu_init();
  const bool has = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  EXPECT_EQ(name, has ? "avx2-fma" : "baseline");
#else
  EXPECT_EQ(name, "baseline");
#endif
  // Both kernels give the same selected inverse up to rounding on a real pose-graph-sized
  // separator (one dense supernode of 150 columns plus sparse ones).
  const auto A = random_block_spd(60, 6, 40, 99u);
  const ExactMarginals a = ExactMarginals::compute(A, 6);
  const ExactMarginals b =
      ExactMarginals::compute(A, 6, MarginalsOrdering::kBlockAmd, MarginalsKernel::kBaseline);
  for (int k = 0; k < a.num_blocks(); ++k) {
    EXPECT_LE(max_abs_diff(a.marginal(k), b.marginal(k)), 1e-12 * b.marginal(k).norm()) << k;
  }
}

TEST(ExactMarginals, JointOfArbitraryPairsInAndOutOfPattern) {
  const int d = 6;
  const auto A = random_block_spd(50, d, 10, 5u);
  const ExactMarginals em = ExactMarginals::compute(A, d);
  const Eigen::MatrixXd S = dense_inverse(A);
  const double tol = 1e-10 * S.cwiseAbs().maxCoeff();
  int outside = 0;
  for (const auto& [a, b] : std::vector<std::pair<int, int>>{
           {0, 1}, {0, 49}, {49, 0}, {7, 23}, {12, 12}, {30, 2}, {48, 49}, {5, 40}}) {
    Eigen::MatrixXd expected(2 * d, 2 * d);
    expected << S.block(a * d, a * d, d, d), S.block(a * d, b * d, d, d),
        S.block(b * d, a * d, d, d), S.block(b * d, b * d, d, d);
    EXPECT_LE(max_abs_diff(em.joint(a, b), expected), tol) << "pair " << a << ", " << b;
    if (!em.in_pattern(a, b)) ++outside;
  }
  EXPECT_GT(outside, 0) << "no pair exercised the solve path";
}

TEST(ExactMarginals, RejectsIndefiniteAndBadSizes) {
  Eigen::SparseMatrix<double> A(2, 2);
  A.insert(0, 0) = 1.0;
  A.insert(0, 1) = 2.0;
  A.insert(1, 0) = 2.0;
  A.insert(1, 1) = 1.0;  // eigenvalues 3, -1
  EXPECT_THROW(ExactMarginals::compute(A, 1), ExactMarginalsError);
  EXPECT_THROW(ExactMarginals::compute(A, 3), ExactMarginalsError);
  EXPECT_THROW(ExactMarginals::compute(A, 0), std::invalid_argument);
  Eigen::SparseMatrix<double> spd(2, 2);
  spd.insert(0, 0) = 1.0;
  spd.insert(1, 1) = 1.0;
  const ExactMarginals em = ExactMarginals::compute(spd, 1);
  EXPECT_THROW(em.marginal(2), std::out_of_range);
  EXPECT_THROW(em.entry(0, 5), std::out_of_range);
  EXPECT_THROW(em.entry(0, 1), std::out_of_range);  // not in the pattern (diagonal matrix)
}

void expect_graph_matches_dense(const std::filesystem::path& path) {
  const PoseGraph graph = read_g2o(path.string());
  const auto A = assemble_information_sparse(graph);
  expect_matches_dense(A, 6, MarginalsOrdering::kBlockAmd, 1e-9);
}

TEST(ExactMarginals, SmallGrid3DJointsOfArbitraryPairs) {
  NAV_REQUIRE_DATA(path, "posegraphs/smallGrid3D.g2o");
  const auto A = assemble_information_sparse(read_g2o(path.string()));
  const ExactMarginals em = ExactMarginals::compute(A, 6);
  const Eigen::MatrixXd S = dense_inverse(A);
  const double tol = 1e-9 * S.cwiseAbs().maxCoeff();
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> pick(0, em.num_blocks() - 1);
  for (int k = 0; k < 40; ++k) {
    const int a = pick(rng), b = pick(rng);
    Eigen::MatrixXd expected(12, 12);
    expected << S.block(a * 6, a * 6, 6, 6), S.block(a * 6, b * 6, 6, 6),
        S.block(b * 6, a * 6, 6, 6), S.block(b * 6, b * 6, 6, 6);
    EXPECT_LE(max_abs_diff(em.joint(a, b), expected), tol) << "pair " << a << ", " << b;
  }
}

TEST(ExactMarginals, TinyGrid3DAllBlocksMatchDenseInverse) {
  NAV_REQUIRE_DATA(path, "posegraphs/tinyGrid3D.g2o");
  expect_graph_matches_dense(path);
}

TEST(ExactMarginals, SmallGrid3DAllBlocksMatchDenseInverse) {
  NAV_REQUIRE_DATA(path, "posegraphs/smallGrid3D.g2o");
  expect_graph_matches_dense(path);
}

}  // namespace
}  // namespace nav::core
