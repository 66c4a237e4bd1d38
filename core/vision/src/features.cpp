#include "nav/vision/features.h"

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
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

/// Halvings L of the image so that width / 2^L <= max_width_px (0 = no limit).
int description_level(int width_px, int max_width_px) {
  int level = 0;
  while (max_width_px > 0 && (width_px >> level) > max_width_px) ++level;
  return level;
}

/// SIFT keypoints of image level L in full-resolution pixels, sizes scaled alike.
/// OpenCV's SIFT (4.6) builds its first octave by upsampling 2x with bilinear interpolation,
/// whose pixel j samples the input at j / 2 - 1/4, and reports keypoints at j / 2: every
/// keypoint is 1/4 pixel of its input too far right and down (measured on blobs at known
/// positions: features_test.cpp). The level's pixel x is full-resolution pixel 2^L x (pyrDown
/// centres its kernel on the even pixels).
void sift_to_full_resolution(std::vector<cv::KeyPoint>& keypoints, int level) {
  const float s = static_cast<float>(1 << level);
  for (auto& k : keypoints) {
    k.pt = (k.pt - cv::Point2f(0.25f, 0.25f)) * s;
    k.size *= s;
  }
}

/// Dominant gradient orientation of each corner on the level image (Lowe 2004, section 5: a
/// 36-bin histogram of gradient directions weighted by magnitude and a Gaussian of sigma 1.5 x
/// the keypoint scale, smoothed, peak interpolated by a parabola), as OpenCV's keypoint angle
/// (degrees, 360 - the direction with y up), so the descriptor is rotation invariant.
void assign_orientations(const cv::Mat& level_image, std::vector<cv::KeyPoint>& at_level) {
  cv::Mat gx, gy;
  cv::Sobel(level_image, gx, CV_32F, 1, 0, 1);
  cv::Sobel(level_image, gy, CV_32F, 0, 1, 1);
  constexpr int kBins = 36;
  constexpr double kPi = 3.14159265358979323846;
  for (auto& k : at_level) {
    const double sigma = 1.5 * 0.5 * k.size;
    const int radius = static_cast<int>(std::lround(3.0 * sigma));
    const int cx = static_cast<int>(std::lround(k.pt.x)), cy = static_cast<int>(std::lround(k.pt.y));
    std::array<double, kBins> hist{};
    for (int dy = -radius; dy <= radius; ++dy) {
      const int y = cy + dy;
      if (y <= 0 || y >= level_image.rows - 1) continue;
      const float* rx = gx.ptr<float>(y);
      const float* ry = gy.ptr<float>(y);
      for (int dx = -radius; dx <= radius; ++dx) {
        const int x = cx + dx;
        if (x <= 0 || x >= level_image.cols - 1) continue;
        const double w = std::exp(-(dx * dx + dy * dy) / (2.0 * sigma * sigma));
        const double theta = std::atan2(-ry[x], rx[x]);  // y up, as OpenCV's SIFT
        const int bin = static_cast<int>(std::lround((theta + kPi) / (2.0 * kPi) * kBins)) % kBins;
        hist[static_cast<std::size_t>(bin)] += w * std::hypot(rx[x], ry[x]);
      }
    }
    std::array<double, kBins> smooth{};
    for (int b = 0; b < kBins; ++b)
      smooth[static_cast<std::size_t>(b)] =
          0.25 * hist[static_cast<std::size_t>((b + kBins - 1) % kBins)] +
          0.5 * hist[static_cast<std::size_t>(b)] + 0.25 * hist[static_cast<std::size_t>((b + 1) % kBins)];
    const int peak = static_cast<int>(std::max_element(smooth.begin(), smooth.end()) - smooth.begin());
    const double l = smooth[static_cast<std::size_t>((peak + kBins - 1) % kBins)];
    const double c = smooth[static_cast<std::size_t>(peak)];
    const double r = smooth[static_cast<std::size_t>((peak + 1) % kBins)];
    const double denom = l - 2.0 * c + r;
    const double offset = denom != 0.0 ? 0.5 * (l - r) / denom : 0.0;
    const double theta_deg = (peak + offset) * 360.0 / kBins - 180.0;
    double angle = 360.0 - theta_deg;
    angle = std::fmod(angle + 720.0, 360.0);
    k.angle = static_cast<float>(angle);
  }
}

/// SIFT descriptors of Harris corners (detected at full resolution) on the level image: one
/// octave of the SIFT scale space (provided keypoints at octave 0 make OpenCV build only that
/// octave, without the 2x upsampling of detection). Corners whose descriptor OpenCV drops keep
/// nothing; the rest keep their full-resolution position.
void describe_harris(cv::SIFT& sift, const cv::Mat& level_image, int level, bool oriented,
                     std::vector<cv::KeyPoint>& corners, cv::Mat& descriptors) {
  const float s = 1.0f / static_cast<float>(1 << level);
  std::vector<cv::KeyPoint> at_level = corners;
  for (std::size_t k = 0; k < at_level.size(); ++k) {
    at_level[k].pt *= s;
    at_level[k].size *= s;
    at_level[k].class_id = static_cast<int>(k);
  }
  if (oriented) assign_orientations(level_image, at_level);
  sift.compute(level_image, at_level, descriptors);
  std::vector<cv::KeyPoint> kept;
  kept.reserve(at_level.size());
  for (const auto& k : at_level) {
    kept.push_back(corners[static_cast<std::size_t>(k.class_id)]);
    kept.back().angle = k.angle;
  }
  corners = std::move(kept);
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

  // Descriptors (and SIFT detection) on a pyramid level no wider than
  // max_description_width_px: SIFT's scale space of a 1280 px frame, upsampled 2x as Lowe's
  // first octave, costs four times that of the level; the descriptor windows (tens of pixels)
  // lose nothing at half resolution. Harris corners are located at full resolution.
  const int level = description_level(image_8u.cols, options.max_description_width_px);
  cv::Mat level_image = image_8u;
  for (int k = 0; k < level; ++k) cv::pyrDown(level_image, level_image);

  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  if (options.use_harris) {
    keypoints = harris_keypoints(image_8u, options);
    if (!keypoints.empty()) describe_harris(*sift, level_image, level, options.harris_rotation_invariant,
                      keypoints, descriptors);
  }
  std::vector<Detector> detector(keypoints.size(), Detector::kHarris);

  if (options.use_sift) {
    std::vector<cv::KeyPoint> sift_keypoints;
    cv::Mat sift_descriptors;
    sift->detectAndCompute(level_image, cv::noArray(), sift_keypoints, sift_descriptors);
    sift_to_full_resolution(sift_keypoints, level);
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
  out.size_px.reserve(keypoints.size());
  for (const auto& k : keypoints) out.size_px.push_back(k.size);
  out.descriptors = descriptors.empty() ? cv::Mat(0, 128, CV_32F) : descriptors;
  out.width_px = image_8u.cols;
  out.height_px = image_8u.rows;
  *features = std::move(out);
  return Status::Ok();
}

}  // namespace nav::vision
