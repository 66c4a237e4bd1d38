// Tests of models/unary_models.h and models/binary_models.h: hand-computed cases, and every
// analytic Jacobian against central differences on 1,000 random states (pitch <= 80 deg).

#include <gtest/gtest.h>

#include <stdexcept>

#include "nav/core/models/binary_models.h"
#include "nav/core/models/unary_models.h"
#include "pose_test_support.h"

namespace nav::core {
namespace {

using nav::testing::max_abs_diff;
using nav::testing::numeric_jacobian;
using test::deg;
using test::kPi;
using test::pose;

constexpr int kSamples = 1000;
constexpr double kJacobianTol = 1e-6;  // absolute, analytic vs central differences

template <class Model>
std::vector<int> angle_rows(const Model& m) {
  std::vector<int> rows;
  for (int r = 0; r < m.dim(); ++r)
    if (m.is_angle(r)) rows.push_back(r);
  return rows;
}

/// Checks a unary model's H (dim x x.size()) against central differences.
template <class Model>
void expect_unary_jacobian(const Model& model, const Eigen::VectorXd& x) {
  MeasJac H;
  const MeasVec z = model.predict(x, &H);
  ASSERT_EQ(z.size(), model.dim());
  ASSERT_EQ(H.rows(), model.dim());
  ASSERT_EQ(H.cols(), x.size());
  const auto rows = angle_rows(model);
  const Eigen::MatrixXd N = numeric_jacobian(
      [&](const Eigen::VectorXd& v) -> Eigen::VectorXd { return model.predict(v); }, x, 1e-6,
      [&](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
        return test::wrapped_minus(a, b, rows);
      });
  ASSERT_LT(max_abs_diff(H, N), kJacobianTol) << "x " << x.transpose();
}

/// Checks a binary model's H_a, H_b against central differences.
template <class Model>
void expect_binary_jacobian(const Model& model, const Eigen::VectorXd& x_a,
                            const Eigen::VectorXd& x_b) {
  MeasJac H_a, H_b;
  const MeasVec z = model.predict(x_a, x_b, &H_a, &H_b);
  ASSERT_EQ(z.size(), model.dim());
  ASSERT_EQ(H_a.cols(), x_a.size());
  ASSERT_EQ(H_b.cols(), x_b.size());
  const auto rows = angle_rows(model);
  const auto minus = [&](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
    return test::wrapped_minus(a, b, rows);
  };
  const Eigen::MatrixXd N_a = numeric_jacobian(
      [&](const Eigen::VectorXd& v) -> Eigen::VectorXd { return model.predict(v, x_b); }, x_a, 1e-6,
      minus);
  const Eigen::MatrixXd N_b = numeric_jacobian(
      [&](const Eigen::VectorXd& v) -> Eigen::VectorXd { return model.predict(x_a, v); }, x_b, 1e-6,
      minus);
  ASSERT_LT(max_abs_diff(H_a, N_a), kJacobianTol)
      << "x_a " << x_a.transpose() << "\nx_b " << x_b.transpose();
  ASSERT_LT(max_abs_diff(H_b, N_b), kJacobianTol)
      << "x_a " << x_a.transpose() << "\nx_b " << x_b.transpose();
}

Mat3 random_rotation(std::mt19937_64& rng) {
  return rotation_from_euler(test::random_pose(rng).tail<3>());
}

// ---------------------------------------------------------------- DVL

TEST(DvlVelocityModel, PureYawRateWithLeverArmGivesOmegaCrossP) {
  DvlVelocityModel dvl;
  dvl.p_body_dvl_m = Vec3(2.0, 0.0, 0.5);
  Vec12 x = Vec12::Zero();
  x[kR] = 0.1;  // yaw rate
  // omega x p = [0 0 0.1] x [2 0 0.5] = [0, 0.2, 0].
  EXPECT_LT(max_abs_diff(dvl.predict(x), Vec3(0.0, 0.2, 0.0)), 1e-15);
}

TEST(DvlVelocityModel, MountRotationExpressesVelocityInDvlAxes) {
  DvlVelocityModel dvl;
  dvl.R_body_dvl = rot_z(kPi / 2);  // DVL x along body y (starboard)
  Vec12 x = Vec12::Zero();
  x[kU] = 1.5;
  EXPECT_LT(max_abs_diff(dvl.predict(x), Vec3(0.0, -1.5, 0.0)), 1e-15);
  // Pose does not matter: the DVL measures body-frame velocity.
  x.head<6>() = pose(5, 6, 7, 0.3, 0.2, 1.0);
  EXPECT_LT(max_abs_diff(dvl.predict(x), Vec3(0.0, -1.5, 0.0)), 1e-15);
}

TEST(DvlVelocityModel, JacobianMatchesNumeric) {
  std::mt19937_64 rng(41);
  std::uniform_real_distribution<double> arm(-2.0, 2.0);
  for (int i = 0; i < kSamples; ++i) {
    DvlVelocityModel dvl;
    dvl.R_body_dvl = random_rotation(rng);
    dvl.p_body_dvl_m << arm(rng), arm(rng), arm(rng);
    expect_unary_jacobian(dvl, test::random_state(rng));
    if (HasFatalFailure()) return;
  }
}

TEST(DvlVelocityModel, RejectsPoseOnlyBlock) {
  try {
    (void)DvlVelocityModel{}.predict(Vec6::Zero());
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("DvlVelocityModel: state block has 6 elements"),
              std::string::npos)
        << e.what();
  }
}

// ---------------------------------------------------------------- heading, attitude, depth

TEST(AttitudeModels, ReadTheAnglesAndAreAngles) {
  std::mt19937_64 rng(42);
  const Vec12 x = test::random_state(rng);
  MeasJac H;
  const MeasVec h = HeadingModel{}.predict(x, &H);
  ASSERT_EQ(h.size(), 1);
  EXPECT_EQ(h[0], x[kHeading]);
  EXPECT_EQ(H.cols(), 12);
  EXPECT_EQ(H(0, kHeading), 1.0);
  EXPECT_EQ(H.cwiseAbs().sum(), 1.0);
  const MeasVec rp = AttitudeModel{}.predict(x.head<6>(), &H);
  ASSERT_EQ(rp.size(), 2);
  EXPECT_EQ(rp[0], x[kRoll]);
  EXPECT_EQ(rp[1], x[kPitch]);
  EXPECT_EQ(H.cols(), 6);
  EXPECT_EQ(H(0, kRoll), 1.0);
  EXPECT_EQ(H(1, kPitch), 1.0);
  EXPECT_EQ(H.cwiseAbs().sum(), 2.0);
  EXPECT_TRUE(HeadingModel{}.is_angle(0));
  EXPECT_TRUE(AttitudeModel{}.is_angle(1));
  EXPECT_FALSE(DepthModel{}.is_angle(0));
  EXPECT_THROW((void)HeadingModel{}.predict(Eigen::VectorXd::Zero(7)), std::invalid_argument);
}

TEST(AttitudeModels, ResidualAcrossPiIsWrapped) {
  const HeadingModel heading;
  Vec6 x = pose(0, 0, 0, 0, 0, deg(179));
  MeasVec r = MeasVec::Constant(1, deg(-179)) - heading.predict(x);
  wrap_angle_rows(heading, r);
  EXPECT_NEAR(r[0], deg(2), 1e-12);
  const DepthModel depth;
  MeasVec d = MeasVec::Constant(1, 10.0);
  wrap_angle_rows(depth, d);  // not an angle: untouched
  EXPECT_EQ(d[0], 10.0);
}

TEST(AttitudeModels, AngleMaskListsAngleRows) {
  const AngleMask rel = angle_mask(RelativePose6Model{});
  for (int r = 0; r < 6; ++r) EXPECT_EQ(rel[r], r >= 3) << r;
  const AngleMask cam = angle_mask(CameraRelativePoseModel{});
  for (int r = 0; r < 6; ++r) EXPECT_EQ(cam[r], r < 5) << r;
  const AngleMask dvl = angle_mask(DvlVelocityModel{});
  for (int r = 0; r < 6; ++r) EXPECT_FALSE(dvl[r]) << r;
}

TEST(DepthModel, LeverArmByHand) {
  DepthModel depth;
  depth.p_body_sensor_m = Vec3(1.0, 0.0, 0.2);
  // Level: sensor 0.2 m below the reference point.
  EXPECT_NEAR(depth.predict(pose(0, 0, 10, 0, 0, 1.0))[0], 10.2, 1e-15);
  // Nose up 30 deg: forward sensor rises by sin(30) = 0.5, the 0.2 m offset becomes 0.2 cos 30.
  EXPECT_NEAR(depth.predict(pose(0, 0, 10, 0, deg(30), 0))[0], 10.0 - 0.5 + 0.2 * std::cos(deg(30)),
              1e-15);
}

TEST(DepthModel, JacobianMatchesNumeric) {
  std::mt19937_64 rng(43);
  std::uniform_real_distribution<double> arm(-2.0, 2.0);
  for (int i = 0; i < kSamples; ++i) {
    DepthModel depth;
    depth.p_body_sensor_m << arm(rng), arm(rng), arm(rng);
    const Vec12 x = test::random_state(rng);
    if (i % 2 == 0) {
      expect_unary_jacobian(depth, x);
    } else {
      expect_unary_jacobian(depth, Eigen::VectorXd(x.head<6>()));
    }
    if (HasFatalFailure()) return;
  }
}

TEST(AttitudeModels, JacobiansMatchNumeric) {
  std::mt19937_64 rng(44);
  for (int i = 0; i < kSamples; ++i) {
    const Vec12 x = test::random_state(rng);
    expect_unary_jacobian(HeadingModel{}, x);
    expect_unary_jacobian(AttitudeModel{}, x);
    if (HasFatalFailure()) return;
  }
}

// ---------------------------------------------------------------- relative pose

TEST(RelativePose6Model, EqualsTailToTailAndJacobianMatchesNumeric) {
  std::mt19937_64 rng(45);
  const RelativePose6Model model;
  for (int n = 0; n < kSamples;) {
    const Vec12 a = test::random_state(rng), b = test::random_state(rng);
    if (std::abs(tail_to_tail(a.head<6>(), b.head<6>())[kPitch]) > deg(80)) continue;
    ++n;
    ASSERT_LT(max_abs_diff(model.predict(a, b), tail_to_tail(a.head<6>(), b.head<6>())), 1e-15);
    if (n % 2 == 0) {
      expect_binary_jacobian(model, a, b);
    } else {
      expect_binary_jacobian(model, Eigen::VectorXd(a.head<6>()), Eigen::VectorXd(b.head<6>()));
    }
    if (HasFatalFailure()) return;
  }
  EXPECT_THROW((void)model.predict(Vec12::Zero(), Vec6::Zero()), std::invalid_argument);
}

TEST(RelativePose6Model, SingularRelativePitchThrowsOnlyForJacobians) {
  const RelativePose6Model model;
  const Vec6 a = pose(1, 2, 3, 0, deg(-10), 0.2);
  const Vec6 b = head_to_tail(a, pose(2, 0, 0, 0.3, kPi / 2, 0));  // relative pitch 90 deg
  const MeasVec z = model.predict(a, b);
  EXPECT_TRUE(z.allFinite());
  EXPECT_NEAR(z[4], kPi / 2, 1e-7);
  MeasJac H_a, H_b;
  EXPECT_THROW((void)model.predict(a, b, &H_a, &H_b), std::domain_error);
  CameraRelativePoseModel camera;
  EXPECT_TRUE(camera.predict(a, b).allFinite());
  EXPECT_THROW((void)camera.predict(a, b, &H_a, &H_b), std::domain_error);
}

// ---------------------------------------------------------------- camera

TEST(CameraRelativePoseModel, AzimuthElevationOfKnownBaselines) {
  CameraRelativePoseModel cam;  // camera frame = body frame
  const Vec6 a = Vec6::Zero();
  struct Case {
    Vec3 t;
    double azimuth, elevation;
  };
  const double s2 = std::sqrt(2.0);
  for (const Case& c :
       {Case{{1, 0, 0}, 0.0, 0.0}, Case{{0, 2, 0}, kPi / 2, 0.0}, Case{{-1, 0, 0}, kPi, 0.0},
        Case{{0, -1, 0}, -kPi / 2, 0.0}, Case{{1, 0, 1}, 0.0, kPi / 4},
        Case{{1, 1, s2}, kPi / 4, kPi / 4}, Case{{1, 1, -s2}, kPi / 4, -kPi / 4}}) {
    const Vec6 b = pose(c.t.x(), c.t.y(), c.t.z(), 0.1, -0.2, 0.3);
    const MeasVec z = cam.predict(a, b);
    ASSERT_EQ(z.size(), 5);
    EXPECT_NEAR(z[0], c.azimuth, 1e-15) << c.t.transpose();
    EXPECT_NEAR(z[1], c.elevation, 1e-15) << c.t.transpose();
    EXPECT_LT(max_abs_diff(z.tail<3>(), Vec3(0.1, -0.2, 0.3)), 1e-15);
  }
}

TEST(CameraRelativePoseModel, DownLookingCameraSeesForwardMotionAsMinusY) {
  // Camera x = body y (right), camera y = -body x, camera z = body z (down): rot_z(90 deg).
  CameraRelativePoseModel cam;
  cam.x_body_camera = pose(0.5, 0, 0.3, 0, 0, kPi / 2);
  const Vec6 a = pose(10, 20, 30, 0, 0, deg(40));
  const Vec6 b = head_to_tail(a, pose(1.0, 0, 0, 0, 0, 0));  // 1 m forward, no rotation
  const MeasVec z = cam.predict(a, b);
  EXPECT_NEAR(z[0], -kPi / 2, 1e-12);
  EXPECT_NEAR(z[1], 0.0, 1e-12);
  EXPECT_LT(z.tail<3>().cwiseAbs().maxCoeff(), 1e-12);
  // Sinking 1 m (body down = camera z) at 1 m forward: elevation 45 deg.
  const Vec6 c = head_to_tail(a, pose(1.0, 0, 1.0, 0, 0, 0));
  EXPECT_NEAR(cam.predict(a, c)[1], kPi / 4, 1e-12);
}

TEST(CameraRelativePoseModel, JacobianMatchesNumeric) {
  std::mt19937_64 rng(46);
  std::uniform_real_distribution<double> arm(-1.0, 1.0);
  for (int n = 0; n < kSamples;) {
    CameraRelativePoseModel cam;
    cam.x_body_camera = test::random_pose(rng);
    cam.x_body_camera.head<3>() << arm(rng), arm(rng), arm(rng);
    const Vec12 a = test::random_state(rng), b = test::random_state(rng);
    const Vec6 x_ab = cam.camera_relative_pose(a, b);
    // Stay away from the undefined azimuth and from the Euler singularity of the result.
    if (std::hypot(x_ab[0], x_ab[1]) < 0.5 || std::abs(x_ab[kPitch]) > deg(80)) continue;
    ++n;
    if (n % 2 == 0) {
      expect_binary_jacobian(cam, a, b);
    } else {
      expect_binary_jacobian(cam, Eigen::VectorXd(a.head<6>()), Eigen::VectorXd(b.head<6>()));
    }
    if (HasFatalFailure()) return;
  }
}

TEST(CameraRelativePoseModel, ZeroBaselineIsADocumentedError) {
  CameraRelativePoseModel cam;
  cam.x_body_camera = pose(0.5, 0, 0.3, 0, 0, kPi / 2);
  const Vec6 a = pose(1, 2, 3, 0.1, 0.2, 0.3);
  EXPECT_TRUE(cam.baseline_is_degenerate(a, a));
  MeasJac H_a, H_b;
  try {
    (void)cam.predict(a, a, &H_a, &H_b);
    FAIL() << "expected std::domain_error";
  } catch (const std::domain_error& e) {
    EXPECT_NE(std::string(e.what()).find("azimuth undefined"), std::string::npos) << e.what();
  }
  // Baseline along the optical axis only (camera z = body z here): azimuth undefined too.
  const Vec6 below = head_to_tail(a, pose(0, 0, 2.0, 0, 0, 0));
  EXPECT_TRUE(cam.baseline_is_degenerate(a, below));
  EXPECT_THROW((void)cam.predict(a, below), std::domain_error);
  const Vec6 ahead = head_to_tail(a, pose(1.0, 0, 0, 0, 0, 0));
  EXPECT_FALSE(cam.baseline_is_degenerate(a, ahead));
}

}  // namespace
}  // namespace nav::core
