// FilterWorker (replay/filter_worker.h).
#include "nav/daemon/replay/filter_worker.h"

#include <utility>

namespace nav::daemon {

FilterWorker::FilterWorker(Apply apply, std::string name, std::size_t batch_size)
    : apply_(std::move(apply)),
      name_(std::move(name)),
      batch_size_(batch_size > 0 ? batch_size : 1) {
  pending_.reserve(batch_size_);
  thread_ = std::thread([this] { run(); });
}

FilterWorker::~FilterWorker() {
  if (thread_.joinable()) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      closing_ = true;
      failed_ = true;  // stop applying: the owner gave up on this run
      batches_.clear();
    }
    cv_.notify_one();
    thread_.join();
  }
}

void FilterWorker::push(const Measurement& m) {
  pending_.push_back(m);
  if (pending_.size() >= batch_size_) hand_over();
}

void FilterWorker::hand_over() {
  if (pending_.empty()) return;
  std::vector<Measurement> next;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    batches_.push_back(std::move(pending_));
    if (!spare_.empty()) {
      next = std::move(spare_.back());
      spare_.pop_back();
    }
  }
  cv_.notify_one();
  next.clear();
  next.reserve(batch_size_);
  pending_ = std::move(next);
}

bool FilterWorker::failed() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return failed_;
}

std::string FilterWorker::finish() {
  hand_over();
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    closing_ = true;
  }
  cv_.notify_one();
  thread_.join();
  return error_;
}

void FilterWorker::run() {
  std::vector<std::vector<Measurement>> work;
  for (;;) {
    bool closing = false;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      for (auto& done : work) {
        done.clear();
        spare_.push_back(std::move(done));
      }
      work.clear();
      cv_.wait(lock, [this] { return closing_ || !batches_.empty(); });
      work.swap(batches_);
      closing = closing_;
      if (failed_) return;
    }
    for (const auto& batch : work) {
      for (const Measurement& m : batch) {
        if (core::Status s = apply_(m); !s.ok()) {
          const std::lock_guard<std::mutex> lock(mutex_);
          error_ = name_ + " at t = " + std::to_string(validity_us(m)) + " us: " + s.to_string();
          failed_ = true;
          return;
        }
      }
    }
    if (closing) {
      const std::lock_guard<std::mutex> lock(mutex_);
      if (batches_.empty()) return;  // else pushed before closing, not yet taken
    }
  }
}

}  // namespace nav::daemon
