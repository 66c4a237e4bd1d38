#pragma once
// The one-line JSON summary navd prints on stdout when it ends. Keys:
//   completed (bool: every survey step applied), images, camera_links, steps, updates,
//   update_failures, final_position_error_m (after a direct mean solve at the end),
//   final_position_error_running_m (the running linearisation point), survey_time_s, wall_s,
//   realtime_factor (survey_time_s / wall_s), queue_drops, late_drops, full_drops,
//   unmatched_measurements, recovery_idle_refinements, recoveries, recoveries_applied,
//   recovery_failures, cg_relative_residual (last solve, worst of mean and Σ_{*r} columns),
//   cg_mean_relative_residual (last solve, mean column), mean_recovery_ms (PCG solve wall time per
//   step), published_position_sigma_m (sqrt of the trace of the last published position
//   covariance), solutions_published, health_published, publish_failures, error.

#include <cstdint>
#include <string>

#include "nav/core/sim/survey.h"
#include "navd/filter_loop.h"
#include "navd/publisher.h"
#include "navd/recovery_worker.h"

namespace nav::navd {

struct Summary {
  const core::sim::Survey& survey;
  const FilterLoopResult& filter;
  const RecoveryCounters& recovery;
  const PublisherCounters& publisher;
  std::uint64_t queue_drops = 0;
  double wall_s = 0.0;
  /// sqrt(trace Σ_xyz) of the last published robot covariance (recovered, fixed iterations).
  double published_position_sigma_m = 0.0;
};

std::string summary_json(const Summary& s);

}  // namespace nav::navd
