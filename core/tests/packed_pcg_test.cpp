// Packed PCG fast path (recovery/packed_pcg.h) against dense products and against the generic
// solver of pcg.h, which it must reproduce iterate for iterate.
#include "nav/core/recovery/packed_pcg.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>
#include <vector>

#include "nav/core/recovery/state_recovery.h"

namespace nav::core {
namespace {

/// Random SPD block matrix like a pose graph: chain + random links (Hᵀ H each) + a prior.
Eigen::MatrixXd random_block_spd(int blocks, int d, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  const int n = blocks * d;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  auto add_link = [&](int a, int b) {
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(d, n);
    for (int r = 0; r < d; ++r) {
      for (int c = 0; c < d; ++c) {
        J(r, a * d + c) = normal(rng);
        J(r, b * d + c) = normal(rng);
      }
    }
    A += J.transpose() * J;
  };
  for (int b = 1; b < blocks; ++b) add_link(b - 1, b);
  std::uniform_int_distribution<int> pick(0, blocks - 1);
  for (int k = 0; k < blocks / 2; ++k) {
    const int a = pick(rng), b = pick(rng);
    if (a != b) add_link(a, b);
  }
  A.topLeftCorner(d, d) += 10.0 * Eigen::MatrixXd::Identity(d, d);
  return A;
}

InformationMatrix to_blocks(const Eigen::MatrixXd& A, int d) {
  InformationMatrix lambda(d);
  const int blocks = static_cast<int>(A.rows()) / d;
  for (int b = 0; b < blocks; ++b) lambda.add_block();
  for (int i = 0; i < blocks; ++i) {
    for (int j = i; j < blocks; ++j) {
      const Eigen::MatrixXd block = A.block(i * d, j * d, d, d);
      if (block.norm() > 0.0) lambda.add_to_block(i, j, block);
    }
  }
  return lambda;
}

class PackedByBlockSize : public ::testing::TestWithParam<int> {};

TEST_P(PackedByBlockSize, MultiplyMatchesDenseProductAndFusedDots) {
  const int d = GetParam();
  const Eigen::MatrixXd A = random_block_spd(9, d, 3);
  const InformationMatrix lambda = to_blocks(A, d);
  PackedBlockOperator op;
  op.refresh(lambda);
  ASSERT_EQ(op.dim(), A.rows());
  const int columns = d + 1;
  const int width = packed_width(columns);
  EXPECT_EQ(width % 8, 0);
  EXPECT_GE(width, columns);
  const Eigen::MatrixXd X = Eigen::MatrixXd::Random(A.rows(), columns);
  std::vector<double> x, y(static_cast<size_t>(A.rows() * width), -1.0);
  pack_columns(X, width, &x);
  std::vector<double> dots(static_cast<size_t>(width), 99.0);
  op.multiply(x.data(), y.data(), width, dots.data());
  Eigen::MatrixXd Y(A.rows(), columns);
  unpack_columns(y, width, Y);
  const Eigen::MatrixXd expected = A * X;
  EXPECT_LT((Y - expected).norm(), 1e-12 * expected.norm());
  for (int c = 0; c < columns; ++c) {
    EXPECT_NEAR(dots[static_cast<size_t>(c)], X.col(c).dot(expected.col(c)),
                1e-12 * expected.norm() * X.norm());
  }
  for (int c = columns; c < width; ++c) EXPECT_EQ(dots[static_cast<size_t>(c)], 0.0);
}

TEST_P(PackedByBlockSize, SpdOperatorAdapterMatchesDenseProduct) {
  const int d = GetParam();
  const Eigen::MatrixXd A = random_block_spd(7, d, 5);
  const InformationMatrix lambda = to_blocks(A, d);
  PackedBlockOperator op;
  op.refresh(lambda);
  std::vector<double> x_scratch, y_scratch;
  const PackedSpdOperator adapter(op, x_scratch, y_scratch);
  ASSERT_EQ(adapter.dim(), A.rows());
  for (const int columns : {1, d + 1, 9}) {  // widths 8 and 16
    const Eigen::MatrixXd X = Eigen::MatrixXd::Random(A.rows(), columns);
    Eigen::MatrixXd Y = Eigen::MatrixXd::Constant(A.rows(), columns, -1.0);
    adapter.multiply(X, Y);
    const Eigen::MatrixXd expected = A * X;
    EXPECT_LT((Y - expected).norm(), 1e-12 * expected.norm()) << columns << " columns";
  }
}

TEST_P(PackedByBlockSize, SolveReproducesGenericPcgIterates) {
  const int d = GetParam();
  const Eigen::MatrixXd A = random_block_spd(25, d, 7);
  const InformationMatrix lambda = to_blocks(A, d);
  const int columns = d + 1;
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(A.rows(), columns);
  // A warm start that is good for some columns and worse than zero for the last one (the
  // restart rule must fire identically).
  Eigen::MatrixXd X0 = A.ldlt().solve(B) + 1e-3 * Eigen::MatrixXd::Random(A.rows(), columns);
  X0.col(columns - 1) *= -5.0;
  for (const double tolerance : {0.0, 1e-9}) {
    PcgOptions options;
    options.max_iterations = tolerance > 0.0 ? 1000 : 5;
    options.relative_tolerance = tolerance;
    Eigen::MatrixXd X_generic = X0;
    BlockJacobiPreconditioner M_generic;
    ASSERT_TRUE(M_generic.factor(lambda).ok());
    PcgWorkspace ws_generic;
    const PcgSummary generic =
        solve_pcg(InformationOperator(lambda), M_generic, B, X_generic, options, ws_generic);
    ASSERT_TRUE(generic.status.ok()) << generic.status.to_string();

    const int width = packed_width(columns);
    PackedBlockOperator op;
    op.refresh(lambda);
    PackedBlockJacobi M;
    ASSERT_TRUE(M.update(lambda).ok());
    EXPECT_EQ(M.last_refactored(), lambda.num_blocks());
    std::vector<double> b, x;
    pack_columns(B, width, &b);
    pack_columns(X0, width, &x);
    PackedPcgWorkspace ws;
    const PcgSummary packed =
        solve_pcg_packed(op, M, b.data(), x.data(), columns, width, options, ws);
    ASSERT_TRUE(packed.status.ok()) << packed.status.to_string();
    Eigen::MatrixXd X(A.rows(), columns);
    unpack_columns(x, width, X);

    EXPECT_EQ(packed.iterations, generic.iterations) << "tolerance " << tolerance;
    EXPECT_EQ(packed.restarted_columns, generic.restarted_columns);
    EXPECT_GE(packed.restarted_columns, 1);
    EXPECT_EQ(packed.converged, generic.converged);
    EXPECT_LT((X - X_generic).norm(), 1e-9 * X_generic.norm()) << "tolerance " << tolerance;
    for (int c = 0; c < columns; ++c) {
      const double true_residual = (B.col(c) - A * X.col(c)).norm();
      EXPECT_NEAR(packed.residual_norm[c], true_residual, 1e-9 * (1.0 + true_residual));
      // Same up to rounding (which dominates once the residual is ~1e-9 ‖b‖).
      EXPECT_NEAR(packed.residual_norm[c], generic.residual_norm[c],
                  1e-6 * generic.residual_norm[c] + 1e-12 * B.col(c).norm());
    }
  }
}

// 6 and 12 are the specialised kernels; 3 runs the generic (run-time block size) tile loop.
INSTANTIATE_TEST_SUITE_P(BlockSizes, PackedByBlockSize, ::testing::Values(6, 12, 3));

TEST(PackedBlockJacobi, RefactorsOnlyChangedDiagonalBlocks) {
  const int d = 6;
  InformationMatrix lambda = to_blocks(random_block_spd(12, d, 5), d);
  PackedBlockJacobi M;
  ASSERT_TRUE(M.update(lambda).ok());
  EXPECT_EQ(M.last_refactored(), 12);
  ASSERT_TRUE(M.update(lambda).ok());
  EXPECT_EQ(M.last_refactored(), 0);
  // A link between states 3 and 7 changes their diagonal blocks only.
  Eigen::MatrixXd H = Eigen::MatrixXd::Random(d, 2 * d);
  const Eigen::MatrixXd HtH = H.transpose() * H;
  lambda.add_to_block(3, 3, HtH.topLeftCorner(d, d));
  lambda.add_to_block(3, 7, HtH.topRightCorner(d, d));
  lambda.add_to_block(7, 7, HtH.bottomRightCorner(d, d));
  ASSERT_TRUE(M.update(lambda).ok());
  EXPECT_EQ(M.last_refactored(), 2);
  // A new state: one more block.
  const int added = lambda.add_block();
  lambda.add_to_block(added, added, Eigen::MatrixXd::Identity(d, d));
  ASSERT_TRUE(M.update(lambda).ok());
  EXPECT_EQ(M.last_refactored(), 1);

  // The incrementally maintained inverses equal freshly computed ones.
  PackedBlockJacobi fresh;
  ASSERT_TRUE(fresh.update(lambda).ok());
  const int width = 8;
  const Eigen::MatrixXd R = Eigen::MatrixXd::Random(lambda.dim(), width);
  std::vector<double> r, z1(static_cast<size_t>(lambda.dim() * width)), z2(z1.size());
  pack_columns(R, width, &r);
  M.apply(r.data(), z1.data(), width);
  fresh.apply(r.data(), z2.data(), width);
  EXPECT_EQ(z1, z2);
  // And equal M⁻¹ R.
  Eigen::MatrixXd Z(lambda.dim(), width);
  unpack_columns(z1, width, Z);
  for (int b = 0; b < lambda.num_blocks(); ++b) {
    const Eigen::MatrixXd expected =
        Eigen::MatrixXd(lambda.diagonal_block(b)).ldlt().solve(R.middleRows(b * d, d));
    EXPECT_LT((Z.middleRows(b * d, d) - expected).norm(), 1e-10 * (1.0 + expected.norm()));
  }
}

TEST(PackedBlockJacobi, NamesTheBlockThatIsNotPositiveDefinite) {
  InformationMatrix lambda = to_blocks(random_block_spd(4, 6, 9), 6);
  lambda.add_to_block(2, 2, -1e6 * Eigen::MatrixXd::Identity(6, 6));
  PackedBlockJacobi M;
  const Status s = M.update(lambda);
  EXPECT_EQ(s.code(), StatusCode::kNotPositiveDefinite);
  EXPECT_NE(s.message().find("diagonal block 2"), std::string::npos) << s.message();
  EXPECT_EQ(M.num_blocks(), 0);
}

TEST(PackedPcg, RejectsMismatchedPreconditioner) {
  const InformationMatrix lambda = to_blocks(random_block_spd(4, 6, 1), 6);
  PackedBlockOperator op;
  op.refresh(lambda);
  PackedBlockJacobi M;  // never updated
  std::vector<double> b(static_cast<size_t>(lambda.dim() * 8), 1.0), x(b.size(), 0.0);
  PackedPcgWorkspace ws;
  const PcgSummary s = solve_pcg_packed(op, M, b.data(), x.data(), 7, 8, PcgOptions{}, ws);
  EXPECT_EQ(s.status.code(), StatusCode::kInvalidArgument);
}

TEST(StateRecoveryKernels, PackedAndGenericAgreeOverSteps) {
  const int d = 6;
  InformationMatrix lambda = to_blocks(random_block_spd(40, d, 13), d);
  const Eigen::VectorXd eta = Eigen::VectorXd::Random(lambda.dim());
  StateRecoveryOptions packed_options, generic_options;
  packed_options.iterations_per_step = generic_options.iterations_per_step = 4;
  // The kernels of the block-Jacobi preconditioner (the factor's have their own tests).
  packed_options.preconditioner = generic_options.preconditioner =
      RecoveryPreconditioner::kBlockJacobi;
  generic_options.kernel = RecoveryKernel::kGeneric;
  StateRecovery packed(d, packed_options), generic(d, generic_options);
  ASSERT_TRUE(packed.set_solution(Eigen::MatrixXd::Zero(lambda.dim(), d + 1)).ok());
  ASSERT_TRUE(generic.set_solution(Eigen::MatrixXd::Zero(lambda.dim(), d + 1)).ok());
  for (int step = 0; step < 3; ++step) {
    const RecoveryResult a = packed.solve(lambda, eta);
    const RecoveryResult b = generic.solve(lambda, eta);
    ASSERT_TRUE(a.status.ok() && b.status.ok());
    EXPECT_LT((packed.solution() - generic.solution()).norm(), 1e-9 * generic.solution().norm());
    EXPECT_NEAR(a.column_residual_frobenius, b.column_residual_frobenius,
                1e-6 * b.column_residual_frobenius);
    EXPECT_NEAR(a.mean_relative_residual, b.mean_relative_residual,
                1e-6 * b.mean_relative_residual);
    EXPECT_EQ(b.refactored_blocks, 40);
    // ‖E_r - Λ Σ̂_{*r}‖₂ against a dense SVD of the residual (before Λ changes below).
    const Eigen::MatrixXd E = Eigen::MatrixXd::Identity(lambda.dim(), d);
    const Eigen::MatrixXd residual = E - lambda.to_dense() * packed.robot_column();
    const double spectral = Eigen::JacobiSVD<Eigen::MatrixXd>(residual).singularValues()[0];
    EXPECT_NEAR(a.column_residual_spectral, spectral, 1e-6 * spectral);
    EXPECT_NEAR(b.column_residual_spectral, spectral, 1e-6 * spectral);
    EXPECT_LE(a.column_residual_spectral, a.column_residual_frobenius);
    EXPECT_EQ(a.refactored_blocks, step == 0 ? 40 : 1);
    lambda.add_to_block(0, 0, 0.5 * Eigen::MatrixXd::Identity(d, d));  // changes one block
  }
}

TEST(StateRecoveryKernels, FactorPreconditionedPackedAndGenericAgree) {
  const int d = 6;
  InformationMatrix lambda = to_blocks(random_block_spd(30, d, 17), d);
  const Eigen::VectorXd eta = Eigen::VectorXd::Random(lambda.dim());
  StateRecoveryOptions packed_options, generic_options;
  packed_options.preconditioner = generic_options.preconditioner = RecoveryPreconditioner::kFactor;
  packed_options.refresh_interval = generic_options.refresh_interval = 3;
  generic_options.kernel = RecoveryKernel::kGeneric;
  StateRecovery packed(d, packed_options), generic(d, generic_options);
  ASSERT_TRUE(packed.set_solution(Eigen::MatrixXd::Zero(lambda.dim(), d + 1)).ok());
  ASSERT_TRUE(generic.set_solution(Eigen::MatrixXd::Zero(lambda.dim(), d + 1)).ok());
  const Eigen::MatrixXd exact_column = lambda.to_dense().inverse().leftCols(d);
  for (int step = 0; step < 4; ++step) {
    const RecoveryResult a = packed.solve(lambda, eta);
    const RecoveryResult b = generic.solve(lambda, eta);
    ASSERT_TRUE(a.status.ok() && b.status.ok());
    EXPECT_EQ(a.refreshed, b.refreshed);
    EXPECT_LT((packed.solution() - generic.solution()).norm(), 1e-9 * generic.solution().norm());
    // A refreshed step runs iterations_after_refresh (1) iterations, the others the budget.
    EXPECT_EQ(a.iterations, a.refreshed ? 1 : packed_options.iterations_per_step);
    if (step == 0) {  // Λ was factored: M = Λ, one iteration is the direct solve
      EXPECT_LT((packed.robot_column() - exact_column).norm(), 1e-9 * exact_column.norm());
    }
    lambda.add_to_block(3, 3, 0.5 * Eigen::MatrixXd::Identity(d, d));  // a later link's term
  }
}

}  // namespace
}  // namespace nav::core
