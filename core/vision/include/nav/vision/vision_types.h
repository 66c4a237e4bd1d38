#pragma once
// Value types shared by the stages of two-view image registration (Eustice, Singh, Leonard,
// Walter & Ballard, "Visually Navigating the RMS Titanic with SLAM Information Filters",
// RSS 2005, section III-C; Eustice, PhD thesis, MIT/WHOI 2005, ch. 4):
//   per image : preprocessing -> features (ImageFeatures), computed once and cached;
//   per pair  : correspondences (PutativeMatches, pose-constrained when a RelativePosePrior
//               is given) -> robust essential matrix (EssentialEstimate) -> two-view maximum
//               likelihood refinement -> validated RegistrationResult.
//
// Frames and units. Camera frame: x right, y down, z along the optical axis (metres). A relative
// pose x_ij = [t; roll pitch heading] is camera j in camera i's frame, exactly as
// nav::core::CameraRelativePoseModel defines it: p_i = R_i_j p_j + t_i_j with
// R_i_j = Rz(heading) Ry(pitch) Rx(roll). Pixel coordinates are undistorted ideal-pinhole
// pixels of the camera's intrinsics unless a name says otherwise. Angles in radians.
#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "nav/core/geometry/types.h"

namespace nav::vision {

using core::Mat6;
using core::Vec6;
using Vec5 = Eigen::Matrix<double, 5, 1>;
using Mat5 = Eigen::Matrix<double, 5, 5>;

/// Pinhole camera with OpenCV's radial-tangential distortion (k1 k2 p1 p2 k3), all in pixels.
struct CameraIntrinsics {
  double fx_px = 0.0, fy_px = 0.0, cx_px = 0.0, cy_px = 0.0;
  double k1 = 0.0, k2 = 0.0, p1 = 0.0, p2 = 0.0, k3 = 0.0;
  int width_px = 0, height_px = 0;  ///< Expected image size; 0 = not checked.
};

/// Which detector produced a feature (the paper uses both).
enum class Detector : std::uint8_t { kHarris = 0, kSift = 1 };

/// Features of one preprocessed image. Computed once per image, immutable afterwards, so one
/// instance may be shared read-only by any number of concurrent pair registrations.
struct ImageFeatures {
  std::vector<Eigen::Vector2d> points_px;  ///< Undistorted pixel coordinates.
  std::vector<Detector> detector;          ///< Detector of each point.
  /// Keypoint diameter of each point, full-resolution pixels (SIFT: its detection scale;
  /// Harris: the descriptor support). Empty when unknown.
  std::vector<float> size_px;
  cv::Mat descriptors;                     ///< CV_32F, one row per point (SIFT, 128 wide).
  int width_px = 0, height_px = 0;         ///< Size of the preprocessed image.
  std::size_t size() const { return points_px.size(); }
};

/// Prior on the relative pose of camera j in camera i (from the filter's proposal joint) and the
/// scene depth along camera i's optical axis (from the altitude), as pose-constrained
/// correspondence search needs them.
struct RelativePosePrior {
  Vec6 x_i_j = Vec6::Zero();           ///< [t_i_j (m); roll pitch heading of j in i (rad)].
  Mat6 covariance = Mat6::Identity();  ///< 6x6 covariance of x_i_j, same order.
  double scene_depth_m = 0.0;          ///< Mean scene depth in camera i, m.
  double scene_depth_sigma_m = 0.0;    ///< 1-sigma of the scene depth, m.
};

/// One candidate correspondence: feature index_i of image i with feature index_j of image j.
struct Match {
  int index_i = -1;
  int index_j = -1;
  float descriptor_distance = 0.0f;
};

/// Result of a correspondence search, with its cost for comparison of search strategies.
struct PutativeMatches {
  std::vector<Match> matches;
  std::size_t descriptor_comparisons = 0;  ///< Descriptor distances evaluated.
};

/// Robust essential-matrix estimate with the chosen (R, t) decomposition.
struct EssentialEstimate {
  bool ok = false;
  Eigen::Matrix3d E = Eigen::Matrix3d::Zero();  ///< x_i^T E x_j = 0 on normalised coordinates.
  Eigen::Matrix3d R_i_j = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t_i_j_unit = Eigen::Vector3d::Zero();  ///< Baseline direction, |t| = 1.
  std::vector<int> inliers;  ///< Indices into PutativeMatches::matches.
  std::string reason;        ///< Why ok == false.
};

/// Why a registration failed (or kOk). Every failure is an answer, never silence.
enum class RegistrationFailure : std::uint8_t {
  kOk = 0,
  kBadImage,           ///< Empty, truncated, wrong size or depth.
  kTooFewFeatures,
  kTooFewMatches,
  kEssentialFailed,    ///< LMedS found no model / degenerate (pure rotation, planar ambiguity).
  kTooFewInliers,
  kRefinementFailed,   ///< Refinement did not converge or its information is singular.
  kReprojectionError,  ///< Inlier reprojection RMS above the limit.
  kDepthOutOfPrior,    ///< Triangulated depths outside the scene-depth prior.
  kTooUncertain,       ///< An angle's sigma above the limit with too few inliers to trust.
};

/// The answer for one pair: the 5-DOF measurement of nav::core::CameraRelativePoseModel
/// z = [azimuth, elevation, roll, pitch, heading] of camera j in camera i, with its covariance.
struct RegistrationResult {
  bool success = false;
  RegistrationFailure failure = RegistrationFailure::kOk;
  std::string reason;  ///< Human-readable detail of the failure.
  Vec5 z = Vec5::Zero();
  Mat5 covariance = Mat5::Identity();
  int putative_matches = 0;
  int inliers = 0;
  std::size_t descriptor_comparisons = 0;
  double reprojection_rms_px = 0.0;
  /// Feature noise measured on the pair (TwoViewRefinement::robust_sigma_px).
  double noise_sigma_px = 0.0;
  double prior_chi2 = -1.0;  ///< chi2(5) of z against the prior's prediction; -1 without prior.
  double max_leverage = 0.0;  ///< largest leverage of one inlier (TwoViewRefinement)
};

}  // namespace nav::vision
