// Tests of geometry/rotation.h: wrapping, Z-Y-X Euler rotations, their derivatives, the
// Euler-rate matrix J2 and its singularity policy.

#include "nav/core/geometry/rotation.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
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
constexpr double kJacobianTol = 1e-6;  // absolute, analytic vs central differences

Vec3 random_rpy(std::mt19937_64& rng) { return test::random_pose(rng).tail<3>(); }

TEST(Rotation, WrapAngleHandValues) {
  EXPECT_DOUBLE_EQ(wrap_angle(0.0), 0.0);
  EXPECT_DOUBLE_EQ(wrap_angle(0.5), 0.5);
  EXPECT_DOUBLE_EQ(wrap_angle(kPi), kPi);
  EXPECT_DOUBLE_EQ(wrap_angle(-kPi), kPi);
  EXPECT_NEAR(wrap_angle(3 * kPi), kPi, 1e-12);
  EXPECT_NEAR(wrap_angle(-3 * kPi), kPi, 1e-12);
  EXPECT_NEAR(wrap_angle(2 * kPi), 0.0, 1e-12);
  EXPECT_NEAR(wrap_angle(-2 * kPi), 0.0, 1e-12);
  EXPECT_NEAR(wrap_angle(7.0), 7.0 - 2 * kPi, 1e-12);
  EXPECT_NEAR(wrap_angle(-7.0), -7.0 + 2 * kPi, 1e-12);
  EXPECT_NEAR(wrap_angle(kPi + 0.1), -kPi + 0.1, 1e-12);
  EXPECT_NEAR(wrap_angle(1000.0), std::remainder(1000.0, 2 * kPi), 1e-9);
  EXPECT_TRUE(std::isnan(wrap_angle(std::numeric_limits<double>::quiet_NaN())));
}

TEST(Rotation, WrapAngleRangeAndPeriodicity) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> a(-100.0, 100.0);
  for (int i = 0; i < kSamples; ++i) {
    const double x = a(rng);
    const double w = wrap_angle(x);
    ASSERT_GT(w, -kPi) << x;
    ASSERT_LE(w, kPi) << x;
    ASSERT_NEAR(std::cos(w), std::cos(x), 1e-9) << x;
    ASSERT_NEAR(std::sin(w), std::sin(x), 1e-9) << x;
  }
}

TEST(Rotation, ElementaryRotationsAndConventionByHand) {
  // Heading +90 deg: body forward (x) points east (world y).
  EXPECT_LT(max_abs_diff(rotation_from_euler({0, 0, kPi / 2}) * Vec3::UnitX(), Vec3::UnitY()),
            1e-15);
  // Pitch +30 deg (nose up): body x goes to [cos, 0, -sin] in NED (up is -z).
  const Vec3 nose = rotation_from_euler({0, deg(30), 0}) * Vec3::UnitX();
  EXPECT_LT(max_abs_diff(nose, Vec3(std::cos(deg(30)), 0, -0.5)), 1e-15);
  // Roll +30 deg (right side down): body y goes to [0, cos, sin].
  const Vec3 wing = rotation_from_euler({deg(30), 0, 0}) * Vec3::UnitY();
  EXPECT_LT(max_abs_diff(wing, Vec3(0, std::cos(deg(30)), 0.5)), 1e-15);
  // Matches Eigen's angle-axis composition Rz Ry Rx.
  const Vec3 rpy(0.3, -0.4, 2.0);
  const Mat3 expected =
      (Eigen::AngleAxisd(rpy[2], Vec3::UnitZ()) * Eigen::AngleAxisd(rpy[1], Vec3::UnitY()) *
       Eigen::AngleAxisd(rpy[0], Vec3::UnitX()))
          .toRotationMatrix();
  EXPECT_LT(max_abs_diff(rotation_from_euler(rpy), expected), 1e-15);
  EXPECT_LT(max_abs_diff(rot_x(0.7), Eigen::AngleAxisd(0.7, Vec3::UnitX()).toRotationMatrix()),
            1e-15);
}

TEST(Rotation, OrthonormalWithUnitDeterminant) {
  std::mt19937_64 rng(12);
  for (int i = 0; i < kSamples; ++i) {
    const Mat3 R = rotation_from_euler(random_rpy(rng));
    ASSERT_LT(max_abs_diff(R.transpose() * R, Mat3::Identity()), 1e-14);
    ASSERT_NEAR(R.determinant(), 1.0, 1e-14);
  }
}

TEST(Rotation, EulerRoundTrip) {
  std::mt19937_64 rng(13);
  for (int i = 0; i < kSamples; ++i) {
    const Vec3 rpy = random_rpy(rng);
    const Vec3 back = euler_from_rotation(rotation_from_euler(rpy));
    for (int k = 0; k < 3; ++k) ASSERT_NEAR(wrap_angle(back[k] - rpy[k]), 0.0, 1e-12) << k;
  }
}

TEST(Rotation, EulerFromRotationAtGimbalLockIsFiniteAndConsistent) {
  for (const double pitch : {kPi / 2, -kPi / 2}) {
    const Mat3 R = rotation_from_euler({0.3, pitch, 1.1});
    const Vec3 rpy = euler_from_rotation(R);
    ASSERT_TRUE(rpy.allFinite());
    EXPECT_NEAR(rpy[1], pitch, 1e-7);
    EXPECT_LT(max_abs_diff(rotation_from_euler(rpy), R), 1e-7);
  }
  // Rounding pushing |R(2,0)| above one must not give NaN from asin.
  Mat3 R = rotation_from_euler({0, kPi / 2, 0});
  R(2, 0) = -1.0 - 1e-15;
  EXPECT_TRUE(euler_from_rotation(R).allFinite());
}

