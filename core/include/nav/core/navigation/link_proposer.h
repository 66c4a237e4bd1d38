#pragma once
// Which pairs of images to propose for registration: link hypotheses (Eustice et al., "Visually
// Navigating the RMS Titanic with SLAM Information Filters", RSS 2005 sec. IV-A; Eustice's
// thesis, "link hypothesis"), from the Algorithm 1 bounds.
//
// For the robot r (= the current image j) and a delayed state i:
// 1. Prefilter (rigorous, 2x2 only): with Δ = p_i − p_r (world x, y), C its covariance from the
//    certified joint and D = r_i + r_j + 2 ‖lever_xy‖ (r = altitude · footprint half-diagonal per
//    metre), overlap needs ‖Δ‖ < D, and P(‖Δ‖ < D) <= exp(−m²/2) with m = (‖Δ‖ − D)/sqrt(λmax C)
//    (2-dof chi-square tail of the whitened error). Pairs with that bound below min_probability
//    are not candidates for step 2 (they could not pass it).
// 2. The joint [Σ_rr Σ_ri; Σ_ir Σ~_ii] (bounds.h, certified), the first-order relative pose
//    x_ri = ⊖x_r ⊕ x_i and its covariance J joint Jᵀ, the camera-to-camera pose
//    x_cr_ci = ⊖m ⊕ x_ri ⊕ m (m: the camera mount) and its covariance, and the probability that
//    the footprints overlap by at least min_overlap_fraction (footprint_overlap.h).
// 3. Pairs with probability >= min_probability are ranked (probability, then overlap at the
//    mean, then the older state first) and at most max_per_image are proposed: the vision budget.
// Each pair (i, j) is considered once, at image j (the later one), so no pair is reproposed.

#include <optional>
#include <vector>

#include "nav/core/filter/esdf.h"
#include "nav/core/geometry/types.h"
#include "nav/core/navigation/footprint_overlap.h"
#include "nav/core/recovery/bounds.h"
#include "nav/core/recovery/state_recovery.h"

namespace nav::core {

struct LinkProposerOptions {
  double min_probability = 0.05;      ///< P(overlap >= min_overlap_fraction) to propose, (0, 1)
  double min_overlap_fraction = 0.2;  ///< footprint overlap a registration needs, (0, 1]
  int max_per_image = 15;             ///< proposals per image at most (vision budget), >= 1
};

/// One link hypothesis: the certified joint and the first-order relative poses.
struct LinkHypothesis {
  LinkProposal joint;                 ///< [Σ_rr Σ_ri; Σ_ir Σ~_ii] (bounds.h), state = i
  Vec6 x_ri = Vec6::Zero();           ///< ⊖x_r ⊕ x_i: body i in body r (pose.h)
  Mat6 covariance_ri = Mat6::Zero();  ///< its first-order covariance from the joint
  Vec6 x_cr_ci = Vec6::Zero();        ///< camera i in camera r (through the mount)
  Mat6 covariance_cr_ci = Mat6::Zero();
  double overlap_probability = 0.0;   ///< P(overlap >= min_overlap_fraction)
  double overlap_at_mean = 0.0;       ///< overlap fraction at the mean relative pose
};

class LinkProposer {
 public:
  /// `half_extent_per_altitude`: footprint half extents (cx/fx, cy/fy) per metre of altitude;
  /// `x_body_camera`: the camera's mount. Throws std::invalid_argument for invalid options.
  LinkProposer(const LinkProposerOptions& options, const Eigen::Vector2d& half_extent_per_altitude,
               const Vec6& x_body_camera);

  const LinkProposerOptions& options() const { return options_; }

  /// Steps 1-2 of the file comment for delayed state `block` (image altitude altitude_i_m)
  /// against the robot (altitude_j_m): the hypothesis when its probability reaches
  /// min_probability, else nullopt.
  std::optional<LinkHypothesis> evaluate(const Esdf& filter, const CovarianceBounds& bounds,
                                         const StateRecovery& recovery, int block,
                                         double altitude_i_m, double altitude_j_m) const;

  /// Step 3: sorts `hypotheses` best first and keeps at most max_per_image.
  void rank_and_cap(std::vector<LinkHypothesis>& hypotheses) const;

 private:
  LinkProposerOptions options_;
  Eigen::Vector2d half_extent_per_altitude_;
  Vec6 x_body_camera_;
  double prefilter_chi2_;  ///< −2 ln(min_probability)
  double lever_xy_m_;
};

}  // namespace nav::core
