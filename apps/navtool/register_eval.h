#pragma once
// navtool register-eval: registration of the rendered frames of a simulated dive against the
// truth (apps/navtool/cmd_register_eval.cpp is the command; this is its per-pair evaluation).
//
// Per pair (i, j) of frames whose true footprints overlap:
//   prior: the true relative pose of camera j in camera i plus a draw from the stated 6x6
//          covariance P (so the prior is exactly consistent with P), the scene depth between
//          the seafloor below camera i and below camera j (the dive's height field,
//          pccs.h scene_depth_prior) with a stated sigma;
//   registration (nav_vision, pose-constrained search with that prior);
//   errors against the true 5-DOF measurement z_true: rotation angle, baseline direction
//   angle, NEES = (z - z_true)^T C^-1 (z - z_true) with C the registration's covariance;
//   Fig. 4 of Eustice et al. (RSS 2005): true correspondences (unconstrained matches that the
//   true pose confirms: reprojection of their triangulated point within max_true_error_px in
//   image j, in front of both cameras) that fall outside the PCCS search region built with the
//   prior mean and covariance (a) P, (b) bound_inflation * P (a conservative bound, as the
//   filter's recovered covariance is), (c) P / overconfidence (Markov-blanket-like), each
//   without the registration's band floor (pccs.h "Floor"), which would hide the covariance.
#include <cstdint>
#include <string>

#include "nav/vision/registration.h"

namespace nav::tool {

struct PairEvalOptions {
  double prior_position_sigma_m = 0.25;   ///< each axis
  double prior_angle_sigma_rad = 0.0087;  ///< roll, pitch, heading (0.5 deg)
  double depth_sigma_fixed_m = 0.5;       ///< scene-depth sigma = fixed + fraction * depth
  double depth_sigma_fraction = 0.1;
  double bound_inflation = 2.0;   ///< (b): covariance multiplier of the conservative bound
  double overconfidence = 10.0;   ///< (c): covariance divisor of the over-confident prior
  double max_true_error_px = 1.5; ///< a true correspondence reprojects this close in image j
  bool fig4 = true;               ///< count the Fig. 4 band misses (an unconstrained search more)
  std::uint64_t seed = 1;
};

struct PairTruth {
  int i = 0, j = 0;                        ///< frame indices
  vision::Vec6 x_i_j = vision::Vec6::Zero();  ///< true pose of camera j in camera i
  double scene_depth_m = 0.0;              ///< depth of the floor below camera i, m
  double scene_depth_j_m = 0.0;            ///< depth of the floor below camera j, m
  double overlap = 0.0;                    ///< common surface, fraction of the smaller view
};

struct PairEval {
  vision::RegistrationResult result;
  double rotation_error_deg = -1.0;   ///< -1 unless result.success
  double baseline_error_deg = -1.0;
  double nees = -1.0;
  int true_correspondences = 0;
  int missed[3] = {0, 0, 0};  ///< outside the band with (a) P, (b) inflated, (c) over-confident
  double ms = 0.0;            ///< register_pair wall time
  /// Refinement inliers that the true pose confirms (as a true correspondence): few of
  /// result.inliers means wrong matches, all of them with a wrong z means the estimation.
  int inliers_true = 0;
  double inliers_true_rms_px = 0.0;  ///< RMS of the confirmed inliers' true-pose error in image j
  /// The refinement of the same inliers started from the true pose (-1 unless it converged):
  /// the registration's optimum again means the data pull there, not a local minimum.
  double truth_start_rms_px = -1.0, truth_start_rotation_deg = -1.0;
  double residual_sigma_px = 0.0;  ///< the refinement's a-posteriori pixel noise
  double inlier_area_fraction = 0.0;  ///< the refinement's inlier spread in image i
  double max_leverage = 0.0;          ///< the refinement's largest leverage of one inlier
};

/// The prior of pair `truth` (mean drawn from P with a generator seeded by seed, i, j).
vision::RelativePosePrior make_prior(const PairTruth& truth, const PairEvalOptions& options);

/// Registers and evaluates one pair; diagnostics (optional) receives register_pair's.
PairEval evaluate_pair(const vision::Registration& registration, const vision::ImageFeatures& fi,
                       const vision::ImageFeatures& fj, const PairTruth& truth,
                       const PairEvalOptions& options,
                       vision::RegistrationDiagnostics* diagnostics = nullptr);

}  // namespace nav::tool
