// Essential matrix on synthetic scenes with a known pose: recovery of R and the baseline
// direction, the decomposition choice, the prior's tie-break and the pure-rotation failure.
#include "nav/vision/essential.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <opencv2/calib3d.hpp>
#include <random>
#include <vector>

#include "nav/core/geometry/rotation.h"
#include "nav/vision/camera_model.h"
#include "test_cameras.h"

namespace nav::vision {
namespace {

struct Scene {
  ImageFeatures i, j;
  PutativeMatches matches;
};

/// Points on a rough seafloor `depth_m` below camera i, seen by camera j at (R_i_j, t_i_j),
/// with pixel noise and a fraction of outliers.
Scene make_scene(const Eigen::Matrix3d& R_i_j, const Eigen::Vector3d& t_i_j, double depth_m,
                 double relief_m, double noise_px, double outlier_fraction, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, noise_px);
  const CameraIntrinsics cam = test::sim_camera();
  Scene s;
  while (static_cast<int>(s.matches.matches.size()) < n) {
    const Eigen::Vector3d p_i(u(rng) * 0.5 * depth_m, u(rng) * 0.4 * depth_m,
                              depth_m + relief_m * u(rng));
    const Eigen::Vector3d p_j = R_i_j.transpose() * (p_i - t_i_j);
    if (p_j.z() <= 0.1) continue;
    Eigen::Vector2d ui = pixel_from_normalised(cam, p_i.head<2>() / p_i.z());
    Eigen::Vector2d uj = pixel_from_normalised(cam, p_j.head<2>() / p_j.z());
    if (uj.x() < 0 || uj.x() > 1280 || uj.y() < 0 || uj.y() > 1024) continue;
    ui += Eigen::Vector2d(noise(rng), noise(rng));
    uj += Eigen::Vector2d(noise(rng), noise(rng));
    if (std::uniform_real_distribution<double>(0, 1)(rng) < outlier_fraction) {
      uj = Eigen::Vector2d(640 + 600 * u(rng), 512 + 500 * u(rng));
    }
    const int k = static_cast<int>(s.i.points_px.size());
    s.i.points_px.push_back(ui);
    s.j.points_px.push_back(uj);
    s.matches.matches.push_back({k, k, 0.0f});
  }
  return s;
}

double angle_deg(const Eigen::Matrix3d& A, const Eigen::Matrix3d& B) {
  return Eigen::AngleAxisd(A.transpose() * B).angle() * 180.0 / M_PI;
}

TEST(Essential, RecoversPoseWithOutliersByLmeds) {
  const Eigen::Matrix3d R = core::rotation_from_euler(Eigen::Vector3d(0.03, -0.02, 0.15));
  const Eigen::Vector3d t(0.6, 0.2, 0.05);
  const Scene s = make_scene(R, t, 3.0, 0.3, 0.5, 0.25, 300, 1);
  const EssentialEstimate e =
      estimate_essential(s.i, s.j, s.matches, test::sim_camera(), {}, nullptr);
  ASSERT_TRUE(e.ok) << e.reason;
  EXPECT_LT(angle_deg(e.R_i_j, R), 0.1);
  EXPECT_GT(e.t_i_j_unit.dot(t.normalized()), std::cos(1.0 * M_PI / 180.0));
  EXPECT_NEAR(e.t_i_j_unit.norm(), 1.0, 1e-9);
  // E = [t]x R satisfies the epipolar constraint of every inlier to the noise level.
  EXPECT_GT(e.inliers.size(), 200u);
  for (int k : e.inliers) {
    const auto& m = s.matches.matches[static_cast<std::size_t>(k)];
    const Eigen::Vector2d xi = normalised_from_pixel(
        test::sim_camera(), s.i.points_px[static_cast<std::size_t>(m.index_i)]);
    const Eigen::Vector2d xj = normalised_from_pixel(
        test::sim_camera(), s.j.points_px[static_cast<std::size_t>(m.index_j)]);
    EXPECT_LT(std::abs(sampson_distance(e.E, xi, xj)) * 1000.0, 5.0);
  }
}

TEST(Essential, RansacAndUsacAgreeWithLmeds) {
  const Eigen::Matrix3d R = core::rotation_from_euler(Eigen::Vector3d(-0.02, 0.04, -0.3));
  const Eigen::Vector3d t(-0.3, 0.5, 0.1);
  const Scene s = make_scene(R, t, 4.0, 0.5, 0.5, 0.3, 300, 2);
  for (RobustMethod method : {RobustMethod::kRansac, RobustMethod::kUsacMagsac}) {
    EssentialOptions options;
    options.method = method;
    const EssentialEstimate e =
        estimate_essential(s.i, s.j, s.matches, test::sim_camera(), options, nullptr);
    ASSERT_TRUE(e.ok) << e.reason;
    EXPECT_LT(angle_deg(e.R_i_j, R), 0.1);
    EXPECT_GT(e.t_i_j_unit.dot(t.normalized()), std::cos(1.0 * M_PI / 180.0));
  }
}

TEST(Essential, PureRotationFailsWithReason) {
  const Eigen::Matrix3d R = core::rotation_from_euler(Eigen::Vector3d(0.02, 0.01, 0.2));
  const Scene s = make_scene(R, Eigen::Vector3d::Zero(), 3.0, 0.3, 0.1, 0.0, 200, 3);
  const EssentialEstimate e =
      estimate_essential(s.i, s.j, s.matches, test::sim_camera(), {}, nullptr);
  EXPECT_FALSE(e.ok);
  EXPECT_NE(e.reason.find("parallax"), std::string::npos) << e.reason;
}

TEST(Essential, TooFewMatchesFailsWithReason) {
  const Scene s =
      make_scene(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.5, 0, 0), 3.0, 0.3, 0.5, 0.0, 4, 4);
  const EssentialEstimate e =
      estimate_essential(s.i, s.j, s.matches, test::sim_camera(), {}, nullptr);
  EXPECT_FALSE(e.ok);
  EXPECT_NE(e.reason.find("4 putative matches"), std::string::npos) << e.reason;
}

