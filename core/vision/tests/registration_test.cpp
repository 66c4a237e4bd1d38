// Registration pipeline on the Skerki and mosaic images (no calibration recorded: a nominal
// pinhole, f = image width, centre, no distortion) and on bad input.
#include "nav/vision/registration.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <Eigen/Geometry>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numbers>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "nav/core/geometry/rotation.h"
#include "nav/testing/data.h"
#include "nav/vision/camera_model.h"
#include "nav/vision/relative_pose_5dof.h"

namespace nav::vision {
namespace {

cv::Mat read(const std::filesystem::path& path) {
  return cv::imread(path.string(), cv::IMREAD_UNCHANGED);
}

TEST(Registration, SkerkiConsecutivePairsWithinAStripRegister) {
  NAV_REQUIRE_DATA(first, "images/skerki/img_1.tif");
  std::vector<cv::Mat> images;
  for (int k = 1; k <= 6; ++k) {
    images.push_back(read(first.parent_path() / ("img_" + std::to_string(k) + ".tif")));
    ASSERT_FALSE(images.back().empty());
  }
  const Registration registration(nominal_pinhole(images[0].cols, images[0].rows),
                                  RegistrationOptions{});
  std::vector<ImageFeatures> features;
  for (const cv::Mat& image : images) features.push_back(registration.features(image));
  for (auto [i, j] : {std::pair{0, 1}, std::pair{1, 2}, std::pair{3, 4}, std::pair{4, 5}}) {
    const RegistrationResult r = registration.register_pair(features[static_cast<std::size_t>(i)],
                                                            features[static_cast<std::size_t>(j)], nullptr);
    std::printf("Skerki img_%d-img_%d: features %zu/%zu, putative %d, inliers %d, %s\n", i + 1,
                j + 1, features[static_cast<std::size_t>(i)].size(),
                features[static_cast<std::size_t>(j)].size(), r.putative_matches, r.inliers,
                r.success ? "registered" : r.reason.c_str());
    EXPECT_TRUE(r.success) << "img_" << i + 1 << "-img_" << j + 1 << ": " << r.reason;
    EXPECT_GE(r.inliers, 30);
  }
}

TEST(Registration, ConcurrentCallsGiveTheSequentialResults) {
  // One Registration shared by two threads: features of different images, then pairs.
  NAV_REQUIRE_DATA(first, "images/skerki/img_1.tif");
  const cv::Mat a = read(first), b = read(first.parent_path() / "img_2.tif");
  const Registration registration(nominal_pinhole(a.cols, a.rows), RegistrationOptions{});
  const ImageFeatures fa = registration.features(a), fb = registration.features(b);
  const RegistrationResult sequential = registration.register_pair(fa, fb, nullptr);
  ASSERT_TRUE(sequential.success) << sequential.reason;

  ImageFeatures ta, tb;
  RegistrationResult r1, r2;
  {
    std::thread t1([&] { ta = registration.features(a); });
    std::thread t2([&] { tb = registration.features(b); });
    t1.join();
    t2.join();
  }
  EXPECT_EQ(ta.size(), fa.size());
  EXPECT_EQ(tb.size(), fb.size());
  EXPECT_EQ(cv::norm(ta.descriptors, fa.descriptors, cv::NORM_INF), 0.0);
  {
    std::thread t1([&] { r1 = registration.register_pair(fa, fb, nullptr); });
    std::thread t2([&] { r2 = registration.register_pair(fa, fb, nullptr); });
    t1.join();
    t2.join();
  }
  for (const RegistrationResult* r : {&r1, &r2}) {
    ASSERT_TRUE(r->success) << r->reason;
    // LMedS draws random samples (OpenCV's per-thread generator): equal to well within noise.
    EXPECT_LT((r->z - sequential.z).cwiseAbs().maxCoeff(), 2e-3);
  }
}

TEST(Registration, MosaicScenePairRegisters) {
  NAV_REQUIRE_DATA(path1, "images/mosaic-scene/scene1.png");
  const cv::Mat a = read(path1), b = read(path1.parent_path() / "scene2.png");
  ASSERT_FALSE(a.empty());
  ASSERT_FALSE(b.empty());
  const Registration registration(nominal_pinhole(a.cols, a.rows), RegistrationOptions{});
  const ImageFeatures fa = registration.features(a), fb = registration.features(b);
  const RegistrationResult r = registration.register_pair(fa, fb, nullptr);
  std::printf("mosaic scene1-scene2: features %zu/%zu, putative %d, inliers %d, %s\n", fa.size(),
              fb.size(), r.putative_matches, r.inliers, r.success ? "registered" : r.reason.c_str());
  EXPECT_TRUE(r.success) << r.reason;
  EXPECT_GE(r.inliers, 30);
}

// The same pair resampled to 3840x2160 (a camera with four times the pixels): its features are
// localised to about 1 px, three times the configured 0.3 px, which failed the refinement while
// the outlier kink stayed at 3 configured sigmas (two_view_refinement.h). It registers, the
// noise it measures doubles with the resolution, and the pose agrees with the native one.
TEST(Registration, MosaicScenePairResampledToTwiceItsSizeGivesTheSamePose) {
  NAV_REQUIRE_DATA(path1, "images/mosaic-scene/scene1.png");
  const cv::Mat a = read(path1), b = read(path1.parent_path() / "scene2.png");
  ASSERT_FALSE(a.empty());
  ASSERT_FALSE(b.empty());
  cv::Mat a2, b2;
  cv::resize(a, a2, {}, 2.0, 2.0, cv::INTER_CUBIC);
  cv::resize(b, b2, {}, 2.0, 2.0, cv::INTER_CUBIC);
  const Registration native(nominal_pinhole(a.cols, a.rows), RegistrationOptions{});
  const Registration twice(nominal_pinhole(a2.cols, a2.rows), RegistrationOptions{});
  const RegistrationResult r1 =
      native.register_pair(native.features(a), native.features(b), nullptr);
  const RegistrationResult r2 =
      twice.register_pair(twice.features(a2), twice.features(b2), nullptr);
  ASSERT_TRUE(r1.success) << r1.reason;
  ASSERT_TRUE(r2.success) << r2.reason;
  const Vec5 dz = z_minus(r2.z, r1.z);
  const double chi2 = dz.dot((r1.covariance + r2.covariance).ldlt().solve(dz));
  const double rotation_deg =
      Eigen::AngleAxisd(rotation_from_z(r1.z).transpose() * rotation_from_z(r2.z)).angle() * 180.0 /
      std::numbers::pi;
  std::printf(
      "mosaic pair x1 / x2: inliers %d / %d, noise %.2f / %.2f px, rotation apart %.3f "
      "deg, chi2 of the difference %.2f\n",
      r1.inliers, r2.inliers, r1.noise_sigma_px, r2.noise_sigma_px, rotation_deg, chi2);
  EXPECT_GT(r2.noise_sigma_px, 1.5 * r1.noise_sigma_px);
  EXPECT_GE(r2.inliers, 500);
  EXPECT_LT(rotation_deg, 0.1);
  EXPECT_LT(chi2, 20.5);  // chi2_5(0.999); the two answers share their images, so this is loose
}

TEST(Registration, BadImagesGiveErrorsNotCrashes) {
  NAV_REQUIRE_DATA(path, "images/sparus/frame_01.png");
  CameraIntrinsics camera = nominal_pinhole(384, 288);
  const Registration registration(camera, RegistrationOptions{});
  ImageFeatures f;
  // Empty.
  EXPECT_THROW(registration.features(cv::Mat()), std::invalid_argument);
  // Truncated file: imread gives an empty image, reported as such.
  const std::filesystem::path truncated =
      std::filesystem::temp_directory_path() / "nav_vision_truncated.png";
  {
    std::ifstream in(path, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(truncated, std::ios::binary).write(bytes.data(), 200);
  }
  const core::Status s_truncated = registration.try_features(read(truncated), &f);
  std::filesystem::remove(truncated);
  EXPECT_FALSE(s_truncated.ok());
  EXPECT_NE(s_truncated.message().find("empty"), std::string::npos) << s_truncated.message();
  // Wrong depth: float image; 16-bit data beyond 12 bits.
  EXPECT_FALSE(registration.try_features(cv::Mat(288, 384, CV_32F, cv::Scalar(0.2)), &f).ok());
  EXPECT_FALSE(registration.try_features(cv::Mat(288, 384, CV_16U, cv::Scalar(60000)), &f).ok());
  // Missing calibration.
  camera.fx_px = camera.fy_px = 0.0;
  const Registration uncalibrated(camera, RegistrationOptions{});
  const core::Status s_missing = uncalibrated.try_features(read(path), &f);
  EXPECT_FALSE(s_missing.ok());
  EXPECT_NE(s_missing.message().find("missing calibration"), std::string::npos);
  const RegistrationResult r = uncalibrated.register_pair(ImageFeatures{}, ImageFeatures{}, nullptr);
  EXPECT_FALSE(r.success);
  EXPECT_EQ(r.failure, RegistrationFailure::kBadImage);
  // Featureless image: a failure with a reason, not a crash.
  const ImageFeatures blank = registration.features(cv::Mat(288, 384, CV_8U, cv::Scalar(90)));
  const RegistrationResult r_blank = registration.register_pair(blank, blank, nullptr);
  EXPECT_FALSE(r_blank.success);
  EXPECT_EQ(r_blank.failure, RegistrationFailure::kTooFewFeatures) << r_blank.reason;
}

TEST(Registration, PureRotationPairFailsWithReason) {
  NAV_REQUIRE_DATA(path, "images/skerki/img_2.tif");
  const cv::Mat image = read(path);
  const CameraIntrinsics camera = nominal_pinhole(image.cols, image.rows);
  // A camera rotating about its centre sees the infinite homography K R K^-1: no parallax.
  const Eigen::Matrix3d R = core::rotation_from_euler(Eigen::Vector3d(0.01, 0.02, 0.05));
  Eigen::Matrix3d K;
  K << camera.fx_px, 0, camera.cx_px, 0, camera.fy_px, camera.cy_px, 0, 0, 1;
  const Eigen::Matrix3d H = K * R.transpose() * K.inverse();  // pixel of i -> pixel of j
  cv::Mat H_cv(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) H_cv.at<double>(r, c) = H(r, c);
  cv::Mat rotated;
  cv::warpPerspective(image, rotated, H_cv, image.size(), cv::INTER_LINEAR);
  const Registration registration(camera, RegistrationOptions{});
  const RegistrationResult r =
      registration.register_pair(registration.features(image), registration.features(rotated), nullptr);
  std::printf("pure rotation: putative %d, inliers %d, reason: %s\n", r.putative_matches,
              r.inliers, r.reason.c_str());
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.failure, RegistrationFailure::kOk);
  EXPECT_FALSE(r.reason.empty());
}

TEST(Registration, NoOverlapPairFailsWithReason) {
  NAV_REQUIRE_DATA(skerki, "images/skerki/img_1.tif");
  NAV_REQUIRE_DATA(scene, "images/mosaic-scene/scene1.png");
  const cv::Mat a = read(skerki);
  cv::Mat b;
  cv::resize(read(scene), b, a.size(), 0, 0, cv::INTER_AREA);
  const Registration registration(nominal_pinhole(a.cols, a.rows), RegistrationOptions{});
  const RegistrationResult r =
      registration.register_pair(registration.features(a), registration.features(b), nullptr);
  std::printf("no overlap: putative %d, inliers %d, reason: %s\n", r.putative_matches, r.inliers,
              r.reason.c_str());
  EXPECT_FALSE(r.success);
  EXPECT_FALSE(r.reason.empty());
}

}  // namespace
}  // namespace nav::vision
