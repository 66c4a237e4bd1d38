// Multi-RHS block-Jacobi PCG and iterative refinement (recovery/pcg.h): hand-checkable systems
// first, then random block-sparse SPD matrices against dense solves.
#include "nav/core/recovery/pcg.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <random>
#include <vector>

namespace nav::core {
namespace {

/// Random SPD block matrix: a chain of blocks plus a few random "loop closure" blocks,
/// diagonally dominant only through Hᵀ Ω H terms (like a pose graph), plus a prior on block 0.
Eigen::MatrixXd random_block_spd(int blocks, int d, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  const int n = blocks * d;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  auto add_link = [&](int a, int b) {
    Eigen::MatrixXd H(d, 2 * d);
    for (int r = 0; r < d; ++r)
      for (int c = 0; c < 2 * d; ++c) H(r, c) = normal(rng);
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(d, n);
    J.middleCols(a * d, d) = H.leftCols(d);
    J.middleCols(b * d, d) = H.rightCols(d);
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

CsrMatrix to_csr(const Eigen::MatrixXd& A) { return A.sparseView(); }

TEST(Pcg, SolvesTwoByTwoByHand) {
  // A = [4 1; 1 3], b = [1; 2] -> x = [1/11; 7/11]. Scalar blocks: Jacobi preconditioner.
  Eigen::MatrixXd A(2, 2);
  A << 4, 1, 1, 3;
  const CsrMatrix csr = to_csr(A);
  BlockJacobiPreconditioner M;
  ASSERT_TRUE(M.factor(csr, 1).ok());
  Eigen::MatrixXd B(2, 1);
  B << 1, 2;
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(2, 1);
  PcgOptions options;
  options.max_iterations = 2;  // CG is exact after n iterations in exact arithmetic
  PcgWorkspace ws;
  const PcgSummary s = solve_pcg(CsrOperator(csr), M, B, X, options, ws);
  ASSERT_TRUE(s.status.ok()) << s.status.to_string();
  EXPECT_NEAR(X(0, 0), 1.0 / 11.0, 1e-14);
  EXPECT_NEAR(X(1, 0), 7.0 / 11.0, 1e-14);
  EXPECT_LT(s.max_relative_residual, 1e-14);
  EXPECT_EQ(s.iterations, 2);
}

TEST(Pcg, BlockJacobiSolvesBlockDiagonalInOneIteration) {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(12, 12);
  A.topLeftCorner(6, 6) = random_block_spd(1, 6, 3);
  A.bottomRightCorner(6, 6) = random_block_spd(1, 6, 4);
  const CsrMatrix csr = to_csr(A);
  BlockJacobiPreconditioner M;
  ASSERT_TRUE(M.factor(csr, 6).ok());
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(12, 3);
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(12, 3);
  PcgOptions options;
  options.max_iterations = 1;
  PcgWorkspace ws;
  const PcgSummary s = solve_pcg(CsrOperator(csr), M, B, X, options, ws);
  ASSERT_TRUE(s.status.ok());
  EXPECT_LT((X - A.ldlt().solve(B)).norm(), 1e-10 * X.norm());
}

/// Counts applications of a wrapped preconditioner (the cost of a step with a factor M).
class CountingPreconditioner final : public Preconditioner {
 public:
  explicit CountingPreconditioner(const Preconditioner& m) : m_(m) {}
  Eigen::Index dim() const override { return m_.dim(); }
  void apply(const Eigen::Ref<const Eigen::MatrixXd>& R,
             Eigen::Ref<Eigen::MatrixXd> Z) const override {
    ++applications;
    m_.apply(R, Z);
  }
  mutable int applications = 0;

 private:
  const Preconditioner& m_;
};

/// M⁻¹ = scale · A⁻¹ from a dense factor: scale 1 is a factor of A itself (the kept factor);
/// another scale is a factor of A / scale.
class ScaledInversePreconditioner final : public Preconditioner {
 public:
  ScaledInversePreconditioner(const Eigen::MatrixXd& A, double scale) : ldlt_(A), scale_(scale) {}
  Eigen::Index dim() const override { return ldlt_.rows(); }
  void apply(const Eigen::Ref<const Eigen::MatrixXd>& R,
             Eigen::Ref<Eigen::MatrixXd> Z) const override {
    Z = scale_ * ldlt_.solve(R);
  }

 private:
  Eigen::LDLT<Eigen::MatrixXd> ldlt_;
  double scale_;
};

/// Counts the products of a wrapped operator.
class CountingOperator final : public SpdOperator {
 public:
  explicit CountingOperator(const SpdOperator& a) : a_(a) {}
  Eigen::Index dim() const override { return a_.dim(); }
  void multiply(const Eigen::Ref<const Eigen::MatrixXd>& X,
                Eigen::Ref<Eigen::MatrixXd> Y) const override {
    ++products;
    a_.multiply(X, Y);
  }
  mutable int products = 0;

 private:
  const SpdOperator& a_;
};

TEST(Refinement, WithAFactorOfATakesTheDirectSolveInOneIterationAndTwoProducts) {
  const Eigen::MatrixXd A = random_block_spd(20, 6, 11);
  const CsrMatrix csr = to_csr(A);
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(120, 7);
  const Eigen::MatrixXd exact = A.ldlt().solve(B);
  const Eigen::MatrixXd warm = exact + 0.1 * Eigen::MatrixXd::Random(120, 7);
  PcgOptions options;
  options.max_iterations = 1;
  const ScaledInversePreconditioner factor(A, 1.0);
  CountingPreconditioner M(factor);
  const CsrOperator csr_operator(csr);
  CountingOperator op(csr_operator);
  Eigen::MatrixXd X = warm;
  PcgWorkspace ws;
  const PcgSummary s = solve_refinement(op, M, B, X, options, ws);
  ASSERT_TRUE(s.status.ok()) << s.status.to_string();
  EXPECT_EQ(s.iterations, 1);
  EXPECT_EQ(M.applications, 1);
  EXPECT_EQ(op.products, 2);  // the warm start's residual and the true residual at the end
  EXPECT_LT((X - exact).norm() / exact.norm(), 1e-10);
  const Eigen::VectorXd true_residual = (B - A * X).colwise().norm().transpose();
  for (int c = 0; c < 7; ++c) {
    EXPECT_NEAR(s.residual_norm[c], true_residual[c], 1e-13 * B.col(c).norm());
  }

  // PCG takes the same step at one product more.
  Eigen::MatrixXd X_pcg = warm;
  CountingOperator op_pcg(csr_operator);
  ASSERT_TRUE(solve_pcg(op_pcg, factor, B, X_pcg, options, ws).status.ok());
  EXPECT_EQ(op_pcg.products, 3);
  EXPECT_LT((X_pcg - X).norm() / exact.norm(), 1e-10);
}

TEST(Refinement, ANearFactorConvergesToTheTolerance) {
  const Eigen::MatrixXd A = random_block_spd(20, 6, 12);
  const CsrMatrix csr = to_csr(A);
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(120, 3);
  // M = A / 0.8: the error contracts by |1 - 0.8| = 0.2 per iteration.
  const ScaledInversePreconditioner M(A, 0.8);
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(120, 3);
  PcgOptions options;
  options.max_iterations = 100;
  options.relative_tolerance = 1e-10;
  PcgWorkspace ws;
  const PcgSummary s = solve_refinement(CsrOperator(csr), M, B, X, options, ws);
  ASSERT_TRUE(s.status.ok());
  EXPECT_TRUE(s.converged);
  EXPECT_GE(s.iterations, 10);  // 0.2^k ‖e0‖ in the A-norm: no shortcut
  EXPECT_LE(s.iterations, 25);
  EXPECT_LT((B - A * X).norm() / B.norm(), 1e-9);
}

TEST(Refinement, StopsAtTheRoundingFloorBelowAnUnreachableTolerance) {
  const Eigen::MatrixXd A = random_block_spd(20, 6, 14);
  const CsrMatrix csr = to_csr(A);
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(120, 3);
  const ScaledInversePreconditioner M(A, 1.0);
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(120, 3);
  PcgOptions options;
  options.max_iterations = 1000;
  options.relative_tolerance = 1e-30;  // below what double precision resolves
  PcgWorkspace ws;
  const PcgSummary s = solve_refinement(CsrOperator(csr), M, B, X, options, ws);
  ASSERT_TRUE(s.status.ok());
  EXPECT_FALSE(s.converged);
  EXPECT_LE(s.iterations, 4);  // the direct solve, then steps that no longer halve R
  EXPECT_LT((B - A * X).norm() / B.norm(), 1e-10);

  // M = A / 0.01: every step lowers the error, by 1 %. It stops after one step instead of
  // running its 1,000 solves.
  const ScaledInversePreconditioner slow(A, 0.01);
  X.setZero();
  const PcgSummary crawl = solve_refinement(CsrOperator(csr), slow, B, X, options, ws);
  ASSERT_TRUE(crawl.status.ok());
  EXPECT_EQ(crawl.iterations, 1);
  EXPECT_NEAR((B - A * X).norm() / B.norm(), 0.99, 1e-9);
}

TEST(Refinement, AStepThatWouldRaiseTheErrorIsNotTaken) {
  const Eigen::MatrixXd A = random_block_spd(20, 6, 13);
  const CsrMatrix csr = to_csr(A);
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(120, 2);
  const Eigen::MatrixXd exact = A.ldlt().solve(B);
  const Eigen::MatrixXd warm = exact + 0.01 * Eigen::MatrixXd::Random(120, 2);
  // M = A / 3: the step overshoots, e1 = -2 e0, four times the A-norm error.
  const ScaledInversePreconditioner M(A, 3.0);
  Eigen::MatrixXd X = warm;
  PcgOptions options;
  options.max_iterations = 5;
  PcgWorkspace ws;
  const PcgSummary s = solve_refinement(CsrOperator(csr), M, B, X, options, ws);
  ASSERT_TRUE(s.status.ok());
  EXPECT_EQ(s.iterations, 1);  // every column stopped at its first step
  EXPECT_TRUE(X == warm);      // bit for bit
  const Eigen::VectorXd true_residual = (B - A * warm).colwise().norm().transpose();
  for (int c = 0; c < 2; ++c) {
    EXPECT_NEAR(s.residual_norm[c], true_residual[c], 1e-13 * B.col(c).norm());
  }
}

TEST(Pcg, ConvergesToDenseSolutionAndReportsTrueResidual) {
  const Eigen::MatrixXd A = random_block_spd(30, 6, 7);
  const CsrMatrix csr = to_csr(A);
  BlockJacobiPreconditioner M;
  ASSERT_TRUE(M.factor(csr, 6).ok());
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(180, 7);
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(180, 7);
  PcgOptions options;
  options.max_iterations = 2000;
  options.relative_tolerance = 1e-12;
  PcgWorkspace ws;
  const PcgSummary s = solve_pcg(CsrOperator(csr), M, B, X, options, ws);
  ASSERT_TRUE(s.status.ok()) << s.status.to_string();
  EXPECT_TRUE(s.converged);
  const Eigen::MatrixXd exact = A.ldlt().solve(B);
  // Forward error <= condition number * relative residual.
  EXPECT_LT((X - exact).norm() / exact.norm(), 1e-6);
  const Eigen::VectorXd true_residual = (B - A * X).colwise().norm().transpose();
  for (int c = 0; c < 7; ++c) {
    EXPECT_NEAR(s.residual_norm[c], true_residual[c], 1e-12 * B.col(c).norm());
    EXPECT_LE(s.relative_residual[c], 1e-12);
  }
}

TEST(Pcg, ColumnsConvergeIndependently) {
  // A multi-RHS solve with a fixed budget equals solving each column on its own.
  const Eigen::MatrixXd A = random_block_spd(20, 6, 11);
  const CsrMatrix csr = to_csr(A);
  BlockJacobiPreconditioner M;
  ASSERT_TRUE(M.factor(csr, 6).ok());
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(120, 4);
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(120, 4);
  PcgOptions options;
  options.max_iterations = 7;
  PcgWorkspace ws;
  ASSERT_TRUE(solve_pcg(CsrOperator(csr), M, B, X, options, ws).status.ok());
  for (int c = 0; c < 4; ++c) {
    Eigen::MatrixXd x = Eigen::MatrixXd::Zero(120, 1);
    ASSERT_TRUE(solve_pcg(CsrOperator(csr), M, B.col(c), x, options, ws).status.ok());
    EXPECT_LT((x.col(0) - X.col(c)).norm(), 1e-12 * x.norm()) << "column " << c;
  }
}

TEST(Pcg, ResidualDecreasesWithBudgetAndWarmStartKeepsExactSolution) {
  const Eigen::MatrixXd A = random_block_spd(40, 6, 5);
  const CsrMatrix csr = to_csr(A);
  BlockJacobiPreconditioner jacobi;
  ASSERT_TRUE(jacobi.factor(csr, 6).ok());
  const CountingPreconditioner M(jacobi);
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(240, 2);
  PcgWorkspace ws;
  double previous = 1e300;
  for (int budget : {1, 5, 20, 80}) {
    Eigen::MatrixXd X = Eigen::MatrixXd::Zero(240, 2);
    PcgOptions options;
    options.max_iterations = budget;
    M.applications = 0;
    const PcgSummary s = solve_pcg(CsrOperator(csr), M, B, X, options, ws);
    ASSERT_TRUE(s.status.ok());
    EXPECT_EQ(s.iterations, budget);
    // One solve for the initial residual and one per later direction: the direction after the
    // last iteration is never used, so it costs no solve (with a kept factor, M = Λ and one
    // iteration is one pair of triangular solves).
    EXPECT_EQ(M.applications, budget);
    // CG minimises the A-norm error, not the residual, so compare budgets far apart.
    EXPECT_LT(s.max_relative_residual, previous) << "budget " << budget;
    previous = s.max_relative_residual;
  }
  Eigen::MatrixXd X = A.ldlt().solve(B);
  PcgOptions options;
  options.max_iterations = 0;
  const PcgSummary s = solve_pcg(CsrOperator(csr), M, B, X, options, ws);
  EXPECT_LT(s.max_relative_residual, 1e-10);  // rounding of the dense solve only
}

TEST(Pcg, CsrAndInformationMatrixOperatorsAgree) {
  InformationMatrix info(6);
  for (int b = 0; b < 10; ++b) info.add_block();
  const Eigen::MatrixXd A = random_block_spd(10, 6, 21);
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) {
      const Eigen::MatrixXd block = A.block(6 * i, 6 * j, 6, 6);
      if (i <= j && block.norm() > 0.0) {
        if (i == j) {
          info.add_to_block(i, i, block);
        } else {
          info.add_to_block(i, j, block);
        }
      }
    }
  const CsrMatrix csr = info.to_sparse();
  const Eigen::MatrixXd X = Eigen::MatrixXd::Random(60, 7);
  Eigen::MatrixXd Y1(60, 7), Y2(60, 7);
  CsrOperator(csr).multiply(X, Y1);
  InformationOperator(info).multiply(X, Y2);
  EXPECT_LT((Y1 - A * X).norm(), 1e-12 * Y1.norm());
  EXPECT_LT((Y2 - A * X).norm(), 1e-12 * Y2.norm());
  BlockJacobiPreconditioner M1, M2;
  ASSERT_TRUE(M1.factor(csr, 6).ok());
  ASSERT_TRUE(M2.factor(info).ok());
  Eigen::MatrixXd Z1(60, 7), Z2(60, 7);
  M1.apply(X, Z1);
  M2.apply(X, Z2);
  EXPECT_LT((Z1 - Z2).norm(), 1e-12 * Z1.norm());
}

TEST(Pcg, RejectsBadInput) {
  Eigen::MatrixXd A = Eigen::MatrixXd::Identity(6, 6);
  A(2, 2) = -1.0;
  BlockJacobiPreconditioner M;
  const Status s = M.factor(to_csr(A), 3);
  EXPECT_EQ(s.code(), StatusCode::kNotPositiveDefinite);
  EXPECT_NE(s.message().find("block 0"), std::string::npos) << s.message();
  EXPECT_EQ(M.factor(to_csr(A), 4).code(), StatusCode::kInvalidArgument);

  const CsrMatrix I = to_csr(Eigen::MatrixXd::Identity(6, 6));
  ASSERT_TRUE(M.factor(I, 3).ok());
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(5, 1);
  PcgWorkspace ws;
  const PcgSummary bad =
      solve_pcg(CsrOperator(I), M, Eigen::MatrixXd::Ones(6, 1), X, PcgOptions{}, ws);
  EXPECT_EQ(bad.status.code(), StatusCode::kInvalidArgument);
  PcgOptions negative;
  negative.max_iterations = -1;
  EXPECT_EQ(negative.validate().code(), StatusCode::kInvalidArgument);
}

TEST(Pcg, IndefiniteOperatorIsReportedNotHidden) {
  // Diagonal blocks SPD (so the preconditioner factors) but the whole matrix indefinite.
  Eigen::MatrixXd A(2, 2);
  A << 1, 2, 2, 1;  // eigenvalues 3 and -1
  const CsrMatrix csr = to_csr(A);
  BlockJacobiPreconditioner M;
  ASSERT_TRUE(M.factor(csr, 1).ok());
  Eigen::MatrixXd B(2, 1);
  B << 1, -1;  // eigenvector of -1: pᵀAp < 0 at the first step
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(2, 1);
  PcgWorkspace ws;
  const PcgSummary s = solve_pcg(CsrOperator(csr), M, B, X, PcgOptions{}, ws);
  EXPECT_EQ(s.status.code(), StatusCode::kNumericalFailure);
}

}  // namespace
}  // namespace nav::core
