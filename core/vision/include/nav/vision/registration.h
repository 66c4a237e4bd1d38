#pragma once
// Two-view registration pipeline of Eustice et al. (RSS 2005, section III-C), per camera:
//   features(image):  preprocess (preprocess.h) -> Harris + SIFT features (features.h);
//   register_pair(i, j, prior):
//     correspondences: pose-constrained search (pccs.h) when a prior is given, otherwise the
//                      unconstrained ratio + mutual search (matching.h);
//     essential matrix by LMedS with the decomposition choice (essential.h);
//     two-view maximum-likelihood refinement of the 5-DOF pose with its 5x5 covariance
//     (two_view_refinement.h);
//     validation (validation.h) -> RegistrationResult.
// A failure at any stage is a RegistrationResult with success = false, the failure code and a
// reason naming the stage and its numbers.
//
// Thread safety: a Registration is immutable after construction; features() and
// register_pair() are const and may run concurrently from a pool (features once per image,
// then any number of pairs sharing the ImageFeatures read-only).

#include <opencv2/core.hpp>

#include <numbers>
#include <vector>

#include "nav/core/status.h"
#include "nav/vision/essential.h"
#include "nav/vision/features.h"
#include "nav/vision/matching.h"
#include "nav/vision/pccs.h"
#include "nav/vision/preprocess.h"
#include "nav/vision/two_view_refinement.h"
#include "nav/vision/vision_types.h"
#include "nav/vision/validation.h"

namespace nav::vision {

struct RegistrationOptions {
  PreprocessOptions preprocess;
  FeatureOptions features;
  MatchingOptions matching;
  /// PCCS with its band floored at 40 px sigma: a tight prior (exact marginals) otherwise
  /// narrows the band until ambiguous candidates pass the ratio test, and the pose they give is
  /// wrong by degrees under a covariance that claims tenths (pccs.h "Floor"; docs/performance.md
  /// "A floor under the search band").
  PccsOptions pccs = [] {
    PccsOptions o;
    o.band_floor_sigma_px = 40.0;
    return o;
  }();
  EssentialOptions essential;
  /// Refinement. Its pure-rotation floor is EssentialOptions::min_parallax_px (0.25 px) rather
  /// than 3 sigma: slow survey pairs (Sparus consecutive frames, median derotated parallax
  /// ~0.6 px) still measure the rotation well, and their weakly observed baseline direction
  /// shows in the 5x5 covariance instead of a rejection. The covariance's noise model is
  /// calibrated against rendered truth: pixel sigma 0.3 px, scaled by 1.9 x the fit's own
  /// residual sigma where that is larger, no model error (docs/performance.md "An honest
  /// registration covariance"), plus systematic displacements as large as the measured noise
  /// (dark, noisy frames of weak texture: docs/performance.md "Systematic displacements at low
  /// signal-to-noise"). navd's closed loop sets its own, more conservative one
  /// (nav/daemon/config/vision_config.h).
  TwoViewRefinementOptions refinement = [] {
    TwoViewRefinementOptions o;
    o.pixel_sigma_px = 0.3;
    o.residual_sigma_factor = 1.9;
    o.systematic_noise_fraction = 1.0;
    o.min_parallax_sigma = EssentialOptions{}.min_parallax_px / o.pixel_sigma_px;
    return o;
  }();
  /// Validation: at least 20 inliers, none of leverage above 0.85, and 100 inliers for an
  /// answer with an angle's sigma above 1.5 deg. These were chosen by measurements in navd's
  /// closed loop and on the Sparus frames: docs/performance.md, "Vision in the loop".
  ValidationOptions validation = [] {
    ValidationOptions o;
    o.min_inliers = 20;
    o.max_leverage = 0.85;
    o.max_sigma_rad = 1.5 * std::numbers::pi / 180.0;
    o.uncertain_min_inliers = 100;
    return o;
  }();
  /// Inliers whose derotated parallax (pixels) is below this are not handed to the refinement:
  /// their depth is unobservable (information near singular, sign of the depth undetermined).
  double min_point_parallax_px = 0.5;
  int min_features = 8;  ///< Fewer features in either image: kTooFewFeatures.
  int min_inliers = 12;  ///< Fewer essential-matrix inliers: kTooFewInliers.
  /// Smallest inlier fraction of the putative matches: below it the "model" is most likely
  /// fitted to chance matches of a non-overlapping pair (LMedS assumes a majority of inliers).
  double min_inlier_fraction = 0.3;
};

/// Wall time of each stage of one register_pair call, milliseconds.
struct StageTimings {
  double matching_ms = 0.0;
  double essential_ms = 0.0;
  double refinement_ms = 0.0;
  double validation_ms = 0.0;
  double total_ms = 0.0;
};

/// What register_pair saw on the way, for drawing (Fig. 4) and diagnostics.
struct RegistrationDiagnostics {
  PutativeMatches matches;
  EssentialEstimate essential;
  TwoViewRefinement refinement;
  StageTimings timings;
};

class Registration {
 public:
  /// Error-free construction; invalid intrinsics are reported by features()/register_pair().
  Registration(const CameraIntrinsics& camera, const RegistrationOptions& options = {});

  /// Features of one raw frame (8-bit or 12/16-bit grey or colour). Throws
  /// std::invalid_argument with the preprocessing error's message on a bad frame.
  ImageFeatures features(const cv::Mat& image) const;
  /// As features(), reporting a bad frame as a Status instead. `mean` is the dive's
  /// illumination mean for IlluminationCompensation::kRunningMean.
  core::Status try_features(const cv::Mat& image, ImageFeatures* out,
                            const IlluminationMean* mean = nullptr) const;

  /// The 8-bit preprocessed image the features are detected on (for drawing).
  core::Status try_preprocess(const cv::Mat& image, cv::Mat* out_8u,
                              const IlluminationMean* mean = nullptr) const;

  /// Registers image j against image i; prior == nullptr: no pose prior (unconstrained search).
  RegistrationResult register_pair(const ImageFeatures& i, const ImageFeatures& j,
                                   const RelativePosePrior* prior) const;
  RegistrationResult register_pair(const ImageFeatures& i, const ImageFeatures& j,
                                   const RelativePosePrior* prior,
                                   RegistrationDiagnostics* diagnostics) const;

  const CameraIntrinsics& camera() const { return camera_; }
  const RegistrationOptions& options() const { return options_; }

 private:
  CameraIntrinsics camera_;
  RegistrationOptions options_;
  Preprocessor preprocessor_;
};

}  // namespace nav::vision
