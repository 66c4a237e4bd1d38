// Pose prior of a proposed camera pair (vision/camera_prior.h).
#include "nav/daemon/vision/camera_prior.h"

#include "nav/core/geometry/pose.h"

namespace nav::daemon::vision {

using core::Mat6;
using core::Mat6x12;
using core::Vec6;

CameraPairPrior camera_pair_prior(const Vec6& x_world_body_i, const Vec6& x_world_body_j,
                                  const core::Mat12& pose_joint_j_i, const Vec6& x_body_camera) {
  Mat6x12 J_ci, J_cj, J_tt;
  const Vec6 x_w_ci = core::head_to_tail(x_world_body_i, x_body_camera, &J_ci);
  const Vec6 x_w_cj = core::head_to_tail(x_world_body_j, x_body_camera, &J_cj);
  CameraPairPrior out;
  out.x_ci_cj = core::tail_to_tail(x_w_ci, x_w_cj, &J_tt);
  // G = [d/dx_w_bj | d/dx_w_bi], matching the order of pose_joint_j_i.
  Mat6x12 G;
  G.leftCols<6>() = J_tt.rightCols<6>() * J_cj.leftCols<6>();
  G.rightCols<6>() = J_tt.leftCols<6>() * J_ci.leftCols<6>();
  const Mat6 cov = G * pose_joint_j_i * G.transpose();
  out.covariance = 0.5 * (cov + cov.transpose());
  return out;
}

const core::ImageRecord* find_image(const core::NavFilter& filter, std::uint64_t frame_id) {
  const auto& images = filter.images();
  for (auto it = images.rbegin(); it != images.rend(); ++it) {
    if (it->frame_id == frame_id) return &*it;
  }
  return nullptr;
}

std::optional<nav::vision::RelativePosePrior> pair_prior_from_filter(
    const core::NavFilter& filter, const core::PendingRegistration& pair,
    const Vec6& x_body_camera, const VisionConfig& config, std::string* why) {
  const auto fail = [&](const std::string& reason) {
    if (why) *why = "pair " + std::to_string(pair.frame_i) + "-" + std::to_string(pair.frame_j) +
                    ": " + reason;
    return std::nullopt;
  };
  const auto& images = filter.images();
  if (images.empty() || images.back().frame_id != pair.frame_j || images.back().state >= 0) {
    return fail("the robot is no longer at image j (prior asked too late)");
  }
  const core::ImageRecord* image_i = find_image(filter, pair.frame_i);
  if (image_i == nullptr || image_i->state < 0) return fail("image i is not a delayed state");
  core::LinkProposal joint;
  const int block = image_i->state;
  if (const core::Status s =
          filter.bounds().propose(block, filter.recovery().cross_covariance(block), &joint);
      !s.ok()) {
    return fail("no proposal joint: " + s.to_string());
  }
  constexpr int kD = 12;
  core::Mat12 pose_joint;
  pose_joint.topLeftCorner<6, 6>() = joint.joint.block(0, 0, 6, 6);
  pose_joint.topRightCorner<6, 6>() = joint.joint.block(0, kD, 6, 6);
  pose_joint.bottomLeftCorner<6, 6>() = joint.joint.block(kD, 0, 6, 6);
  pose_joint.bottomRightCorner<6, 6>() = joint.joint.block(kD, kD, 6, 6);
  const Vec6 x_i = filter.esdf().mean_block(block).head<6>();
  const Vec6 x_j = filter.esdf().mean_block(core::Esdf::kRobotBlock).head<6>();
  CameraPairPrior p;
  try {
    p = camera_pair_prior(x_i, x_j, pose_joint, x_body_camera);
  } catch (const std::domain_error& e) {
    return fail(std::string("prior Jacobian: ") + e.what());
  }
  nav::vision::RelativePosePrior prior;
  prior.x_i_j = p.x_ci_cj;
  prior.covariance = p.covariance;
  const nav::vision::SceneDepthPrior depth = nav::vision::scene_depth_prior(
      image_i->altitude_m, images.back().altitude_m, p.x_ci_cj[2], config.depth_sigma_fraction,
      config.depth_sigma_floor_m);
  prior.scene_depth_m = depth.depth_m;
  prior.scene_depth_sigma_m = depth.sigma_m;
  return prior;
}

}  // namespace nav::daemon::vision
