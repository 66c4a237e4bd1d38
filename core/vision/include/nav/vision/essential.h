#pragma once
// Robust essential matrix and the choice of its (R, t) decomposition.
//
// Model: x_i^T E x_j = 0 on normalised coordinates, E = [t_i_j]x R_i_j, p_i = R_i_j p_j + t_i_j
// (vision_types.h). The 5-point minimal solver (Nister, PAMI 26(6), 2004) inside least median of
// squares (Rousseeuw, JASA 79, 1984; Zhang, IJCV 27(2), 1998, for epipolar geometry), as the
// paper's registration does: LMedS needs no inlier threshold, which suits imagery whose
// feature noise changes with turbidity and altitude; it assumes more than half the putative
// matches are inliers. RANSAC and USAC (MAGSAC++) are offered for comparison.
//
// Decomposition: E has four (R, t) decompositions (Hartley & Zisserman, 2nd ed., result 9.19).
// Each is scored by cheirality, the number of inliers triangulated in front of both cameras.
// Over a near-planar seafloor the homography's decompositions (Faugeras & Lustman, 1988; Malis
// & Vargas, INRIA RR-6303, 2007) are candidates too: over a plane the 5-point solution inside
// LMedS may be either of the two poses that explain the matches, the true one or its planar
// twin, in which the plane's normal and the baseline roughly trade places (Longuet-Higgins,
// "The reconstruction of a plane surface from two perspective projections", Proc. R. Soc.
// Lond. B 227, 1986). Candidates whose cheirality count is within `ambiguity_ratio` of the best
// are ambiguous. With a prior, the one nearest the prior's predicted 5-DOF measurement in
// Mahalanobis distance is chosen. Without one, the ambiguous candidates that also fit the
// matches as well as the best (median Sampson distance within twice the best plus
// min_sigma_px) are told apart by the scene: under the true pose of a down-looking camera the
// inliers lie on a floor roughly across the optical axis, under the twin on a plane tilted by
// about the baseline's angle to the floor's normal. The candidate whose least-squares plane is
// least tilted is chosen when its tilt is at most `floor_max_tilt_deg` and every twin is
// tilted `floor_min_tilt_gap_deg` more; otherwise the pair fails as a planar ambiguity. A twin
// is a candidate at least 2 deg of rotation or 30 deg of baseline away whose floor is tilted
// over 5 deg more; closer candidates are seeds of the same reconstruction.
// The chosen pose is polished on the inliers by Gauss-Newton on the Sampson error (first-order
// geometric error; Hartley & Zisserman, 2nd ed., section 11.4.3), parametrised minimally as
// R <- R exp([w]x), t <- normalise(t + B b) with B a basis of t's tangent plane (5 DOF).
// After each polish the inliers are re-selected among all putative matches at inlier_k_sigma
// robust standard deviations of the Sampson error, so that a LMedS model fitted to a biased
// minimal sample does not keep its biased inlier set (as in locally optimised RANSAC: Chum,
// Matas & Kittler, DAGM 2003).
// A pair with too little parallax (pure rotation, or baseline negligible against the scene
// depth) has no defined E and fails with a reason.

#include <Eigen/Core>

#include <cstdint>
#include <vector>

#include "nav/vision/vision_types.h"

namespace nav::vision {

enum class RobustMethod : std::uint8_t { kLmeds = 0, kRansac, kUsacMagsac };

struct EssentialOptions {
  RobustMethod method = RobustMethod::kLmeds;
  double confidence = 0.999;
  double threshold_px = 1.0;     ///< RANSAC/USAC inlier threshold (LMedS derives its own).
  int max_iterations = 2000;
  int min_matches = 8;           ///< Fewer putative matches: fail.
  double ambiguity_ratio = 0.9;  ///< Candidates with >= ratio x best cheirality count tie.
  double min_parallax_px = 0.25;  ///< Median derotated inlier parallax below this (pixels at
                                  ///< the mean focal length): pure rotation.
  bool planar_candidates = true;    ///< Add the homography decompositions as candidates.
  /// Without a prior, the largest tilt of the scene's plane from the optical axis that the
  /// planar ambiguity may be resolved with (above); 0: every ambiguity fails.
  double floor_max_tilt_deg = 45.0;
  double floor_min_tilt_gap_deg = 20.0;  ///< ... and the least tilt of the other poses over it.
  int polish_iterations = 10;       ///< Sampson-error Gauss-Newton steps on the inliers (0: off).
  int polish_rounds = 3;            ///< Polish, re-select inliers, repeat.
  double inlier_k_sigma = 2.5;      ///< Re-selection gate in robust sigmas of the Sampson error.
  double min_sigma_px = 0.2;        ///< Floor of the robust sigma, pixels.
};

/// Triangulated depths (along each camera's optical axis) of a correspondence of normalised
/// coordinates under the pose (R_i_j, t_i_j), by the midpoint method. Returns false when the
/// rays are parallel.
bool triangulate_depths(const Eigen::Matrix3d& R_i_j, const Eigen::Vector3d& t_i_j,
                        const Eigen::Vector2d& x_i, const Eigen::Vector2d& x_j, double* depth_i,
                        double* depth_j);

/// Sampson distance (normalised-coordinate units) of x_i <-> x_j under E (x_i^T E x_j = 0).
double sampson_distance(const Eigen::Matrix3d& E, const Eigen::Vector2d& x_i,
                        const Eigen::Vector2d& x_j);

/// Polishes (R_i_j, t_i_j_unit) by Gauss-Newton on the Sampson distances of the
/// correspondences (normalised coordinates); returns the number of accepted steps.
int polish_sampson(const std::vector<Eigen::Vector2d>& x_i, const std::vector<Eigen::Vector2d>& x_j,
                   int iterations, Eigen::Matrix3d* R_i_j, Eigen::Vector3d* t_i_j_unit);

/// Robust essential matrix of the putative matches with the chosen decomposition.
/// `prior` may be null. ok == false with a reason when there are too few matches, no model,
/// too little parallax, or no candidate with points in front of both cameras.
EssentialEstimate estimate_essential(const ImageFeatures& features_i,
                                     const ImageFeatures& features_j,
                                     const PutativeMatches& matches,
                                     const CameraIntrinsics& camera,
                                     const EssentialOptions& options,
                                     const RelativePosePrior* prior);

}  // namespace nav::vision
