// The certificate's K3 (recovery/certificate.h) against dense inverses: a filter whose Λ grew
// from a factored Λ₀ (its robot marginalised, three states and a robot appended by a process
// chain, links between old and new states), recovered columns with random errors of every
// size. K3 bounds the exact residual energy, the certified joints dominate the exact ones, and
// K3 is tighter than K1/K2.
#include "nav/core/recovery/certificate.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <random>
#include <utility>
#include <vector>

#include "nav/core/recovery/bounds.h"
#include "nav/core/recovery/consistency.h"
#include "nav/core/recovery/factor_preconditioner.h"

namespace nav::core {
namespace {

constexpr int kD = 6;
constexpr int kOldBlocks = 40;  // Λ₀: its robot r₀ and states 1..39
constexpr int kNewStates = 2;
constexpr int kBlocks = kOldBlocks + kNewStates;  // current Λ: robot, states 1..10

Eigen::MatrixXd random_matrix(int rows, int cols, std::mt19937& rng) {
  std::normal_distribution<double> normal;
  Eigen::MatrixXd A(rows, cols);
  for (int i = 0; i < A.size(); ++i) A(i) = normal(rng);
  return A;
}

struct Grown {
  Eigen::MatrixXd lambda0, lambda, sigma;  // Λ₀ (kOldBlocks), current Λ and Σ (kBlocks)
};

/// Variables of the growth, in this order: r₀, states 1..39, new states 40 and 41, new robot.
/// Units: positions ~10 m, angles ~1e-3 rad (S), so that K1 mixes m² and rad².
Grown grow(unsigned seed) {
  std::mt19937 rng(seed);
  const int nb = kOldBlocks + kNewStates + 1, n0 = kD * kOldBlocks;
  Eigen::VectorXd s(kD);
  s << 10, 10, 10, 1e-3, 1e-3, 1e-3;
  const Eigen::MatrixXd S = s.asDiagonal(), S_inv = s.cwiseInverse().asDiagonal();
  Grown g;
  const Eigen::MatrixXd A = random_matrix(n0, n0, rng);
  Eigen::MatrixXd sigma0 = A * A.transpose() / n0 + 0.1 * Eigen::MatrixXd::Identity(n0, n0);
  for (int b = 0; b < kOldBlocks; ++b) {
    for (int c = 0; c < kOldBlocks; ++c) {
      auto block = sigma0.block(b * kD, c * kD, kD, kD);
      block = (S * block * S).eval();
    }
  }
  g.lambda0 = sigma0.inverse();
  g.lambda0 = (0.5 * (g.lambda0 + g.lambda0.transpose())).eval();
  Eigen::MatrixXd big = Eigen::MatrixXd::Zero(nb * kD, nb * kD);
  big.topLeftCorner(n0, n0) = g.lambda0;
  // A relative measurement z = x_j − F x_i (unitless after S⁻¹) with information `weight`.
  auto add_relative = [&](int i, int j, const Eigen::MatrixXd& F, double weight) {
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(kD, nb * kD);
    H.middleCols(i * kD, kD) = -S_inv * F;
    H.middleCols(j * kD, kD) = S_inv;
    big += weight * H.transpose() * H;
  };
  // Process chain r₀ -> 40 -> 41 -> robot (42), links between old and new states.
  const int chain[] = {0, kOldBlocks, kOldBlocks + 1, kOldBlocks + 2};
  for (int k = 0; k + 1 < 4; ++k) {
    const Eigen::MatrixXd F = S * (Eigen::MatrixXd::Identity(kD, kD) +
                                   0.1 * random_matrix(kD, kD, rng)) * S_inv;
    add_relative(chain[k], chain[k + 1], F, 100.0);
  }
  for (const auto& [i, j] : {std::pair{3, 40}, {5, 42}, {17, 41}, {2, 6}, {30, 42}}) {
    add_relative(i, j, Eigen::MatrixXd::Identity(kD, kD), 20.0);
  }
  // Marginalise r₀ (block 0) and reorder to [robot, 1..7, 8..10].
  const int rest = (nb - 1) * kD;
  const Eigen::MatrixXd schur =
      big.bottomRightCorner(rest, rest) -
      big.bottomLeftCorner(rest, kD) *
          big.topLeftCorner(kD, kD).llt().solve(big.topRightCorner(kD, rest));
  Eigen::PermutationMatrix<Eigen::Dynamic> perm(rest);  // rest index -> current index
  for (int b = 0; b < nb - 1; ++b) {
    const int to = b == nb - 2 ? 0 : b + 1;
    for (int k = 0; k < kD; ++k) perm.indices()[b * kD + k] = to * kD + k;
  }
  g.lambda = perm * schur * perm.transpose();
  g.lambda = (0.5 * (g.lambda + g.lambda.transpose())).eval();
  g.sigma = g.lambda.inverse();
  return g;
}

/// Bounds equal to the exact marginals; no rounding margin (the algebra alone: κ is not floored).
CovarianceBounds exact_bounds(const Grown& g) {
  BoundsOptions options;
  options.rounding_margin = 0.0;
  CovarianceBounds bounds(kD, options);
  EXPECT_TRUE(bounds.initialize_robot(g.sigma.topLeftCorner(kD, kD)).ok());
  for (int i = 1; i < kBlocks; ++i) EXPECT_TRUE(bounds.insert(i).ok());
  const Eigen::SparseMatrix<double> sparse = g.lambda.sparseView();
  EXPECT_TRUE(bounds.refresh_exact(ExactMarginals::compute(sparse, kD), kBlocks).ok());
  return bounds;
}

TEST(Certificate, GrownFilterKeepsTheOldStatesMarginalsBelowTheFactoredOnes) {
  // The premise of K3, checked on the test problem itself: Σ_OO <= Σ₀_OO.
  const Grown g = grow(11);
  const int o = kD * (kOldBlocks - 1);
  const Eigen::MatrixXd sigma0 = g.lambda0.inverse();
  EXPECT_TRUE(is_conservative(sigma0.block(kD, kD, o, o), g.sigma.block(kD, kD, o, o), 1e-9));
}

TEST(Certificate, K3BoundsTheResidualEnergyAndTheJointsAndBeatsK1K2) {
  int checked = 0;
  for (unsigned seed : {1u, 2u, 3u}) {
    const Grown g = grow(seed);
    FactorPreconditioner factor;
    const Eigen::SparseMatrix<double> lambda0 = g.lambda0.sparseView();
    ASSERT_TRUE(factor.refresh(lambda0, kD).ok());
    const Eigen::MatrixXd sigma0 = g.lambda0.inverse();
    const int n = kD * kBlocks;
    std::mt19937 rng(50 + seed);
    std::normal_distribution<double> normal;
    for (double error : {1e-9, 1e-5, 1e-2, 1.0, 100.0}) {
      Eigen::MatrixXd X = g.sigma.leftCols(kD);
      for (int r = 0; r < n; ++r) {
        for (int c = 0; c < kD; ++c) {
          X(r, c) += error * std::sqrt(g.sigma(r, r) * g.sigma(c, c)) * normal(rng);
        }
      }
      Eigen::MatrixXd E_r = Eigen::MatrixXd::Zero(n, kD);
      E_r.topRows(kD).setIdentity();
      const Eigen::MatrixXd R = E_r - g.lambda * X;
      const OldStateEnergy old_states = factor.old_state_energy(R);
      ASSERT_EQ(old_states.old_end, kOldBlocks);
      // The factor's energy is R_Oᵀ Σ₀_OO R_O over the old states (Λ₀'s robot left out).
      const int o = kD * (kOldBlocks - 1);
      const Eigen::MatrixXd R_O = R.middleRows(kD, o);
      const Eigen::MatrixXd expected = R_O.transpose() * sigma0.block(kD, kD, o, o) * R_O;
      EXPECT_LE((old_states.energy - expected).norm(), 1e-9 * expected.norm()) << "seed " << seed;
      CovarianceBounds k3 = exact_bounds(g), k12 = exact_bounds(g);
      const Eigen::MatrixXd W = k3.robot_bound();
      const double exact = std::sqrt(lambda_max_scaled(R.transpose() * g.sigma * R, W));
      ASSERT_TRUE(k3.set_recovery(X.topRows(kD), R, kBlocks, [&] { return old_states; }).ok());
      ASSERT_TRUE(k12.set_recovery(X.topRows(kD), R, kBlocks).ok());
      EXPECT_GE(k3.kappa(), exact * (1.0 - 1e-9)) << "seed " << seed << " error " << error;
      // Measured (3 seeds x 5 errors) 12-21 times the exact κ̄, K1/K2 32-45 times: K3's
      // blkdiag bound over the chain-coupled new states is what remains.
      EXPECT_LT(k3.kappa(), 0.6 * k12.kappa()) << "seed " << seed << " error " << error;
      for (int i = 1; i < kBlocks; ++i) {
        LinkProposal proposal;
        ASSERT_TRUE(k3.propose(i, X.middleRows(i * kD, kD), &proposal).ok());
        Eigen::MatrixXd J(2 * kD, 2 * kD);
        J << g.sigma.block(0, 0, kD, kD), g.sigma.block(0, i * kD, kD, kD),
            g.sigma.block(i * kD, 0, kD, kD), g.sigma.block(i * kD, i * kD, kD, kD);
        EXPECT_TRUE(is_conservative(proposal.joint, J, 1e-9))
            << "seed " << seed << " error " << error << " state " << i;
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 3 * 5 * (kBlocks - 1));
}

TEST(Certificate, MisshapenOldStateEnergyIsRefused) {
  const Grown g = grow(4);
  CovarianceBounds bounds = exact_bounds(g);
  const Eigen::MatrixXd R = Eigen::MatrixXd::Constant(kD * kBlocks, kD, 1e-3);
  const Eigen::MatrixXd sigma_rr = g.sigma.topLeftCorner(kD, kD);
  auto energy = [](int old_end, int dim) {
    return [=] { return OldStateEnergy{old_end, Eigen::MatrixXd::Identity(dim, dim)}; };
  };
  EXPECT_EQ(bounds.set_recovery(sigma_rr, R, kBlocks, energy(kBlocks + 1, kD)).code(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(bounds.set_recovery(sigma_rr, R, kBlocks, energy(kOldBlocks, kD + 1)).code(),
            StatusCode::kInvalidArgument);
  // K3 (a solve) runs only when K1 and K2 are above the rounding margin.
  int calls = 0;
  const auto counted = [&] {
    ++calls;
    return OldStateEnergy{};
  };
  CovarianceBounds floored(kD);  // default rounding margin
  ASSERT_TRUE(floored.initialize_robot(sigma_rr).ok());
  for (int i = 1; i < kBlocks; ++i) ASSERT_TRUE(floored.insert(i).ok());
  EXPECT_TRUE(floored.set_recovery(sigma_rr, 1e-20 * R, kBlocks, counted).ok());
  EXPECT_EQ(calls, 0);
  EXPECT_TRUE(floored.set_recovery(sigma_rr, R, kBlocks, counted).ok());
  EXPECT_EQ(calls, 1);
}

TEST(Certificate, KappaSquaredSplitIsTheOptimumOverOmega) {
  // min over ω of a/ω + b/(1 − ω) = (√a + √b)², against a grid.
  for (const auto& [a, b] : {std::pair{1.0, 4.0}, {1e-2, 3.0}, {2.5, 2.5}}) {
    double best = 1e300;
    for (int k = 1; k < 100000; ++k) {
      const double w = k / 100000.0;
      best = std::min(best, a / w + b / (1.0 - w));
    }
    EXPECT_NEAR(kappa_squared_split(a, b), best, 1e-6 * best);
    EXPECT_LE(kappa_squared_split(a, b), best * (1.0 + 1e-12));
  }
  EXPECT_EQ(kappa_squared_split(0.0, 0.0), 0.0);
}

// K2's sum against the dense product Rᵀ blkdiag(W, B_11, …) R restricted to the block rows it
// names.
TEST(Certificate, WeightedBlockGramIsTheDenseBlockDiagonalProduct) {
  std::mt19937 rng(8);
  for (const int d : {5, 6, 12}) {
    const int blocks = 9;
    const Eigen::MatrixXd R = random_matrix(blocks * d, d, rng);
    std::vector<Eigen::MatrixXd> B;
    for (int j = 0; j < blocks; ++j) {
      const Eigen::MatrixXd A = random_matrix(d, d, rng);
      B.push_back(A * A.transpose());
    }
    const auto bound = [&](int j) -> const Eigen::MatrixXd& { return B[static_cast<size_t>(j)]; };
    for (const auto& [first, last] : {std::pair{0, blocks}, {4, blocks}, {0, 1}}) {
      Eigen::MatrixXd D = Eigen::MatrixXd::Zero(blocks * d, blocks * d);
      D.topLeftCorner(d, d) = B[0];  // W: the robot's block, always in
      for (int j = std::max(first, 1); j < last; ++j) D.block(j * d, j * d, d, d) = B[j];
      const Eigen::MatrixXd expected = R.transpose() * D * R;
      const Eigen::MatrixXd gram = weighted_block_gram(R, first, last, B[0], bound);
      EXPECT_LT((gram - expected).norm(), 1e-12 * expected.norm())
          << "d " << d << ", blocks [" << first << ", " << last << ")";
    }
  }
}

}  // namespace
}  // namespace nav::core