TEST(Essential, PlanarSceneWithPriorPicksTheDecompositionNearestThePrior) {
  // Flat seafloor (no relief): the homography's two physical decompositions both fit.
  const Eigen::Matrix3d R = core::rotation_from_euler(Eigen::Vector3d(0.01, -0.01, 0.1));
  const Eigen::Vector3d t(0.4, 0.1, 0.02);
  const Scene s = make_scene(R, t, 3.0, 0.0, 0.3, 0.0, 200, 5);
  RelativePosePrior prior;
  prior.x_i_j << t * 2.0, core::euler_from_rotation(R);  // Metric baseline, true angles.
  prior.covariance = Mat6::Identity() * 1e-3;
  prior.scene_depth_m = 3.0;
  prior.scene_depth_sigma_m = 0.5;
  const EssentialEstimate e =
      estimate_essential(s.i, s.j, s.matches, test::sim_camera(), {}, &prior);
  ASSERT_TRUE(e.ok) << e.reason;
  EXPECT_LT(angle_deg(e.R_i_j, R), 0.2);
  EXPECT_GT(e.t_i_j_unit.dot(t.normalized()), std::cos(2.0 * M_PI / 180.0));
}

TEST(Essential, PlanarSceneFollowsThePriorToTheOtherPlanarSolution) {
  // Over a flat floor the homography x_i ~ (R + t n^T / d) x_j has a second physically valid
  // decomposition (R2, t2). With the prior placed on it, the choice must follow the prior:
  // the tie-break is by the prior, not by the data.
  const Eigen::Matrix3d R = core::rotation_from_euler(Eigen::Vector3d(0.01, -0.01, 0.1));
  const Eigen::Vector3d t(0.4, 0.1, 0.02);
  const Scene s = make_scene(R, t, 3.0, 0.0, 0.3, 0.0, 200, 6);
  // Exact homography of the plane z_i = 3 in camera j's frame: n_j = R^T e_z, d_j = 3 - n_i.t.
  const Eigen::Vector3d n_j = R.transpose() * Eigen::Vector3d::UnitZ();
  const double d_j = 3.0 - t.z();
  const Eigen::Matrix3d H = R + t * n_j.transpose() / d_j;
  cv::Mat H_cv(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) H_cv.at<double>(r, c) = H(r, c);
  std::vector<cv::Mat> Rs, ts, ns;
  cv::decomposeHomographyMat(H_cv, cv::Mat::eye(3, 3, CV_64F), Rs, ts, ns);
  bool found_other = false;
  for (std::size_t k = 0; k < Rs.size() && !found_other; ++k) {
    Eigen::Matrix3d Rk;
    Eigen::Vector3d tk, nk;
    for (int r = 0; r < 3; ++r) {
      tk[r] = ts[k].at<double>(r);
      nk[r] = ns[k].at<double>(r);
      for (int c = 0; c < 3; ++c) Rk(r, c) = Rs[k].at<double>(r, c);
    }
    // Physically valid: the plane in front of camera j (n_z > 0 in camera j) and not the truth.
    if (nk.z() <= 0.0 || angle_deg(Rk, R) < 1.0) continue;
    found_other = true;
    RelativePosePrior prior;
    prior.x_i_j << tk.normalized() * t.norm(), core::euler_from_rotation(Rk);
    prior.covariance = Mat6::Identity() * 1e-4;
    prior.scene_depth_m = 3.0;
    prior.scene_depth_sigma_m = 0.5;
    EssentialOptions options;
    options.ambiguity_ratio = 0.5;
    const EssentialEstimate e =
        estimate_essential(s.i, s.j, s.matches, test::sim_camera(), options, &prior);
    ASSERT_TRUE(e.ok) << e.reason;
    EXPECT_LT(angle_deg(e.R_i_j, Rk), angle_deg(e.R_i_j, R)) << "chose the truth, not the prior's";
    EXPECT_LT(angle_deg(e.R_i_j, Rk), 0.5);
  }
  EXPECT_TRUE(found_other) << "no second physical homography decomposition";
}

