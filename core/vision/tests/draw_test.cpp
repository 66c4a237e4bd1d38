// The Fig. 4 picture: size and type, epipolar lines drawn over the pair, PCCS bands on the
// lines of their features.
#include "nav/vision/draw.h"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "nav/testing/data.h"
#include "nav/vision/camera_model.h"

namespace nav::vision {
namespace {

TEST(Draw, PairPictureWithEpipolarLinesAndSearchBands) {
  NAV_REQUIRE_DATA(path1, "images/skerki/img_1.tif");
  const cv::Mat a = cv::imread(path1.string(), cv::IMREAD_UNCHANGED);
  const cv::Mat b = cv::imread((path1.parent_path() / "img_2.tif").string(), cv::IMREAD_UNCHANGED);
  const CameraIntrinsics camera = nominal_pinhole(a.cols, a.rows);
  const Registration registration(camera);
  const ImageFeatures fa = registration.features(a), fb = registration.features(b);
  RegistrationDiagnostics d;
  const RegistrationResult r = registration.register_pair(fa, fb, nullptr, &d);
  ASSERT_TRUE(r.success) << r.reason;

  // A prior at the measured pose (unit baseline; depth 3 +- 1 baseline units).
  RelativePosePrior prior;
  prior.x_i_j.head<3>() = d.refinement.t_i_j_unit;
  prior.x_i_j.tail<3>() = r.z.tail<3>();
  prior.covariance = Mat6::Identity() * 1e-4;
  prior.scene_depth_m = 3.0;
  prior.scene_depth_sigma_m = 1.0;
  const DrawOptions options;
  const std::vector<SearchBand> bands =
      search_bands(fa, d, camera, &prior, PccsOptions{}, options.max_epipolar_lines);
  ASSERT_EQ(static_cast<int>(bands.size()), options.max_epipolar_lines);
  int non_empty = 0;
  for (const SearchBand& band : bands) {
    if (band.centres_px.empty()) continue;
    ++non_empty;
    EXPECT_EQ(band.centres_px.size(), band.half_widths_px.size());
    // Each band centre lies on the epipolar line of its feature under the measured pose: the
    // prior is the measured pose, so the distance is small compared with the band width.
    const Eigen::Vector2d x_i = normalised_from_pixel(camera, fa.points_px[static_cast<std::size_t>(band.feature_i)]);
    const Eigen::Vector3d l = d.essential.E.transpose() * Eigen::Vector3d(x_i.x(), x_i.y(), 1.0);
    for (const Eigen::Vector2d& c : band.centres_px) {
      const Eigen::Vector2d x_j = normalised_from_pixel(camera, c);
      const double dist_px = std::abs(l.dot(Eigen::Vector3d(x_j.x(), x_j.y(), 1.0))) /
                             l.head<2>().norm() * camera.fx_px;
      EXPECT_LT(dist_px, 5.0);
    }
  }
  EXPECT_GE(non_empty, options.max_epipolar_lines / 2);

  cv::Mat grey_a, grey_b;
  ASSERT_TRUE(registration.try_preprocess(a, &grey_a).ok());
  ASSERT_TRUE(registration.try_preprocess(b, &grey_b).ok());
  const cv::Mat picture = draw_registration(grey_a, grey_b, fa, fb, d, camera, bands);
  EXPECT_EQ(picture.type(), CV_8UC3);
  EXPECT_EQ(picture.cols, a.cols + b.cols);
  EXPECT_EQ(picture.rows, a.rows);
  // Drawing changed pixels of both halves relative to the plain grey images.
  cv::Mat plain_left, plain_right;
  cv::cvtColor(grey_a, plain_left, cv::COLOR_GRAY2BGR);
  cv::cvtColor(grey_b, plain_right, cv::COLOR_GRAY2BGR);
  cv::Mat diff_left, diff_right;
  cv::absdiff(picture(cv::Rect(0, 0, a.cols, a.rows)), plain_left, diff_left);
  cv::absdiff(picture(cv::Rect(a.cols, 0, b.cols, b.rows)), plain_right, diff_right);
  EXPECT_GT(cv::countNonZero(diff_left.reshape(1)), 500);
  EXPECT_GT(cv::countNonZero(diff_right.reshape(1)), 2000);
}

}  // namespace
}  // namespace nav::vision
