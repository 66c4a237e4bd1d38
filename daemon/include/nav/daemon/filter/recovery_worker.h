#pragma once
// RecoveryWorker: navd's recovery thread, the threaded core::RecoveryExecutor
// (nav/core/navigation/recovery_executor.h; Eustice et al., RSS 2005 sec. III-A: mean and
// robot covariance column by a fixed number of PCG iterations per step).
//
// One job at a time: the filter copies its information form (Λ, η) and the warm start
// X = [μ | Σ_{*r}] into the worker's preallocated snapshot buffers (submit()), the thread runs
// core::run_recovery_job on the snapshot and publishes [μ | Σ_{*r}] and the RecoveryResult;
// the filter takes them with wait() at a DATA time (core::RecoverySchedule), so its outputs
// never depend on thread timing: a job's result is a pure function of its inputs, the same as
// core::InlineRecoveryExecutor's.
//
// Buffers: the snapshot's InformationMatrix, η and the solution are assigned in place, so a
// steady-state job allocates only when the map grew. Threads: submit(), wait(), peek(), busy(),
// set_ready() are called by the owner thread (the filter's); the worker thread only runs jobs.
// A job cannot be interrupted (its cost is bounded: fixed iterations); the destructor waits for
// a job in flight, then joins. `hook` (tests) runs on the worker thread before each job, e.g.
// to sleep and show that the results do not depend on timing.

#include <Eigen/Core>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>

#include "nav/core/filter/information_matrix.h"
#include "nav/core/navigation/recovery_executor.h"
#include "nav/core/recovery/state_recovery.h"

namespace nav::daemon {

using core::RecoveryOutput;

class RecoveryWorker final : public core::RecoveryExecutor {
 public:
  /// `options` must validate (std::invalid_argument otherwise, from core::StateRecovery).
  RecoveryWorker(int block_dim, const core::StateRecoveryOptions& options,
                 std::function<void()> hook = {});
  ~RecoveryWorker() override;
  RecoveryWorker(const RecoveryWorker&) = delete;
  RecoveryWorker& operator=(const RecoveryWorker&) = delete;

  void submit(const core::InformationMatrix& lambda, const Eigen::VectorXd& eta,
              const Eigen::MatrixXd& warm_start) override;
  bool busy() const override { return submitted_; }
  const RecoveryOutput& wait() override;
  const RecoveryOutput& peek() override;
  void set_ready(const RecoveryOutput& output) override;
  /// A new worker (its own thread) with the same block size, options and hook.
  std::unique_ptr<core::RecoveryExecutor> make_idle() const override;

 private:
  void run();
  void wait_done();

  int block_dim_;
  core::StateRecoveryOptions options_;
  std::function<void()> hook_;
  core::StateRecovery recovery_;    // the worker's solver (preconditioner cache, scratch)
  core::InformationMatrix lambda_;  // snapshot
  Eigen::VectorXd eta_;             // snapshot
  RecoveryOutput output_;
  bool submitted_ = false;  // owner thread only
  std::mutex mutex_;
  std::condition_variable cv_;
  bool job_ready_ = false;  // guarded: a job waits for the worker
  bool job_done_ = true;    // guarded: the last job finished
  bool stopping_ = false;   // guarded
  std::thread thread_;
};

/// NavFilterOptions::recovery_executor for RecoveryWorker threads; `hook` as above.
core::RecoveryExecutorFactory threaded_recovery_executor(std::function<void()> hook = {});

}  // namespace nav::daemon
