// core::DeadReckoningFilter (navigation/dead_reckoning.h) on the straight run of the NavFilter
// tests: it holds measurements until attitude, heading and depth, tracks the run, records the
// robot at every image, matches the information filter without links (a NavFilter that
// proposes no link and solves its delayed states exactly at every image) and gates what
// NavFilter gates.
#include "nav/core/navigation/dead_reckoning.h"

#include <gtest/gtest.h>

#include <limits>
#include <vector>

#include "nav/core/navigation/nav_filter.h"
#include "nav/testing/straight_line.h"

namespace nav::core {
namespace {

using testing::kDepthM;
using testing::kSpeedMps;
using testing::straight_line;
using testing::straight_line_options;

NavFilterOptions without_links_exact(NavFilterOptions o) {
  o.propose_links = false;
  o.recovery.preconditioner = RecoveryPreconditioner::kFactor;
  o.recovery.keep_factor_equal = true;
  o.recovery.refresh_interval = std::numeric_limits<int>::max();
  return o;
}

TEST(DeadReckoning, TracksTheRunAndRecordsEveryImage) {
  DeadReckoningFilter f(straight_line_options());
  const std::vector<Measurement> ms = straight_line(60.0);
  EXPECT_TRUE(f.process(ms.front()).ok());
  EXPECT_FALSE(f.initialised()) << "no depth yet";
  for (std::size_t k = 1; k < ms.size(); ++k) ASSERT_TRUE(f.process(ms[k]).ok());
  ASSERT_TRUE(f.initialised());
  const double t_s = 1e-6 * static_cast<double>(f.time_us());
  EXPECT_NEAR(f.robot_mean()(0), kSpeedMps * t_s, 0.05) << "north after " << t_s << " s";
  EXPECT_NEAR(f.robot_mean()(1), 0.0, 1e-3);
  EXPECT_NEAR(f.robot_mean()(2), kDepthM, 1e-3) << "depth of the reference point";
  EXPECT_NEAR(f.robot_mean()(6), kSpeedMps, 1e-3) << "surge";
  EXPECT_EQ(f.counters().measurements, ms.size());
  ASSERT_EQ(f.images().size(), 30u);
  for (const ImageRecord& image : f.images()) {
    EXPECT_NEAR(image.robot_mean(0), kSpeedMps * 1e-6 * static_cast<double>(image.t_us), 0.05);
  }
  EXPECT_GT(f.images().back().robot_covariance(1, 1), f.images().front().robot_covariance(1, 1))
      << "the cross-track variance grows without links";
}

TEST(DeadReckoning, MatchesTheInformationFilterWithoutLinks) {
  const std::vector<Measurement> ms = straight_line(60.0);
  DeadReckoningFilter dr(straight_line_options());
  NavFilter reference(without_links_exact(straight_line_options()), nullptr);
  for (const Measurement& m : ms) {
    ASSERT_TRUE(dr.process(m).ok());
    ASSERT_TRUE(reference.process(m).ok());
  }
  ASSERT_EQ(dr.images().size(), reference.images().size());
  for (std::size_t k = 0; k < dr.images().size(); ++k) {
    const ImageRecord& a = dr.images()[k];
    const ImageRecord& b = reference.images()[k];
    EXPECT_EQ(a.t_us, b.t_us);
    EXPECT_EQ(a.frame_id, b.frame_id);
    const Vec12 sigma = b.robot_covariance.diagonal().cwiseSqrt();
    EXPECT_LT((a.robot_mean - b.robot_mean).cwiseQuotient(sigma).cwiseAbs().maxCoeff(), 1e-3)
        << "image " << k;
    const Mat12 scale = sigma * sigma.transpose();
    EXPECT_LT((a.robot_covariance - b.robot_covariance).cwiseQuotient(scale).cwiseAbs().maxCoeff(),
              1e-3)
        << "image " << k;
  }
}

TEST(DeadReckoning, SkipsOutOfOrderMessagesAndGatesAnOutlier) {
  std::vector<Measurement> ms = straight_line(20.0);
  std::vector<Measurement> with_faults;
  bool outlier = false, late = false;
  for (const Measurement& m : ms) {
    with_faults.push_back(m);
    const auto* dvl = std::get_if<DvlVelocity>(&m);
    if (!dvl || dvl->time.validity_us < 10'000'000) continue;
    if (!outlier) {
      DvlVelocity bad = *dvl;
      bad.time.validity_us += 10;
      bad.v_sensor_mps = {kSpeedMps + 5.0, 0.0, 0.0};  // 500 sigma of the DVL
      with_faults.push_back(bad);
      outlier = true;
    } else if (!late) {
      DvlVelocity old = *dvl;
      old.time.validity_us -= 1'000'000;
      with_faults.push_back(old);
      late = true;
    }
  }
  DeadReckoningFilter f(straight_line_options());
  for (const Measurement& m : with_faults) ASSERT_TRUE(f.process(m).ok());
  EXPECT_EQ(f.counters().out_of_order, 1u);
  const SensorInnovation* dvl = nullptr;
  for (const SensorInnovation& s : f.innovations().sensors()) {
    if (s.name == "dvl") dvl = &s;
  }
  ASSERT_NE(dvl, nullptr);
  EXPECT_EQ(dvl->rejected, 1u);
  EXPECT_NEAR(f.robot_mean()(6), kSpeedMps, 1e-3) << "the outlier was not fused";
}

}  // namespace
}  // namespace nav::core
