#pragma once
// Where NavFilter's recovery jobs run (Eustice et al., RSS 2005 sec. III-A: the mean and the
// robot covariance column by a fixed number of PCG iterations per step), and when the filter
// takes their results.
//
// A job is one core::StateRecovery::solve on a SNAPSHOT of the information form (Λ, η) from a
// warm start X = [μ | Σ_{*r}]; its result is a pure function of those inputs, so it is
// bit-identical wherever and whenever it runs. The filter submits a job after the prediction
// that keeps an image's state (the image's links included) and takes the result at a DATA time
// (RecoverySchedule: the first measurement at or after the snapshot's time plus the hand-off
// delay, the next image, or the end), never at a wall-clock time, so its outputs do not depend
// on thread timing.
//
// RecoveryExecutor is the seam: InlineRecoveryExecutor (here) runs each job on the caller when
// its result is first asked for; navd's RecoveryWorker (daemon/filter/recovery_worker.h) runs
// it on a thread. Owner-thread calls only: submit, busy, wait, peek, set_ready, make_idle.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <memory>

#include "nav/core/filter/information_matrix.h"
#include "nav/core/recovery/state_recovery.h"

namespace nav::core {

struct RecoveryOutput {
  RecoveryResult result;
  Eigen::MatrixXd solution;  ///< [μ | Σ_{*r}] of the snapshot (valid when result.status is ok)
  /// When the job refactored (result.refreshed): the exact Σ_jj of the snapshot's Λ, block j in
  /// rows [j d, (j+1) d), for the bounds' refresh at the hand-off (bounds.h refresh_exact);
  /// empty otherwise.
  Eigen::MatrixXd marginals;
};

/// Runs one job: `output.solution` holds the warm start on entry and the result on exit.
void run_recovery_job(StateRecovery& recovery, const InformationMatrix& lambda,
                      const Eigen::VectorXd& eta, RecoveryOutput& output);

class RecoveryExecutor {
 public:
  virtual ~RecoveryExecutor() = default;
  /// Starts a job on copies of (Λ, η) from the warm start X (n x (1 + block_dim)); waits for
  /// (and drops) an unconsumed job first.
  virtual void submit(const InformationMatrix& lambda, const Eigen::VectorXd& eta,
                      const Eigen::MatrixXd& warm_start) = 0;
  /// A submitted job that wait() has not returned yet.
  virtual bool busy() const = 0;
  /// The submitted job's output once done (valid until the next submit/set_ready); marks it
  /// consumed. Must be busy().
  virtual const RecoveryOutput& wait() = 0;
  /// The output wait() would return, after waiting; leaves the job unconsumed (checkpoints).
  virtual const RecoveryOutput& peek() = 0;
  /// Output of a job already run elsewhere (a checkpoint's): busy() afterwards.
  virtual void set_ready(const RecoveryOutput& output) = 0;
  /// A new executor of the same kind and settings, without a job.
  virtual std::unique_ptr<RecoveryExecutor> make_idle() const = 0;
};

using RecoveryExecutorFactory = std::function<std::unique_ptr<RecoveryExecutor>(
    int block_dim, const StateRecoveryOptions& options)>;

/// Runs each job on the caller at wait()/peek() (the reference for the threaded executor).
class InlineRecoveryExecutor final : public RecoveryExecutor {
 public:
  InlineRecoveryExecutor(int block_dim, const StateRecoveryOptions& options);
  void submit(const InformationMatrix& lambda, const Eigen::VectorXd& eta,
              const Eigen::MatrixXd& warm_start) override;
  bool busy() const override { return submitted_; }
  const RecoveryOutput& wait() override;
  const RecoveryOutput& peek() override;
  void set_ready(const RecoveryOutput& output) override;
  std::unique_ptr<RecoveryExecutor> make_idle() const override;

 private:
  int block_dim_;
  StateRecoveryOptions options_;
  StateRecovery recovery_;
  InformationMatrix lambda_;
  Eigen::VectorXd eta_;
  RecoveryOutput output_;
  bool submitted_ = false, done_ = true;
};

/// The job in flight and the data time at which the filter takes it. Copyable (a NavFilter is
/// copied to restore a checkpoint all-or-nothing): a copy gets its own executor (make_idle)
/// and, when a job is in flight, that job's output (waited for) as a ready result.
class RecoverySchedule {
 public:
  RecoverySchedule() = default;
  /// `handoff_s`: data time from a job's snapshot to its hand-off, >= 0.
  RecoverySchedule(std::unique_ptr<RecoveryExecutor> executor, double handoff_s);
  RecoverySchedule(const RecoverySchedule& other);
  RecoverySchedule& operator=(const RecoverySchedule& other);
  RecoverySchedule(RecoverySchedule&&) noexcept = default;
  RecoverySchedule& operator=(RecoverySchedule&&) noexcept = default;
  ~RecoverySchedule() = default;

  /// Jobs run on an executor (NavFilterOptions::recovery_thread).
  bool enabled() const { return executor_ != nullptr; }
  bool in_flight() const { return executor_ && executor_->busy(); }
  /// The job in flight is due at data time t_us.
  bool due(std::int64_t t_us) const { return in_flight() && t_us >= handoff_us_; }
  std::int64_t handoff_us() const { return handoff_us_; }

  /// Submits a job on a snapshot taken at data time `time_us`.
  void submit(const InformationMatrix& lambda, const Eigen::VectorXd& eta,
              const Eigen::MatrixXd& warm_start, std::int64_t time_us);
  /// Takes the job in flight (waits for it). Must be in_flight().
  const RecoveryOutput& take() { return executor_->wait(); }
  /// The job in flight's output without taking it (waits). Must be in_flight().
  const RecoveryOutput& peek() const { return executor_->peek(); }
  /// Restores a checkpointed job: in flight with `output`, due at handoff_us.
  void restore(const RecoveryOutput& output, std::int64_t handoff_us);

 private:
  std::unique_ptr<RecoveryExecutor> executor_;
  std::int64_t handoff_delay_us_ = 0;
  std::int64_t handoff_us_ = 0;
};

}  // namespace nav::core
