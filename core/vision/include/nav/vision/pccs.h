#pragma once
// Pose-constrained correspondence search (PCCS): Eustice, Singh, Leonard, Walter & Ballard,
// RSS 2005, section III-C and Fig. 4; Eustice, PhD thesis, MIT/WHOI 2005, ch. 4.
//
// A feature u_i of image i is back-projected at a scene depth d along its ray, moved into
// camera j with the prior relative pose x_i_j and projected:
//   X_i = d K^-1 [u_i; 1],  X_j = R_i_j^T (X_i - t_i_j),  u_j = pi(K X_j).
// Over the depth interval d in [d_mean - k_d sigma_d, d_mean + k_d sigma_d] the transfer
// traces a segment of the epipolar line of u_i in image j. At each depth the transfer is
// linearised in the pose and in the pixel noise of both features, giving a 2x2 covariance
//   S(d) = J_x P_x J_x^T + sigma_px^2 (J_u J_u^T + I),
// and the search region is the union over the interval of the ellipses
//   (q - u_j(d))^T S(d)^-1 (q - u_j(d)) <= g.
// The region is stored as a polyline of depth samples (uniform in inverse depth, where the
// transfer is a projective and hence well sampled parametrisation of the line); a candidate's
// distance is the smallest Mahalanobis distance to the sub-segments, each sub-segment measured
// in the metric of either end's covariance and the smaller distance kept (a union of ellipses).
//
// Confidence. With the depth interval holding probability sqrt(c) (k_d the two-sided normal
// quantile) and g = chi2_2^-1(sqrt(c)), the true correspondence lies in the region with
// probability >= sqrt(c) * sqrt(c) = c, to first order in the pose (the depth is exact along
// the segment). c = PccsOptions::confidence. The bound is conservative: inside the interval
// the error along the epipolar line is absorbed by the depth freedom, so only the 1-D error
// across the line is really gated (with a 2-D threshold).
//
// Floor. A prior much tighter than the features' repeatability gives a band of a pixel or two
// around the epipolar line. An ambiguous candidate (repeated texture, a neighbouring corner) is
// then alone in its region and passes the ratio test for lack of competitors; a few such
// matches decide the pose of a weak pair (few inliers on a small patch), wrong by degrees under
// a covariance of tenths. band_floor_sigma_px adds sigma^2 I to every S, so that the ratio test
// sees the candidates around the line again while the prior still shortens the band along it.
//
// Matching. Only candidates inside the region are compared (L2 descriptor distance); the best
// candidate of u_i is kept when best < ratio * second best among the candidates of its region
// (a lone candidate passes), and, with `mutual`, when u_i is also the best of u_j among all i
// whose region contains u_j. Image j's points are bucketed in a uniform grid so a region only
// visits the cells its sub-segments' bounding boxes cover.
//
// Pure function of its inputs; thread-safe. Without a prior: matching.h (match_unconstrained),
// the same ratio and mutual tests over every pair.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "nav/vision/vision_types.h"

namespace nav::vision {

struct PccsOptions {
  double confidence = 0.999;    ///< Probability that the true correspondence is in its region.
  double ratio = 0.8;           ///< Lowe ratio test inside the region (best < ratio * second).
  double pixel_sigma_px = 0.5;  ///< Feature localisation noise, each image, each axis.
  /// Floor of the band's width: sigma^2 I added to every S, px (header comment "Floor").
  double band_floor_sigma_px = 0.0;
  int depth_samples = 8;        ///< Sub-segments of the depth interval (>= 1).
  double min_depth_m = 0.05;    ///< Near end of the depth interval is clamped to this.
  int grid_cell_px = 32;        ///< Bucket size of image j's point index.
  bool mutual = true;           ///< Keep only mutual best matches.
};

/// Search region of one feature of image i in image j (see the header comment).
struct SearchRegion {
  std::vector<Eigen::Vector2d> centres_px;        ///< u_j(d_k) at the depth samples, near to far.
  std::vector<Eigen::Matrix2d> covariances_px2;   ///< S(d_k), same order.
  std::vector<Eigen::Matrix2d> informations_px2;  ///< S(d_k)^-1, same order.
  std::vector<double> depths_m;                   ///< d_k.
  double gate_chi2 = 0.0;                         ///< g.
  Eigen::AlignedBox2d bounds_px;                  ///< Bounding box of the whole region.

  /// False when no depth sample lands in front of camera j (the region is empty).
  bool valid() const { return !centres_px.empty(); }
  /// Sub-segments of the polyline (a one-sample region has one, a point).
  std::size_t segments() const {
    return centres_px.size() <= 1 ? centres_px.size() : centres_px.size() - 1;
  }
  /// Mahalanobis distance squared from q to sub-segment k (smaller of its two end metrics).
  double segment_mahalanobis2(std::size_t k, const Eigen::Vector2d& q_px) const;
  /// Smallest Mahalanobis distance squared from q to the region's polyline; +inf if !valid().
  double mahalanobis2(const Eigen::Vector2d& q_px) const;
  bool contains(const Eigen::Vector2d& q_px) const { return mahalanobis2(q_px) <= gate_chi2; }
};

/// Gate g and depth multiplier k_d for a confidence c in (0, 1) (see the header comment).
/// Throws std::invalid_argument when c is outside (0, 1).
struct PccsGate {
  double gate_chi2 = 0.0;
  double depth_k_sigma = 0.0;
};
PccsGate pccs_gate(double confidence);

/// The scene-depth prior (mean and sigma along camera i's axis) of a pair over relief: the
/// scene the two cameras share lies anywhere between the seafloor below camera i (altitude_i_m)
/// and the seafloor below camera j seen from camera i (altitude_j_m + t_z_i_j_m, camera j's
/// offset along camera i's axis), each known to sigma = sigma_fraction x altitude + sigma_floor_m.
/// The result's mean +- 3 sigma spans both (a frame above a hull's edge and one above its deck
/// share the deck, which the altitude below the first misses by metres); equal depths give the
/// single-camera prior. The registration code of Eustice et al. bounds its scene depth by both
/// images' altitudes likewise.
struct SceneDepthPrior {
  double depth_m = 0.0;
  double sigma_m = 0.0;
};
SceneDepthPrior scene_depth_prior(double altitude_i_m, double altitude_j_m, double t_z_i_j_m,
                                  double sigma_fraction, double sigma_floor_m);

/// The search region of feature u_i_px (undistorted pixels of image i) in image j.
/// Throws std::invalid_argument for a non-positive depth prior or focal length, or
/// depth_samples < 1.
SearchRegion search_region(const Eigen::Vector2d& u_i_px, const CameraIntrinsics& camera,
                           const RelativePosePrior& prior, const PccsOptions& options);

/// Pose-constrained putative matches of image i's features into image j. Both images share
/// `camera`. descriptor_comparisons counts every descriptor distance evaluated. Throws
/// std::invalid_argument when the descriptors are not CV_32F rows of equal width matching the
/// point counts.
PutativeMatches match_pose_constrained(const ImageFeatures& i, const ImageFeatures& j,
                                       const CameraIntrinsics& camera,
                                       const RelativePosePrior& prior, const PccsOptions& options);

}  // namespace nav::vision
