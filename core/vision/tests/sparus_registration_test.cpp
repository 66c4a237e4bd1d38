// Real-frame registration of the Sparus dataset: pairs 1, 3 and 6 frames apart (every
// consecutive pair, and the non-overlapping chains 1-4-7-..-22 and 1-7-13-19: 21 + 7 + 3 = 31
// pairs), relative rotation against the interpolated logged camera attitude, with the robust
// estimator LMedS (the paper's) measured against RANSAC and USAC (MAGSAC++).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <utility>
#include <vector>

#include "nav/core/geometry/rotation.h"
#include "nav/testing/data.h"
#include "nav/vision/registration.h"
#include "sparus_truth.h"
#include "test_cameras.h"

namespace nav::vision {
namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

std::vector<std::pair<std::size_t, std::size_t>> sparus_pairs(std::size_t frames) {
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t gap : {1u, 3u, 6u}) {
    for (std::size_t i = 0; i + gap < frames; i += gap) pairs.emplace_back(i, i + gap);
  }
  return pairs;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

struct Evaluation {
  std::vector<double> errors_deg;  ///< 180 for a failed pair.
  std::vector<double> inliers;
  int successes = 0;
  double pair_ms = 0.0;
};

Evaluation evaluate(const Registration& registration, const std::vector<ImageFeatures>& features,
                    const testing::SparusTruth& truth, bool print) {
  Evaluation e;
  for (auto [i, j] : sparus_pairs(features.size())) {
    RegistrationDiagnostics d;
    const RegistrationResult r = registration.register_pair(features[i], features[j], nullptr, &d);
    e.pair_ms += d.timings.total_ms;
    if (!r.success) {
      if (print) std::printf("pair %2zu-%2zu failed: %s\n", i + 1, j + 1, r.reason.c_str());
      e.errors_deg.push_back(180.0);
      continue;
    }
    ++e.successes;
    // The pipeline's answer: R_i_j from the measurement's roll, pitch, heading.
    const Eigen::Matrix3d R_i_j = core::rotation_from_euler(r.z.tail<3>());
    const double err = testing::rotation_angle_between(R_i_j, truth.R_i_j(i, j)) * kDeg;
    e.errors_deg.push_back(err);
    e.inliers.push_back(r.inliers);
    if (print) {
      std::printf("pair %2zu-%2zu: putative %4d inliers %4d rotation %.2f deg, error %.3f deg\n",
                  i + 1, j + 1, r.putative_matches, r.inliers,
                  Eigen::AngleAxisd(truth.R_i_j(i, j)).angle() * kDeg, err);
    }
  }
  e.pair_ms /= static_cast<double>(e.errors_deg.size());
  return e;
}

TEST(SparusRegistration, MedianRotationErrorOfPairs1_3_6ApartAndRobustEstimators) {
  NAV_REQUIRE_DATA(frames_csv, "images/sparus/frames.csv");
  const auto truth = testing::load_sparus_truth(frames_csv.parent_path().string());
  ASSERT_EQ(truth.frame_files.size(), 22u);
  ASSERT_GE(truth.knot_times_s.size(), 10u);
  const Registration lmeds(test::sparus_camera());
  std::vector<ImageFeatures> features;
  const auto t0 = std::chrono::steady_clock::now();
  for (const auto& file : truth.frame_files) {
    const cv::Mat image =
        cv::imread((frames_csv.parent_path() / file).string(), cv::IMREAD_UNCHANGED);
    features.push_back(lmeds.features(image));
  }
  std::printf(
      "features: %.1f ms per 384x288 frame\n",
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() /
          static_cast<double>(features.size()));

  const Evaluation e = evaluate(lmeds, features, truth, true);
  ASSERT_EQ(e.errors_deg.size(), 31u);
  std::printf(
      "LMedS: %d/31 registered, median rotation error %.3f deg, median inliers %.0f, "
      "%.1f ms per pair\n",
      e.successes, median(e.errors_deg), median(e.inliers), e.pair_ms);
  RecordProperty("lmeds_median_rotation_error_deg", std::to_string(median(e.errors_deg)));
  EXPECT_GE(e.successes, 29);
  EXPECT_LE(median(e.errors_deg), 0.75);

  for (RobustMethod method : {RobustMethod::kRansac, RobustMethod::kUsacMagsac}) {
    RegistrationOptions options;
    options.essential.method = method;
    const Evaluation other =
        evaluate(Registration(test::sparus_camera(), options), features, truth, false);
    std::printf(
        "%s: %d/31 registered, median rotation error %.3f deg, median inliers %.0f, "
        "%.1f ms per pair\n",
        method == RobustMethod::kRansac ? "RANSAC" : "USAC-MAGSAC", other.successes,
        median(other.errors_deg), median(other.inliers), other.pair_ms);
    // The comparison is reported; each estimator must still register the overlapping pairs.
    EXPECT_GE(other.successes, 27);
  }
}

}  // namespace
}  // namespace nav::vision
