#pragma once
// The pose prior of a proposed camera pair for pose-constrained correspondence search (Eustice
// et al., RSS 2005, sec. III-C "pose-constrained correspondence search"): the relative pose of
// camera j in camera i predicted by the filter, with its first-order covariance.
//
// Algorithm. With the camera mount x_b_c (body frame), the cameras are
//   x_w_ci = x_w_bi (+) x_b_c,  x_w_cj = x_w_bj (+) x_b_c,
// and the prior is x_ci_cj = (-)x_w_ci (+) x_w_cj (tail-to-tail; Smith, Self & Cheeseman 1990).
// Its covariance is G P Gᵀ with G = d x_ci_cj / d [x_w_bj; x_w_bi] (chain rule through the
// closed-form Jacobians of core/geometry/pose.h) and P the 12x12 pose part of the proposal
// joint [Σ_rr Σ_ri; Σ_ir Σ~_ii] (nav/core/recovery/bounds.h: robot r = image j, first), which
// the bounds make conservative, so the prior is too (to first order).
// One small function (camera_pair_prior) so that a relative pose computed by the link proposer
// itself can replace it.

#include <optional>
#include <string>

#include "nav/core/geometry/types.h"
#include "nav/core/navigation/nav_filter.h"
#include "nav/daemon/config/vision_config.h"
#include "nav/vision/pccs.h"
#include "nav/vision/vision_types.h"

namespace nav::daemon::vision {

struct CameraPairPrior {
  core::Vec6 x_ci_cj = core::Vec6::Zero();  ///< camera j in camera i [m; rad]
  core::Mat6 covariance = core::Mat6::Zero();
};

/// First-order prior (file comment). `pose_joint_j_i`: covariance of [x_w_bj; x_w_bi] (12x12).
/// Throws std::domain_error at a singular pitch (pose.h).
CameraPairPrior camera_pair_prior(const core::Vec6& x_world_body_i,
                                  const core::Vec6& x_world_body_j,
                                  const core::Mat12& pose_joint_j_i,
                                  const core::Vec6& x_body_camera);

/// The filter's record of image frame_id (the newest with that id), or nullptr.
const core::ImageRecord* find_image(const core::NavFilter& filter, std::uint64_t frame_id);

/// The prior of a pair the filter has just deferred at image j (call right after the image's
/// measurement: the robot is image j and the proposal joint is rebuilt from the same bounds and
/// recovery the proposer used). Scene depth: between image i's and image j's altitude
/// (nav/vision/pccs.h scene_depth_prior), sigma from `config`.
/// nullopt and `why` set when the pair cannot be rebuilt (image i no longer a delayed state,
/// robot not at image j, bounds refused it).
std::optional<nav::vision::RelativePosePrior> pair_prior_from_filter(
    const core::NavFilter& filter, const core::PendingRegistration& pair,
    const core::Vec6& x_body_camera, const VisionConfig& config, std::string* why);

}  // namespace nav::daemon::vision
