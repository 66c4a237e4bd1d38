// The camera-pair pose prior (vision/camera_prior.h) against independent references: the
// relative pose from 4x4 homogeneous transforms, the covariance from a central-difference
// Jacobian of that reference.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "nav/daemon/vision/camera_prior.h"

namespace nav::daemon::vision {
namespace {

using core::Mat12;
using core::Vec6;

Eigen::Matrix4d transform(const Vec6& x) {
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(x[5], Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(x[4], Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(x[3], Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = R;
  T.topRightCorner<3, 1>() = x.head<3>();
  return T;
}

/// Camera j in camera i by matrices: (T_w_bi T_b_c)^-1 T_w_bj T_b_c, Z-Y-X angles read back.
Vec6 reference_relative(const Vec6& x_i, const Vec6& x_j, const Vec6& mount) {
  const Eigen::Matrix4d T = (transform(x_i) * transform(mount)).inverse() *
                            transform(x_j) * transform(mount);
  const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
  Vec6 out;
  out.head<3>() = T.topRightCorner<3, 1>();
  out[3] = std::atan2(R(2, 1), R(2, 2));
  out[4] = std::asin(-R(2, 0));
  out[5] = std::atan2(R(1, 0), R(0, 0));
  return out;
}

double wrap(double a) { return std::atan2(std::sin(a), std::cos(a)); }

TEST(CameraPrior, RelativePoseMatchesHomogeneousTransforms) {
  const Vec6 mount = (Vec6() << 1.0, 0.0, 0.5, 0.0, 0.0, M_PI / 2).finished();
  const Vec6 x_i = (Vec6() << 10.0, -3.0, 3790.0, 0.02, -0.05, 1.2).finished();
  const Vec6 x_j = (Vec6() << 12.5, -1.0, 3789.4, -0.03, 0.04, 1.6).finished();
  const CameraPairPrior p = camera_pair_prior(x_i, x_j, Mat12::Identity(), mount);
  const Vec6 ref = reference_relative(x_i, x_j, mount);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(p.x_ci_cj[k], ref[k], 1e-9) << k;
  for (int k = 3; k < 6; ++k) EXPECT_NEAR(wrap(p.x_ci_cj[k] - ref[k]), 0.0, 1e-9) << k;
}

TEST(CameraPrior, CovarianceIsFirstOrderPropagationWithNumericJacobian) {
  const Vec6 mount = (Vec6() << 1.0, 0.1, 0.5, 0.01, -0.02, M_PI / 2).finished();
  const Vec6 x_i = (Vec6() << 4.0, 7.0, 3790.0, 0.05, 0.03, -2.9).finished();
  const Vec6 x_j = (Vec6() << 5.2, 9.1, 3790.8, -0.02, 0.06, 3.0).finished();
  // A correlated joint of [x_j; x_i] (robot first, as in the proposal joint).
  Eigen::Matrix<double, 12, 12> A = Eigen::Matrix<double, 12, 12>::Random() * 0.1;
  const Mat12 P = A * A.transpose() + 1e-3 * Mat12::Identity();
  const CameraPairPrior p = camera_pair_prior(x_i, x_j, P, mount);

  Eigen::Matrix<double, 6, 12> G;
  const double h = 1e-6;
  for (int c = 0; c < 12; ++c) {
    Vec6 xi_p = x_i, xi_m = x_i, xj_p = x_j, xj_m = x_j;
    if (c < 6) {
      xj_p[c] += h;
      xj_m[c] -= h;
    } else {
      xi_p[c - 6] += h;
      xi_m[c - 6] -= h;
    }
    Vec6 d = reference_relative(xi_p, xj_p, mount) - reference_relative(xi_m, xj_m, mount);
    for (int k = 3; k < 6; ++k) d[k] = wrap(d[k]);
    G.col(c) = d / (2 * h);
  }
  const core::Mat6 expected = G * P * G.transpose();
  EXPECT_LT((p.covariance - expected).norm(), 1e-6 * expected.norm())
      << "analytic:\n" << p.covariance << "\nnumeric:\n" << expected;
  EXPECT_LT((p.covariance - p.covariance.transpose()).norm(), 1e-15 + 1e-12 * expected.norm());
}

}  // namespace
}  // namespace nav::daemon::vision
