// Camera model: undistortion against OpenCV's forward projection (independent reference),
// normalisation round trips and validation messages.
#include "nav/vision/camera_model.h"

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>

#include <vector>

namespace nav::vision {
namespace {

CameraIntrinsics distorted_camera() {
  CameraIntrinsics c;
  c.fx_px = 405.6;
  c.fy_px = 405.5;
  c.cx_px = 189.9;
  c.cy_px = 139.9;
  c.k1 = -0.367;
  c.k2 = 0.203;
  c.p1 = 0.0033;
  c.p2 = -0.0005;
  c.width_px = 384;
  c.height_px = 288;
  return c;
}

TEST(CameraModel, UndistortInvertsOpenCvForwardDistortion) {
  const CameraIntrinsics c = distorted_camera();
  // Ideal normalised points across the image, distorted by cv::projectPoints.
  std::vector<cv::Point3d> rays;
  for (double x = -0.4; x <= 0.4; x += 0.1) {
    for (double y = -0.3; y <= 0.3; y += 0.1) rays.emplace_back(x, y, 1.0);
  }
  std::vector<cv::Point2d> distorted;
  cv::projectPoints(rays, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(camera_matrix(c)),
                    distortion_coefficients(c), distorted);
  std::vector<cv::Point2f> distorted_f(distorted.begin(), distorted.end());
  const std::vector<Eigen::Vector2d> ideal = undistort_pixels(c, distorted_f);
  ASSERT_EQ(ideal.size(), rays.size());
  for (std::size_t k = 0; k < rays.size(); ++k) {
    const Eigen::Vector2d expected = pixel_from_normalised(c, {rays[k].x, rays[k].y});
    EXPECT_LT((ideal[k] - expected).norm(), 0.01) << "ray " << rays[k];
  }
}

TEST(CameraModel, NormalisedPixelRoundTrip) {
  const CameraIntrinsics c = distorted_camera();
  const Eigen::Vector2d u(12.5, 250.25);
  EXPECT_LT((pixel_from_normalised(c, normalised_from_pixel(c, u)) - u).norm(), 1e-12);
  EXPECT_NEAR(normalised_from_pixel(c, {c.cx_px, c.cy_px}).norm(), 0.0, 1e-15);
}

TEST(CameraModel, ValidationNamesTheProblem) {
  EXPECT_TRUE(validate(distorted_camera()).ok());
  CameraIntrinsics c = distorted_camera();
  c.fx_px = 0.0;
  EXPECT_NE(validate(c).message().find("missing calibration"), std::string::npos);
  c = distorted_camera();
  c.cx_px = 1000.0;
  EXPECT_NE(validate(c).message().find("outside the 384x288 image"), std::string::npos);
  const CameraIntrinsics nominal = nominal_pinhole(576, 384);
  EXPECT_TRUE(validate(nominal).ok());
  EXPECT_EQ(nominal.fx_px, 576.0);
  EXPECT_FALSE(has_distortion(nominal));
}

}  // namespace
}  // namespace nav::vision
