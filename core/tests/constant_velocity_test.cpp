// Tests of models/constant_velocity.h: hand-computed prediction, F against central
// differences on 1,000 states (with and without the attitude restoring terms), Q against an independent quadrature, and input errors.

#include "nav/core/models/constant_velocity.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <limits>
#include <stdexcept>

#include "pose_test_support.h"

namespace nav::core {
namespace {

using nav::testing::max_abs_diff;
using nav::testing::numeric_jacobian;
using test::deg;
using test::kPi;

constexpr int kSamples = 1000;
constexpr double kJacobianTol = 1e-6;  // absolute, analytic F vs central differences

Vec12 state_with(std::initializer_list<std::pair<int, double>> entries) {
  Vec12 x = Vec12::Zero();
  for (const auto& [k, v] : entries) x[k] = v;
  return x;
}

TEST(ConstantVelocity, ForwardMotionHeadingEastMovesEast) {
  const ConstantVelocityModel model;
  const Vec12 x = state_with({{kHeading, kPi / 2}, {kU, 1.0}, {kZ, 3.0}});
  const Vec12 next = model.predict(x, 2.0);
  Vec12 expected = x;
  expected[kY] = 2.0;
  EXPECT_LT(max_abs_diff(next, expected), 1e-12) << next.transpose();
}

TEST(ConstantVelocity, YawRateTurnsHeadingAndWraps) {
  const ConstantVelocityModel model;
  const Vec12 x = state_with({{kHeading, deg(175)}, {kR, deg(10)}});
  const Vec12 next = model.predict(x, 1.0);
  EXPECT_NEAR(next[kHeading], deg(-175), 1e-12);
  EXPECT_NEAR(next[kR], deg(10), 0.0);  // rates are constant
  // Rolled 90 deg, a body pitch rate q turns the heading: psi_dot = sin(phi)/cos(theta) q.
  const Vec12 rolled = state_with({{kRoll, kPi / 2}, {kQ, 0.1}});
  EXPECT_NEAR(model.predict(rolled, 1.0)[kHeading], 0.1, 1e-12);
  EXPECT_NEAR(model.predict(rolled, 1.0)[kPitch], 0.0, 1e-12);
}

/// F of predict() against central differences at 1,000 random states and steps.
void expect_jacobian_matches_numeric(const ConstantVelocityModel& model, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> dt(0.01, 1.0);
  for (int i = 0; i < kSamples; ++i) {
    const Vec12 x = test::random_state(rng);
    const double dt_s = dt(rng);
    Mat12 F;
    model.predict(x, dt_s, &F);
    const Eigen::MatrixXd N = numeric_jacobian(
        [&](const Eigen::VectorXd& v) -> Eigen::VectorXd { return model.predict(Vec12(v), dt_s); },
        x, 1e-6,
        [](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
          return test::wrapped_minus(a, b, {kRoll, kPitch, kHeading});
        });
    ASSERT_LT(max_abs_diff(F, N), kJacobianTol) << "x " << x.transpose() << " dt " << dt_s;
  }
}

TEST(ConstantVelocity, JacobianMatchesNumeric) {
  expect_jacobian_matches_numeric(ConstantVelocityModel(), 31);
}

TEST(ConstantVelocity, JacobianMatchesNumericWithAttitudeRestoring) {
  ConstantVelocityOptions o;  // of the order identified on the simulated vehicle
  o.attitude_restoring.natural_period_s << 7.3, 9.0;
  o.attitude_restoring.damping_ratio << 0.17, 0.14;
  o.attitude_restoring.trim_rad << 0.003, 0.02;
  o.attitude_restoring.pitch_per_heave_rad_per_mps = -0.1;
  expect_jacobian_matches_numeric(ConstantVelocityModel(o), 41);
}

TEST(ConstantVelocity, ProcessNoiseMatchesQuadratureAndIsPsd) {
  // Q = int_0^dt Phi(tau) G Qc G^T Phi(tau)^T dtau with Phi(tau) = F(tau) = I + tau A. The
  // integrand is quadratic in tau, so Simpson's rule on [0, dt/2, dt] is exact.
  ConstantVelocityOptions options;
  options.accel_psd << 0.01, 0.02, 0.03;
  options.angular_accel_psd << 1e-4, 2e-4, 3e-4;
  const ConstantVelocityModel model(options);
  Mat12 GQcGt = Mat12::Zero();
  GQcGt.diagonal().tail<6>() << options.accel_psd, options.angular_accel_psd;
  std::mt19937_64 rng(32);
  std::uniform_real_distribution<double> dt(0.01, 2.0);
  for (int i = 0; i < kSamples; ++i) {
    const Vec12 x = test::random_state(rng);
    const double dt_s = dt(rng);
    Mat12 F_half, F_full;
    model.predict(x, dt_s / 2, &F_half);
    model.predict(x, dt_s, &F_full);
    const Mat12 expected =
        dt_s / 6.0 *
        (GQcGt + 4.0 * F_half * GQcGt * F_half.transpose() + F_full * GQcGt * F_full.transpose());
    const Mat12 Q = model.process_noise(x, dt_s);
    ASSERT_LT(max_abs_diff(Q, expected), 1e-12) << "x " << x.transpose() << " dt " << dt_s;
    ASSERT_EQ(max_abs_diff(Q, Q.transpose()), 0.0);
    ASSERT_GE(Eigen::SelfAdjointEigenSolver<Mat12>(Q).eigenvalues().minCoeff(), -1e-15);
    ASSERT_NEAR(Q(kU, kU), 0.01 * dt_s, 1e-15);  // velocity random walk psd * dt
    ASSERT_NEAR(Q(kR, kR), 3e-4 * dt_s, 1e-15);
  }
}

TEST(ConstantVelocity, ProcessNoiseByHandAtLevelNorth) {
  // Level, heading north: forward-velocity noise shows up in x only, as psd dt^3/3.
  ConstantVelocityOptions options;
  options.accel_psd << 0.5, 0.0, 0.0;
  options.angular_accel_psd.setZero();
  const Mat12 Q = ConstantVelocityModel(options).process_noise(Vec12::Zero(), 2.0);
  EXPECT_NEAR(Q(kX, kX), 0.5 * 8.0 / 3.0, 1e-15);
  EXPECT_NEAR(Q(kX, kU), 0.5 * 4.0 / 2.0, 1e-15);
  EXPECT_NEAR(Q(kU, kU), 0.5 * 2.0, 1e-15);
  EXPECT_EQ(Q(kY, kY), 0.0);
  EXPECT_EQ(Q(kHeading, kHeading), 0.0);
}

TEST(ConstantVelocity, InvalidTimeStepIsRejected) {
  const ConstantVelocityModel model;
  const Vec12 x = Vec12::Zero();
  for (const double dt_s : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(),
                            std::numeric_limits<double>::infinity()}) {
    EXPECT_THROW(model.predict(x, dt_s), std::invalid_argument) << dt_s;
    EXPECT_THROW(model.process_noise(x, dt_s), std::invalid_argument) << dt_s;
  }
  try {
    model.predict(x, -0.5);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("dt_s = -0.5"), std::string::npos) << e.what();
  }
}