/// A flat plane through [0 0 depth] in camera i, its normal tilted `tilt_deg` about camera i's
/// x axis, seen by camera j at (R, t) with 0.3 px noise.
Scene plane_scene(const Eigen::Matrix3d& R, const Eigen::Vector3d& t, double tilt_deg, int n,
                  unsigned seed) {
  const double slope = std::tan(tilt_deg * M_PI / 180.0);  // depth change per metre of y
  Scene s = make_scene(R, t, 3.0, 0.0, 0.3, 0.0, n, seed);
  // Re-project every point of the flat floor onto the tilted plane along camera i's ray.
  std::mt19937 rng(seed + 1000);
  std::normal_distribution<double> noise(0.0, 0.3);
  const CameraIntrinsics cam = test::sim_camera();
  Scene out;
  for (const Eigen::Vector2d& u : s.i.points_px) {
    const Eigen::Vector2d x = normalised_from_pixel(cam, u);
    const double depth = 3.0 / (1.0 - slope * x.y());  // z = 3 + slope y on the ray z [x y 1]
    if (!(depth > 0.5) || depth > 30.0) continue;
    const Eigen::Vector3d p_j = R.transpose() * (depth * Eigen::Vector3d(x.x(), x.y(), 1.0) - t);
    if (p_j.z() <= 0.1) continue;
    const int k = static_cast<int>(out.i.points_px.size());
    out.i.points_px.push_back(u);
    out.j.points_px.push_back(pixel_from_normalised(cam, p_j.head<2>() / p_j.z()) +
                              Eigen::Vector2d(noise(rng), noise(rng)));
    out.matches.matches.push_back({k, k, 0.0f});
  }
  return out;
}

