// Time-of-validity ordering within a latency window: see time_ordering.h.
#include "nav/daemon/queue/time_ordering.h"

#include <algorithm>
#include <stdexcept>

namespace nav::daemon {

void TimeOrderingOptions::validate() const {
  if (latency_window_us < 0) {
    throw std::invalid_argument("TimeOrderingOptions.latency_window_us: " +
                                std::to_string(latency_window_us) + " is negative");
  }
  if (capacity == 0) throw std::invalid_argument("TimeOrderingOptions.capacity: must be >= 1");
}

TimeOrderingBuffer::TimeOrderingBuffer(const TimeOrderingOptions& options) : options_(options) {
  options_.validate();
  heap_.reserve(options_.capacity);
}

bool TimeOrderingBuffer::later(const Entry& a, const Entry& b) {
  if (a.validity_us != b.validity_us) return a.validity_us > b.validity_us;
  return a.sequence > b.sequence;
}

TimeOrderingBuffer::InsertResult TimeOrderingBuffer::insert(const Measurement& m) {
  const std::int64_t t = validity_us(m);
  if (last_released_us_ && t < *last_released_us_) {
    ++stats_.dropped_late;
    return InsertResult::kDroppedLate;
  }
  if (heap_.size() >= options_.capacity) {
    ++stats_.dropped_full;
    return InsertResult::kDroppedFull;
  }
  heap_.push_back(Entry{t, next_sequence_++, m});
  std::push_heap(heap_.begin(), heap_.end(), later);
  newest_us_ = newest_us_ ? std::max(*newest_us_, t) : t;
  ++stats_.accepted;
  return InsertResult::kAccepted;
}

Measurement TimeOrderingBuffer::pop_top() {
  std::pop_heap(heap_.begin(), heap_.end(), later);
  Entry entry = std::move(heap_.back());
  heap_.pop_back();
  last_released_us_ = entry.validity_us;
  ++stats_.released;
  return entry.measurement;
}

std::optional<Measurement> TimeOrderingBuffer::pop_ready() {
  if (heap_.empty()) return std::nullopt;
  const std::int64_t oldest = heap_.front().validity_us;
  if (oldest > *newest_us_ - options_.latency_window_us) return std::nullopt;
  return pop_top();
}

std::optional<Measurement> TimeOrderingBuffer::pop_any() {
  if (heap_.empty()) return std::nullopt;
  return pop_top();
}

}  // namespace nav::daemon
