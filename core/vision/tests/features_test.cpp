// Feature extraction on large frames: SIFT detection and the descriptors run on a pyramid level
// (FeatureOptions::max_description_width_px), the keypoints come back in full-resolution
// pixels, and a saturated or wrong-size 12-bit frame is an error or a failure with a reason.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
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
