// The scaled certificate of the covariance bounds (recovery/bounds.h, K1/K2) against dense
// inverses: for random SPD Λ, exact marginal bounds and recovered columns with random errors of
// every size, the certified proposal joint dominates the exact joint (PSD difference), and the
// exact refresh resets every bound to the exact marginal plus the rounding margin.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <limits>
#include <random>
#include <utility>

#include "nav/core/recovery/bounds.h"
#include "nav/core/recovery/consistency.h"
#include "nav/core/recovery/exact_marginals.h"

namespace nav::core {
namespace {

struct Problem {
  int d = 6;
  int blocks = 6;
  Eigen::MatrixXd lambda, sigma;
};

/// SPD Λ with badly scaled units: positions ~1e2 m², angles ~1e-6 rad² in Σ; blocks of d.
Problem make_problem(unsigned seed, int d = 6) {
  Problem p;
  p.d = d;
  const int n = p.d * p.blocks;
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd A(n, n);
  for (int i = 0; i < A.size(); ++i) A(i) = normal(rng);
  Eigen::VectorXd scale(n);
  for (int i = 0; i < n; ++i) scale[i] = (i % p.d) < 3 || (i % p.d) >= 6 ? 10.0 : 1e-3;
  const Eigen::MatrixXd sigma0 = A * A.transpose() / n + 0.1 * Eigen::MatrixXd::Identity(n, n);
  p.sigma = scale.asDiagonal() * sigma0 * scale.asDiagonal();
  p.lambda = p.sigma.inverse();
  p.lambda = 0.5 * (p.lambda + p.lambda.transpose()).eval();
  p.sigma = p.lambda.inverse();
  return p;
}

/// Bounds whose every block is the exact marginal (refresh_exact of the dense Λ).
CovarianceBounds exact_bounds(const Problem& p, BoundsOptions options = {}) {
  CovarianceBounds bounds(p.d, options);
  EXPECT_TRUE(bounds.initialize_robot(p.sigma.topLeftCorner(p.d, p.d)).ok());
  for (int i = 1; i < p.blocks; ++i) EXPECT_TRUE(bounds.insert(i).ok());
  const Eigen::SparseMatrix<double> sparse = p.lambda.sparseView();
  EXPECT_TRUE(bounds.refresh_exact(ExactMarginals::compute(sparse, p.d), p.blocks).ok());
  return bounds;
}

Eigen::MatrixXd exact_joint(const Problem& p, int i) {
  const int d = p.d;
  Eigen::MatrixXd J(2 * d, 2 * d);
  J << p.sigma.block(0, 0, d, d), p.sigma.block(0, i * d, d, d), p.sigma.block(i * d, 0, d, d),
      p.sigma.block(i * d, i * d, d, d);
  return J;
}

// Blocks of 6 (pose graphs), 12 (the survey's states) and 5.
TEST(BoundsCertificate, CertifiedJointDominatesTheExactJointForRandomResiduals) {
  int checked = 0;
  for (const auto& [seed, d] : {std::pair{1u, 6}, {2u, 6}, {3u, 6}, {4u, 12}, {5u, 5}}) {
    const Problem p = make_problem(seed, d);
    const int n = p.d * p.blocks;
    std::mt19937 rng(100 + seed);
    std::normal_distribution<double> normal;
    for (double error : {1e-9, 1e-5, 1e-2, 1.0, 100.0}) {
      // X = exact column + an error in the column's own scale (relative `error`).
      Eigen::MatrixXd X = p.sigma.leftCols(p.d);
      for (int r = 0; r < n; ++r) {
        for (int c = 0; c < p.d; ++c) {
          X(r, c) += error * std::sqrt(p.sigma(r, r) * p.sigma(c, c)) * normal(rng);
        }
      }
      Eigen::MatrixXd E_r = Eigen::MatrixXd::Zero(n, p.d);
      E_r.topRows(p.d).setIdentity();
      const Eigen::MatrixXd R = E_r - p.lambda * X;
      for (bool matrix_certificate : {true, false}) {
        CovarianceBounds bounds = exact_bounds(p);
        const Eigen::MatrixXd X_rr = X.topRows(p.d);
        const Status s =
            matrix_certificate
                ? bounds.set_recovery(X_rr, R, p.blocks)
                : bounds.set_recovery(X_rr, Eigen::JacobiSVD<Eigen::MatrixXd>(R).singularValues()[0],
                                      p.blocks);
        ASSERT_TRUE(s.ok()) << s.to_string();
        EXPECT_TRUE(is_conservative(bounds.robot_bound(), p.sigma.topLeftCorner(p.d, p.d), 1e-9));
        for (int i = 1; i < p.blocks; ++i) {
          LinkProposal proposal;
          ASSERT_TRUE(bounds.propose(i, X.middleRows(i * p.d, p.d), &proposal).ok());
          double min_eig = 0.0;
          EXPECT_TRUE(is_conservative(proposal.joint, exact_joint(p, i), 1e-9, &min_eig))
              << "seed " << seed << " error " << error << " state " << i << " matrix "
              << matrix_certificate << " κ " << bounds.kappa() << " min eig " << min_eig;
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 5 * 5 * 2 * 5);
}

TEST(BoundsCertificate, KappaVanishesWithTheResidualAndK2BeatsK1OnMixedUnits) {
  const Problem p = make_problem(7);
  const int n = p.d * p.blocks;
  Eigen::MatrixXd X = p.sigma.leftCols(p.d);
  X.array() *= 1.0 + 1e-9;  // a relative error of 1e-9
  Eigen::MatrixXd E_r = Eigen::MatrixXd::Zero(n, p.d);
  E_r.topRows(p.d).setIdentity();
  const Eigen::MatrixXd R = E_r - p.lambda * X;
  BoundsOptions unfloored;  // the algebra alone: κ not floored at the rounding margin
  unfloored.rounding_margin = 0.0;
  CovarianceBounds with_matrix = exact_bounds(p, unfloored), with_norm = exact_bounds(p, unfloored);
  ASSERT_TRUE(with_matrix.set_recovery(X.topRows(p.d), R, p.blocks).ok());
  const double rho = Eigen::JacobiSVD<Eigen::MatrixXd>(R).singularValues()[0];
  ASSERT_TRUE(with_norm.set_recovery(X.topRows(p.d), rho, p.blocks).ok());
  EXPECT_GT(with_matrix.kappa(), 0.0);
  EXPECT_LT(with_matrix.kappa(), 1e-6);
  // K1 sums λmax over m² and rad² blocks alike: it is orders of magnitude looser here.
  EXPECT_LT(100.0 * with_matrix.kappa(), with_norm.kappa());
  // A zero residual certifies the recovered column as it is; by default κ keeps the rounding
  // margin (the computed residual cannot see the solve's rounding).
  CovarianceBounds exact = exact_bounds(p, unfloored);
  ASSERT_TRUE(exact.set_recovery(X.topRows(p.d), Eigen::MatrixXd::Zero(n, p.d), p.blocks).ok());
  EXPECT_EQ(exact.kappa(), 0.0);
  CovarianceBounds floored = exact_bounds(p);
  ASSERT_TRUE(floored.set_recovery(X.topRows(p.d), Eigen::MatrixXd::Zero(n, p.d), p.blocks).ok());
  EXPECT_EQ(floored.kappa(), floored.options().rounding_margin);
  EXPECT_GT(floored.kappa(), 0.0);
  // A residual of the wrong shape is refused.
  EXPECT_EQ(exact.set_recovery(X.topRows(p.d), Eigen::MatrixXd::Zero(n - 1, p.d), p.blocks).code(),
            StatusCode::kInvalidArgument);
}

TEST(BoundsCertificate, ExactRefreshIsTheMarginalPlusTheMargin) {
  const Problem p = make_problem(5);
  CovarianceBounds bounds = exact_bounds(p);
  const double tau = bounds.options().rounding_margin;
  for (int i = 1; i < p.blocks; ++i) {
    const Eigen::MatrixXd sigma_ii = p.sigma.block(i * p.d, i * p.d, p.d, p.d);
    EXPECT_TRUE(is_conservative(bounds.bound(i), sigma_ii, 0.0)) << "state " << i;
    // (1 + τ) Σ + τ diag(Σ), Σ from the dense inverse (differs from the selected one by rounding).
    Eigen::MatrixXd padded = (1.0 + tau) * sigma_ii;
    padded.diagonal() += tau * sigma_ii.diagonal();
    EXPECT_LT((bounds.bound(i) - padded).norm(), 1e-9 * sigma_ii.norm()) << "state " << i;
  }
  // Marginals of a differently sized filter are refused.
  const Eigen::SparseMatrix<double> sparse = p.lambda.sparseView();
  EXPECT_EQ(bounds.refresh_exact(ExactMarginals::compute(sparse, p.d), p.blocks + 1).code(),
            StatusCode::kInvalidArgument);
}

// A recovery job's exact marginals come from an earlier Λ with fewer states (its snapshot):
// they reset those states' bounds only; the robot and the states kept since keep theirs.
TEST(BoundsCertificate, RefreshFromAnEarlierSnapshotResetsItsStatesOnly) {
  const Problem p = make_problem(6);
  const int d = p.d, m = 4;  // the snapshot had blocks 0..3
  CovarianceBounds bounds(d);
  const Eigen::MatrixXd loose = 10.0 * p.sigma.topLeftCorner(d, d);
  ASSERT_TRUE(bounds.initialize_robot(loose).ok());
  for (int i = 1; i < p.blocks; ++i) ASSERT_TRUE(bounds.insert(i).ok());
  Eigen::MatrixXd stacked(m * d, d);
  for (int j = 0; j < m; ++j) stacked.middleRows(j * d, d) = p.sigma.block(j * d, j * d, d, d);
  ASSERT_TRUE(bounds.refresh_exact(stacked, p.blocks).ok());
  const double tau = bounds.options().rounding_margin;
  for (int i = 1; i < m; ++i) {
    Eigen::MatrixXd padded = (1.0 + tau) * stacked.middleRows(i * d, d);
    padded.diagonal() += tau * stacked.middleRows(i * d, d).diagonal();
    EXPECT_LT((bounds.bound(i) - padded).norm(), 1e-15 * padded.norm()) << "state " << i;
  }
  for (int i = m; i < p.blocks; ++i) {
    EXPECT_LT((bounds.bound(i) - loose).norm(), 1e-15 * loose.norm()) << "state " << i;
  }
  EXPECT_LT((bounds.robot_bound() - loose).norm(), 1e-15 * loose.norm());
  // Refused: more blocks than the filter has, a ragged or non-finite matrix, a missing state.
  EXPECT_EQ(bounds.refresh_exact(stacked, m - 1).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(bounds.refresh_exact(stacked.topRows(m * d - 1), p.blocks).code(),
            StatusCode::kInvalidArgument);
  Eigen::MatrixXd bad = stacked;
  bad(d, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(bounds.refresh_exact(bad, p.blocks).code(), StatusCode::kInvalidArgument);
  CovarianceBounds partial(d);
  ASSERT_TRUE(partial.initialize_robot(loose).ok());
  ASSERT_TRUE(partial.insert(1).ok());
  EXPECT_EQ(partial.refresh_exact(stacked, p.blocks).code(), StatusCode::kInvalidArgument);
}

// A prediction's rounding in Λ may raise EVERY marginal by 1 + ρ, ρ = 8 ε tr(Q⁻¹ F B Fᵀ)
// (bounds.cpp prediction_rounding): the stored bounds grow by the product at the next
// set_recovery, and an exact refresh of the current Λ starts them afresh.
TEST(BoundsCertificate, StoredBoundsGrowByThePredictionsRoundingAtTheNextRecovery) {
  const Problem p = make_problem(7);
  const int d = p.d, n = d * p.blocks;
  CovarianceBounds bounds = exact_bounds(p);
  const Eigen::MatrixXd before = bounds.bound(2);
  const Eigen::MatrixXd F = Eigen::MatrixXd::Identity(d, d);
  const Eigen::MatrixXd Q = 1e-9 * Eigen::MatrixXd::Identity(d, d);
  double growth = 1.0;
  for (int k = 0; k < 3; ++k) {
    growth *=
        1.0 + 8.0 * std::numeric_limits<double>::epsilon() * bounds.robot_bound().trace() / 1e-9;
    ASSERT_TRUE(bounds.predict_robot(F, Q, false, -1).ok());
  }
  ASSERT_GT(growth - 1.0, 1e-4);
  EXPECT_EQ(bounds.bound(2), before);  // until the next set_recovery
  const Eigen::MatrixXd sigma_rr = p.sigma.topLeftCorner(d, d);
  ASSERT_TRUE(bounds.set_recovery(sigma_rr, Eigen::MatrixXd::Zero(n, d), p.blocks).ok());
  EXPECT_LT((bounds.bound(2) - growth * before).norm(), 1e-12 * before.norm());
  ASSERT_TRUE(bounds.predict_robot(F, Q, false, -1).ok());
  const Eigen::SparseMatrix<double> sparse = p.lambda.sparseView();
  ASSERT_TRUE(bounds.refresh_exact(ExactMarginals::compute(sparse, d), p.blocks).ok());
  ASSERT_TRUE(bounds.set_recovery(sigma_rr, Eigen::MatrixXd::Zero(n, d), p.blocks).ok());
  EXPECT_LT((bounds.bound(2) - before).norm(), 1e-9 * before.norm());
}

// Exact marginals renewed from a snapshot some images old (recovery/lagged_renewal.h): they
// first grow by the rounding of the predictions since (that of the last image is applied by the
// next set_recovery, as for every bound); a state a link tightened since keeps whichever of its
// bound and the grown marginal has the smaller trace (both bound its marginal now).
TEST(BoundsCertificate, LaggedRefreshGrowsTheMarginalsAndKeepsTheTighterOfLaterLinks) {
  const Problem p = make_problem(8);
  const int d = p.d, n = d * p.blocks;
  CovarianceBounds bounds(d);
  const Eigen::MatrixXd sigma_rr = p.sigma.topLeftCorner(d, d);
  ASSERT_TRUE(bounds.initialize_robot(10.0 * sigma_rr).ok());
  for (int i = 1; i < p.blocks; ++i) ASSERT_TRUE(bounds.insert(i).ok());
  const Eigen::MatrixXd F = Eigen::MatrixXd::Identity(d, d), I = F;
  const Eigen::MatrixXd Q = 1e-9 * I, zero = Eigen::MatrixXd::Zero(n, d);
  ASSERT_TRUE(bounds.predict_robot(F, Q, false, -1).ok());
  const BoundsSnapshot snapshot = bounds.snapshot();  // the renewal's Λ
  ASSERT_TRUE(bounds.set_recovery(sigma_rr, zero, p.blocks).ok());
  // Registrations with states 2 (precise) and 3 (nearly uninformative) after the snapshot.
  for (const auto& [state, r] : {std::pair{2, 1e-8}, std::pair{3, 1e6}}) {
    LinkProposal proposal;
    ASSERT_TRUE(bounds.propose(state, p.sigma.block(state * d, 0, d, d), &proposal).ok());
    ASSERT_TRUE(bounds.update(proposal, -I, I, r * I).ok());
  }
  ASSERT_TRUE(bounds.predict_robot(F, Q, false, -1).ok());
  ASSERT_TRUE(bounds.set_recovery(sigma_rr, zero, p.blocks).ok());
  const double applied = bounds.snapshot().growth - snapshot.growth;  // the image after
  ASSERT_TRUE(bounds.predict_robot(F, Q, false, -1).ok());
  const double pending = bounds.snapshot().growth - snapshot.growth - applied;
  ASSERT_GT(applied, 1e-4);
  ASSERT_GT(pending, 1e-4);
  const Eigen::MatrixXd linked_2 = bounds.bound(2), linked_3 = bounds.bound(3);
  // The earlier marginals; state 2's inflated (an upper bound still) so that its link wins.
  Eigen::MatrixXd stacked(n, d);
  for (int j = 0; j < p.blocks; ++j) {
    stacked.middleRows(j * d, d) = p.sigma.block(j * d, j * d, d, d);
  }
  stacked.middleRows(2 * d, d) *= 1e3;
  ASSERT_TRUE(bounds.refresh_exact(stacked, p.blocks, &snapshot).ok());
  const double tau = bounds.options().rounding_margin;
  const auto grown = [&](int i) {
    Eigen::MatrixXd padded = (1.0 + tau) * stacked.middleRows(i * d, d);
    padded.diagonal() += tau * stacked.middleRows(i * d, d).diagonal();
    return Eigen::MatrixXd(std::exp(applied) * padded);
  };
  ASSERT_LT(linked_2.trace(), grown(2).trace());
  ASSERT_GT(linked_3.trace(), grown(3).trace());
  EXPECT_EQ(bounds.bound(2), linked_2);
  for (int i : {1, 3, 4, 5}) {
    EXPECT_LT((bounds.bound(i) - grown(i)).norm(), 1e-12 * grown(i).norm()) << "state " << i;
  }
  ASSERT_TRUE(bounds.set_recovery(sigma_rr, zero, p.blocks).ok());
  EXPECT_LT((bounds.bound(2) - std::exp(pending) * linked_2).norm(), 1e-12 * linked_2.norm());
}

}  // namespace
}  // namespace nav::core
