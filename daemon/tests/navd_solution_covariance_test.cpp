// navd's published pose covariance: from the first estimate on, the SolutionBoard
// that Publisher turns into nav_solution_t.pose_covariance carries the robot's marginal, not
// the identity placeholder (a ±1 m / ±57° bound at dive start). Before the first delayed state
// it must equal the exact marginal of the filter's Λ (CHOLMOD selected inversion,
// core::ExactMarginals: computed independently of navd's Λ_rr⁻¹), be symmetric positive
// definite and sized like the filter's prior (NavFilterOptions: xy 0.01 m, attitude 10x the
// sensor sigmas, velocity 0.5 m/s); afterwards it is the filter's current robot covariance
// (NavFilter::robot_covariance(), tested against the dense marginal in core's tests).
// LinkPublisher is compiled into this test (daemon/CMakeLists.txt) and fed a synthetic dive
// (support/synthetic_dive.h) on config/sim.yaml, LCM memq://.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <string>

#include "nav/core/navigation/nav_filter.h"
#include "nav/core/recovery/exact_marginals.h"
#include "nav/daemon/config/config.h"
#include "nav/daemon/filter/filter_options.h"
#include "nav/daemon/service/link_publisher.h"
#include "nav/daemon/service/solution_board.h"
#include "support/synthetic_dive.h"

namespace nav::daemon::service {
namespace {

constexpr double kDeg = M_PI / 180.0;

daemon::NavdConfig memq_sim_config() {
  daemon::NavdConfig config =
      nav::testing::synthetic_dive_config(std::string(NAV_SOURCE_DIR) + "/config/sim.yaml");
  config.lcm.url = "memq://";
  return config;
}

void expect_symmetric_positive_definite(const core::Mat12& m) {
  EXPECT_LE((m - m.transpose()).norm(), 1e-12 * m.norm());
  const Eigen::SelfAdjointEigenSolver<core::Mat12> eigen(m);
  EXPECT_GT(eigen.eigenvalues().minCoeff(), 0.0) << m;
}

/// The first published covariance: the prior's size after a few updates, not the identity.
void expect_sized_like_the_prior(const core::Mat12& sigma) {
  const core::Vec12 sd = sigma.diagonal().cwiseSqrt();
  std::printf(
      "first published sigma: x %.4f y %.4f z %.4f m, roll %.3f pitch %.3f heading "
      "%.3f deg, u %.3f m/s\n",
      sd(0), sd(1), sd(2), sd(3) / kDeg, sd(4) / kDeg, sd(5) / kDeg, sd(6));
  EXPECT_GT(sd(0), 0.005);  // initial_xy_sigma_m 0.01 plus process noise
  EXPECT_LT(sd(0), 0.05);
  EXPECT_LT(sd(1), 0.05);
  EXPECT_LT(sd(2), 0.1 + 1e-9);  // depth prior 10 x 0.01 m, then updates
  for (int k = 3; k < 6; ++k) EXPECT_LT(sd(k), 1.0 * kDeg + 1e-9);  // 10 x 0.1 deg
  EXPECT_LT(sd(6), 0.5 + 1e-9);                                     // initial_velocity_sigma_mps
  EXPECT_GT((sigma - core::Mat12::Identity()).norm(), 0.9);
}

TEST(NavdSolutionCovariance, IsTheRobotMarginalFromTheFirstEstimate) {
  const daemon::NavdConfig config = memq_sim_config();
  nav::testing::SyntheticDiveOptions dive_options;
  dive_options.duration_s = 20.0;
  dive_options.image_period_s = 4.0;
  const nav::testing::SyntheticDive dive = nav::testing::make_synthetic_dive(config, dive_options);
  daemon::NavFilter filter(daemon::filter_options_from_config(config), &dive.registrations);
  SolutionBoard board;
  LinkPublisher links(config.lcm, board);
  int robot_only = 0, recovered = 0;
  for (const daemon::Measurement& m : dive.measurements) {
    ASSERT_TRUE(filter.process(m).ok());
    links.on_measurement(filter);
    const SolutionView view = board.read();
    if (!filter.initialised()) {
      EXPECT_FALSE(view.has_estimate);  // nothing published before the first estimate
      continue;
    }
    ASSERT_TRUE(view.has_estimate);
    if (filter.esdf().num_blocks() == 1) {
      const Eigen::MatrixXd exact =
          core::ExactMarginals::compute(filter.esdf().information().to_sparse(), 12)
              .marginal(core::Esdf::kRobotBlock);
      ASSERT_EQ(exact.rows(), 12);
      EXPECT_LE((view.robot_covariance - exact).norm(), 1e-9 * exact.norm())
          << "published\n"
          << view.robot_covariance << "\nexact\n"
          << exact;
      expect_symmetric_positive_definite(view.robot_covariance);
      if (robot_only++ == 0) expect_sized_like_the_prior(view.robot_covariance);
    } else if (!filter.images().empty()) {
      EXPECT_EQ(view.robot_covariance, filter.robot_covariance());
      ++recovered;
    }
  }
  EXPECT_GT(robot_only, 10);  // before the first image is kept (DVL, attitude, depth at 1-5 Hz)
  EXPECT_GT(recovered, 10);   // after it: the propagated recovered covariance
}

TEST(NavdSolutionCovariance, RobotOnlyCovarianceGivesBackTheInitialCovariance) {
  core::Esdf esdf(12);
  EXPECT_FALSE(robot_only_covariance(esdf).has_value());  // no block at all
  core::Mat12 P0 = core::Vec12::LinSpaced(1e-4, 2.0).asDiagonal();
  P0(0, 5) = P0(5, 0) = 0.5 * std::sqrt(P0(0, 0) * P0(5, 5));  // a correlation of 0.5
  ASSERT_TRUE(esdf.initialize(core::Vec12::Zero(), P0).ok());
  const std::optional<core::Mat12> sigma = robot_only_covariance(esdf);
  ASSERT_TRUE(sigma.has_value());
  EXPECT_LE((*sigma - P0).norm(), 1e-10 * P0.norm()) << *sigma;
}

}  // namespace
}  // namespace nav::daemon::service
