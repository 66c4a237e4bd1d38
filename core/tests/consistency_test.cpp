// Consistency metrics (recovery/consistency.h).

#include "nav/core/recovery/consistency.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "nav/core/geometry/pose.h"
#include "nav/testing/numeric_jacobian.h"

namespace nav::core {
namespace {

using nav::testing::max_abs_diff;

TEST(Consistency, IsConservativeOnHandCases) {
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(3, 3);
  double min_eig = 0.0;
  EXPECT_TRUE(is_conservative(2.0 * I, I, 1e-9, &min_eig));
  EXPECT_NEAR(min_eig, 1.0, 1e-12);
  EXPECT_FALSE(is_conservative(0.5 * I, I, 1e-9, &min_eig));
  EXPECT_NEAR(min_eig, -0.5, 1e-12);
  EXPECT_TRUE(is_conservative(I, I, 1e-9, &min_eig));  // equal: PSD difference (zero)
  // Larger on the diagonal but the difference is indefinite: [[1 2]; [2 1]] has eig -1.
  Eigen::Matrix2d exact = Eigen::Matrix2d::Identity();
  Eigen::Matrix2d bound;
  bound << 2.0, 2.0, 2.0, 2.0;
  EXPECT_FALSE(is_conservative(bound, exact, 1e-9, &min_eig));
  EXPECT_NEAR(min_eig, -1.0, 1e-12);
  // Tolerance is relative to the norm of exact: -1e-10 * 1e3 passes at tol 1e-9, not 1e-12.
  const Eigen::MatrixXd big = 1e3 * I;
  Eigen::MatrixXd slightly_less = big;
  slightly_less(1, 1) -= 1e-7;
  EXPECT_TRUE(is_conservative(slightly_less, big, 1e-9));
  EXPECT_FALSE(is_conservative(slightly_less, big, 1e-12));
  EXPECT_THROW(is_conservative(I, Eigen::MatrixXd::Identity(2, 2), 1e-9), std::invalid_argument);
}

TEST(Consistency, RelativePoseCovarianceMatchesNumericJacobian) {
  const Vec6 x_r = (Vec6() << 1, 2, -3, 0.1, -0.2, 0.7).finished();
  const Vec6 x_i = (Vec6() << 4, -1, -2.5, -0.3, 0.15, -2.0).finished();
  std::mt19937 rng(3);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd A(12, 12);
  for (int k = 0; k < A.size(); ++k) A.data()[k] = normal(rng);
  const Mat12 joint = 0.01 * A * A.transpose() + 1e-4 * Mat12::Identity();
  Eigen::VectorXd x(12);
  x << x_r, x_i;
  const auto f = [](const Eigen::VectorXd& v) {
    return Eigen::VectorXd(tail_to_tail(v.head<6>(), v.tail<6>()));
  };
  const auto minus = [](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
    return Eigen::VectorXd(pose_minus(a, b));
  };
  const Eigen::MatrixXd J = nav::testing::numeric_jacobian(f, x, 1e-6, minus);
  const Eigen::MatrixXd expected = J * joint * J.transpose();
  const Mat6 cov = relative_pose_covariance(joint, x_r, x_i);
  EXPECT_LT(max_abs_diff(cov, expected), 1e-7 * expected.cwiseAbs().maxCoeff());
  // Perfectly correlated identical poses (x_i = x_r exactly): the relative pose is certain.
  Mat12 same = Mat12::Zero();
  same.topLeftCorner<6, 6>() = joint.topLeftCorner<6, 6>();
  same.topRightCorner<6, 6>() = joint.topLeftCorner<6, 6>();
  same.bottomLeftCorner<6, 6>() = joint.topLeftCorner<6, 6>();
  same.bottomRightCorner<6, 6>() = joint.topLeftCorner<6, 6>();
  EXPECT_LT(relative_pose_covariance(same, x_r, x_r).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Consistency, PoseJointTakesTheFirstSixOfEachBlock) {
  Eigen::MatrixXd joint(24, 24);
  for (int r = 0; r < 24; ++r) {
    for (int c = 0; c < 24; ++c) joint(r, c) = 100.0 * r + c;
  }
  const Mat12 p = pose_joint(joint);
  EXPECT_EQ(p(0, 0), 0.0);
  EXPECT_EQ(p(5, 6), 5.0 * 100.0 + 12.0);   // row 5 of r, column 0 of i
  EXPECT_EQ(p(6, 5), 12.0 * 100.0 + 5.0);   // row 0 of i, column 5 of r
  EXPECT_EQ(p(11, 11), 17.0 * 100.0 + 17.0);
  EXPECT_EQ(pose_joint(Eigen::MatrixXd::Identity(12, 12)), Mat12::Identity());
  EXPECT_THROW(pose_joint(Eigen::MatrixXd::Zero(10, 10)), std::invalid_argument);
  EXPECT_THROW(pose_joint(Eigen::MatrixXd::Zero(24, 12)), std::invalid_argument);
}

TEST(Consistency, LogdetRatioSignAndValue) {
  const Mat6 I = Mat6::Identity();
  EXPECT_NEAR(logdet_ratio(Mat6(2.0 * I), I), 6.0 * std::log(2.0), 1e-12);
  EXPECT_NEAR(logdet_ratio(I, Mat6(2.0 * I)), -6.0 * std::log(2.0), 1e-12);
  EXPECT_NEAR(logdet_ratio(I, I), 0.0, 0.0);
  Mat6 indefinite = I;
  indefinite(2, 2) = -1.0;
  EXPECT_THROW(logdet_ratio(indefinite, I), std::invalid_argument);
  EXPECT_THROW(logdet_ratio(I, indefinite), std::invalid_argument);
  // Mixed fixed/dynamic arguments resolve to the one Ref overload.
  const Eigen::MatrixXd dynamic = 3.0 * Eigen::MatrixXd::Identity(6, 6);
  EXPECT_NEAR(logdet_ratio(dynamic, I), 6.0 * std::log(3.0), 1e-12);
  EXPECT_THROW(logdet_ratio(Eigen::MatrixXd::Identity(3, 3), I), std::invalid_argument);
}

TEST(Consistency, SummaryStats) {
  const SummaryStats odd = summarize({3.0, -1.0, 2.0});
  EXPECT_EQ(odd.count, 3u);
  EXPECT_EQ(odd.min, -1.0);
  EXPECT_EQ(odd.median, 2.0);
  EXPECT_EQ(odd.max, 3.0);
  const SummaryStats even = summarize({4.0, 1.0, 2.0, 10.0});
  EXPECT_EQ(even.median, 3.0);
  EXPECT_EQ(even.max, 10.0);
  EXPECT_THROW(summarize({}), std::invalid_argument);
}

}  // namespace
}  // namespace nav::core
