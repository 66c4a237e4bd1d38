#pragma once
// Two-view maximum-likelihood refinement of the 5-DOF relative pose with its covariance
// (Eustice et al., RSS 2005, section III-C; Hartley & Zisserman, 2nd ed., sections 11.4.1 and
// A6.3 (sparse Levenberg-Marquardt); Triggs et al., "Bundle adjustment - a modern synthesis",
// 2000, section 6.1 (Schur complement) and 9 (gauge)).
//
// Unknowns: the pose z = [azimuth, elevation, roll, pitch, heading] of camera j in camera i
// (relative_pose_5dof.h) and one 3-D point X_k per match in camera i's frame, with the baseline
// fixed to unit length (the scale gauge: depths come out in baseline units). Camera i sits at
// the origin. Cost (pixel_sigma_px = s the isotropic feature noise, rho the Huber loss):
//   sum_k rho(|u_i,k - pi(K X_k)|^2 / s^2) + rho(|u_j,k - pi(K R^T (X_k - t_unit(z)))|^2 / s^2)
// minimised by Levenberg-Marquardt with the 3x3 point blocks eliminated (Schur complement) at
// every iteration, robust weights by iteratively reweighted least squares (Triggs section 3.3).
// The solver works in inverse-depth points (finite for distant points) and updates the unit
// baseline on its tangent plane (no pole where it points along the optical axis); each accepted
// step is followed by point-only Gauss-Newton steps (two_view_problem.h).
// Stops on a small relative cost decrease, a small step, or a pose step below
// pose_step_tolerance_sigma standard deviations (S-norm of the step). Then matches with a
// residual beyond the Huber kink in either image are rejected and the rest re-solved (up to
// three rounds). The kink sits at huber_threshold_sigma x max(s, s_robust), where s_robust is
// the feature noise measured on the first robust solution: a match's four residuals leave one
// degree of freedom after its point is fitted, so under a feature noise sigma its residual
// norm is sigma |N(0, 1)| and s_robust = 1.4826 x the median norm (the normalised median absolute
// deviation; Rousseeuw & Leroy, "Robust regression and outlier detection", 1987, section 5.1). With
// s fixed instead, more pixels per feature scale or a scene that moves (weed, sand, caustics) put a
// good pair's inliers past the kink round after round: the seafloor pair of data/images resampled
// to 3840x2160 has a noise of 1 px and failed with s = 0.3 px. Matches whose point ends behind a
// camera are rejected too (a distant point may cross infinity within its noise), so the final
// solution and its information have unit weights: with gross mismatches the robust loss alone
// crawls (their points drift along a flat valley of the cost) and would leave down-weighted
// terms in the covariance.
// Points start from the linear (DLT) triangulation with the initial (R_i_j, t_unit).
//
// Covariance: at the solution, the inverse of the Schur complement
//   S = H_pp - sum_k H_pk H_kk^-1 H_kp
// of the information H = J^T J of the whitened residuals of the kept matches (all inside the
// Huber kink, so unit weights) in the solver's pose parameters p, mapped to z by dz/dp: the
// 3-D points are marginalised, equal to the top-left 5x5 block of the dense inverse of the
// information in (z, points). That covariance assumes the feature noise is pixel_sigma_px; the
// residuals measure it: with s_hat^2 = RSS / (n - 5) (4n residuals, 3n + 5 unknowns) the
// covariance is multiplied by max(1, k^2 s_hat^2 / s^2) (Hartley & Zisserman, section 5.1.3,
// the a-posteriori variance factor; floored at 1 so a lucky fit of few points does not shrink
// it below the configured localisation noise), reported in covariance_scale. k =
// residual_sigma_factor: on rendered truth the pose errors are 1.9 times what the residuals
// alone imply (errors the pose absorbs leave no residual), yet grow with them.
// The information describes independent noise only: a few mismatches that agree with a nearby
// pose leave no visible residual when they dominate a direction of the pose (few inliers on a
// small patch). With reliability_delta0 > 0 the covariance adds Baarda's external reliability
// (Foerstner, CVGIP 40(3), 1987): the shift that blunders at their detection limit
// (non-centrality reliability_delta0) in the reliability_group matches of largest joint
// leverage would cause,
//   covariance = s_f (C + delta0^2 C A_G (I - A_G^T C A_G)^-1 A_G^T C),
// C the information's inverse, A_G the matches' rank-one information columns, s_f the factor
// above (two_view_problem.h reliability_bound). Off by default; why, with the measurements:
// docs/performance.md, "Image registration" and "Vision in the loop".
// Errors common to all matches (camera calibration, feature-localisation biases that do not
// average out over the matches) bound how well any direction of z is known however many matches
// there are; model_sigma_rad adds them as model_sigma_rad^2 I (z's five angles, radians).
// systematic_*: the same errors as a smooth displacement field in each image (quadratic in the
// pixel position, sigma = systematic_sigma_px + systematic_noise_fraction x s_robust per
// coefficient), added as a consider covariance: it grows along the directions of z that such a
// field moves, e.g. roll against sideways motion over a flat floor, where the Huber-weighted
// residuals cannot see it (two_view_problem.h systematic_field_covariance).
//
// Failures (converged == false, `reason` says why and with which numbers): fewer than
// min_points usable matches; too many matches triangulating behind either camera; median
// derotated parallax below min_parallax_sigma noise sigmas (pure rotation / zero baseline,
// before and after the solve); more than max_fraction_outliers dropped after a solve;
// non-finite or singular information (reciprocal condition of S below min_rcond); no
// convergence within max_iterations.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "nav/vision/vision_types.h"

