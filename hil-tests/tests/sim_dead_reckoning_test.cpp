// The replay's dead-reckoning twin is the baseline of "SLAM against dead reckoning": it must be
// the best dead reckoning the sensors allow, not the SLAM filter's recovery without links. On a
// simulated dive through the replay library (dive-log source, decoders, time ordering, the twin
// on its worker thread), one step of the twin's recovery (what it runs at every image to set
// the means its predictions are linearised at) must give the direct solve of its Λ μ = η, and
// its final XY error must lie inside its exact marginal's 99.9 % ellipse. A recovery that has
// not converged (block Jacobi at 5 iterations per image on a chain of 100 delayed states)
// fails the first check by metres: 6.9 m on this dive.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "nav/core/navigation/chi_square.h"
#include "nav/daemon/replay/dive_replay.h"
#include "support/sim_dive.h"

namespace nav::sim::test {
namespace {

const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new ScratchCleanup);

TEST(SimDeadReckoning, TwinMeansAreTheDirectSolveAndItsErrorIsInsideItsMarginal) {
  const auto dir = scratch_dir("dead_reckoning");
  simulate_dive(sim_options(dir, 5, 100), sim_config_path().string());
  const daemon::NavdConfig cfg = daemon::load_config_file((dir / "config.yaml").string());
  daemon::ReplayRun run = daemon::run_replay((dir / "dive.lcmlog").string(), cfg, {});
  ASSERT_TRUE(run.error.empty()) << run.error;
  ASSERT_NE(run.dead_reckoning, nullptr);
  daemon::NavFilter& dr = *run.dead_reckoning;
  EXPECT_EQ(dr.counters().links_accepted, 0u);
  ASSERT_EQ(dr.images().size(), 100u);

  // analyse() runs one more step of the twin's recovery, which sets its means, then solves
  // Λ μ = η by sparse Cholesky (the reference).
  const daemon::ReplayAnalysis a = daemon::analyse(dr);
  const Eigen::VectorXd filter_mean = dr.esdf().mean();
  ASSERT_TRUE(a.error.empty()) << a.error;
  ASSERT_EQ(a.states.size(), 100u);
  const int d = dr.esdf().block_dim();
  double worst_m = 0.0;
  for (const daemon::StateCheck& s : a.states) {
    const auto xy = filter_mean.segment(s.state * d, 2) - s.mean.head(2);
    worst_m = std::max(worst_m, xy.cwiseAbs().maxCoeff());
  }
  std::printf(
      "dead reckoning: worst |filter mean - direct solve| of the delayed states' xy %.3g m\n",
      worst_m);
  EXPECT_LT(worst_m, 1e-4) << "the twin's means are not the solution of its own Λ μ = η";

  const daemon::StateCheck* newest = nullptr;
  for (const daemon::StateCheck& s : a.states)
    if (s.image && (!newest || s.image->frame_id > newest->image->frame_id)) newest = &s;
  ASSERT_NE(newest, nullptr);
  const auto images = read_csv(dir / "images.csv");  // frame_id,t_us,x,y,...
  const auto& truth = images.at(newest->image->frame_id);
  const Eigen::Vector2d e(newest->mean[0] - truth[2], newest->mean[1] - truth[3]);
  const double nees2 = e.dot(newest->exact.topLeftCorner<2, 2>().ldlt().solve(e));
  std::printf("dead reckoning: final XY error %.3f m, NEES %.2f (2 dof)\n", e.norm(), nees2);
  EXPECT_LT(nees2, core::chi_square_quantile(0.999, 2));
}

}  // namespace
}  // namespace nav::sim::test
