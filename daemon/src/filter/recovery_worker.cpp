// RecoveryWorker: the background recovery thread (filter/recovery_worker.h).
#include "nav/daemon/filter/recovery_worker.h"

#include <utility>

#include "nav/daemon/system/realtime.h"

namespace nav::daemon {

RecoveryWorker::RecoveryWorker(int block_dim, const core::StateRecoveryOptions& options,
                               std::function<void()> hook)
    : block_dim_(block_dim),
      options_(options),
      hook_(std::move(hook)),
      recovery_(block_dim, options),
      lambda_(block_dim) {
  thread_ = std::thread([this] {
    name_this_thread("navd-recovery");
    run();
  });
}

RecoveryWorker::~RecoveryWorker() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  cv_.notify_all();
  thread_.join();  // after the job in flight, if any (bounded: fixed iterations)
}

void RecoveryWorker::submit(const core::InformationMatrix& lambda, const Eigen::VectorXd& eta,
                            const Eigen::MatrixXd& warm_start) {
  wait_done();  // the worker must not read the buffers while they are overwritten
  lambda_ = lambda;
  eta_ = eta;
  output_.solution = warm_start;
  submitted_ = true;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    job_ready_ = true;
    job_done_ = false;
  }
  cv_.notify_all();
}

const RecoveryOutput& RecoveryWorker::wait() {
  wait_done();
  submitted_ = false;
  return output_;
}

const RecoveryOutput& RecoveryWorker::peek() {
  wait_done();
  return output_;
}

void RecoveryWorker::set_ready(const RecoveryOutput& output) {
  wait_done();
  output_ = output;
  submitted_ = true;
}

std::unique_ptr<core::RecoveryExecutor> RecoveryWorker::make_idle() const {
  return std::make_unique<RecoveryWorker>(block_dim_, options_, hook_);
}

void RecoveryWorker::wait_done() {
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait(lock, [this] { return job_done_; });
}

void RecoveryWorker::run() {
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait(lock, [this] { return stopping_ || job_ready_; });
      if (!job_ready_) return;  // stopping with nothing to do
      job_ready_ = false;
    }
    if (hook_) hook_();
    core::run_recovery_job(recovery_, lambda_, eta_, output_);
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      job_done_ = true;
    }
    cv_.notify_all();
  }
}

core::RecoveryExecutorFactory threaded_recovery_executor(std::function<void()> hook) {
  return [hook](int block_dim, const core::StateRecoveryOptions& options) {
    return std::unique_ptr<core::RecoveryExecutor>(
        std::make_unique<RecoveryWorker>(block_dim, options, hook));
  };
}

}  // namespace nav::daemon
