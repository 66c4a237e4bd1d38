// Checkpoint thread: one-slot mailbox from the filter thread, atomic writes (checkpoint_worker.h).
#include "nav/daemon/checkpoint/checkpoint_worker.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <utility>

namespace nav::daemon {

CheckpointWorker::CheckpointWorker(std::filesystem::path dir, int keep)
    : writer_(std::move(dir), keep), thread_([this] { run(); }) {}

CheckpointWorker::~CheckpointWorker() { stop(); }

bool CheckpointWorker::offer(std::uint32_t payload_version, std::vector<std::uint8_t>&& payload) {
  std::optional<Pending> replaced;  // freed outside the lock
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_) return false;
    ++stats_.offered;
    if (pending_) {
      ++stats_.superseded;
      replaced = std::move(pending_);
    }
    // Not emplace(): clang rejects default-constructing a nested struct with default member
    // initialisers inside std::optional (is_constructible is false while the class is parsed).
    pending_ = Pending{payload_version, std::move(payload)};
  }
  wake_.notify_one();
  return true;
}

void CheckpointWorker::write(Pending& job) {
  const auto start = std::chrono::steady_clock::now();
  const WriteResult r = writer_.write(job.version, job.payload);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::lock_guard<std::mutex> lock(mutex_);
  if (r.ok) {
    ++stats_.written;
    stats_.last_sequence = r.sequence;
    stats_.last_bytes = job.payload.size();
    stats_.last_write_ms = ms;
  } else {
    // Logged too (a full disk was silent before: docs/faults.md), once per failed write, at
    // most once per checkpoint.period_s.
    spdlog::warn("navd: checkpoint write {} failed: {}", stats_.failed + 1, r.error);
    ++stats_.failed;
    stats_.last_error = r.error;
  }
}

void CheckpointWorker::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return pending_.has_value() || stopping_; });
    if (!pending_) break;  // stopping with nothing left
    Pending job = std::move(*pending_);
    pending_.reset();
    writing_ = true;
    lock.unlock();
    write(job);
    lock.lock();
    writing_ = false;
    idle_.notify_all();
  }
  idle_.notify_all();
}

void CheckpointWorker::flush() {
  std::unique_lock<std::mutex> lock(mutex_);
  idle_.wait(lock, [this] { return !pending_ && !writing_; });
}

void CheckpointWorker::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_one();
  if (thread_.joinable()) thread_.join();
}

CheckpointWorkerStats CheckpointWorker::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

}  // namespace nav::daemon