TEST(Rotation, RotationDerivativesMatchNumeric) {
  std::mt19937_64 rng(14);
  for (int i = 0; i < kSamples; ++i) {
    const Vec3 rpy = random_rpy(rng);
    const Vec3 v = Vec3::Random();
    const auto f = [&](const Eigen::VectorXd& a) -> Eigen::VectorXd {
      return rotation_from_euler(a) * v;
    };
    const Eigen::MatrixXd N = numeric_jacobian(f, rpy);
    Mat3 A;
    A << dR_droll(rpy) * v, dR_dpitch(rpy) * v, dR_dheading(rpy) * v;
    ASSERT_LT(max_abs_diff(A, N), kJacobianTol) << "rpy " << rpy.transpose();
  }
}

TEST(Rotation, EulerRateMatrixGivesEulerAngleRates) {
  // rpy(t) of R(t) = R0 exp([omega]x t): d rpy/dt at t = 0 must equal J2 omega.
  std::mt19937_64 rng(15);
  for (int i = 0; i < kSamples; ++i) {
    const Vec3 rpy = random_rpy(rng);
    const Vec3 omega = Vec3::Random();
    const Mat3 R0 = rotation_from_euler(rpy);
    const auto f = [&](const Eigen::VectorXd& t) -> Eigen::VectorXd {
      return euler_from_rotation(
          R0 * Eigen::AngleAxisd(t[0] * omega.norm(), omega.normalized()).toRotationMatrix());
    };
    const Eigen::MatrixXd N =
        numeric_jacobian(f, Eigen::VectorXd::Zero(1), 1e-6, [](const auto& a, const auto& b) {
          return test::wrapped_minus(a, b, {0, 1, 2});
        });
    ASSERT_LT(max_abs_diff(euler_rate_matrix(rpy) * omega, N), kJacobianTol)
        << "rpy " << rpy.transpose();
    ASSERT_LT(
        max_abs_diff(euler_rate_matrix(rpy) * euler_rate_matrix_inverse(rpy), Mat3::Identity()),
        1e-12);
  }
}

TEST(Rotation, EulerRateMatrixDerivativesMatchNumeric) {
  std::mt19937_64 rng(16);
  for (int i = 0; i < kSamples; ++i) {
    const Vec3 rpy = random_rpy(rng);
    const Vec3 omega = Vec3::Random();
    const auto f = [&](const Eigen::VectorXd& a) -> Eigen::VectorXd {
      return euler_rate_matrix(a) * omega;
    };
    const Eigen::MatrixXd N = numeric_jacobian(f, rpy);
    ASSERT_LT(max_abs_diff(dJ2_droll(rpy) * omega, N.col(0)), kJacobianTol);
    ASSERT_LT(max_abs_diff(dJ2_dpitch(rpy) * omega, N.col(1)), kJacobianTol);
    ASSERT_LT(N.col(2).cwiseAbs().maxCoeff(), kJacobianTol);  // J2 independent of heading
  }
}

TEST(Rotation, PitchSingularityIsAClearErrorNeverNaN) {
  EXPECT_FALSE(pitch_is_singular(0.0));
  EXPECT_FALSE(pitch_is_singular(deg(89.0)));
  EXPECT_FALSE(pitch_is_singular(-kMaxAbsPitchRad));
  EXPECT_TRUE(pitch_is_singular(deg(89.6)));
  EXPECT_TRUE(pitch_is_singular(kPi / 2));
  EXPECT_TRUE(pitch_is_singular(-kPi / 2));
  EXPECT_TRUE(pitch_is_singular(std::numeric_limits<double>::quiet_NaN()));
  EXPECT_TRUE(pitch_is_singular(std::numeric_limits<double>::infinity()));

  for (const double pitch :
       {kPi / 2, -kPi / 2, deg(89.9), deg(-89.6), std::numeric_limits<double>::quiet_NaN()}) {
    const Vec3 rpy(0.1, pitch, 0.2);
    EXPECT_THROW(euler_rate_matrix(rpy), std::domain_error) << pitch;
    EXPECT_THROW(dJ2_droll(rpy), std::domain_error) << pitch;
    EXPECT_THROW(dJ2_dpitch(rpy), std::domain_error) << pitch;
    EXPECT_TRUE(euler_rate_matrix_inverse(rpy).allFinite() || std::isnan(pitch));
  }
  try {
    (void)euler_rate_matrix({0, kPi / 2, 0});
    FAIL() << "expected std::domain_error";
  } catch (const std::domain_error& e) {
    EXPECT_NE(std::string(e.what()).find("euler_rate_matrix: pitch 1.5707963"), std::string::npos)
        << e.what();
  }
  // Just inside the limit: large but finite.
  const Mat3 J2 = euler_rate_matrix({0.3, deg(89.4), 0});
  EXPECT_TRUE(J2.allFinite());
  EXPECT_GT(J2.cwiseAbs().maxCoeff(), 90.0);
}

}  // namespace
}  // namespace nav::core
