#include "nav/daemon/service/link_publisher.h"

#include <Eigen/Cholesky>
#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <navlcm/bounds_snapshot_t.hpp>
#include <navlcm/camera_link_t.hpp>
#include <navlcm/delayed_state_bound_t.hpp>

#include "nav/daemon/system/host_clock.h"

namespace nav::daemon::service {

LinkPublisher::LinkPublisher(const daemon::LcmConfig& config, SolutionBoard& board)
    : config_(config), board_(board), lcm_(std::make_unique<lcm::LCM>(config.url)) {}

LinkPublisher::~LinkPublisher() = default;

void LinkPublisher::on_measurement(const daemon::NavFilter& filter) {
  publish_links(filter);
  const auto& images = filter.images();
  while (images_seen_ < images.size() && images[images_seen_].state >= 0) {
    publish_bound(filter, images[images_seen_].state);
    ++images_seen_;
  }
  const std::int64_t now = daemon::monotonic_us();
  if (now >= next_snapshot_us_) {
    if (next_snapshot_us_ != 0) publish_snapshot(filter);
    next_snapshot_us_ = now + static_cast<std::int64_t>(1e6 / config_.bounds_snapshot.rate_hz);
  }
  update_board(filter);
}

void LinkPublisher::publish_links(const daemon::NavFilter& filter) {
  const auto& links = filter.links();
  // A pair is published once its later image is kept (state_j known); all of an image's pairs
  // are kept together.
  while (links_seen_ < links.size() && links[links_seen_].state_j >= 0) {
    const daemon::LinkRecord& l = links[links_seen_++];
    navlcm::camera_link_t msg{};
    msg.utime = daemon::realtime_us();
    msg.state_id_i = l.state_i;
    msg.state_id_j = l.state_j;
    for (int r = 0; r < 5; ++r) {
      msg.measurement[r] = l.z(r);
      msg.innovation[r] = l.innovation(r);
      for (int c = 0; c < 5; ++c) msg.covariance[5 * r + c] = l.covariance(r, c);
    }
    msg.mahalanobis_sq = l.mahalanobis_sq;
    msg.accepted = l.outcome == daemon::LinkOutcome::kAccepted;
    msg.reason = msg.accepted ? "" : daemon::to_string(l.outcome);
    if (lcm_->good() && lcm_->publish(config_.camera_links.name, &msg) == 0) {
      ++counters_.links;
    } else {
      ++counters_.failures;
    }
    if (msg.accepted) {
      if (tightenings_.size() <= static_cast<std::size_t>(l.state_i)) {
        tightenings_.resize(static_cast<std::size_t>(l.state_i) + 1, 0);
      }
      ++tightenings_[static_cast<std::size_t>(l.state_i)];
      publish_bound(filter, l.state_i);
    }
  }
}

namespace {

navlcm::delayed_state_bound_t bound_message(const daemon::NavFilter& filter, int state,
                                            int tightenings) {
  navlcm::delayed_state_bound_t msg{};
  msg.utime = daemon::realtime_us();
  msg.state_id = state;
  const daemon::ImageRecord* image = filter.image_of_state(state);
  msg.image_time_us = image ? image->t_us : 0;
  const auto& mean = filter.esdf().mean_block(state);
  for (int k = 0; k < 6; ++k) msg.mean_pose[k] = mean(k);
  const Eigen::MatrixXd& bound = filter.bounds().bound(state);
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) msg.bound_covariance[6 * r + c] = bound(r, c);
  }
  msg.num_tightenings = tightenings;
  return msg;
}

}  // namespace

void LinkPublisher::publish_bound(const daemon::NavFilter& filter, int state) {
  if (!filter.bounds().contains(state)) return;
  const int t = static_cast<std::size_t>(state) < tightenings_.size()
                    ? tightenings_[static_cast<std::size_t>(state)]
                    : 0;
  const navlcm::delayed_state_bound_t msg = bound_message(filter, state, t);
  if (lcm_->good() && lcm_->publish(config_.bounds.name, &msg) == 0) {
    ++counters_.bounds;
  } else {
    ++counters_.failures;
  }
}

void LinkPublisher::publish_snapshot(const daemon::NavFilter& filter) {
  navlcm::bounds_snapshot_t msg{};
  msg.utime = daemon::realtime_us();
  for (int b = 1; b < filter.esdf().num_blocks(); ++b) {
    if (!filter.bounds().contains(b)) continue;
    const int t = static_cast<std::size_t>(b) < tightenings_.size()
                      ? tightenings_[static_cast<std::size_t>(b)]
                      : 0;
    msg.states.push_back(bound_message(filter, b, t));
  }
  msg.num_states = static_cast<std::int32_t>(msg.states.size());
  if (lcm_->good() && lcm_->publish(config_.bounds_snapshot.name, &msg) == 0) {
    ++counters_.snapshots;
  } else {
    ++counters_.failures;
  }
}

std::optional<core::Mat12> robot_only_covariance(const core::Esdf& esdf) {
  if (esdf.num_blocks() != 1 || esdf.block_dim() != 12) return std::nullopt;
  const core::Mat12 lambda = esdf.information().diagonal_block(core::Esdf::kRobotBlock);
  const Eigen::LLT<core::Mat12> llt(lambda);
  if (llt.info() != Eigen::Success) return std::nullopt;
  const core::Mat12 sigma = llt.solve(core::Mat12::Identity());
  return core::Mat12(0.5 * (sigma + sigma.transpose()));
}

void LinkPublisher::update_board(const daemon::NavFilter& filter) {
  if (!filter.initialised()) return;
  const core::Vec12 robot = filter.robot_mean();  // after every update (nav_filter.h)
  const auto& images = filter.images();
  const daemon::NavFilterCounters& c = filter.counters();
  char line[160];
  std::snprintf(line, sizeof line, "replay images %llu links %llu gated %llu held %llu",
                static_cast<unsigned long long>(c.images),
                static_cast<unsigned long long>(c.links_accepted),
                static_cast<unsigned long long>(c.links_gated),
                static_cast<unsigned long long>(c.predictions_held));
  const std::optional<core::Mat12> robot_only = robot_only_covariance(filter.esdf());
  board_.modify([&](SolutionView& v) {
    v.time_of_validity_us = filter.time_us();
    v.robot_mean = robot;
    if (robot_only) {
      v.robot_covariance = *robot_only;  // no delayed state yet: Σ_rr = Λ_rr⁻¹ exactly
    } else {
      v.robot_covariance = filter.robot_covariance();  // current (nav_filter.h "Published")
      if (!images.empty()) v.cg_relative_residual = images.back().relative_residual;
    }
    v.cg_iterations = filter.options().recovery.iterations_per_step;
    v.num_delayed_states = filter.esdf().num_blocks() - 1;
    v.num_camera_links = static_cast<int>(c.links_accepted);
    v.filter_status = c.update_failures > 0 || c.predictions_held > 0 ? 1 : 0;  // degraded
    v.status_line = line;
    v.innovations = filter.innovations().sensors();
    v.has_estimate = true;
  });
}

}  // namespace nav::daemon::service
