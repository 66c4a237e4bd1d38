// Real-frame registration of the Sparus dataset: pairs 1, 3 and 6 frames apart, relative
// rotation against the interpolated logged camera attitude.
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "nav/testing/data.h"
#include "nav/vision/registration.h"
#include "sparus_truth.h"

namespace nav::vision {
namespace {

CameraIntrinsics sparus_camera() {
  CameraIntrinsics c;
  c.fx_px = 405.6384738851233;
  c.fy_px = 405.588335378204;
  c.cx_px = 189.9054317917407;
  c.cy_px = 139.9149578253755;
  c.k1 = -0.3670656233416921;
  c.k2 = 0.203001968694465;
  c.p1 = 0.003336917744124004;
  c.p2 = -0.000487426354679637;
  c.width_px = 384;
  c.height_px = 288;
  return c;
}

constexpr double kDeg = 180.0 / std::numbers::pi;

TEST(SparusRegistration, MedianRotationErrorOfPairs1_3_6Apart) {
  NAV_REQUIRE_DATA(frames_csv, "images/sparus/frames.csv");
  const auto truth = testing::load_sparus_truth(frames_csv.parent_path().string());
  ASSERT_EQ(truth.frame_files.size(), 22u);
  const Registration registration(sparus_camera());
  std::vector<ImageFeatures> features;
  const auto t0 = std::chrono::steady_clock::now();
  for (const auto& file : truth.frame_files) {
    const cv::Mat image = cv::imread((frames_csv.parent_path() / file).string(), cv::IMREAD_UNCHANGED);
    features.push_back(registration.features(image));
  }
  std::printf("features: %.1f ms per frame\n",
              std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() /
                  static_cast<double>(features.size()));
  std::vector<double> errors_deg, errors_alt_deg;
  int successes = 0;
  for (std::size_t gap : {1u, 3u, 6u}) {
    for (std::size_t i = 0; i + gap < features.size(); i += gap) {
      const std::size_t j = i + gap;
      RegistrationDiagnostics diagnostics;
      const RegistrationResult r = registration.register_pair(features[i], features[j], nullptr,
                                                              &diagnostics);
      if (!r.success) {
        std::printf("pair %zu-%zu failed: %s\n", i + 1, j + 1, r.reason.c_str());
        errors_deg.push_back(180.0);
        continue;
      }
      ++successes;
      const Eigen::Matrix3d R_est = diagnostics.essential.R_i_j;
      const double e = testing::rotation_angle_between(R_est, truth.R_i_j(i, j)) * kDeg;
      errors_deg.push_back(e);
      std::printf("pair %2zu-%2zu: matches %4d inliers %4d rotation error %.3f deg (truth %.2f deg) "
                  "match %.1f ms essential %.1f ms\n",
                  i + 1, j + 1, r.putative_matches, r.inliers, e,
                  Eigen::AngleAxisd(truth.R_i_j(i, j)).angle() * kDeg, diagnostics.timings.matching_ms,
                  diagnostics.timings.essential_ms);
    }
  }
  ASSERT_EQ(errors_deg.size(), 31u);
  std::vector<double> sorted = errors_deg;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted[sorted.size() / 2];
  std::printf("Sparus: %d/29 registered, median rotation error %.3f deg\n", successes, median);
  RecordProperty("median_rotation_error_deg", std::to_string(median));
  EXPECT_GE(successes, 27);
  EXPECT_LE(median, 1.0);
}

}  // namespace
}  // namespace nav::vision
