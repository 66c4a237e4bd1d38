#pragma once
// Feature extraction, once per image: Harris corners and SIFT keypoints (the paper registers
// with both: Eustice et al., RSS 2005, section III-C), each described by a SIFT descriptor
// (Lowe, IJCV 60(2), 2004), with ideal (undistorted) pixel coordinates.
//
// Harris corners (Harris & Stephens, Alvey Vision Conference 1988) are scored by the corner
// response and thinned by a minimum distance (Shi & Tomasi's selection, as OpenCV's
// goodFeaturesToTrack); they are described at a fixed support size, oriented along their
// dominant gradient (or upright, an option).
// Descriptors are RootSIFT (Arandia & Zisserman, CVPR 2012: L1-normalise, square root), which
// makes the Euclidean distance a Hellinger kernel and matches more reliably than raw SIFT.

#include <opencv2/core.hpp>

#include "nav/core/status.h"
#include "nav/vision/vision_types.h"

namespace nav::vision {

struct FeatureOptions {
  bool use_harris = true;
  int max_harris = 800;                   ///< Strongest corners kept.
  double harris_quality = 0.005;          ///< Response floor relative to the strongest corner.
  double harris_min_distance_px = 6.0;    ///< Minimum spacing of kept corners.
  int harris_block_size = 5;              ///< Structure-tensor window, px.
  double harris_k = 0.04;                 ///< Harris' det - k trace^2 constant.
  /// SIFT keypoint size of a corner: the descriptor window is 4 x 3 x size / 2 = 6 x size pixels
  /// wide (OpenCV SIFT), so 16 px describes a ~96 px patch (on Sparus, sizes 7/12/16 gave
  /// median rotation errors 0.67/0.59/0.53 deg).
  float harris_descriptor_size_px = 16.0f;
  /// Describe each corner at its dominant gradient orientation (Lowe's orientation
  /// assignment) instead of upright: overlapping survey frames from adjacent track lines are
  /// taken on opposite headings, which upright descriptors cannot match.
  bool harris_rotation_invariant = false;
  bool use_sift = true;
  int max_sift = 1500;                    ///< Strongest SIFT keypoints kept (0 = all).
  double sift_contrast_threshold = 0.03;  ///< Lowe's DoG contrast threshold.
  bool root_sift = true;                  ///< RootSIFT descriptors.
  /// SIFT detection and all descriptors run on the image halved until it is no wider than
  /// this (0 = full resolution); Harris corners are still located at full resolution. SIFT
  /// upsamples its input 2x for its first octave, so a halved 1280 px frame is still analysed
  /// at the full resolution's pixel scale, at a quarter of the cost.
  int max_description_width_px = 800;
};

/// Detects and describes features on a preprocessed 8-bit grey image. When `image_is_ideal`
/// the image was undistorted (Preprocessor with undistort) and keypoint coordinates are already
/// ideal pixels; otherwise they are undistorted with `camera`'s distortion. Error on an empty
/// or non-8-bit-grey image.
core::Status extract_features(const cv::Mat& image_8u, const CameraIntrinsics& camera,
                              bool image_is_ideal, const FeatureOptions& options,
                              ImageFeatures* features);

}  // namespace nav::vision
