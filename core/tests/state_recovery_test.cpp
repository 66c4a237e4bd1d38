// State recovery (recovery/state_recovery.h): exact warm-start extension across predictions,
// the three modes against dense and direct solves, real pose graphs (tinyGrid3D, smallGrid3D).
#include "nav/core/recovery/state_recovery.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>
#include <random>

#include "nav/core/filter/information_matrix.h"
#include "nav/core/posegraph/g2o.h"
#include "nav/testing/data.h"

namespace nav::core {
namespace {

Eigen::MatrixXd random_spd(int n, unsigned seed, double ridge = 0.5) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd A(n, n);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) A(r, c) = normal(rng);
  return A * A.transpose() / n + ridge * Eigen::MatrixXd::Identity(n, n);
}

Eigen::MatrixXd random_matrix(int rows, int cols, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd A(rows, cols);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) A(r, c) = normal(rng);
  return A;
}

/// [μ | Σ_{*0}] of a dense Gaussian: the exact recovery solution.
Eigen::MatrixXd exact_solution(const Eigen::VectorXd& mu, const Eigen::MatrixXd& sigma, int d) {
  Eigen::MatrixXd X(mu.size(), 1 + d);
  X.col(0) = mu;
  X.rightCols(d) = sigma.leftCols(d);
  return X;
}

struct Predicted {
  Eigen::VectorXd mu;
  Eigen::MatrixXd sigma;
};

/// Dense reference of the ESDF prediction: z = T y + [w; 0] with the old robot x_t in block 0,
/// new robot f(x_t) in block 0 and, when kept, x_t appended last.
Predicted dense_prediction(const Eigen::VectorXd& mu, const Eigen::MatrixXd& sigma,
                           const Eigen::MatrixXd& F, const Eigen::MatrixXd& Q,
                           const Eigen::VectorXd& f_of_mean, bool keep, int d) {
  const Eigen::Index n = mu.size();
  const Eigen::Index m = keep ? n + d : n;
  Eigen::MatrixXd T = Eigen::MatrixXd::Zero(m, n);
  T.topLeftCorner(d, d) = F;
  T.block(d, d, n - d, n - d).setIdentity();
  if (keep) T.block(n, 0, d, d).setIdentity();
  Predicted p;
  p.sigma = T * sigma * T.transpose();
  p.sigma.topLeftCorner(d, d) += Q;
  p.mu = Eigen::VectorXd(m);
  p.mu.head(n) = mu;
  p.mu.head(d) = f_of_mean;
  if (keep) p.mu.tail(d) = mu.head(d);
  return p;
}

class ExtendedWarmStart : public ::testing::TestWithParam<bool> {};

