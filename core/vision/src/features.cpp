#include "nav/vision/features.h"

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <string>
#include <vector>

#include "nav/vision/camera_model.h"

namespace nav::vision {

using core::Status;
using core::StatusCode;

namespace {

std::vector<cv::KeyPoint> harris_keypoints(const cv::Mat& image, const FeatureOptions& o) {
  std::vector<cv::Point2f> corners;
  cv::goodFeaturesToTrack(image, corners, o.max_harris, o.harris_quality, o.harris_min_distance_px,
                          cv::noArray(), o.harris_block_size, /*useHarrisDetector=*/true,
                          o.harris_k);
  std::vector<cv::KeyPoint> keypoints;
  keypoints.reserve(corners.size());
  // Upright (angle 0) at octave 0: the SIFT descriptor is then computed at this support size.
  for (const auto& c : corners) keypoints.emplace_back(c, o.harris_descriptor_size_px, 0.0f);
  return keypoints;
}

void to_root_sift(cv::Mat& descriptors) {
  for (int r = 0; r < descriptors.rows; ++r) {
    cv::Mat row = descriptors.row(r);
    const double l1 = cv::norm(row, cv::NORM_L1);
    if (l1 > 0.0) row *= 1.0 / l1;
    cv::sqrt(row, row);
  }
}

}  // namespace

Status extract_features(const cv::Mat& image_8u, const CameraIntrinsics& camera,
                        bool image_is_ideal, const FeatureOptions& options,
                        ImageFeatures* features) {
  if (image_8u.empty()) {
    return Status::Error(StatusCode::kInvalidArgument, "extract_features: empty image");
  }
  if (image_8u.type() != CV_8UC1) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "extract_features: image type " + std::to_string(image_8u.type()) +
                             " is not 8-bit grey (CV_8UC1); run the Preprocessor first");
  }
  // One detector object per call: OpenCV's Feature2D objects are not documented thread-safe.
  cv::Ptr<cv::SIFT> sift =
      cv::SIFT::create(options.max_sift, 3, options.sift_contrast_threshold, 10.0, 1.6);

  std::vector<cv::KeyPoint> keypoints;
  std::vector<Detector> detector;
  if (options.use_harris) {
    keypoints = harris_keypoints(image_8u, options);
    detector.assign(keypoints.size(), Detector::kHarris);
  }
  cv::Mat descriptors;
  if (!keypoints.empty()) sift->compute(image_8u, keypoints, descriptors);
  // compute() may drop keypoints too near the border; recount what survived.
  detector.assign(keypoints.size(), Detector::kHarris);

  if (options.use_sift) {
    std::vector<cv::KeyPoint> sift_keypoints;
    cv::Mat sift_descriptors;
    sift->detectAndCompute(image_8u, cv::noArray(), sift_keypoints, sift_descriptors);
    if (!sift_keypoints.empty()) {
      keypoints.insert(keypoints.end(), sift_keypoints.begin(), sift_keypoints.end());
      detector.insert(detector.end(), sift_keypoints.size(), Detector::kSift);
      if (descriptors.empty()) {
        descriptors = sift_descriptors;
      } else {
        cv::vconcat(descriptors, sift_descriptors, descriptors);
      }
    }
  }
  if (options.root_sift && !descriptors.empty()) to_root_sift(descriptors);

  std::vector<cv::Point2f> pixels;
  pixels.reserve(keypoints.size());
  for (const auto& k : keypoints) pixels.push_back(k.pt);
  ImageFeatures out;
  if (image_is_ideal) {
    out.points_px.reserve(pixels.size());
    for (const auto& p : pixels) out.points_px.emplace_back(p.x, p.y);
  } else {
    out.points_px = undistort_pixels(camera, pixels);
  }
  out.detector = std::move(detector);
  out.descriptors = descriptors.empty() ? cv::Mat(0, 128, CV_32F) : descriptors;
  out.width_px = image_8u.cols;
  out.height_px = image_8u.rows;
  *features = std::move(out);
  return Status::Ok();
}

}  // namespace nav::vision
