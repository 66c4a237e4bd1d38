// Feature extraction on large frames: SIFT detection and the descriptors run on a pyramid level
// (FeatureOptions::max_description_width_px), the keypoints come back in full-resolution
// pixels, keypoints sit where their image content is (no sub-pixel offset: an offset common to
// both images of a pair does not cancel when the second camera is turned, as on adjacent survey
// lines), and a saturated or wrong-size 12-bit frame is an error or a failure with a reason.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "nav/testing/data.h"
#include "nav/vision/camera_model.h"
#include "nav/vision/registration.h"

namespace nav::vision {
namespace {

/// Median distance from each point of `a` (scaled by `scale`) to its nearest point of `b`.
double median_nearest_px(const ImageFeatures& a, double scale, const ImageFeatures& b) {
  std::vector<double> d;
  for (const auto& p : a.points_px) {
    double best = 1e9;
    for (const auto& q : b.points_px) best = std::min(best, (scale * p - q).norm());
    d.push_back(best);
  }
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  return d[d.size() / 2];
}

TEST(Features, PyramidLevelKeypointsAreInFullResolutionPixels) {
  NAV_REQUIRE_DATA(path, "images/sparus/frame_01.png");
  const cv::Mat grey = cv::imread(path, cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(grey.empty());
  cv::Mat small, large;
  cv::resize(grey, small, cv::Size(768, 576), 0, 0, cv::INTER_CUBIC);  // described at level 0
  cv::resize(grey, large, cv::Size(1536, 1152), 0, 0, cv::INTER_CUBIC);  // at level 1
  FeatureOptions options;
  options.use_harris = false;  // SIFT only: detected on the level image, then scaled back
  ImageFeatures f_small, f_large;
  const CameraIntrinsics cam_small = nominal_pinhole(768, 576), cam_large = nominal_pinhole(1536, 1152);
  ASSERT_TRUE(extract_features(small, cam_small, true, options, &f_small).ok());
  ASSERT_TRUE(extract_features(large, cam_large, true, options, &f_large).ok());
  ASSERT_GT(f_small.size(), 100u);
  ASSERT_GT(f_large.size(), 100u);
  // The same image content: keypoints of the large frame sit where twice the small frame's do
  // (a wrong level scale or offset would move them by tens of pixels).
  EXPECT_LT(median_nearest_px(f_small, 2.0, f_large), 1.5);
  EXPECT_EQ(f_large.width_px, 1536);
  // Full resolution (no level) finds them at the same place too.
  options.max_description_width_px = 0;
  ImageFeatures f_full;
  ASSERT_TRUE(extract_features(large, cam_large, true, options, &f_full).ok());
  EXPECT_LT(median_nearest_px(f_large, 1.0, f_full), 1.5);
}

/// Smoothed Gaussian noise, 8 bit: texture at every position, no preferred direction.
cv::Mat noise_texture(int width_px, int height_px) {
  cv::Mat n(height_px, width_px, CV_32F);
  cv::RNG rng(7);
  rng.fill(n, cv::RNG::NORMAL, 0.0, 1.0);
  cv::GaussianBlur(n, n, cv::Size(), 2.5);
  cv::Mat out;
  cv::normalize(n, n, 0.0, 255.0, cv::NORM_MINMAX);
  n.convertTo(out, CV_8U);
  return out;
}

struct Offset {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  int count = 0;
};

/// Mean of (nearest point of `b` within 1 px) - a over the points of `a` that have one.
Offset mean_offset(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b) {
  Offset o;
  for (const auto& p : a) {
    const Eigen::Vector2d* best = nullptr;
    for (const auto& q : b)
      if ((q - p).norm() < 1.0 && (best == nullptr || (q - p).norm() < (*best - p).norm())) best = &q;
    if (best == nullptr) continue;
    o.mean += *best - p;
    ++o.count;
  }
  if (o.count > 0) o.mean /= o.count;
  return o;
}

// The image turned by 180 deg: a detector that places every keypoint c pixels off its content
// finds the turned keypoints, turned back, 2c away from the originals.
TEST(Features, KeypointsOfTheTurnedImageTurnBackOntoTheOriginals) {
  for (const int width : {640, 1280}) {  // SIFT at full resolution, and on the halved level
    const cv::Mat image = noise_texture(width, width * 4 / 5);
    cv::Mat turned;
    cv::flip(image, turned, -1);
    const CameraIntrinsics camera = nominal_pinhole(image.cols, image.rows);
    for (const bool harris : {true, false}) {
      FeatureOptions options;
      options.use_harris = harris;
      options.use_sift = !harris;
      ImageFeatures f, g;
      ASSERT_TRUE(extract_features(image, camera, true, options, &f).ok());
      ASSERT_TRUE(extract_features(turned, camera, true, options, &g).ok());
      for (auto& q : g.points_px) q = Eigen::Vector2d(image.cols - 1, image.rows - 1) - q;
      const Offset o = mean_offset(f.points_px, g.points_px);
      SCOPED_TRACE(std::string(harris ? "Harris" : "SIFT") + " at width " + std::to_string(width));
      EXPECT_GT(o.count, static_cast<int>(0.8 * static_cast<double>(f.size())));
      EXPECT_LT(o.mean.norm(), 0.05) << o.mean.transpose();  // OpenCV's SIFT alone: 0.5 / 1.0 px
    }
  }
}

// Gaussian blobs at known sub-pixel centres (pixel (u, v) samples the intensity at u, v): SIFT
// finds their centres, at full resolution and through the halved level.
TEST(Features, SiftKeypointsSitOnBlobCentres) {
  for (const int width : {640, 1280}) {
    const int height = width * 4 / 5;
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> jitter(-2.0, 2.0);
    std::vector<Eigen::Vector2d> centres;
    for (double y = 20.0; y < height - 20; y += 40.0)
      for (double x = 20.0; x < width - 20; x += 40.0) centres.emplace_back(x + jitter(rng), y + jitter(rng));
    cv::Mat image(height, width, CV_8U);
    for (int v = 0; v < height; ++v)
      for (int u = 0; u < width; ++u) {
        double value = 30.0;
        for (const auto& c : centres)
          if (std::abs(c.x() - u) < 16 && std::abs(c.y() - v) < 16)
            value += 200.0 * std::exp(-(Eigen::Vector2d(u, v) - c).squaredNorm() / 32.0);
        image.at<std::uint8_t>(v, u) = cv::saturate_cast<std::uint8_t>(value);
      }
    FeatureOptions options;
    options.use_harris = false;
    ImageFeatures f;
    ASSERT_TRUE(extract_features(image, nominal_pinhole(width, height), true, options, &f).ok());
    const Offset o = mean_offset(f.points_px, centres);
    EXPECT_GT(o.count, static_cast<int>(0.8 * static_cast<double>(centres.size()))) << width;
    EXPECT_LT(o.mean.norm(), 0.05) << width << ": " << o.mean.transpose();
  }
}

TEST(Features, SaturatedOrWrongSizeTwelveBitFrameFailsWithReason) {
  const CameraIntrinsics camera = nominal_pinhole(1280, 1024);
  const Registration registration(camera);
  ImageFeatures f;
  const core::Status wrong_size = registration.try_features(cv::Mat(512, 640, CV_16U, cv::Scalar(900)), &f);
  EXPECT_FALSE(wrong_size.ok());
  EXPECT_NE(wrong_size.message().find("calibration is for 1280x1024"), std::string::npos)
      << wrong_size.message();
  // All pixels at full scale (a hull top too close to the strobe): no features, a failure.
  ASSERT_TRUE(registration.try_features(cv::Mat(1024, 1280, CV_16U, cv::Scalar(4095)), &f).ok());
  const RegistrationResult r = registration.register_pair(f, f, nullptr);
  EXPECT_FALSE(r.success);
  EXPECT_EQ(r.failure, RegistrationFailure::kTooFewFeatures) << r.reason;
}

}  // namespace
}  // namespace nav::vision
