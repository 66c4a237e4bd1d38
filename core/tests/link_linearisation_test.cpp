// iterated_link_point (link_linearisation.h): the point at which NavFilter linearises an
// accepted camera link.
#include "nav/core/navigation/link_linearisation.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>

namespace nav::core {
namespace {

struct Scene {
  core::CameraRelativePoseModel camera;
  LinkPair truth = LinkPair::Zero();  ///< [x_r; x_i]
  core::MeasCov R = core::MeasCov::Identity(5, 5) * 1e-6;
  Scene() {
    camera.x_body_camera << 1.0, 0.0, 0.5, 0.0, 0.0, M_PI / 2;  // the simulated survey's camera mount
    truth.head<6>() << 2.0, 0.5, 10.0, 0.01, 0.02, 0.1;         // robot 2 m ahead of state i
    truth.segment<6>(12) << 0.0, 0.0, 10.0, 0.0, 0.0, 0.0;
  }
  core::MeasVec z() const { return camera.predict(truth.tail<12>(), truth.head<12>()); }
  /// Prior: the robot's position uncertain by sigma_m, state i fixed.
  static Eigen::MatrixXd robot_prior(double sigma_m) {
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(kLinkPairDim, kLinkPairDim);
    J.topLeftCorner(3, 3) = Eigen::Matrix3d::Identity() * sigma_m * sigma_m;
    J.block<3, 3>(3, 3) = Eigen::Matrix3d::Identity() * 1e-4;
    return J;
  }
};

TEST(LinkLinearisation, AtTheTruthTheMeanIsAFixedPoint) {
  const Scene s;
  const LinkLinearisation l =
      iterated_link_point(s.camera, s.truth, Scene::robot_prior(1.0), s.z(), s.R);
  EXPECT_LE(l.iterations, 1);
  EXPECT_LT((l.x - s.truth).norm(), 1e-9);
}

// The case that broke the map (hil-tests/README.md "Consistency", seed 33): the robot's mean is
// metres off on a 2 m baseline. The iterate lands on the bearing through state i, near the
// truth, where one linearisation at the mean overshoots.
TEST(LinkLinearisation, AMeanMetresOffIsPulledOntoTheMeasuredBearing) {
  const Scene s;
  LinkPair x0 = s.truth;
  x0.head<2>() += Eigen::Vector2d(1.5, -1.0);  // 1.8 m off, prior sigma 2 m
  const Eigen::MatrixXd J = Scene::robot_prior(2.0);
  const LinkLinearisation l = iterated_link_point(s.camera, x0, J, s.z(), s.R);
  EXPECT_GT(l.iterations, 1);
  EXPECT_LT(l.iterations, 10) << "did not converge";
  // The measured residual at the point is tiny: the bearing is met (up to the prior's pull).
  core::MeasVec r = s.z() - l.h;
  core::wrap_angle_rows(s.camera, r);
  EXPECT_LT(r.head<2>().norm(), 1e-3);
  // One EKF step from the mean, for comparison: further from the truth than the iterate.
  core::MeasJac H_i, H_r;
  const core::MeasVec h0 = s.camera.predict(x0.tail<12>(), x0.head<12>(), &H_i, &H_r);
  Eigen::Matrix<double, 5, kLinkPairDim> H;
  H << H_r, H_i;
  core::MeasVec nu = s.z() - h0;
  core::wrap_angle_rows(s.camera, nu);
  const Eigen::Matrix<double, 5, 5> S = H * J * H.transpose() + s.R;
  const LinkPair ekf = x0 + J * H.transpose() * S.ldlt().solve(Eigen::Matrix<double, 5, 1>(nu));
  const double iterate_miss = (l.x.head<2>() - s.truth.head<2>()).norm();
  const double ekf_miss = (ekf.head<2>() - s.truth.head<2>()).norm();
  EXPECT_LT(iterate_miss, ekf_miss);
  // State i has no prior freedom here: it stays at its mean.
  EXPECT_LT((l.x.tail<12>() - x0.tail<12>()).norm(), 1e-12);
}

}  // namespace
}  // namespace nav::core
