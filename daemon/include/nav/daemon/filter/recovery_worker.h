#pragma once
// RecoveryWorker: NavFilter's background recovery thread (ARCHITECTURE.md "The recovery thread
// works on a snapshot and hands results back through an atomic swap"; Eustice et al., RSS 2005
// sec. III-A: mean and robot covariance column by a fixed number of PCG iterations per step).
//
// One job at a time: the filter copies its information form (Λ, η) and the warm start
// X = [μ | Σ_{*r}] into the worker's preallocated snapshot buffers (submit()), the thread runs
// core::StateRecovery::solve on the snapshot (the configured fixed PCG iterations) and publishes
// [μ | Σ_{*r}] and the RecoveryResult; the filter takes them with wait() at a point defined by
// DATA time (NavFilter: the first measurement at or after the snapshot's time plus
// filter.recovery_handoff_s, the next image, finish()), so the outputs never depend on thread
// timing. The result of a job is a pure function of its inputs (same code, same arithmetic as a
// synchronous solve), hence bit-identical whenever and wherever it runs.
//
// Buffers: the snapshot's InformationMatrix, η and the solution are assigned in place (std::deque
// / std::vector / Eigen assignment reuse their storage), so a steady-state job allocates only
// when the map grew.
//
// Threads: submit(), wait(), busy(), set_ready() are called by the owner thread (the filter's);
// the worker thread only runs jobs. A job cannot be interrupted (its cost is bounded: fixed
// iterations); the destructor waits for a job in flight, then joins. `hook` (tests) runs on the
// worker thread before each job, e.g. to sleep and prove the results do not depend on timing.
// With `threaded` false no thread is started and wait() runs the job on the caller (the same
// result, for checking).

#include <Eigen/Core>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>

#include "nav/core/filter/information_matrix.h"
#include "nav/core/recovery/state_recovery.h"

namespace nav::daemon {

struct RecoveryOutput {
  core::RecoveryResult result;
  Eigen::MatrixXd solution;  ///< [μ | Σ_{*r}] of the snapshot (valid when result.status is ok)
};

class RecoveryWorker {
 public:
  /// `options` must validate (std::invalid_argument otherwise, from core::StateRecovery).
  RecoveryWorker(int block_dim, const core::StateRecoveryOptions& options,
                 std::function<void()> hook = {}, bool threaded = true);
  ~RecoveryWorker();
  RecoveryWorker(const RecoveryWorker&) = delete;
  RecoveryWorker& operator=(const RecoveryWorker&) = delete;

  /// Starts a job on copies of (Λ, η) from the warm start X (n x (1 + block_dim)). Waits for
  /// (and drops) an unconsumed job first.
  void submit(const core::InformationMatrix& lambda, const Eigen::VectorXd& eta,
              const Eigen::MatrixXd& warm_start);
  /// A submitted job that wait() has not returned yet.
  bool busy() const { return submitted_; }
  /// Blocks until the submitted job is done and returns its output (valid until the next
  /// submit()/set_ready()); marks it consumed. Must be busy().
  const RecoveryOutput& wait();
  /// Output of a job already run elsewhere (a checkpoint's awaited result): busy() afterwards,
  /// wait() returns it at once.
  void set_ready(const RecoveryOutput& output);
  /// The output wait() would return, after waiting (for checkpoints; leaves the job unconsumed).
  const RecoveryOutput& peek();

  int block_dim() const { return block_dim_; }
  const core::StateRecoveryOptions& options() const { return options_; }
  const std::function<void()>& hook() const { return hook_; }
  bool threaded() const { return threaded_; }

 private:
  void run();
  void run_job();
  void wait_done();

  int block_dim_;
  core::StateRecoveryOptions options_;
  std::function<void()> hook_;
  bool threaded_;
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

/// A copyable owner of an optional RecoveryWorker, so that NavFilter stays copyable (checkpoint
/// restore builds a copy first): a copy gets its own worker with the same settings and, when
/// the source has a job in flight, that job's output (waited for) as a ready result.
struct RecoveryWorkerSlot {
  std::unique_ptr<RecoveryWorker> worker;

  RecoveryWorkerSlot() = default;
  RecoveryWorkerSlot(const RecoveryWorkerSlot& other);
  RecoveryWorkerSlot& operator=(const RecoveryWorkerSlot& other);
  RecoveryWorkerSlot(RecoveryWorkerSlot&&) noexcept = default;
  RecoveryWorkerSlot& operator=(RecoveryWorkerSlot&&) noexcept = default;
  ~RecoveryWorkerSlot() = default;
};

}  // namespace nav::daemon
