#include "nav/vision/camera_model.h"

#include <opencv2/calib3d.hpp>

#include <cmath>
#include <string>

namespace nav::vision {

using core::Status;
using core::StatusCode;

Status validate(const CameraIntrinsics& camera) {
  auto bad = [](const std::string& what) {
    return Status::Error(StatusCode::kInvalidArgument, "camera intrinsics: " + what);
  };
  if (!(std::isfinite(camera.fx_px) && camera.fx_px > 0.0) ||
      !(std::isfinite(camera.fy_px) && camera.fy_px > 0.0)) {
    return bad("focal lengths fx=" + std::to_string(camera.fx_px) +
               " fy=" + std::to_string(camera.fy_px) + " must be positive and finite (missing calibration?)");
  }
  if (!std::isfinite(camera.cx_px) || !std::isfinite(camera.cy_px)) {
    return bad("principal point is not finite");
  }
  for (double k : {camera.k1, camera.k2, camera.p1, camera.p2, camera.k3}) {
    if (!std::isfinite(k)) return bad("distortion coefficient is not finite");
  }
  if (camera.width_px < 0 || camera.height_px < 0) return bad("negative image size");
  if (camera.width_px > 0 && camera.height_px > 0 &&
      (camera.cx_px < 0.0 || camera.cx_px > camera.width_px || camera.cy_px < 0.0 ||
       camera.cy_px > camera.height_px)) {
    return bad("principal point (" + std::to_string(camera.cx_px) + ", " +
               std::to_string(camera.cy_px) + ") outside the " + std::to_string(camera.width_px) +
               "x" + std::to_string(camera.height_px) + " image");
  }
  return Status::Ok();
}

cv::Matx33d camera_matrix(const CameraIntrinsics& camera) {
  return {camera.fx_px, 0.0, camera.cx_px, 0.0, camera.fy_px, camera.cy_px, 0.0, 0.0, 1.0};
}

cv::Mat distortion_coefficients(const CameraIntrinsics& camera) {
  return (cv::Mat_<double>(1, 5) << camera.k1, camera.k2, camera.p1, camera.p2, camera.k3);
}

bool has_distortion(const CameraIntrinsics& camera) {
  return camera.k1 != 0.0 || camera.k2 != 0.0 || camera.p1 != 0.0 || camera.p2 != 0.0 ||
         camera.k3 != 0.0;
}

std::vector<Eigen::Vector2d> undistort_pixels(const CameraIntrinsics& camera,
                                              const std::vector<cv::Point2f>& distorted_px) {
  std::vector<Eigen::Vector2d> ideal_px;
  ideal_px.reserve(distorted_px.size());
  if (distorted_px.empty()) return ideal_px;
  if (!has_distortion(camera)) {
    for (const auto& p : distorted_px) ideal_px.emplace_back(p.x, p.y);
    return ideal_px;
  }
  std::vector<cv::Point2f> out;
  const cv::Matx33d K = camera_matrix(camera);
  // P = K maps the undistorted normalised coordinates back to ideal pixels; iterative
  // inversion of the distortion model until 1e-6 px change or 20 iterations.
  cv::undistortPoints(distorted_px, out, K, distortion_coefficients(camera), cv::noArray(), K,
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 20, 1e-6));
  for (const auto& p : out) ideal_px.emplace_back(p.x, p.y);
  return ideal_px;
}

CameraIntrinsics nominal_pinhole(int width_px, int height_px) {
  CameraIntrinsics camera;
  camera.fx_px = camera.fy_px = static_cast<double>(width_px);
  camera.cx_px = 0.5 * width_px;
  camera.cy_px = 0.5 * height_px;
  camera.width_px = width_px;
  camera.height_px = height_px;
  return camera;
}

}  // namespace nav::vision