TEST_P(ExtendedWarmStart, EqualsExactSolutionWhenPreviousWasExact) {
  const bool keep = GetParam();
  const int d = 6, blocks = 4, n = d * blocks;
  const Eigen::MatrixXd sigma = random_spd(n, 1);
  const Eigen::VectorXd mu = random_matrix(n, 1, 2);
  const Eigen::MatrixXd F = Eigen::MatrixXd::Identity(d, d) + 0.3 * random_matrix(d, d, 3);
  const Eigen::MatrixXd Q = random_spd(d, 4, 0.1);
  const Eigen::VectorXd f_of_mean = random_matrix(d, 1, 5);

  StateRecovery recovery(d);
  ASSERT_TRUE(recovery.set_solution(exact_solution(mu, sigma, d)).ok());
  ASSERT_TRUE(recovery.extend_for_prediction(F, Q, f_of_mean, keep, blocks).ok());

  const Predicted p = dense_prediction(mu, sigma, F, Q, f_of_mean, keep, d);
  const Eigen::MatrixXd expected = exact_solution(p.mu, p.sigma, d);
  ASSERT_EQ(recovery.solution().rows(), expected.rows());
  EXPECT_LT((recovery.solution() - expected).norm(), 1e-12 * expected.norm());

  // And it is the solution of the predicted information form: zero iterations, zero residual.
  const Eigen::MatrixXd lambda = p.sigma.inverse();
  const CsrMatrix csr = lambda.sparseView();
  StateRecoveryOptions options;
  options.iterations_per_step = 0;
  ASSERT_TRUE(recovery.set_options(options).ok());
  const RecoveryResult r = recovery.solve(csr, lambda * p.mu);
  ASSERT_TRUE(r.status.ok()) << r.status.to_string();
  EXPECT_LT(r.max_relative_residual, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(KeepCurrent, ExtendedWarmStart, ::testing::Bool());

TEST(StateRecovery, AugmentationCopiesTheRobotRows) {
  const int d = 3;
  const Eigen::MatrixXd sigma = random_spd(2 * d, 8);
  const Eigen::VectorXd mu = random_matrix(2 * d, 1, 9);
  StateRecovery recovery(d);
  ASSERT_TRUE(recovery.set_solution(exact_solution(mu, sigma, d)).ok());
  ASSERT_TRUE(recovery.extend_for_augmentation(2).ok());
  EXPECT_EQ(recovery.num_blocks(), 3);
  EXPECT_TRUE(recovery.solution().bottomRows(d).isApprox(recovery.solution().topRows(d)));
  // Appending anywhere but at the end is refused.
  EXPECT_EQ(recovery.extend_for_augmentation(1).code(), StatusCode::kInvalidArgument);
}

TEST(StateRecovery, ModesAgreeWithDenseSolution) {
  const int d = 6, n = 10 * d;
  const Eigen::MatrixXd lambda = random_spd(n, 12, 0.05).inverse();  // dense but SPD
  const Eigen::VectorXd eta = random_matrix(n, 1, 13);
  const Eigen::MatrixXd sigma = lambda.inverse();
  const Eigen::MatrixXd expected = exact_solution(sigma * eta, sigma, d);
  const CsrMatrix csr = lambda.sparseView();

  for (RecoveryMode mode : {RecoveryMode::kDirect, RecoveryMode::kTolerance}) {
    StateRecoveryOptions options;
    options.mode = mode;
    options.relative_tolerance = 1e-12;
    StateRecovery recovery(d, options);
    ASSERT_TRUE(recovery.set_solution(Eigen::MatrixXd::Zero(n, 1 + d)).ok());
    const RecoveryResult r = recovery.solve(csr, eta);
    ASSERT_TRUE(r.status.ok()) << to_string(mode) << ": " << r.status.to_string();
    EXPECT_LT((recovery.solution() - expected).norm(), 1e-8 * expected.norm()) << to_string(mode);
    EXPECT_LT(r.max_relative_residual, 1e-11) << to_string(mode);
    EXPECT_LT(r.column_residual_frobenius, 1e-10) << to_string(mode);
  }
  // A fixed budget is approximate; more iterations, smaller residual.
  double previous = 1e300;
  for (int k : {1, 10, 40}) {
    StateRecoveryOptions options;
    options.iterations_per_step = k;
    StateRecovery recovery(d, options);
    ASSERT_TRUE(recovery.set_solution(Eigen::MatrixXd::Zero(n, 1 + d)).ok());
    const RecoveryResult r = recovery.solve(csr, eta);
    ASSERT_TRUE(r.status.ok());
    EXPECT_EQ(r.iterations, k);
    EXPECT_LT(r.max_relative_residual, previous);
    previous = r.max_relative_residual;
  }
}

// The packed kernel on an InformationMatrix: without the final residual product the iterate is
// the same (bit for bit) and the reported residual is the recurrence's, close to the true one;
// after 0 iterations the reported residual is the true residual of the warm start itself.
TEST(StateRecovery, ResidualOptionsOfThePackedKernel) {
  const int d = 6, blocks = 8, n = blocks * d;
  const Eigen::MatrixXd dense = random_spd(n, 21, 0.05).inverse();
  InformationMatrix lambda(d);
  for (int b = 0; b < blocks; ++b) lambda.add_block();
  for (int i = 0; i < blocks; ++i) {
    for (int j = i; j < blocks; ++j) lambda.add_to_block(i, j, dense.block(i * d, j * d, d, d));
  }
  ASSERT_LT((lambda.to_dense() - dense).norm(), 1e-12 * dense.norm());
  const Eigen::VectorXd eta = random_matrix(n, 1, 22);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, 1 + d);
  rhs.col(0) = eta;
  rhs.block(0, 1, d, d).setIdentity();
  // A warm start near the solution (one worse than zero would restart from zero).
  const Eigen::MatrixXd exact = dense.ldlt().solve(rhs);
  const Eigen::MatrixXd warm = exact + 1e-3 * exact.norm() * random_matrix(n, 1 + d, 23);
  auto solve = [&](int iterations, bool recompute, RecoveryResult* result) {
    StateRecoveryOptions o;
    o.iterations_per_step = iterations;
    o.recompute_true_residual = recompute;
    o.preconditioner = RecoveryPreconditioner::kBlockJacobi;  // the packed kernel
    StateRecovery recovery(d, o);
    EXPECT_TRUE(recovery.set_solution(warm).ok());
    *result = recovery.solve(lambda, eta);
    EXPECT_TRUE(result->status.ok()) << result->status.to_string();
    return Eigen::MatrixXd(recovery.solution());
  };
  RecoveryResult with, without, zero;
  const Eigen::MatrixXd x_with = solve(5, true, &with);
  const Eigen::MatrixXd x_without = solve(5, false, &without);
  EXPECT_EQ((x_with - x_without).cwiseAbs().maxCoeff(), 0.0);
  const double true_frobenius = (rhs - dense * x_with).rightCols(d).norm();
  EXPECT_NEAR(with.column_residual_frobenius, true_frobenius, 1e-9 * true_frobenius);
  EXPECT_NEAR(without.column_residual_frobenius, true_frobenius, 1e-6 * true_frobenius);
  const Eigen::MatrixXd x_zero = solve(0, true, &zero);
  EXPECT_EQ((x_zero - warm).cwiseAbs().maxCoeff(), 0.0);  // no column restarted here
  const double warm_frobenius = (rhs - dense * warm).rightCols(d).norm();
  EXPECT_NEAR(zero.column_residual_frobenius, warm_frobenius, 1e-12 * warm_frobenius);
}

/// SPD matrix with eigenvalues log-spaced in [1, condition] and random eigenvectors: across
/// blocks, so block Jacobi cannot undo it.
Eigen::MatrixXd ill_conditioned_spd(int n, double condition, unsigned seed) {
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(random_matrix(n, n, seed));
  const Eigen::MatrixXd U = qr.householderQ();
  Eigen::VectorXd eig(n);
  for (int i = 0; i < n; ++i) eig[i] = std::pow(condition, static_cast<double>(i) / (n - 1));
  const Eigen::MatrixXd A = U * eig.asDiagonal() * U.transpose();
  return 0.5 * (A + A.transpose());
}

TEST(StateRecovery, ToleranceModeReturnsOkAtTheIterationCapWithTheResidualReached) {
  const int d = 6, n = 12 * d;
  const Eigen::MatrixXd lambda = ill_conditioned_spd(n, 1e10, 21);
  const Eigen::VectorXd eta = random_matrix(n, 1, 22);
  const CsrMatrix csr = lambda.sparseView();
  for (int cap : {3, 10}) {
    StateRecoveryOptions options;
    options.mode = RecoveryMode::kTolerance;
    options.relative_tolerance = 1e-14;
    options.max_iterations = cap;
    StateRecovery recovery(d, options);
    ASSERT_TRUE(recovery.set_solution(Eigen::MatrixXd::Zero(n, 1 + d)).ok());
    const RecoveryResult r = recovery.solve(csr, eta);
    ASSERT_TRUE(r.status.ok()) << "cap " << cap << ": " << r.status.to_string();
    EXPECT_TRUE(r.hit_iteration_cap) << "cap " << cap;
    EXPECT_EQ(r.iterations, cap);
    EXPECT_GT(r.max_relative_residual, 1e-14);
    // The reported residual is the true one of the iterate handed back.
    const Eigen::MatrixXd column_residual =
        Eigen::MatrixXd::Identity(n, d) - lambda * recovery.robot_column();
    EXPECT_NEAR(r.column_residual_frobenius, column_residual.norm(),
                1e-9 * column_residual.norm());
    const double mean_residual = (eta - lambda * recovery.mean()).norm() / eta.norm();
    EXPECT_NEAR(r.mean_relative_residual, mean_residual, 1e-9 * mean_residual);
  }
  // A reachable tolerance (well-conditioned matrix) does not report the cap.
  const Eigen::MatrixXd easy = ill_conditioned_spd(n, 1e3, 23);
  StateRecoveryOptions options;
  options.mode = RecoveryMode::kTolerance;
  options.relative_tolerance = 1e-6;
  options.max_iterations = 5000;
  StateRecovery recovery(d, options);
  ASSERT_TRUE(recovery.set_solution(Eigen::MatrixXd::Zero(n, 1 + d)).ok());
  const RecoveryResult r = recovery.solve(CsrMatrix(easy.sparseView()), eta);
  ASSERT_TRUE(r.status.ok()) << r.status.to_string();
  EXPECT_FALSE(r.hit_iteration_cap);
  EXPECT_LE(r.max_relative_residual, 1e-6);
}

TEST(StateRecovery, RejectsMismatchedSnapshotAndBadOptions) {
  StateRecovery recovery(6);
  ASSERT_TRUE(recovery.initialize(Eigen::VectorXd::Zero(6), Eigen::MatrixXd::Identity(6, 6)).ok());
  const CsrMatrix big = Eigen::MatrixXd::Identity(12, 12).sparseView();
  const RecoveryResult r = recovery.solve(big, Eigen::VectorXd::Zero(12));
  EXPECT_EQ(r.status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(r.status.message().find("warm start"), std::string::npos) << r.status.message();
  StateRecoveryOptions bad;
  bad.relative_tolerance = 0.0;
  EXPECT_EQ(recovery.set_options(bad).code(), StatusCode::kInvalidArgument);
  EXPECT_THROW(StateRecovery(6, bad), std::invalid_argument);
  StateRecoveryOptions negative_recent;
  negative_recent.kept_factor_recent_blocks = -1;
  const Status s = recovery.set_options(negative_recent);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("kept_factor_recent_blocks"), std::string::npos) << s.message();
  EXPECT_EQ(recovery.initialize(Eigen::VectorXd::Zero(5), Eigen::MatrixXd::Identity(6, 6)).code(),
            StatusCode::kInvalidArgument);
}

/// Recovery on a real pose graph's information matrix, against a dense inverse.
void check_pose_graph(const std::filesystem::path& path) {
  const PoseGraph graph = read_g2o(path.string());
  const Eigen::SparseMatrix<double> lambda = assemble_information_sparse(graph);
  const Eigen::Index n = lambda.rows();
  Eigen::VectorXd mu_file(n);
  for (size_t v = 0; v < graph.vertices.size(); ++v) {
    mu_file.segment(6 * static_cast<Eigen::Index>(v), 6) = graph.vertices[v].pose;
  }
  const Eigen::VectorXd eta = lambda * mu_file;
  const Eigen::MatrixXd sigma = Eigen::MatrixXd(lambda).inverse();
  const Eigen::MatrixXd expected = exact_solution(mu_file, sigma, 6);
  const CsrMatrix csr = lambda;

  Eigen::MatrixXd direct;
  for (RecoveryMode mode : {RecoveryMode::kDirect, RecoveryMode::kTolerance}) {
    StateRecoveryOptions options;
    options.mode = mode;
    options.relative_tolerance = 1e-12;
    StateRecovery recovery(6, options);
    ASSERT_TRUE(recovery.set_solution(Eigen::MatrixXd::Zero(n, 7)).ok());
    const RecoveryResult r = recovery.solve(csr, eta);
    ASSERT_TRUE(r.status.ok()) << to_string(mode) << ": " << r.status.to_string();
    EXPECT_LT((recovery.solution() - expected).norm(), 1e-7 * expected.norm()) << to_string(mode);
    if (mode == RecoveryMode::kDirect) {
      direct = recovery.solution();
    } else {
      EXPECT_LT((recovery.solution() - direct).norm(), 1e-7 * direct.norm()) << "PCG vs direct";
      EXPECT_GT(r.iterations, 0);
    }
  }
}

TEST(StateRecovery, TinyGrid3DMatchesDenseInverse) {
  NAV_REQUIRE_DATA(path, "posegraphs/tinyGrid3D.g2o");
  check_pose_graph(path);
}

TEST(StateRecovery, SmallGrid3DMatchesDenseInverse) {
  NAV_REQUIRE_DATA(path, "posegraphs/smallGrid3D.g2o");
  check_pose_graph(path);
}

}  // namespace
}  // namespace nav::core