TEST(ConstantVelocity, SingularPitchIsAClearErrorNeverNaN) {
  const ConstantVelocityModel model;
  const Vec12 x = state_with({{kPitch, kPi / 2}, {kP, 0.1}});
  Mat12 F;
  EXPECT_THROW(model.predict(x, 0.1), std::domain_error);
  EXPECT_THROW(model.predict(x, 0.1, &F), std::domain_error);
  EXPECT_THROW(model.process_noise(x, 0.1), std::domain_error);
  const Vec12 near = state_with({{kPitch, deg(89)}, {kP, 0.1}, {kR, 0.1}});
  EXPECT_TRUE(model.predict(near, 0.1, &F).allFinite());
  EXPECT_TRUE(F.allFinite());
}

TEST(ConstantVelocity, OptionsValidate) {
  EXPECT_TRUE(ConstantVelocityOptions{}.validate().ok());
  ConstantVelocityOptions bad;
  bad.accel_psd[1] = -1.0;
  const Status s = bad.validate();
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("accel_psd[1] = -1"), std::string::npos) << s.message();
  EXPECT_THROW(ConstantVelocityModel{bad}, std::invalid_argument);
  ConstantVelocityOptions nan;
  nan.angular_accel_psd[2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(nan.validate().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace nav::core
