// NavFilter's camera links: proposal at each image, registration look-up or deferral, gate and
// update (the test: navigation/link_proposer.h; gate and linearisation: link_gate.h; deferral:
// navigation/pending_registrations.h).
#include <optional>
#include <string>
#include <utility>

#include "nav/core/navigation/nav_filter.h"

namespace nav::core {
namespace {

constexpr int kD = 12;  // block dimension

}  // namespace

void NavFilter::propose_and_link(ImageRecord& current) {
  ProposalRecord summary;
  summary.frame_id = current.frame_id;
  scratch_hypotheses_.clear();
  for (int block = 1; block < filter_.num_blocks(); ++block) {
    const long index = image_of_block_[static_cast<std::size_t>(block)];
    if (index < 0) continue;
    ++summary.candidates;
    std::optional<LinkHypothesis> h =
        proposer_.evaluate(filter_, bounds_, recovery_, block,
                           images_[static_cast<std::size_t>(index)].altitude_m, current.altitude_m);
    if (h) scratch_hypotheses_.push_back(std::move(*h));
  }
  proposer_.rank_and_cap(scratch_hypotheses_);
  summary.proposed = static_cast<int>(scratch_hypotheses_.size());
  for (const LinkHypothesis& h : scratch_hypotheses_) {
    const ImageRecord& earlier = *image_of_state(h.joint.state);
    PendingRegistrations::Entry entry;
    entry.info.frame_i = earlier.frame_id;
    entry.info.frame_j = current.frame_id;
    entry.info.t_i_us = earlier.t_us;
    entry.info.t_j_us = current.t_us;
    entry.joint = h.joint;
    entry.image_j = images_.size() - 1;
    entry.proposal = proposals_.size();  // this image's record, pushed after its proposals
    if (pending_.defer(registrations_, std::move(entry), now_realtime_us_)) continue;
    LinkRecord link = try_link(h, current);
    if (link.outcome == LinkOutcome::kAccepted) ++summary.accepted;
    pending_links_.push_back(links_.size());
    links_.push_back(link);
  }
  counters_.candidates += static_cast<std::uint64_t>(summary.candidates);
  counters_.links_proposed += static_cast<std::uint64_t>(summary.proposed);
  proposals_.push_back(summary);
}

LinkRecord NavFilter::try_link(const LinkHypothesis& h, const ImageRecord& current) {
  const int block = h.joint.state;
  const ImageRecord& earlier = *image_of_state(block);
  LinkRecord link;
  link.t_us = current.t_us;
  link.frame_i = earlier.frame_id;
  link.frame_j = current.frame_id;
  link.state_i = block;
  const std::optional<RegistrationResult> reg =
      registrations_ ? registrations_->find(static_cast<std::int64_t>(earlier.frame_id),
                                            static_cast<std::int64_t>(current.frame_id))
                     : std::nullopt;
  if (!reg) {
    link.outcome = LinkOutcome::kNotRegistered;
    ++counters_.not_registered;
    return link;
  }
  resolve_link(h.joint, Esdf::kRobotBlock, *reg, link);
  return link;
}

void NavFilter::resolve_link(const LinkProposal& joint, int block_j,
                             const RegistrationResult& reg, LinkRecord& link) {
  const int block = joint.state;
  link.is_outlier = reg.is_outlier;
  if (!reg.success) {
    link.outcome = LinkOutcome::kRegistrationFailed;
    ++counters_.registration_failed;
    return;
  }
  link.z = reg.z;
  link.covariance = reg.covariance;
  // Gate (nav_filter.h): ν = z − h(μ_i, μ_j), S = H J Hᵀ + R with H = [H_j H_i] (j: the robot
  // at the image, or its delayed state for a deferred link).
  const CameraRelativePoseModel& camera = *sensors_.camera();
  const LinkPair x0 =
      (LinkPair() << filter_.mean_block(block_j), filter_.mean_block(block)).finished();
  const Eigen::MatrixXd joint_cov = LinkGate::gate_joint(joint);
  link.outcome =
      gate_.pass(camera, x0, joint_cov, reg, link) ? LinkOutcome::kAccepted : LinkOutcome::kGated;
  if (link.outcome == LinkOutcome::kAccepted) {
    const MeasCov R = reg.covariance;
    const LinkLinearisation lin = gate_.linearise(camera, x0, joint_cov, reg, link);
    // The EIF update adds Hᵀ R⁻¹ (z - h(x*) + H x*) to η at the point x*; Esdf::update forms
    // z - h' + H μ, so h' = h(x*) + H (μ - x*).
    const LinkPair dmu = wrapped_difference(x0, lin.x);
    const MeasVec h_at_mean = lin.h + lin.H_r * dmu.head<kD>() + lin.H_i * dmu.tail<kD>();
    if (Status s = filter_.update(block, block_j, reg.z, h_at_mean, lin.H_i, lin.H_r, R,
                                        angle_mask(camera));
        !s.ok()) {
      warn("NavFilter: camera link " + std::to_string(link.frame_i) + "-" +
           std::to_string(link.frame_j) + " rejected by the filter: " + s.to_string());
      link.outcome = LinkOutcome::kGated;
    } else if (block_j == Esdf::kRobotBlock &&
               !bounds_.update(joint, lin.H_r, lin.H_i, R).ok()) {
      ++counters_.bound_update_failures;
    }
  }
  if (link.outcome == LinkOutcome::kAccepted) {
    ++counters_.links_accepted;
    if (link.is_outlier) ++counters_.outliers_accepted;
  } else {
    ++counters_.links_gated;
    if (link.is_outlier) ++counters_.outliers_rejected;
  }
}

void NavFilter::finish_pending(PendingRegistrations::Entry& pending,
                               const RegistrationResult* reg) {
  PendingRegistrationCounters& counters = pending_.counters();
  LinkRecord link;
  link.t_us = time_us_;
  link.frame_i = pending.info.frame_i;
  link.frame_j = pending.info.frame_j;
  link.state_i = pending.joint.state;
  link.state_j = images_[pending.image_j].state;
  if (reg == nullptr) {
    link.outcome = LinkOutcome::kNotRegistered;
    ++counters_.not_registered;
    ++counters.expired;
  } else {
    // Image j is a delayed state once the prediction after it kept it; before that (a
    // registration within min_predict_step_s of the image) it is still the robot.
    const int block_j = link.state_j >= 0 ? link.state_j : Esdf::kRobotBlock;
    resolve_link(pending.joint, block_j, *reg, link);
    ++counters.applied;
    if (link.outcome == LinkOutcome::kAccepted) {
      ++counters.accepted;
      ++proposals_[pending.proposal].accepted;
    }
  }
  if (link.state_j < 0) pending_links_.push_back(links_.size());
  links_.push_back(link);
}

}  // namespace nav::core
