#include "navd/mailboxes.h"

#include <chrono>
#include <utility>

namespace nav::navd {

void RecoveryInbox::post(std::vector<PredictionRecord>&& records, FilterSnapshot&& snapshot) {
  {
    std::lock_guard lock(mutex_);
    for (auto& r : records) records_.push_back(std::move(r));
    snapshot_ = std::move(snapshot);
  }
  cv_.notify_one();
}

bool RecoveryInbox::take(std::vector<PredictionRecord>& records, FilterSnapshot& snapshot,
                         int timeout_ms) {
  std::unique_lock lock(mutex_);
  if (!cv_.wait_for(lock, std::chrono::milliseconds(timeout_ms),
                    [this] { return snapshot_.has_value(); })) {
    return false;
  }
  records.clear();
  records.swap(records_);
  snapshot = std::move(*snapshot_);
  snapshot_.reset();
  return true;
}

void RecoveryOutbox::put(RecoveredState&& state) {
  std::lock_guard lock(mutex_);
  state_ = std::move(state);
}

bool RecoveryOutbox::take_new(RecoveredState& out) {
  std::lock_guard lock(mutex_);
  if (!state_) return false;
  out = std::move(*state_);
  state_.reset();
  return true;
}

}  // namespace nav::navd