namespace nav::vision {

struct TwoViewRefinementOptions {
  /// Isotropic pixel noise of every feature, each axis, and the floor of the a-posteriori
  /// factor (its choice: docs/performance.md, "Image registration").
  double pixel_sigma_px = 0.5;
  double huber_threshold_sigma = 3.0;       ///< Huber kink in units of sigma (per residual pair).
  /// Raise the kink to the measured noise s_robust where that exceeds pixel_sigma_px (above);
  /// false: the kink stays at huber_threshold_sigma x pixel_sigma_px.
  bool kink_at_measured_noise = true;
  int max_iterations = 200;                 ///< Per solve round; weak baselines take ~100.
  double function_tolerance = 1e-8;         ///< Stop when relative cost decrease is below.
  double parameter_tolerance = 1e-10;       ///< Stop when the step norm is below (radians/units).
  double pose_step_tolerance_sigma = 1e-3;  ///< Stop when sqrt(dz^T S dz) is below.
  int min_points = 8;                       ///< Fewest usable matches.
  double max_fraction_behind = 0.5;         ///< Larger fraction of points behind a camera fails.
  double max_fraction_outliers = 0.5;       ///< Larger fraction dropped after a solve fails.
  /// Median derotated parallax (ray angle x mean focal length) below min_parallax_sigma x
  /// pixel_sigma_px fails as pure rotation: under a pure rotation the derotated disparity of a
  /// match is noise, Rayleigh with scale sqrt(2) sigma and median 1.67 sigma.
  double min_parallax_sigma = 3.0;
  double min_rcond = 1e-12;  ///< Smallest reciprocal condition of S.
  /// Non-centrality of blunders at the detection limit (Baarda: 4.13 for a two-sided test at
  /// 0.1 % with 80 % power; 0: the information alone, the default) and the largest group of
  /// matches blundering together, for the reliability term of the covariance.
  double reliability_delta0 = 0.0;
  int reliability_group = 3;
  /// Multiply the covariance by max(1, (residual_sigma_factor residual_sigma_px)^2 /
  /// pixel_sigma_px^2) (k above).
  bool scale_by_residual_variance = true;
  double residual_sigma_factor = 1.0;
  /// Model error of z added to the covariance as sigma^2 I, rad (0: none; its choice:
  /// docs/performance.md, "Vision in the loop").
  double model_sigma_rad = 0.0;
  /// Systematic displacement field's sigma per coefficient, px, and its part proportional to
  /// the measured noise s_robust (0 and 0: none; the choice: docs/performance.md "Systematic
  /// displacements at low signal-to-noise").
  double systematic_sigma_px = 0.0;
  double systematic_noise_fraction = 0.0;
};

/// Sets options.pixel_sigma_px and rescales min_parallax_sigma so that the pure-rotation floor
/// in pixels (min_parallax_sigma x pixel_sigma_px) stays where it was.
void set_pixel_sigma_keeping_parallax_floor(TwoViewRefinementOptions& options,
                                            double pixel_sigma_px);

/// Result of refine_two_view. Points, depths and pixel residuals are listed for the matches
/// that were used (`used_matches`, indices into the caller's match list).
struct TwoViewRefinement {
  bool converged = false;
  std::string reason;  ///< Why converged == false.
  /// Failure class when !converged: kTooFewInliers when too few usable matches remain
  /// (including after outlier rejection), otherwise kRefinementFailed.
  RegistrationFailure failure = RegistrationFailure::kOk;
  Vec5 z = Vec5::Zero();  ///< As nav::core::CameraRelativePoseModel measures it.
  /// 5x5 covariance of z, points marginalised: information_covariance + reliability_covariance
  /// + systematic_covariance + model_sigma_rad^2 I.
  Mat5 covariance = Mat5::Identity();
  Mat5 information_covariance = Mat5::Identity();  ///< s_f C (see above)
  Mat5 reliability_covariance = Mat5::Zero();      ///< s_f delta0^2 C A_G (...) A_G^T C
  Mat5 systematic_covariance = Mat5::Zero();       ///< the displacement field's (above)
  std::vector<int> reliability_matches;            ///< G, as indices like used_matches
  Eigen::Matrix3d R_i_j = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t_i_j_unit = Eigen::Vector3d::UnitX();
  std::vector<int> used_matches;
  std::vector<Eigen::Vector3d> points_i;  ///< X_k in camera i, baseline units.
  std::vector<double> depths_i;           ///< z coordinate of X_k in camera i, baseline units.
  std::vector<double> depths_j;           ///< z coordinate of X_k in camera j, baseline units.
  double reprojection_rms_px = 0.0;       ///< RMS over all 4 * n residual components.
  double initial_rms_px = 0.0;
  double median_parallax_px = 0.0;  ///< Median triangulation angle x focal length.
  /// A-posteriori pixel noise sqrt(RSS / (n - 5)) (reported; the covariance uses
  /// pixel_sigma_px). Much smaller or larger than pixel_sigma_px: the noise model is off.
  double residual_sigma_px = 0.0;
  /// s_robust of the first robust solution (above), px; the kink used was
  /// huber_threshold_sigma x max(pixel_sigma_px, robust_sigma_px) when kink_at_measured_noise.
  double robust_sigma_px = 0.0;
  double covariance_scale = 1.0;  ///< the a-posteriori factor applied to `covariance`
  /// Spread of the used matches in image i: 12 sqrt(det(second moment of u_i)) / (width x
  /// height), 1 for points spread uniformly over the frame (the area of a uniform rectangle
  /// with the same second moments, as a fraction of the frame).
  double inlier_area_fraction = 0.0;
  int iterations = 0;
  int behind_camera = 0;      ///< Matches dropped behind a camera (initial DLT or after a solve).
  int rejected_outliers = 0;  ///< Matches dropped beyond the Huber kink.
  /// Largest leverage a_k^T C a_k of a used match on the pose (its share of the information
  /// in the direction it informs; the leverages sum to 5).
  double max_leverage = 0.0;
};

/// Refinement from pixel correspondences (undistorted pixels) and an initial pose.
/// t_i_j_initial may have any non-zero length; only its direction is used.
TwoViewRefinement refine_two_view(const std::vector<Eigen::Vector2d>& u_i_px,
                                  const std::vector<Eigen::Vector2d>& u_j_px,
                                  const CameraIntrinsics& camera,
                                  const Eigen::Matrix3d& R_i_j_initial,
                                  const Eigen::Vector3d& t_i_j_initial,
                                  const TwoViewRefinementOptions& options);

/// Refinement of an essential-matrix estimate: the matches are estimate.inliers of `matches`
/// (used_matches then index `matches.matches`). Fails when !estimate.ok.
TwoViewRefinement refine_two_view(const ImageFeatures& i, const ImageFeatures& j,
                                  const PutativeMatches& matches, const EssentialEstimate& estimate,
                                  const CameraIntrinsics& camera,
                                  const TwoViewRefinementOptions& options);

/// Whitened residuals (divided by sigma, no robust loss) of the cost above, stacked per point
/// as [u_i (2); u_j (2)]: 4 * n rows. For tests (numeric Jacobians, dense information) and
/// diagnostics.
Eigen::VectorXd two_view_residuals(const Vec5& z, const std::vector<Eigen::Vector3d>& points_i,
                                   const std::vector<Eigen::Vector2d>& u_i_px,
                                   const std::vector<Eigen::Vector2d>& u_j_px,
                                   const CameraIntrinsics& camera, double pixel_sigma_px);

}  // namespace nav::vision
