// RecoveryWorker: the background recovery thread (filter/recovery_worker.h).
#include "nav/daemon/filter/recovery_worker.h"

#include <utility>

namespace nav::daemon {

RecoveryWorker::RecoveryWorker(int block_dim, const core::StateRecoveryOptions& options,
                               std::function<void()> hook, bool threaded)
    : block_dim_(block_dim),
      options_(options),
      hook_(std::move(hook)),
      threaded_(threaded),
      recovery_(block_dim, options),
      lambda_(block_dim) {
  if (threaded_) thread_ = std::thread([this] { run(); });
}

RecoveryWorker::~RecoveryWorker() {
  if (!thread_.joinable()) return;
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
  if (!threaded_) {
    job_done_ = false;  // run by wait_done() on the caller
    return;
  }
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

void RecoveryWorker::wait_done() {
  if (!threaded_) {
    if (!job_done_) run_job();
    job_done_ = true;
    return;
  }
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
    run_job();
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      job_done_ = true;
    }
    cv_.notify_all();
  }
}

void RecoveryWorker::run_job() {
  if (hook_) hook_();
  output_.result = core::RecoveryResult{};
  if (core::Status s = recovery_.set_solution(output_.solution); !s.ok()) {
    output_.result.status = s;
    return;
  }
  output_.result = recovery_.solve(lambda_, eta_);
  output_.solution = recovery_.solution();
}

RecoveryWorkerSlot::RecoveryWorkerSlot(const RecoveryWorkerSlot& other) {
  if (!other.worker) return;
  RecoveryWorker& w = *other.worker;
  worker = std::make_unique<RecoveryWorker>(w.block_dim(), w.options(), w.hook(), w.threaded());
  if (w.busy()) worker->set_ready(w.peek());
}

RecoveryWorkerSlot& RecoveryWorkerSlot::operator=(const RecoveryWorkerSlot& other) {
  if (this != &other) {
    RecoveryWorkerSlot copy(other);
    worker = std::move(copy.worker);
  }
  return *this;
}

}  // namespace nav::daemon
