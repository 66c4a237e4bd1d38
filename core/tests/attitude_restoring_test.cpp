// Tests of the roll/pitch restoring terms of models/constant_velocity.h: a noise-free
// propagation against the damped oscillator's closed-form equilibrium and period, off by
// default and per axis, option errors (F against central differences: constant_velocity_test).

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "nav/core/models/constant_velocity.h"
#include "pose_test_support.h"

namespace nav::core {
namespace {

/// Values of the order identified on the simulated vehicle (docs/consistency.md).
ConstantVelocityOptions restoring_options() {
  ConstantVelocityOptions o;
  o.attitude_restoring.natural_period_s << 7.3, 9.0;
  o.attitude_restoring.damping_ratio << 0.17, 0.14;
  o.attitude_restoring.trim_rad << 0.003, 0.02;
  o.attitude_restoring.pitch_per_heave_rad_per_mps = -0.1;
  return o;
}

/// Times at which roll - its equilibrium changes sign going up, over a noise-free propagation.
struct Propagation {
  Vec12 final_state;
  std::vector<double> upward_crossings_s;
};

Propagation propagate(const ConstantVelocityModel& model, Vec12 x, double equilibrium_roll,
                      double duration_s, double dt_s) {
  Propagation out;
  for (double t = 0.0; t < duration_s; t += dt_s) {
    const double before = x[kRoll] - equilibrium_roll;
    x = model.predict(x, dt_s);
    const double after = x[kRoll] - equilibrium_roll;
    if (before < 0.0 && after >= 0.0) out.upward_crossings_s.push_back(t + dt_s);
  }
  out.final_state = x;
  return out;
}

TEST(AttitudeRestoring, SettlesAtTheEquilibriumWithTheDampedPeriod) {
  const ConstantVelocityOptions o = restoring_options();
  const ConstantVelocityModel model(o);
  Vec12 x = Vec12::Zero();
  x[kRoll] = 0.1;
  x[kPitch] = -0.15;
  x[kW] = 0.2;  // climbing at 0.2 m/s: pitch settles at trim + c w = 0.02 - 0.02 = 0
  x[kR] = 0.01;
  const Propagation p = propagate(model, x, o.attitude_restoring.trim_rad[0], 200.0, 1e-3);
  const AttitudeRestoringOptions& a = o.attitude_restoring;
  EXPECT_NEAR(p.final_state[kRoll], a.trim_rad[0], 1e-4);
  EXPECT_NEAR(p.final_state[kPitch], a.trim_rad[1] + a.pitch_per_heave_rad_per_mps * 0.2, 1e-4);
  EXPECT_NEAR(p.final_state[kP], 0.0, 1e-4);
  EXPECT_NEAR(p.final_state[kQ], 0.0, 1e-4);
  EXPECT_DOUBLE_EQ(p.final_state[kR], 0.01);  // yaw rate: a random walk as before
  EXPECT_DOUBLE_EQ(p.final_state[kW], 0.2);

  // Damped period T / sqrt(1 - zeta^2) between upward crossings of the equilibrium (the
  // kinematic coupling through J2 is second order at these angles).
  ASSERT_GE(p.upward_crossings_s.size(), 4u);
  const double measured_s = (p.upward_crossings_s[3] - p.upward_crossings_s[0]) / 3.0;
  const double zeta = a.damping_ratio[0];
  EXPECT_NEAR(measured_s, a.natural_period_s[0] / std::sqrt(1.0 - zeta * zeta), 0.05);
}

TEST(AttitudeRestoring, OffByDefaultAndPerAxis) {
  Vec12 x = Vec12::Zero();
  x[kRoll] = 0.1;
  x[kPitch] = 0.1;
  x[kP] = 0.02;
  x[kQ] = -0.03;
  const Vec12 random_walk = ConstantVelocityModel().predict(x, 0.1);
  EXPECT_EQ(random_walk[kP], 0.02);
  EXPECT_EQ(random_walk[kQ], -0.03);

  ConstantVelocityOptions roll_only = restoring_options();
  roll_only.attitude_restoring.natural_period_s[1] = 0.0;  // pitch rate stays a random walk
  const Vec12 y = ConstantVelocityModel(roll_only).predict(x, 0.1);
  EXPECT_LT(y[kP], 0.02);  // pulled back towards the roll trim
  EXPECT_EQ(y[kQ], -0.03);
}

TEST(AttitudeRestoring, OptionsValidate) {
  ConstantVelocityOptions o = restoring_options();
  EXPECT_TRUE(o.validate().ok());
  o.attitude_restoring.natural_period_s[1] = -1.0;
  Status s = o.validate();
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("attitude_restoring.natural_period_s[1] = -1"), std::string::npos)
      << s.message();
  EXPECT_THROW(ConstantVelocityModel{o}, std::invalid_argument);
  o = restoring_options();
  o.attitude_restoring.damping_ratio[0] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(o.validate().message().find("damping_ratio[0]"), std::string::npos);
  o = restoring_options();
  o.attitude_restoring.pitch_per_heave_rad_per_mps = std::numeric_limits<double>::infinity();
  EXPECT_NE(o.validate().message().find("pitch_per_heave_rad_per_mps = inf"), std::string::npos)
      << o.validate().message();
}

}  // namespace
}  // namespace nav::core
