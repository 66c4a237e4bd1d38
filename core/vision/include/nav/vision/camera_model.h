#pragma once
// Pinhole camera with OpenCV's radial-tangential distortion: conversions between distorted
// pixels (as recorded), ideal pixels (undistorted, same intrinsics) and normalised image
// coordinates (x/z, y/z in the camera frame). Hartley & Zisserman, "Multiple View Geometry",
// 2nd ed., section 6.1 (pinhole) and 7.4 (radial distortion).

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <vector>

#include "nav/core/status.h"
#include "nav/vision/vision_types.h"

namespace nav::vision {

/// OK when the focal lengths are positive and finite, the principal point finite and, when a
/// size is given, inside the image. The message names the offending field.
core::Status validate(const CameraIntrinsics& camera);

/// 3x3 calibration matrix K (pixels).
cv::Matx33d camera_matrix(const CameraIntrinsics& camera);

/// OpenCV distortion vector (k1, k2, p1, p2, k3).
cv::Mat distortion_coefficients(const CameraIntrinsics& camera);

/// True when any distortion coefficient is non-zero.
bool has_distortion(const CameraIntrinsics& camera);

/// Ideal (undistorted) pixel coordinates of recorded pixel coordinates; identity when the
/// camera has no distortion.
std::vector<Eigen::Vector2d> undistort_pixels(const CameraIntrinsics& camera,
                                              const std::vector<cv::Point2f>& distorted_px);

/// Normalised image coordinates (K^-1 [u v 1]) of an ideal pixel.
inline Eigen::Vector2d normalised_from_pixel(const CameraIntrinsics& camera,
                                             const Eigen::Vector2d& ideal_px) {
  return {(ideal_px.x() - camera.cx_px) / camera.fx_px,
          (ideal_px.y() - camera.cy_px) / camera.fy_px};
}

/// Ideal pixel of normalised image coordinates.
inline Eigen::Vector2d pixel_from_normalised(const CameraIntrinsics& camera,
                                             const Eigen::Vector2d& normalised) {
  return {camera.fx_px * normalised.x() + camera.cx_px,
          camera.fy_px * normalised.y() + camera.cy_px};
}

/// A plausible pinhole for images without calibration: f = image width (about a 53 degree
/// horizontal field of view, typical of survey cameras), principal point at the centre, no
/// distortion. Used for the Skerki and mosaic images, whose calibration is not recorded.
CameraIntrinsics nominal_pinhole(int width_px, int height_px);

}  // namespace nav::vision
