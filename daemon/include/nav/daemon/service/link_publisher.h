#pragma once
// navd's publisher of the map events of the NavFilter (replay and, later, live): camera_link_t
// for every proposed pair (lcm.channels.camera_links), delayed_state_bound_t each time a bound
// is inserted (a delayed state kept) or tightened (an accepted link) (lcm.channels.bounds),
// bounds_snapshot_t of every state at lcm.channels.bounds_snapshot.rate_hz, and the
// SolutionBoard view that Publisher turns into nav_solution_t / health_t. The view's pose
// covariance is the robot's marginal from the first estimate on: Λ_rr⁻¹ before the first
// delayed state (no identity placeholder at dive start), then the Σ_rr recovered
// at the last image.
// Called on the filter thread after each measurement; work is O(1) except for new events and
// the periodic snapshot (O(map)).

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "nav/core/navigation/nav_filter.h"
#include "nav/daemon/config/config.h"
#include "nav/daemon/filter/filter_options.h"
#include "nav/daemon/service/solution_board.h"

namespace lcm {
class LCM;
}

namespace nav::daemon::service {

/// The robot's marginal covariance while the map holds only the robot (before the first
/// delayed state): Λ_rr⁻¹ (12 x 12 Cholesky, ~2 µs); nullopt once delayed states exist (their
/// Σ_rr comes from state recovery) or when Λ_rr is not positive definite.
std::optional<core::Mat12> robot_only_covariance(const core::Esdf& esdf);

struct LinkPublisherCounters {
  std::uint64_t links = 0, bounds = 0, snapshots = 0, failures = 0;
};

class LinkPublisher {
 public:
  LinkPublisher(const daemon::LcmConfig& config, SolutionBoard& board);
  ~LinkPublisher();
  void on_measurement(const daemon::NavFilter& filter);
  const LinkPublisherCounters& counters() const { return counters_; }

 private:
  void publish_links(const daemon::NavFilter& filter);
  void publish_bound(const daemon::NavFilter& filter, int state);
  void publish_snapshot(const daemon::NavFilter& filter);
  void update_board(const daemon::NavFilter& filter);

  daemon::LcmConfig config_;
  SolutionBoard& board_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::size_t links_seen_ = 0;
  std::size_t images_seen_ = 0;
  std::vector<int> tightenings_;                ///< per state
  std::vector<std::size_t> pending_link_rows_;  ///< links whose state_j is not yet kept
  std::int64_t next_snapshot_us_ = 0;
  LinkPublisherCounters counters_;
};

}  // namespace nav::daemon::service
