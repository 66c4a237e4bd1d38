// Tests of the held step of navigation/robot_prediction.h and of NavFilter going on through a pitch
// beyond the constant-velocity model's +-89.5 deg (nav_filter.h "Predict"): F against central
// differences at off-branch pitches, Q's inflation by hand, and a filter fed attitude messages with
// the pitch at -175 deg (as navd saw after a 100x replay) that holds those steps, keeps every
// published covariance positive definite (the pitch variance pi^2 after a held step), and predicts
// with the model again once the attitude sensor brings the pitch back.

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "nav/core/geometry/rotation.h"
#include "nav/core/navigation/nav_filter.h"
#include "nav/core/navigation/robot_prediction.h"
#include "nav/testing/filter_sensors.h"
#include "pose_test_support.h"

namespace nav::core {
namespace {

using nav::testing::max_abs_diff;
using nav::testing::numeric_jacobian;
using test::deg;
using test::kPi;

TEST(HeldPrediction, JacobianMatchesNumericAtOffBranchPitch) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> pitch(deg(89.6), deg(180.0));
  std::uniform_real_distribution<double> dt(0.01, 0.5);
  const ConstantVelocityOptions noise;
  for (int i = 0; i < 200; ++i) {
    Vec12 x = test::random_state(rng);
    x[kPitch] = (i % 2 == 0 ? 1.0 : -1.0) * pitch(rng);
    ASSERT_TRUE(pitch_is_singular(x[kPitch]));
    const double dt_s = dt(rng);
    const RobotPrediction held = held_prediction(x, dt_s, noise, kPi, 0.05);
    const Eigen::MatrixXd N = numeric_jacobian(
        [&](const Eigen::VectorXd& v) -> Eigen::VectorXd {
          return held_prediction(Vec12(v), dt_s, noise, kPi, 0.05).x_next;
        },
        x, 1e-6, [](const Eigen::VectorXd& a, const Eigen::VectorXd& b) { return a - b; });
    ASSERT_LT(max_abs_diff(held.F, N), 1e-6) << "x " << x.transpose() << " dt " << dt_s;
  }
}

TEST(HeldPrediction, MovesAlongTheBodyVelocityHoldsAttitudeRestartsRatesAndInflates) {
  Vec12 x = Vec12::Zero();
  x[kRoll] = 0.2;
  x[kPitch] = deg(-175);
  x[kHeading] = 1.0;
  x[kU] = 0.5;
  x[kQ] = 30.0;  // the rate that carried the pitch off
  const double dt_s = 0.1;
  const ConstantVelocityOptions noise;
  const RobotPrediction held = held_prediction(x, dt_s, noise, kPi, 0.05);
  const Vec3 moved = dt_s * rotation_from_euler(x.segment<3>(kRoll)) * x.segment<3>(kU);
  EXPECT_LT(max_abs_diff(held.x_next.head<3>(), moved), 1e-15);
  EXPECT_EQ(held.x_next.segment<6>(kRoll), x.segment<6>(kRoll));  // attitude, velocity held
  EXPECT_EQ(held.x_next.segment<3>(kP), Vec3::Zero());
  // Position: (2 dt |v|)^2 = 0.01 m^2 on top of dt^3/3 accel_psd; attitude pi^2; rates 0.05^2.
  for (int k = kX; k <= kZ; ++k) EXPECT_GT(held.Q(k, k), 0.01);
  for (int k = kRoll; k <= kHeading; ++k) EXPECT_NEAR(held.Q(k, k), kPi * kPi, 1e-12);
  for (int k = kP; k <= kR; ++k) EXPECT_NEAR(held.Q(k, k), 0.0025, 1e-15);
  EXPECT_EQ(held.Q, held.Q.transpose());
  EXPECT_EQ(Eigen::LLT<Mat12>(held.Q).info(), Eigen::Success);
  EXPECT_THROW((void)held_prediction(x, 0.0, noise, kPi, 0.05), std::invalid_argument);
}

MeasurementTime at(std::int64_t t_us, std::uint16_t sensor) {
  return MeasurementTime{t_us, t_us, 1'700'000'000'000'000 + t_us, sensor};
}

/// 6 s heading north at 0.5 m/s; from 2.0 s to 2.5 s the attitude sensor reports the pitch at
/// -175 deg (the truth stays level).
std::vector<Measurement> run_with_pitch_off() {
  std::vector<Measurement> out;
  for (std::int64_t t = 0; t <= 6'000'000; t += 100'000) {
    const bool off = t >= 2'000'000 && t <= 2'500'000;
    out.push_back(Attitude{at(t, 1), 0.0, off ? deg(-175) : 0.0, 0.0, true, true});
    if (t % 200'000 == 0) out.push_back(DvlVelocity{at(t + 50'000, 0), {0.5, 0.0, 0.0}});
    if (t % 500'000 == 0) out.push_back(Depth{at(t + 60'000, 2), 100.0});
  }
  return out;
}

TEST(NavFilterHeldPrediction, PitchBeyondTheLimitIsHeldAndTheFilterGoesOn) {
  NavFilterOptions o;
  o.sensors = nav::testing::named_sensors({"dvl", "attitude", "depth"});
  // The fault is an attitude the innovation gate would refuse (aid_gate.h): the test is about
  // the model's limit, so the attitude is let in.
  o.aid_gate.roll_pitch_sigma = 0.0;
  std::vector<std::string> warnings;
  o.warn = [&](const std::string& w) { warnings.push_back(w); };
  NavFilter filter(o, nullptr);
  double max_pitch_off_rad = 0.0;
  int inflated = 0;
  std::uint64_t held_at_end_of_fault = 0, predictions_at_end_of_fault = 0;
  for (const Measurement& m : run_with_pitch_off()) {
    const std::uint64_t held_before = filter.counters().predictions_held;
    ASSERT_TRUE(filter.process(m).ok()) << "at t = " << validity_us(m) << " us";
    if (!filter.initialised()) continue;
    const Mat12 P = filter.robot_covariance();
    ASSERT_EQ(Eigen::LLT<Mat12>(P).info(), Eigen::Success) << "at t = " << filter.time_us();
    const double pitch = filter.esdf().mean_block(Esdf::kRobotBlock)[kPitch];
    max_pitch_off_rad = std::max(max_pitch_off_rad, std::abs(pitch));
    if (filter.counters().predictions_held > held_before && !std::holds_alternative<Attitude>(m)) {
      // A held step, no attitude update since: the published pitch variance is the lost one.
      EXPECT_GE(P(kPitch, kPitch), kPi * kPi) << "at t = " << filter.time_us();
      ++inflated;
    }
    if (validity_us(m) <= 3'000'000) {
      held_at_end_of_fault = filter.counters().predictions_held;
      predictions_at_end_of_fault = filter.counters().predictions;
    }
  }
  EXPECT_GT(inflated, 0);
  EXPECT_GT(max_pitch_off_rad, kMaxAbsPitchRad);  // the fault reached the model's limit
  EXPECT_GT(filter.counters().predictions_held, 0u);
  EXPECT_FALSE(warnings.empty());
  // Back on the model: no held step in the last 3 s, predictions went on, pitch level again.
  EXPECT_EQ(filter.counters().predictions_held, held_at_end_of_fault);
  EXPECT_GT(filter.counters().predictions, predictions_at_end_of_fault + 20);
  EXPECT_LT(std::abs(filter.esdf().mean_block(Esdf::kRobotBlock)[kPitch]), deg(1));
  EXPECT_EQ(filter.counters().update_failures, 0u);
}

}  // namespace
}  // namespace nav::core
