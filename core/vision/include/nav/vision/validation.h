#pragma once
// Validation of a refined two-view registration before it becomes a filter measurement
// (Eustice et al., RSS 2005, section III-C: a camera constraint is added only when the
// registration is geometrically sound). Checks, in order; the first failing one decides:
//   1. the refinement converged; else its own code and reason (TwoViewRefinement::failure:
//      kTooFewInliers, kEssentialFailed or kRefinementFailed);
//   2. at least min_inliers points were used                  -> kTooFewInliers;
//      and they spread over at least min_inlier_area_fraction of the frame (TwoViewRefinement::
//      inlier_area_fraction): a small cluster of matches pins the pose on one patch of the
//      scene, where a few coherent mismatches (repeated texture, a moving shadow) can fit a
//      wrong pose with sub-pixel residuals                    -> kTooFewInliers;
//      and no match has a leverage above max_leverage (TwoViewRefinement::max_leverage, the
//      match's share of the information in the pose direction it informs): near 1, that match
//      decides a direction of the pose alone, so a mismatch there bends the pose until its own
//      residual vanishes and no residual test can see it      -> kTooFewInliers;
//   3. an answer with an angle of z whose standard deviation (covariance, model error
//      included) exceeds max_sigma_rad needs at least uncertain_min_inliers inliers: a weakly
//      determined pose from few matches is where a set of mismatches fits as well as the truth,
//      while with many matches a wide sigma is the honest uncertainty of a short baseline
//                                                             -> kTooUncertain;
//   4. reprojection RMS <= max_reprojection_rms_px            -> kReprojectionError;
//   5. every point in front of both cameras                   -> kRefinementFailed;
//   6. with a prior: its baseline has a defined azimuth (else there is neither a depth scale
//      nor a prediction of z)                                 -> kRefinementFailed;
//      the triangulated depths, scaled to metres by the prior's baseline length |t_prior|,
//      lie within the scene-depth prior, |d_k - d_prior| <= k sigma_k with
//        sigma_k^2 = sigma_d^2 + (d_k / |t_prior|)^2 sigma_|t|^2
//      (sigma_|t| the prior's baseline-length sigma, first order): the median depth must pass
//      and at most max_fraction_depth_outliers of the points may fail -> kDepthOutOfPrior;
//   7. with a prior: chi2 of z against the prior's prediction (relative_pose_5dof.h z_chi2)
//      is always reported in prior_chi2; it fails only when gate_prior_chi2 is set and it
//      exceeds chi2_5^-1(prior_chi2_confidence)              -> kRefinementFailed.
// A failure sets success = false, the failure code and a reason with the numbers; success keeps
// failure = kOk and an empty reason. Pure functions; thread-safe.
#include <limits>
#include <string>

#include "nav/vision/two_view_refinement.h"
#include "nav/vision/vision_types.h"

namespace nav::vision {

struct ValidationOptions {
  int min_inliers = 12;
  double min_inlier_area_fraction = 0.03;
  /// Largest leverage of one match (in (0, 1]; 1 accepts all). Its choice, measured:
  /// docs/performance.md, "Image registration".
  double max_leverage = 1.0;
  /// Largest standard deviation of one angle of z, radians (infinity accepts all). Its choice,
  /// measured: docs/performance.md, "Vision in the loop".
  double max_sigma_rad = std::numeric_limits<double>::infinity();
  /// Inliers an answer needs when an angle's sigma exceeds max_sigma_rad (check 3).
  int uncertain_min_inliers = std::numeric_limits<int>::max();
  double max_reprojection_rms_px = 1.5;
  double depth_k_sigma = 3.0;
  double max_fraction_depth_outliers = 0.2;
  bool gate_prior_chi2 = false;
  double prior_chi2_confidence = 0.999;
};

/// Upper tail Q(x) = P(chi2_5 > x), closed form (odd degrees of freedom):
///   Q(x) = erfc(sqrt(x/2)) + sqrt(2x/pi) exp(-x/2) (1 + x/3).
double chi2_5_survival(double x);

/// chi2_5^-1(p): x with P(chi2_5 <= x) = p, by bisection on chi2_5_survival. p in (0, 1),
/// otherwise std::invalid_argument.
double chi2_5_quantile(double p);

/// Fills success/failure/reason, z, covariance, inliers, reprojection_rms_px and prior_chi2 of
/// `result` from `refinement` (the other counters are the caller's). `prior` may be nullptr:
/// then checks 6 and 7 are skipped and prior_chi2 stays -1.
void validate_registration(const TwoViewRefinement& refinement, const RelativePosePrior* prior,
                           const ValidationOptions& options, RegistrationResult& result);

/// Human-readable name of a failure code ("too few inliers", ...).
std::string failure_name(RegistrationFailure failure);

}  // namespace nav::vision
