#pragma once
// Hand-over points between navd's threads. Each is a small mutex-protected slot that is only
// held for a copy or a swap, so the filter thread never waits for recovery or publishing.
//
// * RecoveryInbox (filter -> recovery): the newest information-form snapshot plus every
//   warm-start extension (one per prediction) since the recovery thread last took it. Snapshots
//   in between are overwritten (the recovery thread always solves the newest); extensions are
//   never dropped, so the warm start stays the exact extension rules of state_recovery.h.
// * RecoveryOutbox (recovery -> filter, publisher): the newest recovered mean and robot
//   covariance with the filter step they belong to.
// * SolutionBoard (filter, recovery -> publisher): what nav_solution_t and health_t carry.

#include <Eigen/Core>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "nav/core/filter/information_matrix.h"
#include "nav/core/geometry/types.h"

namespace nav::navd {

/// One prediction as StateRecovery::extend_for_prediction needs it.
struct PredictionRecord {
  core::Mat12 F = core::Mat12::Identity();
  core::Mat12 Q = core::Mat12::Zero();
  core::Vec12 robot_mean = core::Vec12::Zero();  ///< f(mu_t) (+ control)
  bool keep_current = false;
  int kept_block = -1;
};

/// Λ, η after a filter step, with the filter's robot linearisation point at that step.
struct FilterSnapshot {
  std::uint64_t step = 0;  ///< filter steps completed
  core::InformationMatrix lambda{12};
  Eigen::VectorXd eta;
  core::Vec12 filter_robot_mean = core::Vec12::Zero();
};

class RecoveryInbox {
 public:
  /// Filter thread: queues the step's predictions and replaces the snapshot.
  void post(std::vector<PredictionRecord>&& records, FilterSnapshot&& snapshot);
  /// Recovery thread: waits (up to `timeout_ms`) for a snapshot; moves out everything posted.
  bool take(std::vector<PredictionRecord>& records, FilterSnapshot& snapshot, int timeout_ms);

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  std::vector<PredictionRecord> records_;
  std::optional<FilterSnapshot> snapshot_;
};

struct RecoveredState {
  std::uint64_t step = 0;         ///< filter step of the snapshot solved
  Eigen::VectorXd mean;           ///< μ of every block of the snapshot
  core::Vec12 filter_robot_mean;  ///< filter's robot linearisation point at that step
  core::Mat12 robot_covariance = core::Mat12::Identity();
  double relative_residual = 0.0;  ///< RecoveryResult::max_relative_residual
  int iterations = 0;
  bool ok = false;
};

class RecoveryOutbox {
 public:
  void put(RecoveredState&& state);
  /// Moves the newest result out if there is one newer than the last taken.
  bool take_new(RecoveredState& out);

 private:
  std::mutex mutex_;
  std::optional<RecoveredState> state_;
};

/// The published view of the estimate.
struct SolutionView {
  std::int64_t time_of_validity_us = 0;
  core::Vec12 robot_mean = core::Vec12::Zero();
  core::Mat12 robot_covariance = core::Mat12::Identity();
  int num_delayed_states = 0;
  int num_camera_links = 0;
  int filter_status = 2;  ///< 0 ok, 1 degraded, 2 initialising (nav_solution_t)
  double cg_relative_residual = 0.0;
  int cg_iterations = 0;
  std::string status_line = "initialising";
  bool has_estimate = false;
};

class SolutionBoard {
 public:
  template <class F>
  void modify(F&& f) {
    std::lock_guard lock(mutex_);
    f(view_);
  }
  SolutionView read() const {
    std::lock_guard lock(mutex_);
    return view_;
  }

 private:
  mutable std::mutex mutex_;
  SolutionView view_;
};

}  // namespace nav::navd
