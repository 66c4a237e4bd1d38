// Covariance bounds (recovery/bounds.h, Algorithm 1 of Eustice et al. RSS 2005): a scalar case
// by hand, then a dense linear-Gaussian delayed-state filter where the exact covariance is
// known, with exact and truncated recoveries, certified and not.
#include "nav/core/recovery/bounds.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <random>

#include "nav/core/recovery/consistency.h"
#include "nav/core/recovery/state_recovery.h"

namespace nav::core {
namespace {

TEST(CovarianceBounds, ScalarKalmanUpdateByHand) {
  // Σ_rr = 2, Σ_ir = 1, Σ~_ii = 3, z = x_i - x_r with R = 1:
  // S = 2 - 2 + 3 + 1 = 4, P Hᵀ = [-1; 2], Σ~_ii+ = 3 - 2·2/4 = 2.
  CovarianceBounds bounds(1, BoundsOptions{false});
  ASSERT_TRUE(bounds.initialize_robot(Eigen::MatrixXd::Constant(1, 1, 3.0)).ok());
  ASSERT_TRUE(bounds.insert(1).ok());
  EXPECT_DOUBLE_EQ(bounds.bound(1)(0, 0), 3.0);
  ASSERT_TRUE(bounds.set_recovery(Eigen::MatrixXd::Constant(1, 1, 2.0), 0.0, 2).ok());
  LinkProposal p;
  ASSERT_TRUE(bounds.propose(1, Eigen::MatrixXd::Constant(1, 1, 1.0), &p).ok());
  Eigen::Matrix2d expected_joint;
  expected_joint << 2, 1, 1, 3;
  EXPECT_TRUE(p.joint.isApprox(Eigen::MatrixXd(expected_joint)));
  ASSERT_TRUE(bounds
                  .update(p, Eigen::MatrixXd::Constant(1, 1, -1.0),
                          Eigen::MatrixXd::Constant(1, 1, 1.0), Eigen::MatrixXd::Identity(1, 1))
                  .ok());
  EXPECT_NEAR(bounds.bound(1)(0, 0), 2.0, 1e-15);
}

TEST(CovarianceBounds, RobotUpdateIsTheKalmanUpdateOfTheBound) {
  // 2-dim robot, prior bound diag(4, 1), measurement of x0 with variance 1: the posterior
  // variance of x0 is 4 - 16/5 = 0.8, x1 unchanged (uncorrelated).
  CovarianceBounds bounds(2);
  ASSERT_TRUE(bounds.initialize_robot(Eigen::Vector2d(4.0, 1.0).asDiagonal().toDenseMatrix()).ok());
  Eigen::MatrixXd H(1, 2);
  H << 1.0, 0.0;
  ASSERT_TRUE(bounds.update_robot(H, Eigen::MatrixXd::Identity(1, 1)).ok());
  EXPECT_NEAR(bounds.robot_bound()(0, 0), 0.8, 1e-12);
  EXPECT_NEAR(bounds.robot_bound()(1, 1), 1.0, 1e-12);
  EXPECT_NEAR(bounds.robot_bound()(0, 1), 0.0, 1e-12);
  EXPECT_FALSE(bounds.update_robot(Eigen::MatrixXd::Identity(1, 3), Eigen::MatrixXd::Identity(1, 1)).ok());
}

TEST(CovarianceBounds, CertifiedInflationFollowsTheResidual) {
  CovarianceBounds bounds(2);
  ASSERT_TRUE(bounds.initialize_robot(Eigen::Matrix2d::Identity() * 4.0).ok());
  ASSERT_TRUE(bounds.insert(1).ok());
  // L = λmax(B_11) + λmax(B_rr) = 4 + 4, W = B_rr = 4 I, ρ = 0.1 (K1):
  // κ² = L ρ² λmax(W⁻¹) = 8 · 0.01 / 4.
  ASSERT_TRUE(bounds.set_recovery(Eigen::Matrix2d::Identity(), 0.1, 2).ok());
  EXPECT_DOUBLE_EQ(bounds.certificate_lambda(), 8.0);
  const double kappa = std::sqrt(0.02);
  EXPECT_NEAR(bounds.kappa(), kappa, 1e-15);
  LinkProposal p;
  ASSERT_TRUE(bounds.propose(1, Eigen::Matrix2d::Zero(), &p).ok());
  EXPECT_NEAR(p.kappa, kappa, 1e-15);
  EXPECT_NEAR(p.joint(0, 0), 1.0 + 2.0 * kappa * 4.0, 1e-14);  // Σ^_rr + 2κ W
  EXPECT_NEAR(p.joint(2, 2), (1.0 + kappa) * 4.0, 1e-14);      // (1 + κ) Σ~_ii
  // The robot bound tightened to Σ^_rr + κ W (smaller trace than 4 I).
  EXPECT_NEAR(bounds.robot_bound()(0, 0), 1.0 + 4.0 * kappa, 1e-14);
}

/// rr + ii − ir − irᵀ of the first two elements, read from propose()'s joint.
Eigen::Matrix2d offset_from_joint(const LinkProposal& p, int d) {
  const Eigen::Matrix2d rr = p.joint.block<2, 2>(0, 0);
  const Eigen::Matrix2d ii = p.joint.block<2, 2>(d, d);
  const Eigen::Matrix2d ir = p.joint.block<2, 2>(d, 0);
  return rr + ii - ir - ir.transpose();
}

TEST(CovarianceBounds, OffsetCovarianceEqualsTheOneOfTheProposalJoint) {
  // Random SPD robot bound, certified inflation, one state tightened within the snapshot (its
  // snapshot bound is used): the 2x2 shortcut must give exactly the joint's numbers.
  std::mt19937 rng(11);
  std::normal_distribution<double> n01;
  const int d = 6;
  Eigen::MatrixXd A(d, d);
  for (int i = 0; i < A.size(); ++i) A(i) = n01(rng);
  const Eigen::MatrixXd P0 = A * A.transpose() + Eigen::MatrixXd::Identity(d, d);
  CovarianceBounds bounds(d);
  ASSERT_TRUE(bounds.initialize_robot(P0).ok());
  ASSERT_TRUE(bounds.insert(1).ok());
  ASSERT_TRUE(bounds.insert(2).ok());
  ASSERT_TRUE(bounds.set_recovery(0.5 * P0, 0.03, 3).ok());
  Eigen::MatrixXd sigma_ir(d, d);
  for (int i = 0; i < sigma_ir.size(); ++i) sigma_ir(i) = 0.1 * n01(rng);
  LinkProposal first;
  ASSERT_TRUE(bounds.propose(1, sigma_ir, &first).ok());
  Eigen::MatrixXd H_r = Eigen::MatrixXd::Zero(2, d), H_i = Eigen::MatrixXd::Zero(2, d);
  H_r.leftCols(2) = -Eigen::Matrix2d::Identity();
  H_i.leftCols(2) = Eigen::Matrix2d::Identity();
  ASSERT_TRUE(bounds.update(first, H_r, H_i, 0.01 * Eigen::MatrixXd::Identity(2, 2)).ok());
  for (int state : {1, 2}) {
    LinkProposal p;
    ASSERT_TRUE(bounds.propose(state, sigma_ir, &p).ok());
    Eigen::Matrix2d shortcut;
    const Eigen::Matrix2d sigma_ir_xy = sigma_ir.topLeftCorner<2, 2>();
    ASSERT_TRUE(bounds.offset_covariance_2d(state, sigma_ir_xy, &shortcut).ok());
    EXPECT_EQ(shortcut, offset_from_joint(p, d)) << "state " << state;
  }
  Eigen::Matrix2d unused;
  EXPECT_EQ(bounds.offset_covariance_2d(7, Eigen::Matrix2d::Zero(), &unused).code(),
            StatusCode::kUnknownState);
}

TEST(CovarianceBounds, RejectsMissingStatesAndBadInput) {
  CovarianceBounds bounds(6);
  EXPECT_EQ(bounds.insert(1).code(), StatusCode::kInvalidArgument);  // no robot yet
  ASSERT_TRUE(bounds.initialize_robot(Mat6::Identity()).ok());
  EXPECT_EQ(bounds.insert(0).code(), StatusCode::kInvalidArgument);  // block 0 is the robot
  // Three states in the filter but no delayed bounds: the certificate would be void.
  const Status s = bounds.set_recovery(Mat6::Identity(), 0.0, 3);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("every state"), std::string::npos) << s.message();
  LinkProposal p;
  EXPECT_EQ(bounds.propose(4, Mat6::Zero(), &p).code(), StatusCode::kUnknownState);
  EXPECT_THROW(bounds.bound(4), std::out_of_range);
}

/// A dense linear-Gaussian delayed-state filter in covariance form (ground truth) driving the
/// recovery and the bounds exactly as the replay does: predict (keep) -> recover -> bounds
/// (propose + update per link) -> filter update.
struct DenseRun {
  int checked = 0;
  int conservative = 0;
  double worst_min_eig = 1e300;
  int failed_updates = 0;  ///< joint not PSD enough for a Kalman update (stale recovery)
};

DenseRun run_dense(int budget, bool certify, bool direct, unsigned seed,
                   bool matrix_certificate = false) {
  const int d = 6, steps = 25;
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  auto random = [&](int r, int c, double s) {
    Eigen::MatrixXd m(r, c);
    for (int i = 0; i < r; ++i)
      for (int j = 0; j < c; ++j) m(i, j) = s * normal(rng);
    return m;
  };
  auto spd = [&](int n, double s) {
    Eigen::MatrixXd a = random(n, n, 1.0);
    return Eigen::MatrixXd(s * (a * a.transpose() / n + 0.2 * Eigen::MatrixXd::Identity(n, n)));
  };
  Eigen::MatrixXd sigma = spd(d, 0.01);
  Eigen::VectorXd mu = random(d, 1, 1.0);
  StateRecoveryOptions ro;
  ro.mode = direct ? RecoveryMode::kDirect : RecoveryMode::kFixedIterations;
  ro.iterations_per_step = budget;
  StateRecovery recovery(d, ro);
  CovarianceBounds bounds(d, BoundsOptions{certify});
  DenseRun run;
  EXPECT_TRUE(recovery.initialize(mu, sigma).ok());
  EXPECT_TRUE(bounds.initialize_robot(sigma).ok());
  for (int step = 0; step < steps; ++step) {
    const int n = static_cast<int>(mu.size());
    const Eigen::MatrixXd F = Eigen::MatrixXd::Identity(d, d) + random(d, d, 0.1);
    const Eigen::MatrixXd Q = spd(d, 0.05);
    // Ground truth: keep x_t as the last block, f(x_t) in block 0.
    Eigen::MatrixXd T = Eigen::MatrixXd::Zero(n + d, n);
    T.topLeftCorner(d, d) = F;
    T.block(d, d, n - d, n - d).setIdentity();
    T.block(n, 0, d, d).setIdentity();
    const Eigen::VectorXd f_of_mean = F * mu.head(d);
    Eigen::VectorXd mu_new = T * mu;
    mu_new.head(d) = f_of_mean;
    sigma = T * sigma * T.transpose();
    sigma.topLeftCorner(d, d) += Q;
    mu = mu_new;
    const int kept = n / d;
    EXPECT_TRUE(recovery.extend_for_prediction(F, Q, f_of_mean, true, kept).ok());
    EXPECT_TRUE(bounds.predict_robot(F, Q, true, kept).ok());

    const Eigen::MatrixXd lambda = sigma.inverse();
    const CsrMatrix csr = lambda.sparseView();
    const RecoveryResult r = recovery.solve(csr, lambda * mu);
    EXPECT_TRUE(r.status.ok()) << r.status.to_string();
    EXPECT_TRUE((matrix_certificate
                     ? bounds.set_recovery(recovery.robot_covariance(), recovery.column_residual(),
                                           recovery.num_blocks())
                     : bounds.set_recovery(recovery.robot_covariance(), r.column_residual_spectral,
                                           recovery.num_blocks()))
                    .ok());
    // Links from the robot to up to two random older states (one of them possibly twice).
    std::uniform_int_distribution<int> pick(1, kept);
    std::vector<int> targets{pick(rng), pick(rng)};
    targets.push_back(targets[0]);
    std::vector<Eigen::MatrixXd> Hs;
    for (int i : targets) {
      const Eigen::MatrixXd H_r = random(d, d, 1.0), H_i = random(d, d, 1.0);
      const Eigen::MatrixXd R = spd(d, 0.02);
      LinkProposal p;
      EXPECT_TRUE(bounds.propose(i, recovery.cross_covariance(i), &p).ok());
      const Status updated = bounds.update(p, H_r, H_i, R);
      if (!updated.ok()) ++run.failed_updates;
      // A certified joint is >= the true one, hence PSD: its update cannot fail.
      EXPECT_TRUE(updated.ok() || !certify) << updated.to_string();
      // Ground truth covariance update with the same linear measurement.
      Eigen::MatrixXd H = Eigen::MatrixXd::Zero(d, sigma.rows());
      H.leftCols(d) = H_r;
      H.middleCols(i * d, d) = H_i;
      const Eigen::MatrixXd S = H * sigma * H.transpose() + R;
      sigma -= sigma * H.transpose() * S.ldlt().solve(H * sigma);
      sigma = 0.5 * (sigma + sigma.transpose()).eval();
    }
  }
  for (int i = 1; i < static_cast<int>(mu.size()) / d; ++i) {
    double min_eig = 0.0;
    const bool ok = is_conservative(bounds.bound(i), sigma.block(i * d, i * d, d, d), 1e-9,
                                    &min_eig);
    ++run.checked;
    run.conservative += ok ? 1 : 0;
    run.worst_min_eig = std::min(run.worst_min_eig, min_eig);
  }
  double min_eig = 0.0;
  ++run.checked;
  run.conservative +=
      is_conservative(bounds.robot_bound(), sigma.topLeftCorner(d, d), 1e-9, &min_eig) ? 1 : 0;
  return run;
}

TEST(CovarianceBounds, ConservativeWithExactRecovery) {
  for (bool certify : {false, true}) {
    const DenseRun run = run_dense(0, certify, /*direct=*/true, 42);
    EXPECT_EQ(run.failed_updates, 0);
    EXPECT_EQ(run.conservative, run.checked) << "certify " << certify << ", worst min eig "
                                             << run.worst_min_eig;
  }
}

TEST(CovarianceBounds, CertifiedBoundsStayConservativeUnderTruncatedCg) {
  for (bool matrix : {false, true}) {
    for (int budget : {0, 1, 2, 5}) {
      for (unsigned seed : {1u, 2u, 3u}) {
        const DenseRun run = run_dense(budget, /*certify=*/true, false, seed, matrix);
        EXPECT_EQ(run.conservative, run.checked) << "budget " << budget << " seed " << seed
                                                 << " matrix certificate " << matrix
                                                 << ", worst min eig " << run.worst_min_eig;
      }
    }
  }
}

TEST(CovarianceBounds, UncertifiedBoundsBreakUnderTruncatedCg) {
  // The reason for the certificate: with no iterations the paper's bounds trust a stale Σ_rr
  // and some become over-confident (or the proposal joint is not even PSD and the Kalman
  // update of the bound is refused).
  int broken = 0, checked = 0;
  for (unsigned seed : {1u, 2u, 3u}) {
    const DenseRun run = run_dense(0, /*certify=*/false, false, seed);
    broken += run.checked - run.conservative + run.failed_updates;
    checked += run.checked;
  }
  EXPECT_GT(broken, 0) << "of " << checked;
}

}  // namespace
}  // namespace nav::core
