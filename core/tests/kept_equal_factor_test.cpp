// Factor kept equal to Λ (recovery/kept_equal_factor.h): after every step of a delayed-state
// filter (predictions that marginalise the robot, kept states, camera links between delayed
// states, a link to the robot) the modified factor's solve matches a dense solve of the filter's
// Λ, and so do its direct solve of the robot's covariance column and that solve together with a
// refinement step; running out of reserved slots,
// a lost block and a copy are reported, not mis-solved; a recovery in the kept-equal mode
// converges in one iteration per step on a replayed pose graph, its mean solving only the
// changed blocks; and its renewals follow their schedule.
#include "nav/core/recovery/kept_equal_factor.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <vector>

#include "nav/core/filter/esdf.h"
#include "nav/core/posegraph/g2o.h"
#include "nav/core/posegraph/replay.h"
#include "nav/core/recovery/consistency.h"
#include "nav/core/recovery/exact_marginals.h"
#include "nav/testing/data.h"

namespace nav::core {
namespace {

constexpr int kD = 6;

class RandomSource {
 public:
  explicit RandomSource(unsigned seed) : rng_(seed) {}
  Eigen::MatrixXd matrix(int rows, int cols, double scale) {
    Eigen::MatrixXd m(rows, cols);
    for (int i = 0; i < m.size(); ++i) m(i) = scale * normal_(rng_);
    return m;
  }
  int index(int below) { return std::uniform_int_distribution<int>(0, below - 1)(rng_); }

 private:
  std::mt19937 rng_;
  std::normal_distribution<double> normal_;
};

/// A linear delayed-state filter: random-walk-like process, rank-5 links.
class LinearFilter {
 public:
  LinearFilter() : esdf_(kD), random_(7) {
    EXPECT_TRUE(
        esdf_.initialize(Eigen::VectorXd::Zero(kD), Eigen::MatrixXd::Identity(kD, kD)).ok());
  }
  void predict(bool keep) {
    const Eigen::MatrixXd F = Eigen::MatrixXd::Identity(kD, kD) + random_.matrix(kD, kD, 0.05);
    const Eigen::MatrixXd q = random_.matrix(kD, kD, 0.1);
    const Eigen::MatrixXd Q = q * q.transpose() + 0.01 * Eigen::MatrixXd::Identity(kD, kD);
    ASSERT_TRUE(esdf_.predict(F * esdf_.mean().head(kD), F, Q, keep).ok());
  }
  /// A 5-row link between blocks a and b.
  void link(int a, int b) {
    const MeasJac Ha = random_.matrix(5, kD, 1.0), Hb = random_.matrix(5, kD, 1.0);
    const MeasVec z = random_.matrix(5, 1, 1.0), h = MeasVec::Zero(5);
    const MeasCov R = 0.2 * MeasCov::Identity(5, 5);
    ASSERT_TRUE(esdf_.update(a, b, z, h, Ha, Hb, R, AngleMask{}).ok());
  }
  int random_block(int below) { return 1 + random_.index(below - 1); }
  const InformationMatrix& lambda() const { return esdf_.information(); }

