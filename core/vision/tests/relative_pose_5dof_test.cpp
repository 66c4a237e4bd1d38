// Tests of relative_pose_5dof.h: values by hand, agreement with
// nav::core::CameraRelativePoseModel, round trips, and every Jacobian against central
// differences on random relative poses.

#include "nav/vision/relative_pose_5dof.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include "nav/core/geometry/pose.h"
#include "nav/core/geometry/rotation.h"
#include "nav/core/models/binary_models.h"
#include "nav/testing/numeric_jacobian.h"

namespace nav::vision {
namespace {

using nav::testing::max_abs_diff;
using nav::testing::numeric_jacobian;

constexpr double kPi = std::numbers::pi;
constexpr double kJacobianTol = 1e-7;

double deg(double d) { return d * kPi / 180.0; }

Vec6 random_relative_pose(std::mt19937& rng) {
  std::uniform_real_distribution<double> t(-2.0, 2.0), a(-deg(60), deg(60)), h(-kPi, kPi);
  Vec6 x;
  do {
    x << t(rng), t(rng), t(rng), a(rng), a(rng), h(rng);
  } while (std::hypot(x[0], x[1]) < 0.1);
  return x;
}

TEST(RelativePose5Dof, ValuesByHand) {
  // Baseline along +y, 45 deg down the optical axis: azimuth 90 deg, elevation 45 deg.
  Vec6 x;
  x << 0.0, 1.0, 1.0, 0.1, -0.2, 3.0;
  const Vec5 z = z_from_relative_pose(x);
  EXPECT_NEAR(z[0], kPi / 2, 1e-15);
  EXPECT_NEAR(z[1], kPi / 4, 1e-15);
  EXPECT_NEAR(z[2], 0.1, 1e-15);
  EXPECT_NEAR(z[3], -0.2, 1e-15);
  EXPECT_NEAR(z[4], 3.0, 1e-15);
  // Angles beyond pi wrap.
  x[5] = kPi + 0.5;
  EXPECT_NEAR(z_from_relative_pose(x)[4], -kPi + 0.5, 1e-12);
  EXPECT_NEAR(baseline_direction(kPi / 2, kPi / 4).y(), std::sqrt(0.5), 1e-15);
}

TEST(RelativePose5Dof, AgreesWithCameraRelativePoseModel) {
  // The filter's measurement model and this file must define the same z: camera poses in the
  // world with an identity mount, so x_ab = tail_to_tail(x_a, x_b).
  std::mt19937 rng(7);
  core::CameraRelativePoseModel model;
  for (int k = 0; k < 200; ++k) {
    const Vec6 x_a = random_relative_pose(rng), x_b = random_relative_pose(rng);
    const Vec6 x_ab = core::tail_to_tail(x_a, x_b);
    if (std::hypot(x_ab[0], x_ab[1]) < 1e-3) continue;
    const Eigen::VectorXd z_model = model.predict(x_a, x_b);
    const Vec5 z = z_from_relative_pose(x_ab);
    EXPECT_LT(z_minus(z, z_model).cwiseAbs().maxCoeff(), 1e-12) << "sample " << k;
    // And via rotation + translation of any length.
    const Vec5 z_rt =
        z_from_rotation_translation(core::pose_rotation(x_ab), 3.7 * core::pose_translation(x_ab));
    EXPECT_LT(z_minus(z_rt, z).cwiseAbs().maxCoeff(), 1e-9) << "sample " << k;
  }
}

TEST(RelativePose5Dof, RoundTripThroughZ) {
  std::mt19937 rng(11);
  for (int k = 0; k < 200; ++k) {
    const Vec6 x = random_relative_pose(rng);
    const double baseline = core::pose_translation(x).norm();
    const Vec6 back = relative_pose_from_z(z_from_relative_pose(x), baseline);
    EXPECT_LT(core::pose_minus(back, x).cwiseAbs().maxCoeff(), 1e-12) << "sample " << k;
    const Eigen::Matrix3d R = rotation_from_z(z_from_relative_pose(x));
    EXPECT_LT((R - core::pose_rotation(x)).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(RelativePose5Dof, JacobiansMatchCentralDifferences) {
  std::mt19937 rng(3);
  const auto wrap_minus = [](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
    Eigen::VectorXd d = a - b;
    for (Eigen::Index k = 0; k < d.size(); ++k) d[k] = core::wrap_angle(d[k]);
    return d;
  };
  for (int k = 0; k < 300; ++k) {
    const Vec6 x = random_relative_pose(rng);
    Mat5x6 J;
    const Vec5 z = z_from_relative_pose(x, &J);
    const Eigen::MatrixXd J_num = numeric_jacobian(
        [](const Eigen::VectorXd& v) { return Eigen::VectorXd(z_from_relative_pose(v)); }, x, 1e-6,
        wrap_minus);
    EXPECT_LT(max_abs_diff(J, J_num), kJacobianTol) << "dz/dx, sample " << k;

    const double baseline = 0.5 + k * 0.01;
    Mat6x5 Jx;
    relative_pose_from_z(z, baseline, &Jx);
    const Eigen::MatrixXd Jx_num = numeric_jacobian(
        [baseline](const Eigen::VectorXd& v) {
          return Eigen::VectorXd(relative_pose_from_z(v, baseline));
        },
        z);
    EXPECT_LT(max_abs_diff(Jx, Jx_num), kJacobianTol) << "dx/dz, sample " << k;

    Mat3x2 Jt;
    baseline_direction(z[0], z[1], &Jt);
    const Eigen::MatrixXd Jt_num = numeric_jacobian(
        [](const Eigen::VectorXd& v) { return Eigen::VectorXd(baseline_direction(v[0], v[1])); },
        z.head<2>());
    EXPECT_LT(max_abs_diff(Jt, Jt_num), kJacobianTol) << "dt/d(az, el), sample " << k;
  }
}

TEST(RelativePose5Dof, PredictionCovarianceMatchesMonteCarlo) {
  // First-order P_z = J P_x J^T against the sample covariance of z over draws of a prior
  // with small covariance (where first order is accurate to a few percent).
  RelativePosePrior prior;
  prior.x_i_j << 0.6, 0.3, 0.05, deg(2), deg(-1), deg(10);
  prior.covariance = Mat6::Zero();
  prior.covariance.diagonal() << 0.01, 0.01, 0.005, deg(0.5), deg(0.5), deg(1.0);
  prior.covariance = prior.covariance.cwiseProduct(prior.covariance).eval();
  const PredictedZ predicted = predict_z(prior);
  std::mt19937 rng(5);
  std::normal_distribution<double> n01;
  const Eigen::LLT<Mat6> chol(prior.covariance);
  const int n = 20000;
  Mat5 sample = Mat5::Zero();
  for (int k = 0; k < n; ++k) {
    Vec6 e;
    for (int r = 0; r < 6; ++r) e[r] = n01(rng);
    const Vec5 d = z_minus(z_from_relative_pose(prior.x_i_j + chol.matrixL() * e), predicted.z);
    sample += d * d.transpose() / n;
  }
  for (int r = 0; r < 5; ++r) {
    EXPECT_NEAR(std::sqrt(sample(r, r)), std::sqrt(predicted.covariance(r, r)),
                0.05 * std::sqrt(predicted.covariance(r, r)))
        << "row " << r;
  }
  // chi2 of the prediction itself is zero.
  EXPECT_NEAR(z_chi2(predicted.z, predicted.covariance, predicted), 0.0, 1e-20);
}

TEST(RelativePose5Dof, Chi2ByHand) {
  // Diagonal covariances, equal for prediction and measurement: a 1-sigma offset in one
  // component gives 1/2 (the innovation covariance is twice each), across the +-pi seam too.
  PredictedZ predicted;
  predicted.z << kPi - 0.01, 0.1, 0.0, 0.0, 0.0;
  predicted.covariance = Mat5::Zero();
  predicted.covariance.diagonal() << 0.04, 0.01, 0.01, 0.01, 0.01;
  Vec5 z = predicted.z;
  z[0] = -kPi + 0.19;  // +0.2 rad = +1 sigma across the seam
  EXPECT_NEAR(z_chi2(z, predicted.covariance, predicted), 0.5, 1e-9);
}

TEST(RelativePose5Dof, UndefinedAzimuthThrowsWithTheBaseline) {
  Vec6 x;
  x << 0.0, 0.0, 1.0, 0.0, 0.0, 0.0;  // baseline along the optical axis
  try {
    z_from_relative_pose(x);
    FAIL() << "expected std::domain_error";
  } catch (const std::domain_error& e) {
    EXPECT_NE(std::string(e.what()).find("no defined azimuth"), std::string::npos) << e.what();
  }
  x.setZero();  // no baseline at all
  EXPECT_THROW(z_from_relative_pose(x), std::domain_error);
  RelativePosePrior prior;
  prior.x_i_j = x;
  EXPECT_THROW(predict_z(prior), std::domain_error);
}

TEST(RelativePose5Dof, Chi2RejectsNonPositiveDefiniteCovariance) {
  PredictedZ predicted;
  predicted.covariance = -Mat5::Identity();
  EXPECT_THROW(z_chi2(Vec5::Zero(), Mat5::Zero(), predicted), std::invalid_argument);
}

}  // namespace
}  // namespace nav::vision
