// Tests of geometry/pose.h: SSC compounding by hand, round trips, and every analytic
// Jacobian against central differences on 1,000 random poses.

#include "nav/core/geometry/pose.h"

#include <gtest/gtest.h>

#include <stdexcept>

#include "pose_test_support.h"

namespace nav::core {
namespace {

using nav::testing::max_abs_diff;
using nav::testing::numeric_jacobian;
using test::deg;
using test::kPi;
using test::pose;

constexpr int kSamples = 1000;
// Analytic vs central-difference Jacobian, absolute. Samples whose result pitch exceeds
// 80 deg are redrawn (J2 of the result grows as 1/cos(pitch)).
constexpr double kJacobianTol = 1e-6;
constexpr double kRoundTripTol = 1e-9;

bool regular_result(const Vec6& x) { return std::abs(x[kPitch]) <= deg(80); }

void expect_pose_near(const Vec6& a, const Vec6& b, double tol, const char* what) {
  EXPECT_LT(pose_minus(a, b).cwiseAbs().maxCoeff(), tol)
      << what << "\n  got      " << a.transpose() << "\n  expected " << b.transpose();
}

TEST(Pose, HeadToTailByHand) {
  // Vehicle at (1, 0, 0) heading east; 1 m forward ends at (1, 1, 0), still heading east.
  expect_pose_near(head_to_tail(pose(1, 0, 0, 0, 0, kPi / 2), pose(1, 0, 0, 0, 0, 0)),
                   pose(1, 1, 0, 0, 0, kPi / 2), 1e-15, "east");
  // Headings add and wrap: 170 deg + 20 deg = -170 deg.
  expect_pose_near(head_to_tail(pose(0, 0, 0, 0, 0, deg(170)), pose(0, 0, 0, 0, 0, deg(20))),
                   pose(0, 0, 0, 0, 0, deg(-170)), 1e-12, "wrap");
  // Pitched 30 deg nose up: 2 m forward climbs 1 m (depth z decreases).
  expect_pose_near(head_to_tail(pose(0, 0, 5, 0, deg(30), 0), pose(2, 0, 0, 0, 0, 0)),
                   pose(2 * std::cos(deg(30)), 0, 4, 0, deg(30), 0), 1e-12, "pitch");
}

TEST(Pose, InverseAndTailToTailByHand) {
  // Frame j at (1, 1, 0) heading east: i's origin seen from j is 1 m left (-y) and 1 m behind.
  expect_pose_near(inverse_pose(pose(1, 1, 0, 0, 0, kPi / 2)), pose(-1, 1, 0, 0, 0, -kPi / 2),
                   1e-15, "inverse");
  // From a pose heading east at origin to a point 3 m east: 3 m forward in a's frame.
  expect_pose_near(tail_to_tail(pose(0, 0, 0, 0, 0, kPi / 2), pose(0, 3, 1, 0, 0, kPi / 2)),
                   pose(3, 0, 1, 0, 0, 0), 1e-15, "tail_to_tail");
}

TEST(Pose, PoseMinusWrapsAnglesOnly) {
  const Vec6 d =
      pose_minus(pose(10, 0, 0, deg(179), 0, deg(-179)), pose(-10, 0, 0, deg(-179), 0, deg(179)));
  expect_pose_near(d, pose(20, 0, 0, deg(-2), 0, deg(2)), 1e-12, "pose_minus");
  EXPECT_NEAR(d[0], 20.0, 0.0);
}

TEST(Pose, RoundTrips) {
  std::mt19937_64 rng(21);
  const Vec6 zero = Vec6::Zero();
  for (int i = 0; i < kSamples; ++i) {
    const Vec6 a = test::random_pose(rng), b = test::random_pose(rng);
    SCOPED_TRACE(::testing::Message() << "a " << a.transpose() << " b " << b.transpose());
    expect_pose_near(head_to_tail(a, inverse_pose(a)), zero, kRoundTripTol, "x (+) (-)x");
    expect_pose_near(head_to_tail(inverse_pose(a), a), zero, kRoundTripTol, "(-)x (+) x");
    expect_pose_near(inverse_pose(inverse_pose(a)), a, kRoundTripTol, "(-)(-)x");
    expect_pose_near(tail_to_tail(a, head_to_tail(a, b)), b, kRoundTripTol, "t2t(a, a(+)b)");
    expect_pose_near(tail_to_tail(a, b), head_to_tail(inverse_pose(a), b), kRoundTripTol,
                     "t2t = (-)a (+) b");
    expect_pose_near(tail_to_tail(a, a), zero, kRoundTripTol, "t2t(a, a)");
    const Vec6 c = test::random_pose(rng);
    expect_pose_near(head_to_tail(head_to_tail(a, b), c), head_to_tail(a, head_to_tail(b, c)),
                     kRoundTripTol, "associativity");
    if (HasFailure()) return;
  }
}

/// Numeric Jacobian of a two-pose function, columns [d/d first | d/d second].
template <class F>
Eigen::MatrixXd numeric_binary(F f, const Vec6& a, const Vec6& b) {
  Eigen::VectorXd ab(12);
  ab << a, b;
  return numeric_jacobian(
      [&](const Eigen::VectorXd& v) -> Eigen::VectorXd {
        return f(Vec6(v.head<6>()), Vec6(v.tail<6>()));
      },
      ab, 1e-6, test::pose_diff);
}

TEST(Pose, HeadToTailJacobianMatchesNumeric) {
  std::mt19937_64 rng(22);
  for (int n = 0; n < kSamples;) {
    const Vec6 a = test::random_pose(rng), b = test::random_pose(rng);
    if (!regular_result(head_to_tail(a, b))) continue;
    ++n;
    Mat6x12 J;
    head_to_tail(a, b, &J);
    const auto f = [](const Vec6& p, const Vec6& q) { return head_to_tail(p, q); };
    ASSERT_LT(max_abs_diff(J, numeric_binary(f, a, b)), kJacobianTol)
        << "a " << a.transpose() << " b " << b.transpose();
  }
}

TEST(Pose, TailToTailJacobianMatchesNumeric) {
  std::mt19937_64 rng(23);
  for (int n = 0; n < kSamples;) {
    const Vec6 a = test::random_pose(rng), b = test::random_pose(rng);
    if (!regular_result(tail_to_tail(a, b))) continue;
    ++n;
    Mat6x12 J;
    tail_to_tail(a, b, &J);
    const auto f = [](const Vec6& p, const Vec6& q) { return tail_to_tail(p, q); };
    ASSERT_LT(max_abs_diff(J, numeric_binary(f, a, b)), kJacobianTol)
        << "a " << a.transpose() << " b " << b.transpose();
  }
}

TEST(Pose, InverseJacobianMatchesNumeric) {
  std::mt19937_64 rng(24);
  for (int n = 0; n < kSamples; ++n) {
    const Vec6 a = test::random_pose(rng);  // pitch of (-)a is bounded by 80 deg as well
    Mat6 J;
    inverse_pose(a, &J);
    const Eigen::MatrixXd N = numeric_jacobian(
        [](const Eigen::VectorXd& v) -> Eigen::VectorXd { return inverse_pose(Vec6(v)); }, a, 1e-6,
        test::pose_diff);
    ASSERT_LT(max_abs_diff(J, N), kJacobianTol) << "a " << a.transpose();
  }
}

TEST(Pose, JacobianAtIdentityIsSimple) {
  Mat6x12 J;
  head_to_tail(Vec6::Zero(), Vec6::Zero(), &J);
  EXPECT_LT(max_abs_diff(J.leftCols<6>(), Mat6::Identity()), 1e-15);
  EXPECT_LT(max_abs_diff(J.rightCols<6>(), Mat6::Identity()), 1e-15);
  Mat6 Ji;
  inverse_pose(Vec6::Zero(), &Ji);
  EXPECT_LT(max_abs_diff(Ji, -Mat6::Identity()), 1e-15);
}

TEST(Pose, JacobianAtSingularResultPitchThrowsValueDoesNot) {
  const Vec6 a = pose(1, 2, 3, 0, deg(50), 0.3);
  const Vec6 b = pose(1, 0, 0, 0, deg(40), 0);  // composed pitch 90 deg
  EXPECT_NO_THROW(head_to_tail(a, b));
  EXPECT_TRUE(head_to_tail(a, b).allFinite());
  Mat6x12 J;
  EXPECT_THROW(head_to_tail(a, b, &J), std::domain_error);
  const Vec6 up = pose(0, 0, 0, 0, kPi / 2, 0);
  EXPECT_TRUE(tail_to_tail(Vec6::Zero(), up).allFinite());
  EXPECT_THROW(tail_to_tail(Vec6::Zero(), up, &J), std::domain_error);
  Mat6 Ji;
  EXPECT_THROW(inverse_pose(up, &Ji), std::domain_error);
  try {
    head_to_tail(a, b, &J);
  } catch (const std::domain_error& e) {
    EXPECT_NE(std::string(e.what()).find("head_to_tail"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace nav::core
