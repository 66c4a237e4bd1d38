// Regression test of commit 05138fc (NavFilter::relinearise_robot): the O(1) robot
// relinearisation used to wrap the mean's angles to (-pi, pi] while the information vector η
// stayed on the other branch, so the next update shifted η_r by 2π·Hᵀ R⁻¹ H and the whole
// estimate jumped (5.4 m in one turn of the default dive) whenever an update moved the heading
// across ±π. Synthetic dives (support/synthetic_dive.h, config/sim.yaml's sensors) heading
// south, where the 0.1 deg heading noise puts the measurements and the estimate on both sides
// of ±π many times, and circling through south several times: the estimate must not jump.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "nav/daemon/config/config.h"
#include "nav/daemon/filter/filter_options.h"
#include "nav/core/navigation/nav_filter.h"
#include "support/synthetic_dive.h"

namespace nav::daemon {
namespace {

struct WrapRun {
  int truth_wraps = 0;            ///< true heading crossings of ±π between images
  int estimate_side_changes = 0;  ///< sign changes of the estimated heading near ±π
  double max_xy_error_m = 0.0;    ///< running robot estimate at each image vs truth
  double max_xy_step_m = 0.0;     ///< largest change of that error between images
  double max_heading_error_rad = 0.0;
};

WrapRun run(const nav::testing::SyntheticDiveOptions& o, bool links) {
  const NavdConfig config = nav::testing::synthetic_dive_config();  // ctest: source directory
  const nav::testing::SyntheticDive dive = nav::testing::make_synthetic_dive(config, o);
  NavFilterOptions options = filter_options_from_config(config);
  options.propose_links = links;
  NavFilter filter(options, &dive.registrations);
  for (const Measurement& m : dive.measurements) {
    const core::Status s = filter.process(m);
    EXPECT_TRUE(s.ok()) << s.to_string();
  }
  EXPECT_TRUE(filter.finish().ok());
  WrapRun r;
  const std::vector<ImageRecord>& images = filter.images();
  EXPECT_EQ(images.size(), dive.image_truth.size());
  Eigen::Vector2d last_error = Eigen::Vector2d::Zero();
  for (std::size_t k = 0; k < images.size(); ++k) {
    const core::Vec12& truth = dive.image_truth.at(images[k].frame_id);
    const core::Vec12& mean = images[k].robot_mean;
    const Eigen::Vector2d e = mean.head<2>() - truth.head<2>();
    r.max_xy_error_m = std::max(r.max_xy_error_m, e.norm());
    r.max_heading_error_rad =
        std::max(r.max_heading_error_rad, std::abs(core::wrap_angle(mean(5) - truth(5))));
    if (k > 0) {
      r.max_xy_step_m = std::max(r.max_xy_step_m, (e - last_error).norm());
      const core::Vec12& prev_truth = dive.image_truth.at(images[k - 1].frame_id);
      if (std::abs(truth(5) - prev_truth(5)) > std::numbers::pi) ++r.truth_wraps;
      const double prev = images[k - 1].robot_mean(5);
      if (std::abs(mean(5)) > 3.0 && std::abs(prev) > 3.0 && mean(5) * prev < 0.0)
        ++r.estimate_side_changes;
    }
    last_error = e;
  }
  std::printf(
      "truth wraps %d, estimate side changes %d, max XY error %.4f m, max step %.4f m, "
      "max heading error %.3f deg\n",
      r.truth_wraps, r.estimate_side_changes, r.max_xy_error_m, r.max_xy_step_m,
      r.max_heading_error_rad * 180.0 / std::numbers::pi);
  return r;
}

// Straight south (a 5 km circle): the heading measurements scatter across ±π at every update.
// Before 05138fc this dead-reckoning run jumped by metres (see the commit message).
TEST(NavFilterHeadingWrap, HeadingSouthDoesNotMoveTheEstimate) {
  nav::testing::SyntheticDiveOptions o;
  o.heading0_rad = std::numbers::pi;
  o.yaw_rate_radps = 1e-4;
  o.duration_s = 120.0;
  const WrapRun r = run(o, false);
  EXPECT_GE(r.estimate_side_changes, 5) << "the estimate must cross ±π for this test to bite";
  EXPECT_LT(r.max_xy_error_m, 0.2);
  EXPECT_LT(r.max_xy_step_m, 0.05);
  EXPECT_LT(r.max_heading_error_rad, 0.5 * std::numbers::pi / 180.0);
}

// Circling (8 m radius) through south four times, with camera links (SLAM).
TEST(NavFilterHeadingWrap, CirclingThroughSouthWithLinksDoesNotJump) {
  nav::testing::SyntheticDiveOptions o;
  o.duration_s = 400.0;
  const WrapRun r = run(o, true);
  EXPECT_GE(r.truth_wraps, 3);
  EXPECT_LT(r.max_xy_error_m, 0.2);
  EXPECT_LT(r.max_xy_step_m, 0.05);
  EXPECT_LT(r.max_heading_error_rad, 0.5 * std::numbers::pi / 180.0);
}

}  // namespace
}  // namespace nav::daemon
