// check_time_of_use (recovery/time_of_use.h) against a dense inverse of Λ on tinyGrid3D: the
// Fig. 3 log-det ratios recomputed independently, every bound and joint conservative with an
// exact recovery, and a robot bound below its marginal caught.
#include "nav/core/recovery/time_of_use.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "nav/core/posegraph/replay.h"
#include "nav/core/recovery/consistency.h"
#include "nav/testing/data.h"

namespace nav::core {
namespace {

constexpr int kD = 6;

/// tinyGrid3D up to its last step's recovery: the moment its links are proposed.
struct AtLastProposal {
  PoseGraph graph;
  std::unique_ptr<PoseGraphReplay> replay;

  explicit AtLastProposal(const std::string& path) : graph(read_g2o(path)) {
    ReplayOptions o;
    o.recovery.mode = RecoveryMode::kDirect;
    replay = std::make_unique<PoseGraphReplay>(graph, o);
    EXPECT_TRUE(replay->start().ok());
    while (replay->next_vertex() + 1 < replay->num_vertices()) EXPECT_TRUE(replay->step().ok());
    EXPECT_TRUE(replay->predict().ok());
    EXPECT_TRUE(replay->recover().status.ok());
  }
};

/// Fig. 3's ratio for (robot, i) from a dense inverse of Λ, with our joint from propose().
double dense_reference_ratio(const PoseGraphReplay& r, int i) {
  const Eigen::MatrixXd sigma = r.filter().information().to_dense().inverse();
  Mat12 exact;
  exact << sigma.block(0, 0, kD, kD), sigma.block(0, kD * i, kD, kD),
      sigma.block(kD * i, 0, kD, kD), sigma.block(kD * i, kD * i, kD, kD);
  LinkProposal p;
  EXPECT_TRUE(r.bounds().propose(i, r.recovery().cross_covariance(i), &p).ok());
  const Vec6 x_r = r.filter().mean_block(0).head<6>();
  const Vec6 x_i = r.filter().mean_block(i).head<6>();
  return logdet_ratio(relative_pose_covariance(Mat12(p.joint), x_r, x_i),
                      relative_pose_covariance(exact, x_r, x_i));
}

TEST(TimeOfUse, MatchesDenseInverseAndIsConservativeWithAnExactRecovery) {
  NAV_REQUIRE_DATA(path, "posegraphs/tinyGrid3D.g2o");
  const AtLastProposal at(path.string());
  const PoseGraphReplay& r = *at.replay;
  TimeOfUseStats stats;
  check_time_of_use(r.filter(), r.bounds(), r.recovery(), {}, stats);
  const int states = r.filter().num_blocks() - 1;
  ASSERT_GE(states, 7);
  EXPECT_EQ(stats.checks, 1);
  EXPECT_EQ(stats.bounds_checked, states + 1);  // the robot and every delayed state
  EXPECT_EQ(stats.joints_checked, states);
  EXPECT_DOUBLE_EQ(stats.bounds_conservative_fraction(), 1.0);
  EXPECT_DOUBLE_EQ(stats.joints_conservative_fraction(), 1.0);
  EXPECT_GE(stats.worst_min_eigenvalue, -1e-12);
  ASSERT_EQ(stats.pairs.size(), static_cast<std::size_t>(states));
  ASSERT_EQ(stats.markov_blanket().size(), static_cast<std::size_t>(states));
  for (const TimeOfUsePair& p : stats.pairs) {
    EXPECT_EQ(p.check, 1);
    EXPECT_NEAR(p.ours, dense_reference_ratio(r, p.state), 1e-8) << "state " << p.state;
    EXPECT_GE(p.ours, -1e-8) << "state " << p.state;  // conservative joint: never below exact
  }
  // A second check accumulates.
  check_time_of_use(r.filter(), r.bounds(), r.recovery(), {1e-9, false}, stats);
  EXPECT_EQ(stats.checks, 2);
  EXPECT_EQ(stats.ours().size(), 2u * states);
  EXPECT_EQ(stats.markov_blanket().size(), static_cast<std::size_t>(states));
  EXPECT_EQ(stats.pairs.back().check, 2);
}

TEST(TimeOfUse, CatchesARobotBoundBelowItsMarginal) {
  NAV_REQUIRE_DATA(path, "posegraphs/tinyGrid3D.g2o");
  const AtLastProposal at(path.string());
  const PoseGraphReplay& r = *at.replay;
  const Eigen::MatrixXd sigma = r.filter().information().to_dense().inverse();
  CovarianceBounds overconfident = r.bounds();
  // A robot measurement the filter never saw: B_rr falls far below Σ_rr.
  const Eigen::MatrixXd sigma_rr = sigma.topLeftCorner(kD, kD);
  ASSERT_TRUE(overconfident.update_robot(Eigen::MatrixXd::Identity(kD, kD), 1e-3 * sigma_rr).ok());
  TimeOfUseStats stats;
  check_time_of_use(r.filter(), overconfident, r.recovery(), {1e-9, false}, stats);
  EXPECT_EQ(stats.bounds_conservative, stats.bounds_checked - 1);
  EXPECT_LT(stats.worst_min_eigenvalue, 0.0);
}

TEST(TimeOfUse, RejectsBlocksSmallerThanAPose) {
  Esdf filter(3);
  CovarianceBounds bounds(3);
  StateRecovery recovery(3);
  TimeOfUseStats stats;
  EXPECT_THROW(check_time_of_use(filter, bounds, recovery, {}, stats), std::invalid_argument);
}

}  // namespace
}  // namespace nav::core
