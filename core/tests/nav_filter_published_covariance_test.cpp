// NavFilter::robot_covariance() (nav_filter.h "Published solution") against the dense
// marginal of the full filter: on a small run (a vehicle heading north at 0.5 m/s with noise-free
// DVL, attitude and depth, an image every 2 s, exact recovery at images, no registrations), at
// every non-image measurement the propagated 12x12 covariance must equal block (0, 0) of Λ⁻¹
// (CHOLMOD selected inversion, ExactMarginals), and it must differ from the covariance recorded
// at the last image (the robot moved since: what the published covariance is for).
#include <gtest/gtest.h>

#include <cstdint>
#include <numbers>
#include <variant>
#include <vector>

#include "nav/core/navigation/nav_filter.h"
#include "nav/core/recovery/exact_marginals.h"

namespace nav::core {
namespace {

NavFilterOptions options() {
  NavFilterOptions o;
  SensorModelOptions dvl, attitude, depth, camera;
  dvl.name = "dvl";
  attitude.name = "attitude";
  depth.name = "depth";
  camera.name = "camera";
  camera.camera = CameraIntrinsics{1000.0, 1000.0, 640.0, 480.0};
  o.sensors = {dvl, attitude, depth, camera};
  o.recovery.mode = RecoveryMode::kDirect;  // exact Σ_rr at each image
  return o;
}

MeasurementTime at(std::int64_t t_us, std::uint16_t sensor) {
  return MeasurementTime{t_us, t_us, 1'700'000'000'000'000 + t_us, sensor};
}

std::vector<Measurement> run(double duration_s) {
  std::vector<Measurement> out;
  const auto end_us = static_cast<std::int64_t>(duration_s * 1e6);
  for (std::int64_t t = 0; t <= end_us; t += 100'000) {
    out.push_back(Attitude{at(t, 1), 0.0, 0.0, 0.0, true, true});
    if (t % 200'000 == 0) out.push_back(DvlVelocity{at(t + 1'000, 0), {0.5, 0.0, 0.0}});
    if (t % 500'000 == 0) out.push_back(Depth{at(t + 2'000, 2), 100.0});
    if (t % 2'000'000 == 1'000'000) {
      out.push_back(Altitude{at(t + 3'000, 3), 3.0});
      out.push_back(ImageEvent{at(t + 50'000, 3), static_cast<std::uint64_t>(t / 1000)});
    }
  }
  return out;
}

TEST(NavFilterPublishedCovariance, EqualsTheDenseRobotMarginalBetweenImages) {
  NavFilter filter(options(), nullptr);
  int checked = 0, moved = 0;
  for (const Measurement& m : run(12.0)) {
    ASSERT_TRUE(filter.process(m).ok());
    if (std::holds_alternative<ImageEvent>(m) || filter.esdf().num_blocks() < 2) continue;
    const Eigen::MatrixXd exact =
        ExactMarginals::compute(filter.esdf().information().to_sparse(), 12).marginal(0);
    const Mat12& published = filter.robot_covariance();
    EXPECT_LE((published - exact).norm(), 1e-6 * exact.norm())
        << "at t = " << filter.time_us() << " us\npublished\n"
        << published << "\nexact\n"
        << exact;
    moved +=
        (published - filter.images().back().robot_covariance).norm() > 1e-3 * exact.norm() ? 1 : 0;
    ++checked;
  }
  EXPECT_GT(checked, 100);
  EXPECT_GT(moved, checked / 2);  // most checks are well after the last image
}

// The published mean includes an update applied without a prediction (a measurement less than
// min_predict_step_s after the filter's time): a heading 0.2 deg off the estimate moves
// robot_mean() towards it, and the ESDF's own robot mean (the last prediction's linearisation
// point) stays where it was.
TEST(NavFilterPublishedCovariance, PublishedMeanIncludesAnUpdateWithoutPrediction) {
  NavFilter filter(options(), nullptr);
  for (const Measurement& m : run(6.0)) ASSERT_TRUE(filter.process(m).ok());
  const Vec12 before = filter.robot_mean();
  const Vec12 linearisation_point = filter.esdf().mean_block(Esdf::kRobotBlock);
  const double z = before[5] + 0.2 * std::numbers::pi / 180.0;
  const std::int64_t t = filter.time_us() + 4'000;  // within min_predict_step_s (5 ms)
  ASSERT_TRUE(filter.process(Attitude{at(t, 1), 0.0, 0.0, z, false, true}).ok());
  ASSERT_EQ(filter.time_us(), t - 4'000);  // applied at the filter's time
  const double moved = filter.robot_mean()[5] - before[5];
  EXPECT_GT(moved, 0.05 * (z - before[5]));
  EXPECT_LT(moved, z - before[5]);
  EXPECT_EQ(filter.esdf().mean_block(Esdf::kRobotBlock), linearisation_point);
}

}  // namespace
}  // namespace nav::core
