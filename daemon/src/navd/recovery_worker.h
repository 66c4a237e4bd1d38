#pragma once
// The recovery thread: owns a StateRecovery (fixed-iteration PCG, the paper's real-time mode).
// It takes the newest filter snapshot with every prediction since the last one, extends its
// warm start across those predictions (exact rules of state_recovery.h), runs the fixed number
// of PCG iterations on the snapshot and hands μ and Σ_rr back through the RecoveryOutbox and
// the SolutionBoard. It never blocks the filter (mailboxes.h). With spare time (no newer
// snapshot waiting) it solves the newest snapshot again, up to a bounded number of times, so
// the covariance column converges between filter steps.

#include <atomic>
#include <cstdint>

#include "nav/core/recovery/state_recovery.h"
#include "nav/core/sim/survey.h"
#include "navd/mailboxes.h"

namespace nav::navd {

struct RecoveryCounters {
  std::uint64_t solves = 0;
  std::uint64_t failures = 0;
  double last_relative_residual = 0.0;       ///< max of mean and Σ_{*r} columns
  double last_mean_relative_residual = 0.0;  ///< ‖η − Λμ‖ / ‖η‖
  double total_solve_s = 0.0;
  std::uint64_t idle_refinements = 0;  ///< extra solves of a snapshot while idle
};

class RecoveryWorker {
 public:
  /// Starts from the filter's prior; `iterations_per_step` from filter.cg_iterations_per_step.
  RecoveryWorker(const core::Vec12& x0, const core::Mat12& P0, int iterations_per_step,
                 RecoveryInbox& inbox, RecoveryOutbox& outbox, SolutionBoard& board);

  /// Runs until `stop`; then returns what it did.
  RecoveryCounters run(const std::atomic<bool>& stop);

 private:
  bool extend(const std::vector<PredictionRecord>& records);
  void solve(const FilterSnapshot& snapshot);
  void refine(const FilterSnapshot& snapshot);  ///< solve with more iterations while idle

  core::StateRecovery recovery_;
  RecoveryInbox& inbox_;
  RecoveryOutbox& outbox_;
  SolutionBoard& board_;
  RecoveryCounters counters_;
  bool broken_ = false;  ///< warm start out of step with the filter (then only reported)
};

}  // namespace nav::navd
