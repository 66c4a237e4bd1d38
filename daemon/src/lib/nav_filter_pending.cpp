// NavFilter: proposed pairs waiting for an asynchronous registration (the vision stage answers
// after the image; nav_filter.h "Asynchronous registrations"). Filter thread only, no locks;
// the pending set is bounded and its storage reserved at construction.
#include <algorithm>
#include <cmath>
#include <limits>

#include "nav/daemon/filter/nav_filter.h"

namespace nav::daemon {
namespace {

std::int64_t wait_us(double wait_s) {
  return static_cast<std::int64_t>(std::llround(wait_s * 1e6));
}

}  // namespace

bool NavFilter::defer_link(const Proposal& p, const ImageRecord& current) {
  if (options_.registration_wait_s <= 0.0) return false;
  const ImageRecord& earlier = images_[p.image];
  const std::optional<RegistrationResult> reg =
      registrations_ ? registrations_->find(static_cast<std::int64_t>(earlier.frame_id),
                                            static_cast<std::int64_t>(current.frame_id))
                     : std::nullopt;
  if (reg && reg->available_us <= now_realtime_us_) return false;  // answered already
  if (pending_.size() >= static_cast<std::size_t>(options_.max_pending_registrations)) {
    ++pending_counters_.dropped_full;  // looked up now: not_registered
    return false;
  }
  Pending pending;
  pending.info.sequence = ++pending_sequence_;
  pending.info.frame_i = earlier.frame_id;
  pending.info.frame_j = current.frame_id;
  pending.info.t_i_us = earlier.t_us;
  pending.info.t_j_us = current.t_us;
  pending.info.asked_realtime_us = now_realtime_us_;
  pending.info.deadline_realtime_us = now_realtime_us_ + wait_us(options_.registration_wait_s);
  pending.joint = p.joint;
  pending.image_j = images_.size() - 1;
  pending.proposal = proposals_.size();  // this image's record, pushed after its proposals
  const std::int64_t deadline_us = pending.info.deadline_realtime_us;
  pending_.push_back(std::move(pending));
  ++pending_counters_.deferred;
  pending_next_check_us_ = std::min(pending_next_check_us_, deadline_us);
  if (reg) pending_next_check_us_ = std::min(pending_next_check_us_, reg->available_us);
  return true;
}

void NavFilter::resolve_pending(std::int64_t realtime_us) {
  if (pending_.empty()) return;
  const std::uint64_t generation = registrations_ ? registrations_->generation() : 0;
  if (generation == pending_seen_generation_ && realtime_us < pending_next_check_us_) return;
  pending_seen_generation_ = generation;
  pending_next_check_us_ = std::numeric_limits<std::int64_t>::max();
  auto keep = pending_.begin();
  for (auto it = pending_.begin(); it != pending_.end(); ++it) {
    const std::optional<RegistrationResult> reg =
        registrations_ ? registrations_->find(static_cast<std::int64_t>(it->info.frame_i),
                                              static_cast<std::int64_t>(it->info.frame_j))
                       : std::nullopt;
    if (reg && reg->available_us <= realtime_us) {
      finish_pending(*it, &*reg);
      continue;
    }
    if (realtime_us >= it->info.deadline_realtime_us) {
      finish_pending(*it, nullptr);
      continue;
    }
    pending_next_check_us_ = std::min(pending_next_check_us_, it->info.deadline_realtime_us);
    if (reg) pending_next_check_us_ = std::min(pending_next_check_us_, reg->available_us);
    if (keep != it) *keep = std::move(*it);
    ++keep;
  }
  pending_.erase(keep, pending_.end());
}

void NavFilter::finish_pending(Pending& pending, const RegistrationResult* reg) {
  LinkRecord link;
  link.t_us = time_us_;
  link.frame_i = pending.info.frame_i;
  link.frame_j = pending.info.frame_j;
  link.state_i = pending.joint.state;
  link.state_j = images_[pending.image_j].state;
  if (reg == nullptr) {
    link.outcome = LinkOutcome::kNotRegistered;
    ++counters_.not_registered;
    ++pending_counters_.expired;
  } else {
    // Image j is a delayed state once the prediction after it kept it; before that (a
    // registration within min_predict_step_s of the image) it is still the robot.
    const int block_j = link.state_j >= 0 ? link.state_j : core::Esdf::kRobotBlock;
    resolve_link(pending.joint, block_j, *reg, link);
    ++pending_counters_.applied;
    if (link.outcome == LinkOutcome::kAccepted) {
      ++pending_counters_.accepted;
      ++proposals_[pending.proposal].accepted;
    }
  }
  if (link.state_j < 0) pending_links_.push_back(links_.size());
  links_.push_back(link);
}

std::vector<PendingRegistration> NavFilter::pending_registrations() const {
  std::vector<PendingRegistration> out;
  out.reserve(pending_.size());
  for (const Pending& p : pending_) out.push_back(p.info);
  return out;
}

}  // namespace nav::daemon
