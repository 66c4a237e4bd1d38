// Factor preconditioner (recovery/factor_preconditioner.h) and the StateRecovery that refreshes
// it: ExactMarginals::solve against a dense solve, M⁻¹ against a dense blkdiag(Λ₀, Λ_tt)⁻¹,
// and the refresh policy on a pose graph replayed as the filter (tinyGrid3D).
#include "nav/core/recovery/factor_preconditioner.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <algorithm>
#include <random>
#include <vector>

#include "nav/core/posegraph/g2o.h"
#include "nav/core/posegraph/replay.h"
#include "nav/testing/data.h"

namespace nav::core {
namespace {

Eigen::MatrixXd random_matrix(int rows, int cols, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd A(rows, cols);
  for (int i = 0; i < A.size(); ++i) A(i) = normal(rng);
  return A;
}

/// Block tridiagonal SPD matrix of `blocks` blocks of size d (a chain with random couplings).
InformationMatrix chain(int blocks, int d, unsigned seed) {
  InformationMatrix lambda(d);
  for (int b = 0; b < blocks; ++b) lambda.add_block();
  for (int b = 0; b < blocks; ++b) {
    const Eigen::MatrixXd A = random_matrix(d, d, seed + 2 * b);
    lambda.add_to_block(b, b, A * A.transpose() + 4.0 * Eigen::MatrixXd::Identity(d, d));
    if (b + 1 < blocks) lambda.add_to_block(b, b + 1, 0.3 * random_matrix(d, d, seed + 2 * b + 1));
  }
  return lambda;
}

TEST(FactorPreconditioner, SolveMatchesDenseAndTrailingStatesUseBlockJacobi) {
  const int d = 6, factored = 5, blocks = 7;
  InformationMatrix lambda = chain(blocks, d, 3);
  // Factor the leading 5 blocks only: rebuild them as their own matrix.
  InformationMatrix head(d);
  for (int b = 0; b < factored; ++b) head.add_block();
  for (int i = 0; i < factored; ++i) {
    for (int j = i; j < factored; ++j) {
      head.add_to_block(i, j, lambda.to_dense().block(i * d, j * d, d, d));
    }
  }
  FactorPreconditioner M;
  ASSERT_TRUE(M.refresh(head.to_sparse(), d).ok());
  ASSERT_TRUE(M.update_trailing(lambda).ok());
  EXPECT_EQ(M.factored_dim(), factored * d);
  EXPECT_EQ(M.dim(), blocks * d);
  // M = blkdiag(P Λ₀ Pᵀ, Λ_TT): Λ₀ (blocks 0..4 of the factored matrix) with its block 0 at
  // block 5, and T = blocks 0 and 6 of the current Λ.
  const Eigen::MatrixXd dense = lambda.to_dense();
  const Eigen::MatrixXd head_dense = head.to_dense();
  const int n = blocks * d;
  std::vector<int> factored_rows;  // current row of each row of Λ₀
  for (int r = 0; r < d; ++r) factored_rows.push_back(factored * d + r);
  for (int r = d; r < factored * d; ++r) factored_rows.push_back(r);
  std::vector<int> tail_rows;
  for (int r = 0; r < d; ++r) tail_rows.push_back(r);
  for (int r = (factored + 1) * d; r < n; ++r) tail_rows.push_back(r);
  Eigen::MatrixXd M_dense = Eigen::MatrixXd::Zero(n, n);
  for (size_t a = 0; a < factored_rows.size(); ++a)
    for (size_t b = 0; b < factored_rows.size(); ++b)
      M_dense(factored_rows[a], factored_rows[b]) = head_dense(a, b);
  for (int a : tail_rows)
    for (int b : tail_rows) M_dense(a, b) = dense(a, b);
  const Eigen::MatrixXd expected_inverse = M_dense.inverse();
  const Eigen::MatrixXd R = random_matrix(blocks * d, 7, 99);
  Eigen::MatrixXd Z(blocks * d, 7);
  M.apply(R, Z);
  EXPECT_LT((Z - expected_inverse * R).norm(), 1e-12 * Z.norm());
  // The factor's own solve against the dense inverse; a size mismatch is an error.
  Eigen::MatrixXd X(factored * d, 3);
  M.marginals()->solve(R.topLeftCorner(factored * d, 3), X);
  EXPECT_LT((X - dense.topLeftCorner(factored * d, factored * d).inverse() *
                     R.topLeftCorner(factored * d, 3)).norm(),
            1e-12 * X.norm());
  EXPECT_THROW(M.marginals()->solve(R, Z), ExactMarginalsError);
  // A smaller Λ than the factor cannot be preconditioned.
  EXPECT_EQ(M.update_trailing(chain(3, d, 3)).code(), StatusCode::kInvalidArgument);
}

/// Per-step covariance-column relative residuals and refresh flags of a replay.
struct ReplayRun {
  std::vector<double> residual;
  std::vector<bool> refreshed;
};

ReplayRun replay_run(const PoseGraph& graph, RecoveryPreconditioner preconditioner) {
  ReplayOptions options;
  options.recovery.preconditioner = preconditioner;
  options.recovery.iterations_per_step = 5;
  options.recovery.refresh_interval = 4;
  options.recovery.refresh_residual = 1e-6;
  PoseGraphReplay replay(graph, options);
  EXPECT_TRUE(replay.start().ok());
  ReplayRun run;
  while (!replay.done()) {
    RecoveryResult r;
    EXPECT_TRUE(replay.step(&r).ok()) << r.status.to_string();
    run.residual.push_back(r.column_relative_residual);
    run.refreshed.push_back(r.refreshed);
  }
  return run;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

TEST(FactorPreconditioner, RefreshPolicyAndConvergenceOnAReplayedPoseGraph) {
  NAV_REQUIRE_DATA(path, "posegraphs/smallGrid3D.g2o");
  const PoseGraph graph = read_g2o(path.string());
  const ReplayRun run = replay_run(graph, RecoveryPreconditioner::kFactor);
  ASSERT_GT(run.residual.size(), 20u);
  // Refreshed exactly when 4 steps used the factor or the previous step missed 1e-6.
  int since = 0;
  for (size_t k = 0; k < run.residual.size(); ++k) {
    const bool expected = k == 0 || since >= 4 || run.residual[k - 1] > 1e-6;
    EXPECT_EQ(run.refreshed[k], expected) << "step " << k;
    since = run.refreshed[k] ? 1 : since + 1;
  }
  // Same budget (5 iterations): the factor converges, block Jacobi does not.
  const ReplayRun jacobi = replay_run(graph, RecoveryPreconditioner::kBlockJacobi);
  EXPECT_LT(median(run.residual), 1e-9);
  EXPECT_LT(1e3 * median(run.residual), median(jacobi.residual));
}

}  // namespace
}  // namespace nav::core