TEST(Essential, FlatFloorWithoutPriorPicksTheFloorNotItsPlanarTwin) {
  // A survey's motions over a flat floor: along the line, across to the next line flown back,
  // a turn. Both planar solutions put every point in front and fit the matches exactly; the
  // twin's floor stands at about 90 deg. Without a prior the floor decides.
  const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> motions = {
      {{0.0, 0.0, 0.05}, {0.6, 0.0, 0.0}},
      {{0.02, -0.01, M_PI}, {0.0, 0.7, 0.05}},
      {{0.0, 0.03, M_PI / 2}, {0.4, 0.4, -0.1}}};
  unsigned seed = 40;
  for (const auto& [rpy, t] : motions) {
    const Eigen::Matrix3d R = core::rotation_from_euler(rpy);
    const Scene s = plane_scene(R, t, 0.0, 200, ++seed);
    const EssentialEstimate e =
        estimate_essential(s.i, s.j, s.matches, test::sim_camera(), {}, nullptr);
    ASSERT_TRUE(e.ok) << "heading " << rpy.z() << ": " << e.reason;
    EXPECT_LT(angle_deg(e.R_i_j, R), 0.3) << "heading " << rpy.z();
    EXPECT_GT(e.t_i_j_unit.dot(t.normalized()), std::cos(2.0 * M_PI / 180.0))
        << "heading " << rpy.z();
  }
}

TEST(Essential, ClimbingOverAFlatFloorTheTwinTiesAndTheFloorDecides) {
  // Forward 0.5 m while climbing 0.6 m over a floor 3 m down: the planar twin puts as many
  // points in front and fits as well, its floor tilted about 35 deg. The floor test decides;
  // with floor_max_tilt_deg 0 (no floor trusted) the pair fails as ambiguous.
  const Eigen::Matrix3d R = core::rotation_from_euler(Eigen::Vector3d(0.0, 0.0, 0.1));
  const Eigen::Vector3d t(0.5, 0.0, -0.6);
  const Scene s = plane_scene(R, t, 0.0, 200, 8);
  const EssentialEstimate e =
      estimate_essential(s.i, s.j, s.matches, test::sim_camera(), {}, nullptr);
  ASSERT_TRUE(e.ok) << e.reason;
  EXPECT_LT(angle_deg(e.R_i_j, R), 0.3);
  EXPECT_GT(e.t_i_j_unit.dot(t.normalized()), std::cos(2.0 * M_PI / 180.0));
  EssentialOptions no_floor;
  no_floor.floor_max_tilt_deg = 0.0;
  const EssentialEstimate refused =
      estimate_essential(s.i, s.j, s.matches, test::sim_camera(), no_floor, nullptr);
  EXPECT_FALSE(refused.ok);
  EXPECT_NE(refused.reason.find("planar ambiguity"), std::string::npos) << refused.reason;
}

TEST(Essential, TiltedPlanesWithoutPriorGiveTheTruthOrAnAmbiguity) {
  // Slopes up to a wall: the answer is the truth or a failure that says why, never the twin.
  int right = 0, ambiguous = 0;
  unsigned seed = 60;
  for (const double tilt_deg : {20.0, 40.0, 55.0, 70.0}) {
    for (const Eigen::Vector3d& t :
         {Eigen::Vector3d(0.6, 0.0, 0.0), Eigen::Vector3d(0.0, 0.6, 0.1)}) {
      const Eigen::Matrix3d R = core::rotation_from_euler(Eigen::Vector3d(0.0, 0.02, 0.3));
      const Scene s = plane_scene(R, t, tilt_deg, 200, ++seed);
      const EssentialEstimate e =
          estimate_essential(s.i, s.j, s.matches, test::sim_camera(), {}, nullptr);
      if (!e.ok) {
        EXPECT_NE(e.reason.find("planar ambiguity"), std::string::npos) << e.reason;
        ++ambiguous;
        continue;
      }
      EXPECT_LT(angle_deg(e.R_i_j, R), 0.3) << "tilt " << tilt_deg << ", t " << t.transpose();
      EXPECT_GT(e.t_i_j_unit.dot(t.normalized()), std::cos(2.0 * M_PI / 180.0))
          << "tilt " << tilt_deg << ", t " << t.transpose();
      ++right;
    }
  }
  std::printf("tilted planes: %d right, %d ambiguous of 8\n", right, ambiguous);
  EXPECT_GE(right, 4);
}

}  // namespace
}  // namespace nav::vision