 private:
  Esdf esdf_;
  RandomSource random_;
};

/// ‖Λ⁻¹B − M⁻¹B‖ / ‖Λ⁻¹B‖ with a dense solve of Λ, B random with `columns` columns.
double solve_error(const KeptEqualFactor& factor, const InformationMatrix& lambda,
                   int columns = 7) {
  const Eigen::MatrixXd dense = lambda.to_dense();
  const Eigen::MatrixXd B = RandomSource(3).matrix(static_cast<int>(dense.rows()), columns, 1.0);
  const Eigen::MatrixXd expected = dense.ldlt().solve(B);
  Eigen::MatrixXd Z(B.rows(), B.cols());
  factor.apply(B, Z);
  return (Z - expected).norm() / expected.norm();
}

/// ‖Σ_{*r} − solve_robot_columns()‖ / ‖Σ_{*r}‖ with a dense inverse of Λ.
double robot_column_error(const KeptEqualFactor& factor, const InformationMatrix& lambda) {
  const Eigen::MatrixXd expected = lambda.to_dense().inverse().leftCols(kD);
  Eigen::MatrixXd Z = Eigen::MatrixXd::Constant(expected.rows(), kD, 1e3);
  factor.solve_robot_columns(Z);
  return (Z - expected).norm() / expected.norm();
}

/// The same for solve_with_robot_columns: [Λ⁻¹ r | Σ_{*r}] against a dense inverse.
double step_with_robot_column_error(const KeptEqualFactor& factor,
                                    const InformationMatrix& lambda) {
  const Eigen::MatrixXd inverse = lambda.to_dense().inverse();
  const Eigen::VectorXd r = RandomSource(5).matrix(static_cast<int>(inverse.rows()), 1, 1.0);
  Eigen::MatrixXd expected(inverse.rows(), 1 + kD);
  expected << inverse * r, inverse.leftCols(kD);
  Eigen::MatrixXd Z = Eigen::MatrixXd::Constant(expected.rows(), 1 + kD, 1e3);
  factor.solve_with_robot_columns(r, Z);
  return (Z - expected).norm() / expected.norm();
}

TEST(KeptEqualFactor, FollowsTheFiltersLambdaThroughPredictionsKeptStatesAndLinks) {
  LinearFilter filter;
  for (int k = 0; k < 4; ++k) filter.predict(true);
  KeptEqualFactor factor;
  ASSERT_TRUE(factor.factor(filter.lambda(), 40).ok());
  // One column, and widths that take 1-4 vectors of 4 and more than one pass of 16.
  for (const int columns : {1, 2, 4, 7, 13, 16, 21, 40}) {
    EXPECT_LT(solve_error(factor, filter.lambda(), columns), 1e-10) << columns << " columns";
  }
  EXPECT_LT(robot_column_error(factor, filter.lambda()), 1e-10);
  int images = 0, pivots_modified = 0, appended = 0, supernodes = 0, solved_blocks = 0;
  for (int image = 0; image < 30; ++image, ++images) {
    for (int p = 0; p < 3; ++p) filter.predict(false);  // the robot is marginalised
    filter.predict(true);                               // and kept at the image
    const int newest = filter.lambda().num_blocks() - 1;
    for (int l = 0; l < 1 + image % 3; ++l) filter.link(filter.random_block(newest), newest);
    const int a = filter.random_block(newest), b = filter.random_block(newest);
    if (image % 4 == 0 && a != b) filter.link(a, b);  // between two older states
    if (image % 5 == 0) filter.link(0, filter.random_block(newest + 1));  // a link to the robot
    ASSERT_TRUE(factor.update(filter.lambda()).ok()) << "image " << image;
    EXPECT_EQ(factor.factored_blocks(), filter.lambda().num_blocks());
    EXPECT_LT(solve_error(factor, filter.lambda()), 1e-9) << "image " << image;
    EXPECT_LT(robot_column_error(factor, filter.lambda()), 1e-9) << "image " << image;
    supernodes += factor.last_solve_supernodes();
    solved_blocks += factor.slot(0) + 1;  // the robot holds the last slot
    EXPECT_LT(step_with_robot_column_error(factor, filter.lambda()), 1e-9) << "image " << image;
    // The robot and its neighbours were replaced (the newest state's rows kept when only its
    // diagonal block changed), one state was appended, and nothing needed a downdate (the older
    // endpoints only gained link information).
    const KeptFactorUpdate& u = factor.last_update();
    EXPECT_GE(u.rows_replaced + u.pivots_modified, 2);
    pivots_modified += u.pivots_modified;
    appended += u.blocks_appended;
    EXPECT_EQ(factor.last_update().rows_added, 1);
    EXPECT_EQ(factor.last_update().downdate_rank, 0);
    if (factor.last_update().blocks_updated > 0) {
      EXPECT_LE(factor.last_update().update_rank, 5 * 4 + 5);  // rank 5 per link
    }
  }
  EXPECT_EQ(factor.spare_blocks(), 40 - images);
  // The newest state's change went to its pivot block in place except where the robot had a
  // second neighbour (a link to the robot) or the state was an end of a link between two older
  // states (22 of 30 images when written; the dense comparisons above check both paths).
  EXPECT_GE(pivots_modified, 20);
  // The appended state's rows were formed as one block at every image; the robot and the
  // re-added states, whose deleted rows left explicit zeros, went row by row.
  EXPECT_EQ(appended, images);
  // The backward passes took a good part of the blocks as supernodes (615 of 1,350 slots when
  // written: the reserved slots not taken yet are identity rows, solved column by column).
  EXPECT_GT(supernodes, solved_blocks / 3);
}

TEST(KeptEqualFactor, OrdersTheNewestStatesLastAndStillFollowsLambda) {
  LinearFilter filter;
  for (int k = 0; k < 20; ++k) {
    filter.predict(true);
    const int newest = filter.lambda().num_blocks() - 1;
    if (newest > 2) filter.link(filter.random_block(newest), newest);
  }
  const int n = filter.lambda().num_blocks(), recent = 6, spare = 8;
  KeptEqualFactor factor;
  ASSERT_TRUE(factor.factor(filter.lambda(), spare, recent).ok());
  // Blocks n-6 .. n-1 hold the six slots before the reserved ones; the robot the last.
  for (int b = 1; b < n; ++b) {
    if (b >= n - recent) {
      EXPECT_GE(factor.slot(b), n - 1 - recent) << "block " << b;
    } else {
      EXPECT_LT(factor.slot(b), n - 1 - recent) << "block " << b;
    }
  }
  EXPECT_EQ(factor.slot(0), n - 1 + spare);
  EXPECT_LT(solve_error(factor, filter.lambda()), 1e-10);
  for (int image = 0; image < spare; ++image) {
    filter.predict(false);
    filter.predict(true);
    const int newest = filter.lambda().num_blocks() - 1;
    filter.link(newest - 1 - image % 3, newest);
    filter.link(filter.random_block(newest), newest);
    ASSERT_TRUE(factor.update(filter.lambda()).ok()) << "image " << image;
    EXPECT_LT(solve_error(factor, filter.lambda()), 1e-9) << "image " << image;
    EXPECT_LT(robot_column_error(factor, filter.lambda()), 1e-9) << "image " << image;
  }
  // More recent states than states: all of them are "recent", the plain order.
  EXPECT_TRUE(factor.factor(filter.lambda(), spare, 10 * n).ok());
  EXPECT_LT(solve_error(factor, filter.lambda()), 1e-10);
  EXPECT_EQ(factor.factor(filter.lambda(), spare, -1).code(), StatusCode::kInvalidArgument);
}

TEST(KeptEqualFactor, ReportsWhatItCannotFollow) {
  LinearFilter filter;
  for (int k = 0; k < 3; ++k) filter.predict(true);
  KeptEqualFactor factor;
  ASSERT_TRUE(factor.factor(filter.lambda(), 1).ok());
  const InformationMatrix before = filter.lambda();
  filter.predict(true);
  filter.predict(true);
  EXPECT_EQ(factor.update(filter.lambda()).code(), StatusCode::kOutOfRange);
  EXPECT_TRUE(factor.has_factor());  // kept: the caller refactors
  KeptEqualFactor copy(factor);
  EXPECT_FALSE(copy.has_factor());
  ASSERT_TRUE(factor.factor(filter.lambda(), 2).ok());
  EXPECT_EQ(factor.update(before).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(KeptEqualFactor().factor(InformationMatrix(kD), 0).code(),
            StatusCode::kInvalidArgument);
  InformationMatrix indefinite(kD);
  indefinite.add_block();
  indefinite.add_to_block(0, 0, -Eigen::MatrixXd::Identity(kD, kD));
  EXPECT_EQ(factor.factor(indefinite, 0).code(), StatusCode::kNotPositiveDefinite);
  EXPECT_FALSE(factor.has_factor());
}

struct KeptReplay {
  int steps = 0, refreshes = 0;
};

/// A pose-graph replay with the kept factor, exact marginals renewed every 10 steps.
ReplayOptions kept_replay_options() {
  ReplayOptions options;
  options.recovery.preconditioner = RecoveryPreconditioner::kFactor;
  options.recovery.keep_factor_equal = true;
  options.recovery.refresh_interval = 10;
  return options;
}

/// Replays smallGrid3D with a kept-factor recovery and `refresh_residual`, checking that every
/// step converged in one iteration to the rounding floor.
KeptReplay replay_kept(const std::filesystem::path& path, double refresh_residual) {
  ReplayOptions options = kept_replay_options();
  options.recovery.iterations_per_step = 5;
  options.recovery.kept_factor_spare_blocks = 16;
  options.recovery.refresh_residual = refresh_residual;
  const PoseGraph graph = read_g2o(path.string());  // the replay refers to it
  PoseGraphReplay replay(graph, options);
  EXPECT_TRUE(replay.start().ok());
  KeptReplay out;
  while (!replay.done()) {
    RecoveryResult r;
    if (!replay.step(&r).ok()) {
      ADD_FAILURE() << r.status.to_string();
      break;
    }
    EXPECT_EQ(r.iterations, 1) << "step " << out.steps;
    EXPECT_LT(r.column_relative_residual, 1e-9) << "step " << out.steps;
    EXPECT_LT(r.mean_relative_residual, 1e-9) << "step " << out.steps;
    out.refreshes += r.refreshed ? 1 : 0;
    ++out.steps;
  }
  EXPECT_GT(out.steps, 20);
  return out;
}

TEST(KeptEqualFactor, RecoveryConvergesInOneIterationPerStepOnAReplayedPoseGraph) {
  NAV_REQUIRE_DATA(path, "posegraphs/smallGrid3D.g2o");
  // The robot's columns come from the direct solve, whose residual meets the default target:
  // exact refreshes of the bounds by the interval only, the residual never asked for one.
  const KeptReplay direct = replay_kept(path, 1e-6);
  EXPECT_EQ(direct.refreshes, (direct.steps + 9) / 10);
  // A target no solve meets: the columns are refined after the direct solve and the factor is
  // rebuilt at every step; the bounds' refreshes still follow the interval alone.
  const KeptReplay refined = replay_kept(path, 1e-300);
  EXPECT_EQ(refined.refreshes, (refined.steps + 9) / 10);
}

// The step of μ solves only the blocks of η − Λμ that changed since the previous step
// (StateRecovery::keep_changed_blocks), from a product Λμ that recomputed only the rows that
// changed (mean_product.h): most steps are such, and the mean still matches, after every step,
// that of the same replay recovered by CHOLMOD's direct solve.
TEST(KeptEqualFactor, MeanStepsOfTheChangedBlocksMatchDirectSolves) {
  NAV_REQUIRE_DATA(path, "posegraphs/smallGrid3D.g2o");
  ReplayOptions options = kept_replay_options();
  options.recovery.kept_factor_spare_blocks = 16;
  ReplayOptions direct_options;
  direct_options.recovery.mode = RecoveryMode::kDirect;
  const PoseGraph graph = read_g2o(path.string());
  PoseGraphReplay replay(graph, options), direct(graph, direct_options);
  ASSERT_TRUE(replay.start().ok());
  ASSERT_TRUE(direct.start().ok());
  int steps = 0, partial = 0, kept_products = 0;
  while (!replay.done()) {
    RecoveryResult r, reference;
    ASSERT_TRUE(replay.step(&r).ok()) << r.status.to_string();
    ASSERT_TRUE(direct.step(&reference).ok()) << reference.status.to_string();
    const int blocks = replay.filter().num_blocks();
    EXPECT_GT(r.mean_step_blocks, 0) << "step " << steps;
    EXPECT_LE(r.mean_step_blocks, blocks) << "step " << steps;
    partial += r.mean_step_blocks < blocks ? 1 : 0;
    EXPECT_LE(r.mean_product_rows, blocks) << "step " << steps;
    kept_products += r.mean_product_rows >= 0 && r.mean_product_rows < blocks ? 1 : 0;
    const Eigen::VectorXd expected = direct.recovery().mean();
    EXPECT_LT((replay.recovery().mean() - expected).norm(), 1e-9 * expected.norm())
        << "step " << steps << ", " << r.mean_step_blocks << " of " << blocks << " blocks";
    ++steps;
  }
  EXPECT_GT(partial, steps / 2) << steps << " steps";
  // Most steps recomputed only the changed rows of Λμ (115 of 124 when written).
  EXPECT_GT(kept_products, steps / 2) << steps << " steps";
}

// The renewal schedule of the kept factor (recovery_options.h refresh_growth, renewal_lag): a
// refresh at the first step and whenever the map's size passes a power of 1.5, none while
// a lagged one is in flight; every 10 steps a renewal started instead, taken 3 steps later; the
// bounds conservative at the end.
TEST(KeptEqualFactor, RenewalsFollowTheMapsGrowthThenTheIntervalWithTheirLag) {
  NAV_REQUIRE_DATA(path, "posegraphs/smallGrid3D.g2o");
  ReplayOptions options = kept_replay_options();
  options.recovery.refresh_growth = 0.5;
  options.recovery.renewal_lag = 3;
  const PoseGraph graph = read_g2o(path.string());
  PoseGraphReplay replay(graph, options);
  ASSERT_TRUE(replay.start().ok());
  // The powers of 1.5 the map's size passes: 1, 2 (1.5), 3 (2.25), 4 (3.4), 6 (5.1), 8 (7.6), ...
  std::vector<int> powers;
  for (double p = 1.0; p < 1e6; p *= 1.5) powers.push_back(static_cast<int>(std::ceil(p)));
  int since = 0, previous = 0, in_flight_age = -1, steps = 0;
  int refreshes = 0, started = 0, taken = 0;
  while (!replay.done()) {
    RecoveryResult r;
    ASSERT_TRUE(replay.step(&r).ok()) << r.status.to_string();
    const int blocks = replay.filter().num_blocks();
    bool passed = false;
    for (int p : powers) passed = passed || (previous < p && p <= blocks);
    previous = blocks;
    // The rules, step by step, in the order the recovery applies them.
    const bool refresh = in_flight_age < 0 && (steps == 0 || passed);
    if (refresh) since = 0;
    const bool take = in_flight_age >= 3;
    if (take) in_flight_age = -1;
    const bool start = since >= 10 && in_flight_age < 0;
    if (start) since = 0, in_flight_age = 0;
    EXPECT_EQ(r.refreshed, refresh) << "step " << steps << ", " << blocks << " blocks";
    EXPECT_EQ(r.renewed_earlier, take) << "step " << steps;
    EXPECT_EQ(r.renewal_started, start) << "step " << steps;
    refreshes += refresh, taken += take, started += start;
    if (in_flight_age >= 0) ++in_flight_age;
    ++since, ++steps;
  }
  EXPECT_GE(refreshes, 5);
  EXPECT_GE(taken, 3);
  EXPECT_GE(started - taken, 0);
  // The bounds renewed from the earlier Λs stay above the exact marginals of the end.
  const Esdf& filter = replay.filter();
  const ExactMarginals exact =
      ExactMarginals::compute(filter.information().to_sparse(), filter.information().block_dim());
  for (int b = 1; b < filter.num_blocks(); ++b) {
    double min_eig = 0.0;
    EXPECT_TRUE(is_conservative(replay.bounds().bound(b), exact.marginal(b), 1e-9, &min_eig))
        << "state " << b << ": " << min_eig;
  }
}

}  // namespace
}  // namespace nav::core
